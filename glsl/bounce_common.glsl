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

// The reflectance sums' fixed point (64 bits: low word, high word): this many steps a unit, a
// voxel's share at most REFLECTANCE_MAX units (a voxel's light is weighted by its gathered
// light, which the radiance scale keeps under about 1e4 times pi): 2^24 voxels of the most
// still fit in 64 bits, and light under a millionth rounds to nothing.
const float REFLECTANCE_ONE = 1048576.0;
const float REFLECTANCE_MAX = 1048576.0;
// Words of the tail's sums (inject_bounce.comp): 4 sums of 4 values, 2 words each.
const uint REFLECTANCE_WORDS = 32u;

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
