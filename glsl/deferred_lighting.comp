#version 450
// variants: AREA_FACES
// Deferred direct lighting: punctual lights with filtered shadow maps, emissive surfaces as area
// lights (area_lights.glsl) with shadows softened by their size, plus emission, written as
// linear radiance (RGBA32F). Where no cone traces the environment (--mode direct), its light
// too, unoccluded, as a glTF viewer's image-based lighting: the cones take it otherwise.
// AREA_FACES (area lights and the default's voxels): the pixels whose area-light blockers lie
// within the light's own reach are listed for area_faces.comp, which adds what the light's
// faces show them past what it rests on.
#include "common.glsl"
#include "brdf.glsl"
#include "lights.glsl"
#include "environment.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0) uniform sampler2D gb_position;
layout(set = 1, binding = 1) uniform sampler2D gb_normals;
layout(set = 1, binding = 2) uniform sampler2D gb_albedo;
layout(set = 1, binding = 3) uniform sampler2D gb_emission;
layout(set = 1, binding = 4) uniform sampler2D gb_specular;
layout(set = 1, binding = 5) uniform sampler2DArrayShadow shadow_map;
layout(set = 1, binding = 6, rgba32f) uniform writeonly image2D out_radiance;
// The area lights' shadow maps (lights.glsl: area_shadow), for comparisons and, read as depths,
// for the blocker search.
layout(set = 1, binding = 7) uniform sampler2DArrayShadow area_shadow_map;
layout(set = 1, binding = 8) uniform sampler2DArray area_shadow_depth;

#ifdef AREA_FACES
// The pixels for area_faces.comp (lights.glsl's hidden_by_support says which).
#define PIXEL_LIST FacesList
#define PIXEL_LIST_BINDING 9
#include "pixel_list.glsl"
#endif

void main() {
    ivec2 px = ivec2(gl_GlobalInvocationID.xy);
    if (px.x >= int(frame.counts.y) || px.y >= int(frame.counts.z)) return;

    vec4 pos = texelFetch(gb_position, px, 0);
    if (pos.a == 0.0) {
        // Background: the environment along the pixel's ray (black without one). The view
        // ray of the pixel's centre through the projection: x_view = (ndc.x + proj[2][0]) /
        // proj[0][0] at z_view = -1, and likewise y (the viewport is flipped: ndc y is up).
        vec2 ndc = (vec2(px) + 0.5) / vec2(frame.counts.yz) * 2.0 - 1.0;
        ndc.y = -ndc.y;
        vec3 ray = vec3((ndc.x + frame.proj[2][0]) / frame.proj[0][0],
                        (ndc.y + frame.proj[2][1]) / frame.proj[1][1], -1.0);
        vec3 d = normalize(transpose(mat3(frame.view)) * ray);
        imageStore(out_radiance, px, vec4(environment_radiance(d, 0.0), 1.0));
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
    Surface s = Surface(albedo.rgb, albedo.a, emission.a, spec.rgb, spec.a);

    vec3 radiance = emission.rgb;
    AreaLobes lobes = area_lobes(s, n, v);
    bool listed = false;
    for (uint i = 0u; i < frame.counts.x; i++) {
        Light light = lights[i];
        if (uint(light.position_type.w) == LIGHT_AREA) {
            vec3 e = area_light_radiance(light, lobes, p);
            if (all(equal(e, vec3(0.0)))) continue;
            float blocker;
            float vis = area_shadow(light, p, geo, area_shadow_map, area_shadow_depth, blocker);
            radiance += e * vis;
            listed = listed || hidden_by_support(light, vis, blocker);
            continue;
        }
        vec3 l;
        float dist;
        vec3 e = light_irradiance(light, p, l, dist);
        float n_dot_l = dot(n, l);
        if (n_dot_l <= 0.0 || dot(geo, l) <= 0.0 || all(equal(e, vec3(0.0)))) continue;
        float vis = shadow_visibility(light, p, geo, shadow_map, area_shadow_map);
        radiance += brdf(s, n, v, l) * e * n_dot_l * vis;
    }
#ifdef AREA_FACES
    if (listed) list_pixel(px);
#endif
    if (environment_lights_directly()) {
        vec3 diffuse_weight;
        vec3 spec_reflectance;
        reflectances(albedo, s.roughness, spec, clamp(dot(n, v), 1e-4, 1.0), diffuse_weight,
                     spec_reflectance);
        vec3 r = reflect(-v, n);
        radiance += diffuse_weight * environment_irradiance(n)
                    + spec_reflectance * environment_radiance(r, specular_aperture(s.roughness));
    }
    imageStore(out_radiance, px, vec4(radiance, 1.0));
}
