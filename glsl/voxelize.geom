#version 450
// variants: PAPER
// Voxelization, step 1 of the paper: conservative rasterization in the geometry shader
// (Hasselgren et al., GPU Gems 2 ch. 42). Each triangle is projected along the axis where its
// area is largest, its edges are pushed out by half a voxel so that every voxel it touches gets a
// fragment, and the fragment shader trims the over-grown corners with the triangle's bounding box.
#include "common.glsl"
#include "voxel_common.glsl"

layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;

layout(location = 0) in vec3 v_world[];
layout(location = 1) in vec3 v_normal[];
layout(location = 2) in vec2 v_uv[];

layout(location = 0) out vec3 g_normal;
layout(location = 1) out vec2 g_uv;
layout(location = 2) flat out vec4 g_aabb;      // pixel-space bounds grown by half a voxel
layout(location = 3) flat out vec4 g_plane;     // depth = x * px + y * py + z (voxel units)
#ifndef PAPER
layout(location = 4) flat out vec2 g_depth;     // the triangle's depth range
#endif
layout(location = 5) flat out int g_axis;      // 0: project along X, 1: Y, 2: Z
#ifndef PAPER
layout(location = 6) flat out vec4 g_tri01;     // the projected triangle's corners (voxel units)
layout(location = 7) flat out vec2 g_tri2;
#endif

// (u, v, depth) for a projection along `axis`, in voxel units.
vec3 swizzle(vec3 p, int axis) {
    return axis == 0 ? p.yzx : (axis == 1 ? p.zxy : p.xyz);
}

void main() {
    float n = float(grid_n());
    vec3 p[3];
    for (int i = 0; i < 3; i++) p[i] = world_to_grid(v_world[i]) * n;
    vec3 fn = abs(cross(p[1] - p[0], p[2] - p[0]));
    // Dominant axis. The original sends every tie to Z; the default sends an X = Y > Z tie to Y.
#ifdef PAPER
    int axis = (fn.x > fn.y && fn.x > fn.z) ? 0 : ((fn.y > fn.x && fn.y > fn.z) ? 1 : 2);
#else
    int axis = (fn.x > fn.y && fn.x > fn.z) ? 0 : (fn.y > fn.z ? 1 : 2);
#endif

    vec3 q[3];
    int order[3] = int[3](0, 1, 2);
    for (int i = 0; i < 3; i++) q[i] = swizzle(p[i], axis);
    vec2 e1 = q[1].xy - q[0].xy, e2 = q[2].xy - q[0].xy;
    float area = e1.x * e2.y - e1.y * e2.x;
    if (area == 0.0) return;  // degenerate in its best projection: no area at all
    if (area < 0.0) {
        // Counter-clockwise in the projection, so "outward" is the same for every edge.
        vec3 t = q[1]; q[1] = q[2]; q[2] = t;
        order[1] = 2; order[2] = 1;
    }

    // Depth as a plane over the projection: depth = a * x + b * y + c.
    vec3 pn = cross(q[1] - q[0], q[2] - q[0]);
    vec3 plane = vec3(-pn.x / pn.z, -pn.y / pn.z, 0.0);
    plane.z = q[0].z - plane.x * q[0].x - plane.y * q[0].y;

    // Edge lines in homogeneous 2D, interior positive, pushed out by half a voxel
    // (the L-infinity distance that reaches the corner of a touched voxel).
    vec3 edge[3];
    for (int i = 0; i < 3; i++) {
        vec3 a = vec3(q[i].xy, 1.0), b = vec3(q[(i + 1) % 3].xy, 1.0);
        edge[i] = cross(a, b);
        edge[i].z += 0.5 * (abs(edge[i].x) + abs(edge[i].y));
    }

    vec2 lo = min(min(q[0].xy, q[1].xy), q[2].xy) - 0.5;
    vec2 hi = max(max(q[0].xy, q[1].xy), q[2].xy) + 0.5;
    float dlo = min(min(q[0].z, q[1].z), q[2].z);
    float dhi = max(max(q[0].z, q[1].z), q[2].z);

    for (int i = 0; i < 3; i++) {
        // The grown vertex i is where the grown edges (i-1) and i meet.
        vec3 h = cross(edge[(i + 2) % 3], edge[i]);
        vec2 v = abs(h.z) > 1e-12 ? h.xy / h.z : q[i].xy;
        // Attributes extrapolated with the barycentrics of the grown vertex.
        vec2 d1 = q[1].xy - q[0].xy, d2 = q[2].xy - q[0].xy, dv = v - q[0].xy;
        float den = d1.x * d2.y - d1.y * d2.x;
        float b1 = (dv.x * d2.y - dv.y * d2.x) / den;
        float b2 = (d1.x * dv.y - d1.y * dv.x) / den;
        float b0 = 1.0 - b1 - b2;
        int i0 = order[0], i1 = order[1], i2 = order[2];
#ifdef PAPER
        // The original keeps each vertex's own attributes on its grown corner. --paper-slips:
        // its winding flip swaps two corners' texture coordinates but not their normals.
        bool slips = (frame.grid_info.w & FLAG_PAPER_SLIPS) != 0u;
        g_normal = v_normal[slips ? i : order[i]];
        g_uv = v_uv[order[i]];
#else
        g_normal = b0 * v_normal[i0] + b1 * v_normal[i1] + b2 * v_normal[i2];
        g_uv = b0 * v_uv[i0] + b1 * v_uv[i1] + b2 * v_uv[i2];
        // A sliver's grown corners lie far out along its nearly parallel edges, where the
        // extrapolated attributes grow without bound (texture coordinates of 1e30 and more,
        // which cost lavapipe minutes a draw): past 16 triangle-heights out, the corner keeps
        // its own vertex's attributes, as the original's always do.
        if (!(max(max(abs(b0), abs(b1)), abs(b2)) <= 16.0)) {
            g_normal = v_normal[order[i]];
            g_uv = v_uv[order[i]];
        }
#endif
        g_aabb = vec4(lo, hi);
        g_plane = vec4(plane, 0.0);
#ifndef PAPER
        g_depth = vec2(dlo, dhi);
#endif
        g_axis = axis;
#ifndef PAPER
        g_tri01 = vec4(q[0].xy, q[1].xy);
        g_tri2 = q[2].xy;
#endif
        gl_Position = vec4(v / n * 2.0 - 1.0, 0.5, 1.0);
        EmitVertex();
    }
    EndPrimitive();
}
