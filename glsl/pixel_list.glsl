// A list of pixels that drives an indirect dispatch (groups of 64 in rows of PIXEL_LIST_ROW):
// the dispatch's arguments, a count, then up to one entry per pixel, x | y << 16; gi/mod.rs's
// record_list_clear empties it. The including shader defines PIXEL_LIST (the block's name),
// PIXEL_LIST_BINDING (in set 1) and, where it only reads the list, PIXEL_LIST_READONLY. The
// trace's unmatched pixels (cone_trace.comp) and the area lights' faces (area_faces.comp).

// Groups per row of the dispatch (maxComputeWorkGroupCount may be 65535 per axis).
const uint PIXEL_LIST_ROW = 4096u;

#ifdef PIXEL_LIST_READONLY
layout(set = 1, binding = PIXEL_LIST_BINDING, std430) readonly buffer PIXEL_LIST {
#else
layout(set = 1, binding = PIXEL_LIST_BINDING, std430) buffer PIXEL_LIST {
#endif
    uint dispatch_x, dispatch_y, dispatch_z;
    uint count;
    uint pixels[];
};

#ifdef PIXEL_LIST_READONLY
// The listed pixel this invocation of the indirect dispatch takes; false past the list's end.
bool listed_pixel(out ivec2 px) {
    uint i = (gl_WorkGroupID.y * PIXEL_LIST_ROW + gl_WorkGroupID.x) * 64u + gl_LocalInvocationID.x;
    if (i >= min(count, uint(pixels.length()))) return false;
    px = ivec2(pixels[i] & 0xffffu, pixels[i] >> 16);
    return true;
}
#else
// Appends px, growing the dispatch by a group every 64 pixels.
void list_pixel(ivec2 px) {
    uint i = atomicAdd(count, 1u);
    if (i >= uint(pixels.length())) return;
    pixels[i] = uint(px.x) | (uint(px.y) << 16);
    if (i % 64u == 0u) {
        uint groups = i / 64u + 1u;
        atomicMax(dispatch_x, min(groups, PIXEL_LIST_ROW));
        atomicMax(dispatch_y, (groups + PIXEL_LIST_ROW - 1u) / PIXEL_LIST_ROW);
    }
}
#endif
