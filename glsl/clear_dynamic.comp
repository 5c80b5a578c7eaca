#version 450
// The paper's clear_dynamic: zeroes the voxels no static geometry wrote (flag 0), so that the
// dynamic pass can voxelize moving geometry again while static voxels stay. The averages are
// read and written as RGBA8 texels, as the original does (voxelize.frag writes their r32ui
// views).
layout(local_size_x = 8, local_size_y = 8, local_size_z = 8) in;

layout(set = 0, binding = 0, rgba8) uniform image3D paper_albedo;
layout(set = 0, binding = 1, rgba8) uniform writeonly image3D paper_normal;
layout(set = 0, binding = 2, rgba8) uniform writeonly image3D paper_emission;
layout(set = 0, binding = 3, r8) uniform readonly image3D paper_flag;
layout(push_constant) uniform Clear {
    uint emissive;  // the emission volume is in use (else one texel, never written)
} clear;

const float EPSILON = 1e-30;

void main() {
    ivec3 c = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(c, imageSize(paper_albedo)))) return;
    if (imageLoad(paper_albedo, c).a < EPSILON) return;     // empty voxel
    if (imageLoad(paper_flag, c).r > EPSILON) return;       // a static voxel stays
    imageStore(paper_albedo, c, vec4(0.0));
    imageStore(paper_normal, c, vec4(0.0));
    if (clear.emissive != 0u) imageStore(paper_emission, c, vec4(0.0));
}
