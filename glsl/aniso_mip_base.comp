#version 450
// variants: PAPER
// Anisotropic mipmapping, base level: each texel of the six half-resolution face volumes from a
// 2x2x2 block of the radiance volume. PAPER: every voxel shines the same every way. Default: a
// voxel's light shows in a face volume only as far as it goes that way (facing() below).
#include "aniso_mip.glsl"

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(set = 0, binding = 0, VOLUME_FORMAT) uniform readonly image3D radiance;
layout(set = 0, binding = 1, VOLUME_FORMAT) uniform writeonly image3D face_nx;
layout(set = 0, binding = 2, VOLUME_FORMAT) uniform writeonly image3D face_px;
layout(set = 0, binding = 3, VOLUME_FORMAT) uniform writeonly image3D face_ny;
layout(set = 0, binding = 4, VOLUME_FORMAT) uniform writeonly image3D face_py;
layout(set = 0, binding = 5, VOLUME_FORMAT) uniform writeonly image3D face_nz;
layout(set = 0, binding = 6, VOLUME_FORMAT) uniform writeonly image3D face_pz;
#ifndef PAPER
layout(set = 0, binding = 7, rgba8_snorm) uniform readonly image3D emit_dir;
layout(set = 0, binding = 8, rgba16f) uniform writeonly image3D light_dir;
layout(set = 0, binding = 9, rgba16f) uniform writeonly image3D light_pos;
// The luminance of each voxel's light that comes from emitters smaller than it
// (inject_radiance.comp); one texel, not read, when the scene emits nothing.
layout(set = 0, binding = 10, r32f) uniform readonly image3D small_emission;
// The light of open backs (inject_radiance.comp), going against emit_dir; one texel, not read,
// without GiSettings::backs.
layout(set = 0, binding = 11, rgba16f) uniform readonly image3D back_radiance;
// The thin walls per axis: where they lie (times their cover) and how much of the texel's
// cross-section they cover; x and y, then z (Volumes::thin_walls). One texel, not written,
// without a bounce.
layout(set = 0, binding = 12, rgba16f) uniform writeonly image3D thin_walls_xy;
layout(set = 0, binding = 13, rgba16f) uniform writeonly image3D thin_walls_z;
// The light of mirror-like lobes (inject_radiance.comp), which the full-resolution volume leaves
// out: the directional volumes, which wide cones read, hold it.
layout(set = 0, binding = 14, rgba16f) uniform readonly image3D glossy_radiance;
// 1: make the thin walls (the first mip pass after the voxels are lit; they hold through the
// bounces, changing with the voxels rather than the light).
layout(push_constant) uniform Push {
    uint walls;
} push;
#endif

#ifndef PAPER
// A cone travelling along `face` sees a voxel's light only if the voxel sends it back against
// the cone's travel (emit_dir, from inject_radiance.comp: where its light goes): fully for
// directions up to the surface's plane, fading to nothing 30 degrees behind it. The paper's
// voxels shine every way, so a wall's lit side shows through its back (light leaks) and a
// cone leaving a surface sees the emitter beside it in the same plane. The opacity stays: a
// surface blocks light from both sides.
// `small`: the share of the voxel's light from emitters smaller than it, shown to the side by
// the cosine (small_emitter_shown).
vec3 face_towards(int face) {
    vec3 towards = vec3(0.0);
    towards[face / 2] = (face % 2 == 0) ? 1.0 : -1.0;  // against the cone's travel
    return towards;
}

vec4 facing(vec4 v, vec3 dir, float small, int face) {
    vec3 towards = face_towards(face);
    float shown = seen_from(dir, towards) * (1.0 - small * (1.0 - small_emitter_shown(dir, towards)));
    return vec4(v.rgb * shown, v.a);
}

// The thin walls around texel c: a filled voxel with empty voxels on both sides along the axis
// it faces most (by its light's direction: a one-sided voxel's normal, a thin wall's lit side),
// within the grid, covers its column along each axis as much as it faces that axis; four
// columns a block. Along each axis the block reaches a voxel further on either side, so that a
// sample beside a wall reads its whole cover. Where they lie: the voxels' surfaces (emit_dir.w
// along the direction from the centre), weighted by their cover.
void thin_walls(ivec3 c) {
    ivec3 size = imageSize(radiance);
    float n = float(size.x);
    vec3 cover = vec3(0.0), at = vec3(0.0);
    for (int i = 0; i < 64; i++) {
        ivec3 o = ivec3(i & 3, (i >> 2) & 3, i >> 4);
        ivec3 s = 2 * c - 1 + o;
        if (any(lessThan(s, ivec3(0))) || any(greaterThanEqual(s, size))) continue;
        if (imageLoad(radiance, s).a <= 0.0) continue;
        vec4 e = imageLoad(emit_dir, s);
        float dd = dot(e.xyz, e.xyz);
        if (dd == 0.0) continue;
        vec3 faces = e.xyz * e.xyz / dd;
        int k = faces.x >= max(faces.y, faces.z) ? 0 : (faces.y >= faces.z ? 1 : 2);
        ivec3 step_k = ivec3(0);
        step_k[k] = 1;
        ivec3 below = s - step_k, above = s + step_k;
        if (any(lessThan(below, ivec3(0))) || any(greaterThanEqual(above, size))) continue;
        if (imageLoad(radiance, below).a > 0.0 || imageLoad(radiance, above).a > 0.0) continue;
        // Inside the block across each axis: o is 1 or 2 along the other two.
        bvec3 inside = bvec3(o.x == 1 || o.x == 2, o.y == 1 || o.y == 2, o.z == 1 || o.z == 2);
        vec3 across = vec3(inside.y && inside.z, inside.x && inside.z, inside.x && inside.y);
        vec3 lies = (vec3(s) + 0.5 + e.w * e.xyz * inversesqrt(dd)) / n;
        cover += faces * across;
        at += faces * across * lies;
    }
    at /= max(cover, vec3(1e-6));  // 0 where nothing covers
    cover = min(cover * 0.25, vec3(1.0));
    imageStore(thin_walls_xy, c, vec4(cover.x * at.x, cover.x, cover.y * at.y, cover.y));
    imageStore(thin_walls_z, c, vec4(cover.z * at.z, cover.z, 0.0, 0.0));
}
#endif

#ifndef PAPER
// The far side of a thick wall: a filled voxel with no light whose first filled voxel behind it
// (against its normal, up to MAX_THICK voxels) is lit and faces the other way, and which faces
// the void. Returns its normal's axis, or -1. Seen edge-on (the face volumes of the other
// axes) such a voxel holds only opacity: a texel across the wall averaged the lit face with it
// into half the light at full opacity, where a single wall's empty column gives half the light
// at half the opacity, and closed rooms of thick walls lost up to a quarter of their light.
// Rays that meet it edge-on from the lit side would have met the lit face; head-on it still
// blocks.
const int MAX_THICK = 8;
int dark_back_of_lit_face(ivec3 s, vec4 v, vec3 back, vec3 dir) {
    if (v.a <= 0.0 || dot(v.rgb + back, vec3(1.0)) > 0.0 || dot(dir, dir) == 0.0) return -1;
    vec3 a = abs(dir);
    int k = a.x >= max(a.y, a.z) ? 0 : (a.y >= a.z ? 1 : 2);
    ivec3 step_k = ivec3(0);
    step_k[k] = dir[k] > 0.0 ? -1 : 1;
    ivec3 size = imageSize(radiance);
    bool lit_behind = false;
    for (int j = 1; j <= MAX_THICK; j++) {
        ivec3 t = s + step_k * j;
        if (any(lessThan(t, ivec3(0))) || any(greaterThanEqual(t, size))) return -1;
        vec4 u = imageLoad(radiance, t);
        if (u.a <= 0.0) continue;
        vec3 e = imageLoad(emit_dir, t).xyz;
        lit_behind = dot(u.rgb, vec3(1.0)) > 0.0 && e[k] * dir[k] < 0.0;
        break;
    }
    if (!lit_behind) return -1;
    // It faces the void (nothing in front of it to the grid's edge): the outside of a closed
    // room, not the dark side of a wall between two rooms, whose opacity keeps the lit room's
    // light out of the dark one.
    for (ivec3 t = s - step_k; all(greaterThanEqual(t, ivec3(0))) && all(lessThan(t, size));
         t -= step_k) {
        if (imageLoad(radiance, t).a > 0.0) return -1;
    }
    return k;
}
#endif

void main() {
    ivec3 c = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(c, imageSize(face_nx)))) return;
    vec4 block[8];
#ifndef PAPER
    vec4 dirs[8];
    float small[8];
    vec3 back[8];
    // The stand-in is one texel; a grid has at least two voxels a side (VoxelGrid::fit).
    bool emits = imageSize(small_emission) == imageSize(radiance);
    bool backs = imageSize(back_radiance) == imageSize(radiance);
#endif
    for (int i = 0; i < 8; i++) {
        ivec3 s = 2 * c + ivec3(i & 1, (i >> 1) & 1, (i >> 2) & 1);
        // Odd sizes: the block's far half lies outside the source and is empty.
        bool inside = all(lessThan(s, imageSize(radiance)));
        block[i] = inside ? imageLoad(radiance, s) : vec4(0.0);
#ifndef PAPER
        if (inside) block[i].rgb += imageLoad(glossy_radiance, s).rgb;
        dirs[i] = inside ? imageLoad(emit_dir, s) : vec4(0.0);
        back[i] = inside && backs ? imageLoad(back_radiance, s).rgb : vec3(0.0);
        float e = inside && emits ? imageLoad(small_emission, s).r : 0.0;
        float l = dot(block[i].rgb, vec3(0.2126, 0.7152, 0.0722));
        small[i] = l > 0.0 ? clamp(e / l, 0.0, 1.0) : 0.0;
#endif
    }
#ifdef PAPER
    imageStore(face_nx, c, reduce_block(block, 0));
    imageStore(face_px, c, reduce_block(block, 1));
    imageStore(face_ny, c, reduce_block(block, 2));
    imageStore(face_py, c, reduce_block(block, 3));
    imageStore(face_nz, c, reduce_block(block, 4));
    imageStore(face_pz, c, reduce_block(block, 5));
#else
    // Where the block's light goes, weighted by its luminance, for cones to see it only from
    // that side (cone_tracing.glsl): the face volumes, one per axis, cannot tell a cone that
    // meets a surface from its front from one that comes from behind its plane.
    // And where it lies: each voxel's surface (emit_dir.w: how far from its centre along its
    // light's direction), in grid units, weighted the same way. An open back's light goes the
    // other way from the same plane: it weighs the plane as the front's does, and its share
    // of the weight goes in light_pos.w (cone_tracing.glsl shows it from behind the plane).
    vec4 going = vec4(0.0);
    vec4 lies = vec4(0.0);
    float n = float(imageSize(radiance).x);
    for (int i = 0; i < 8; i++) {
        // Rec. 709 luminance, as common.glsl's luminance() (whose bindings clash with this pass's).
        float lb = dot(back[i], vec3(0.2126, 0.7152, 0.0722));
        float l = dot(block[i].rgb, vec3(0.2126, 0.7152, 0.0722)) + lb;
        going += vec4(dirs[i].xyz * l, l);
        ivec3 s = 2 * c + ivec3(i & 1, (i >> 1) & 1, (i >> 2) & 1);
        vec3 g = dot(dirs[i].xyz, dirs[i].xyz) > 0.0 ? normalize(dirs[i].xyz) : vec3(0.0);
        lies += vec4(l * (vec3(s) + 0.5 + dirs[i].w * g) / n, lb);
    }
    imageStore(light_dir, c, going * 0.125);
    imageStore(light_pos, c, lies * 0.125);
    if (push.walls != 0u && imageSize(thin_walls_xy) == imageSize(face_nx)) thin_walls(c);
    int hidden_axis[8];
    for (int i = 0; i < 8; i++) {
        ivec3 s = 2 * c + ivec3(i & 1, (i >> 1) & 1, (i >> 2) & 1);
        hidden_axis[i] = dark_back_of_lit_face(s, block[i], back[i], dirs[i].xyz);
    }
    for (int face = 0; face < 6; face++) {
        vec4 shown[8];
        for (int i = 0; i < 8; i++) {
            shown[i] = facing(block[i], dirs[i].xyz, small[i], face);
            shown[i].rgb += back[i] * seen_from(-dirs[i].xyz, face_towards(face));
            if (hidden_axis[i] >= 0 && hidden_axis[i] != face / 2) shown[i] = vec4(0.0);
        }
        vec4 r = reduce_block(shown, face);
        if (face == 0) imageStore(face_nx, c, r);
        else if (face == 1) imageStore(face_px, c, r);
        else if (face == 2) imageStore(face_ny, c, r);
        else if (face == 3) imageStore(face_py, c, r);
        else if (face == 4) imageStore(face_nz, c, r);
        else imageStore(face_pz, c, r);
    }
#endif
}
