#version 450
// variants: PAPER UPSAMPLED UNMATCHED
// Cone tracing per pixel, step 4 of the paper (its light_pass): indirect diffuse from a set of
// cones over the normal's hemisphere, a specular cone along the reflection whose aperture
// follows roughness, and ambient occlusion; added to the direct light already in `radiance_out`.
// Default: glTF BRDF weights (diffuse albedo / pi, split-sum specular). PAPER: 6 cones of 60
// degrees tilted ~41 degrees, weights pi/4 and 3pi/20, indirect x 2 (bounceStrength) and
// (direct + indirect) x AO + emission, as the original composes it (without its gamma mix-up).
// UPSAMPLED: the diffuse cones were traced at reduced resolution (diffuse_gather.comp); each
// pixel takes them from the blocks around it that hold its own surface (a joint bilateral
// upsampling guided by position and normal). A pixel no block holds (a thin or edge-on
// surface) is listed instead, and UNMATCHED traces the listed pixels' diffuse cones in a
// dispatch of their own: traced in place, each such pixel held up the SIMD lanes beside it for
// its whole cone set (on EmissiveStrengthTest's edge-on panels, 120 of the trace's 250 ms at
// 256x256 for about 1% of its pixels).
#include "common.glsl"
#include "voxel_common.glsl"
#define CONE_SET 2
#define CONE_FULL_RES 1
#define CONE_LIGHT_PASS 1
#include "cone_tracing.glsl"
#include "brdf.glsl"
#include "lights.glsl"

#ifdef UNMATCHED
layout(local_size_x = 64) in;
#else
layout(local_size_x = 8, local_size_y = 8) in;
#endif

layout(set = 1, binding = 0) uniform sampler2D gb_position;
layout(set = 1, binding = 1) uniform sampler2D gb_normals;
layout(set = 1, binding = 2) uniform sampler2D gb_albedo;
layout(set = 1, binding = 3) uniform sampler2D gb_emission;
layout(set = 1, binding = 4) uniform sampler2D gb_specular;
layout(set = 1, binding = 5, rgba32f) uniform image2D radiance_out;

#ifdef UPSAMPLED
// Per block of scale x scale pixels (diffuse_gather.comp): irradiance and occlusion; the
// specular cone's radiance and the tangent of its half angle (a), or none (a 0).
layout(set = 1, binding = 6) uniform sampler2D gathered;
layout(set = 1, binding = 7) uniform sampler2D gathered_specular;
#endif

#if defined(UPSAMPLED) || defined(UNMATCHED)
// The pixels no block holds, listed by UPSAMPLED for UNMATCHED.
#define PIXEL_LIST Unmatched
#define PIXEL_LIST_BINDING 8
#ifdef UNMATCHED
#define PIXEL_LIST_READONLY
#endif
#include "pixel_list.glsl"
#endif

layout(push_constant) uniform Pass {
    uint mode;   // 0 full, 1 indirect only, 2 ambient occlusion
    uint scale;  // UPSAMPLED: pixels per block side
} pass;

#ifdef UPSAMPLED
struct Upsampled {
    Gather diffuse;  // weight 0: no block holds the pixel's surface
    vec4 specular;   // a 0: no block traced a specular cone close enough to the pixel's
};

// The cones of the pixel at p from the four blocks around it, each weighted bilinearly by
// where its traced pixel (the one nearest the block's centre) lies, and only if that pixel
// shows the same surface: its position within a quarter voxel of p's plane and eight voxels of
// p, its geometric normal within 25 degrees of p's, `geo`. Geometric normals, not shading ones:
// a normal map would part every pixel from its neighbours (its detail is lost to the blocks'
// cones). A block's specular cone is taken where it has the pixel's aperture (`tan_half`, to
// a tenth) and its reflection lies within SPECULAR_TURN of the half angle of the pixel's, `refl`.
Upsampled upsample(ivec2 px, vec3 p, vec3 geo, vec3 refl, float tan_half) {
    int s = int(pass.scale);
    ivec2 blocks = textureSize(gathered, 0);
    ivec2 size = ivec2(frame.counts.yz);
    vec2 u = (vec2(px) - float(s / 2)) / float(s);
    ivec2 b = ivec2(floor(u));
    vec2 f = u - vec2(b);
    float vs = voxel_size();
    vec4 sum = vec4(0.0);
    vec4 spec = vec4(0.0);
    float wsum = 0.0;
    float turn_cos = cos(SPECULAR_TURN * atan(tan_half));
    for (int k = 0; k < 4; k++) {
        ivec2 o = ivec2(k & 1, k >> 1);
        ivec2 c = b + o;
        if (any(lessThan(c, ivec2(0))) || any(greaterThanEqual(c, blocks))) continue;
        ivec2 traced = min(c * s + s / 2, size - 1);
        vec4 pk = texelFetch(gb_position, traced, 0);
        if (pk.a == 0.0) continue;
        vec4 normals_k = texelFetch(gb_normals, traced, 0);
        vec3 nk = oct_decode(normals_k.zw);
        vec3 d = pk.xyz - p;
        float facing = dot(geo, nk);
        if (abs(dot(d, geo)) > 0.25 * vs || dot(d, d) > 64.0 * vs * vs || facing < 0.9) continue;
        // A floor under the bilinear weight keeps a block that holds the surface when the
        // nearer ones do not.
        vec2 wb = mix(1.0 - f, f, vec2(o));
        float w = (wb.x + 1e-3) * (wb.y + 1e-3);
        sum += w * texelFetch(gathered, c, 0);
        wsum += w;
        vec4 sk = texelFetch(gathered_specular, c, 0);
        if (sk.a > 0.0 && abs(sk.a - tan_half) <= 0.1 * tan_half) {
            vec3 rk = reflect(normalize(pk.xyz - frame.eye.xyz), oct_decode(normals_k.xy));
            if (dot(rk, refl) >= turn_cos) spec += w * vec4(sk.rgb, 1.0);
        }
    }
    Upsampled r;
    r.diffuse = wsum > 0.0 ? Gather(sum.rgb / wsum, sum.a / wsum, PI) : Gather(vec3(0.0), 0.0, 0.0);
    r.specular = spec.a > 0.0 ? vec4(spec.rgb / spec.a, 1.0) : vec4(0.0);
    return r;
}
#endif

#ifdef UNMATCHED
// A listed pixel's diffuse cones, the whole set, added to what the trace left (it took no
// diffuse light there); the ambient occlusion mode's value replaced.
void main() {
    ivec2 px;
    if (!listed_pixel(px)) return;
    vec4 normals = texelFetch(gb_normals, px, 0);
    vec3 p = texelFetch(gb_position, px, 0).xyz;
    vec3 n = oct_decode(normals.xy);
    vec3 v = normalize(frame.eye.xyz - p);
    float t0;
    vec3 origin = cone_start(p, n, oct_decode(normals.zw), t0);
    Gather g = diffuse_cones(origin, tangent_frame(n), t0, 0u, 1u);
    vec4 radiance = imageLoad(radiance_out, px);
    if (pass.mode == 2u) {
        radiance.rgb = vec3(clamp(1.0 - g.occlusion / PI, 0.0, 1.0));
    } else {
        vec3 diffuse_weight;
        vec3 spec_reflectance;
        reflectances(texelFetch(gb_albedo, px, 0), texelFetch(gb_emission, px, 0).a,
                     texelFetch(gb_specular, px, 0), clamp(dot(n, v), 1e-4, 1.0),
                     diffuse_weight, spec_reflectance);
        radiance.rgb += diffuse_weight * g.irradiance;
    }
    imageStore(radiance_out, px, radiance);
}
#else

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (px.x >= int(frame.counts.y) || px.y >= int(frame.counts.z)) return;
    vec4 pos = texelFetch(gb_position, px, 0);
    vec4 direct = imageLoad(radiance_out, px);
    if (pos.a == 0.0) {
        if (pass.mode != 0u) imageStore(radiance_out, px, vec4(0.0, 0.0, 0.0, 1.0));
        return;
    }
    vec4 normals = texelFetch(gb_normals, px, 0);
    vec4 albedo = texelFetch(gb_albedo, px, 0);
    vec4 emission = texelFetch(gb_emission, px, 0);
    vec4 spec = texelFetch(gb_specular, px, 0);
    vec3 p = pos.xyz;
    vec3 n = oct_decode(normals.xy);
    vec3 geo = oct_decode(normals.zw);
    vec3 v = normalize(frame.eye.xyz - p);
    float max_dist = frame.cone.z * frame.grid.w;
    mat3 frame_n = tangent_frame(n);
    float t0;
    vec3 origin = cone_start(p, n, geo, t0);

    vec3 base = albedo.rgb;
    float metallic = albedo.a;
    float roughness = emission.a;
    float n_dot_v = clamp(dot(n, v), 1e-4, 1.0);
    vec3 diffuse_weight;
    vec3 spec_reflectance;
    reflectances(albedo, roughness, spec, n_dot_v, diffuse_weight, spec_reflectance);

#ifdef PAPER
    Gather g = diffuse_cones(origin, frame_n, t0, 0u, 1u);
#else
    // A surface that reflects no diffuse light (a metal, black) needs no diffuse cones in the
    // full image.
    bool diffuse = pass.mode != 0u || max(diffuse_weight.r, max(diffuse_weight.g, diffuse_weight.b)) > 0.0;
    Gather g = Gather(vec3(0.0), 0.0, PI);
#ifdef UPSAMPLED
    Upsampled up = upsample(px, p, geo, reflect(-v, n), specular_aperture(roughness));
    if (diffuse) {
        g = up.diffuse;
        if (g.weight == 0.0) {
            // No block shows this surface: UNMATCHED adds its diffuse light.
            list_pixel(px);
        }
    }
#else
    if (diffuse) g = diffuse_cones(origin, frame_n, t0, 0u, 1u);
#endif
#endif
    vec3 irradiance = g.irradiance;
#ifdef PAPER
    // The original's 1 - sum(w occlusion) + aoAlpha (0), its weights summing to pi: black once
    // the mean occlusion reaches 1/pi.
    float ao = clamp(1.0 - g.occlusion, 0.0, 1.0);
#else
    float ao = clamp(1.0 - g.occlusion / PI, 0.0, 1.0);
#endif

    vec3 specular = vec3(0.0);
    if (frame.trace.z > 0.0 && max(spec_reflectance.r, max(spec_reflectance.g, spec_reflectance.b)) > 1e-4) {
        float tan_half = specular_aperture(roughness);
        vec4 seen = vec4(0.0);
#ifdef UPSAMPLED
        seen = up.specular;
#endif
        if (seen.a == 0.0) seen.rgb = trace_specular_cone(origin, reflect(-v, n), tan_half, t0).radiance;
        specular = seen.rgb * spec_reflectance;
    }

    if ((frame.grid_info.w & FLAG_CONE_SHADOWS) != 0u) {
        // Soft shadows: the direct light again, each light's visibility from a narrow cone
        // (the paper's aperture 0.03) towards it instead of the shadow map.
        Surface surf = Surface(base, metallic, roughness, spec.rgb, spec.a);
        vec3 d = emission.rgb;
        for (uint i = 0u; i < frame.counts.x; i++) {
            vec3 l;
            float dist;
            vec3 e = light_irradiance(lights[i], p, l, dist);
            float n_dot_l = dot(n, l);
            if (n_dot_l <= 0.0 || dot(geo, l) <= 0.0) continue;
#ifdef PAPER
            // Up to the light, or across the grid for a directional light (its dist is
            // unbounded), as the original's calls do.
            float shown = paper_shadow_cone(p, l, min(dist, frame.grid.w));
#else
            float shown = 1.0 - trace_cone(origin, l, 0.03, t0, min(dist, max_dist)).opacity;
#endif
            d += brdf(surf, n, v, l) * e * n_dot_l * shown;
        }
        direct.rgb = d;
    }

#ifdef PAPER
    // The original's G-buffer and voxels hold its textures undecoded (gamma-space albedo): it
    // multiplies the cones by that albedo, doubles the sum (bounceStrength 2) and raises it to
    // 2.2.
    vec3 indirect = pow(max(2.0 * (pow(base, vec3(1.0 / 2.2)) * irradiance + specular), vec3(0.0)),
                        vec3(2.2));
    vec3 full = (direct.rgb - emission.rgb + indirect) * ao + emission.rgb;
#else
    vec3 indirect = diffuse_weight * irradiance + specular;
    vec3 full = direct.rgb + indirect;
#endif
    vec3 result = pass.mode == 0u ? full : (pass.mode == 1u ? indirect : vec3(ao));
    imageStore(radiance_out, px, vec4(result, 1.0));
}
#endif
