// The list of pixels whose area-light shadow may hide an emitter's faces (deferred_lighting.comp's
// AREA_FACES writes it, area_faces.comp runs over it: an indirect dispatch's arguments, a count,
// then up to one entry per pixel; lights.glsl's hidden_by_support says which).
#ifndef AREA_FACES_GLSL
#define AREA_FACES_GLSL

// Groups per row of area_faces.comp's dispatch (maxComputeWorkGroupCount may be 65535 per axis).
const uint FACES_ROW = 4096u;

// The list: area_faces.comp reads it (FACES_LIST_READONLY), the lighting pass appends to it.
#ifdef FACES_LIST_READONLY
layout(set = 1, binding = 9, std430) readonly buffer FacesList {
#else
layout(set = 1, binding = 9, std430) buffer FacesList {
#endif
    uint dispatch_x, dispatch_y, dispatch_z;
    uint count;
    uint pixels[];  // x | y << 16
};

#ifndef FACES_LIST_READONLY
// Appends px to the list, growing the dispatch by a group every 64 pixels.
void list_pixel(ivec2 px) {
    uint i = atomicAdd(count, 1u);
    if (i >= uint(pixels.length())) return;
    pixels[i] = uint(px.x) | (uint(px.y) << 16);
    if (i % 64u == 0u) {
        uint groups = i / 64u + 1u;
        atomicMax(dispatch_x, min(groups, FACES_ROW));
        atomicMax(dispatch_y, (groups + FACES_ROW - 1u) / FACES_ROW);
    }
}
#endif

#endif
