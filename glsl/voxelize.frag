#version 450
// variants: PAPER
// Voxelization, step 1 of the paper: each fragment averages the surface's albedo, normal and
// emission into its voxel. The default path sums fixed-point values with a 32-bit count
// (atomicAdd), writes every voxel the triangle crosses within the pixel's column (so a closed mesh
// stays watertight), and keeps emission HDR. PAPER: the original imageAtomicRGBA8Avg into r32ui
// 3D images (the bits of RGBA8 texels), one voxel per fragment, normals encoded n * 0.5 + 0.5.
#include "common.glsl"
#include "material.glsl"
#include "voxel_common.glsl"

layout(push_constant) uniform Draw {
    mat4 model;
    uint material;
    uint flags;   // bit 0: mirrored transform; bit 1: static pass (PAPER: writes the flag);
                  // bit 2: the emitter is a light (src/render/emitter_lights.rs)
} draw;

layout(location = 0) in vec3 g_normal;
layout(location = 1) in vec2 g_uv;
layout(location = 2) flat in vec4 g_aabb;
layout(location = 3) flat in vec4 g_plane;
#ifndef PAPER
layout(location = 4) flat in vec2 g_depth;
#endif
layout(location = 5) flat in int g_axis;
#ifndef PAPER
layout(location = 6) flat in vec4 g_tri01;
layout(location = 7) flat in vec2 g_tri2;
#endif

#ifdef PAPER
// The original's volumes: RGBA8 averages in r32ui images, and its static flags.
layout(set = 2, binding = 0, r32ui) coherent volatile uniform uimage3D paper_albedo;
layout(set = 2, binding = 1, r32ui) coherent volatile uniform uimage3D paper_normal;
layout(set = 2, binding = 2, r32ui) coherent volatile uniform uimage3D paper_emission;
layout(set = 2, binding = 3, r8) uniform image3D paper_flag;
#include "atomic_average.glsl"
IMAGE_ATOMIC_RGBA8_AVG(paper_albedo)
IMAGE_ATOMIC_RGBA8_AVG(paper_normal)
IMAGE_ATOMIC_RGBA8_AVG(paper_emission)
#else
// This pass's words: their addresses (voxel_common.glsl: WORDS_*).
layout(set = 2, binding = 0, std430) readonly buffer Target { uvec2 target[4]; };
#endif

#ifndef PAPER
// The fraction of the pixel (one voxel's face in the projection) the triangle covers: the
// triangle clipped to the pixel's square (Sutherland-Hodgman), by the shoelace formula.
// Conservative rasterization gives every voxel a triangle touches a fragment, so weighting by
// this keeps a surface's edges from counting as whole voxels.
float pixel_coverage(vec2 px) {
    vec2 lo = floor(px), hi = lo + 1.0;
    vec2 poly[8];
    poly[0] = g_tri01.xy;
    poly[1] = g_tri01.zw;
    poly[2] = g_tri2;
    int count = 3;
    for (int side = 0; side < 4; side++) {
        vec2 kept[8];
        int k = 0;
        for (int i = 0; i < count; i++) {
            vec2 a = poly[i], b = poly[(i + 1) % count];
            // Signed distance inside the side's edge of the square.
            float da = side == 0 ? a.x - lo.x : side == 1 ? hi.x - a.x
                     : side == 2 ? a.y - lo.y : hi.y - a.y;
            float db = side == 0 ? b.x - lo.x : side == 1 ? hi.x - b.x
                     : side == 2 ? b.y - lo.y : hi.y - b.y;
            if (da >= 0.0 && k < 8) kept[k++] = a;
            if ((da >= 0.0) != (db >= 0.0) && k < 8) kept[k++] = mix(a, b, da / (da - db));
        }
        poly = kept;
        count = k;
    }
    float twice = 0.0;
    for (int i = 0; i < count; i++) {
        vec2 a = poly[i], b = poly[(i + 1) % count];
        twice += a.x * b.y - a.y * b.x;
    }
    return clamp(0.5 * abs(twice), 0.0, 1.0);
}
#endif

// Grid coordinates from (u, v, depth) of the projection along g_axis.
ivec3 unswizzle(ivec3 c) {
    return g_axis == 0 ? c.zxy : (g_axis == 1 ? c.yzx : c.xyz);
}


#ifndef PAPER
// What a voxel reflects, shining like a Lambertian surface: the BRDF's diffuse albedo (none
// for a metal; a dielectric's base colour less what its Fresnel term F(v.h) takes, whose
// Schlick weight (1 - v.h)^5 averages 0.0037 over cosine-weighted pairs of directions; the
// mean over one direction, 1/21, took 4.5% too much), plus its specular lobe's albedo.
// `glossy`: the luminance of the part of it a voxel shows only to wide cones (the directional
// volumes, not the full-resolution one: inject_radiance.comp): the lobe's albedo less the
// share a wide lobe spreads about as a Lambertian surface would (none below roughness 0.15,
// all of it above 0.65). A mirror's light goes one way, which depends on where it came from:
// seen by a narrow cone its mean is wrong (a smooth metal tile glowed in its own reflection,
// NormalTangentTest relMSE 0.016 -> 0.32; DamagedHelmet 0.019 -> 0.077), while the wide cones
// that gather light for diffuse surfaces take its mean over many directions, which is its
// albedo times its light: without it a silver floor sent no light into its room (the corpus's
// materials class, the image's mean 0.47 of the path tracer's).
// The lobe's albedo is GGX's with height-correlated Smith masking, cosine-weighted over the
// view, fitted within 0.02: F0 (lobe - rim) + F90 rim (single scattering loses up to 60% of
// it at roughness 1).
vec3 voxel_albedo(vec3 base, float metallic, float roughness, vec3 f0, float f90,
                  out float glossy) {
    vec3 diffuse = base * (1.0 - metallic) * (1.0 - (f0 + (f90 - f0) * 0.0037));
    float lobe = clamp(1.0 + 0.1027 * roughness - 0.7139 * roughness * roughness, 0.0, 1.0);
    float rim = 0.0504 - 0.0713 * roughness + 0.0217 * roughness * roughness;
    vec3 specular = mix(f0 * (lobe - rim) + f90 * rim, base * (lobe - rim) + rim, metallic);
    glossy = luminance(clamp(specular, 0.0, 1.0)) * (1.0 - smoothstep(0.15, 0.65, roughness));
    return diffuse + specular;
}
#endif

void main() {
    vec2 px = gl_FragCoord.xy;
    if (any(lessThan(px, g_aabb.xy)) || any(greaterThan(px, g_aabb.zw))) discard;

    Material m = material;
    vec4 base = m.base_color * texture(t_base_color, g_uv);
#ifdef PAPER
    // The original keeps a fragment whose opacity is above 0 and premultiplies its albedo by it
    // (glTF's alpha is an opacity where it has a cutoff; elsewhere the surface is opaque).
    float opacity = m.params.w >= 0.0 ? base.a : 1.0;
    if (opacity <= 0.0) discard;
#else
    if (m.params.w >= 0.0 && base.a < m.params.w) discard;
#endif
    vec3 emission = m.emissive.rgb * texture(t_emissive, g_uv).rgb;
    // An emitter injected as a light lights the voxels through it, not as emission.
    if ((draw.flags & 4u) != 0u) emission = vec3(0.0);
    float nl = length(g_normal);
    vec3 normal = nl > 1e-8 ? g_normal / nl : vec3(0.0);

    float depth = dot(g_plane.xy, px) + g_plane.z;
#ifdef PAPER
    ivec3 c = unswizzle(ivec3(ivec2(px), int(depth)));
    // Dilated triangles reach -1 and N: no-ops in GL, out of bounds in Vulkan.
    if (!in_grid(c)) return;
    bool static_pass = (draw.flags & 2u) != 0u;
    bool dynamic = (frame.grid_info.w & FLAG_DYNAMIC) != 0u;
    if (!static_pass && dynamic && imageLoad(paper_flag, c).r > 0.0) {
        return;  // the paper hides dynamic geometry inside static voxels
    }
    // The original's textures are not decoded from sRGB: its voxels hold gamma-space albedo
    // (cone_trace.comp raises the indirect light to 2.2 in the end).
    imageAtomicRGBA8Avg_paper_albedo(c, vec4(pow(base.rgb, vec3(1.0 / 2.2)) * opacity, 1.0));
    imageAtomicRGBA8Avg_paper_normal(c, vec4(normal * 0.5 + 0.5, 1.0));
    if ((frame.grid_info.w & FLAG_EMISSIVE) != 0u) {
        imageAtomicRGBA8Avg_paper_emission(c, vec4(emission, 1.0));
    }
    if (static_pass && dynamic) imageStore(paper_flag, c, vec4(1.0));
#else
    // Every voxel of this column the triangle's plane crosses within the pixel, clamped to the
    // triangle's own depth range.
    float half_span = 0.5 * (abs(g_plane.x) + abs(g_plane.y));
    float lo0 = max(depth - half_span, g_depth.x);
    float hi0 = min(depth + half_span, g_depth.y);
    float metallic = clamp(m.params.x * texture(t_metallic_roughness, g_uv).b, 0.0, 1.0);
    float roughness = clamp(m.params.y * texture(t_metallic_roughness, g_uv).g, 0.0, 1.0);
    float spec = m.specular.a * texture(t_specular, g_uv).a;
    vec3 f0 = min(vec3(0.04) * m.specular.rgb * texture(t_specular_color, g_uv).rgb, vec3(1.0)) * spec;
    float glossy;
    vec3 albedo = voxel_albedo(base.rgb, metallic, roughness, f0, spec, glossy);
    uvec3 a = uvec3(round(clamp(albedo, 0.0, 1.0) * FIXED_ONE));
    uint ag = uint(round(clamp(glossy, 0.0, 1.0) * FIXED_ONE));
    uvec3 n2 = uvec3(round(normal * normal * FIXED_ONE));
    // Emission weighted by coverage, and the emitters' coverage summed beside it: a voxel's
    // emission is the coverage-weighted mean of its emitters', diluted where they cover less
    // than the voxel (a triangle smaller than a voxel, or an emitter's edge, emits its own
    // power, not a voxel's). Surfaces that emit nothing stay out of the mean: a lamp just under
    // a ceiling shares its voxels and, lying in front of it, emits at full strength.
    float coverage = (frame.grid_info.w & FLAG_EMISSIVE) != 0u ? pixel_coverage(px) : 0.0;
    uvec3 e = uvec3(round(max(emission, vec3(0.0)) * coverage * frame.cone.w));
    bool emits = any(greaterThan(emission, vec3(0.0)));
    uint cov = emits ? uint(round(coverage * FIXED_ONE)) : 0u;
    // A double-sided emitter emits from both faces (CONVENTIONS.md), and a voxel sends its
    // light one way (inject_radiance.comp): each face goes to the voxel on its own side of the
    // nearest voxel boundary, with its own normal, so the back face's light is not lost (the
    // Cornell box's lamp, 1 cm under the ceiling, lights the ceiling's gap with its top face).
    // Other surfaces keep their voxel: splitting them too moves closed meshes half a voxel out
    // of their surfaces on average (docs/hard-cases.md, "Tried").
    bool two_faces = m.tex1.z != 0 && emits;
    float toward = normal[g_axis] >= 0.0 ? 1.0 : -1.0;
    for (int side = 0; side < (two_faces ? 2 : 1); side++) {
        float facing = side == 0 ? 1.0 : -1.0;
        vec3 face_normal = normal * facing;
        // A face lying exactly on a voxel boundary goes to the voxel in front of it, not always
        // to the one above: the two faces of a zero-thickness wall then fill the voxels of their
        // own sides instead of sharing one that shines on both.
        float shift = two_faces ? 0.5 * facing * toward : 1e-3 * normal[g_axis];
        float lo = lo0 + shift, hi = hi0 + shift;
        int z0 = int(floor(min(lo, hi)));
        int z1 = int(floor(max(lo, hi)));
        ivec3 nq = ivec3(round(face_normal * FIXED_ONE));
        Words albedo_accum = Words(target[WORDS_ALBEDO]);
        Words normal_accum = Words(target[WORDS_NORMAL]);
        Words spread_accum = Words(target[WORDS_SPREAD]);
        Words emission_accum = Words(target[WORDS_EMISSION]);
        for (int z = z0; z <= z1 && z <= z0 + 2; z++) {
            ivec3 c = unswizzle(ivec3(ivec2(px), z));
            if (!in_grid(c)) continue;
            uint i = voxel_index(c) * ALBEDO_STRIDE;
            atomicAdd(albedo_accum.w[i], 1u);
            atomicAdd(albedo_accum.w[i + 1u], a.r);
            atomicAdd(albedo_accum.w[i + 2u], a.g);
            atomicAdd(albedo_accum.w[i + 3u], a.b);
            uint k = voxel_index(c) * NORMAL_STRIDE;
            atomicAdd(normal_accum.w[k], uint(nq.x));
            atomicAdd(normal_accum.w[k + 1u], uint(nq.y));
            atomicAdd(normal_accum.w[k + 2u], uint(nq.z));
            // Where the surface crosses this voxel along the projection's axis, from its centre
            // (across that axis the pixel's centre is the voxel's): cones see a voxel's light
            // only from in front of its surface (cone_tracing.glsl), wherever in it that lies.
            float along = clamp(depth + shift, float(z), float(z + 1)) - (float(z) + 0.5);
            atomicAdd(normal_accum.w[k + 3u], uint(int(round(along * FIXED_ONE))));
            uint q = voxel_index(c) * SPREAD_STRIDE;
            atomicAdd(spread_accum.w[q], n2.x);
            atomicAdd(spread_accum.w[q + 1u], n2.y);
            atomicAdd(spread_accum.w[q + 2u], n2.z);
            atomicAdd(spread_accum.w[q + 3u], ag);
            if ((frame.grid_info.w & FLAG_EMISSIVE) != 0u) {
                uint j = voxel_index(c) * EMISSION_STRIDE;
                atomicAdd(emission_accum.w[j], e.r);
                atomicAdd(emission_accum.w[j + 1u], e.g);
                atomicAdd(emission_accum.w[j + 2u], e.b);
                atomicAdd(emission_accum.w[j + 3u], cov);
            }
        }
    }
#endif
}
