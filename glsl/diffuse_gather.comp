#version 450
// variants: TEMPORAL
// The diffuse cones of step 4 at reduced resolution: indirect light is smooth on a surface, so
// one pixel per block of scale x scale (the one nearest the block's centre) traces them, and
// cone_trace.comp (UPSAMPLED) spreads each block's result over the pixels that show the same
// surface. Writes per block: irradiance (rgb) and occlusion (a), each over the whole cone set;
// and the specular cone's radiance where it is wide enough to be smooth (rough surfaces).
// TEMPORAL: a block keeps a history of its cones, taken each frame from where its surface was
// in the frame before. Irradiance does not depend on the view, so the history stays right
// while the camera moves. A block whose history holds every cone traces none; one whose
// surface was not seen before (a disocclusion) traces one of `subsets` interleaved subsets of
// the cone set per frame (cones k, k + subsets, ...; k = frame mod subsets) and has them all
// after `subsets` frames. When the light in the voxels changed, or on a cut (`reset`), every
// block traces the whole set at once: that frame is a full one, as without a history.
#include "common.glsl"
#include "voxel_common.glsl"
#define CONE_SET 2
#define CONE_FULL_RES 1
#include "cone_tracing.glsl"

layout(local_size_x = 8, local_size_y = 8) in;

layout(set = 1, binding = 0) uniform sampler2D gb_position;
layout(set = 1, binding = 1) uniform sampler2D gb_normals;
layout(set = 1, binding = 2, rgba32f) uniform writeonly image2D gathered;
// The specular cone where it is wide enough to share (SHARED_SPECULAR): its radiance (rgb) and
// the tangent of its half angle (a); else a 0. It depends on the view, so it is traced every
// frame and kept in no history.
layout(set = 1, binding = 9) uniform sampler2D gb_emission;
layout(set = 1, binding = 10, rgba16f) uniform writeonly image2D gathered_specular;
#ifdef TEMPORAL
// Per block, the frame before's (in) and this frame's (out): the cones' sums (irradiance rgb,
// occlusion a), where the block's surface lies (xyz) with the weight of the cones summed (w:
// 0 is no history), and its geometric normal (octahedral, xy).
layout(set = 1, binding = 3, rgba32f) uniform readonly image2D history_in;
layout(set = 1, binding = 4, rgba32f) uniform readonly image2D history_place_in;
layout(set = 1, binding = 5, rgba16f) uniform readonly image2D history_normal_in;
layout(set = 1, binding = 6, rgba32f) uniform writeonly image2D history_out;
layout(set = 1, binding = 7, rgba32f) uniform writeonly image2D history_place_out;
layout(set = 1, binding = 8, rgba16f) uniform writeonly image2D history_normal_out;
#endif

layout(push_constant) uniform Pass {
    mat4 prev_view_proj;  // TEMPORAL: the frame before's camera
    uint scale;           // pixels per block side
    uint subsets;         // TEMPORAL: frames to trace the whole cone set
    uint frame_index;     // TEMPORAL: picks this frame's subset
    uint reset;           // TEMPORAL: 1 drops every block's history
} pass;

#ifdef TEMPORAL
// The history at world point p (geometric normal geo): the frame before's blocks around where
// p was seen, bilinearly weighted, those that held the same surface only (as cone_trace.comp's
// upsampling tests it). Sums and weight are both interpolated, so their ratio stays an estimate of the
// whole set.
void reproject(vec3 p, vec3 geo, out vec4 sums, out float weight) {
    sums = vec4(0.0);
    weight = 0.0;
    if (pass.reset != 0u) return;
    vec4 clip = pass.prev_view_proj * vec4(p, 1.0);
    if (clip.w <= 0.0) return;
    vec2 ndc = clip.xy / clip.w;
    // The viewport's height is negative (common.glsl's frames are y up): row 0 is ndc y = 1.
    vec2 pixel = vec2(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * vec2(frame.counts.yz);
    int s = int(pass.scale);
    vec2 u = (pixel - 0.5 - float(s / 2)) / float(s);
    ivec2 b = ivec2(floor(u));
    vec2 f = u - vec2(b);
    // A still camera lands on the block itself (up to rounding): take it alone.
    f = mix(f, round(f), lessThan(abs(f - round(f)), vec2(1e-3)));
    ivec2 blocks = imageSize(history_place_in);
    float vs = voxel_size();
    float wsum = 0.0;
    for (int k = 0; k < 4; k++) {
        ivec2 o = ivec2(k & 1, k >> 1);
        ivec2 c = b + o;
        vec2 wb = mix(1.0 - f, f, vec2(o));
        float w = wb.x * wb.y;
        if (w == 0.0 || any(lessThan(c, ivec2(0))) || any(greaterThanEqual(c, blocks))) continue;
        vec4 place = imageLoad(history_place_in, c);
        if (place.w <= 0.0) continue;
        vec3 nk = oct_decode(imageLoad(history_normal_in, c).xy);
        vec3 d = place.xyz - p;
        if (abs(dot(d, geo)) > 0.25 * vs || dot(d, d) > 4.0 * vs * vs || dot(geo, nk) < 0.9) continue;
        sums += w * imageLoad(history_in, c);
        weight += w * place.w;
        wsum += w;
    }
    if (wsum > 0.0) {
        sums /= wsum;
        weight /= wsum;
    }
}
#endif

void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    ivec2 blocks = imageSize(gathered);
    if (any(greaterThanEqual(q, blocks))) return;
    int s = int(pass.scale);
    ivec2 px = min(q * s + s / 2, ivec2(frame.counts.yz) - 1);
    vec4 pos = texelFetch(gb_position, px, 0);
    if (pos.a == 0.0) {
        imageStore(gathered, q, vec4(0.0));
        imageStore(gathered_specular, q, vec4(0.0));
#ifdef TEMPORAL
        imageStore(history_out, q, vec4(0.0));
        imageStore(history_place_out, q, vec4(0.0));
        imageStore(history_normal_out, q, vec4(0.0));
#endif
        return;
    }
    vec4 normals = texelFetch(gb_normals, px, 0);
    vec3 p = pos.xyz;
    vec3 n = oct_decode(normals.xy);
    vec3 geo = oct_decode(normals.zw);
    float t0;
    vec3 origin = cone_start(p, n, geo, t0);
    mat3 frame_n = tangent_frame(n);
    float whole = cone_set_weight();

    float tan_half = specular_aperture(texelFetch(gb_emission, px, 0).a);
    vec4 specular = vec4(0.0);
    if (frame.trace.z > 0.0 && tan_half >= SHARED_SPECULAR) {
        vec3 r = reflect(normalize(p - frame.eye.xyz), n);
        specular = vec4(trace_specular_cone(origin, r, tan_half, t0).radiance, tan_half);
    }
    imageStore(gathered_specular, q, specular);
#ifdef TEMPORAL
    vec4 sums;
    float weight;
    reproject(p, geo, sums, weight);
    if (pass.reset != 0u) {
        Gather g = diffuse_cones(origin, frame_n, t0, 0u, 1u);
        sums = vec4(g.irradiance, g.occlusion);
        weight = g.weight;
    } else if (weight < whole * (1.0 - 1e-4)) {
        // Complete once the sums hold the whole set's weight (to rounding).
        uint subsets = max(pass.subsets, 1u);
        Gather g = diffuse_cones(origin, frame_n, t0, pass.frame_index % subsets, subsets);
        sums += vec4(g.irradiance, g.occlusion);
        weight += g.weight;
    }
    imageStore(history_out, q, sums);
    imageStore(history_place_out, q, vec4(p, weight));
    imageStore(history_normal_out, q, vec4(normals.zw, 0.0, 0.0));
    imageStore(gathered, q, weight > 0.0 ? sums * (whole / weight) : vec4(0.0));
#else
    Gather g = diffuse_cones(origin, frame_n, t0, 0u, 1u);
    imageStore(gathered, q, vec4(g.irradiance, g.occlusion));
#endif
}
