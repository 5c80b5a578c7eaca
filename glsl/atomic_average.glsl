// imageAtomicRGBA8Avg, as the paper uses it (Crassin and Green, OpenGL Insights ch. 22): a
// compare-and-swap moving average of RGBA8 values, the count in the 8-bit alpha. Kept exactly,
// flaws included, for --paper: the count wraps after 255 fragments, every round truncates,
// values above 1 wrap, and a fragment that loses 255 rounds is dropped.
#ifndef ATOMIC_AVERAGE_GLSL
#define ATOMIC_AVERAGE_GLSL

vec4 unpack_rgba8(uint v) {
    return vec4(float(v & 0xFFu), float((v >> 8u) & 0xFFu), float((v >> 16u) & 0xFFu),
                float((v >> 24u) & 0xFFu));
}

uint pack_rgba8(vec4 v) {
    // uint(x) & 0xFF per channel: truncation, and wrap-around above 255.
    return (uint(v.x) & 0xFFu) | ((uint(v.y) & 0xFFu) << 8u) | ((uint(v.z) & 0xFFu) << 16u)
         | ((uint(v.w) & 0xFFu) << 24u);
}

// Each voxel is one 32-bit word of an r32ui 3D image, the bits of an RGBA8 texel. The loop
// retries until no other fragment changed the word between its read and its swap. The
// original takes the image as a parameter, `layout(r32ui) coherent volatile uimage3D grid`;
// GLSL for Vulkan allows no format on a parameter, and image atomics need one, so the function
// is written out once per volume: IMAGE_ATOMIC_RGBA8_AVG(grid) defines
// imageAtomicRGBA8Avg_grid(ivec3 coords, vec4 value) for the image named grid.
#define IMAGE_ATOMIC_RGBA8_AVG(grid) \
void imageAtomicRGBA8Avg_##grid(ivec3 coords, vec4 value) { \
    value.rgb *= 255.0; \
    uint new_value = pack_rgba8(vec4(value.rgb, 1.0)); \
    uint prev = 0u; \
    uint cur; \
    int iterations = 0; \
    while ((cur = imageAtomicCompSwap(grid, coords, prev, new_value)) != prev \
           && iterations < 255) { \
        prev = cur; \
        vec4 rval = unpack_rgba8(cur); \
        rval.rgb = rval.rgb * rval.a; \
        vec4 curf = rval + vec4(value.rgb, 1.0); \
        curf.rgb /= curf.a; \
        new_value = pack_rgba8(curf); \
        iterations++; \
    } \
}

#endif
