//! The corpus's geometry: boxes, spheres, cylinders, tables and rooms with openings, as
//! builder primitives in world coordinates.

use crate::hard::scenes::slab_face;
use crate::scene::builder::{merge, NodeDesc, PrimitiveDesc, SceneBuilder};
use glam::{Mat3, Mat4, Vec3};

/// A closed box `lo`..`hi` with outward faces.
pub fn solid_box(lo: Vec3, hi: Vec3, material: usize) -> PrimitiveDesc {
    let (l, h) = (lo.to_array(), hi.to_array());
    let faces: Vec<PrimitiveDesc> = (0..3)
        .flat_map(|axis| {
            [
                slab_face(l, h, axis, l[axis], -1.0, material),
                slab_face(l, h, axis, h[axis], 1.0, material),
            ]
        })
        .collect();
    merge(&faces)
}

/// `p` moved by `m` (normals by its inverse transpose).
pub fn transformed(mut p: PrimitiveDesc, m: Mat4) -> PrimitiveDesc {
    let n = Mat3::from_mat4(m).inverse().transpose();
    for v in &mut p.positions {
        *v = m.transform_point3(Vec3::from(*v)).to_array();
    }
    if let Some(normals) = &mut p.normals {
        for v in normals {
            *v = (n * Vec3::from(*v)).normalize_or_zero().to_array();
        }
    }
    p
}

/// A box of `size` standing on the floor at `base` (its bottom face's centre), turned `yaw`
/// radians about +Y.
pub fn standing_box(base: Vec3, size: Vec3, yaw: f32, material: usize) -> PrimitiveDesc {
    let half = Vec3::new(size.x * 0.5, 0.0, size.z * 0.5);
    let b = solid_box(-half, half + Vec3::Y * size.y, material);
    transformed(b, Mat4::from_translation(base) * Mat4::from_rotation_y(yaw))
}

/// A UV sphere with smooth normals.
pub fn sphere(centre: Vec3, radius: f32, material: usize) -> PrimitiveDesc {
    let (rings, segments) = (16u32, 32u32);
    let mut p = PrimitiveDesc {
        material: Some(material),
        normals: Some(Vec::new()),
        indices: Some(Vec::new()),
        ..Default::default()
    };
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..=segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            p.positions.push((centre + n * radius).to_array());
            p.normals.as_mut().unwrap().push(n.to_array());
        }
    }
    let row = segments + 1;
    let idx = p.indices.as_mut().unwrap();
    for i in 0..rings {
        for j in 0..segments {
            let (a, b) = (i * row + j, (i + 1) * row + j);
            // Wound so that the front faces outward.
            if i > 0 {
                idx.extend([a, a + 1, b]);
            }
            if i + 1 < rings {
                idx.extend([a + 1, b + 1, b]);
            }
        }
    }
    p
}

/// An upright cylinder on `base` (its bottom's centre), with flat caps.
pub fn cylinder(base: Vec3, radius: f32, height: f32, material: usize) -> PrimitiveDesc {
    let segments = 16u32;
    let mut parts = Vec::new();
    let mut side = PrimitiveDesc {
        material: Some(material),
        normals: Some(Vec::new()),
        indices: Some(Vec::new()),
        ..Default::default()
    };
    for j in 0..=segments {
        let phi = std::f32::consts::TAU * j as f32 / segments as f32;
        let n = Vec3::new(phi.cos(), 0.0, phi.sin());
        for y in [0.0, height] {
            side.positions
                .push((base + n * radius + Vec3::Y * y).to_array());
            side.normals.as_mut().unwrap().push(n.to_array());
        }
    }
    let idx = side.indices.as_mut().unwrap();
    for j in 0..segments {
        let (a, b) = (2 * j, 2 * j + 2);
        idx.extend([a, a + 1, b, b, a + 1, b + 1]);
    }
    parts.push(side);
    for (y, ny) in [(0.0, -1.0), (height, 1.0)] {
        let c = base + Vec3::Y * y;
        for j in 0..segments {
            let p0 = std::f32::consts::TAU * j as f32 / segments as f32;
            let p1 = std::f32::consts::TAU * (j + 1) as f32 / segments as f32;
            let a = c + Vec3::new(p0.cos(), 0.0, p0.sin()) * radius;
            let b = c + Vec3::new(p1.cos(), 0.0, p1.sin()) * radius;
            parts.push(facing(
                [c.to_array(), a.to_array(), b.to_array()],
                [0.0, ny, 0.0],
                material,
            ));
        }
    }
    merge(&parts)
}

/// One triangle wound to face along `normal`.
fn facing(t: [[f32; 3]; 3], normal: [f32; 3], material: usize) -> PrimitiveDesc {
    let [a, b, c] = t.map(Vec3::from);
    let front = (b - a).cross(c - a).dot(Vec3::from(normal)) >= 0.0;
    let positions = if front {
        vec![t[0], t[1], t[2]]
    } else {
        vec![t[0], t[2], t[1]]
    };
    PrimitiveDesc {
        normals: Some(vec![normal; 3]),
        indices: Some(vec![0, 1, 2]),
        positions,
        material: Some(material),
        uvs: None,
    }
}

/// A table: a top of `size.x` by `size.z`, 4 cm thick, at height `size.y`, on four legs of 5 cm.
/// Returns the primitives and the height of its top.
pub fn table(centre: Vec3, size: Vec3, yaw: f32, material: usize) -> (Vec<PrimitiveDesc>, f32) {
    let (t, leg) = (0.04, 0.05);
    let half = Vec3::new(size.x * 0.5, 0.0, size.z * 0.5);
    let mut parts = vec![solid_box(
        Vec3::new(-half.x, size.y - t, -half.z),
        Vec3::new(half.x, size.y, half.z),
        material,
    )];
    for (sx, sz) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        let c = Vec3::new(sx * (half.x - leg), 0.0, sz * (half.z - leg));
        parts.push(solid_box(
            c - Vec3::new(leg * 0.5, 0.0, leg * 0.5),
            c + Vec3::new(leg * 0.5, size.y - t, leg * 0.5),
            material,
        ));
    }
    let m = Mat4::from_translation(centre) * Mat4::from_rotation_y(yaw);
    (
        parts.into_iter().map(|p| transformed(p, m)).collect(),
        centre.y + size.y,
    )
}

/// A rectangle in a side's plane: `u` and `v` ranges (see [`Room`] for the axes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rect {
    pub u: [f32; 2],
    pub v: [f32; 2],
}

/// `outer` less `holes`, as rectangles: the grid that the holes' edges cut, without the cells
/// inside a hole.
pub fn pieces(outer: Rect, holes: &[Rect]) -> Vec<Rect> {
    let cuts = |a: [f32; 2], pick: &dyn Fn(&Rect) -> [f32; 2]| {
        let mut c = vec![a[0], a[1]];
        for h in holes {
            c.extend(pick(h).into_iter().map(|x| x.clamp(a[0], a[1])));
        }
        c.sort_by(f32::total_cmp);
        c.dedup();
        c
    };
    let us = cuts(outer.u, &|h| h.u);
    let vs = cuts(outer.v, &|h| h.v);
    let mut out = Vec::new();
    for v in vs.windows(2) {
        for u in us.windows(2) {
            let mid = (0.5 * (u[0] + u[1]), 0.5 * (v[0] + v[1]));
            let inside = holes
                .iter()
                .any(|h| (h.u[0]..h.u[1]).contains(&mid.0) && (h.v[0]..h.v[1]).contains(&mid.1));
            if !inside {
                out.push(Rect {
                    u: [u[0], u[1]],
                    v: [v[0], v[1]],
                });
            }
        }
    }
    out
}

/// How a room's walls are made.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Walls {
    /// Single quads facing into the room (`true`) or out of it.
    Quads { facing_in: bool },
    /// Closed boxes this thick (metres), outside the room's inner bounds.
    Thick(f32),
}

/// A room: inner bounds `x` in -size.x/2..size.x/2, `y` in 0..size.y, `z` likewise. Its sides
/// are numbered -x, +x, floor, ceiling, -z, +z; a side's plane has the axes (u, v) = (z, y)
/// for the x sides, (x, z) for the floor and ceiling, (x, y) for the z sides.
#[derive(Clone, Debug)]
pub struct Room {
    pub size: Vec3,
    pub walls: Walls,
    /// Sides left out (an open side, or the floor where a ground plane is).
    pub open: [bool; 6],
    pub holes: [Vec<Rect>; 6],
    pub materials: [usize; 6],
}

impl Room {
    /// The side's axis, the coordinate of its inner face and the direction into the room.
    pub fn plane(&self, side: usize) -> (usize, f32, f32) {
        let axis = [0, 0, 1, 1, 2, 2][side];
        let lo = side.is_multiple_of(2);
        let at = match (axis, lo) {
            (1, true) => 0.0,
            (1, false) => self.size.y,
            (_, true) => -0.5 * self.size[axis],
            (_, false) => 0.5 * self.size[axis],
        };
        (axis, at, if lo { 1.0 } else { -1.0 })
    }

    /// The (u, v) axes of a side.
    pub fn side_axes(side: usize) -> (usize, usize) {
        match side / 2 {
            0 => (2, 1),
            1 => (0, 2),
            _ => (0, 1),
        }
    }

    /// The full extent of a side's inner face in (u, v).
    pub fn side_rect(&self, side: usize) -> Rect {
        let (u, v) = Self::side_axes(side);
        let range = |a: usize| {
            if a == 1 {
                [0.0, self.size.y]
            } else {
                [-0.5 * self.size[a], 0.5 * self.size[a]]
            }
        };
        Rect {
            u: range(u),
            v: range(v),
        }
    }

    /// Every face of the room.
    pub fn primitives(&self) -> Vec<PrimitiveDesc> {
        let mut out = Vec::new();
        for side in 0..6 {
            if self.open[side] {
                continue;
            }
            let (axis, at, into) = self.plane(side);
            let (ua, va) = Self::side_axes(side);
            let mut outer = self.side_rect(side);
            let thick = match self.walls {
                Walls::Thick(t) => t,
                Walls::Quads { .. } => 0.0,
            };
            // Thick walls reach over the corners so that no gap is left between them.
            for (a, r) in [(ua, &mut outer.u), (va, &mut outer.v)] {
                if a != 1 || side / 2 == 1 {
                    r[0] -= thick;
                    r[1] += thick;
                } else {
                    r[1] += thick;
                    if !self.open[2] {
                        r[0] -= thick;
                    }
                }
            }
            for piece in pieces(outer, &self.holes[side]) {
                let mut lo = [0.0; 3];
                let mut hi = [0.0; 3];
                lo[ua] = piece.u[0];
                hi[ua] = piece.u[1];
                lo[va] = piece.v[0];
                hi[va] = piece.v[1];
                let m = self.materials[side];
                match self.walls {
                    Walls::Quads { facing_in } => {
                        lo[axis] = at;
                        hi[axis] = at;
                        let face = if facing_in { into } else { -into };
                        out.push(slab_face(lo, hi, axis, at, face, m));
                    }
                    Walls::Thick(t) => {
                        lo[axis] = at.min(at - into * t);
                        hi[axis] = at.max(at - into * t);
                        out.push(solid_box(Vec3::from(lo), Vec3::from(hi), m));
                    }
                }
            }
        }
        out
    }
}

/// A quad of `material` in the plane `axis = at`, facing `side`, over `lo`..`hi` in the
/// other two axes (the `axis` entries of `lo` and `hi` are ignored).
pub fn panel(
    lo: Vec3,
    hi: Vec3,
    axis: usize,
    at: f32,
    side: f32,
    material: usize,
) -> PrimitiveDesc {
    slab_face(lo.to_array(), hi.to_array(), axis, at, side, material)
}

/// Adds `parts` as one mesh (one primitive per material) on a node of its own.
pub fn add_parts(b: &mut SceneBuilder, name: &str, parts: Vec<PrimitiveDesc>) -> Option<usize> {
    if parts.is_empty() {
        return None;
    }
    let mut materials: Vec<Option<usize>> = parts.iter().map(|p| p.material).collect();
    materials.sort();
    materials.dedup();
    let prims = materials
        .iter()
        .map(|m| {
            let same: Vec<PrimitiveDesc> =
                parts.iter().filter(|p| p.material == *m).cloned().collect();
            let mut p = merge(&same);
            p.material = *m;
            p
        })
        .collect();
    let mesh = b.add_mesh(name, prims);
    Some(b.add_node(NodeDesc::new(name).mesh(mesh)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pieces_cover_the_outer_rect_less_the_holes() {
        let outer = Rect {
            u: [0.0, 4.0],
            v: [0.0, 3.0],
        };
        let holes = [Rect {
            u: [1.0, 2.0],
            v: [1.0, 2.0],
        }];
        let area = |r: &Rect| (r.u[1] - r.u[0]) * (r.v[1] - r.v[0]);
        let p = pieces(outer, &holes);
        let total: f32 = p.iter().map(area).sum();
        assert!((total - (12.0 - 1.0)).abs() < 1e-5, "{total}");
        assert!(p.iter().all(|r| area(r) > 0.0));
    }

    #[test]
    fn sphere_faces_outward() {
        let s = sphere(Vec3::ZERO, 1.0, 0);
        let idx = s.indices.unwrap();
        for t in idx.chunks(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| Vec3::from(s.positions[i as usize]));
            let n = (b - a).cross(c - a);
            assert!(n.dot(a + b + c) > 0.0, "a triangle faces inward");
        }
    }
}
