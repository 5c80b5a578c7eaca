#version 450
// variants: PAPER
// Anisotropic mipmapping, base level: each texel of the six half-resolution face volumes from a
// 2x2x2 block of the radiance volume.
#include "aniso_mip.glsl"

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(set = 0, binding = 0, VOLUME_FORMAT) uniform readonly image3D radiance;
layout(set = 0, binding = 1, VOLUME_FORMAT) uniform writeonly image3D face_nx;
layout(set = 0, binding = 2, VOLUME_FORMAT) uniform writeonly image3D face_px;
layout(set = 0, binding = 3, VOLUME_FORMAT) uniform writeonly image3D face_ny;
layout(set = 0, binding = 4, VOLUME_FORMAT) uniform writeonly image3D face_py;
layout(set = 0, binding = 5, VOLUME_FORMAT) uniform writeonly image3D face_nz;
layout(set = 0, binding = 6, VOLUME_FORMAT) uniform writeonly image3D face_pz;

void main() {
    ivec3 c = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(c, imageSize(face_nx)))) return;
    vec4 block[8];
    for (int i = 0; i < 8; i++) {
        ivec3 s = 2 * c + ivec3(i & 1, (i >> 1) & 1, (i >> 2) & 1);
        // Odd sizes: the block's far half lies outside the source and is empty.
        block[i] = all(lessThan(s, imageSize(radiance))) ? imageLoad(radiance, s) : vec4(0.0);
    }
    imageStore(face_nx, c, reduce_block(block, 0));
    imageStore(face_px, c, reduce_block(block, 1));
    imageStore(face_ny, c, reduce_block(block, 2));
    imageStore(face_py, c, reduce_block(block, 3));
    imageStore(face_nz, c, reduce_block(block, 4));
    imageStore(face_pz, c, reduce_block(block, 5));
}
