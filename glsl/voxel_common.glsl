// The voxel grid: a cube of N^3 voxels over the scene (frame.grid), and the fixed-point
// accumulators the default voxelization averages into (sums and a 32-bit count per voxel, so
// the average neither wraps, drifts nor drops fragments as the paper's RGBA8 average does).
#ifndef VOXEL_COMMON_GLSL
#define VOXEL_COMMON_GLSL
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

// The voxel words lie in buffers reached by address: a 512^3 grid's sums (2 GiB a buffer) are
// larger than a storage buffer's descriptor may span (maxStorageBufferRange: 128 MiB on
// lavapipe). Each voxelization pass has a table of four addresses (volumes.rs), indexed by:
const uint WORDS_ALBEDO = 0u;
const uint WORDS_NORMAL = 1u;
const uint WORDS_SPREAD = 2u;
const uint WORDS_EMISSION = 3u;
// PAPER: one table, of its RGBA8 volumes and its static flags.
const uint PAPER_ALBEDO = 0u;
const uint PAPER_NORMAL = 1u;
const uint PAPER_EMISSION = 2u;
const uint PAPER_FLAG = 3u;
layout(buffer_reference, std430, buffer_reference_align = 4) buffer Words { uint w[]; };

// Per voxel, in three buffers (each within a 2 GiB allocation at 512^3): count, albedo r g b;
// normal x y z (two's complement) and where the surfaces cross the voxel along their
// projection's axis, from its centre (two's complement, in voxels); squared normal x y z and the
// luminance of the albedo's glossy part (voxelize.frag: voxel_albedo). The squared normals keep
// the axes a voxel's surfaces face even where opposite normals cancel.
const uint ALBEDO_STRIDE = 4u;
const uint NORMAL_STRIDE = 4u;
const uint SPREAD_STRIDE = 4u;
// Per voxel: emission r g b (scaled by frame.cone.w).
const uint EMISSION_STRIDE = 4u;  // RGB weighted by coverage, emitters' coverage (volumes.rs)
// 12 fractional bits: a 32-bit sum holds 2^20 fragments of value 1; the quantisation of one
// fragment (1/4096) is 16 times finer than the paper's 8-bit channels.
const float FIXED_ONE = 4096.0;

int grid_n() { return int(frame.grid_info.x); }
float voxel_size() { return frame.grid.w / float(frame.grid_info.x); }

// World position to grid texture coordinates [0, 1]^3.
vec3 world_to_grid(vec3 p) { return (p - frame.grid.xyz) / frame.grid.w; }
vec3 voxel_centre(ivec3 c) { return frame.grid.xyz + (vec3(c) + 0.5) * voxel_size(); }
bool in_grid(ivec3 c) { return all(greaterThanEqual(c, ivec3(0))) && all(lessThan(c, ivec3(grid_n()))); }
uint voxel_index(ivec3 c) { int n = grid_n(); return uint(c.x + n * (c.y + n * c.z)); }

#endif
