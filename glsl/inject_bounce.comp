#version 450
// variants: PAPER SHARE
// Second bounce (the paper's inject_propagation): every voxel gathers the light the directional
// volumes hold around it with diffuse cones and adds what it reflects to its radiance; the mip
// passes then run again. Default: the bounces' own cone set (frame.bounce_cones, fewer than the
// pixels') and albedo / pi; a two-sided voxel gathers both sides. What a voxel reflects is kept
// aside for bounce_tail.comp, which adds it (on the last bounce with the bounces not traced),
// and each voxel's albedo times the share of its hemisphere the cones found closed is summed
// for it over the voxels that gathered light. One-sided voxels share their gather within blocks of BLOCK^3 voxels
// (FLAG_BOUNCE_SHARE): the SHARE dispatch, run first, one invocation a block, gathers from the
// middle of the block's first one-sided voxel's plane where no surface rises in front of it,
// and the voxels in that plane that face its way take that light (bounce light is smooth, and
// the pixels' cones blur it again). PAPER: the original's 4 cones of aperture 1, 40.9 degrees
// from the normal, weights pi/3 and 2pi/9, clamped to 1, added to the radiance here.
#include "common.glsl"
#include "voxel_common.glsl"
#define VOXEL_SET 1
#include "voxel_data.glsl"
#define CONE_SET 2
#define CONE_FULL_RES 0
#define CONE_THIN_WALLS 1
#include "cone_tracing.glsl"
#include "bounce_common.glsl"

// One invocation per filled voxel, from the list voxel_list.comp made.
layout(local_size_x = 64) in;

#ifdef PAPER
layout(set = 1, binding = 5, rgba8) uniform image3D radiance;
#else
// Per listed voxel: the light it reflects (times the radiance scale) as half floats, r g and b
// then, for a two-sided voxel, which way it goes along voxel_facing (-1 to 1; 2: one-sided).
// With FLAG_BACKS two entries a voxel: then what its back reflects (r g b, 0), zero but for
// open backs (voxel_data.glsl).
#ifndef SHARE
layout(set = 1, binding = 11, std430) writeonly buffer Reflected { uvec2 reflected[]; };
#endif
// The tail's sums (bounce_tail.comp), each as 64-bit fixed point (low word, high word;
// bounce_common.glsl): over the listed voxels, albedo x closed share (r, g, b) and the weights,
// each voxel weighted by the light it gathered (its luminance) times its closed share; then the
// same over the open backs (the backs' own series: a room of quads facing out holds its light
// on their backs); then both again with every voxel that gathered light weighing the same.
#ifndef SHARE
layout(set = 1, binding = 12, std430) buffer Reflectance { uint reflectance[REFLECTANCE_WORDS]; };
shared uvec2 partial[4][64];
shared uvec2 partial_back[4][64];
#endif
// Voxels a side of the blocks that share a gather (volumes.rs: BOUNCE_BLOCK).
const int BLOCK = 4;
// Per block: the gather made for it (gather()'s light and closed share), and which voxel's
// plane it was made in (voxel_index + 1; 0: none, its voxels gather their own), which SHARE
// writes and the gather reads.
#ifdef SHARE
layout(set = 1, binding = 13, rgba32f) writeonly uniform image3D block_gather;
layout(set = 1, binding = 14, r32ui) writeonly uniform uimage3D block_first;
#else
layout(set = 1, binding = 13, rgba32f) readonly uniform image3D block_gather;
layout(set = 1, binding = 14, r32ui) readonly uniform uimage3D block_first;
#endif
#endif

#ifdef PAPER
// The original's propagation cone: aperture 1 (diameter = distance, a half angle of 26.6
// degrees), the directional volumes only, steps of a diameter but at least a texel (two
// voxels), composited "over". Nothing if its first sample lies outside the grid; past the grid
// it reads the edge texels (clamp to edge), as the original does with its boundary check off.
vec3 paper_propagation_cone(vec3 origin, vec3 dir, float max_dist) {
    float texel = 2.0 * voxel_size();
    float t = texel;
    vec4 cone = vec4(0.0);
    vec3 uvw = world_to_grid(origin + dir * t);
    if (any(lessThan(uvw, vec3(0.0))) || any(greaterThan(uvw, vec3(1.0)))) return vec3(0.0);
    for (int i = 0; i < 1024 && cone.a <= 1.0 && t <= max_dist; i++) {
        float diameter = t;
        float level = max(log2(diameter / texel) - 1.0, 0.0);
        vec4 s = sample_directional(world_to_grid(origin + dir * t), dir, level);
        cone += (1.0 - cone.a) * s;
        t += max(diameter, texel);
    }
    return cone.rgb / frame.tuning.y;  // the volumes' radiance scale
}
#endif

// The light falling on a surface at p facing n (rgb), and the share of its hemisphere, cosine
// weighted, where the cones met surfaces (a).
vec4 gather(vec3 p, vec3 n) {
    mat3 frame_n = tangent_frame(n);
    float vs = voxel_size();
    float max_dist = frame.cone.z * frame.grid.w;
    vec3 e = vec3(0.0);
    float closed = 0.0;
#ifdef PAPER
    // The original's four directions, its ring vectors' tangent parts added to the normal (so
    // tilted 40.9 degrees, not the 60 their y of 0.5 suggests), in tangent_frame's axes: the
    // original's "right" is the frame's second axis and its "up" the first.
    const vec3 dirs[4] = vec3[4](vec3(0.0, 0.0, 1.0), vec3(0.866025, 0.0, 1.0),
                                 vec3(-0.4330128, 0.754996, 1.0), vec3(-0.4330128, -0.754996, 1.0));
    const float weights[4] = float[4](PI / 3.0, 2.0 * PI / 9.0, 2.0 * PI / 9.0, 2.0 * PI / 9.0);
    vec3 origin = p + n * 2.0 * vs;  // one directional-volume texel
    for (int i = 0; i < 4; i++) {
        vec3 d = normalize(frame_n * dirs[i]);
        e += weights[i] * paper_propagation_cone(origin, d, max_dist);
    }
#else
    // From a voxel centre, which can lie up to sqrt(3)/2 voxel behind its surface: one voxel
    // further out than the pixels' cones start.
    vec3 origin = p + n * (frame.trace.x + 1.0) * vs;
    for (uint i = 0u; i < uint(frame.bounce_cone.y); i++) {
        vec3 d = normalize(frame_n * frame.bounce_cones[i].xyz);
        Cone cone = trace_cone(origin, d, frame.bounce_cone.x, vs, max_dist);
        e += frame.bounce_cones[i].w * cone.radiance;
        closed += frame.bounce_cones[i].w * cone.opacity;
    }
#endif
    return vec4(e, closed / PI);  // the cone weights sum to pi
}

#ifdef PAPER
void main() {
    uint i = list_entry();
    if (!listed(i)) return;
    ivec3 c = listed_voxel(i);
    Voxel v = load_voxel(c);
    if (!v.filled) return;
    vec4 direct = imageLoad(radiance, c);
    vec3 p = frame.grid.xyz + vec3(c) * voxel_size();
    vec3 n = dot(v.normal, v.normal) > 0.0 ? v.normal : vec3(0.0, 1.0, 0.0);
    vec3 bounce = clamp(gather(p, n).rgb, 0.0, 1.0) * v.albedo;
    imageStore(radiance, c, vec4(direct.rgb + bounce * frame.tuning.y, direct.a));
}
#else
// The axis a normal is nearest.
int main_axis(vec3 n) {
    vec3 a = abs(n);
    return a.x >= max(a.y, a.z) ? 0 : (a.y >= a.z ? 1 : 2);
}

// Whether one-sided voxel v at c may take the gather made in the plane of its block's first
// one-sided voxel (r, rep): it faces within 26 degrees of it and lies in its plane (a floor
// voxelized two voxels thick keeps its layers apart: the lower one's cones start among the
// upper one's voxels). SHARE made no gather where a surface rises in front of the plane.
bool shares_gather(ivec3 c, Voxel v, ivec3 r, Voxel rep) {
    return dot(v.normal, rep.normal) >= 0.9 && abs(dot(vec3(c - r), rep.normal)) < 0.5
        && c[main_axis(rep.normal)] == r[main_axis(rep.normal)];
}

// The workgroup's gathers are queued and then run by its invocations in turn, not each by
// its own voxel's invocation: a voxel needs none (it takes its block's), one or two, and
// invocations run in lockstep groups (lanes of a SIMD unit, a warp), where one that gathers
// holds up the rest.
const uint NO_GATHER = 0xFFFFFFFFu;
shared vec3 queued_p[128];  // two a voxel at most
shared vec3 queued_n[128];
shared vec4 gathered[128];
shared uint queued;

void start_queue() {
    if (gl_LocalInvocationIndex == 0u) queued = 0u;
    barrier();
}

// Queues a gather from p facing n; its slot in `gathered`.
uint queue_gather(vec3 p, vec3 n) {
    uint k = atomicAdd(queued, 1u);
    queued_p[k] = p;
    queued_n[k] = n;
    return k;
}

// Runs the queued gathers, spread over the workgroup (every invocation calls it).
void run_queue() {
    barrier();
    uint count = queued;
    for (uint k = gl_LocalInvocationIndex; k < count; k += gl_WorkGroupSize.x) {
        gathered[k] = gather(queued_p[k], queued_n[k]);
    }
    barrier();
}

#ifdef SHARE
// Whether the voxels in front of block b's plane through r (normal n) are empty, a voxel
// beyond the block to each side too: no wall rises beside its voxels, whose nearness would
// change what each sees (and a divider through the block would hand the dark side the lit
// side's light).
bool clear_in_front(ivec3 b, ivec3 r, vec3 n) {
    int axis = main_axis(n);
    ivec3 lo = b * BLOCK - ivec3(1), hi = b * BLOCK + ivec3(BLOCK);
    lo[axis] = r[axis] + (n[axis] > 0.0 ? 1 : -1);
    hi[axis] = lo[axis];
    for (int z = lo.z; z <= hi.z; z++) {
        for (int y = lo.y; y <= hi.y; y++) {
            for (int x = lo.x; x <= hi.x; x++) {
                ivec3 q = ivec3(x, y, z);
                if (in_grid(q) && voxel_filled(q)) return false;
            }
        }
    }
    return true;
}

// One invocation a block (x fastest), in rows of groups of 64.
void main() {
    start_queue();
    int m = (grid_n() + BLOCK - 1) / BLOCK;
    uint k = gl_GlobalInvocationID.x + gl_WorkGroupID.y * gl_NumWorkGroups.x * 64u;
    ivec3 b = ivec3(int(k) % m, (int(k) / m) % m, int(k) / (m * m));
    bool inside = k < uint(m * m * m);
    uint first = 0u;
    uint slot = NO_GATHER;
    if (inside) {
        for (int j = 0; j < BLOCK * BLOCK * BLOCK; j++) {
            ivec3 q = b * BLOCK + ivec3(j % BLOCK, (j / BLOCK) % BLOCK, j / (BLOCK * BLOCK));
            if (!in_grid(q) || !voxel_filled(q)) continue;
            Voxel v = load_voxel(q);
            if (v.agreement < 0.5) continue;
            if (clear_in_front(b, q, v.normal)) {
                first = voxel_index(q) + 1u;
                // From the block's middle moved into the plane: within half a block of
                // each voxel that takes it.
                vec3 middle = frame.grid.xyz + (vec3(b) + 0.5) * float(BLOCK) * voxel_size();
                vec3 p = middle - v.normal * dot(middle - voxel_centre(q), v.normal);
                slot = queue_gather(p, v.normal);
            }
            break;
        }
        imageStore(block_first, b, uvec4(first));
    }
    run_queue();
    if (slot != NO_GATHER) imageStore(block_gather, b, gathered[slot]);
}
#else
// Whether one-sided voxel v at c takes its block's gather (then in `light`).
bool block_gather_for(ivec3 c, Voxel v, out vec4 light) {
    light = vec4(0.0);
    if ((frame.grid_info.w & FLAG_BOUNCE_SHARE) == 0u) return false;
    ivec3 b = c / BLOCK;
    uint first = imageLoad(block_first, b).x;
    if (first == 0u) return false;
    uint n = uint(grid_n()), f = first - 1u;
    ivec3 r = ivec3(int(f % n), int((f / n) % n), int(f / (n * n)));
    if (r != c && !shares_gather(c, v, r, load_voxel(r))) return false;
    light = imageLoad(block_gather, b);
    return true;
}

// x in the sums' fixed point, as (low word, high word).
uvec2 to_fixed(float x) {
    float f = floor(clamp(x, 0.0, REFLECTANCE_MAX) * REFLECTANCE_ONE + 0.5);
    float high = floor(f / 4294967296.0);
    return uvec2(uint(f - high * 4294967296.0), uint(high));
}

uvec2 add64(uvec2 a, uvec2 b) {
    uint low = a.x + b.x;
    return uvec2(low, a.y + b.y + (low < a.x ? 1u : 0u));
}

// Adds a workgroup's sum, in fixed point, to the 64-bit word pair at k.
void add_fixed(uint k, uvec2 x) {
    if (x == uvec2(0u)) return;
    uint before = atomicAdd(reflectance[k], x.x);
    uint carry = before > 0xFFFFFFFFu - x.x ? 1u : 0u;
    if (x.y + carry > 0u) atomicAdd(reflectance[k + 1u], x.y + carry);
}

// Adds this workgroup's fronts' (a) and backs' (b) shares to the sums at `base` and base + 8.
void add_sums(vec4 a, vec4 b, uint base) {
    uint l = gl_LocalInvocationIndex;
    for (uint k = 0u; k < 4u; k++) {
        partial[k][l] = to_fixed(a[k]);
        partial_back[k][l] = to_fixed(b[k]);
    }
    barrier();
    for (uint s = 32u; s > 0u; s >>= 1u) {
        if (l < s) {
            for (uint k = 0u; k < 4u; k++) {
                partial[k][l] = add64(partial[k][l], partial[k][l + s]);
                partial_back[k][l] = add64(partial_back[k][l], partial_back[k][l + s]);
            }
        }
        barrier();
    }
    if (l == 0u) {
        for (uint k = 0u; k < 4u; k++) {
            add_fixed(base + 2u * k, partial[k][0]);
            add_fixed(base + 8u + 2u * k, partial_back[k][0]);
        }
    }
    barrier();
}

void main() {
    start_queue();
    uint i = list_entry();
    vec4 mine = vec4(0.0);  // albedo x closed share, and 1, weighted, for the sums
    vec4 mine_back = vec4(0.0);  // the same for an open back
    vec4 mine_even = vec4(0.0), mine_back_even = vec4(0.0);  // the same, unweighted
    // What the voxel gathers: its front (or its block's) and its back, queued or taken.
    Voxel v;
    v.filled = false;
    ivec3 c = ivec3(0);
    uint front_slot = NO_GATHER, back_slot = NO_GATHER;
    vec4 front_light = vec4(0.0);
    bool two_sided = false, open = false;
    if (listed(i)) {
        c = listed_voxel(i);
        v = load_voxel(c);
        if (v.filled) {
            vec3 p = voxel_centre(c);
            vec3 n = voxel_facing(v);
            two_sided = v.agreement < 0.5;
            if (two_sided) {
                front_slot = queue_gather(p, n);
                back_slot = queue_gather(p, -n);
            } else {
                if (!block_gather_for(c, v, front_light)) front_slot = queue_gather(p, n);
                // An open back gathers its own side, kept apart.
                open = open_back(c, v);
                if (open) back_slot = queue_gather(p, -n);
            }
        }
    }
    run_queue();
    if (front_slot != NO_GATHER) front_light = gathered[front_slot];
    vec4 back_gather = back_slot != NO_GATHER ? gathered[back_slot] : vec4(0.0);
    if (listed(i)) {
        vec3 bounce = vec3(0.0), back_light = vec3(0.0);
        float side = 2.0;
        if (v.filled) {
            float closed;
            if (two_sided) {
                // Two-sided: each face reflects what falls on its side. The voxel shows one
                // radiance, the brighter side's, and its light goes that way by how much brighter
                // it is (as inject_radiance.comp's direct light does): a wall lit on one side
                // stays dark on the other (seen_from, aniso_mip.glsl), and where both sides are
                // alike each sees its own. Their mean halved the light of a wall thinner than a
                // voxel whose outer face sees the dark.
                vec4 gf = front_light, gb = back_gather;
                vec3 front = v.albedo / PI * gf.rgb, back = v.albedo / PI * gb.rgb;
                float lf = luminance(front), lb = luminance(back);
                bounce = lf >= lb ? front : back;
                side = (lf - lb) / max(lf + lb, 1e-30);
                // The series goes on from the side that gathered the light: an outer face that
                // sees the void would halve it (as for one-sided voxels below).
                float seen_f = luminance(gf.rgb), seen_b = luminance(gb.rgb);
                closed = (gf.a * seen_f + gb.a * seen_b) / max(seen_f + seen_b, 1e-30);
            } else {
                bounce = v.albedo / PI * front_light.rgb;
                closed = front_light.a;
                if (open) {
                    vec4 gb = back_gather;
                    back_light = v.albedo / PI * gb.rgb;
                    float cb = clamp(gb.a, 0.0, 1.0);
                    mine_back = vec4(v.albedo * cb, 1.0) * luminance(gb.rgb) * cb;
                    if (luminance(gb.rgb) > 0.0) mine_back_even = vec4(v.albedo * cb, 1.0);
                }
            }
            // Each voxel weighs in the series by the light it gathered times its closed share:
            // the next bounce gathers where this one's light is (a lit room on a dark ground,
            // white walls over a dark floor: openings-010's lambda 0.24 over every surface that
            // gathered light, where the path tracer's orders go by 0.52), and a surface gathers
            // the next bounce only from what closes its hemisphere (a roof's top under the sky
            // gathers much light and returns none). The dark outer faces of a closed room's
            // thick walls see the void and weigh nothing.
            float gathered_light = two_sided ? luminance(front_light.rgb + back_gather.rgb)
                                             : luminance(front_light.rgb);
            float c = clamp(closed, 0.0, 1.0);
            mine = vec4(v.albedo * c, 1.0) * gathered_light * c;
            if (gathered_light > 0.0) mine_even = vec4(v.albedo * c, 1.0);
        }
        bounce *= frame.tuning.y;
        back_light *= frame.tuning.y;
        if ((frame.grid_info.w & FLAG_BACKS) != 0u) {
            reflected[2u * i] = uvec2(packHalf2x16(bounce.rg), packHalf2x16(vec2(bounce.b, side)));
            reflected[2u * i + 1u] =
                uvec2(packHalf2x16(back_light.rg), packHalf2x16(vec2(back_light.b, 0.0)));
        } else {
            reflected[i] = uvec2(packHalf2x16(bounce.rg), packHalf2x16(vec2(bounce.b, side)));
        }
    }
    // The workgroup's sums, then one atomic add per word. Each voxel's share is rounded to the
    // fixed point first and added as integers, exactly whatever the order: the list's order
    // (which voxels share a workgroup) changes from run to run.
    add_sums(mine, mine_back, 0u);
    add_sums(mine_even, mine_back_even, 16u);
}
#endif  // SHARE
#endif
