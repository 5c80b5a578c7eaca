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

#endif
