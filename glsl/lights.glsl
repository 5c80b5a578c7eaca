// Punctual lights (KHR_lights_punctual, radiometric per CONVENTIONS.md) and shadow-map lookups.
#ifndef LIGHTS_GLSL
#define LIGHTS_GLSL
#include "area_lights.glsl"

// Irradiance on a surface facing the light, and the unit direction towards the light. An area
// light's polygons within `reach` of p give it nothing (area_vector_form_factor).
vec3 light_irradiance_near(Light light, vec3 p, float reach, out vec3 to_light, out float dist) {
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
    if (type == LIGHT_AREA) {
        // Where the light comes from on average and the irradiance facing it (the pixels
        // integrate it exactly instead: deferred_lighting.comp).
        vec3 f = area_vector_form_factor(light, p, reach);
        float l = length(f);
        if (l > 0.0) to_light = f / l;
        return light.radiance.rgb * (PI * l);
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

vec3 light_irradiance(Light light, vec3 p, out vec3 to_light, out float dist) {
    return light_irradiance_near(light, p, 0.0, to_light, dist);
}

// Where a shadow view sees q: its uv and depth; false when it cannot (behind the view or
// beyond its far plane).
bool shadow_coords(ShadowView sv, vec3 q, out vec2 uv, out float depth) {
    vec4 c = sv.view_proj * vec4(q, 1.0);
    if (c.w <= 0.0) return false;
    vec3 ndc = c.xyz / c.w;
    if (ndc.z > 1.0) return false;
    uv = vec2(0.5 + 0.5 * ndc.x, 0.5 - 0.5 * ndc.y);
    depth = ndc.z;
    return true;
}

// Which of a point light's six cube views (+X, -X, +Y, -Y, +Z, -Z) sees direction d.
uint cube_face(vec3 d) {
    vec3 a = abs(d);
    if (a.x >= a.y && a.x >= a.z) return d.x >= 0.0 ? 0u : 1u;
    if (a.y >= a.z) return d.y >= 0.0 ? 2u : 3u;
    return d.z >= 0.0 ? 4u : 5u;
}

// The mean of a (2r + 1)^2 grid of bilinear depth comparisons a texel apart around uv, read as
// (r + 1)^2 gathers of 2x2 comparisons: the grid weighs the 2r + 2 texels along each axis
// 1 - f, 1, ..., 1, f (f: uv's place between texel centres), so each gather's four texels
// take the products of those weights. Half the reads or fewer, the same mean.
float pcf_grid(sampler2DArrayShadow map, float res, vec2 uv, float layer, float depth, int r) {
    vec2 st = uv * res - 0.5;
    vec2 base = floor(st);
    vec2 f = st - base;
    int last = 2 * r + 1;
    float sum = 0.0;
    for (int j = 0; j <= r; j++) {
        for (int i = 0; i <= r; i++) {
            ivec2 k = ivec2(2 * i, 2 * j);
            // Texels base - r + k and the next ones; the gather at the corner they share.
            vec2 corner = base - float(r) + vec2(k);
            vec4 g = textureGather(map, vec3((corner + 1.0) / res, layer), depth);
            vec2 w0 = mix(vec2(1.0), 1.0 - f, vec2(equal(k, ivec2(0))));
            vec2 w1 = mix(vec2(1.0), f, vec2(equal(k + 1, ivec2(last))));
            // Gather order: (0, 1), (1, 1), (1, 0), (0, 0).
            sum += g.x * w0.x * w1.y + g.y * w1.x * w1.y + g.z * w1.x * w0.y + g.w * w0.x * w0.y;
        }
    }
    return sum / float(last * last);
}

// Fraction of the light that reaches p (1 = lit), by percentage-closer filtering of the light's
// shadow map (an area light's in `area_map`, seen from its centre). The lookup point moves along
// the geometric normal by about a texel so that a surface does not shadow itself (acne) without
// detaching shadows from their casters.
float shadow_visibility(Light light, vec3 p, vec3 geo_n, sampler2DArrayShadow shadow_map,
                        sampler2DArrayShadow area_map) {
    uint count = uint(light.cone.w);
    if (count == 0u) return 1.0;
    uint view = uint(light.cone.z);
    if (count == 6u) view += cube_face(p - light.position_type.xyz);
    ShadowView sv = shadow_views[view];

    float texel = sv.info.y;
    if (sv.info.x > 0.5) {
        // Perspective: the texel footprint grows with depth along the view axis.
        vec3 rel = p - light.position_type.xyz;
        float along = count == 6u ? max(max(abs(rel.x), abs(rel.y)), abs(rel.z))
                                  : dot(rel, light.direction_range.xyz);
        texel *= max(along, 0.0);
    }
    vec3 q = p + geo_n * texel * frame.shadow.y;
    vec2 uv;
    float depth;
    if (!shadow_coords(sv, q, uv, depth)) return 1.0;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return 1.0;

    int r = int(frame.shadow.z);
    if (uint(light.position_type.w) == LIGHT_AREA) {
        float layer = float(view) - frame.area_shadow.y;
        return pcf_grid(area_map, frame.area_shadow.x, uv, layer, depth, r);
    }
    return pcf_grid(shadow_map, frame.shadow.x, uv, float(view), depth, r);
}

// Tap i of n spread evenly over the unit disc (Vogel's spiral: golden-angle turns, radii by
// area), the same for every pixel: no straight edge lines up with a row of taps.
vec2 vogel_disc(int i, int n) {
    float r = sqrt((float(i) + 0.5) / float(n));
    float a = float(i) * 2.39996323;
    return r * vec2(cos(a), sin(a));
}

// How the depth of the plane through q (normal n) changes with the view's uv: project two
// points a texel away along the plane and solve for the gradient. Zero when the view sees the
// plane edge-on.
vec2 receiver_slope(mat4 view_proj, vec3 q, vec3 n, float texel, vec2 uv, float depth) {
    vec3 t1 = normalize(cross(n, abs(n.y) < 0.9 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0)));
    vec3 t2 = cross(n, t1);
    vec4 c1 = view_proj * vec4(q + t1 * texel, 1.0);
    vec4 c2 = view_proj * vec4(q + t2 * texel, 1.0);
    if (c1.w <= 0.0 || c2.w <= 0.0) return vec2(0.0);
    vec3 a = c1.xyz / c1.w;
    vec3 b = c2.xyz / c2.w;
    vec2 du1 = vec2(0.5 * a.x, -0.5 * a.y) + 0.5 - uv;
    vec2 du2 = vec2(0.5 * b.x, -0.5 * b.y) + 0.5 - uv;
    float det = du1.x * du2.y - du1.y * du2.x;
    if (abs(det) < 1e-14) return vec2(0.0);
    vec2 dz = vec2(a.z - depth, b.z - depth);
    // [du1; du2] g = dz.
    return vec2(du2.y * dz.x - du1.y * dz.y, du1.x * dz.y - du2.x * dz.x) / det;
}

// Whether the area light's shadow views find something touching `q`, a point on the light's
// surface: a surface within a fiftieth of the light's reach and two texels of q's depth (what
// the light rests on, covering that part of it; not what lies inside the light or beyond).
bool light_rests_on(Light light, vec3 q, sampler2DArray shadow_depth) {
    uint count = uint(light.cone.w);
    if (count == 0u) return false;
    vec3 rel = q - light.position_type.xyz;
    uint view = uint(light.cone.z) + cube_face(rel);
    ShadowView sv = shadow_views[view];
    float at = max(max(abs(rel.x), abs(rel.y)), abs(rel.z));
    vec2 uv;
    float depth;
    if (!shadow_coords(sv, q, uv, depth)) return false;
    float d = textureLod(shadow_depth, vec3(uv, float(view) - frame.area_shadow.y), 0.0).r;
    float near = sv.info.z, far = sv.info.w;
    float found = near * far / (far - d * (far - near));
    return abs(found - at) < 0.02 * light.direction_range.w + 2.0 * sv.info.y * at;
}

// Visibility of an area light from p (0 to 1), by percentage-closer soft shadows in the cube
// of views at its centre: the blockers' mean depth over the part of the view the light's
// size could be hidden by gives the penumbra's width at p by similar triangles, radius x
// (receiver - blocker) / blocker, and the comparisons are filtered over that width. Contact
// shadows stay sharp, far ones widen with the light. `blocker`: the blockers' mean distance
// from the centre along the view's axis (0 where none were found).
float area_shadow(Light light, vec3 p, vec3 geo_n, sampler2DArrayShadow shadow_map,
                  sampler2DArray shadow_depth, out float blocker) {
    blocker = 0.0;
    uint count = uint(light.cone.w);
    if (count == 0u) return 1.0;
    vec3 rel = p - light.position_type.xyz;
    uint view = uint(light.cone.z) + cube_face(rel);
    ShadowView sv = shadow_views[view];
    float receiver = max(max(abs(rel.x), abs(rel.y)), abs(rel.z));
    float texel = sv.info.y * receiver;  // metres per texel at p's depth
    vec3 q = p + geo_n * texel * frame.shadow.y;
    vec2 uv;
    float depth;
    if (!shadow_coords(sv, q, uv, depth)) return 1.0;
    float res = frame.area_shadow.x;
    float layer = float(view) - frame.area_shadow.y;
    // The widest filter the views are widened for (shadows.rs: SOFT_SHADOW_SHARE).
    float widest = max(frame.area_shadow.z, 1.0);
    float radius = light.direction_range.x;
    float near = sv.info.z;
    float far = sv.info.w;
    // Wide filters reach across the receiver itself: each tap compares against the receiver's
    // plane there (its depth is affine in the view's uv), not against p's depth.
    vec2 slope = receiver_slope(sv.view_proj, q, geo_n, texel, uv, depth);
    float bias = 2.0 / res * (abs(slope.x) + abs(slope.y)) + 1e-6;

    // Blockers: 16 taps over the light's radius as seen at p's depth.
    float search = clamp(radius / texel, 1.0, widest);
    float blockers = 0.0;
    float found = 0.0;
    for (int i = 0; i < 16; i++) {
        vec2 o = vogel_disc(i, 16) * search / res;
        float d = texture(shadow_depth, vec3(uv + o, layer)).r;
        if (d < depth + dot(slope, o) - bias) {
            blockers += near * far / (far - d * (far - near));
            found += 1.0;
        }
    }
    if (found == 0.0) return 1.0;
    blocker = blockers / found;
    float penumbra = radius * max(receiver - blocker, 0.0) / max(blocker, near) / texel;
    penumbra = clamp(penumbra, max(frame.shadow.z, 0.5), widest);

    // Comparisons over the penumbra, a disc like the light's: 32 bilinear taps.
    float sum = 0.0;
    for (int i = 0; i < 32; i++) {
        vec2 o = vogel_disc(i, 32) * penumbra / res;
        sum += texture(shadow_map, vec4(uv + o, layer, depth + dot(slope, o) - bias));
    }
    return sum / 32.0;
}

// Whether the cube of shadow views at an area light's centre may hide from a pixel what the
// light's faces see: the blockers its PCSS search found (their mean distance from the centre,
// 0 where none) lie within the light's reach (direction_range.w: its farthest point from the
// centre), which makes them what the light rests on (a cube on a pedestal of its footprint).
bool hidden_by_support(Light light, float vis, float blocker) {
    return vis < 1.0 && blocker > 0.0 && blocker < light.direction_range.w;
}

#endif
