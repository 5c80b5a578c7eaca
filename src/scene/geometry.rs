//! Turning one glTF primitive's attribute arrays into renderer vertices: triangle assembly,
//! dropping non-finite triangles, flat normals where normals are missing or broken, and
//! tangents where the file has none.

use super::{Aabb, Vertex};
use glam::{Vec2, Vec3, Vec4};

/// How a primitive's index list forms triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Topology {
    Triangles,
    Strip,
    Fan,
}

/// Groups an index list into triangles. Returns the triangles and how many trailing indices
/// did not form a whole triangle list entry (only for plain triangle lists).
pub fn assemble(topology: Topology, idx: &[u32]) -> (Vec<[u32; 3]>, usize) {
    match topology {
        Topology::Triangles => {
            let tris = idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
            (tris, idx.len() % 3)
        }
        Topology::Strip => {
            // glTF: triangle i is (i, i + 1 + i % 2, i + 2 - i % 2), keeping a consistent
            // winding along the strip.
            let n = idx.len().saturating_sub(2);
            let tris = (0..n)
                .map(|i| {
                    let odd = i % 2;
                    [idx[i], idx[i + 1 + odd], idx[i + 2 - odd]]
                })
                .collect();
            (tris, 0)
        }
        Topology::Fan => {
            // glTF: triangle i is (i + 1, i + 2, 0).
            let n = idx.len().saturating_sub(2);
            let tris = (0..n).map(|i| [idx[i + 1], idx[i + 2], idx[0]]).collect();
            (tris, 0)
        }
    }
}

/// Attribute arrays of one primitive, all with `positions.len()` elements.
pub struct RawPrimitive {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    pub tangents: Option<Vec<Vec4>>,
    /// Local vertex indices, already checked to be in range.
    pub triangles: Vec<[u32; 3]>,
}

/// What a primitive became: its own vertices, local indices and object-space bounds.
pub struct BuiltPrimitive {
    pub vertices: Vec<Vertex>,
    pub indices: Vec<u32>,
    pub bounds: Aabb,
}

/// Unit normal of a triangle from its winding (counter-clockwise = front); an arbitrary unit
/// vector for zero-area triangles.
pub fn face_normal(p0: Vec3, p1: Vec3, p2: Vec3) -> Vec3 {
    unit((p1 - p0).cross(p2 - p0)).unwrap_or(Vec3::Y)
}

/// `v` at unit length, accurately at any finite size: scaled to about 1 first (the square of a
/// tiny vector's length is subnormal, and dividing by its root left vectors 0.2% too long).
fn unit(v: Vec3) -> Option<Vec3> {
    let m = v.abs().max_element();
    if !(m > 0.0 && m.is_finite()) {
        return None;
    }
    (v / m).try_normalize()
}

/// The unit direction of `d` in the plane perpendicular to unit `n`; None when `d` is not
/// finite or lies within 0.006 degrees of `n`. Projected twice: once leaves an error of a float's
/// step over the projection's length (a tangent 0.4 degrees off the normal's plane).
fn in_plane(d: Vec3, n: Vec3) -> Option<Vec3> {
    let d = unit(d)?;
    let t = d - n * n.dot(d);
    if t.length_squared() < 1e-8 {
        return None;
    }
    let t = unit(t)?;
    unit(t - n * n.dot(t))
}

fn usable_normal(n: Vec3) -> Option<Vec3> {
    if n.is_finite() && n.length_squared() > 1e-12 {
        unit(n)
    } else {
        None
    }
}

/// Any unit vector perpendicular to `n`.
fn any_perpendicular(n: Vec3) -> Vec3 {
    let axis = if n.x.abs() < 0.9 { Vec3::X } else { Vec3::Y };
    (axis - n * n.dot(axis)).normalize()
}

/// Builds the vertices of one primitive. `label` names it in warnings. Returns None (with a
/// warning) when no triangle survives.
pub fn build(raw: RawPrimitive, label: &str, warnings: &mut Vec<String>) -> Option<BuiltPrimitive> {
    let RawPrimitive {
        positions,
        normals,
        uvs,
        tangents,
        triangles,
    } = raw;

    // Non-finite positions would poison bounds, voxelisation and BVHs: drop their triangles.
    let before = triangles.len();
    let triangles: Vec<[u32; 3]> = triangles
        .into_iter()
        .filter(|t| t.iter().all(|&v| positions[v as usize].is_finite()))
        .collect();
    if triangles.len() < before {
        warnings.push(format!(
            "{label}: dropped {} of {before} triangles with NaN or infinite positions",
            before - triangles.len()
        ));
    }
    if triangles.is_empty() {
        warnings.push(format!("{label} has no triangles left; skipped"));
        return None;
    }

    let good_normals: Option<Vec<Option<Vec3>>> = normals
        .as_ref()
        .map(|ns| ns.iter().map(|&n| usable_normal(n)).collect());
    if let Some(good) = &good_normals {
        let bad = triangles
            .iter()
            .flatten()
            .filter(|&&v| good[v as usize].is_none())
            .count();
        if bad > 0 {
            warnings.push(format!(
                "{label}: {bad} triangle corners have zero-length or non-finite normals; \
                 replaced by flat normals"
            ));
        }
    }

    let mut bad_uvs = 0usize;
    let uv_of = |v: usize, bad_uvs: &mut usize| -> Vec2 {
        match &uvs {
            Some(u) if u[v].is_finite() => u[v],
            Some(_) => {
                *bad_uvs += 1;
                Vec2::ZERO
            }
            None => Vec2::ZERO,
        }
    };

    // Vertices with usable normals are shared as in the file; every corner whose normal is
    // missing or broken gets its own copy carrying the triangle's flat normal.
    let mut vertices: Vec<Vertex> = Vec::new();
    let mut given_tangent: Vec<Option<Vec4>> = Vec::new();
    let mut indices: Vec<u32> = Vec::with_capacity(triangles.len() * 3);
    let mut remap = vec![u32::MAX; positions.len()];
    for t in &triangles {
        let p = t.map(|v| positions[v as usize]);
        let mut flat: Option<Vec3> = None;
        for &v in t {
            let v = v as usize;
            let shared = good_normals.as_ref().and_then(|g| g[v]);
            if shared.is_some() && remap[v] != u32::MAX {
                indices.push(remap[v]);
                continue;
            }
            let normal = match shared {
                Some(n) => n,
                None => *flat.get_or_insert_with(|| face_normal(p[0], p[1], p[2])),
            };
            let out = vertices.len() as u32;
            if shared.is_some() {
                remap[v] = out;
            }
            vertices.push(Vertex {
                position: positions[v].to_array(),
                normal: normal.to_array(),
                uv: uv_of(v, &mut bad_uvs).to_array(),
                tangent: [0.0; 4],
            });
            given_tangent.push(tangents.as_ref().map(|ts| ts[v]));
            indices.push(out);
        }
    }
    if bad_uvs > 0 {
        warnings.push(format!(
            "{label}: {bad_uvs} vertices have non-finite texture coordinates; set to 0"
        ));
    }

    // Supplied tangents are kept (made orthogonal to the final normal); the rest are generated.
    let mut missing = 0usize;
    let mut finished: Vec<Option<Vec4>> = Vec::with_capacity(vertices.len());
    for (vert, given) in vertices.iter().zip(&given_tangent) {
        let n = Vec3::from(vert.normal);
        let t = given.and_then(|g| {
            let xyz = g.truncate();
            if !g.is_finite() {
                return None;
            }
            let t = in_plane(xyz, n)?;
            Some(t.extend(if g.w < 0.0 { -1.0 } else { 1.0 }))
        });
        if t.is_none() {
            missing += 1;
        }
        finished.push(t);
    }
    if tangents.is_some() && missing > 0 {
        warnings.push(format!(
            "{label}: {missing} vertices have unusable tangents; generated from texture coordinates"
        ));
    }
    if missing > 0 {
        let generated = generate_tangents(&vertices, &indices);
        for (slot, g) in finished.iter_mut().zip(generated) {
            slot.get_or_insert(g);
        }
    }
    let mut bounds = Aabb::EMPTY;
    for (vert, t) in vertices.iter_mut().zip(finished) {
        vert.tangent = t.unwrap_or(Vec4::X.with_w(1.0)).to_array();
        bounds.extend(Vec3::from(vert.position));
    }
    Some(BuiltPrimitive {
        vertices,
        indices,
        bounds,
    })
}

/// Per-vertex tangents from texture-coordinate gradients: per-triangle tangent and bitangent
/// directions summed over each vertex's triangles, made orthogonal to the normal, handedness
/// in w. Where the UVs give no direction, any vector perpendicular to the normal is used.
pub fn generate_tangents(vertices: &[Vertex], indices: &[u32]) -> Vec<Vec4> {
    let mut tan = vec![Vec3::ZERO; vertices.len()];
    let mut bit = vec![Vec3::ZERO; vertices.len()];
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0] as usize, t[1] as usize, t[2] as usize];
        let p0 = Vec3::from(vertices[a].position);
        let e1 = Vec3::from(vertices[b].position) - p0;
        let e2 = Vec3::from(vertices[c].position) - p0;
        let w0 = Vec2::from(vertices[a].uv);
        let d1 = Vec2::from(vertices[b].uv) - w0;
        let d2 = Vec2::from(vertices[c].uv) - w0;
        let det = d1.x * d2.y - d2.x * d1.y;
        if det.abs() < 1e-20 || !det.is_finite() {
            continue;
        }
        let r = 1.0 / det;
        let sdir = (e1 * d2.y - e2 * d1.y) * r;
        let tdir = (e2 * d1.x - e1 * d2.x) * r;
        if !sdir.is_finite() || !tdir.is_finite() {
            continue;
        }
        for v in [a, b, c] {
            tan[v] += sdir;
            bit[v] += tdir;
        }
    }
    vertices
        .iter()
        .enumerate()
        .map(|(i, v)| {
            let n = Vec3::from(v.normal);
            let t = in_plane(tan[i], n).unwrap_or_else(|| any_perpendicular(n));
            // glTF: bitangent = cross(normal, tangent.xyz) * w.
            let w = if n.cross(t).dot(bit[i]) < 0.0 {
                -1.0
            } else {
                1.0
            };
            t.extend(w)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_keep_winding() {
        let (s, _) = assemble(Topology::Strip, &[0, 1, 2, 3]);
        assert_eq!(s, vec![[0, 1, 2], [1, 3, 2]]);
        let (f, _) = assemble(Topology::Fan, &[0, 1, 2, 3]);
        assert_eq!(f, vec![[1, 2, 0], [2, 3, 0]]);
        let (t, rest) = assemble(Topology::Triangles, &[0, 1, 2, 3]);
        assert_eq!((t, rest), (vec![[0, 1, 2]], 1));
    }

    #[test]
    fn flat_normals_and_generated_tangents() {
        let raw = RawPrimitive {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: None,
            uvs: Some(vec![Vec2::ZERO, Vec2::X, Vec2::Y]),
            tangents: None,
            triangles: vec![[0, 1, 2]],
        };
        let mut w = Vec::new();
        let b = build(raw, "test", &mut w).unwrap();
        assert!(w.is_empty());
        for v in &b.vertices {
            assert_eq!(v.normal, [0.0, 0.0, 1.0]);
            assert_eq!(v.tangent, [1.0, 0.0, 0.0, 1.0]);
        }
    }

    #[test]
    fn tangent_frames_stay_unit_and_orthogonal_at_any_scale() {
        // Found by the fuzzer: a supplied tangent 1e-20 long, one 0.05 degrees off the
        // normal, and texture coordinates of 1e20 (generated tangents) left frames 0.2% long
        // or 0.4 degrees out of the normal's plane.
        let n = Vec3::new(0.14673047, 0.9891766, 0.0);
        let near_n = (n + Vec3::new(-0.99, 0.14673047, 0.0) * 9e-4).extend(1.0);
        for (tangents, uvs) in [
            (Some(vec![Vec4::new(1e-20, 3e-21, 0.0, 1.0); 3]), None),
            (Some(vec![near_n; 3]), None),
            (
                None,
                Some(vec![Vec2::ZERO, Vec2::new(4.5e20, 1.0), Vec2::Y]),
            ),
        ] {
            let raw = RawPrimitive {
                positions: vec![Vec3::ZERO, Vec3::X, Vec3::Z],
                normals: Some(vec![n; 3]),
                uvs,
                tangents,
                triangles: vec![[0, 1, 2]],
            };
            let b = build(raw, "test", &mut Vec::new()).unwrap();
            for v in &b.vertices {
                let t = Vec3::from_slice(&v.tangent[..3]);
                let n = Vec3::from(v.normal);
                assert!((t.length() - 1.0).abs() < 1e-5, "{v:?}");
                assert!(t.dot(n).abs() < 1e-5, "{v:?}");
            }
        }
    }

    #[test]
    fn mirrored_uvs_flip_handedness() {
        let raw = RawPrimitive {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            normals: Some(vec![Vec3::Z; 3]),
            uvs: Some(vec![Vec2::ZERO, Vec2::X, -Vec2::Y]),
            tangents: None,
            triangles: vec![[0, 1, 2]],
        };
        let b = build(raw, "test", &mut Vec::new()).unwrap();
        assert_eq!(b.vertices.len(), 3);
        assert!(b.vertices.iter().all(|v| v.tangent[3] == -1.0));
    }

    #[test]
    fn bad_normals_become_flat_copies() {
        let raw = RawPrimitive {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, 0.0)],
            normals: Some(vec![Vec3::Z, Vec3::ZERO, Vec3::Z, Vec3::NAN]),
            uvs: None,
            tangents: None,
            triangles: vec![[0, 1, 2], [1, 3, 2]],
        };
        let mut w = Vec::new();
        let b = build(raw, "test", &mut w).unwrap();
        assert_eq!(w.len(), 1);
        assert_eq!(b.indices.len(), 6);
        // Vertices 0 and 2 shared; corners of 1 and 3 duplicated.
        assert_eq!(b.vertices.len(), 5);
        assert!(b
            .vertices
            .iter()
            .all(|v| v.normal == [0.0, 0.0, 1.0] && v.tangent[3].abs() == 1.0));
    }
}
