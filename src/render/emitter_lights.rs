//! Emitters smaller than a voxel, injected as lights. A voxel shows one radiance to a whole
//! cone, so a 2 cm emitter in a 3 cm voxel lights what its coarse texels reach, not what it
//! faces (docs/hard-cases.md, emissive-1e4). Seen from a few emitter widths away it is a point
//! light whose intensity follows its faces' cosines; as such it gets a cube of shadow maps and
//! lights the pixels and the voxels like any punctual light, and its emission leaves the voxels
//! (the camera still sees it through the G-buffer).

use crate::scene::{Light, LightKind, Scene};
use glam::{Mat4, Vec3};

/// At most this many emitters become lights (the most powerful); each costs six shadow views.
pub const MAX_EMITTER_LIGHTS: usize = 4;

/// One small emitter's light: radiant intensity Le (lobe cos + uniform) towards a direction at
/// angle theta from `axis` (|cos| for a two-sided emitter, max(cos, 0) for a one-sided one).
#[derive(Clone, Debug)]
pub struct EmitterLight {
    /// The instance whose primitive emits (left out of its own shadow views and of the
    /// voxels' emission).
    pub instance: usize,
    /// Emitted radiance Le.
    pub emission: Vec3,
    pub two_sided: bool,
    /// Object-space triangles, front faces by winding, to place the light again when its
    /// node moves.
    triangles: Vec<[Vec3; 3]>,
    /// Area-weighted centre of the faces (world).
    pub position: Vec3,
    /// The faces' mean normal (world, unit).
    pub axis: Vec3,
    /// Square metres of face seen along the axis: the length of the sum of area x normal.
    pub lobe: f32,
    /// The rest of the area, spread evenly over the sphere so the power is the faces'.
    pub uniform: f32,
}

impl EmitterLight {
    /// Places the light for the instance's world transform: centre, axis and areas of the
    /// transformed faces. A one-sided emitter of area A with normals n_i radiates
    /// sum A_i Le max(n_i . w, 0); the light keeps its power pi Le A with the part along the
    /// mean normal as a cosine lobe (|N| = |sum A_i n_i|) and the rest, (A - |N|) / 4, uniform.
    /// A two-sided one radiates twice that, as |cos| and (A - |N|) / 2.
    pub fn place(&mut self, world: &Mat4) {
        let flip = if world.determinant() < 0.0 { -1.0 } else { 1.0 };
        let (mut area, mut centre, mut sum) = (0.0f32, Vec3::ZERO, Vec3::ZERO);
        let mut reference: Option<Vec3> = None;
        for t in &self.triangles {
            let [a, b, c] = t.map(|p| world.transform_point3(p));
            let cross = (b - a).cross(c - a) * flip;
            let twice = cross.length();
            if !(twice > 0.0 && twice.is_finite()) {
                continue;
            }
            let (a_i, n) = (0.5 * twice, cross / twice);
            // Two-sided faces count along one common side.
            let r = *reference.get_or_insert(n);
            let n = if self.two_sided && n.dot(r) < 0.0 {
                -n
            } else {
                n
            };
            area += a_i;
            centre += a_i * (a + b + c) / 3.0;
            sum += a_i * n;
        }
        if area <= 0.0 {
            self.lobe = 0.0;
            self.uniform = 0.0;
            return;
        }
        self.position = centre / area;
        let along = sum.length();
        self.axis = if along > 1e-6 * area {
            sum / along
        } else {
            Vec3::NEG_Y
        };
        self.lobe = along.min(area);
        let spread = if self.two_sided { 0.5 } else { 0.25 };
        self.uniform = (area - self.lobe) * spread;
    }

    /// The light as the shadow views see it: a point light at the centre (six views).
    pub fn as_point_light(&self) -> Light {
        Light {
            name: None,
            kind: LightKind::Point,
            radiance: self.emission,
            range: None,
            position: self.position,
            direction: self.axis,
        }
    }

    /// Radiant intensity towards `dir` (unit), W/sr.
    pub fn intensity(&self, dir: Vec3) -> Vec3 {
        let c = self.axis.dot(dir);
        let lobe = if self.two_sided { c.abs() } else { c.max(0.0) };
        self.emission * (self.lobe * lobe + self.uniform)
    }

    /// Total radiated power, W (per channel): a cosine lobe radiates pi times its area over
    /// a hemisphere (2 pi over both), an even intensity 4 pi times itself.
    pub fn power(&self) -> Vec3 {
        let hemispheres = if self.two_sided { 2.0 } else { 1.0 };
        self.emission * std::f32::consts::PI * (hemispheres * self.lobe + 4.0 * self.uniform)
    }
}

fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// The instances whose primitive emits, is smaller than `voxel_size` along every world axis
/// and can be a light: an opaque material with an untextured emission (a texture would vary
/// the light over the faces). The most powerful [`MAX_EMITTER_LIGHTS`] are kept.
pub fn find(scene: &Scene, voxel_size: f32) -> Vec<EmitterLight> {
    let mut found = Vec::new();
    if !(voxel_size > 0.0 && voxel_size.is_finite()) {
        return found;
    }
    for (i, inst) in scene.instances.iter().enumerate() {
        let Some(p) = scene.primitives.get(inst.primitive as usize) else {
            continue;
        };
        let Some(m) = scene.materials.get(p.material as usize) else {
            continue;
        };
        let opaque = m.alpha_mode == crate::scene::AlphaMode::Opaque;
        if !m.is_emissive() || m.emissive_tex.is_some() || !opaque {
            continue;
        }
        let world_bounds = p.bounds.transformed(&inst.world);
        if world_bounds.is_empty() || world_bounds.extent().max_element() > voxel_size {
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
        let mut e = EmitterLight {
            instance: i,
            emission: m.emissive,
            two_sided: m.double_sided,
            triangles,
            position: Vec3::ZERO,
            axis: Vec3::NEG_Y,
            lobe: 0.0,
            uniform: 0.0,
        };
        e.place(&inst.world);
        if e.lobe + e.uniform > 0.0 {
            found.push(e);
        }
    }
    found.sort_by(|a, b| luminance(b.power()).total_cmp(&luminance(a.power())));
    found.truncate(MAX_EMITTER_LIGHTS);
    // Instance order, so that the lights' order does not depend on their powers' ties.
    found.sort_by_key(|e| e.instance);
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    fn square(side: f32, two_sided: bool) -> EmitterLight {
        let s = 0.5 * side;
        // Facing -Y (counter-clockwise seen from below).
        let q = [
            Vec3::new(-s, 0.0, -s),
            Vec3::new(s, 0.0, -s),
            Vec3::new(s, 0.0, s),
            Vec3::new(-s, 0.0, s),
        ];
        let mut e = EmitterLight {
            instance: 0,
            emission: Vec3::splat(2.0),
            two_sided,
            triangles: vec![[q[0], q[1], q[2]], [q[0], q[2], q[3]]],
            position: Vec3::ZERO,
            axis: Vec3::ZERO,
            lobe: 0.0,
            uniform: 0.0,
        };
        e.place(&Mat4::IDENTITY);
        e
    }

    #[test]
    fn a_flat_emitter_is_a_cosine_lobe_along_its_front_normal() {
        let e = square(0.1, false);
        assert!((e.axis - Vec3::NEG_Y).length() < 1e-6, "axis {}", e.axis);
        assert!((e.lobe - 0.01).abs() < 1e-7 && e.uniform.abs() < 1e-9);
        // Le A cos: 2 x 0.01 x cos 60 degrees below, nothing above.
        let d = Vec3::new(3f32.sqrt() * 0.5, -0.5, 0.0);
        assert!((e.intensity(d).x - 0.01).abs() < 1e-6);
        assert_eq!(e.intensity(Vec3::Y).x, 0.0);
        // pi Le A.
        assert!((e.power().x - std::f32::consts::PI * 0.02).abs() < 1e-6);
    }

    #[test]
    fn a_two_sided_emitter_lights_both_sides_with_twice_the_power() {
        let e = square(0.1, true);
        assert_eq!(e.intensity(Vec3::Y), e.intensity(Vec3::NEG_Y));
        assert!((e.power().x - 2.0 * std::f32::consts::PI * 0.02).abs() < 1e-6);
    }

    #[test]
    fn a_closed_emitter_radiates_evenly_with_its_faces_power() {
        // A cube of side 0.1 (six faces facing out): no mean normal, intensity Le A / 4.
        let mut tris = Vec::new();
        for axis in 0..3 {
            for sign in [-1.0f32, 1.0] {
                let n = Vec3::AXES[axis] * sign;
                let (u, v) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3]);
                let (u, v) = if sign > 0.0 { (u, v) } else { (v, u) };
                let c = n * 0.05;
                let q = [
                    c - 0.05 * u - 0.05 * v,
                    c + 0.05 * u - 0.05 * v,
                    c + 0.05 * u + 0.05 * v,
                    c - 0.05 * u + 0.05 * v,
                ];
                tris.push([q[0], q[1], q[2]]);
                tris.push([q[0], q[2], q[3]]);
            }
        }
        let mut e = square(0.1, false);
        e.triangles = tris;
        e.place(&Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0)));
        assert!(e.lobe < 1e-6, "lobe {}", e.lobe);
        assert!((e.position - Vec3::new(1.0, 2.0, 3.0)).length() < 1e-5);
        assert!((e.uniform - 0.06 / 4.0).abs() < 1e-6);
        assert!((e.power().x - std::f32::consts::PI * 2.0 * 0.06).abs() < 1e-5);
    }

    #[test]
    fn a_mirrored_emitter_faces_where_its_winding_says() {
        // A mirror through the XZ plane turns the -Y face to +Y; the winding flips with it.
        let mut e = square(0.1, false);
        e.place(&Mat4::from_scale(Vec3::new(1.0, -1.0, 1.0)));
        assert!((e.axis - Vec3::Y).length() < 1e-6, "axis {}", e.axis);
        // Scaled by 2: four times the area.
        e.place(&Mat4::from_scale(Vec3::splat(2.0)));
        assert!((e.lobe - 0.04).abs() < 1e-6);
    }
}
