// The list of pixels whose area-light shadow may hide an emitter's faces (deferred_lighting.comp's
// AREA_FACES writes it, area_faces.comp runs over it: an indirect dispatch's arguments, a count,
// then up to one entry per pixel; lights.glsl's hidden_by_support says which).
#ifndef AREA_FACES_GLSL
#define AREA_FACES_GLSL

// Groups per row of area_faces.comp's dispatch (maxComputeWorkGroupCount may be 65535 per axis).
const uint FACES_ROW = 4096u;

#endif
