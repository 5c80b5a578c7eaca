//! Light views for shadow maps: an orthographic view per directional light fitted to the scene,
//! a perspective view per spot light covering its outer cone, six 90-degree views per point
//! light (+X, -X, +Y, -Y, +Z, -Z, widened a little so filtering near a face edge stays inside).

use super::gpu::ShadowView;
use crate::scene::{Aabb, Light, LightKind};
use glam::{Mat4, Vec3, Vec4};

/// The widest filter an area light's soft shadows take, as a fraction of the shadow map's
/// side (half width); their views are widened by it so that filtering near a face's edge
/// stays inside the face.
pub const SOFT_SHADOW_SHARE: f32 = 1.0 / 16.0;

/// [`SOFT_SHADOW_SHARE`] in texels.
pub fn soft_shadow_texels(resolution: u32) -> u32 {
    (resolution as f32 * SOFT_SHADOW_SHARE).ceil() as u32
}

/// Views of one light and where they start in the shadow array.
pub struct LightViews {
    pub first: u32,
    pub views: Vec<ShadowView>,
}

fn any_up(dir: Vec3) -> Vec3 {
    if dir.y.abs() < 0.99 {
        Vec3::Y
    } else {
        Vec3::Z
    }
}

/// Half the diagonal of the bounds; 1 for a point or empty scene (no scale to follow).
fn scene_radius(bounds: &Aabb) -> f32 {
    let r = bounds.extent().length() * 0.5;
    if r.is_finite() && r > 0.0 {
        r
    } else {
        1.0
    }
}

/// Depth range of a perspective light view: from a small fraction of the scene to its far side.
fn near_far(eye: Vec3, bounds: &Aabb) -> (f32, f32) {
    let radius = scene_radius(bounds);
    let far_corner = bounds
        .corners()
        .iter()
        .map(|c| (*c - eye).length())
        .fold(0.0f32, f32::max);
    // Relative to the scene only: an absolute floor would change shadows with the units.
    let near = radius * 2e-3;
    (near, (far_corner * 1.01).max(near * 10.0))
}

fn perspective(eye: Vec3, dir: Vec3, fov: f32, bounds: &Aabb, resolution: u32) -> ShadowView {
    let (near, far) = near_far(eye, bounds);
    let view = Mat4::look_to_rh(eye, dir, any_up(dir));
    let proj = Mat4::perspective_rh(fov, 1.0, near, far);
    ShadowView {
        view_proj: proj * view,
        info: Vec4::new(1.0, 2.0 * (fov * 0.5).tan() / resolution as f32, near, far),
    }
}

/// An orthographic view along `d` fitted to the box `bounds` as the light sees it (its
/// corners' extent across the light, widened by the filter's reach), not to the sphere around
/// it: a flat ground seen by a high sun fills the map instead of a square as wide as its
/// diagonal, so its texels are up to twice as fine along each side.
fn directional(
    d: Vec3,
    bounds: &Aabb,
    center: Vec3,
    radius: f32,
    resolution: u32,
    pcf_radius: u32,
) -> ShadowView {
    let eye = center - d * 2.0 * radius;
    let view = Mat4::look_to_rh(eye, d, any_up(d));
    let (mut lo, mut hi) = (Vec3::splat(-radius), Vec3::splat(radius));
    if !bounds.is_empty() {
        lo = Vec3::splat(f32::INFINITY);
        hi = Vec3::splat(f32::NEG_INFINITY);
        for c in bounds.corners() {
            let p = view.transform_point3(c);
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    // A flat box seen edge-on still needs a texel's width; the filter reads past the edge.
    let side = (hi - lo).truncate().max(glam::Vec2::splat(radius * 1e-3));
    let margin = side * (pcf_radius + 2) as f32 / resolution as f32;
    let (lo2, hi2) = (lo.truncate() - margin, lo.truncate() + side + margin);
    let proj = Mat4::orthographic_rh(lo2.x, hi2.x, lo2.y, hi2.y, 0.5 * radius, 3.5 * radius);
    let texel = (hi2 - lo2).max_element() / resolution as f32;
    ShadowView {
        view_proj: proj * view,
        info: Vec4::new(0.0, texel, 0.0, 0.0),
    }
}

/// Whether anything inside `bounds` can land in the view (false only when all eight corners are
/// beyond one clip plane), so a caster moving there must draw the view again.
pub fn may_see(view_proj: &Mat4, bounds: &Aabb) -> bool {
    if bounds.is_empty() {
        return false;
    }
    let clip = bounds.corners().map(|c| *view_proj * c.extend(1.0));
    let outside = |f: &dyn Fn(&Vec4) -> bool| clip.iter().all(f);
    !(outside(&|p| p.x < -p.w)
        || outside(&|p| p.x > p.w)
        || outside(&|p| p.y < -p.w)
        || outside(&|p| p.y > p.w)
        || outside(&|p| p.z < 0.0)
        || outside(&|p| p.z > p.w))
}

/// The views of every light, in light order. `pcf_radius` is in texels.
pub fn light_views(
    lights: &[Light],
    bounds: &Aabb,
    resolution: u32,
    pcf_radius: u32,
) -> Vec<LightViews> {
    let mut next = 0u32;
    let mut out = Vec::new();
    let (center, radius) = if bounds.is_empty() {
        (Vec3::ZERO, 1.0)
    } else {
        (bounds.center(), scene_radius(bounds))
    };
    for l in lights {
        let views = match l.kind {
            LightKind::Directional => vec![directional(
                l.direction,
                bounds,
                center,
                radius,
                resolution,
                pcf_radius,
            )],
            LightKind::Spot { outer_cone, .. } => {
                let margin = (2 * pcf_radius + 2) as f32 / resolution as f32;
                let half = (outer_cone.tan() * (1.0 + margin)).atan().clamp(0.01, 1.5);
                vec![perspective(
                    l.position,
                    l.direction,
                    2.0 * half,
                    bounds,
                    resolution,
                )]
            }
            LightKind::Point => {
                let margin = (2 * pcf_radius + 2) as f32 / resolution as f32;
                let fov = 2.0 * (1.0 + margin).atan();
                [
                    Vec3::X,
                    Vec3::NEG_X,
                    Vec3::Y,
                    Vec3::NEG_Y,
                    Vec3::Z,
                    Vec3::NEG_Z,
                ]
                .iter()
                .map(|&axis| perspective(l.position, axis, fov, bounds, resolution))
                .collect()
            }
        };
        let first = next;
        next += views.len() as u32;
        out.push(LightViews { first, views });
    }
    out
}

#[cfg(test)]
mod frustum_tests {
    use super::*;

    #[test]
    fn a_box_is_seen_unless_wholly_beyond_one_plane() {
        // A spot-like view at the origin looking down -Z, 90 degrees, depth 0.1 to 10.
        let vp = Mat4::perspective_rh(std::f32::consts::FRAC_PI_2, 1.0, 0.1, 10.0)
            * Mat4::look_to_rh(Vec3::ZERO, Vec3::NEG_Z, Vec3::Y);
        let b = |min: [f32; 3], max: [f32; 3]| Aabb {
            min: Vec3::from(min),
            max: Vec3::from(max),
        };
        assert!(may_see(&vp, &b([-0.5, -0.5, -3.0], [0.5, 0.5, -2.0])));
        // Straddling the side plane still counts.
        assert!(may_see(&vp, &b([1.5, -0.5, -2.5], [3.0, 0.5, -2.0])));
        // Behind the light, beyond the far plane, or off to the side: not seen.
        assert!(!may_see(&vp, &b([-0.5, -0.5, 1.0], [0.5, 0.5, 2.0])));
        assert!(!may_see(&vp, &b([-0.5, -0.5, -30.0], [0.5, 0.5, -20.0])));
        assert!(!may_see(&vp, &b([5.0, -0.5, -3.0], [6.0, 0.5, -2.0])));
        assert!(!may_see(&vp, &Aabb::EMPTY));
    }

    /// A sun over a ground 50 m across and 10 cm thick: its view holds every corner of the
    /// ground with the filter's margin, and its texels cover less than three quarters of the
    /// ground a square around the bounding sphere (70.7 m across) gave each.
    #[test]
    fn a_suns_view_is_fitted_to_the_ground_as_it_sees_it() {
        let ground = Aabb {
            min: Vec3::new(-25.0, -0.1, -25.0),
            max: Vec3::new(25.0, 0.0, 25.0),
        };
        let sphere_texel = ground.extent().length() / 2048.0;
        for (elevation, azimuth) in [(90.0f32, 0.0f32), (45.0, 0.0), (45.0, 30.0), (15.0, 60.0)] {
            let (e, a) = (elevation.to_radians(), azimuth.to_radians());
            let d = -Vec3::new(e.cos() * a.cos(), e.sin(), e.cos() * a.sin());
            let sun = Light {
                name: None,
                kind: LightKind::Directional,
                radiance: Vec3::ONE,
                range: None,
                position: Vec3::ZERO,
                direction: d,
            };
            let v = &light_views(&[sun], &ground, 2048, 1)[0].views[0];
            for c in ground.corners() {
                let p = v.view_proj.project_point3(c);
                // Inside by the margin: 3 texels of 2048 in clip units.
                assert!(
                    p.x.abs() < 1.0 - 5.0 / 2048.0 && p.y.abs() < 1.0 - 5.0 / 2048.0,
                    "sun {elevation}, {azimuth}: corner {c} at {p}"
                );
                assert!(
                    (0.0..=1.0).contains(&p.z),
                    "sun {elevation}, {azimuth}: depth {p}"
                );
            }
            // The view's width along each of its axes (an orthographic row scales by 2 / width).
            let width = |row: usize| 2.0 / v.view_proj.row(row).truncate().length();
            let (tx, ty) = (width(0) / 2048.0, width(1) / 2048.0);
            assert!(
                tx * ty < 0.75 * sphere_texel * sphere_texel && v.info.y >= tx.max(ty) * 0.999,
                "sun {elevation}, {azimuth}: texels {tx} x {ty} against {sphere_texel}"
            );
        }
    }
}
