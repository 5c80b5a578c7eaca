// Reading a voxel back from what voxelization wrote. Define VOXEL_SET before including.
// Default: fixed-point sums and counts of the static and (when present) dynamic passes,
// averaged here. PAPER: the RGBA8 moving averages in r32ui images, empty when the 8-bit count
// reads 0.
#ifndef VOXEL_DATA_GLSL
#define VOXEL_DATA_GLSL

struct Voxel {
    bool filled;
    vec3 albedo;
    float glossy;       // the share of its reflected light a mirror's lobe sends one way (0 to
                        // 1): shown only to wide cones (voxelize.frag: voxel_albedo)
    vec3 normal;        // unit, or zero when the averaged normals cancelled
    float agreement;    // length of the averaged unit normals: 1 flat, ~0 opposite faces
    vec3 axis_weights;  // mean squared normal: how much the surfaces face each axis (sums to 1)
    vec3 emission;
    float emitter_cover; // of the voxel's face, by its emitters (0 to 1 or more; default only)
    vec3 offset;        // where its surfaces lie from its centre, mean, in voxels
};

#ifdef PAPER
// The paper's volumes as RGBA8 texels, as the original reads them (voxelize.frag wrote them
// through r32ui views; alpha is the 8-bit count over 255).
layout(set = VOXEL_SET, binding = 0, rgba8) readonly uniform image3D paper_albedo;
layout(set = VOXEL_SET, binding = 1, rgba8) readonly uniform image3D paper_normal;
layout(set = VOXEL_SET, binding = 2, rgba8) readonly uniform image3D paper_emission;

bool voxel_filled(ivec3 c) {
    return imageLoad(paper_albedo, c).a > 0.0;
}

Voxel load_voxel(ivec3 c) {
    Voxel v;
    vec4 a = imageLoad(paper_albedo, c);
    v.filled = a.a > 0.0;
    v.albedo = a.rgb;
    v.glossy = 0.0;
    vec3 n = imageLoad(paper_normal, c).rgb * 2.0 - 1.0;
    v.agreement = length(n);
    v.normal = v.agreement > 0.0 ? n / v.agreement : vec3(0.0);
    v.axis_weights = v.normal * v.normal;
    v.emission = (frame.grid_info.w & FLAG_EMISSIVE) != 0u
        ? imageLoad(paper_emission, c).rgb : vec3(0.0);
    v.offset = vec3(0.0);
    return v;
}
#else
// The static pass's words and the dynamic pass's (zero addresses without dynamic geometry).
// Bindings 4 to 6 are the passes' own (shadow map, radiance, voxel list).
layout(set = VOXEL_SET, binding = 0, std430) readonly buffer StaticWords { uvec2 static_words[4]; };
layout(set = VOXEL_SET, binding = 2, std430) readonly buffer DynamicWords { uvec2 dynamic_words[4]; };

bool voxel_filled(ivec3 c) {
    uint i = voxel_index(c) * ALBEDO_STRIDE;
    uint count = Words(static_words[WORDS_ALBEDO]).w[i];
    if ((frame.grid_info.w & FLAG_DYNAMIC) != 0u) count += Words(dynamic_words[WORDS_ALBEDO]).w[i];
    return count > 0u;
}

Voxel load_voxel(ivec3 c) {
    Voxel v;
    uint i = voxel_index(c) * ALBEDO_STRIDE;
    uint k = voxel_index(c) * NORMAL_STRIDE;
    uint q = voxel_index(c) * SPREAD_STRIDE;
    Words sa = Words(static_words[WORDS_ALBEDO]);
    Words sn = Words(static_words[WORDS_NORMAL]);
    Words ss = Words(static_words[WORDS_SPREAD]);
    uint count = sa.w[i];
    uvec3 a = uvec3(sa.w[i + 1u], sa.w[i + 2u], sa.w[i + 3u]);
    ivec3 n = ivec3(sn.w[k], sn.w[k + 1u], sn.w[k + 2u]);
    int off = int(sn.w[k + 3u]);
    uvec3 n2 = uvec3(ss.w[q], ss.w[q + 1u], ss.w[q + 2u]);
    uint g = ss.w[q + 3u];
    bool dynamic = (frame.grid_info.w & FLAG_DYNAMIC) != 0u;
    if (dynamic) {
        Words da = Words(dynamic_words[WORDS_ALBEDO]);
        Words dn = Words(dynamic_words[WORDS_NORMAL]);
        Words ds = Words(dynamic_words[WORDS_SPREAD]);
        count += da.w[i];
        a += uvec3(da.w[i + 1u], da.w[i + 2u], da.w[i + 3u]);
        n += ivec3(dn.w[k], dn.w[k + 1u], dn.w[k + 2u]);
        off += int(dn.w[k + 3u]);
        n2 += uvec3(ds.w[q], ds.w[q + 1u], ds.w[q + 2u]);
        g += ds.w[q + 3u];
    }
    v.filled = count > 0u;
    float inv = v.filled ? 1.0 / (float(count) * FIXED_ONE) : 0.0;
    v.albedo = vec3(a) * inv;
    float reflected = luminance(v.albedo);
    v.glossy = reflected > 0.0 ? clamp(float(g) * inv / reflected, 0.0, 1.0) : 0.0;
    vec3 nf = vec3(n) * inv;
    v.agreement = length(nf);
    v.normal = v.agreement > 1e-6 ? nf / v.agreement : vec3(0.0);
    vec3 w = vec3(n2) * inv;
    float ws = w.x + w.y + w.z;
    v.axis_weights = ws > 0.0 ? w / ws : vec3(1.0 / 3.0);
    // Along the axis the surfaces face most (their projection's, voxelize.frag).
    int axis = v.axis_weights.x >= max(v.axis_weights.y, v.axis_weights.z) ? 0
             : (v.axis_weights.y >= v.axis_weights.z ? 1 : 2);
    v.offset = vec3(0.0);
    v.offset[axis] = float(off) * inv;
    v.emission = vec3(0.0);
    v.emitter_cover = 0.0;
    if ((frame.grid_info.w & FLAG_EMISSIVE) != 0u && v.filled) {
        uint j = voxel_index(c) * EMISSION_STRIDE;
        Words se = Words(static_words[WORDS_EMISSION]);
        uvec3 e = uvec3(se.w[j], se.w[j + 1u], se.w[j + 2u]);
        uint cov = se.w[j + 3u];
        if (dynamic) {
            Words de = Words(dynamic_words[WORDS_EMISSION]);
            e += uvec3(de.w[j], de.w[j + 1u], de.w[j + 2u]);
            cov += de.w[j + 3u];
        }

        // Sum of coverage-weighted emission over the emitters' coverage, or over 1 when they
        // cover less than the voxel (voxelize.frag).
        v.emitter_cover = float(cov) / FIXED_ONE;
        v.emission = vec3(e) / (max(v.emitter_cover, 1.0) * frame.cone.w);
    }
    return v;
}
#endif

// The side a voxel's surfaces face: its normal, or where their normals cancel (a thin two-sided
// panel), the axis they face most.
vec3 voxel_facing(Voxel v) {
    if (dot(v.normal, v.normal) > 0.0) return v.normal;
    return v.axis_weights.x >= max(v.axis_weights.y, v.axis_weights.z) ? vec3(1.0, 0.0, 0.0)
         : (v.axis_weights.y >= v.axis_weights.z ? vec3(0.0, 1.0, 0.0) : vec3(0.0, 0.0, 1.0));
}

#ifndef PAPER
// Whether a voxel holds the light of its surface's back apart (the back radiance volume, with
// FLAG_BACKS): one surface facing one way (its normals agree; a thin panel's two faces in one
// voxel are two-sided instead), with empty voxels behind it for half the grid's edge (or to
// the grid's edge). A zero-thickness wall reflects on both sides (the path tracer's
// surfaces do): a room built of single quads facing out, lit from inside, reflects its light
// inwards from the quads' backs. Behind a solid's surface lies the solid: its other surface,
// near. A hollow narrower than that keeps its inside dark, as a solid's: a light inside a
// box would reach the cones through the coarse texels, which average the box's walls across
// before they hide one behind the other along (hard case light-inside-geometry, a 30 cm crate
// 9 voxels wide with a point light inside: relMSE 13 against the room without that light
// when one empty voxel behind sufficed, 15 with 8, 0 with 16), and inside a solid the back
// gathers light for nothing (the Cornell box's blocks: its relit frame 11% slower with a
// quarter of the grid).
// A back that faces out of the scene from its edge (the grid ends within two voxels behind
// it) sees nothing and nothing sees it, unless an environment lights it: the walls of a closed
// room, whose bounce it would otherwise gather twice.
bool open_back(ivec3 c, Voxel v) {
    if ((frame.grid_info.w & FLAG_BACKS) == 0u || !v.filled || v.agreement < 0.5) return false;
    vec3 centre = vec3(c) + 0.5;
    for (int s = 1; s <= max(grid_n() / 2, 1); s++) {
        ivec3 behind = ivec3(floor(centre - v.normal * float(s)));
        if (!in_grid(behind)) return s > 2 || frame.env.w > 0.0;
        if (voxel_filled(behind)) return false;
    }
    return true;
}
#endif

#endif
