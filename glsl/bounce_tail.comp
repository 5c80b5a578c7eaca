#version 450
// The bounces not traced, and the bounce's light into the voxels. inject_bounce.comp gathered
// what each listed voxel reflects; this adds it to the voxel's radiance. On the last bounce it
// also adds the bounces after it as a geometric series, the ambient term of progressive
// radiosity (Cohen, Chen, Wallace and Greenberg 1988). A voxel returns its albedo times the
// share of its hemisphere that is closed (what the cones found), per channel; the next bounce
// returns lambda of the last, the mean over the voxels weighted by where the light is, and the
// ones after it a ratio at least as large (with_tail). In a closed box of albedo a both are a,
// and every voxel sends out Le / (1 - a). Not for --paper, whose second bounce is its last.
#include "common.glsl"
#include "voxel_common.glsl"
#define VOXEL_SET 1
#include "voxel_data.glsl"
#include "bounce_common.glsl"

layout(local_size_x = 64) in;

layout(push_constant) uniform Push {
    uint last;    // 1: add the bounces not traced
    uint before;  // 1: a bounce before this one left its light in ReflectedBefore
} push;

layout(set = 1, binding = 5, rgba16f) uniform image3D radiance;
// Where the voxel's light goes (inject_radiance.comp): a two-sided voxel's bounce light goes
// to the sides it fell on, as its direct light does.
layout(set = 1, binding = 9, rgba8_snorm) uniform image3D emit_dir;
layout(set = 1, binding = 11, std430) readonly buffer Reflected { uvec2 reflected[]; };
// The bounce before's (the light of one order fewer), when there was one.
layout(set = 1, binding = 13, std430) readonly buffer ReflectedBefore { uvec2 reflected_before[]; };
// Fronts' sums, then open backs' (inject_bounce.comp).
layout(set = 1, binding = 12, std430) readonly buffer Reflectance { uint reflectance[REFLECTANCE_WORDS]; };
// Open backs' light (inject_radiance.comp), with FLAG_BACKS; the reflected buffers then hold a
// second entry a voxel, its back's (inject_bounce.comp).
layout(set = 1, binding = 14, rgba16f) uniform image3D back_radiance;
// The light of mirror-like lobes (inject_radiance.comp): a voxel's glossy share of its bounce
// light goes there, as its direct light's did.
layout(set = 1, binding = 15, rgba16f) uniform image3D glossy_radiance;

// Lambda is kept at most 0.8 (5 times the last bounce): the voxels, whose light the radiance
// scale keeps under about 1e4, stay within half floats. The series multiplies what the last
// bounce got wrong with the rest: at 0.6 (2.5 times) a closed white room, where 5 is exact,
// lacked much of its light (hard case door-room, a room lit through a door, 0.564 against
// 0.444 at 0.8), and at 0.8 the light such a room leaked through a 1 cm floor came over its
// goal until the bounce's cones saw thin walls (docs/hard-cases.md).
const float MAX_LAMBDA = 0.8;

float fixed_sum(uint k) {
    return (float(reflectance[k + 1u]) * 4294967296.0 + float(reflectance[k])) / REFLECTANCE_ONE;
}

vec3 rgb(uvec2 entry) {
    return vec3(unpackHalf2x16(entry.x), unpackHalf2x16(entry.y).x);
}

// The mean reflectance of the sums at k: r, g, b over their weight.
vec3 mean_reflectance(uint k) {
    float weight = fixed_sum(k + 6u);
    return weight > 0.0 ? vec3(fixed_sum(k), fixed_sum(k + 2u), fixed_sum(k + 4u)) / weight
                        : vec3(0.0);
}

// The light entry k reflected, on the last bounce with the bounces after it, by the series of
// the fronts' (sums at 0) or the backs' (at 8) reflectance.
vec3 with_tail(uint k, uint sums) {
    vec3 bounce = rgb(reflected[k]);
    if (push.last == 0u) return bounce;
    // The next bounce returns lambda of this one's light, lambda weighted by where that light is
    // (inject_bounce.comp). The bounces after it spread over the scene and tend to the scene's
    // own ratio, the largest the transport has, which each estimate only bounds from below:
    // they go on by the larger of it and the mean over every voxel that gathered light (a room
    // of light walls over a dark floor lit under its lamp: materials-010's lambda 0.62 weighted,
    // 0.68 even).
    vec3 lambda = min(mean_reflectance(sums), vec3(MAX_LAMBDA));
    vec3 after = max(lambda, min(mean_reflectance(sums + 16u), vec3(MAX_LAMBDA)));
    // The series continues the order of light this bounce added, not the orders before
    // it, which the bounces before traced: with three bounces the third's light is the
    // second order plus the first again, and scaling all of it counted the first order
    // twice over (sky-room 0.023 with two bounces, 0.078 with three, 0.136 with four).
    vec3 before = push.before != 0u ? rgb(reflected_before[k]) : vec3(0.0);
    return max(before + (bounce - before) * (1.0 + lambda / (1.0 - after)), 0.0);
}

void main() {
    uint i = list_entry();
    if (!listed(i)) return;
    ivec3 c = listed_voxel(i);
    Voxel v = load_voxel(c);
    if (!v.filled) return;
    bool backs = (frame.grid_info.w & FLAG_BACKS) != 0u;
    uint k = backs ? 2u * i : i;
    vec3 bounce = with_tail(k, 0u);
    float side = unpackHalf2x16(reflected[k].y).y;
    if (backs && open_back(c, v)) {
        vec4 direct = imageLoad(back_radiance, c);
        vec3 back = with_tail(k + 1u, 8u) * (1.0 - v.glossy);
        imageStore(back_radiance, c, vec4(direct.rgb + back, 0.0));
    }
    vec4 direct = imageLoad(radiance, c);
    vec3 glossy = imageLoad(glossy_radiance, c).rgb;
    if (side <= 1.0) {
        // A two-sided voxel: its light goes the way of its direct and bounce light, by their
        // luminance.
        vec3 dir = imageLoad(emit_dir, c).xyz;
        float ld = luminance(direct.rgb + glossy), lb = luminance(bounce);
        vec3 going = (dir * ld + voxel_facing(v) * side * lb) / max(ld + lb, 1e-30);
        float along = dot(going, going) > 0.0 ? dot(v.offset, normalize(going)) : 0.0;
        imageStore(emit_dir, c, vec4(going, along));
    }
    imageStore(glossy_radiance, c, vec4(glossy + bounce * v.glossy, 0.0));
    imageStore(radiance, c, vec4(direct.rgb + bounce * (1.0 - v.glossy), direct.a));
}
