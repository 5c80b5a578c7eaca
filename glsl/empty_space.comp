#version 450
// variants: AXIS
// Empty space, for cones to skip (not in the paper; cone_tracing.glsl). The grid in cells of
// `cell` voxels a side (src/gi/empty_space.rs): first each cell, 0 if it holds a filled voxel
// and EMPTY_FAR if not; then AXIS, once along each axis in turn, the distance along the
// farthest axis (Chebyshev) in cells to the nearest filled cell, capped at EMPTY_FAR. Every
// cell within d - 1 of a cell at distance d is empty: a box around it that a cone crosses
// without reading anything.

layout(local_size_x = 64) in;

const uint EMPTY_FAR = 255u;

#ifdef AXIS
// Cells per side at most (src/gi/empty_space.rs).
const int MAX_SIDE = 64;

layout(set = 0, binding = 1, r32ui) uniform uimage3D empty_space;

layout(push_constant) uniform Pass {
    uint axis;
} pass;

// Along the axis, every line at once (an invocation each): d[i] = min over j of
// max(|i - j|, d[j]). From 0 / EMPTY_FAR along x it is the distance to the nearest filled cell
// in the line; along y, then z, the Chebyshev distance in the plane, then in the volume (the
// metric's transform is separable).
void main() {
    ivec3 m = imageSize(empty_space);
    int a = int(pass.axis);
    int b = (a + 1) % 3;
    int c = (a + 2) % 3;
    int line = int(gl_GlobalInvocationID.x);
    if (line >= m[b] * m[c]) return;
    ivec3 p = ivec3(0);
    p[b] = line % m[b];
    p[c] = line / m[b];
    uint d[MAX_SIDE];
    for (int i = 0; i < m[a]; i++) {
        p[a] = i;
        d[i] = imageLoad(empty_space, p).r;
    }
    for (int i = 0; i < m[a]; i++) {
        uint best = EMPTY_FAR;
        for (int j = 0; j < m[a]; j++) best = min(best, max(uint(abs(i - j)), d[j]));
        p[a] = i;
        imageStore(empty_space, p, uvec4(best));
    }
}
#else
layout(set = 0, binding = 0, rgba16f) uniform readonly image3D radiance;
layout(set = 0, binding = 1, r32ui) uniform writeonly uimage3D empty_space;

layout(push_constant) uniform Pass {
    uint cell;  // voxels per cell side
} pass;

void main() {
    ivec3 m = imageSize(empty_space);
    int i = int(gl_GlobalInvocationID.x);
    if (i >= m.x * m.y * m.z) return;
    ivec3 cell = ivec3(i % m.x, (i / m.x) % m.y, i / (m.x * m.y));
    ivec3 n = imageSize(radiance);
    int s = int(pass.cell);
    ivec3 first = cell * s;
    ivec3 last = min(first + s, n);
    bool filled = false;
    for (int z = first.z; z < last.z && !filled; z++) {
        for (int y = first.y; y < last.y && !filled; y++) {
            for (int x = first.x; x < last.x && !filled; x++) {
                // A filled voxel's radiance has opacity 1 (inject_radiance.comp).
                filled = imageLoad(radiance, ivec3(x, y, z)).a > 0.0;
            }
        }
    }
    imageStore(empty_space, cell, uvec4(filled ? 0u : EMPTY_FAR));
}
#endif
