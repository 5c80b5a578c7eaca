// Emissive surfaces as area lights (src/render/area_lights.rs): the light a polygon of uniform
// radiance Le sends a point, integrated exactly. Lambert's formula gives the irradiance as a
// sum over the polygon's edges (seen from the point, each edge's arc angle times its great
// circle's normal); clipped to the surface's horizon it is exact for the diffuse lobe.
// Linearly transformed cosines (Heitz et al. 2016) turn the specular lobe into a clamped cosine
// by a 3x3 matrix fitted per roughness and view angle (src/render/ltc.rs): the same formula on
// the polygon's transformed corners integrates the lobe.
#ifndef AREA_LIGHTS_GLSL
#define AREA_LIGHTS_GLSL

const uint AREA_POLYGON = 0u;
const uint AREA_SPHERE = 1u;
// The sides of the polygon a sphere's disc is drawn as (area_lights.rs: SPHERE_SIDES; the
// corners below are its eighths of a turn).
const uint SPHERE_SIDES = 8u;

struct AreaPolygon {
    vec4 plane;    // xyz the front normal (unit), w its dot with the polygon's points
    uvec4 range;   // x first vertex, y vertex count, z kind (AREA_POLYGON, AREA_SPHERE)
};
// Uniform blocks of a fixed size: every pixel reads the same entries, and uniform loads are what
// a GPU (and lavapipe) broadcasts cheaply. At most this many corners and polygons
// (area_lights.rs: MAX_AREA_LIGHTS x MAX_EDGES).
const uint MAX_AREA_CORNERS = 512u;
layout(set = 0, binding = 5, std140) uniform AreaPolygons { AreaPolygon area_polygons[MAX_AREA_CORNERS]; };
// Polygon corners counter-clockwise seen from the front (xyz); a sphere's centre and radius.
layout(set = 0, binding = 6, std140) uniform AreaVertices { vec4 area_vertices[MAX_AREA_CORNERS]; };
// A light's polygons' edges, each once (gpu.rs: GpuAreaEdge), its corners named by the first
// index of their position.
const uint NO_POLYGON = 0xffffffffu;
struct AreaEdge {
    uint a;       // corners
    uint b;
    uint left;    // the polygon it runs a to b in
    uint right;   // the one it runs b to a in (NO_POLYGON: none)
};
layout(set = 0, binding = 9, std140) uniform AreaEdges { AreaEdge area_edges[MAX_AREA_CORNERS]; };

// The LTC table (src/render/ltc.rs): per roughness (rows) and sqrt(1 - n.v) (within a row), on a
// square grid whose first and last cells sit at 0 and 1, two vec4s: the inverse matrix's
// entries a, b, c, d (M^-1 = [[a 0 b] [0 1 0] [c 0 d]]), then the lobe's directional albedo
// with Fresnel 1 and its Schlick part.
layout(set = 0, binding = 7, std430) readonly buffer LtcTable { vec4 ltc_table[]; };

struct Ltc {
    mat3 inverse;   // from the shading frame (area_frame) to the clamped cosine's
    float albedo;   // integral of D V cos over the sphere
    float schlick;  // integral of D V cos (1 - v.h)^5
};

Ltc ltc_lookup(float roughness, float n_dot_v) {
    int size = int(sqrt(float(ltc_table.length() / 2)) + 0.5);
    // x: the view angle (the table's fastest index), y: roughness.
    vec2 uv = vec2(sqrt(1.0 - clamp(n_dot_v, 0.0, 1.0)), clamp(roughness, 0.0, 1.0));
    uv *= float(size - 1);
    ivec2 i = min(ivec2(uv), ivec2(size - 2));
    vec2 f = uv - vec2(i);
    vec4 m = vec4(0.0);
    vec4 e = vec4(0.0);
    for (int k = 0; k < 4; k++) {
        ivec2 c = i + ivec2(k & 1, k >> 1);
        float w = ((k & 1) == 1 ? f.x : 1.0 - f.x) * ((k >> 1) == 1 ? f.y : 1.0 - f.y);
        int cell = c.x + size * c.y;
        m += w * ltc_table[2 * cell];
        e += w * ltc_table[2 * cell + 1];
    }
    // Columns of [[a 0 b] [0 1 0] [c 0 d]].
    mat3 inverse = mat3(vec3(m.x, 0.0, m.z), vec3(0.0, 1.0, 0.0), vec3(m.y, 0.0, m.w));
    return Ltc(inverse, e.x, e.y);
}

// A polygon as p sees it. A sphere shows p the disc across it of the same solid angle: a
// regular polygon of SPHERE_SIDES sides with the disc's area, facing p.
struct Outline {
    uint first;    // first corner (polygons)
    uint count;
    bool sphere;
    vec3 centre;   // sphere: the disc's centre and its two axes (radius included)
    vec3 u;
    vec3 t;
};

Outline area_outline(AreaPolygon poly, vec3 p) {
    Outline o;
    o.first = poly.range.x;
    o.sphere = poly.range.z == AREA_SPHERE;
    o.count = o.sphere ? SPHERE_SIDES : poly.range.y;
    o.centre = vec3(0.0);
    o.u = vec3(0.0);
    o.t = vec3(0.0);
    if (o.sphere) {
        vec4 v = area_vertices[poly.range.x];
        vec3 d = v.xyz - p;
        float len = length(d);
        float dist = max(len, v.w * 1.0001);
        vec3 w = d / max(len, 1e-30);
        // The cone's half angle asin(r / dist); the disc through the centre that fills it. A
        // regular polygon has sides / (2 pi) sin(2 pi / sides) of its circle's area.
        const float ANGLE = 2.0 * PI / float(SPHERE_SIDES);
        float r = v.w * dist / sqrt(dist * dist - v.w * v.w) * sqrt(ANGLE / sin(ANGLE));
        vec3 u = normalize(cross(w, abs(w.y) < 0.99 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0)));
        o.centre = v.xyz;
        o.u = r * u;
        o.t = r * cross(w, u);
    }
    return o;
}

// Corner k (world), counter-clockwise seen from the front (a sphere's disc faces p).
vec3 outline_corner(Outline o, uint k) {
    if (!o.sphere) return area_vertices[o.first + k].xyz;
    // cos and sin of k eighths of a turn.
    const float H = 0.70710678;
    const vec2 TURN[8] = vec2[8](vec2(1.0, 0.0), vec2(H, H), vec2(0.0, 1.0), vec2(-H, H),
                                 vec2(-1.0, 0.0), vec2(-H, -H), vec2(0.0, -1.0), vec2(H, -H));
    vec2 c = TURN[k];
    return o.centre + c.x * o.u - c.y * o.t;
}

// Which side of the polygon p is on: +1 in front, -1 behind, 0 in its plane. A sphere's disc
// always faces p.
float area_side(AreaPolygon poly, vec3 p) {
    if (poly.range.z == AREA_SPHERE) return 1.0;
    float s = dot(poly.plane.xyz, p) - poly.plane.w;
    return s > 0.0 ? 1.0 : (s < 0.0 ? -1.0 : 0.0);
}

// One edge's term of Lambert's formula: the arc angle between a and b (any length) times the
// unit normal of their great circle, as a vector (atan2 keeps it accurate for short edges).
vec3 edge_term(vec3 a, vec3 b) {
    vec3 c = cross(a, b);
    float s = length(c);
    return s > 0.0 ? c * (atan(s, dot(a, b)) / s) : vec3(0.0);
}

// The z term of edge_term for two points on the horizon z = 0: the signed angle between them.
float horizon_arc(vec3 a, vec3 b) {
    float s = a.x * b.y - a.y * b.x;
    return s != 0.0 ? atan(s, a.x * b.x + a.y * b.y) : 0.0;
}

// Lambert's sum clipped to the horizon z >= 0 of a lobe's frame, built an edge at a time as the
// outline's corners come (relative to the shaded point, in that frame): an edge leaving the
// upper side ends at the horizon, and the horizon's arc to where the outline comes back
// closes it (in any order: arcs along the horizon add up). Written without branches around
// the edge terms: SIMD lanes (and lavapipe) run every branch that any lane takes, so each edge
// costs one edge term and one horizon arc, whichever way it crosses.
struct Clip {
    vec3 first;        // the first corner
    vec3 a;            // the last corner
    float sum;         // edge terms' z so far
    vec3 exit_point;   // where the outline last went under the horizon
    vec3 first_entry;  // where it first came up, if it started under
    bool exited;
    bool entered_first;
};

Clip clip_begin(vec3 first) {
    return Clip(first, first, 0.0, vec3(0.0), vec3(0.0), false, false);
}

// The edge from the last corner to b.
void clip_edge(inout Clip c, vec3 b) {
    vec3 a = c.a;
    bool a_up = a.z >= 0.0;
    bool b_up = b.z >= 0.0;
    bool leaves = a_up && !b_up;
    bool enters = !a_up && b_up;
    // Where it crosses the horizon (a itself when it does not: then unused or an empty edge).
    vec3 x = mix(a, b, leaves || enters ? a.z / (a.z - b.z) : 0.0);
    x.z = 0.0;
    // The part above the horizon; an edge wholly under it is x to x, whose term is 0.
    c.sum += edge_term(a_up ? a : x, b_up ? b : x).z;
    // Coming back up after going under: the horizon's arc from where it went under.
    bool closes = enters && c.exited;
    c.sum += closes ? horizon_arc(c.exit_point, x) : 0.0;
    c.first_entry = enters && !c.exited && !c.entered_first ? x : c.first_entry;
    c.entered_first = c.entered_first || (enters && !c.exited);
    c.exit_point = leaves ? x : c.exit_point;
    c.exited = leaves || (c.exited && !enters);
    c.a = b;
}

// Closes the outline: minus 2 pi times the clamped-cosine form factor of a polygon whose front
// faces the point.
float clip_end(inout Clip c) {
    clip_edge(c, c.first);
    if (c.exited && c.entered_first) c.sum += horizon_arc(c.exit_point, c.first_entry);
    return c.sum;
}

// The clipped sums of the polygon's corners taken to two lobes' frames at once (each corner
// read and placed once): `local_a` and `local_b` map world offsets from p to them.
vec2 clipped_edge_sums(Outline o, vec3 p, mat3 local_a, mat3 local_b) {
    vec3 d = outline_corner(o, 0u) - p;
    Clip a = clip_begin(local_a * d);
    Clip b = clip_begin(local_b * d);
    for (uint k = 1u; k < o.count; k++) {
        d = outline_corner(o, k) - p;
        clip_edge(a, local_a * d);
        clip_edge(b, local_b * d);
    }
    return vec2(clip_end(a), clip_end(b));
}

// The shading frame's rows: x the tangent towards v, y the bitangent, z the normal.
mat3 area_frame(vec3 n, vec3 v) {
    vec3 t = v - n * dot(n, v);
    float l = length(t);
    t = l > 1e-6 ? t / l : normalize(cross(n, abs(n.y) < 0.99 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0)));
    vec3 b = cross(n, t);
    return transpose(mat3(t, b, n));
}

// How polygon `index` counts from p: +1 seen from its front, -1 from its back when the light
// is two-sided, else 0.
float polygon_weight(uint index, vec3 p, bool two_sided) {
    if (index == NO_POLYGON) return 0.0;
    float side = area_side(area_polygons[index], p);
    return side < 0.0 && !two_sided ? 0.0 : side;
}

// The clipped sums of a light's silhouette, the loops its edges of nonzero weight make
// (edges `first` to `first + count`, at most 32): false when the weights differ in size (an
// open two-sided mesh), for the sum over polygons to do instead.
bool silhouette_form_factors(uint first, uint count, vec3 p, bool two_sided, mat3 local_a,
                             mat3 local_b, out vec2 sums) {
    sums = vec2(0.0);
    uint live = 0u;   // bit e: edge e is on the silhouette
    uint flip = 0u;   // and runs from its corner b to a
    float size = 0.0;
    bool uniform_size = true;
    for (uint e = 0u; e < count; e++) {
        AreaEdge edge = area_edges[first + e];
        float w = polygon_weight(edge.left, p, two_sided)
                  - polygon_weight(edge.right, p, two_sided);
        if (w == 0.0) continue;
        live |= 1u << e;
        flip |= w < 0.0 ? 1u << e : 0u;
        uniform_size = uniform_size && (size == 0.0 || size == abs(w));
        size = abs(w);
    }
    if (!uniform_size) return false;
    uint left = live;
    // Each pass walks one loop: from an unused edge's start, to the edge that starts where the
    // last one ended, until back at the start.
    for (uint loop = 0u; loop < 32u && left != 0u; loop++) {
        uint e = uint(findLSB(left));
        left &= ~(1u << e);
        AreaEdge edge = area_edges[first + e];
        bool back = (flip & (1u << e)) != 0u;
        uint start = back ? edge.b : edge.a;
        uint end = back ? edge.a : edge.b;
        vec3 d = area_vertices[start].xyz - p;
        Clip a = clip_begin(local_a * d);
        Clip b = clip_begin(local_b * d);
        for (uint step = 0u; step < 32u && end != start; step++) {
            d = area_vertices[end].xyz - p;
            clip_edge(a, local_a * d);
            clip_edge(b, local_b * d);
            uint next = 32u;
            for (uint m = left; m != 0u; m &= m - 1u) {
                uint k = uint(findLSB(m));
                AreaEdge ek = area_edges[first + k];
                bool kb = (flip & (1u << k)) != 0u;
                if ((kb ? ek.b : ek.a) == end) {
                    next = k;
                    end = kb ? ek.a : ek.b;
                    break;
                }
            }
            if (next == 32u) return false;  // an open chain: not a silhouette after all
            left &= ~(1u << next);
        }
        // Seen from p a front face turns clockwise around the lobe's axis: negative sums.
        sums -= size * vec2(clip_end(a), clip_end(b));
    }
    return true;
}

// The form factors of one area light's polygons from p for two lobes (0 to 1; pi Le times one
// is the irradiance the lobe gathers), with `local_a` and `local_b` the maps from world
// offsets to the frames whose z are the lobes' axes (area_frame for the diffuse lobe, the
// LTC's inverse matrix times it for the specular one).
vec2 area_form_factors(Light light, vec3 p, mat3 local_a, mat3 local_b) {
    uint first = uint(light.cone.x);
    uint count = uint(light.cone.y);
    bool two_sided = light.radiance.w > 0.5;
    vec2 f = vec2(0.0);
    // Where polygons share edges (a box's faces), an edge counts by the difference of its two
    // polygons' weights: between two faces seen from the front it cancels, so the sum needs
    // only the outline of the faces in view (a box: four to six edges instead of up to twelve).
    // Those edges are chained into closed loops and clipped as the polygons would be. Only from
    // outside the light's bounding sphere: there the light lies within a hemisphere, so its
    // outline bounds what it covers. From inside a closed light (a furnace) every face is seen
    // from the front, every edge cancels, and the outline would say nothing is covered.
    uint edges = uint(light.direction_range.z);
    vec3 centre = light.position_type.xyz - p;
    float reach = light.direction_range.w;
    if (edges > 0u && edges <= 32u && dot(centre, centre) > reach * reach) {
        vec2 g;
        if (silhouette_form_factors(uint(light.direction_range.y), edges, p, two_sided,
                                    local_a, local_b, g)) {
            return max(g, vec2(0.0)) / (2.0 * PI);
        }
    }
    for (uint i = 0u; i < count; i++) {
        AreaPolygon poly = area_polygons[first + i];
        float side = area_side(poly, p);
        if (side == 0.0 || (side < 0.0 && !two_sided)) continue;
        // A front face turns clockwise around the lobe's axis seen from p: negative sums.
        f += -side * clipped_edge_sums(area_outline(poly, p), p, local_a, local_b);
    }
    return max(f, vec2(0.0)) / (2.0 * PI);
}

// Whether p lies within `reach` of a polygon (inside a sphere's, or within reach of its
// surface).
bool polygon_near(AreaPolygon poly, vec3 p, float reach) {
    if (poly.range.z == AREA_SPHERE) {
        vec4 s = area_vertices[poly.range.x];
        return length(p - s.xyz) < s.w + reach;
    }
    vec3 n = poly.plane.xyz;
    if (abs(dot(n, p) - poly.plane.w) >= reach) return false;
    // Within reach of the outline on its inner side (convex outlines).
    uint m = poly.range.y;
    for (uint k = 0u; k < m; k++) {
        vec3 a = area_vertices[poly.range.x + k].xyz;
        vec3 b = area_vertices[poly.range.x + (k + 1u) % m].xyz;
        vec3 inward = cross(n, b - a);
        if (dot(inward, p - a) < -reach * length(inward)) return false;
    }
    return true;
}

// One polygon's part of area_vector_form_factor.
vec3 polygon_vector(Light light, AreaPolygon poly, vec3 p, float reach) {
    bool two_sided = light.radiance.w > 0.5;
    float side = area_side(poly, p);
    if (side == 0.0 || (side < 0.0 && !two_sided)) return vec3(0.0);
    if (reach > 0.0 && polygon_near(poly, p, reach)) return vec3(0.0);
    Outline o = area_outline(poly, p);
    vec3 first_corner = outline_corner(o, 0u) - p;
    vec3 a = first_corner;
    vec3 sum = vec3(0.0);
    for (uint k = 0u; k < o.count; k++) {
        vec3 b = k + 1u == o.count ? first_corner : outline_corner(o, k + 1u) - p;
        sum += edge_term(a, b);
        a = b;
    }
    return -side * sum / (2.0 * PI);
}

// The vector form factor of the light's polygons (unclipped): for any normal above all of
// them, dot(normal, it) is the form factor; its direction is where the light comes from on
// average. For the voxels' normal-weighted lighting. Polygons within `reach` of p are left
// out: a voxel a polygon passes through is the light itself or what it hides (a ceiling 1 mm
// above a two-sided panel is lit by its back, but only the gap sees that, while the voxel
// would send it down every cone); the other faces of a closed light still light it.
vec3 area_vector_form_factor(Light light, vec3 p, float reach) {
    uint first = uint(light.cone.x);
    uint count = uint(light.cone.y);
    vec3 f = vec3(0.0);
    for (uint i = 0u; i < count; i++) {
        f += polygon_vector(light, area_polygons[first + i], p, reach);
    }
    return f;
}

#ifdef BRDF_GLSL
// What a surface point's area lighting needs from its material and view, the same for every
// area light: the two lobes' frames and their weights.
struct AreaLobes {
    mat3 diffuse_frame;   // world offsets to the diffuse lobe's frame (area_frame)
    mat3 specular_frame;  // and to the specular lobe's clamped cosine (the LTC's inverse)
    vec3 diffuse;         // what each lobe's form factor is weighted by
    vec3 specular;
};

// The diffuse lobe by the exact form factor (its Fresnel as the specular lobe's mean), the
// specular lobe by LTC.
AreaLobes area_lobes(Surface s, vec3 n, vec3 v) {
    mat3 local = area_frame(n, v);
    float n_dot_v = clamp(dot(n, v), 1e-4, 1.0);
    vec3 f0 = mix(min(vec3(0.04) * s.specular_color, vec3(1.0)) * s.specular, s.base_color, s.metallic);
    vec3 f90 = vec3(mix(s.specular, 1.0, s.metallic));
    Ltc ltc = ltc_lookup(s.roughness, n_dot_v);
    vec3 reflectance = f0 * (ltc.albedo - ltc.schlick) + f90 * ltc.schlick;
    vec3 diffuse = (1.0 - s.metallic) * (1.0 - reflectance) * s.base_color;
    return AreaLobes(local, ltc.inverse * local, diffuse, reflectance);
}

// The light an area light sends towards the view from p, unshadowed: both lobes in one walk
// over the outlines (a lobe a surface lacks weighs 0).
vec3 area_light_radiance(Light light, AreaLobes lobes, vec3 p) {
    vec2 f = area_form_factors(light, p, lobes.diffuse_frame, lobes.specular_frame);
    return light.radiance.rgb * (lobes.diffuse * f.x + lobes.specular * f.y);
}
#endif

#endif
