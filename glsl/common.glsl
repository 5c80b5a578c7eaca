// Shared declarations: the scene set (set 0) and packing helpers.
// Layouts match src/render/gpu.rs (std140 uniform, std430 storage).
#ifndef COMMON_GLSL
#define COMMON_GLSL

const float PI = 3.14159265358979;

const uint LIGHT_DIRECTIONAL = 0u;
const uint LIGHT_POINT = 1u;
const uint LIGHT_SPOT = 2u;
// An emissive surface lit as an area light (src/render/area_lights.rs, area_lights.glsl).
const uint LIGHT_AREA = 3u;

layout(set = 0, binding = 0, std140) uniform Frame {
    mat4 view_proj;
    mat4 view;
    mat4 proj;
    vec4 eye;         // xyz camera position
    uvec4 counts;     // x lights, y width, z height, w shadow views
    vec4 shadow;      // x shadow-map resolution, y normal-offset in texels, z PCF radius in texels
    vec4 area_shadow; // the area lights' shadow maps: x resolution, y their first view (the
                      // punctual lights' come first), z the widest soft-shadow filter's half
                      // width in texels
    vec4 grid;        // voxel grid: xyz origin (min corner), w edge length (metres)
    uvec4 grid_info;  // x resolution N, y bounces, z diffuse cone count, w flags (FLAG_*)
    vec4 cone;        // x diffuse aperture (tan of half angle), y step factor, z max distance
                      // (fraction of the grid), w emission fixed-point scale
    vec4 trace;       // x start offset (voxels), y AO falloff, z specular (0: off), w debug mip
    vec4 cones[16];   // diffuse cones: xyz direction in the normal's frame (z = normal), w weight
    vec4 tuning;      // x levels finer than the cone diameter to sample (keeps coarse samples off
                      // the surface the cone leaves), y radiance scale: the volumes hold
                      // radiance x y, so that a very strong light stays within half floats;
                      // z the specular cone's narrowest diameter (voxels), w voxels per
                      // empty-space cell
    vec4 env;         // the environment (environment.glsl): x strength, yz cosine and sine of
                      // its turn about +Y, w 1 when there is one
    vec4 bounce_cone;       // the bounces' diffuse cones: x aperture (tan of half angle), y count
    vec4 bounce_cones[16];  // as cones[16], for the bounces (inject_bounce.comp)
} frame;

const uint FLAG_DYNAMIC = 1u;        // dynamic accumulators are bound and filled
const uint FLAG_EMISSIVE = 2u;       // emission accumulators exist
const uint FLAG_VOXEL_SHADOWS = 4u;  // visibility by tracing the voxels instead of shadow maps
const uint FLAG_CONE_SHADOWS = 8u;   // direct light shadowed by cones through the voxels
const uint FLAG_EMPTY_SPACE = 16u;   // the empty-space volume is filled: cones may skip by it
const uint FLAG_PAPER_SLIPS = 32u;   // PAPER: the original's C++ slips reproduced (--paper-slips)
const uint FLAG_BACKS = 64u;         // the back radiance volume is filled (GiSettings::backs)
const uint FLAG_BOUNCE_SHARE = 128u; // one-sided voxels share their bounce gather in blocks

struct Material {
    vec4 base_color;
    vec4 emissive;        // rgb radiance (factor x strength), a unused
    vec4 specular;        // rgb specularColorFactor, a specularFactor
    vec4 params;          // x metallic, y roughness, z normal scale, w alpha cutoff (< 0: opaque)
    ivec4 tex0;           // texture present (>= 0): base colour, metallic-roughness, normal, emissive
    ivec4 tex1;           // x specular (A), y specular colour present; z double-sided flag
};

struct Light {
    vec4 position_type;   // xyz position, w type
    vec4 direction_range; // xyz direction the light shines along, w range (0: none)
    vec4 radiance;        // rgb: W/sr (point, spot), W/m^2 (directional), Le (area; w 1 when
                          // two-sided)
    vec4 cone;            // x angle scale, y angle offset (glTF), z first shadow view, w view count
                          // (area: x first polygon, y polygon count; direction_range.x the
                          // radius of its apparent disc, w its reach from its centre,
                          // position_type.xyz)
};
// A uniform block of a fixed size (gpu.rs: MAX_LIGHTS, 16 KiB, what every device allows):
// every pixel reads the same light at once, which uniform loads broadcast (lavapipe reads a
// storage buffer one lane at a time).
const uint MAX_LIGHTS = 256u;
layout(set = 0, binding = 3, std140) uniform Lights { Light lights[MAX_LIGHTS]; };

struct ShadowView {
    mat4 view_proj;
    vec4 info;            // x 1 if perspective, y texel size (ortho: metres; persp: per metre of depth)
};
// As many as fit in 64 KiB (gpu.rs: MAX_SHADOW_VIEWS; context.rs asks the device for that much).
const uint MAX_SHADOW_VIEWS = 819u;
layout(set = 0, binding = 4, std140) uniform ShadowViews { ShadowView shadow_views[MAX_SHADOW_VIEWS]; };

// Rec. 709 luminance.
float luminance(vec3 c) {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

// Octahedral encoding of unit vectors (two components in [-1, 1]).
vec2 oct_encode(vec3 n) {
    n /= abs(n.x) + abs(n.y) + abs(n.z);
    vec2 e = n.xy;
    if (n.z < 0.0) {
        e = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    }
    return e;
}

vec3 oct_decode(vec2 e) {
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    float t = max(-n.z, 0.0);
    n.x += n.x >= 0.0 ? -t : t;
    n.y += n.y >= 0.0 ? -t : t;
    return normalize(n);
}

#endif
