// Reading a voxel back from what voxelization wrote. Define VOXEL_SET before including.
// Default: fixed-point sums and counts of the static and (when present) dynamic passes,
// averaged here. PAPER: the RGBA8 moving averages, empty when the 8-bit count reads 0.
#ifndef VOXEL_DATA_GLSL
#define VOXEL_DATA_GLSL

#include "atomic_average.glsl"

struct Voxel {
    bool filled;
    vec3 albedo;
    vec3 normal;        // unit, or zero when the averaged normals cancelled
    float agreement;    // length of the averaged unit normals: 1 flat, ~0 opposite faces
    vec3 axis_weights;  // mean squared normal: how much the surfaces face each axis (sums to 1)
    vec3 emission;
    float emitter_cover; // of the voxel's face, by its emitters (0 to 1 or more; default only)
    vec3 offset;        // where its surfaces lie from its centre, mean, in voxels
};

#ifdef PAPER
layout(set = VOXEL_SET, binding = 0, std430) readonly buffer AlbedoGrid { uint albedo_grid[]; };
layout(set = VOXEL_SET, binding = 1, std430) readonly buffer NormalGrid { uint normal_grid[]; };
layout(set = VOXEL_SET, binding = 2, std430) readonly buffer EmissionGrid { uint emission_grid[]; };

bool voxel_filled(ivec3 c) {
    return (albedo_grid[voxel_index(c)] >> 24u) != 0u;
}

Voxel load_voxel(ivec3 c) {
    Voxel v;
    uint i = voxel_index(c);
    vec4 a = unpack_rgba8(albedo_grid[i]);
    v.filled = a.a > 0.0;
    v.albedo = a.rgb / 255.0;
    vec3 n = unpack_rgba8(normal_grid[i]).rgb / 255.0 * 2.0 - 1.0;
    v.agreement = length(n);
    v.normal = v.agreement > 0.0 ? n / v.agreement : vec3(0.0);
    v.axis_weights = v.normal * v.normal;
    v.emission = (frame.grid_info.w & FLAG_EMISSIVE) != 0u
        ? unpack_rgba8(emission_grid[i]).rgb / 255.0 : vec3(0.0);
    v.offset = vec3(0.0);
    return v;
}
#else
// Bindings 4 to 6 are the passes' own (shadow map, radiance, voxel list).
layout(set = VOXEL_SET, binding = 0, std430) readonly buffer StaticAlbedo { uint static_albedo[]; };
layout(set = VOXEL_SET, binding = 1, std430) readonly buffer StaticEmission { uint static_emission[]; };
layout(set = VOXEL_SET, binding = 2, std430) readonly buffer DynamicAlbedo { uint dynamic_albedo[]; };
layout(set = VOXEL_SET, binding = 3, std430) readonly buffer DynamicEmission { uint dynamic_emission[]; };
layout(set = VOXEL_SET, binding = 7, std430) readonly buffer StaticNormal { uint static_normal[]; };
layout(set = VOXEL_SET, binding = 8, std430) readonly buffer DynamicNormal { uint dynamic_normal[]; };

bool voxel_filled(ivec3 c) {
    uint i = voxel_index(c) * ALBEDO_STRIDE;
    uint count = static_albedo[i];
    if ((frame.grid_info.w & FLAG_DYNAMIC) != 0u) count += dynamic_albedo[i];
    return count > 0u;
}

Voxel load_voxel(ivec3 c) {
    Voxel v;
    uint i = voxel_index(c) * ALBEDO_STRIDE;
    uint k = voxel_index(c) * NORMAL_STRIDE;
    uint count = static_albedo[i];
    uvec3 a = uvec3(static_albedo[i + 1u], static_albedo[i + 2u], static_albedo[i + 3u]);
    ivec3 n = ivec3(static_normal[k], static_normal[k + 1u], static_normal[k + 2u]);
    uvec3 n2 = uvec3(static_normal[k + 3u], static_normal[k + 4u], static_normal[k + 5u]);
    int off = int(static_normal[k + 6u]);
    bool dynamic = (frame.grid_info.w & FLAG_DYNAMIC) != 0u;
    if (dynamic) {
        count += dynamic_albedo[i];
        a += uvec3(dynamic_albedo[i + 1u], dynamic_albedo[i + 2u], dynamic_albedo[i + 3u]);
        n += ivec3(dynamic_normal[k], dynamic_normal[k + 1u], dynamic_normal[k + 2u]);
        n2 += uvec3(dynamic_normal[k + 3u], dynamic_normal[k + 4u], dynamic_normal[k + 5u]);
        off += int(dynamic_normal[k + 6u]);
    }
    v.filled = count > 0u;
    float inv = v.filled ? 1.0 / (float(count) * FIXED_ONE) : 0.0;
    v.albedo = vec3(a) * inv;
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
        uvec3 e = uvec3(static_emission[j], static_emission[j + 1u], static_emission[j + 2u]);
        uint cov = static_emission[j + 3u];
        if (dynamic) {
            e += uvec3(dynamic_emission[j], dynamic_emission[j + 1u], dynamic_emission[j + 2u]);
            cov += dynamic_emission[j + 3u];
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

#endif
