#version 450
// The paper's clear_dynamic: zeroes the voxels no static geometry wrote (flag 0), so that the
// dynamic pass can voxelize moving geometry again while static voxels stay.
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(set = 0, binding = 0, r32ui) uniform uimage3D albedo_grid;
layout(set = 0, binding = 1, r32ui) uniform uimage3D normal_grid;
layout(set = 0, binding = 2, r32ui) uniform uimage3D emission_grid;
layout(set = 0, binding = 3, r32ui) uniform readonly uimage3D static_flag;

void main() {
    ivec3 c = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(c, imageSize(static_flag)))) return;
    if (imageLoad(static_flag, c).r != 0u) return;
    imageStore(albedo_grid, c, uvec4(0u));
    imageStore(normal_grid, c, uvec4(0u));
    imageStore(emission_grid, c, uvec4(0u));
}
