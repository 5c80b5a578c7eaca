//! Direct light is exact: radiance of a Lambertian plane under punctual lights matches the
//! analytic answer (CONVENTIONS.md: radiometric lights, glTF BRDF).

mod gpu;
use glam::Vec3;
use gpu::*;
use std::f32::consts::PI;
use voxgi::render::{Mode, RenderSettings};
use voxgi::scene::LightKind;

const W: u32 = 96;
const CAM_H: f32 = 4.0;
const FOV: f32 = 60.0;

fn settings() -> RenderSettings {
    RenderSettings {
        width: W,
        height: W,
        shadow_resolution: 1024,
        mode: Mode::Direct,
        ..Default::default()
    }
}

/// Compares every pixel whose analytic radiance passes `include` against `expected`.
fn check(
    img: &voxgi::output::RadianceImage,
    albedo: Vec3,
    mut expected: impl FnMut(Vec3) -> Option<Vec3>,
) -> usize {
    let mut checked = 0;
    let mut worst = 0.0f32;
    for y in 0..W {
        for x in 0..W {
            let p = top_pixel_to_floor(x, y, W, W, CAM_H, FOV);
            let Some(e) = expected(p) else { continue };
            let want = albedo / PI * e;
            let got = Vec3::from(img.at(x, y));
            for c in 0..3 {
                if want[c] > 1e-3 {
                    let rel = (got[c] - want[c]).abs() / want[c];
                    worst = worst.max(rel);
                    assert!(
                        rel < 0.01,
                        "pixel ({x},{y}) at {p}: got {got}, want {want} ({:.2}% off)",
                        rel * 100.0
                    );
                }
            }
            checked += 1;
        }
    }
    eprintln!(
        "checked {checked} pixels, worst relative error {:.4}%",
        worst * 100.0
    );
    checked
}

#[test]
fn point_light_over_lambertian_plane() {
    let mut s = empty_scene();
    let albedo = Vec3::new(0.8, 0.5, 0.25);
    let m = lambert(&mut s, albedo);
    floor(&mut s, 3.0, m);
    top_camera(&mut s, CAM_H, FOV);
    let h = 1.5;
    let lp = Vec3::new(0.4, h, -0.3);
    let i = Vec3::new(10.0, 20.0, 30.0);
    s.lights.push(light(LightKind::Point, i, lp, Vec3::NEG_Y));
    let img = render(&s, settings());
    assert!(!img.has_non_finite());
    let n = check(&img, albedo, |p| {
        let d = lp - p;
        let cos = d.y / d.length();
        Some(i * cos / d.length_squared())
    });
    assert!(n > (W * W / 2) as usize, "only {n} pixels checked");
}

#[test]
fn directional_light_over_lambertian_plane() {
    let mut s = empty_scene();
    let albedo = Vec3::new(0.3, 0.6, 0.9);
    let m = lambert(&mut s, albedo);
    floor(&mut s, 3.0, m);
    top_camera(&mut s, CAM_H, FOV);
    let dir = Vec3::new(0.3, -1.0, 0.5).normalize();
    let e = Vec3::new(2.0, 3.0, 4.0);
    s.lights
        .push(light(LightKind::Directional, e, Vec3::ZERO, dir));
    let img = render(&s, settings());
    let cos = -dir.y;
    let n = check(&img, albedo, |_| Some(e * cos));
    assert!(n > (W * W / 2) as usize);
}

#[test]
fn spot_light_falloff_between_cone_angles() {
    let mut s = empty_scene();
    let albedo = Vec3::splat(0.7);
    let m = lambert(&mut s, albedo);
    floor(&mut s, 3.0, m);
    top_camera(&mut s, CAM_H, FOV);
    let lp = Vec3::new(0.0, 2.0, 0.0);
    let dir = Vec3::new(0.2, -1.0, 0.1).normalize();
    let (inner, outer) = (20f32.to_radians(), 35f32.to_radians());
    let i = Vec3::splat(40.0);
    s.lights.push(light(
        LightKind::Spot {
            inner_cone: inner,
            outer_cone: outer,
        },
        i,
        lp,
        dir,
    ));
    let img = render(&s, settings());
    let scale = 1.0 / (inner.cos() - outer.cos());
    let offset = -outer.cos() * scale;
    let mut in_falloff = 0;
    let n = check(&img, albedo, |p| {
        let d = lp - p;
        let l = d.normalize();
        let cd = dir.dot(-l);
        let a = (cd * scale + offset).clamp(0.0, 1.0);
        // Skip the outer edge where the falloff reaches zero (relative error is meaningless).
        if a < 0.05 {
            return None;
        }
        if a < 0.95 {
            in_falloff += 1;
        }
        Some(i * a * a * l.y / d.length_squared())
    });
    assert!(
        n > 200 && in_falloff > 100,
        "{n} pixels, {in_falloff} in the falloff"
    );
}

/// A floor under `count` lights of `kind`, each dim enough that the sum stays moderate.
fn many_lights(kind: LightKind, count: usize) -> voxgi::scene::Scene {
    let mut s = empty_scene();
    let white = lambert(&mut s, Vec3::splat(0.8));
    floor(&mut s, 2.0, white);
    top_camera(&mut s, 3.0, 60.0);
    for i in 0..count {
        let a = i as f32 * 0.37;
        s.lights.push(light(
            kind,
            Vec3::splat(0.01),
            Vec3::new(a.cos(), 2.0, a.sin()),
            Vec3::new(0.1 * a.cos(), -1.0, 0.1 * a.sin()),
        ));
    }
    s
}

#[test]
fn the_light_and_shadow_view_caps_are_reached_cleanly_and_refused_beyond() {
    // The lights and shadow views are uniform blocks of 256 lights and 819 views: at the caps
    // the scene renders (validation-clean, finite, lit); one more is a clear error, not a
    // truncated table.
    let small = || RenderSettings {
        width: 32,
        height: 32,
        shadow_resolution: 16,
        ..settings()
    };
    for (kind, count) in [(LightKind::Directional, 256), (LightKind::Point, 136)] {
        let img = render(&many_lights(kind, count), small());
        assert!(
            !img.has_non_finite(),
            "{count} {kind:?} lights: non-finite pixels"
        );
        assert!(
            img.pixels.iter().any(|p| p[0] > 0.0),
            "{count} {kind:?} lights: the floor is dark"
        );
    }
    let ctx = context();
    let refused = |kind: LightKind, count: usize| {
        let err = voxgi::render::Renderer::new(&ctx, &many_lights(kind, count), small())
            .err()
            .unwrap_or_else(|| panic!("{count} {kind:?} lights were accepted"));
        err.to_string()
    };
    let lights = refused(LightKind::Directional, 257);
    assert!(
        lights.contains("257 lights") && lights.contains("at most 256"),
        "{lights}"
    );
    // 137 point lights: 822 views.
    let views = refused(LightKind::Point, 137);
    assert!(
        views.contains("822 shadow views") && views.contains("at most 819"),
        "{views}"
    );
}
