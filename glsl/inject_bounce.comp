#version 450
// variants: PAPER
// Second bounce (the paper's inject_propagation): every voxel gathers the light the directional
// volumes hold around it with diffuse cones and adds what it reflects to its radiance; the mip
// passes then run again. Default: the pixel pass's cone set and albedo / pi; a two-sided voxel
// gathers both sides. PAPER: 4 cones of aperture 1, weights pi/3 and 2pi/9, clamped to 1.
#include "common.glsl"
#include "voxel_common.glsl"
#define VOXEL_SET 1
#include "voxel_data.glsl"
#define CONE_SET 2
#define CONE_FULL_RES 0
#include "cone_tracing.glsl"

// One invocation per filled voxel, from the list voxel_list.comp made.
layout(local_size_x = 64) in;

layout(set = 1, binding = 6, std430) readonly buffer VoxelList {
    uint dispatch_x, dispatch_y, dispatch_z;
    uint count;
    uint coords[];
};

#ifdef PAPER
layout(set = 1, binding = 5, rgba8) uniform image3D radiance;
#else
layout(set = 1, binding = 5, rgba16f) uniform image3D radiance;
// Where the voxel's light goes (inject_radiance.comp): a two-sided voxel's bounce light goes
// to the sides it fell on, as its direct light does.
layout(set = 1, binding = 9, rgba8_snorm) uniform image3D emit_dir;
#endif

vec3 gather(vec3 p, vec3 n) {
    mat3 frame_n = tangent_frame(n);
    float vs = voxel_size();
    float max_dist = frame.cone.z * frame.grid.w;
    vec3 e = vec3(0.0);
#ifdef PAPER
    const vec3 dirs[4] = vec3[4](vec3(0.0, 0.0, 1.0), vec3(0.0, 0.866025, 0.5),
                                 vec3(0.754996, -0.4330128, 0.5), vec3(-0.754996, -0.4330128, 0.5));
    const float weights[4] = float[4](PI / 3.0, 2.0 * PI / 9.0, 2.0 * PI / 9.0, 2.0 * PI / 9.0);
    vec3 origin = p + n * 2.0 * vs;  // one directional-volume texel
    for (int i = 0; i < 4; i++) {
        vec3 d = normalize(frame_n * dirs[i]);
        e += weights[i] * trace_cone(origin, d, 1.0, 2.0 * vs, max_dist).radiance;
    }
#else
    // From a voxel centre, which can lie up to sqrt(3)/2 voxel behind its surface: one voxel
    // further out than the pixels' cones start.
    vec3 origin = p + n * (frame.trace.x + 1.0) * vs;
    for (uint i = 0u; i < frame.grid_info.z; i++) {
        vec3 d = normalize(frame_n * frame.cones[i].xyz);
        e += frame.cones[i].w * trace_cone(origin, d, frame.cone.x, vs, max_dist).radiance;
    }
#endif
    return e;
}

void main() {
    // Rows of groups (voxel_list.comp): the list's index runs along x, then y.
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u;
    if (i >= min(count, uint(coords.length()))) return;
    uint packed = coords[i];
    ivec3 c = ivec3(packed & 1023u, (packed >> 10) & 1023u, packed >> 20);
    Voxel v = load_voxel(c);
    if (!v.filled) return;
    vec4 direct = imageLoad(radiance, c);
#ifdef PAPER
    vec3 p = frame.grid.xyz + vec3(c) * voxel_size();
    vec3 n = dot(v.normal, v.normal) > 0.0 ? v.normal : vec3(0.0, 1.0, 0.0);
    vec3 bounce = clamp(gather(p, n), 0.0, 1.0) * v.albedo;
#else
    vec3 p = voxel_centre(c);
    vec3 n = dot(v.normal, v.normal) > 0.0 ? v.normal
           : (v.axis_weights.x >= max(v.axis_weights.y, v.axis_weights.z) ? vec3(1.0, 0.0, 0.0)
           : (v.axis_weights.y >= v.axis_weights.z ? vec3(0.0, 1.0, 0.0) : vec3(0.0, 0.0, 1.0)));
    vec3 bounce;
    if (v.agreement < 0.5) {
        // Two-sided: each face reflects what falls on its side; the voxel holds their mean,
        // and its light goes where the brighter side faces (as inject_radiance.comp's direct
        // light does), not every way: a thin wall lit on one side stays dark on the other.
        vec3 front = v.albedo / PI * gather(p, n);
        vec3 back = v.albedo / PI * gather(p, -n);
        bounce = 0.5 * (front + back);
        float lf = luminance(front), lb = luminance(back);
        vec3 bounce_dir = n * (lf - lb) / max(lf + lb, 1e-30);
        vec3 dir = imageLoad(emit_dir, c).xyz;
        float ld = luminance(direct.rgb / frame.tuning.y), lbounce = luminance(bounce);
        vec3 going = (dir * ld + bounce_dir * lbounce) / max(ld + lbounce, 1e-30);
        float along = dot(going, going) > 0.0 ? dot(v.offset, normalize(going)) : 0.0;
        imageStore(emit_dir, c, vec4(going, along));
    } else {
        bounce = v.albedo / PI * gather(p, n);
    }
#endif
    imageStore(radiance, c, vec4(direct.rgb + bounce * frame.tuning.y, direct.a));
}
