// Light from beyond the scene (../shared/CONVENTIONS.md, "Environment"): an equirectangular
// image of linear radiance with its mip chain (1x1 for a uniform radiance), turned about +Y and
// scaled as frame.env says (src/render/environment.rs). A cone that leaves the grid before it
// is opaque takes it, averaged over the cone's aperture, for the part of it still open.
#ifndef ENVIRONMENT_GLSL
#define ENVIRONMENT_GLSL

layout(set = 0, binding = 8) uniform sampler2D environment_map;

bool has_environment() { return frame.env.w > 0.0; }

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

#endif
