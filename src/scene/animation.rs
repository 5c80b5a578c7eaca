//! Moving scenes: glTF node animations (translation, rotation, scale) and a node spun about its
//! vertical axis, as poses over time. A pose gives the world transform of every node that
//! moves; the renderer voxelizes those nodes every frame, apart from the static voxels.

use super::{Aabb, Scene};
use glam::{DMat4, DQuat, DVec3, Mat4, Quat, Vec3};

/// A node of the chosen glTF scene: where it hangs and its rest pose (local TRS).
#[derive(Clone, Debug)]
pub struct Node {
    pub name: Option<String>,
    pub parent: Option<usize>,
    /// In f64 (as the file writes it): a node far from the origin keeps its place.
    pub translation: DVec3,
    pub rotation: Quat,
    pub scale: Vec3,
    /// Given by a matrix: glTF does not animate such nodes, and neither does a spin
    /// (the matrix may not decompose into TRS).
    pub matrix: Option<DMat4>,
}

/// Which part of a node's transform a channel drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Property {
    Translation,
    Rotation,
    Scale,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    Step,
    Linear,
    /// Hermite spline: each key holds an in-tangent, the value and an out-tangent.
    CubicSpline,
}

/// One animated property of one node.
#[derive(Clone, Debug)]
pub struct Channel {
    pub node: usize,
    pub property: Property,
    pub interpolation: Interpolation,
    /// Key times in seconds, increasing.
    pub times: Vec<f32>,
    /// 3 (translation, scale) or 4 (rotation xyzw) components per key; three times that for
    /// cubic splines (in-tangent, value, out-tangent).
    pub values: Vec<f32>,
}

#[derive(Clone, Debug)]
pub struct Animation {
    pub name: Option<String>,
    pub channels: Vec<Channel>,
}

impl Animation {
    /// The last key time of any channel.
    pub fn duration(&self) -> f32 {
        self.channels
            .iter()
            .filter_map(|c| c.times.last().copied())
            .fold(0.0, f32::max)
    }
}

impl Channel {
    fn width(&self) -> usize {
        match self.property {
            Property::Rotation => 4,
            _ => 3,
        }
    }

    /// Component `c` of element `e` of key `k` (e: 0 in-tangent, 1 value, 2 out-tangent for
    /// cubic splines; always 0 otherwise).
    fn at(&self, k: usize, e: usize, c: usize) -> f32 {
        let w = self.width();
        let per_key = if self.interpolation == Interpolation::CubicSpline {
            3 * w
        } else {
            w
        };
        self.values[k * per_key + e * w + c]
    }

    fn key(&self, k: usize) -> [f32; 4] {
        let e = (self.interpolation == Interpolation::CubicSpline) as usize;
        std::array::from_fn(|c| {
            if c < self.width() {
                self.at(k, e, c)
            } else {
                0.0
            }
        })
    }

    /// The property's value at time `t` (clamped to the keys), xyz or a unit quaternion xyzw.
    pub fn sample(&self, t: f32) -> [f32; 4] {
        let n = self.times.len();
        if n == 1 || t <= self.times[0] {
            return self.key(0);
        }
        if t >= self.times[n - 1] {
            return self.key(n - 1);
        }
        // The key interval holding t.
        let k = self.times.partition_point(|&k| k <= t) - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let dt = t1 - t0;
        let s = if dt > 0.0 { (t - t0) / dt } else { 0.0 };
        let rotation = self.property == Property::Rotation;
        match self.interpolation {
            Interpolation::Step => self.key(k),
            Interpolation::Linear if rotation => {
                let a = Quat::from_array(self.key(k));
                let b = Quat::from_array(self.key(k + 1));
                a.normalize().slerp(b.normalize(), s).to_array()
            }
            Interpolation::Linear => {
                let (a, b) = (self.key(k), self.key(k + 1));
                std::array::from_fn(|c| a[c] + (b[c] - a[c]) * s)
            }
            Interpolation::CubicSpline => {
                let (s2, s3) = (s * s, s * s * s);
                let mut v: [f32; 4] = std::array::from_fn(|c| {
                    if c >= self.width() {
                        return 0.0;
                    }
                    let p0 = self.at(k, 1, c);
                    let m0 = self.at(k, 2, c) * dt;
                    let p1 = self.at(k + 1, 1, c);
                    let m1 = self.at(k + 1, 0, c) * dt;
                    (2.0 * s3 - 3.0 * s2 + 1.0) * p0
                        + (s3 - 2.0 * s2 + s) * m0
                        + (-2.0 * s3 + 3.0 * s2) * p1
                        + (s3 - s2) * m1
                });
                if rotation {
                    v = Quat::from_array(v).normalize().to_array();
                }
                v
            }
        }
    }
}

/// A node turned about the vertical (+Y) axis through its origin, in its parent's frame.
#[derive(Clone, Debug)]
pub struct Spin {
    pub node: usize,
    pub degrees_per_second: f32,
}

impl Spin {
    /// The turn about +Y after `t` seconds, radians (f64: hours in, the angle keeps its
    /// micro-radians).
    pub fn angle(&self, t: f32) -> f64 {
        (self.degrees_per_second as f64 * t as f64).to_radians()
    }
}

/// What moves in a scene: its animations (all of them play, looped over the longest) and
/// an optional spin.
#[derive(Clone, Debug, Default)]
pub struct Motion {
    pub spin: Option<Spin>,
    pub animate: bool,
}

/// Spin rate of `--spin`: a quarter turn per second.
pub const SPIN_DEGREES_PER_SECOND: f32 = 90.0;

impl Scene {
    /// The node named `name` (the first one, in file order), with a clear error otherwise.
    pub fn node_named(&self, name: &str) -> Result<usize, String> {
        if let Some(i) = self
            .nodes
            .iter()
            .position(|n| n.name.as_deref() == Some(name))
        {
            return Ok(i);
        }
        let names: Vec<&str> = self
            .nodes
            .iter()
            .filter_map(|n| n.name.as_deref())
            .take(20)
            .collect();
        Err(if names.is_empty() {
            format!(
                "{}: no node named {name:?} (its nodes have no names)",
                self.source.display()
            )
        } else {
            format!(
                "{}: no node named {name:?} (the named nodes: {}{})",
                self.source.display(),
                names.join(", "),
                if names.len() == 20 { ", ..." } else { "" }
            )
        })
    }

    /// A spin of the node named `name`, or an error naming the file and the problem.
    pub fn spin(&self, name: &str) -> Result<Spin, String> {
        let node = self.node_named(name)?;
        Ok(Spin {
            node,
            degrees_per_second: SPIN_DEGREES_PER_SECOND,
        })
    }
}

impl Motion {
    /// Whether anything moves.
    pub fn moves(&self, scene: &Scene) -> bool {
        !self.moving_nodes(scene).is_empty()
    }

    /// The time after which the motion repeats: the longest animation, or a full turn.
    pub fn period(&self, scene: &Scene) -> f32 {
        let anim = if self.animate {
            scene
                .animations
                .iter()
                .map(Animation::duration)
                .fold(0.0, f32::max)
        } else {
            0.0
        };
        let spin = self
            .spin
            .as_ref()
            .filter(|s| s.degrees_per_second != 0.0)
            .map_or(0.0, |s| 360.0 / s.degrees_per_second.abs());
        anim.max(spin)
    }

    /// Nodes with meshes whose world transform changes over time: the driven ones and their
    /// descendants.
    pub fn moving_nodes(&self, scene: &Scene) -> Vec<usize> {
        let mut has_mesh = vec![false; scene.nodes.len()];
        for i in &scene.instances {
            if let Some(m) = has_mesh.get_mut(i.node) {
                *m = true;
            }
        }
        let mut driven = vec![false; scene.nodes.len()];
        if self.animate {
            for c in scene.animations.iter().flat_map(|a| &a.channels) {
                driven[c.node] = true;
            }
        }
        if let Some(s) = &self.spin {
            driven[s.node] = true;
        }
        (0..scene.nodes.len())
            .filter(|&n| has_mesh[n])
            .filter(|&n| {
                let mut at = Some(n);
                while let Some(i) = at {
                    if driven[i] {
                        return true;
                    }
                    at = scene.nodes[i].parent;
                }
                false
            })
            .collect()
    }

    /// World transforms (relative to `Scene::origin`) of the moving nodes at time `t`
    /// (seconds; animations loop over their longest duration).
    pub fn pose(&self, scene: &Scene, t: f32) -> Vec<(usize, Mat4)> {
        let n = scene.nodes.len();
        let mut t_of = vec![None::<Vec3>; n];
        let mut r_of = vec![None::<Quat>; n];
        let mut s_of = vec![None::<Vec3>; n];
        if self.animate {
            let period = scene
                .animations
                .iter()
                .map(Animation::duration)
                .fold(0.0, f32::max);
            let ta = if period > 0.0 {
                t.rem_euclid(period)
            } else {
                0.0
            };
            for c in scene.animations.iter().flat_map(|a| &a.channels) {
                let v = c.sample(ta);
                match c.property {
                    Property::Translation => t_of[c.node] = Some(Vec3::new(v[0], v[1], v[2])),
                    Property::Rotation => r_of[c.node] = Some(Quat::from_array(v)),
                    Property::Scale => s_of[c.node] = Some(Vec3::new(v[0], v[1], v[2])),
                }
            }
        }
        let local = |i: usize| -> DMat4 {
            let node = &scene.nodes[i];
            if let Some(m) = node.matrix {
                // A matrix need not split into translation, rotation and scale: turned as a
                // whole about the vertical through its origin.
                return match self.spin.as_ref().filter(|s| s.node == i) {
                    Some(s) => {
                        let at = m.w_axis.truncate();
                        DMat4::from_translation(at)
                            * DMat4::from_rotation_y(s.angle(t))
                            * DMat4::from_translation(-at)
                            * m
                    }
                    None => m,
                };
            }
            let mut r = r_of[i].unwrap_or(node.rotation).as_dquat();
            if let Some(s) = self.spin.as_ref().filter(|s| s.node == i) {
                r = DQuat::from_rotation_y(s.angle(t)) * r;
            }
            DMat4::from_scale_rotation_translation(
                s_of[i].unwrap_or(node.scale).as_dvec3(),
                r,
                t_of[i].map_or(node.translation, |t| t.as_dvec3()),
            )
        };
        // World transforms in f64 down each node's chain of parents, relative to the origin.
        let mut world: Vec<Option<DMat4>> = vec![None; n];
        fn resolve(
            i: usize,
            scene: &Scene,
            world: &mut Vec<Option<DMat4>>,
            local: &dyn Fn(usize) -> DMat4,
        ) -> DMat4 {
            if let Some(w) = world[i] {
                return w;
            }
            let parent = match scene.nodes[i].parent {
                Some(p) => resolve(p, scene, world, local),
                None => DMat4::from_translation(-scene.origin),
            };
            let w = parent * local(i);
            world[i] = Some(w);
            w
        }
        self.moving_nodes(scene)
            .into_iter()
            .map(|i| (i, resolve(i, scene, &mut world, &local).as_mat4()))
            .collect()
    }

    /// Readies `scene` to move: widens its bounds to what the motion sweeps (the voxel grid and
    /// the shadow views are fitted to them) and returns the nodes to voxelize every frame.
    pub fn prepare(&self, scene: &mut Scene) -> Vec<usize> {
        let moving = self.moving_nodes(scene);
        if !moving.is_empty() {
            scene.bounds = self.swept_bounds(scene);
        }
        moving
    }

    /// The scene's bounds with everything the motion sweeps (sampled over one period), so
    /// that a grid fitted to them holds the moving nodes at every time.
    pub fn swept_bounds(&self, scene: &Scene) -> Aabb {
        let moving = self.moving_nodes(scene);
        if moving.is_empty() {
            return scene.bounds;
        }
        let period = self.period(scene);
        let steps = if period > 0.0 { 96 } else { 1 };
        let mut swept = Aabb::EMPTY;
        for k in 0..steps {
            let t = period * k as f32 / steps as f32;
            for (node, world) in self.pose(scene, t) {
                for inst in scene.instances.iter().filter(|i| i.node == node) {
                    swept = swept.union(
                        &scene.primitives[inst.primitive as usize]
                            .bounds
                            .transformed(&world),
                    );
                }
            }
        }
        if swept.is_empty() {
            return scene.bounds;
        }
        // Between samples a turning corner bulges out by under 0.1% of its radius.
        let pad = swept.extent() * 0.005;
        let swept = Aabb {
            min: swept.min - pad,
            max: swept.max + pad,
        };
        scene.bounds.union(&swept)
    }
}

/// Pose of the rest transforms with nothing moving, for tests.
pub fn rest_world(scene: &Scene, node: usize) -> DMat4 {
    let mut m = DMat4::IDENTITY;
    let mut at = Some(node);
    while let Some(i) = at {
        let n = &scene.nodes[i];
        let local = match n.matrix {
            Some(m) => m,
            None => DMat4::from_scale_rotation_translation(
                n.scale.as_dvec3(),
                n.rotation.as_dquat(),
                n.translation,
            ),
        };
        m = local * m;
        at = n.parent;
    }
    DMat4::from_translation(-scene.origin) * m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn channel(
        property: Property,
        interpolation: Interpolation,
        times: &[f32],
        v: &[f32],
    ) -> Channel {
        Channel {
            node: 0,
            property,
            interpolation,
            times: times.to_vec(),
            values: v.to_vec(),
        }
    }

    #[test]
    fn linear_step_and_clamped_sampling() {
        let c = channel(
            Property::Translation,
            Interpolation::Linear,
            &[1.0, 3.0],
            &[0.0, 0.0, 0.0, 4.0, -2.0, 8.0],
        );
        assert_eq!(c.sample(0.0), [0.0, 0.0, 0.0, 0.0]);
        assert_eq!(c.sample(2.0), [2.0, -1.0, 4.0, 0.0]);
        assert_eq!(c.sample(9.0), [4.0, -2.0, 8.0, 0.0]);
        let s = Channel {
            interpolation: Interpolation::Step,
            ..c
        };
        assert_eq!(s.sample(2.9), [0.0, 0.0, 0.0, 0.0]);
        assert_eq!(s.sample(3.0), [4.0, -2.0, 8.0, 0.0]);
    }

    #[test]
    fn rotations_slerp_at_constant_speed() {
        let a = Quat::IDENTITY;
        let b = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
        let mut v = a.to_array().to_vec();
        v.extend(b.to_array());
        let c = channel(Property::Rotation, Interpolation::Linear, &[0.0, 1.0], &v);
        let q = Quat::from_array(c.sample(0.25));
        let want = Quat::from_rotation_y(std::f32::consts::FRAC_PI_8);
        assert!(q.angle_between(want) < 1e-5, "{q:?} vs {want:?}");
    }

    #[test]
    fn cubic_spline_passes_its_keys_and_follows_its_tangents() {
        // Keys 0 -> 1 over one second with zero tangents: smoothstep.
        let v = [
            0.0, 0.0, 0.0, /* in */ 0.0, 0.0, 0.0, /* value */ 0.0, 0.0,
            0.0, /* out */
            0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 0.0, 0.0, 0.0,
        ];
        let c = channel(Property::Scale, Interpolation::CubicSpline, &[0.0, 1.0], &v);
        assert_eq!(c.sample(1.0), [1.0, 2.0, 3.0, 0.0]);
        let mid = c.sample(0.5);
        assert!((mid[0] - 0.5).abs() < 1e-6 && (mid[2] - 1.5).abs() < 1e-6);
        let q = c.sample(0.25)[0];
        let smooth = 3.0 * 0.0625 - 2.0 * 0.015625;
        assert!((q - smooth).abs() < 1e-6, "{q} vs {smooth}");
    }
}
