#version 450
// The light an area light's faces give the pixels its centre's shadow views cannot judge
// (listed by deferred_lighting.comp's AREA_FACES): where what the light rests on hides its
// centre (a cube on a pedestal of its footprint hides the floor around the pedestal from its
// centre, not from its side faces), the voxels between the pixel and each of the light's
// polygons say how much of it arrives; the light that the shadow views took away and the
// faces give back is added to the direct light. A pass of its own over the listed pixels: in
// the lighting pass this code made every pixel 1.5 to 2 times slower on lavapipe.
#include "common.glsl"
#include "brdf.glsl"
#include "lights.glsl"
#include "voxel_common.glsl"
#define PIXEL_LIST FacesList
#define PIXEL_LIST_BINDING 9
#define PIXEL_LIST_READONLY
#include "pixel_list.glsl"

layout(local_size_x = 64) in;

layout(set = 1, binding = 0) uniform sampler2D gb_position;
layout(set = 1, binding = 1) uniform sampler2D gb_normals;
layout(set = 1, binding = 2) uniform sampler2D gb_albedo;
layout(set = 1, binding = 3) uniform sampler2D gb_emission;
layout(set = 1, binding = 4) uniform sampler2D gb_specular;
layout(set = 1, binding = 6, rgba32f) uniform image2D out_radiance;
layout(set = 1, binding = 7) uniform sampler2DArrayShadow area_shadow_map;
layout(set = 1, binding = 8) uniform sampler2DArray area_shadow_depth;
// The lit voxels (inject_radiance.comp): a filled voxel's opacity is 1, an empty one's 0.
layout(set = 1, binding = 10, rgba16f) uniform readonly image3D radiance;
bool voxel_filled(ivec3 c) { return imageLoad(radiance, c).a > 0.0; }
#include "area_light_voxels.glsl"

// How much of an area light's light p (normal n) gets through the voxels: each polygon's seen
// share (polygon_seen) weighted by its form factor along n (unclipped). Polygons that rest on
// something (a cube's bottom on its pedestal or table) send p nothing: their ends of the
// segments, a voxel and a half in front of them, would lie beyond a support thinner than that.
float area_seen(Light light, vec3 p, vec3 n) {
    uint first = uint(light.cone.x);
    uint polygons = uint(light.cone.y);
    float sum = 0.0, seen = 0.0;
    for (uint i = 0u; i < polygons; i++) {
        AreaPolygon poly = area_polygons[first + i];
        float w = max(dot(polygon_vector(light, poly, p, 0.0), n), 0.0);
        if (w == 0.0) continue;
        sum += w;
        Outline o = area_outline(poly, p);
        if (!o.sphere) {
            vec3 on = vec3(0.0);
            for (uint k = 0u; k < o.count; k++) on += outline_corner(o, k);
            if (light_rests_on(light, on / float(o.count), area_shadow_depth)) continue;
        }
        seen += w * polygon_seen(poly, p);
    }
    return sum > 0.0 ? seen / sum : 0.0;
}

void main() {
    ivec2 px;
    if (!listed_pixel(px)) return;
    vec4 normals = texelFetch(gb_normals, px, 0);
    vec4 albedo = texelFetch(gb_albedo, px, 0);
    vec4 emission = texelFetch(gb_emission, px, 0);
    vec4 spec = texelFetch(gb_specular, px, 0);
    vec3 p = texelFetch(gb_position, px, 0).xyz;
    vec3 n = oct_decode(normals.xy);
    vec3 geo = oct_decode(normals.zw);
    vec3 v = normalize(frame.eye.xyz - p);
    Surface s = Surface(albedo.rgb, albedo.a, emission.a, spec.rgb, spec.a);
    AreaLobes lobes = area_lobes(s, n, v);
    // The segments start a voxel and a half off the surface, past its own voxels.
    vec3 from = p + geo * 1.5 * voxel_size();

    vec3 added = vec3(0.0);
    for (uint k = 0u; k < frame.counts.x; k++) {
        Light light = lights[k];
        if (uint(light.position_type.w) != LIGHT_AREA) continue;
        vec3 e = area_light_radiance(light, lobes, p);
        if (all(equal(e, vec3(0.0)))) continue;
        float blocker;
        float vis = area_shadow(light, p, geo, area_shadow_map, area_shadow_depth, blocker);
        if (!hidden_by_support(light, vis, blocker)) continue;
        added += e * max(area_seen(light, from, n) - vis, 0.0);
    }
    if (any(greaterThan(added, vec3(0.0)))) {
        imageStore(out_radiance, px, imageLoad(out_radiance, px) + vec4(added, 0.0));
    }
}
