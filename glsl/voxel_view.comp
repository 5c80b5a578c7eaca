#version 450
// variants: PAPER
// Debug views of the volumes: each pixel's camera ray walks the voxels (Amanatides and Woo)
// and shows the first non-empty one: albedo, normal (n * 0.5 + 0.5), emission, radiance (its
// mirror-like lobes' too; from behind its surface, its back's where it holds one), or the
// directional volumes at mip level frame.trace.w, seen along the ray.
#include "common.glsl"
#include "voxel_common.glsl"
#define VOXEL_SET 1
#include "voxel_data.glsl"
#define CONE_SET 2
#define CONE_FULL_RES 1
#include "cone_tracing.glsl"

layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 1, binding = 5, rgba32f) uniform writeonly image2D view_out;
#ifndef PAPER
// The light of mirror-like lobes, which the full-resolution volume leaves out for the cones
// (inject_radiance.comp): the view shows a voxel's whole light.
layout(set = 1, binding = 6) uniform sampler3D glossy_radiance_tex;
#endif

layout(push_constant) uniform Pass {
    uint mode;   // 0 albedo, 1 normal, 2 emission, 3 radiance, 4 directional volumes
} pass;

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = ivec2(frame.counts.yz);
    if (px.x >= size.x || px.y >= size.y) return;
    // The camera ray through the pixel centre (row 0 at the top).
    vec2 ndc = vec2((float(px.x) + 0.5) / float(size.x) * 2.0 - 1.0,
                    1.0 - (float(px.y) + 0.5) / float(size.y) * 2.0);
    vec3 dir_view = normalize(vec3(ndc.x / frame.proj[0][0], ndc.y / frame.proj[1][1], -1.0));
    vec3 dir = normalize(transpose(mat3(frame.view)) * dir_view);
    vec3 origin = frame.eye.xyz;

    int level = int(frame.trace.w);
    int res = pass.mode == 4u ? max(grid_n() >> (level + 1), 1) : grid_n();
    // The ray in grid units of this resolution.
    vec3 o = world_to_grid(origin) * float(res);
    vec3 inv = 1.0 / dir;  // +-inf on axis-aligned rays is handled by the slab test below
    vec3 t_a = (vec3(0.0) - o) * inv, t_b = (vec3(float(res)) - o) * inv;
    vec3 t_lo = min(t_a, t_b), t_hi = max(t_a, t_b);
    float t_enter = max(max(max(t_lo.x, t_lo.y), t_lo.z), 0.0);
    float t_exit = min(min(t_hi.x, t_hi.y), t_hi.z);
    vec4 result = vec4(0.0, 0.0, 0.0, 1.0);
    if (t_enter < t_exit && !any(isnan(vec2(t_enter, t_exit)))) {
        vec3 q = o + dir * (t_enter + 1e-4);
        ivec3 c = clamp(ivec3(floor(q)), ivec3(0), ivec3(res - 1));
        ivec3 step_dir = ivec3(sign(dir));
        vec3 next = (vec3(c) + max(vec3(step_dir), vec3(0.0)) - o) * inv;
        vec3 delta = abs(inv);
        for (int i = 0; i < 3 * res + 3; i++) {
            if (any(lessThan(c, ivec3(0))) || any(greaterThanEqual(c, ivec3(res)))) break;
            if (pass.mode == 4u) {
                vec3 uvw = (vec3(c) + 0.5) / float(res);
                vec4 s = sample_directional(uvw, dir, float(level));
                if (s.a > 0.0) { result = vec4(s.rgb / frame.tuning.y, 1.0); break; }
            } else if (pass.mode == 3u) {
                vec4 s = texelFetch(radiance_tex, c, 0);
#ifndef PAPER
                s.rgb += texelFetch(glossy_radiance_tex, c, 0).rgb;
                // Seen from behind its surface, a voxel that holds its back's light shows it.
                if (s.a > 0.0 && dot(texelFetch(emit_dir_tex, c, 0).xyz, dir) > 0.0
                    && open_back(c, load_voxel(c))) {
                    s.rgb = texelFetch(back_radiance_tex, c, 0).rgb;
                }
#endif
                if (s.a > 0.0) { result = vec4(s.rgb / frame.tuning.y, 1.0); break; }
            } else {
                Voxel v = load_voxel(c);
                if (v.filled) {
                    vec3 value = pass.mode == 0u ? v.albedo
                               : (pass.mode == 1u ? v.normal * 0.5 + 0.5 : v.emission);
                    result = vec4(value, 1.0);
                    break;
                }
            }
            // Step into the neighbour whose boundary the ray crosses first.
            if (next.x <= next.y && next.x <= next.z) { c.x += step_dir.x; next.x += delta.x; }
            else if (next.y <= next.z) { c.y += step_dir.y; next.y += delta.y; }
            else { c.z += step_dir.z; next.z += delta.z; }
        }
    }
    imageStore(view_out, px, result);
}
