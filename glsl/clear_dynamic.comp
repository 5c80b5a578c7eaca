#version 450
// The paper's clear_dynamic: zeroes the voxels no static geometry wrote (flag 0), so that the
// dynamic pass can voxelize moving geometry again while static voxels stay.
layout(local_size_x = 64) in;

layout(set = 0, binding = 0, std430) buffer AlbedoGrid { uint albedo_grid[]; };
layout(set = 0, binding = 1, std430) buffer NormalGrid { uint normal_grid[]; };
layout(set = 0, binding = 2, std430) buffer EmissionGrid { uint emission_grid[]; };
layout(set = 0, binding = 3, std430) readonly buffer StaticFlag { uint static_flag[]; };

void main() {
    // Rows of groups (voxelize.rs): a large grid needs more than a dimension's 65535.
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u;
    if (i >= uint(static_flag.length()) || static_flag[i] != 0u) return;
    albedo_grid[i] = 0u;
    normal_grid[i] = 0u;
    if (i < uint(emission_grid.length())) emission_grid[i] = 0u;
}
