//! Zero-thickness surfaces reflect on both sides (CONVENTIONS.md: every surface does): a voxel
//! of a surface with open space behind it holds the light of its back apart
//! (`GiSettings::backs`, glsl/voxel_data.glsl's `open_back`).

mod common;
mod gpu;
use glam::Vec3;
use gpu::*;
use voxgi::gi::GiSettings;
use voxgi::render::{Mode, RenderSettings};
use voxgi::scene::{LightKind, Scene};

fn settings(size: u32, backs: bool, bounces: u32, mode: Mode) -> RenderSettings {
    RenderSettings {
        width: size,
        height: size,
        shadow_resolution: 256,
        mode,
        gi: GiSettings {
            voxels: 32,
            bounces,
            backs,
            ..GiSettings::default()
        },
        ..Default::default()
    }
}

/// A quad with its front towards `facing`, whatever order `corners` go round in.
fn quad_facing(s: &mut Scene, mut corners: [Vec3; 4], facing: Vec3, material: u32) {
    let n = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
    if n.dot(facing) < 0.0 {
        corners.reverse();
    }
    quad(s, corners, material);
}

/// A closed 4 x 2.5 x 4 m room of six single quads, all facing in or all facing out, lit by a
/// point light inside and seen from inside.
fn quad_room(outward: bool) -> Scene {
    let mut s = empty_scene();
    let grey = lambert(&mut s, Vec3::splat(0.6));
    let (a, h) = (2.0, 2.5);
    let side = if outward { -1.0 } else { 1.0 };
    let v = Vec3::new;
    let faces = [
        (
            [v(-a, 0.0, -a), v(a, 0.0, -a), v(a, 0.0, a), v(-a, 0.0, a)],
            Vec3::Y,
        ),
        (
            [v(-a, h, -a), v(a, h, -a), v(a, h, a), v(-a, h, a)],
            -Vec3::Y,
        ),
        (
            [v(-a, 0.0, -a), v(-a, 0.0, a), v(-a, h, a), v(-a, h, -a)],
            Vec3::X,
        ),
        (
            [v(a, 0.0, -a), v(a, 0.0, a), v(a, h, a), v(a, h, -a)],
            -Vec3::X,
        ),
        (
            [v(-a, 0.0, -a), v(a, 0.0, -a), v(a, h, -a), v(-a, h, -a)],
            Vec3::Z,
        ),
        (
            [v(-a, 0.0, a), v(a, 0.0, a), v(a, h, a), v(-a, h, a)],
            -Vec3::Z,
        ),
    ];
    for (corners, inward) in faces {
        quad_facing(&mut s, corners, inward * side, grey);
    }
    s.lights.push(light(
        LightKind::Point,
        Vec3::splat(4.0),
        v(0.6, 1.9, -0.7),
        Vec3::NEG_Y,
    ));
    look_at(&mut s, v(-0.3, 1.3, 1.8), v(0.4, 0.8, -2.0), 70.0);
    s
}

/// The room of quads facing out gives the indirect light of the same room facing in: the
/// quads' backs hold what their fronts would (without them its walls reflect nothing into it).
#[test]
fn a_room_of_quads_facing_out_is_lit_as_one_facing_in() {
    let size = 48;
    let inward = render(&quad_room(false), settings(size, true, 2, Mode::Indirect));
    let outward = render(&quad_room(true), settings(size, true, 2, Mode::Indirect));
    let without = render(&quad_room(true), settings(size, false, 2, Mode::Indirect));
    let (e, e_without) = (rel_mse(&outward, &inward), rel_mse(&without, &inward));
    eprintln!("facing out against facing in: relMSE {e:.5}, without backs {e_without:.5}");
    let mean = |img: &voxgi::output::RadianceImage| {
        img.pixels.iter().map(|p| p[0] as f64).sum::<f64>() / img.pixels.len() as f64
    };
    let (m_in, m_out) = (mean(&inward), mean(&outward));
    eprintln!("mean indirect: in {m_in:.4}, out {m_out:.4}");
    assert!(!outward.has_non_finite() && !without.has_non_finite());
    assert!(
        m_in > 0.01,
        "the room facing in has indirect light ({m_in})"
    );
    assert!(e < 0.01, "relMSE {e}");
    assert!(e_without > 0.5, "without backs relMSE {e_without}");
}

/// Voxels, lit directly only (one bounce), under a sun straight down: a single quad facing down
/// holds the sun on its back, albedo / pi x E, and nothing on its front; a slab of two quads
/// less than a voxel apart (in two voxels) holds nothing on either back, its underside's back
/// being the slab; without `backs` there is no back volume.
#[test]
fn a_quad_facing_down_holds_the_sun_on_its_back_and_a_slab_does_not() {
    let mut s = empty_scene();
    let albedo = 0.5;
    let m = lambert(&mut s, Vec3::splat(albedo));
    // 4 m across: 32 voxels of 4 x 32 / 30 m (one voxel of margin each side).
    let vs = 4.0 * 32.0 / 30.0 / 32.0;
    // The slab spans 0 to 0.75 voxel, centred on the grid's middle, a voxel boundary.
    let t = 0.75 * vs;
    let v = Vec3::new;
    let square =
        |x0: f32, x1: f32, y: f32| [v(x0, y, -1.0), v(x1, y, -1.0), v(x1, y, 1.0), v(x0, y, 1.0)];
    quad_facing(&mut s, square(-2.0, -0.5, t / 2.0 + 0.25 * vs), -Vec3::Y, m);
    quad_facing(&mut s, square(0.5, 2.0, t), Vec3::Y, m);
    quad_facing(&mut s, square(0.5, 2.0, 0.0), -Vec3::Y, m);
    let e = 2.0;
    s.lights.push(light(
        LightKind::Directional,
        Vec3::splat(e),
        Vec3::ZERO,
        Vec3::NEG_Y,
    ));
    top_camera(&mut s, 5.0, 60.0);
    let d = render_voxels(&s, settings(16, true, 1, Mode::Full));
    let backs = d
        .back_radiance
        .as_ref()
        .expect("the backs' volume read back");
    let radiance = d.radiance.as_ref().expect("radiance read back");
    let n = d.resolution;
    let want = albedo / std::f32::consts::PI * e;
    let (mut quad_voxels, mut slab_bottoms) = (0, 0);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let i = d.index(x, y, z);
                if !d.filled[i] || d.normal[i].y > -0.9 {
                    continue;
                }
                // Away from the edges, where the shadow maps' filter and the partly covered
                // voxels are.
                let wx = (x as f32 + 0.5) / n as f32 * 4.0 * 32.0 / 30.0 - 2.0 * 32.0 / 30.0;
                let wz = (z as f32 + 0.5) / n as f32 * 4.0 * 32.0 / 30.0 - 2.0 * 32.0 / 30.0;
                if wz.abs() > 0.8 {
                    continue;
                }
                if (-1.7..=-0.8).contains(&wx) {
                    quad_voxels += 1;
                    let b = backs[i].x;
                    assert!(
                        (b - want).abs() <= 0.01 * want,
                        "back {b} at {x} {y} {z}, want {want}"
                    );
                    assert!(
                        radiance[i].x.abs() <= 1e-4 * want,
                        "front {}",
                        radiance[i].x
                    );
                } else if (0.8..=1.7).contains(&wx) {
                    slab_bottoms += 1;
                    assert!(
                        d.filled[d.index(x, y + 1, z)],
                        "the slab's top above {x} {y} {z}"
                    );
                    assert_eq!(backs[i], Vec3::ZERO, "the slab's underside at {x} {y} {z}");
                    assert!(
                        radiance[i].x.abs() <= 1e-4 * want,
                        "front {}",
                        radiance[i].x
                    );
                }
            }
        }
    }
    assert!(
        quad_voxels > 20 && slab_bottoms > 20,
        "{quad_voxels} {slab_bottoms}"
    );
    let d = render_voxels(&s, settings(16, false, 1, Mode::Full));
    assert!(d.back_radiance.is_none());
}
