// What the voxels between a point and an area light's polygons show of them (the voxels'
// lighting, inject_radiance.comp, and the pixels' where an emitter's centre is hidden by what it
// rests on, deferred_lighting.comp). Include after voxel_data.glsl and area_lights.glsl.
#ifndef AREA_LIGHT_VOXELS_GLSL
#define AREA_LIGHT_VOXELS_GLSL

// 1 when no point of the segment a to b, sampled a voxel apart, lies in a filled voxel; else 0.
float segment_open(vec3 a, vec3 b) {
    float vs = voxel_size();
    vec3 d = b - a;
    int steps = int(length(d) / vs);
    for (int i = 1; i < steps; i++) {
        ivec3 c = ivec3(floor(world_to_grid(a + d * (float(i) / float(steps))) * float(grid_n())));
        if (in_grid(c) && voxel_filled(c)) return 0.0;
    }
    return 1.0;
}

// How much of an area light's polygon the point `from` sees through the voxels: the segments to
// five points on it (its centre and halfway to four of its corners; a sphere's the same on the
// disc it shows `from`), each ending a voxel and a half in front of the polygon so that its
// own voxels do not count.
float polygon_seen(AreaPolygon poly, vec3 from) {
    float vs = voxel_size();
    Outline o = area_outline(poly, from);
    vec3 centre = o.centre;
    vec3 out_dir = poly.plane.xyz * area_side(poly, from);
    if (o.sphere) {
        vec4 s = area_vertices[poly.range.x];
        out_dir = normalize(from - s.xyz);
        centre = s.xyz + out_dir * s.w;
    } else {
        for (uint k = 0u; k < o.count; k++) centre += outline_corner(o, k);
        centre /= float(o.count);
    }
    vec3 lift = out_dir * 1.5 * vs;
    float open = segment_open(from, centre + lift);
    for (uint i = 0u; i < 4u; i++) {
        uint k = o.sphere ? 2u * i : i * o.count / 4u;
        vec3 corner = o.sphere ? centre + (outline_corner(o, k) - o.centre) : outline_corner(o, k);
        open += segment_open(from, mix(centre, corner, 0.5) + lift);
    }
    return open / 5.0;
}

#endif
