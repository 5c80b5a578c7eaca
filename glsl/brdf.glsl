// The glTF 2.0 metallic-roughness BRDF (specification appendix B) with KHR_materials_specular.
// alpha = roughness^2. A material with metallic 0 and specularFactor 0 is exactly Lambertian.
#ifndef BRDF_GLSL
#define BRDF_GLSL

struct Surface {
    vec3 base_color;
    float metallic;
    float roughness;
    vec3 specular_color;  // specularColorFactor x texture
    float specular;       // specularFactor x texture alpha
};

float d_ggx(float n_dot_h, float alpha) {
    float a2 = alpha * alpha;
    float d = n_dot_h * n_dot_h * (a2 - 1.0) + 1.0;
    return a2 / (PI * d * d);
}

// Height-correlated Smith visibility V = G / (4 |N.L| |N.V|).
float v_smith_ggx(float n_dot_l, float n_dot_v, float alpha) {
    float a2 = alpha * alpha;
    float gv = n_dot_l * sqrt(n_dot_v * n_dot_v * (1.0 - a2) + a2);
    float gl = n_dot_v * sqrt(n_dot_l * n_dot_l * (1.0 - a2) + a2);
    float s = gv + gl;
    return s > 0.0 ? 0.5 / s : 0.0;
}

// f(l, v) for unit N, V, L on the same side (N.L > 0, N.V > 0).
vec3 brdf(Surface s, vec3 n, vec3 v, vec3 l) {
    float n_dot_l = clamp(dot(n, l), 0.0, 1.0);
    float n_dot_v = clamp(dot(n, v), 1e-4, 1.0);
    vec3 hv = v + l;
    float hl = length(hv);
    vec3 h = hl > 1e-6 ? hv / hl : n;
    float n_dot_h = clamp(dot(n, h), 0.0, 1.0);
    float v_dot_h = clamp(dot(v, h), 0.0, 1.0);
    float alpha = max(s.roughness * s.roughness, 1e-3);

    float spec_lobe = d_ggx(n_dot_h, alpha) * v_smith_ggx(n_dot_l, n_dot_v, alpha);
    float schlick = pow(1.0 - v_dot_h, 5.0);

    vec3 diffuse = s.base_color / PI;
    // Dielectric: f0 from ior 1.5 scaled by KHR_materials_specular, f90 = specular.
    vec3 f0 = min(vec3(0.04) * s.specular_color, vec3(1.0)) * s.specular;
    vec3 fresnel = f0 + (vec3(s.specular) - f0) * schlick;
    vec3 dielectric = mix(diffuse, vec3(spec_lobe), fresnel);
    // Metal: conductor Fresnel with f0 = base colour.
    vec3 metal = spec_lobe * (s.base_color + (1.0 - s.base_color) * schlick);
    return mix(dielectric, metal, s.metallic);
}

// Karis' analytic fit of the split-sum environment BRDF: scale and bias of f0.
vec2 env_brdf(float roughness, float n_dot_v) {
    const vec4 c0 = vec4(-1.0, -0.0275, -0.572, 0.022);
    const vec4 c1 = vec4(1.0, 0.0425, 1.04, -0.04);
    vec4 r = roughness * c0 + c1;
    float a004 = min(r.x * r.x, exp2(-9.28 * n_dot_v)) * r.x + r.y;
    return vec2(-1.04, 1.04) * a004 + r.zw;
}

// What a surface reflects of light from all around (the cones', the environment's): the share
// of the irradiance its diffuse lobe sends to the eye (albedo / pi, less what the specular
// lobe takes), and the specular lobe's reflectance by the split sum (of the radiance seen
// along the reflection, prefiltered to the lobe: the specular cone's).
void reflectances(vec4 albedo, float roughness, vec4 spec, float n_dot_v,
                  out vec3 diffuse_weight, out vec3 spec_reflectance) {
    vec3 base = albedo.rgb;
    float metallic = albedo.a;
    vec3 f0 = mix(min(vec3(0.04) * spec.rgb, vec3(1.0)) * spec.a, base, metallic);
    vec3 f90 = vec3(mix(spec.a, 1.0, metallic));
    vec2 ab = env_brdf(roughness, n_dot_v);
    spec_reflectance = f0 * ab.x + f90 * ab.y;
    diffuse_weight = (1.0 - metallic) * (1.0 - spec_reflectance) * base / PI;
}

// The specular cone's tangent of half aperture for a surface's roughness.
float specular_aperture(float roughness) {
#ifdef PAPER
    return clamp(tan(0.5 * PI * roughness), 0.0174533, PI);
#else
    // The GGX lobe's half width at half maximum, doubled by reflection.
    return clamp(1.29 * roughness * roughness, 0.02, 1.0);
#endif
}

#endif
