#version 450
// The paper's clear_dynamic: zeroes the voxels no static geometry wrote (flag 0), so that the
// dynamic pass can voxelize moving geometry again while static voxels stay.
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(set = 0, binding = 0, r32ui) uniform writeonly uimage3D paper_albedo;
layout(set = 0, binding = 1, r32ui) uniform writeonly uimage3D paper_normal;
layout(set = 0, binding = 2, r32ui) uniform writeonly uimage3D paper_emission;
layout(set = 0, binding = 3, r8) uniform readonly image3D paper_flag;
layout(push_constant) uniform Clear {
    uint emissive;  // the emission volume is in use (else one texel, never written)
} clear;

void main() {
    ivec3 c = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(c, imageSize(paper_albedo))) || imageLoad(paper_flag, c).r > 0.0) {
        return;
    }
    imageStore(paper_albedo, c, uvec4(0u));
    imageStore(paper_normal, c, uvec4(0u));
    if (clear.emissive != 0u) imageStore(paper_emission, c, uvec4(0u));
}
