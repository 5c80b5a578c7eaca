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
// A moving camera's history is blended from the blocks around each surface point, so it is
// near the block's own cones but not them. Once the camera stops (`still`), each block traces
// its cones afresh, one subset a frame, and after `subsets` frames holds exactly the whole set
// at its own pixel, as a fresh start would: the still image does not depend on the way there.
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
// 0 is no history), its geometric normal (octahedral, xy) with the first (z) and count (w) of
// the subsets traced afresh since the camera stopped, and their sums (fresh).
layout(set = 1, binding = 3, rgba32f) uniform readonly image2D history_in;
layout(set = 1, binding = 4, rgba32f) uniform readonly image2D history_place_in;
layout(set = 1, binding = 5, rgba32f) uniform readonly image2D history_normal_in;
layout(set = 1, binding = 6, rgba32f) uniform writeonly image2D history_out;
layout(set = 1, binding = 7, rgba32f) uniform writeonly image2D history_place_out;
layout(set = 1, binding = 8, rgba32f) uniform writeonly image2D history_normal_out;
layout(set = 1, binding = 11, rgba32f) uniform readonly image2D history_fresh_in;
layout(set = 1, binding = 12, rgba32f) uniform writeonly image2D history_fresh_out;
#endif

layout(push_constant) uniform Pass {
    mat4 prev_view_proj;  // TEMPORAL: the frame before's camera
    uint scale;           // pixels per block side
    uint subsets;         // TEMPORAL: frames to trace the whole cone set
    uint frame_index;     // TEMPORAL: picks the subset a block starts from
    uint reset;           // TEMPORAL: 1 drops every block's history
    uint still;           // TEMPORAL: 1 when the camera is the frame before's (jitter aside)
} pass;

#ifdef TEMPORAL
// What a block carries from frame to frame.
struct History {
    vec4 sums;           // the cones' sums, over the cones of weight `weight`
    float weight;        // 0: no history
    vec4 fresh;          // the sums of the subsets traced at this block since the camera stopped
    uint fresh_first;    // the first of those subsets
    uint fresh_count;    // how many they are
};

// Whether the block's surface at `place` (normal nk) is the one at p (normal geo).
bool same_surface(vec3 place, vec3 nk, vec3 p, vec3 geo) {
    float vs = voxel_size();
    vec3 d = place - p;
    return abs(dot(d, geo)) <= 0.25 * vs && dot(d, d) <= 4.0 * vs * vs && dot(geo, nk) >= 0.9;
}

// The history at world point p (geometric normal geo) of block q. A still camera sees the
// same point at the block's pixel (to the antialiasing's sub-pixel shift): its own history,
// fresh sums included. A moving one: the frame before's blocks around where p was seen,
// bilinearly weighted, those that held the same surface only (as cone_trace.comp's upsampling
// tests it). Sums and weight are both interpolated, so their ratio stays an estimate of the
// whole set; nothing of it is fresh.
History reproject(ivec2 q, vec3 p, vec3 geo) {
    History h = History(vec4(0.0), 0.0, vec4(0.0), 0u, 0u);
    if (pass.reset != 0u) return h;
    if (pass.still != 0u) {
        vec4 place = imageLoad(history_place_in, q);
        vec4 nk = imageLoad(history_normal_in, q);
        if (place.w > 0.0 && same_surface(place.xyz, oct_decode(nk.xy), p, geo)) {
            h.sums = imageLoad(history_in, q);
            h.weight = place.w;
            h.fresh = imageLoad(history_fresh_in, q);
            h.fresh_first = uint(nk.z);
            h.fresh_count = uint(nk.w);
        }
        return h;
    }
    vec4 clip = pass.prev_view_proj * vec4(p, 1.0);
    if (clip.w <= 0.0) return h;
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
        if (!same_surface(place.xyz, nk, p, geo)) continue;
        h.sums += w * imageLoad(history_in, c);
        h.weight += w * place.w;
        wsum += w;
    }
    if (wsum > 0.0) {
        h.sums /= wsum;
        h.weight /= wsum;
    }
    return h;
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
        imageStore(history_fresh_out, q, vec4(0.0));
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
    uint subsets = max(pass.subsets, 1u);
    History h = reproject(q, p, geo);
    // Complete once the sums hold the whole set's weight (to rounding).
    bool partial = h.weight < whole * (1.0 - 1e-4);
    bool refreshing = pass.still != 0u && h.fresh_count < subsets;
    if (pass.reset != 0u) {
        Gather g = diffuse_cones(origin, frame_n, t0, 0u, 1u);
        h.sums = vec4(g.irradiance, g.occlusion);
        h.weight = g.weight;
        h.fresh = h.sums;
        h.fresh_count = subsets;
    } else if (partial || refreshing) {
        // A block traces consecutive subsets, so it has them all after `subsets` frames: while
        // moving, from the frame's number; at rest, from the one its fresh sums began at (a
        // frame's number picks it; the block's count goes on, whatever the frames are called).
        if (refreshing && h.fresh_count == 0u) h.fresh_first = pass.frame_index % subsets;
        uint k = refreshing ? (h.fresh_first + h.fresh_count) % subsets
                            : pass.frame_index % subsets;
        Gather g = diffuse_cones(origin, frame_n, t0, k, subsets);
        vec4 s = vec4(g.irradiance, g.occlusion);
        if (partial) {
            h.sums += s;
            h.weight += g.weight;
        }
        if (refreshing) {
            h.fresh += s;
            h.fresh_count += 1u;
        }
        if (h.fresh_count >= subsets) {
            // Every cone traced afresh at this pixel: the history is now exactly the set.
            h.sums = h.fresh;
            h.weight = whole;
        }
    }
    // Until the fresh sums are complete the blended ones stand: subsets differ by where their
    // cones point, so part fresh and part blended would be further from the set than either.
    vec4 estimate = h.sums;
    if (pass.reset == 0u) {
        estimate = h.weight > 0.0 ? h.sums * (whole / h.weight) : vec4(0.0);
    }
    if (pass.still == 0u && pass.reset == 0u) {
        // Moving: what is traced now is at a point the next frame will not see again.
        h.fresh = vec4(0.0);
        h.fresh_count = 0u;
    }
    imageStore(history_out, q, h.sums);
    imageStore(history_place_out, q, vec4(p, h.weight));
    imageStore(history_normal_out, q, vec4(normals.zw, float(h.fresh_first), float(h.fresh_count)));
    imageStore(history_fresh_out, q, h.fresh);
    imageStore(gathered, q, estimate);
#else
    Gather g = diffuse_cones(origin, frame_n, t0, 0u, 1u);
    imageStore(gathered, q, vec4(g.irradiance, g.occlusion));
#endif
}
