// What the bounce passes (inject_bounce.comp, bounce_tail.comp) share: the filled voxels
// voxel_list.comp listed, one invocation per entry in rows of groups of 64 (the list's index
// runs along x, then y), and the fixed point of the reflectance sums.
#ifndef BOUNCE_COMMON_GLSL
#define BOUNCE_COMMON_GLSL

layout(set = 1, binding = 6, std430) readonly buffer VoxelList {
    uint dispatch_x, dispatch_y, dispatch_z;
    uint count;
    uint coords[];
};

// The reflectance sums hold this per voxel (64-bit fixed point: low word, high word).
const float REFLECTANCE_ONE = 65536.0;

// This invocation's entry of the list.
uint list_entry() {
    return gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * 64u;
}

// Whether the list holds entry i (the count may exceed the list's room).
bool listed(uint i) {
    return i < min(count, uint(coords.length()));
}

ivec3 listed_voxel(uint i) {
    uint packed = coords[i];
    return ivec3(packed & 1023u, (packed >> 10) & 1023u, packed >> 20);
}

#endif
