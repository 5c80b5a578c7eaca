// Punctual lights (KHR_lights_punctual, radiometric per CONVENTIONS.md) and shadow-map lookups.
#ifndef LIGHTS_GLSL
#define LIGHTS_GLSL

// Irradiance on a surface facing the light, and the unit direction towards the light.
vec3 light_irradiance(Light light, vec3 p, out vec3 to_light, out float dist) {
    uint type = uint(light.position_type.w);
    if (type == LIGHT_DIRECTIONAL) {
        to_light = -light.direction_range.xyz;
        dist = 1e30;
        return light.radiance.rgb;
    }
    vec3 d = light.position_type.xyz - p;
    float d2 = max(dot(d, d), 1e-12);
    dist = sqrt(d2);
    to_light = d / dist;
    if (type == LIGHT_EMITTER) {
        // Intensity Le (lobe cos + uniform), cone.x and cone.y in square metres; |cos| when
        // two-sided. Never more than pi Le, the irradiance under an emitter that fills the
        // sky, which a point closer than the emitter's size would exceed.
        float c = dot(light.direction_range.xyz, -to_light);
        float lobe = light.radiance.w > 0.5 ? abs(c) : max(c, 0.0);
        return light.radiance.rgb * min((light.cone.x * lobe + light.cone.y) / d2, PI);
    }
    float atten = 1.0 / d2;
    float range = light.direction_range.w;
    if (range > 0.0) {
        // glTF's recommended smooth window to zero at the range.
        float r = dist / range;
        atten *= clamp(1.0 - r * r * r * r, 0.0, 1.0) * clamp(1.0 - r * r * r * r, 0.0, 1.0);
    }
    if (type == LIGHT_SPOT) {
        // glTF's smooth angular falloff between the inner and outer cone angles.
        float cd = dot(light.direction_range.xyz, -to_light);
        float a = clamp(cd * light.cone.x + light.cone.y, 0.0, 1.0);
        atten *= a * a;
    }
    return light.radiance.rgb * atten;
}

// Which of a point light's six cube views (+X, -X, +Y, -Y, +Z, -Z) sees direction d.
uint cube_face(vec3 d) {
    vec3 a = abs(d);
    if (a.x >= a.y && a.x >= a.z) return d.x >= 0.0 ? 0u : 1u;
    if (a.y >= a.z) return d.y >= 0.0 ? 2u : 3u;
    return d.z >= 0.0 ? 4u : 5u;
}

// Fraction of the light that reaches p (1 = lit), by percentage-closer filtering of the light's
// shadow map. The lookup point moves along the geometric normal by about a texel so that a
// surface does not shadow itself (acne) without detaching shadows from their casters.
float shadow_visibility(Light light, vec3 p, vec3 geo_n, sampler2DArrayShadow shadow_map) {
    uint count = uint(light.cone.w);
    if (count == 0u) return 1.0;
    uint view = uint(light.cone.z);
    if (count == 6u) view += cube_face(p - light.position_type.xyz);
    ShadowView sv = shadow_views[view];

    float texel = sv.info.y;
    if (sv.info.x > 0.5) {
        // Perspective: the texel footprint grows with depth along the view axis.
        vec3 rel = p - light.position_type.xyz;
        float depth = count == 6u ? max(max(abs(rel.x), abs(rel.y)), abs(rel.z))
                                  : dot(rel, light.direction_range.xyz);
        texel *= max(depth, 0.0);
    }
    vec3 q = p + geo_n * texel * frame.shadow.y;
    vec4 c = sv.view_proj * vec4(q, 1.0);
    if (c.w <= 0.0) return 1.0;
    vec3 ndc = c.xyz / c.w;
    if (ndc.z > 1.0) return 1.0;
    vec2 uv = vec2(0.5 + 0.5 * ndc.x, 0.5 - 0.5 * ndc.y);
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return 1.0;

    float res = frame.shadow.x;
    int radius = int(frame.shadow.z);
    float sum = 0.0;
    float n = 0.0;
    for (int y = -radius; y <= radius; y++) {
        for (int x = -radius; x <= radius; x++) {
            vec2 o = vec2(x, y) / res;
            sum += texture(shadow_map, vec4(uv + o, float(view), ndc.z));
            n += 1.0;
        }
    }
    return sum / n;
}

#endif
