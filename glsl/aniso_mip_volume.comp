#version 450
// variants: PAPER
// Anisotropic mipmapping, higher levels: each face volume's next level from its previous one,
// with the same front-to-back compositing, down to a single texel.
#include "aniso_mip.glsl"

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(set = 0, binding = 0, VOLUME_FORMAT) uniform readonly image3D src_nx;
layout(set = 0, binding = 1, VOLUME_FORMAT) uniform readonly image3D src_px;
layout(set = 0, binding = 2, VOLUME_FORMAT) uniform readonly image3D src_ny;
layout(set = 0, binding = 3, VOLUME_FORMAT) uniform readonly image3D src_py;
layout(set = 0, binding = 4, VOLUME_FORMAT) uniform readonly image3D src_nz;
layout(set = 0, binding = 5, VOLUME_FORMAT) uniform readonly image3D src_pz;
layout(set = 0, binding = 6, VOLUME_FORMAT) uniform writeonly image3D dst_nx;
layout(set = 0, binding = 7, VOLUME_FORMAT) uniform writeonly image3D dst_px;
layout(set = 0, binding = 8, VOLUME_FORMAT) uniform writeonly image3D dst_ny;
layout(set = 0, binding = 9, VOLUME_FORMAT) uniform writeonly image3D dst_py;
layout(set = 0, binding = 10, VOLUME_FORMAT) uniform writeonly image3D dst_nz;
layout(set = 0, binding = 11, VOLUME_FORMAT) uniform writeonly image3D dst_pz;
#ifndef PAPER
layout(set = 0, binding = 12, rgba16f) uniform readonly image3D src_dir;
layout(set = 0, binding = 13, rgba16f) uniform writeonly image3D dst_dir;
layout(set = 0, binding = 14, rgba16f) uniform readonly image3D src_pos;
layout(set = 0, binding = 15, rgba16f) uniform writeonly image3D dst_pos;
#endif

#define REDUCE(SRC, DST, FACE)                                                              \
    for (int i = 0; i < 8; i++) {                                                          \
        ivec3 s = 2 * c + ivec3(i & 1, (i >> 1) & 1, (i >> 2) & 1);                        \
        block[i] = all(lessThan(s, imageSize(SRC))) ? imageLoad(SRC, s) : vec4(0.0);       \
    }                                                                                      \
    imageStore(DST, c, reduce_block(block, FACE));

void main() {
    ivec3 c = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(c, imageSize(dst_nx)))) return;
    vec4 block[8];
    REDUCE(src_nx, dst_nx, 0)
    REDUCE(src_px, dst_px, 1)
    REDUCE(src_ny, dst_ny, 2)
    REDUCE(src_py, dst_py, 3)
    REDUCE(src_nz, dst_nz, 4)
    REDUCE(src_pz, dst_pz, 5)
#ifndef PAPER
    // Where the light goes and where it lies: the means of the block's (luminance-weighted)
    // directions and positions.
    vec4 going = vec4(0.0);
    vec4 lies = vec4(0.0);
    for (int i = 0; i < 8; i++) {
        ivec3 s = 2 * c + ivec3(i & 1, (i >> 1) & 1, (i >> 2) & 1);
        if (all(lessThan(s, imageSize(src_dir)))) {
            going += imageLoad(src_dir, s);
            lies += imageLoad(src_pos, s);
        }
    }
    imageStore(dst_dir, c, going * 0.125);
    imageStore(dst_pos, c, lies * 0.125);
#endif
}
