#version 450
// variants: PAPER
// Voxel illumination, step 2 of the paper: the direct light every voxel receives, with the
// paper's normal-weighted attenuation, shadowed by the shadow maps, plus its emission, stored as
// outgoing radiance (premultiplied by opacity) in the radiance volume. The default divides by pi
// (the original forgot), lights the voxel centre, and treats voxels whose normals cancelled
// (thin two-sided panels) as lit from both sides. PAPER: voxel corner, no 1/pi, RGBA8 radiance.
#include "common.glsl"
#include "voxel_common.glsl"
#include "lights.glsl"
#define VOXEL_SET 1
#include "voxel_data.glsl"
#ifndef PAPER
#include "area_light_voxels.glsl"
#endif

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(set = 1, binding = 4) uniform sampler2DArrayShadow shadow_map;
layout(set = 1, binding = 11) uniform sampler2DArrayShadow area_shadow_map;
#ifdef PAPER
layout(set = 1, binding = 5, rgba8) uniform writeonly image3D radiance;
#else
layout(set = 1, binding = 5, rgba16f) uniform writeonly image3D radiance;
// Where the voxel's light goes (aniso_mip_base.comp), in xyz: the surface normal, or for a
// two-sided voxel (a thin wall, both faces in one voxel) the side the lights fall on; shorter
// where it spreads (bent surfaces, light on both sides), zero for every way; in w, where along it
// the voxel's surfaces lie from its centre (in voxels).
layout(set = 1, binding = 6, rgba8_snorm) uniform writeonly image3D emit_dir;
// The luminance of the emission that comes from emitters covering less than the voxel, which
// cones see less of from the side (aniso_mip_base.comp). One texel when nothing emits.
layout(set = 1, binding = 10, r32f) uniform writeonly image3D small_emission;
// The light the backs of open-backed voxels reflect (voxel_data.glsl's open_back), as the
// radiance volume's (opacity 0: the front's counts). One texel, not written, without FLAG_BACKS.
layout(set = 1, binding = 12, rgba16f) uniform writeonly image3D back_radiance;
// The light of mirror-like lobes (voxel_data.glsl: Voxel.glossy), as the radiance volume's but
// without opacity: it goes one way, which depends on where it came from, so only wide cones
// (the directional volumes: aniso_mip_base.comp adds it) take it, as its mean.
layout(set = 1, binding = 13, rgba16f) uniform writeonly image3D glossy_radiance;
#endif

#ifdef PAPER
// The original's ceil(texture(voxelAlbedo, uvw).a): a hit when any of the eight voxels a
// trilinear lookup at `uvw` blends (clamped to the edge) is filled.
bool paper_hit(vec3 uvw) {
    int n = int(grid_n());
    ivec3 base = ivec3(floor(uvw * float(n) - 0.5));
    for (int k = 0; k < 8; k++) {
        ivec3 c = clamp(base + ivec3(k & 1, (k >> 1) & 1, k >> 2), ivec3(0), ivec3(n - 1));
        if (voxel_filled(c)) return true;
    }
    return false;
}
#endif

// Visibility of the light by marching the voxels (--voxel-shadows), from two voxels out, one
// voxel per step, up to the light or out of the grid. Default: the nearest voxel, and any
// filled one on the way blocks. PAPER: the original's accumulation v += (1 - v) * k / dst with
// k = 0.25 and dst in grid units, which saturates near hits, of the trilinear lookup's voxels;
// returns 1 - v.
float voxel_visibility(vec3 p, vec3 l, float dist) {
    float vs = voxel_size();
    float v = 0.0;
    for (float t = 2.0 * vs; t < dist; t += vs) {
        vec3 uvw = world_to_grid(p + l * t);
#ifdef PAPER
        if (any(lessThan(uvw, vec3(0.0))) || any(greaterThan(uvw, vec3(1.0)))) break;
        if (paper_hit(uvw)) {
            v += (1.0 - v) * 0.25 / (t / frame.grid.w);
            if (v > 1.0) return 0.0;
        }
#else
        ivec3 c = ivec3(floor(uvw * float(grid_n())));
        if (!in_grid(c)) break;
        if (voxel_filled(c)) return 0.0;
#endif
    }
    return clamp(1.0 - v, 0.0, 1.0);
}

#ifndef PAPER
// The solid angle of the triangle a, b, c seen from the origin (Van Oosterom and Strackee).
float triangle_solid_angle(vec3 a, vec3 b, vec3 c) {
    float la = length(a), lb = length(b), lc = length(c);
    float den = la * lb * lc + dot(a, b) * lc + dot(a, c) * lb + dot(b, c) * la;
    return 2.0 * atan(abs(dot(a, cross(b, c))), den);
}

// The mean irradiance, per unit of the light's intensity, over the voxel's surface near a
// point or spot light at `from`: a square of the voxel's cross-section through the surface
// point s facing n, whose flux is the intensity times the square's solid angle. Far from the
// light it is cos / d^2 at s; within a few voxels the light at one point says little of what
// the surface receives (a lamp a centimetre under a ceiling of 3 cm voxels lit the voxels'
// centres at a fifth of the flux the ceiling takes).
float patch_irradiance(vec3 from, vec3 s, vec3 n, float vs) {
    vec3 rel = s - from;
    if (dot(rel, n) >= 0.0) return 0.0;
    // A plane through a cube of side vs cuts about vs^2 / max |n_i| of it.
    float half_side = 0.5 * vs / sqrt(max(max(abs(n.x), abs(n.y)), abs(n.z)));
    vec3 t = normalize(cross(n, abs(n.x) < 0.9 ? vec3(1.0, 0.0, 0.0) : vec3(0.0, 1.0, 0.0)));
    vec3 b = cross(n, t);
    vec3 c0 = rel + (-t - b) * half_side, c1 = rel + (t - b) * half_side;
    vec3 c2 = rel + (t + b) * half_side, c3 = rel + (-t + b) * half_side;
    float omega = triangle_solid_angle(c0, c1, c2) + triangle_solid_angle(c0, c2, c3);
    return omega / (4.0 * half_side * half_side);
}
#endif


// The direct light falling on the surfaces of a voxel at p facing n (or, two-sided, both ways),
// with axis weights w and its surfaces at s; for a two-sided voxel also the sides it falls on,
// weighted by the light they reflect (lit_side).
vec3 direct_irradiance(vec3 p, vec3 s, vec3 n, vec3 w, bool two_sided, vec3 albedo,
                       inout vec3 lit_side) {
    float vs = voxel_size();
    vec3 irradiance = vec3(0.0);
    for (uint i = 0u; i < frame.counts.x; i++) {
        Light light = lights[i];
        vec3 l;
        float dist;
        // An area light's polygons do not light the voxels they pass through.
        vec3 e = light_irradiance_near(light, p, vs, l, dist);
        // Normal-weighted attenuation: per axis, the light along that axis on the side the
        // surface faces, weighted by how much the surface faces that axis. A two-sided voxel
        // faces both ways.
        vec3 d = two_sided ? abs(l) : max(sign(n) * l, vec3(0.0));
        float n_dot_l = dot(w, d);
#ifndef PAPER
        uint type = uint(light.position_type.w);
        if (!two_sided && dot(n, n) > 0.0 && (type == LIGHT_POINT || type == LIGHT_SPOT)) {
            // Near the light: the mean over the surface's patch instead, blended into the
            // light at the centre from 4 to 8 voxels away.
            vec3 ls;
            float ds;
            vec3 es = light_irradiance_near(light, s, vs, ls, ds);
            float near = ds * ds * patch_irradiance(light.position_type.xyz, s, n, vs);
            float k = smoothstep(4.0 * vs, 8.0 * vs, ds);
            e = mix(es * near, e * n_dot_l, k);
            n_dot_l = 1.0;
        }
#endif
        if (n_dot_l <= 0.0 || all(equal(e, vec3(0.0)))) continue;
        // The shadow is looked up off the voxel, on the side facing the light: the paper moves
        // half a voxel from the corner; the centre of a voxel a surface crosses can lie up to
        // sqrt(3)/2 voxel behind it, so the default moves one and a half.
        vec3 side = (two_sided || dot(n, n) == 0.0) ? l : n;
#ifdef PAPER
        vec3 q = p + side * 0.5 * vs;
#else
        vec3 q = p + side * 1.5 * vs;
#endif
        float vis = (frame.grid_info.w & FLAG_VOXEL_SHADOWS) != 0u
            ? voxel_visibility(q, l, dist)
            : shadow_visibility(light, q, side, shadow_map, area_shadow_map);
#ifndef PAPER
        if (uint(light.position_type.w) == LIGHT_AREA && vis < 0.999) {
            // In the shadow of the light's centre, where its faces may still be seen (an
            // emissive cube on a pedestal of its footprint hides the floor around the pedestal
            // from its centre, not from its sides): each polygon shadowed by the voxels between
            // it and q instead.
            vec3 f = vec3(0.0);
            for (uint k = 0u; k < uint(light.cone.y); k++) {
                AreaPolygon poly = area_polygons[uint(light.cone.x) + k];
                vec3 fk = polygon_vector(light, poly, p, vs);
                if (dot(fk, fk) > 0.0) f += fk * polygon_seen(poly, q);
            }
            float len = length(f);
            l = len > 0.0 ? f / len : l;
            e = light.radiance.rgb * (PI * len);
            n_dot_l = dot(w, two_sided ? abs(l) : max(sign(n) * l, vec3(0.0)));
            vis = 1.0;
        }
#endif
        irradiance += e * n_dot_l * vis;
        if (two_sided) {
            lit_side += luminance(albedo * e * n_dot_l * vis) * normalize(w * l + 1e-12);
        }
    }
    return irradiance;
}

void main() {
    ivec3 c = ivec3(gl_GlobalInvocationID);
    if (!in_grid(c)) return;
    Voxel v = load_voxel(c);
#ifndef PAPER
    if ((frame.grid_info.w & FLAG_BACKS) != 0u) {
        // Its back lit as a surface facing the other way (its shadow looked up behind it).
        vec3 back = vec3(0.0);
        if (open_back(c, v)) {
            vec3 unused = vec3(0.0);
            vec3 e = direct_irradiance(voxel_centre(c), voxel_centre(c) + v.offset * voxel_size(),
                                       -v.normal, v.axis_weights, false, v.albedo, unused);
            back = v.albedo * (1.0 - v.glossy) / PI * e * frame.tuning.y;
        }
        imageStore(back_radiance, c, vec4(back, 0.0));
    }
#endif
    if (!v.filled) {
        imageStore(radiance, c, vec4(0.0));
#ifndef PAPER
        imageStore(emit_dir, c, vec4(0.0));
        imageStore(glossy_radiance, c, vec4(0.0));
        if ((frame.grid_info.w & FLAG_EMISSIVE) != 0u) imageStore(small_emission, c, vec4(0.0));
#endif
        return;
    }
    float vs = voxel_size();
#ifdef PAPER
    vec3 p = frame.grid.xyz + vec3(c) * vs;
    bool two_sided = false;
#else
    vec3 p = voxel_centre(c);
    bool two_sided = v.agreement < 0.5;
#endif
    vec3 n = v.normal;
    vec3 w = v.axis_weights;

    // Two-sided voxels: the lit sides, weighted by the light they reflect (where the light goes).
    vec3 lit_side = vec3(0.0);
#ifdef PAPER
    vec3 s = p;
#else
    vec3 s = p + v.offset * vs;
#endif
    vec3 irradiance = direct_irradiance(p, s, n, w, two_sided, v.albedo, lit_side);
#ifdef PAPER
    vec3 outgoing = v.albedo * irradiance + v.emission;
#else
    vec3 reflected = v.albedo / PI * irradiance;
    vec3 outgoing = reflected + v.emission;
    // One-sided: the averaged normal (shorter where the surfaces bend). Two-sided: the sides the
    // lights fall on; the emission (which side is unknown) goes every way.
    vec3 dir = two_sided ? lit_side / PI / max(luminance(outgoing), 1e-30)
                         : v.normal * v.agreement;
    // w: how far in front of the centre the voxel's surfaces lie, along that direction.
    float along = dot(dir, dir) > 0.0 ? dot(v.offset, normalize(dir)) : 0.0;
    imageStore(emit_dir, c, vec4(dir, along));
    if ((frame.grid_info.w & FLAG_EMISSIVE) != 0u) {
        // An emitter that covers only part of the voxel is smaller than it (or its edge).
        float small = 1.0 - min(v.emitter_cover, 1.0);
        imageStore(small_emission, c, vec4(luminance(v.emission) * small * frame.tuning.y));
    }
    imageStore(glossy_radiance, c, vec4(reflected * v.glossy * frame.tuning.y, 0.0));
    outgoing -= reflected * v.glossy;
#endif
    imageStore(radiance, c, vec4(outgoing * frame.tuning.y, 1.0));
}
