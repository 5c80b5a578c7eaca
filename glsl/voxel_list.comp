#version 450
// variants: PAPER
// The list of filled voxels, for the second bounce: it then runs one invocation per surface
// voxel instead of one per grid cell (a dense dispatch leaves most SIMD lanes idle beside a
// wall, and the bounce's cones are the frame's most expensive work). Not a step of the paper:
// the result is the same, only the dispatch changes.
#include "common.glsl"
#include "voxel_common.glsl"
#define VOXEL_SET 1
#include "voxel_data.glsl"

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(set = 1, binding = 6, std430) buffer VoxelList {
    uint dispatch_x, dispatch_y, dispatch_z; // the bounce's indirect dispatch, groups of 64 in
                                             // rows of at most ROW (inject_bounce.comp)
    uint count;                              // filled voxels (may exceed the capacity)
    uint coords[];                           // x | y << 10 | z << 20
};

// Groups per row of the bounce's dispatch: a large grid's surfaces need more groups than a
// device must allow in one dimension (maxComputeWorkGroupCount: 65535).
const uint ROW = 4096u;

void main() {
    ivec3 c = ivec3(gl_GlobalInvocationID);
    if (!in_grid(c) || !voxel_filled(c)) return;
    uint i = atomicAdd(count, 1u);
    if (i >= uint(coords.length())) return;
    coords[i] = uint(c.x) | (uint(c.y) << 10) | (uint(c.z) << 20);
    if (i % 64u == 0u) {
        uint groups = i / 64u + 1u;
        atomicMax(dispatch_x, min(groups, ROW));
        atomicMax(dispatch_y, (groups + ROW - 1u) / ROW);
    }
}
