#version 450
// variants: PAPER
// Cone tracing per pixel, step 4 of the paper (its light_pass): indirect diffuse from a set of
// cones over the normal's hemisphere, a specular cone along the reflection whose aperture
// follows roughness, and ambient occlusion; added to the direct light already in `radiance_out`.
// Default: glTF BRDF weights (diffuse albedo / pi, split-sum specular). PAPER: 6 cones of 60
// degrees tilted ~41 degrees, weights pi/4 and 3pi/20, indirect x 2 (bounceStrength) and
// (direct + indirect) x AO + emission, as the original composes it (without its gamma mix-up).
#include "common.glsl"
#include "voxel_common.glsl"
#define CONE_SET 2
#define CONE_FULL_RES 1
#include "cone_tracing.glsl"
#include "brdf.glsl"
#include "lights.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0) uniform sampler2D gb_position;
layout(set = 1, binding = 1) uniform sampler2D gb_normals;
layout(set = 1, binding = 2) uniform sampler2D gb_albedo;
layout(set = 1, binding = 3) uniform sampler2D gb_emission;
layout(set = 1, binding = 4) uniform sampler2D gb_specular;
layout(set = 1, binding = 5, rgba32f) uniform image2D radiance_out;

layout(push_constant) uniform Pass {
    uint mode;   // 0 full, 1 indirect only, 2 ambient occlusion
} pass;

// Karis' analytic fit of the split-sum environment BRDF: scale and bias of f0.
vec2 env_brdf(float roughness, float n_dot_v) {
    const vec4 c0 = vec4(-1.0, -0.0275, -0.572, 0.022);
    const vec4 c1 = vec4(1.0, 0.0425, 1.04, -0.04);
    vec4 r = roughness * c0 + c1;
    float a004 = min(r.x * r.x, exp2(-9.28 * n_dot_v)) * r.x + r.y;
    return vec2(-1.04, 1.04) * a004 + r.zw;
}

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (px.x >= int(frame.counts.y) || px.y >= int(frame.counts.z)) return;
    vec4 pos = texelFetch(gb_position, px, 0);
    vec4 direct = imageLoad(radiance_out, px);
    if (pos.a == 0.0) {
        if (pass.mode != 0u) imageStore(radiance_out, px, vec4(0.0, 0.0, 0.0, 1.0));
        return;
    }
    vec4 normals = texelFetch(gb_normals, px, 0);
    vec4 albedo = texelFetch(gb_albedo, px, 0);
    vec4 emission = texelFetch(gb_emission, px, 0);
    vec4 spec = texelFetch(gb_specular, px, 0);
    vec3 p = pos.xyz;
    vec3 n = oct_decode(normals.xy);
    vec3 geo = oct_decode(normals.zw);
    vec3 v = normalize(frame.eye.xyz - p);
    float vs = voxel_size();
    float max_dist = frame.cone.z * frame.grid.w;
    mat3 frame_n = tangent_frame(n);

    vec3 irradiance = vec3(0.0);
    float occlusion = 0.0;
#ifdef PAPER
    vec3 origin = p + n * 2.0 * vs;
    float t0 = 2.0 * vs;
#else
    vec3 origin = p + geo * frame.trace.x * vs;
    float t0 = vs;
#endif
    for (uint i = 0u; i < frame.grid_info.z; i++) {
        vec3 d = normalize(frame_n * frame.cones[i].xyz);
        Cone c = trace_cone(origin, d, frame.cone.x, t0, max_dist);
        irradiance += frame.cones[i].w * c.radiance;
        occlusion += frame.cones[i].w * c.occlusion;
    }
    float ao = clamp(1.0 - occlusion / PI, 0.0, 1.0);

    vec3 base = albedo.rgb;
    float metallic = albedo.a;
    float roughness = emission.a;
    float n_dot_v = clamp(dot(n, v), 1e-4, 1.0);
    vec3 specular = vec3(0.0);
    vec3 f0 = mix(min(vec3(0.04) * spec.rgb, vec3(1.0)) * spec.a, base, metallic);
    vec3 f90 = vec3(mix(spec.a, 1.0, metallic));
    vec2 ab = env_brdf(roughness, n_dot_v);
    vec3 spec_reflectance = f0 * ab.x + f90 * ab.y;
    if (frame.trace.z > 0.0 && max(spec_reflectance.r, max(spec_reflectance.g, spec_reflectance.b)) > 1e-4) {
        vec3 r = reflect(-v, n);
        float alpha = roughness * roughness;
#ifdef PAPER
        float tan_half = clamp(tan(0.5 * PI * roughness), 0.0174533, PI);
#else
        // The GGX lobe's half width at half maximum, doubled by reflection.
        float tan_half = clamp(1.29 * alpha, 0.02, 1.0);
#endif
        Cone c = trace_cone(origin, r, tan_half, t0, max_dist);
        specular = c.radiance * spec_reflectance;
    }

    if ((frame.grid_info.w & FLAG_CONE_SHADOWS) != 0u) {
        // Soft shadows: the direct light again, each light's visibility from a narrow cone
        // (the paper's aperture 0.03) towards it instead of the shadow map.
        Surface surf = Surface(base, metallic, roughness, spec.rgb, spec.a);
        vec3 d = emission.rgb;
        for (uint i = 0u; i < frame.counts.x; i++) {
            vec3 l;
            float dist;
            vec3 e = light_irradiance(lights[i], p, l, dist);
            float n_dot_l = dot(n, l);
            if (n_dot_l <= 0.0 || dot(geo, l) <= 0.0) continue;
            Cone c = trace_cone(origin, l, 0.03, t0, min(dist, max_dist));
            d += brdf(surf, n, v, l) * e * n_dot_l * (1.0 - c.opacity);
        }
        direct.rgb = d;
    }

#ifdef PAPER
    vec3 indirect = 2.0 * (base * irradiance + specular);
    vec3 full = (direct.rgb - emission.rgb + indirect) * ao + emission.rgb;
#else
    vec3 diffuse_weight = (1.0 - metallic) * (1.0 - spec_reflectance) * base / PI;
    vec3 indirect = diffuse_weight * irradiance + specular;
    vec3 full = direct.rgb + indirect;
#endif
    vec3 result = pass.mode == 0u ? full : (pass.mode == 1u ? indirect : vec3(ao));
    imageStore(radiance_out, px, vec4(result, 1.0));
}
