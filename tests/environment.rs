//! The environment (CONVENTIONS.md, "Environment") in the real-time renderer, against what it
//! must give and against the reference path tracer: a white sphere under a uniform sky, an open
//! floor, a floor under a roof open on one side, the equirectangular mapping and its turn,
//! the background, and bad files.

mod common;
mod gpu;
use glam::Vec3;
use gpu::*;
use std::f32::consts::PI;
use voxgi::gi::GiSettings;
use voxgi::output::RadianceImage;
use voxgi::reference::{self, ReferenceSettings};
use voxgi::render::{Mode, RenderSettings};
use voxgi::scene::environment::EnvImage;
use voxgi::scene::{Environment, Scene};

fn settings(size: u32) -> RenderSettings {
    RenderSettings {
        width: size,
        height: size,
        shadow_resolution: 256,
        gi: GiSettings {
            voxels: 32,
            ..GiSettings::default()
        },
        ..Default::default()
    }
}

/// Mean radiance of the pixels `keep` accepts.
fn mean_where(img: &RadianceImage, keep: impl Fn(u32, u32) -> bool) -> Vec3 {
    let (mut sum, mut n) = (Vec3::ZERO, 0);
    for y in 0..img.height {
        for x in 0..img.width {
            if keep(x, y) {
                sum += Vec3::from_array(img.at(x, y));
                n += 1;
            }
        }
    }
    sum / n.max(1) as f32
}

/// A closed UV sphere of radius r at the origin.
fn sphere(s: &mut Scene, r: f32, m: u32) {
    let (rings, segments) = (16, 32);
    let p = |i: u32, j: u32| {
        let th = PI * i as f32 / rings as f32;
        let ph = 2.0 * PI * j as f32 / segments as f32;
        Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()) * r
    };
    let mut tris = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1));
            if i != rings - 1 {
                tris.push([a, c, b]);
            }
            if i != 0 {
                tris.push([a, d, c]);
            }
        }
    }
    mesh(s, &tris, m);
}

/// A white (albedo 1) unit sphere under a uniform sky `le`, seen from 4 m.
fn white_sphere_under(le: Vec3) -> Scene {
    let mut s = empty_scene();
    let m = lambert(&mut s, Vec3::ONE);
    sphere(&mut s, 1.0, m);
    look_at(&mut s, Vec3::new(0.0, 1.0, 4.0), Vec3::ZERO, 40.0);
    s.environment = Some(Environment::uniform(le));
    s
}

/// A white (albedo 1) sphere under a uniform sky Le, nothing else: radiance Le everywhere.
#[test]
fn a_white_sphere_under_a_uniform_sky_is_the_sky() {
    let le = Vec3::new(0.5, 1.0, 2.0);
    let s = white_sphere_under(le);
    let img = render(&s, settings(64));
    let centre = mean_where(&img, |x, y| {
        (x as i32 - 32).pow(2) + (y as i32 - 30).pow(2) < 14 * 14
    });
    let corner = mean_where(&img, |x, y| x < 4 && y < 4);
    eprintln!("sphere {centre}, background {corner}, sky {le}");
    assert!(
        (corner - le).abs().max_element() < 1e-3 * le.max_element(),
        "background {corner}"
    );
    // Measured 1% low: the sphere's own voxels close a little of each cone.
    let rel = ((centre - le) / le).abs().max_element();
    assert!(rel < 0.02, "the sphere {centre} against the sky {le}");
}

/// The path tracer's mean radiance over a 16 x 16 image of `s` at 64 spp.
fn path_traced_mean(s: &Scene) -> Vec3 {
    let st = ReferenceSettings {
        width: 16,
        height: 16,
        spp: 64,
        ..Default::default()
    };
    mean_where(&reference::render(s, &st), |_, _| true)
}

/// A 2 m wall facing +X, seen from +X, under the image `sky` turned by `turn` degrees.
fn wall_under(sky: EnvImage, turn: f32) -> Scene {
    let mut s = empty_scene();
    let m = lambert(&mut s, Vec3::splat(0.8));
    wall_facing_x(&mut s, 1.0, m);
    look_at(&mut s, Vec3::new(3.0, 0.0, 0.0), Vec3::ZERO, 20.0);
    s.environment = Some(Environment::image(sky).turned(turn));
    s
}

/// Without cones (`--mode direct`) the lighting pass lights by the environment, unoccluded:
/// the white sphere under a uniform sky is the sky; a wall facing +X under a sky bright only
/// on the +X side (no texel bright enough to be its sun) is lit as the path tracer lights it
/// (within a bound from measurement), and turned half a turn it is dark.
#[test]
fn direct_mode_lights_by_the_environment() {
    let mut st = settings(64);
    st.mode = Mode::Direct;
    let le = Vec3::new(0.5, 1.0, 2.0);
    let s = white_sphere_under(le);
    let img = render(&s, st.clone());
    let centre = mean_where(&img, |x, y| {
        (x as i32 - 32).pow(2) + (y as i32 - 30).pow(2) < 14 * 14
    });
    let rel = ((centre - le) / le).abs().max_element();
    eprintln!("direct mode: sphere {centre} under {le}");
    // Exact but for the environment's f16 texels.
    assert!(rel < 2e-3, "the sphere {centre} against the sky {le}");

    let wall = |turn: f32| {
        let (w, h) = (64u32, 32u32);
        // u > 1/2 is the +X side (CONVENTIONS.md: u = 1/2 + atan2(x, -z) / 2 pi).
        let texels = (0..w * h)
            .map(|i| {
                if i % w >= w / 2 {
                    Vec3::ONE
                } else {
                    Vec3::ZERO
                }
            })
            .collect();
        wall_under(EnvImage::new("half.hdr", w, h, texels), turn)
    };
    let mut st = settings(16);
    st.mode = Mode::Direct;
    let s = wall(0.0);
    let got = mean_where(&render(&s, st.clone()), |_, _| true);
    let want = path_traced_mean(&s);
    let turned = mean_where(&render(&wall(180.0), st), |_, _| true);
    eprintln!("direct mode: wall {got} against the path tracer's {want}, turned {turned}");
    // Measured 0.9% low (the seven cones' texels blur across the bright half's edges) and
    // 0.9% turned.
    assert!(
        ((got - want) / want).abs().max_element() < 0.03,
        "{got} against {want}"
    );
    assert!(
        turned.max_element() < 0.02 * want.max_element(),
        "turned away: {turned}"
    );
}

/// An open floor of albedo a under a uniform sky: irradiance pi Le, radiance a Le.
#[test]
fn an_open_floor_under_a_uniform_sky_gets_pi_le() {
    let (albedo, le) = (0.5, Vec3::new(2.0, 1.0, 0.5));
    let s = floor_under_sky(albedo, le);
    let img = render(&s, settings(32));
    let got = mean_where(&img, |x, y| (8..24).contains(&x) && (8..24).contains(&y));
    let want = le * albedo;
    eprintln!("open floor {got} against {want}");
    // Measured 4% low: the floor's own voxels close a little of the cones near its plane.
    let rel = ((got - want) / want).abs().max_element();
    assert!(rel < 0.05, "{got} against {want}");
}

/// A floor under a roof open on one side (+X), under a uniform sky, seen from above through a
/// cut-away: the real-time image against the path tracer's.
#[test]
fn a_floor_under_a_roof_open_on_one_side_matches_the_path_tracer() {
    let le = Vec3::splat(1.0);
    let mut s = empty_scene();
    let m = lambert(&mut s, Vec3::splat(0.6));
    floor(&mut s, 2.0, m);
    let (h, a) = (2.5, 2.0);
    // Roof and three walls; +X open.
    quad(
        &mut s,
        [
            Vec3::new(-a, h, -a),
            Vec3::new(a, h, -a),
            Vec3::new(a, h, a),
            Vec3::new(-a, h, a),
        ],
        m,
    );
    quad(
        &mut s,
        [
            Vec3::new(-a, 0.0, -a),
            Vec3::new(-a, 0.0, a),
            Vec3::new(-a, h, a),
            Vec3::new(-a, h, -a),
        ],
        m,
    );
    quad(
        &mut s,
        [
            Vec3::new(-a, 0.0, -a),
            Vec3::new(-a, h, -a),
            Vec3::new(a, h, -a),
            Vec3::new(a, 0.0, -a),
        ],
        m,
    );
    quad(
        &mut s,
        [
            Vec3::new(-a, 0.0, a),
            Vec3::new(a, 0.0, a),
            Vec3::new(a, h, a),
            Vec3::new(-a, h, a),
        ],
        m,
    );
    look_at(
        &mut s,
        Vec3::new(4.5, 1.2, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
        60.0,
    );
    s.environment = Some(Environment::uniform(le));
    let size = 48;
    let img = render(&s, settings(size));
    let st = ReferenceSettings {
        width: size,
        height: size,
        spp: 256,
        seed: 3,
        ..Default::default()
    };
    let reference = reference::render(&s, &st);
    let e = rel_mse(&img, &reference);
    eprintln!("roof open on one side: relMSE {e:.4}");
    // Measured 0.0256 (2026-12-05; 48x48 and a 256-spp reference carry noise; issue 31's goal
    // of 0.02 is at 256x256). The walls' fronts face out: their voxels hold the light of their
    // backs apart, which the room is lit by (0.089 before, when a zero-thickness surface's
    // voxel reflected to its front only; docs/environment.md).
    assert!(e < 0.03, "relMSE {e}");
}

/// An image whose texels hold their own centre's image coordinates (u, v) in red and green:
/// bilinear filtering gives back the (u, v) of any direction away from the poles and the seam.
fn coordinate_sky(w: u32, h: u32, turn_deg: f32) -> Environment {
    let texels = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            Vec3::new(
                (x as f32 + 0.5) / w as f32,
                (y as f32 + 0.5) / h as f32,
                1.0,
            )
        })
        .collect();
    Environment::image(EnvImage::new("coordinates.hdr", w, h, texels)).turned(turn_deg)
}

/// The background shows the environment by the mapping of CONVENTIONS.md, turned as asked.
#[test]
fn the_background_shows_the_environment_where_it_should() {
    for turn in [0.0f32, 90.0] {
        let mut s = empty_scene();
        let m = lambert(&mut s, Vec3::splat(0.5));
        // Something to voxelize, out of the view (behind the camera).
        floor(&mut s, 0.5, m);
        for t in s.vertices.iter_mut() {
            t.position[2] += 5.0;
        }
        s.instances[0].world = glam::Mat4::IDENTITY;
        s.bounds = voxgi::scene::Aabb {
            min: Vec3::new(-0.5, 0.0, 4.5),
            max: Vec3::new(0.5, 0.0, 5.5),
        };
        look_at(&mut s, Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), 90.0);
        s.environment = Some(coordinate_sky(64, 32, turn));
        let size = 32;
        let img = render(&s, settings(size));
        let env = s.environment.as_ref().unwrap();
        let (c, w) = (&s.camera, size as f32);
        let tan = (c.yfov * 0.5).tan();
        for (x, y) in [(16u32, 16u32), (4, 16), (28, 10), (16, 26)] {
            let sx = ((x as f32 + 0.5) / w * 2.0 - 1.0) * tan;
            let sy = (1.0 - (y as f32 + 0.5) / w * 2.0) * tan;
            let d = Vec3::new(sx, sy, -1.0).normalize();
            let (u, v) = voxgi::scene::environment::equirect_uv(env.to_image_frame(d));
            let p = img.at(x, y);
            let close = (p[0] - u).abs() < 0.004 && (p[1] - v).abs() < 0.004;
            assert!(
                close,
                "turn {turn}, pixel ({x}, {y}): {p:?}, the mapping gives ({u}, {v})"
            );
        }
    }
}

/// A wall facing +X, seen from +X, under a sky of one bright texel just above the horizon
/// towards +X: lit as the path tracer lights it (within a bound from measurement); turned
/// half a turn the texel lies behind it and the wall stays dark.
#[test]
fn an_environment_image_lights_what_faces_its_texels() {
    let wall = |turn: f32| {
        let (w, h) = (64u32, 32u32);
        let mut texels = vec![Vec3::ZERO; (w * h) as usize];
        texels[(15 * w + 48) as usize] = Vec3::splat(1000.0);
        wall_under(EnvImage::new("one-texel.hdr", w, h, texels), turn)
    };
    let s = wall(0.0);
    let img = render(&s, settings(16));
    let want = path_traced_mean(&s);
    let got = mean_where(&img, |_, _| true);
    eprintln!("wall under one texel: {got} against the path tracer's {want}");
    // The texel is much brighter than the rest: lit as the environment's sun, a directional
    // light (src/render/environment.rs). Measured 0.4% off.
    assert!(
        ((got - want) / want).abs().max_element() < 0.02,
        "{got} against {want}"
    );
    let turned = mean_where(&render(&wall(180.0), settings(16)), |_, _| true);
    assert!(
        turned.max_element() < 1e-3 * want.max_element(),
        "turned away: {turned}"
    );
}

/// Every mode renders an environment clean (validation, finite), the paper's too.
#[test]
fn every_mode_renders_an_environment_clean() {
    let (mut s, _) = corner_scene();
    s.environment = Some(coordinate_sky(16, 8, 30.0));
    for paper in [false, true] {
        for mode in [
            Mode::Full,
            Mode::Direct,
            Mode::Indirect,
            Mode::Ao,
            Mode::VoxelsRadiance,
        ] {
            let mut st = settings(24);
            st.mode = mode;
            if paper {
                st.gi = GiSettings::paper(32);
            }
            let img = render(&s, st);
            assert!(!img.has_non_finite(), "{mode:?} paper {paper}");
        }
    }
}

/// A file that is not an environment, or does not decode, is a clear error naming it.
#[test]
fn a_bad_environment_file_is_a_clear_error() {
    let dir = common::temp_dir("bad-env");
    let bad = dir.join("broken.hdr");
    std::fs::write(&bad, b"#?RADIANCE\nnot really").unwrap();
    let out = dir.join("out.exr");
    for cmd in ["render", "reference"] {
        let (ok, _, err) = common::voxgi(&[
            cmd,
            "--env",
            bad.to_str().unwrap(),
            "--width",
            "8",
            "--height",
            "8",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(!ok, "{cmd} accepted a broken .hdr");
        assert!(
            err.contains("broken.hdr") && err.contains("does not decode"),
            "{cmd}: {err}"
        );
        assert!(!out.exists(), "{cmd} left an image");
    }
    let (ok, _, err) =
        common::voxgi(&["render", "--env", "sky.png", "--out", out.to_str().unwrap()]);
    assert!(
        !ok && err.contains("sky.png") && err.contains(".hdr"),
        "{err}"
    );
}

/// Issue 31's goal on a model from outside the project: DamagedHelmet under the bundled sky
/// (its sun lit as a directional light), 256x256 against the path tracer: relMSE <= 0.02 and
/// FLIP <= 0.1 (measured 0.0171 and 0.057 against 512 spp; the reference's own noise at
/// 256 spp adds about 0.001).
#[test]
fn damaged_helmet_under_the_sky_meets_issue_31s_goal() {
    let scene = common::scenes_dir().join("DamagedHelmet/DamagedHelmet.gltf");
    let sky = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/sky.hdr");
    let dir = common::temp_dir("helmet-sky");
    let (rt, rf) = (dir.join("rt.exr"), dir.join("ref.exr"));
    let size = [
        "--width",
        "256",
        "--height",
        "256",
        "--env",
        sky.to_str().unwrap(),
    ];
    let mut args = vec!["render", scene.to_str().unwrap(), "--validate"];
    args.extend(size);
    args.extend(["--out", rt.to_str().unwrap()]);
    let (ok, _, err) = common::voxgi(&args);
    assert!(ok, "render: {err}");
    let mut args = vec!["reference", scene.to_str().unwrap(), "--spp", "256"];
    args.extend(size);
    args.extend(["--out", rf.to_str().unwrap()]);
    let (ok, _, err) = common::voxgi(&args);
    assert!(ok, "reference: {err}");
    let load = |p: &std::path::Path| voxgi::output::load_exr(p).unwrap();
    let (a, r) = (load(&rt), load(&rf));
    let m = voxgi::metrics::compare(&a, &r);
    let flip = voxgi::metrics::flip(&a, &r, 0.0);
    eprintln!(
        "DamagedHelmet under the sky: relMSE {:.4}, FLIP {flip:.4}",
        m.rel_mse
    );
    assert!(m.rel_mse <= 0.02, "relMSE {}", m.rel_mse);
    assert!(flip <= 0.1, "FLIP {flip}");
}
