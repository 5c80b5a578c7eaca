#version 450
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
// The paper's clear_dynamic: zeroes the voxels no static geometry wrote (flag 0), so that the
// dynamic pass can voxelize moving geometry again while static voxels stay.
layout(local_size_x = 64) in;

layout(buffer_reference, std430, buffer_reference_align = 4) buffer Words { uint w[]; };
// The paper's words (voxel_common.glsl, PAPER_*): albedo, normal, emission (a zero address when
// the scene emits nothing), static flags.
layout(set = 0, binding = 0, std430) readonly buffer PaperWords { uvec2 paper_words[4]; };
layout(push_constant) uniform Clear { uint voxels; } clear;

void main() {
    // Rows of groups (voxelize.rs): a large grid needs more than a dimension's 65535.
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u;
    Words albedo_grid = Words(paper_words[0]);
    Words normal_grid = Words(paper_words[1]);
    Words static_flag = Words(paper_words[3]);
    if (i >= clear.voxels || static_flag.w[i] != 0u) return;
    albedo_grid.w[i] = 0u;
    normal_grid.w[i] = 0u;
    if (paper_words[2] != uvec2(0u)) Words(paper_words[2]).w[i] = 0u;
}
