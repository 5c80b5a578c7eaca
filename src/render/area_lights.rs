//! Emissive surfaces as area lights. A voxel shows one radiance to a whole cone, and sixteen
//! cones sample a small bright emitter at a few directions and coarse levels, so an emitter's
//! direct light reached the pixels as streaks and blotches. Here every emissive primitive
//! (the most powerful [`MAX_AREA_LIGHTS`]) is a light of its own shape, whose light the pixels
//! integrate analytically (glsl/area_lights.glsl: Lambert's edge integral for the diffuse lobe,
//! linearly transformed cosines for the specular one), shadowed through a cube of shadow views
//! at its centre (filtered by the light's size). The voxels take it as a light too, so the
//! bounces carry it, and its emission leaves the voxels (the G-buffer still shows it).
//!
//! Shapes: the primitive's triangles grouped by plane into polygons (their outlines: a quad is
//! one polygon of four edges, a box six); a closed mesh whose vertices lie on a sphere is a
//! sphere, which
//! a point sees as the disc of the same solid angle. Any other mesh with more edges stays in
//! the voxels.

use crate::output::luminance;
use crate::scene::{AlphaMode, Material, Scene};
use glam::{Mat4, Vec3};
use std::collections::HashMap;

/// At most this many emitters become area lights (the most powerful); each has six shadow
/// views. The rest stay in the voxels.
pub const MAX_AREA_LIGHTS: usize = 8;
/// Outline edges a light may have (each costs every pixel two edge integrals).
pub const MAX_EDGES: usize = 64;
/// The area lights' corners (and polygons) the shaders' uniform blocks hold
/// (glsl/area_lights.glsl: MAX_AREA_CORNERS).
pub const MAX_AREA_CORNERS: usize = MAX_AREA_LIGHTS * MAX_EDGES;
/// The sides of the polygon a sphere's disc is drawn as (glsl/area_lights.glsl).
pub const SPHERE_SIDES: usize = 8;

/// A light's shape, in object space or placed in the world.
#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// Planar outlines, counter-clockwise seen from the front, with their front normals.
    Polygons(Vec<Polygon>),
    Sphere {
        centre: Vec3,
        radius: f32,
    },
}

impl Shape {
    /// Whether it encloses a volume: a sphere, or polygons whose every edge another polygon
    /// runs the other way (a box). A closed emitter's faces hide their own backs, so a
    /// double-sided one lights the world from its outside alone: summed from both sides, a
    /// point outside it took the light of its silhouette twice, once through its near faces'
    /// fronts and once through its far faces' backs.
    pub fn closed(&self) -> bool {
        let Shape::Polygons(polys) = self else {
            return true;
        };
        let key = |v: Vec3| v.to_array().map(f32::to_bits);
        let mut unpaired: HashMap<([u32; 3], [u32; 3]), i32> = HashMap::new();
        for p in polys {
            let n = p.vertices.len();
            for k in 0..n {
                let (a, b) = (key(p.vertices[k]), key(p.vertices[(k + 1) % n]));
                // +1 for a to b, -1 for its twin b to a: a closed outline sums to 0 per edge.
                let (lo, hi, sign) = if a < b { (a, b, 1) } else { (b, a, -1) };
                *unpaired.entry((lo, hi)).or_insert(0) += sign;
            }
        }
        !polys.is_empty() && unpaired.values().all(|&c| c == 0)
    }

    /// The same, its polygons turned to face out where they enclose a volume facing in (the
    /// divergence theorem: the volume their fronts bound is negative).
    fn facing_out(self) -> Shape {
        let Shape::Polygons(polys) = &self else {
            return self;
        };
        let o = polys[0].vertices[0];
        let volume: f32 = polys
            .iter()
            .map(|p| p.area() * p.normal.dot(p.vertices[0] - o))
            .sum();
        if volume >= 0.0 {
            return self;
        }
        Shape::Polygons(
            polys
                .iter()
                .map(|p| Polygon {
                    vertices: p.vertices.iter().rev().copied().collect(),
                    normal: -p.normal,
                })
                .collect(),
        )
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Polygon {
    pub vertices: Vec<Vec3>,
    /// Unit, towards the front (the side the winding faces).
    pub normal: Vec3,
}

impl Polygon {
    fn area(&self) -> f32 {
        // About the first corner: far from the origin the cross products would cancel.
        let v = &self.vertices;
        let mut sum = Vec3::ZERO;
        for i in 1..v.len().saturating_sub(1) {
            sum += (v[i] - v[0]).cross(v[i + 1] - v[0]);
        }
        0.5 * sum.dot(self.normal).abs()
    }
}

/// One emissive primitive instance as a light.
#[derive(Clone, Debug)]
pub struct AreaLight {
    /// The instance whose primitive emits (left out of its own shadow views and of the
    /// voxels' emission).
    pub instance: usize,
    /// Emitted radiance Le (the emissive texture's mean times the factor where it has one).
    pub emission: Vec3,
    pub two_sided: bool,
    /// The primitive's triangles.
    pub triangles: usize,
    /// Object space.
    local: Shape,
    /// World space (see `place`).
    pub shape: Shape,
    /// Area-weighted centre (world): where its shadow views look from.
    pub position: Vec3,
    /// Distance from the centre to the farthest point of the light.
    pub radius: f32,
    /// Emitting area, m^2.
    pub area: f32,
}

impl AreaLight {
    /// The radius of the disc as large as the light looks on average, for the soft shadows'
    /// penumbra: a flat light's area, a closed one's mean silhouette (a quarter of its area,
    /// Cauchy's formula for convex bodies; a sphere's disc).
    pub fn apparent_radius(&self) -> f32 {
        let seen = match &self.shape {
            Shape::Polygons(p) if p.iter().all(|q| q.normal.dot(p[0].normal) > 0.999) => self.area,
            _ => 0.25 * self.area,
        };
        (seen / std::f32::consts::PI).sqrt()
    }
}

impl AreaLight {
    /// Places the light for the instance's world transform.
    pub fn place(&mut self, world: &Mat4) {
        let flip = world.determinant() < 0.0;
        self.shape = match &self.local {
            Shape::Polygons(polys) => Shape::Polygons(
                polys
                    .iter()
                    .map(|p| {
                        let mut vertices: Vec<Vec3> = p
                            .vertices
                            .iter()
                            .map(|v| world.transform_point3(*v))
                            .collect();
                        // A mirror turns the winding; keep it counter-clockwise from the front.
                        if flip {
                            vertices.reverse();
                        }
                        let normal = newell_normal(&vertices).unwrap_or(p.normal);
                        Polygon { vertices, normal }
                    })
                    .collect(),
            ),
            Shape::Sphere { centre, radius } => {
                // The sphere of the transformed area (a non-uniform scale makes an ellipsoid).
                let s = [world.x_axis, world.y_axis, world.z_axis].map(|a| a.truncate().length());
                let scale = (s[0] * s[1] * s[2]).cbrt();
                Shape::Sphere {
                    centre: world.transform_point3(*centre),
                    radius: radius * scale,
                }
            }
        };
        let (mut area, mut centre) = (0.0f32, Vec3::ZERO);
        match &self.shape {
            Shape::Polygons(polys) => {
                for p in polys {
                    let a = p.area();
                    let mean = p.vertices.iter().sum::<Vec3>() / p.vertices.len() as f32;
                    area += a;
                    centre += a * mean;
                }
                centre = if area > 0.0 {
                    centre / area
                } else {
                    Vec3::ZERO
                };
                self.radius = polys
                    .iter()
                    .flat_map(|p| &p.vertices)
                    .map(|v| (*v - centre).length())
                    .fold(0.0, f32::max);
            }
            Shape::Sphere { centre: c, radius } => {
                area = 4.0 * std::f32::consts::PI * radius * radius;
                centre = *c;
                self.radius = *radius;
            }
        }
        self.position = centre;
        self.area = area;
    }

    /// Total radiated power, W (per channel): pi Le A, twice for a two-sided one.
    pub fn power(&self) -> Vec3 {
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        self.emission * std::f32::consts::PI * self.area * sides
    }

    /// The light as its shadow views see it: a point light at the centre (six views).
    pub fn as_point_light(&self) -> crate::scene::Light {
        crate::scene::Light {
            name: None,
            kind: crate::scene::LightKind::Point,
            radiance: self.emission,
            range: None,
            position: self.position,
            direction: Vec3::NEG_Y,
        }
    }

    /// Edges each pixel integrates (twice: diffuse and specular).
    pub fn edges(&self) -> usize {
        match &self.shape {
            Shape::Polygons(p) => p.iter().map(|p| p.vertices.len()).sum(),
            Shape::Sphere { .. } => SPHERE_SIDES,
        }
    }

    /// What it is, for `voxgi info`.
    pub fn describe(&self) -> String {
        match &self.shape {
            Shape::Polygons(p) => format!("{} polygons", p.len()),
            Shape::Sphere { radius, .. } => format!("sphere r {radius:.4}"),
        }
    }
}

/// The unit normal of a planar loop (Newell's method); None when it has no area.
fn newell_normal(v: &[Vec3]) -> Option<Vec3> {
    let mut n = Vec3::ZERO;
    for i in 0..v.len() {
        n += v[i].cross(v[(i + 1) % v.len()]);
    }
    let l = n.length();
    (l > 0.0 && l.is_finite()).then(|| n / l)
}

/// Le of a material: the factor times its emissive texture's mean (in linear light), which is
/// what the light's whole surface sends on average; the G-buffer still shows the texture.
fn emission(scene: &Scene, m: &Material) -> Vec3 {
    let Some(t) = m
        .emissive_tex
        .and_then(|t| scene.textures.get(t.texture as usize))
    else {
        return m.emissive;
    };
    let texels = t.rgba8.chunks_exact(4);
    let n = texels.len().max(1) as f64;
    let linear = t.linear_table();
    let mut sum = [0.0f64; 3];
    for px in texels {
        for k in 0..3 {
            sum[k] += linear[px[k] as usize] as f64;
        }
    }
    m.emissive * Vec3::new(sum[0] as f32, sum[1] as f32, sum[2] as f32) / n as f32
}

/// The emissive primitive instances that can be area lights (opaque materials), the most
/// powerful [`MAX_AREA_LIGHTS`], in instance order.
pub fn find(scene: &Scene) -> Vec<AreaLight> {
    let mut found = Vec::new();
    for (i, inst) in scene.instances.iter().enumerate() {
        let Some(p) = scene.primitives.get(inst.primitive as usize) else {
            continue;
        };
        let Some(m) = scene.materials.get(p.material as usize) else {
            continue;
        };
        if !m.is_emissive() || m.alpha_mode != AlphaMode::Opaque {
            continue;
        }
        let first = p.first_index as usize;
        let Some(indices) = scene.indices.get(first..first + p.index_count as usize) else {
            continue;
        };
        let position = |v: u32| {
            scene
                .vertices
                .get(v as usize)
                .map(|v| Vec3::from(v.position))
        };
        let triangles: Vec<[Vec3; 3]> = indices
            .chunks_exact(3)
            .filter_map(|t| Some([position(t[0])?, position(t[1])?, position(t[2])?]))
            .filter(|t| t.iter().all(|p| p.is_finite()))
            .collect();
        let Some(local) = shape_of(&triangles) else {
            continue;
        };
        // A closed double-sided emitter lights the world from its outside alone.
        let closed = m.double_sided && local.closed();
        let local = if closed { local.facing_out() } else { local };
        let mut light = AreaLight {
            instance: i,
            emission: emission(scene, m),
            two_sided: m.double_sided && !closed,
            triangles: triangles.len(),
            shape: local.clone(),
            local,
            position: Vec3::ZERO,
            radius: 0.0,
            area: 0.0,
        };
        light.place(&inst.world);
        if light.area > 0.0 && light.power().max_element() > 0.0 {
            found.push(light);
        }
    }
    found.sort_by(|a, b| luminance(b.power()).total_cmp(&luminance(a.power())));
    found.truncate(MAX_AREA_LIGHTS);
    // Instance order, so that the lights' order does not depend on their powers' ties.
    found.sort_by_key(|e| e.instance);
    found
}

/// The shape of a primitive's triangles (object space), or None when it has no area or is
/// neither a sphere nor a mesh of at most [`MAX_EDGES`] outline edges.
pub fn shape_of(triangles: &[[Vec3; 3]]) -> Option<Shape> {
    let (lo, hi) = triangles
        .iter()
        .flatten()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        });
    let extent = (hi - lo).max_element();
    if !(extent > 0.0 && extent.is_finite()) {
        return None;
    }
    // Vertices closer than this are one (meshes split vertices by normal and uv).
    let weld = extent * 1e-5;
    let mut ids: HashMap<[i64; 3], u32> = HashMap::new();
    let mut points: Vec<Vec3> = Vec::new();
    let mut id = |p: Vec3| -> u32 {
        let key = (p / weld).round().as_i64vec3().to_array();
        *ids.entry(key).or_insert_with(|| {
            points.push(p);
            points.len() as u32 - 1
        })
    };
    // Triangles with area, by welded corners, with their planes.
    let mut tris: Vec<([u32; 3], Vec3, f32)> = Vec::new();
    let mut area = 0.0f32;
    for t in triangles {
        let cross = (t[1] - t[0]).cross(t[2] - t[0]);
        let twice = cross.length();
        let c = t.map(&mut id);
        let degenerate = twice.is_nan() || twice <= weld * weld;
        if degenerate || c[0] == c[1] || c[1] == c[2] || c[0] == c[2] {
            continue;
        }
        let n = cross / twice;
        tris.push((c, n, n.dot(t[0])));
        area += 0.5 * twice;
    }
    if tris.is_empty() {
        return None;
    }
    let closed = is_closed(&tris);
    // Coplanar groups: same normal and plane (up to the weld).
    let mut groups: Vec<(Vec3, f32, Vec<[u32; 3]>)> = Vec::new();
    for (c, n, d) in &tris {
        match groups
            .iter_mut()
            .find(|g| g.0.dot(*n) > 1.0 - 1e-5 && (g.1 - d).abs() < 4.0 * weld)
        {
            Some(g) => g.2.push(*c),
            None => groups.push((*n, *d, vec![*c])),
        }
    }
    let polygons: Vec<Polygon> = groups
        .iter()
        .flat_map(|(n, _, g)| outlines(g, &points, *n))
        .collect();
    let edges: usize = polygons.iter().map(|p| p.vertices.len()).sum();
    let sphere = sphere_of(&tris, &points, area);
    match sphere {
        // A sphere as its disc is exact and costs SPHERE_SIDES edges.
        Some(s) if closed && edges > SPHERE_SIDES => Some(s),
        _ if edges <= MAX_EDGES => Some(Shape::Polygons(polygons)),
        // Anything else (a lamp's body whose emissive texture lights a bulb) stays in the
        // voxels: as the sphere of its area it lit LightsPunctualLamp from the wrong place.
        _ => None,
    }
}

/// Whether every edge has a twin running the other way (a closed, consistently wound mesh).
fn is_closed(tris: &[([u32; 3], Vec3, f32)]) -> bool {
    let mut count: HashMap<(u32, u32), i32> = HashMap::new();
    for (c, _, _) in tris {
        for k in 0..3 {
            let (a, b) = (c[k], c[(k + 1) % 3]);
            *count.entry((a.min(b), a.max(b))).or_default() += if a < b { 1 } else { -1 };
        }
    }
    count.values().all(|&v| v == 0)
}

fn area_centre(tris: &[([u32; 3], Vec3, f32)], points: &[Vec3]) -> Vec3 {
    let (mut sum, mut area) = (Vec3::ZERO, 0.0f32);
    for (c, _, _) in tris {
        let [a, b, d] = c.map(|i| points[i as usize]);
        let w = 0.5 * (b - a).cross(d - a).length();
        sum += w * (a + b + d) / 3.0;
        area += w;
    }
    sum / area.max(f32::MIN_POSITIVE)
}

/// A mesh whose vertices lie within 2% of one distance from its centre and whose area is at
/// least 80% of that sphere's (a cube's corners lie on a sphere too, with 64% of its area):
/// the sphere of the same area.
fn sphere_of(tris: &[([u32; 3], Vec3, f32)], points: &[Vec3], area: f32) -> Option<Shape> {
    if tris.len() < 16 {
        return None;
    }
    let centre = area_centre(tris, points);
    let d: Vec<f32> = points.iter().map(|p| (*p - centre).length()).collect();
    let (lo, hi) = d.iter().fold((f32::INFINITY, 0.0f32), |(lo, hi), &x| {
        (lo.min(x), hi.max(x))
    });
    let sphere_area = 4.0 * std::f32::consts::PI * hi * hi;
    (lo > 0.98 * hi && area > 0.8 * sphere_area).then(|| Shape::Sphere {
        centre,
        radius: (area / (4.0 * std::f32::consts::PI)).sqrt(),
    })
}

/// The outlines of a group of coplanar triangles: the directed edges without a twin running
/// the other way, chained into loops, with the points on a straight edge left out.
fn outlines(group: &[[u32; 3]], points: &[Vec3], normal: Vec3) -> Vec<Polygon> {
    let mut directed: HashMap<(u32, u32), i32> = HashMap::new();
    for c in group {
        for k in 0..3 {
            let (a, b) = (c[k], c[(k + 1) % 3]);
            if let Some(n) = directed.get_mut(&(b, a)) {
                *n -= 1;
                if *n == 0 {
                    directed.remove(&(b, a));
                }
            } else {
                *directed.entry((a, b)).or_default() += 1;
            }
        }
    }
    // Next vertex along the outline from each start (several where outlines touch).
    let mut next: HashMap<u32, Vec<u32>> = HashMap::new();
    let mut edges: Vec<(u32, u32)> = directed
        .iter()
        .flat_map(|(&e, &n)| std::iter::repeat_n(e, n.max(0) as usize))
        .collect();
    edges.sort_unstable();
    for (a, b) in edges {
        next.entry(a).or_default().push(b);
    }
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut loops = Vec::new();
    for s in starts {
        while next.get(&s).is_some_and(|v| !v.is_empty()) {
            let mut ids = vec![s];
            let mut at = s;
            while let Some(b) = next.get_mut(&at).and_then(|v| v.pop()) {
                if b == s {
                    break;
                }
                ids.push(b);
                at = b;
                if ids.len() > points.len() + 1 {
                    break;
                }
            }
            let vertices = straighten(ids.iter().map(|&i| points[i as usize]).collect());
            if vertices.len() >= 3 {
                loops.push(Polygon { vertices, normal });
            }
        }
    }
    loops
}

/// Leaves out the vertices in the middle of a straight run (a subdivided quad's edges).
fn straighten(v: Vec<Vec3>) -> Vec<Vec3> {
    let n = v.len();
    let keep: Vec<Vec3> = (0..n)
        .filter(|&i| {
            let (a, b, c) = (v[(i + n - 1) % n], v[i], v[(i + 1) % n]);
            let (u, w) = (b - a, c - b);
            u.cross(w).length() > 1e-6 * u.length() * w.length()
        })
        .map(|i| v[i])
        .collect();
    if keep.len() >= 3 {
        keep
    } else {
        v
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad(c: Vec3, u: Vec3, v: Vec3) -> Vec<[Vec3; 3]> {
        let q = [c - u - v, c + u - v, c + u + v, c - u + v];
        vec![[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
    }

    fn cube(side: f32) -> Vec<[Vec3; 3]> {
        let h = 0.5 * side;
        let mut tris = Vec::new();
        for axis in 0..3 {
            for sign in [-1.0f32, 1.0] {
                let n = Vec3::AXES[axis] * sign;
                let (u, v) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3]);
                let (u, v) = if sign > 0.0 { (u, v) } else { (v, u) };
                tris.extend(quad(n * h, u * h, v * h));
            }
        }
        tris
    }

    #[test]
    fn a_box_is_closed_and_turned_to_face_out() {
        let out = shape_of(&cube(1.0)).unwrap();
        assert!(out.closed());
        assert_eq!(out.clone().facing_out(), out);
        let inward: Vec<[Vec3; 3]> = cube(1.0).iter().map(|t| [t[0], t[2], t[1]]).collect();
        let turned = shape_of(&inward).unwrap();
        assert!(turned.closed());
        let Shape::Polygons(turned) = turned.facing_out() else {
            panic!("a box is polygons")
        };
        for p in &turned {
            let centre = p.vertices.iter().sum::<Vec3>() / p.vertices.len() as f32;
            assert!(p.normal.dot(centre) > 0.49, "a face turned in: {p:?}");
        }
        let open = shape_of(&quad(Vec3::ZERO, Vec3::X, Vec3::Z)).unwrap();
        assert!(!open.closed());
    }

    fn uv_sphere(r: f32, rings: usize, segments: usize) -> Vec<[Vec3; 3]> {
        let p = |i: usize, j: usize| {
            let th = std::f32::consts::PI * i as f32 / rings as f32;
            let ph = std::f32::consts::TAU * j as f32 / segments as f32;
            r * Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin())
        };
        let mut tris = Vec::new();
        for i in 0..rings {
            for j in 0..segments {
                let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
                if i > 0 {
                    tris.push([a, d, c]);
                }
                if i + 1 < rings {
                    tris.push([a, c, b]);
                }
            }
        }
        tris
    }

    #[test]
    fn a_quad_is_one_polygon_of_four_edges_facing_its_winding() {
        // Facing -Y: counter-clockwise seen from below.
        let tris = quad(Vec3::ZERO, Vec3::X * 0.05, Vec3::Z * 0.05);
        let Some(Shape::Polygons(p)) = shape_of(&tris) else {
            panic!("not polygons");
        };
        assert_eq!(p.len(), 1);
        assert_eq!(p[0].vertices.len(), 4);
        assert!(
            (p[0].normal - Vec3::NEG_Y).length() < 1e-6,
            "{}",
            p[0].normal
        );
        assert!((p[0].area() - 0.01).abs() < 1e-7);
    }

    #[test]
    fn a_subdivided_quad_is_still_four_edges() {
        let mut tris = Vec::new();
        for i in 0..4 {
            for j in 0..4 {
                let c = Vec3::new(i as f32 - 1.5, 0.0, j as f32 - 1.5);
                tris.extend(quad(c, Vec3::X * 0.5, Vec3::Z * 0.5));
            }
        }
        let Some(Shape::Polygons(p)) = shape_of(&tris) else {
            panic!("not polygons");
        };
        assert_eq!(p.len(), 1);
        assert_eq!(p[0].vertices.len(), 4, "{:?}", p[0].vertices);
        assert!((p[0].area() - 16.0).abs() < 1e-4);
    }

    #[test]
    fn a_box_is_six_polygons_and_a_sphere_a_sphere() {
        let Some(Shape::Polygons(p)) = shape_of(&cube(0.1)) else {
            panic!("a cube is not polygons");
        };
        assert_eq!(p.len(), 6);
        assert!(p.iter().all(|p| p.vertices.len() == 4));
        let Some(Shape::Sphere { centre, radius }) = shape_of(&uv_sphere(0.1, 12, 24)) else {
            panic!("not a sphere");
        };
        assert!(centre.length() < 1e-3, "centre {centre}");
        // The sphere of the mesh's area: a little smaller than the one through its vertices.
        assert!(radius < 0.1 && radius > 0.098, "radius {radius}");
    }

    #[test]
    fn a_light_keeps_its_power_and_faces_where_its_winding_says() {
        let tris = quad(Vec3::ZERO, Vec3::X * 0.05, Vec3::Z * 0.05);
        let local = shape_of(&tris).unwrap();
        let mut l = AreaLight {
            instance: 0,
            emission: Vec3::splat(2.0),
            two_sided: false,
            triangles: 2,
            shape: local.clone(),
            local,
            position: Vec3::ZERO,
            radius: 0.0,
            area: 0.0,
        };
        l.place(&Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0)));
        assert!((l.position - Vec3::new(1.0, 2.0, 3.0)).length() < 1e-6);
        assert!((l.power().x - std::f32::consts::PI * 0.02).abs() < 1e-6);
        assert!((l.radius - 0.05 * 2f32.sqrt()).abs() < 1e-6);
        // A mirror through the XZ plane turns the -Y face to +Y.
        l.place(&Mat4::from_scale(Vec3::new(1.0, -1.0, 1.0)));
        let Shape::Polygons(p) = &l.shape else {
            panic!()
        };
        assert!((p[0].normal - Vec3::Y).length() < 1e-6, "{}", p[0].normal);
        assert!((newell_normal(&p[0].vertices).unwrap() - Vec3::Y).length() < 1e-6);
        // Scaled by 2: four times the area.
        l.place(&Mat4::from_scale(Vec3::splat(2.0)));
        assert!((l.area - 0.04).abs() < 1e-6);
    }
}
