// Anisotropic mipmapping, step 3 of the paper: six directional volumes, one per direction a cone
// can travel (-X, +X, -Y, +Y, -Z, +Z). A texel of a face volume holds a 2x2x2 block seen from that
// direction: along the direction, the two voxels composite front to back
// (front + back * (1 - front.a), premultiplied); across it, the four columns average.
#ifndef ANISO_MIP_GLSL
#define ANISO_MIP_GLSL

#ifdef PAPER
#define VOLUME_FORMAT rgba8
#else
#define VOLUME_FORMAT rgba16f
#endif

// How much of the light a voxel or texel sends along `going` (its light direction, shorter
// where its light spreads) a cone sees when the light must come back against the cone's travel,
// along `towards`: all of it up to the surface's plane, fading to nothing 30 degrees behind it.
// The face volumes use it per axis (aniso_mip_base.comp), the cones' full-resolution samples
// per voxel with their own direction (cone_tracing.glsl).
float seen_from(vec3 going, vec3 towards) {
    return clamp(1.0 + 2.0 * dot(going, towards), 0.0, 1.0);
}

#ifndef PAPER
// An emitter smaller than its voxel sends its light along `going` (its normal, shorter where the
// voxel's light spreads) by the cosine, but a voxel shows one radiance to every side. The share of
// such light a face volume shows to a cone it comes back to along `towards`: all of it face on,
// SMALL_SIDE at right angles. With the cones' dir^2 weights a cone at angle t from the normal
// sees cos^2 t + SMALL_SIDE sin^2 t of it; SMALL_SIDE = 1/4 makes that send the emitter's own
// power over the hemisphere (the cosine's), where the voxel sent twice. The full-resolution
// samples (a cone's first two voxels, cone_tracing.glsl) keep the voxel's one radiance: showing
// it there too changed nothing measurable and cost a tenth of the trace.
const float SMALL_SIDE = 0.25;
float small_emitter_shown(vec3 going, vec3 towards) {
    float len = length(going);
    float c = len > 0.0 ? max(dot(going / len, towards), 0.0) : 1.0;
    return mix(1.0, SMALL_SIDE + (1.0 - SMALL_SIDE) * c, min(len, 1.0));
}
#endif

// block[x + 2y + 4z]: the 2x2x2 source texels; face 0..5 = -X, +X, -Y, +Y, -Z, +Z.
vec4 reduce_block(vec4 block[8], int face) {
    int axis = face / 2;
    // A cone travelling towards -axis meets the higher coordinate first.
    int front = (face % 2 == 0) ? 1 : 0;
    vec4 sum = vec4(0.0);
    for (int a = 0; a < 2; a++) {
        for (int b = 0; b < 2; b++) {
            ivec3 f, k;
            if (axis == 0) { f = ivec3(front, a, b); k = ivec3(1 - front, a, b); }
            else if (axis == 1) { f = ivec3(a, front, b); k = ivec3(a, 1 - front, b); }
            else { f = ivec3(a, b, front); k = ivec3(a, b, 1 - front); }
            vec4 fv = block[f.x + 2 * f.y + 4 * f.z];
            vec4 bv = block[k.x + 2 * k.y + 4 * k.z];
            sum += fv + bv * (1.0 - fv.a);
        }
    }
    return sum * 0.25;
}

#endif
