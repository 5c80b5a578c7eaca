// Cone tracing, step 4 of the paper: march a cone through the voxels, sampling the directional
// volumes at the mip level whose texels match the cone's diameter, and composite front to back
// (PAPER: "over"; default: added up until opaque, see trace_cone).
// Define CONE_SET (descriptor set) and CONE_FULL_RES (1: the full-resolution radiance volume is
// bound and mixed in for cones narrower than the directional volumes' texels) before including;
// CONE_THIN_WALLS 1: the thin walls are bound and hide what lies behind them (the bounce's
// cones, see thin_wall_between).
#ifndef CONE_TRACING_GLSL
#define CONE_TRACING_GLSL
#ifndef CONE_THIN_WALLS
#define CONE_THIN_WALLS 0
#endif

#include "aniso_mip.glsl"
#include "environment.glsl"
#include "brdf.glsl"

#if CONE_FULL_RES
layout(set = CONE_SET, binding = 0) uniform sampler3D radiance_tex;
#ifndef PAPER
layout(set = CONE_SET, binding = 8) uniform sampler3D emit_dir_tex;
// The light of open backs (voxel_data.glsl), read with FLAG_BACKS.
layout(set = CONE_SET, binding = 11) uniform sampler3D back_radiance_tex;
#endif
#endif
layout(set = CONE_SET, binding = 1) uniform sampler3D aniso_nx;
layout(set = CONE_SET, binding = 2) uniform sampler3D aniso_px;
layout(set = CONE_SET, binding = 3) uniform sampler3D aniso_ny;
layout(set = CONE_SET, binding = 4) uniform sampler3D aniso_py;
layout(set = CONE_SET, binding = 5) uniform sampler3D aniso_nz;
layout(set = CONE_SET, binding = 6) uniform sampler3D aniso_pz;
#ifndef PAPER
layout(set = CONE_SET, binding = 7) uniform sampler3D light_dir;
layout(set = CONE_SET, binding = 9) uniform sampler3D light_pos;
// Per cell of frame.tuning.w voxels, the distance in cells to the nearest cell that holds a
// filled voxel (empty_space.comp).
layout(set = CONE_SET, binding = 10, r32ui) uniform readonly uimage3D empty_space;
#if CONE_THIN_WALLS
// Where the thin walls lie per axis and how much of a texel they cover (Volumes::thin_walls),
// each read from the nearest mip level (Volumes::level_sampler).
layout(set = CONE_SET, binding = 12) uniform sampler3D thin_walls_xy;
layout(set = CONE_SET, binding = 13) uniform sampler3D thin_walls_z;
#endif
#endif

#ifndef PAPER
// How much of a voxel's light going along `going` the face volumes show a cone travelling
// along `dir` (aniso_mip_base.comp's seen_from per axis, weighted as the cone weighs the axes).
float seen_along(vec3 going, vec3 dir) {
    vec3 w = dir * dir;
    return w.x * seen_from(going, vec3(-sign(dir.x), 0.0, 0.0))
         + w.y * seen_from(going, vec3(0.0, -sign(dir.y), 0.0))
         + w.z * seen_from(going, vec3(0.0, 0.0, -sign(dir.z)));
}
#endif

#if CONE_THIN_WALLS && !defined(PAPER)
// How much of a sample's light thin walls hide from the cone's origin `from`, the sample's light
// taken as lying at `light` (its light-weighted mean; all in grid units). A face volume
// composites its texels along its own axis only, and a sample blends texels on both sides of
// a wall: across a divider one voxel thick whose floor, ceiling and side walls run on into the
// room beyond, the dark room's voxels gathered the lit room's floor and walls through the
// volumes of the other axes, whose planes they lie in front of, and their bounces carried it
// on (hard case leak-junction: 1.2% of the lit room's light). A wall hides the light beyond its
// plane, as much as it covers the texels where the line from the origin to the light crosses
// that plane, read two levels finer than the sample: a coarse texel's plane can be the mean of
// two walls (a room's floor and ceiling) where there is none, and a door in a wall is no wall
// (hard case door-room). The origin at least a quarter of a voxel in front of the plane, the
// light from half a voxel to a voxel beyond it: a voxel's light lies at its centre across its
// surface, up to half a voxel past the wall it meets at a corner.
float thin_wall_between(vec3 uvw, float level, vec3 from, vec3 light) {
    vec4 wxy = textureLod(thin_walls_xy, uvw, level);
    vec2 wz = textureLod(thin_walls_z, uvw, level).xy;
    vec3 cover = vec3(wxy.y, wxy.w, wz.y);
    if (all(equal(cover, vec3(0.0)))) return 0.0;
    vec3 at = vec3(wxy.x, wxy.z, wz.x) / max(cover, vec3(1e-6));
    // A quarter of a voxel, but no less than the half floats' steps near 1 (2^-11) allow.
    float m = max(0.25 / float(grid_n()), 1.0 / 1024.0);
    vec3 to_volume = vec3(float(grid_n()) / float(2 * textureSize(aniso_nx, 0).x));
    float fine = max(level - 2.0, 0.0);
    float kept = 1.0;
    for (int k = 0; k < 3; k++) {
        // The light beyond the sample's plane, seen from the origin.
        if (cover[k] <= 0.0 || (at[k] - light[k]) * sign(from[k] - at[k]) <= 0.0) continue;
        vec3 p = from + (light - from) * ((at[k] - from[k]) / (light[k] - from[k]));
        vec4 f = textureLod(thin_walls_xy, p * to_volume, fine);
        vec2 w = k == 0 ? f.xy : (k == 1 ? f.zw : textureLod(thin_walls_z, p * to_volume, fine).xy);
        float wall = w.x / max(w.y, 1e-6);
        float side = sign(from[k] - wall);
        float beyond = clamp((wall - light[k]) * side / (2.0 * m) - 1.0, 0.0, 1.0);
        float in_front = clamp(abs(from[k] - wall) / m, 0.0, 1.0);
        kept *= 1.0 - min(w.y, 1.0) * beyond * in_front;
    }
    return 1.0 - kept;
}
#endif

// The directional volumes seen by a cone travelling along `dir`, weighted by dir^2. Default:
// seen from `from` (grid units), the cone's origin; see below.
vec4 sample_directional(vec3 uvw, vec3 dir, float level, vec3 from, bool from_origin) {
    vec3 w = dir * dir;
    // With an odd grid the directional volumes cover one voxel more than the grid.
    uvw *= float(grid_n()) / float(2 * textureSize(aniso_nx, 0).x);
    vec4 sx = dir.x < 0.0 ? textureLod(aniso_nx, uvw, level) : textureLod(aniso_px, uvw, level);
    vec4 sy = dir.y < 0.0 ? textureLod(aniso_ny, uvw, level) : textureLod(aniso_py, uvw, level);
    vec4 sz = dir.z < 0.0 ? textureLod(aniso_nz, uvw, level) : textureLod(aniso_pz, uvw, level);
#if defined(PAPER) && defined(CONE_LIGHT_PASS)
    // --paper-slips: the original's light pass has the -X volume bound to all six units
    // (gi_deferred_renderer.cpp binds mips[0] in its loop over them).
    if ((frame.grid_info.w & FLAG_PAPER_SLIPS) != 0u) {
        vec4 nx = textureLod(aniso_nx, uvw, level);
        sx = nx;
        sy = nx;
        sz = nx;
    }
#endif
    vec4 s = w.x * sx + w.y * sy + w.z * sz;
#ifndef PAPER
    // Each face volume shows light going at right angles to its axis, so a cone crossing a
    // surface's plane from behind would see it through the volumes of the other axes, and a
    // cone running beside a thin wall, on its dark side, reads texels that hold the wall's lit
    // face: a texel's light reaches the cone only if its origin lies in front of the plane the
    // light leaves (light_dir: where the texel's light goes, light_pos: where its surfaces lie,
    // both light-weighted). Hidden once the origin is a quarter of a voxel behind that plane,
    // at every level: a ramp as wide as a quarter of the texel showed a coarse texel's light
    // to cones starting a voxel or two behind a thin wall, and the bounce carried it into the
    // dark room. (The face volumes already hide each voxel's light from cones it goes away
    // from; a test of the texel's mean light direction against the cone's hid part of every
    // surface's light in a texel that holds several, such as a room's corner.)
    // Light from open backs (light_pos.w, its share of the weight) goes against g from the
    // same plane: seen only from behind it. How much of the sample is the back's is estimated
    // from the texel's one direction, as the face volumes showed each side to this cone.
    if (from_origin) {
        vec4 going = textureLod(light_dir, uvw, level);
        if (going.w > 0.0) {
            vec3 g = going.xyz / going.w;
            vec4 lies = textureLod(light_pos, uvw, level) / going.w;
#if CONE_THIN_WALLS
            s.rgb *= 1.0 - thin_wall_between(uvw, level, from, lies.xyz);
#endif
            float ahead = dot(from - lies.xyz, g) * float(4 * grid_n());
            float shown = clamp(1.0 + ahead, 0.0, 1.0);
            if (lies.w > 0.0) {
                float front = (1.0 - lies.w) * seen_along(g, dir);
                float back = lies.w * seen_along(-g, dir);
                shown = (front * shown + back * clamp(1.0 - ahead, 0.0, 1.0))
                      / max(front + back, 1e-6);
            }
            s.rgb *= shown;
        }
    }
#endif
    return s;
}

// The directional volumes at `uvw` as a cone along `dir` sees them, wherever it comes from (the
// debug views).
vec4 sample_directional(vec3 uvw, vec3 dir, float level) {
    return sample_directional(uvw, dir, level, uvw, false);
}

#ifndef PAPER
// The level a cone of world diameter `diameter` samples: 0 is the full-resolution volume, L >= 1
// level L - 1 of the directional volumes (texels of 2^L voxels). Level 0 of the directional
// volumes has texels of two voxels. A trilinear sample reaches a texel beyond its own, so at the
// cone's matched level it would always touch the surface the cone leaves: sample
// frame.tuning.x levels finer.
float cone_level(float diameter) {
    float vs = voxel_size();
    return max(log2(max(diameter, vs) / vs) - frame.tuning.x, 0.0);
}
#endif

#if CONE_FULL_RES && !defined(PAPER)
// The full-resolution voxels around `uvw`, trilinearly weighted, each seen only from the side
// its light goes to and only from in front of the plane it leaves (as sample_directional's
// texels): filtered by hand, since the test is per voxel.
vec4 full_res_seen(vec3 uvw, vec3 dir, vec3 from) {
    int n = grid_n();
    vec3 q = uvw * float(n) - 0.5;
    ivec3 base = ivec3(floor(q));
    vec3 f = q - vec3(base);
    vec4 sum = vec4(0.0);
    for (int k = 0; k < 8; k++) {
        ivec3 o = ivec3(k & 1, (k >> 1) & 1, (k >> 2) & 1);
        ivec3 c = base + o;
        if (any(lessThan(c, ivec3(0))) || any(greaterThanEqual(c, ivec3(n)))) continue;
        vec3 wk = mix(1.0 - f, f, vec3(o));
        vec4 v = texelFetch(radiance_tex, c, 0);
        vec4 e = texelFetch(emit_dir_tex, c, 0);
        vec3 g = e.xyz;
        // The voxel's surface: e.w voxels from its centre along where its light goes.
        vec3 lies = (vec3(c) + 0.5 + (dot(g, g) > 0.0 ? e.w * normalize(g) : vec3(0.0))) / float(n);
        // Hidden once the origin is 1/64 of a voxel behind the surface's plane: two steps of
        // the stored offset (RGBA8 snorm). A quarter of a voxel let the shaded side of a thin
        // panel see its lit side at its foot, more with each bounce.
        float ahead = dot(from - lies, g) * float(64 * n);
        float shown = seen_from(g, -dir) * clamp(1.0 + ahead, 0.0, 1.0);
        vec3 light = v.rgb * shown;
        // An open back's light, from behind the plane (read only where it can show: most
        // samples lie well in front of the planes they read).
        if (ahead < 1.0 && v.a > 0.0 && (frame.grid_info.w & FLAG_BACKS) != 0u) {
            float back = seen_from(-g, -dir) * clamp(1.0 - ahead, 0.0, 1.0);
            if (back > 0.0) light += texelFetch(back_radiance_tex, c, 0).rgb * back;
        }
        sum += wk.x * wk.y * wk.z * vec4(light, v.a);
    }
    return sum;
}
#endif

// What a cone of world diameter `diameter` sees at grid coordinates `uvw`.
vec4 sample_cone(vec3 uvw, vec3 dir, float diameter, vec3 from) {
    float vs = voxel_size();
#ifdef PAPER
    // The original's "voxelWorldSize" is two voxels, and it subtracts one more level.
    float lod = log2(diameter / (2.0 * vs));
    vec4 s = sample_directional(uvw, dir, max(lod - 1.0, 0.0), from, true);
#if CONE_FULL_RES
    if (lod < 1.0) s = mix(textureLod(radiance_tex, uvw, 0.0), s, clamp(lod, 0.0, 1.0));
#endif
#else
    float level = cone_level(diameter);
#if CONE_FULL_RES
    // Level 0 is the full-resolution voxels alone: the directional volumes would weigh 0.
    if (level == 0.0) return full_res_seen(uvw, dir, from);
#endif
    vec4 s = sample_directional(uvw, dir, max(level - 1.0, 0.0), from, true);
#if CONE_FULL_RES
    if (level < 1.0) s = mix(full_res_seen(uvw, dir, from), s, level);
#endif
#endif
    return s;
}

#ifndef PAPER
// How far from `uvw` (grid units) every voxel is empty, in world units, along the farthest
// axis: to the edge of the box of cells within d - 1 of its own, d being its cell's distance
// to the nearest filled one. 0 in a filled cell or outside the grid.
float empty_reach(vec3 uvw) {
    float c = frame.tuning.w;
    vec3 v = uvw * float(grid_n());
    ivec3 cell = ivec3(floor(v / c));
    if (any(lessThan(cell, ivec3(0))) || any(greaterThanEqual(cell, imageSize(empty_space)))) return 0.0;
    float d = float(imageLoad(empty_space, cell).r);
    if (d == 0.0) return 0.0;
    vec3 r = min(v - (vec3(cell) - (d - 1.0)) * c, (vec3(cell) + d) * c - v);
    return min(r.x, min(r.y, r.z)) * voxel_size();
}

// How far from a sample of a cone of world diameter `diameter` the texels it reads reach: the
// sampler's eight texels around it, of the coarser of the two levels it blends (full
// resolution: the eight voxels filtered by hand), each reaching half a texel beyond its centre.
float sample_reach(float diameter) {
    float level = cone_level(diameter);
    return 1.5 * voxel_size() * exp2(ceil(level));
}
#endif

struct Cone {
    vec3 radiance;   // premultiplied, composited front to back
    float opacity;
    float occlusion; // the paper's ambient-occlusion accumulation
};

// Traces from `origin` (already moved off the surface) along unit `dir`; `tan_half` is the tangent
// of the cone's half angle; `t0` the first sample's distance; stops at `max_dist` or when opaque.
// Default: the cone is at least `min_diameter` voxels wide (1, or the specular cone's floor).
Cone trace_cone(vec3 origin, vec3 dir, float tan_half, float t0, float max_dist, float min_diameter) {
    Cone cone = Cone(vec3(0.0), 0.0, 0.0);
    float vs = voxel_size();
    float t = t0;
    vec3 from = world_to_grid(origin);
#ifndef PAPER
    // Looked up only after a sample that read nothing: within a room most samples read
    // something, and their steps need not pay for the lookup.
    bool was_empty = (frame.grid_info.w & FLAG_EMPTY_SPACE) != 0u;
#endif
#ifdef PAPER
    const float opaque = 1.0;   // the original's
#else
    const float opaque = 0.99;
#endif
    for (int i = 0; i < 1024 && t < max_dist && cone.opacity < opaque; i++) {
        vec3 uvw = world_to_grid(origin + dir * t);
#ifdef PAPER
        // No test against the grid: the original marches to its maximum distance, reading the
        // edge texels beyond the grid (the volumes' sampler clamps to the edge under --paper).
        float diameter = 2.0 * tan_half * t;
#else
        float diameter = max(2.0 * tan_half * t, min_diameter * vs);
        // A sample reads about a cone diameter around it, so the surfaces at the grid's edge
        // are read in full only by samples up to that far beyond it (where the volumes are
        // transparent): stopping at the edge let cones leave a closed room through its walls
        // before they were opaque.
        float margin = diameter / frame.grid.w;
        if (any(lessThan(uvw, vec3(-margin))) || any(greaterThan(uvw, vec3(1.0 + margin)))) break;
#endif
#ifndef PAPER
        // Empty space: the samples up to where the cone's footprint could touch a filled voxel
        // read nothing (they would add no light and no opacity); jump there. The footprint
        // widens as the cone goes, so the jump is taken again with the reach it has at its end.
        float empty = was_empty ? empty_reach(uvw) : 0.0;
        if (empty > 0.0) {
            float axis = max(abs(dir.x), max(abs(dir.y), abs(dir.z)));
            float jump = (empty - sample_reach(diameter)) / axis;
            float wider = max(2.0 * tan_half * (t + jump), min_diameter * vs);
            jump = (empty - sample_reach(wider)) / axis;
            if (jump > max(diameter * frame.cone.y, 0.1 * vs)) {
                t += jump;
                continue;
            }
        }
#endif
        vec4 s = sample_cone(uvw, dir, diameter, from);
#ifndef PAPER
        was_empty = s.a == 0.0 && (frame.grid_info.w & FLAG_EMPTY_SPACE) != 0u;
#endif
        float step_len = max(diameter * frame.cone.y, 0.1 * vs);
#ifdef PAPER
        cone.radiance += (1.0 - cone.opacity) * s.rgb;
        cone.opacity += (1.0 - cone.opacity) * s.a;
        cone.occlusion += (1.0 - cone.occlusion) * s.a / (1.0 + frame.trace.y * diameter);
#else
        // A sample's opacity is that of one texel of the level it is read from, and a step
        // crosses step / texel of them: without that a step shorter than the texel counts the
        // same voxels twice (a bright voxel beside the cone's start most of all) and a longer
        // one skips occlusion. The samples are added up until the cone is opaque rather than
        // composited "over" one another: a thin opaque surface read by two samples as f and
        // 1 - f of it then blocks all that lies behind it, where "over" lets f (1 - f) through
        // (a sixth on average: closed rooms lost that much light, and walls leaked it). The
        // sample that fills the cone counts only for the opacity it lacked.
        float texel = vs * exp2(CONE_FULL_RES != 0 ? cone_level(diameter)
                                                   : max(cone_level(diameter), 1.0));
        float a = clamp(s.a, 0.0, 1.0);
        float k = a > 0.0 ? min(step_len / texel, (1.0 - cone.opacity) / a) : 0.0;
        cone.radiance += k * s.rgb;
        cone.opacity = min(cone.opacity + k * a, 1.0);
        cone.occlusion += (1.0 - cone.occlusion) * min(k * a, 1.0) / (1.0 + frame.trace.y * diameter);
#endif
        t += step_len;
    }
    cone.radiance /= frame.tuning.y;  // the volumes' radiance scale
#ifndef PAPER
    // Left the grid (the scene) before it was opaque: the environment, over the cone's
    // aperture, for the part of the cone still open.
    if (has_environment() && cone.opacity < 1.0) {
        vec3 end = world_to_grid(origin + dir * t);
        if (any(lessThan(end, vec3(0.0))) || any(greaterThan(end, vec3(1.0)))) {
            cone.radiance += (1.0 - cone.opacity) * environment_radiance(dir, tan_half);
        }
    }
#endif
    return cone;
}

#ifdef PAPER
// The original's TraceShadowCone: from the surface point `p` two voxels towards the light
// (along `l`, not the normal), its first sample two voxels further; aperture 0.03; each
// sample's opacity scaled by k = 2^(7 x coneShadowTolerance) = 1.62 (tolerance 0.1); to
// `max_dist`; the light's visibility, 1 - the accumulated occlusion, at least 0.
float paper_shadow_cone(vec3 p, vec3 l, float max_dist) {
    float vs2 = 2.0 * voxel_size();
    vec3 start = p + l * vs2;
    const float k = exp2(7.0 * 0.1);
    float occluded = 0.0;
    float t = vs2;
    for (int i = 0; i < 1024 && occluded < 1.0 && t <= max_dist; i++) {
        float diameter = 2.0 * 0.03 * t;
        vec3 uvw = world_to_grid(start + l * t);
        occluded += (1.0 - occluded) * sample_cone(uvw, l, diameter, uvw).a * k;
        t += diameter * frame.cone.y;
    }
    return max(0.0, 1.0 - occluded);
}
#endif

Cone trace_cone(vec3 origin, vec3 dir, float tan_half, float t0, float max_dist) {
    return trace_cone(origin, dir, tan_half, t0, max_dist, 1.0);
}

// The specular cone along `dir`: no narrower than frame.tuning.z voxels (a voxel's reflection
// is no sharper than the texels the cone reads).
Cone trace_specular_cone(vec3 origin, vec3 dir, float tan_half, float t0) {
    return trace_cone(origin, dir, tan_half, t0, frame.cone.z * frame.grid.w, frame.tuning.z);
}

// An orthonormal frame around n (z = n).
mat3 tangent_frame(vec3 n) {
#ifdef PAPER
    // The original's guide vector, (0,1,0), or (0,0,1) when n is exactly along it (a normal a
    // hair off the vertical takes its tangents from the hair, as in the original).
    vec3 guide = abs(dot(n, vec3(0.0, 1.0, 0.0))) == 1.0 ? vec3(0.0, 0.0, 1.0) : vec3(0.0, 1.0, 0.0);
    vec3 t = normalize(cross(guide, n));
#else
    // Branchless basis (Duff et al. 2017): no division by a vanishing cross product. Its seam
    // (where the tangent jumps) lies where the normal's third coordinate changes sign; taken in
    // world axes that is every floor and every wall facing x, and a turn by a micro-radian would
    // flip their cones' azimuths. So the basis is built in a skewed frame whose third axis k
    // is far from orthogonal to axis-aligned and 45-degree normals (|n.k| >= 0.19).
    const vec3 k = vec3(0.2672612, 0.5345225, 0.8017837);  // normalize(1, 2, 3)
    const vec3 u = vec3(-0.8944272, 0.4472136, 0.0);       // normalize(cross(z, k))
    const vec3 v = vec3(-0.3585686, -0.7171372, 0.5976143); // cross(k, u)
    vec3 m = vec3(dot(n, u), dot(n, v), dot(n, k));
    float s = m.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (s + m.z);
    float b = m.x * m.y * a;
    vec3 tm = vec3(1.0 + s * m.x * m.x * a, s * b, -s * m.x);
    vec3 t = tm.x * u + tm.y * v + tm.z * k;
#endif
    return mat3(t, cross(n, t), n);
}

// Where a pixel's cones start: off the surface at p (shading normal n, geometric normal geo),
// and the first sample's distance from there.
vec3 cone_start(vec3 p, vec3 n, vec3 geo, out float t0) {
    float vs = voxel_size();
#ifdef PAPER
    t0 = 2.0 * vs;
    return p + n * 2.0 * vs;
#else
    t0 = vs;
    return p + geo * frame.trace.x * vs;
#endif
}

// What some of a pixel's diffuse cones gather: the cosine-weighted radiance (the irradiance,
// once every cone is in), the occlusion, and the cones' weight (pi for the whole set).
struct Gather {
    vec3 irradiance;
    float occlusion;
    float weight;
};

// The diffuse cones first, first + stride, ... of the set, around the normal frame `frame_n`.
Gather diffuse_cones(vec3 origin, mat3 frame_n, float t0, uint first, uint stride) {
    Gather g = Gather(vec3(0.0), 0.0, 0.0);
    float max_dist = frame.cone.z * frame.grid.w;
    for (uint i = first; i < frame.grid_info.z; i += stride) {
        vec3 d = normalize(frame_n * frame.cones[i].xyz);
        Cone c = trace_cone(origin, d, frame.cone.x, t0, max_dist);
        g.irradiance += frame.cones[i].w * c.radiance;
        g.occlusion += frame.cones[i].w * c.occlusion;
        g.weight += frame.cones[i].w;
    }
    return g;
}

// The reduced-resolution trace traces the specular cone per block too where it is at least this
// wide (tangent of its half angle; 11 degrees across, roughness above about 0.28), and a pixel
// takes a block's only where the block's reflection is within SPECULAR_TURN of the cone's half
// angle of its own: the cone then sees nearly the same blur of the scene. Narrower cones
// would seldom be shared: a block pixel's reflection turns with the view and the normal.
const float SHARED_SPECULAR = 0.1;
const float SPECULAR_TURN = 0.25;

// The whole set's weight.
float cone_set_weight() {
    float w = 0.0;
    for (uint i = 0u; i < frame.grid_info.z; i++) w += frame.cones[i].w;
    return w;
}

#endif
