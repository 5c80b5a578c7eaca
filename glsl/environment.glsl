// Light from beyond the scene (../shared/CONVENTIONS.md, "Environment"): an equirectangular
// image of linear radiance with its mip chain (1x1 for a uniform radiance), turned about +Y and
// scaled as frame.env says (src/render/environment.rs). A cone that leaves the grid before it
// is opaque takes it, averaged over the cone's aperture, for the part of it still open.
#ifndef ENVIRONMENT_GLSL
#define ENVIRONMENT_GLSL

layout(set = 0, binding = 8) uniform sampler2D environment_map;

bool has_environment() { return frame.env.w > 0.0; }

// No cone traces the environment (--mode direct): the lighting pass lights by it, unoccluded.
bool environment_lights_directly() { return frame.env.w > 1.5; }

// The image coordinates of world direction d: u = 0.5 + atan2(d.x, -d.z) / 2 pi,
// v = acos(d.y) / pi, after turning d back by the environment's turn.
vec2 environment_uv(vec3 d) {
    float c = frame.env.y, s = -frame.env.z;
    vec3 e = vec3(c * d.x + s * d.z, d.y, -s * d.x + c * d.z);
    return vec2(0.5 + atan(e.x, -e.z) / (2.0 * PI), acos(clamp(e.y, -1.0, 1.0)) / PI);
}

// The radiance arriving from direction d (unit, world space), averaged over a cone of half
// angle atan(tan_half) (0: along the ray alone): the mip level whose texels, at the horizon,
// span the cone's solid angle.
vec3 environment_radiance(vec3 d, float tan_half) {
    if (!has_environment()) return vec3(0.0);
    vec2 size = vec2(textureSize(environment_map, 0));
    float texel = (2.0 * PI / size.x) * (PI / size.y);
    float cone = 2.0 * PI * (1.0 - cos(atan(tan_half)));
    float lod = 0.5 * log2(max(cone / texel, 1.0));
    return textureLod(environment_map, environment_uv(d), lod).rgb * frame.env.x;
}

// The irradiance the environment gives a surface of normal n, unoccluded: seven cones of 30
// degrees' half angle, one along n and six 60 degrees from it, weighted by their cosines so
// that a uniform environment gives pi Le exactly.
vec3 environment_irradiance(vec3 n) {
    vec3 t = normalize(cross(n, abs(n.y) < 0.99 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0)));
    vec3 b = cross(n, t);
    const float TAN_30 = 0.57735027;
    vec3 sum = environment_radiance(n, TAN_30);
    for (int k = 0; k < 6; k++) {
        float a = float(k) * (PI / 3.0);
        sum += 0.5 * environment_radiance(0.5 * n + 0.8660254 * (cos(a) * t + sin(a) * b), TAN_30);
    }
    return sum * (PI / 4.0);
}

#endif
