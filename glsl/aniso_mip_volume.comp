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
// The thin walls (aniso_mip_base.comp); one texel, bound both ways and skipped, without a
// bounce.
layout(set = 0, binding = 16, rgba16f) uniform readonly image3D src_thin_walls_xy;
layout(set = 0, binding = 17, rgba16f) uniform writeonly image3D dst_thin_walls_xy;
layout(set = 0, binding = 18, rgba16f) uniform readonly image3D src_thin_walls_z;
layout(set = 0, binding = 19, rgba16f) uniform writeonly image3D dst_thin_walls_z;
// 1: make the thin walls (as aniso_mip_base.comp).
layout(push_constant) uniform Push {
    uint walls;
} push;
#endif

#ifdef PAPER
// The original's 2x2x2 blocks: a level of odd size drops its last texel (Vulkan rounds mip
// sizes down), so the coarser levels no longer reach the grid's far end.
#define REDUCE(SRC, DST, FACE)                                                              \
    for (int i = 0; i < 8; i++) {                                                          \
        ivec3 s = 2 * c + ivec3(i & 1, (i >> 1) & 1, (i >> 2) & 1);                        \
        block[i] = all(lessThan(s, imageSize(SRC))) ? imageLoad(SRC, s) : vec4(0.0);       \
    }                                                                                      \
    imageStore(DST, c, reduce_block(block, FACE));
#else
// Source texels lo..hi (2 or, for the last texel of a level of odd size, 3 along an axis):
// along the face's direction composited front to back, across it averaged, as reduce_block.
#define REDUCE(SRC, DST, FACE)                                                              \
    {                                                                                      \
        int axis = FACE / 2;                                                               \
        bool high_first = (FACE % 2) == 0;                                                 \
        int u = (axis + 1) % 3;                                                            \
        int w = (axis + 2) % 3;                                                            \
        vec4 sum = vec4(0.0);                                                              \
        for (int a = 0; a < count[u]; a++) {                                               \
            for (int b = 0; b < count[w]; b++) {                                           \
                vec4 acc = vec4(0.0);                                                      \
                for (int k = 0; k < count[axis]; k++) {                                    \
                    ivec3 s = lo;                                                          \
                    s[u] += a;                                                             \
                    s[w] += b;                                                             \
                    s[axis] += high_first ? count[axis] - 1 - k : k;                       \
                    acc += imageLoad(SRC, s) * (1.0 - acc.a);                              \
                }                                                                          \
                sum += acc;                                                                \
            }                                                                              \
        }                                                                                  \
        imageStore(DST, c, sum / float(count[u] * count[w]));                              \
    }
#endif

void main() {
    ivec3 c = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(c, imageSize(dst_nx)))) return;
#ifdef PAPER
    vec4 block[8];
#else
    // A texel holds the two texels below it, and the last texel of a level of odd size the
    // third too: every level ends where the grid does. (Padding the base level up to a power
    // of two instead left the walls at the grid's far end in coarse texels mostly past it,
    // which a cone across a room read as nearly empty.)
    ivec3 src = imageSize(src_nx);
    ivec3 lo = 2 * c;
    ivec3 hi = mix(min(lo + 1, src - 1), src - 1, equal(c, imageSize(dst_nx) - 1));
    ivec3 count = hi - lo + 1;
#endif
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
    for (int x = lo.x; x <= hi.x; x++) {
        for (int y = lo.y; y <= hi.y; y++) {
            for (int z = lo.z; z <= hi.z; z++) {
                going += imageLoad(src_dir, ivec3(x, y, z));
                lies += imageLoad(src_pos, ivec3(x, y, z));
            }
        }
    }
    float n = float(count.x * count.y * count.z);
    imageStore(dst_dir, c, going / n);
    imageStore(dst_pos, c, lies / n);
    // The thin walls' cover per axis: the block's columns along it, each covered by the texels
    // it holds one after another (their covers added, up to 1), averaged; along the axis the
    // block reaches a texel further on either side, as the base level's. Where they lie:
    // weighted by their cover.
    if (push.walls == 0u || imageSize(src_thin_walls_xy) != src) return;
    vec3 cover = vec3(0.0), at = vec3(0.0);
    for (int x = lo.x - 1; x <= hi.x + 1; x++) {
        for (int y = lo.y - 1; y <= hi.y + 1; y++) {
            for (int z = lo.z - 1; z <= hi.z + 1; z++) {
                ivec3 t = ivec3(x, y, z);
                if (any(lessThan(t, ivec3(0))) || any(greaterThanEqual(t, src))) continue;
                bvec3 inside = bvec3(x >= lo.x && x <= hi.x, y >= lo.y && y <= hi.y,
                                     z >= lo.z && z <= hi.z);
                vec3 across = vec3(inside.y && inside.z, inside.x && inside.z,
                                   inside.x && inside.y);
                vec4 wxy = imageLoad(src_thin_walls_xy, t);
                vec2 wz = imageLoad(src_thin_walls_z, t).xy;
                cover += across * vec3(wxy.y, wxy.w, wz.y);
                at += across * vec3(wxy.x, wxy.z, wz.x);
            }
        }
    }
    at /= max(cover, vec3(1e-6));  // 0 where nothing covers
    vec3 columns = vec3(count.y * count.z, count.x * count.z, count.x * count.y);
    cover = min(cover / columns, vec3(1.0));
    imageStore(dst_thin_walls_xy, c, vec4(cover.x * at.x, cover.x, cover.y * at.y, cover.y));
    imageStore(dst_thin_walls_z, c, vec4(cover.z * at.z, cover.z, 0.0, 0.0));
#endif
}
