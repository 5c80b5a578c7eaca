//! Shadows fall where the geometry says: fully dark inside the occluder's projection, exact
//! outside it, and attached to a caster that stands on the floor (no peter-panning).

mod gpu;
use glam::Vec3;
use gpu::*;
use std::f32::consts::PI;
use voxgi::render::{Mode, RenderSettings};
use voxgi::scene::LightKind;

const W: u32 = 128;
const CAM_H: f32 = 4.0;
const FOV: f32 = 60.0;

fn pixel_of(p: Vec3) -> (u32, u32) {
    // Inverse of top_pixel_to_floor.
    let t = (FOV.to_radians() * 0.5).tan();
    let ndc_x = p.x / (t * CAM_H);
    let ndc_y = -p.z / (t * CAM_H);
    let x = ((ndc_x + 1.0) * 0.5 * W as f32 - 0.5).round() as u32;
    let y = ((1.0 - ndc_y) * 0.5 * W as f32 - 0.5).round() as u32;
    (x, y)
}

/// A closed axis-aligned box with outward faces.
fn cube(s: &mut voxgi::scene::Scene, min: Vec3, max: Vec3, m: u32) {
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let (a, b) = (min, max);
    quad(
        s,
        [
            c(a.x, b.y, b.z),
            c(b.x, b.y, b.z),
            c(b.x, b.y, a.z),
            c(a.x, b.y, a.z),
        ],
        m,
    ); // +Y
    quad(
        s,
        [
            c(a.x, a.y, a.z),
            c(b.x, a.y, a.z),
            c(b.x, a.y, b.z),
            c(a.x, a.y, b.z),
        ],
        m,
    ); // -Y
    quad(
        s,
        [
            c(b.x, a.y, b.z),
            c(b.x, a.y, a.z),
            c(b.x, b.y, a.z),
            c(b.x, b.y, b.z),
        ],
        m,
    ); // +X
    quad(
        s,
        [
            c(a.x, a.y, a.z),
            c(a.x, a.y, b.z),
            c(a.x, b.y, b.z),
            c(a.x, b.y, a.z),
        ],
        m,
    ); // -X
    quad(
        s,
        [
            c(a.x, a.y, b.z),
            c(b.x, a.y, b.z),
            c(b.x, b.y, b.z),
            c(a.x, b.y, b.z),
        ],
        m,
    ); // +Z
    quad(
        s,
        [
            c(b.x, a.y, a.z),
            c(a.x, a.y, a.z),
            c(a.x, b.y, a.z),
            c(b.x, b.y, a.z),
        ],
        m,
    ); // -Z
}

#[test]
fn occluder_casts_a_shadow_where_the_geometry_says() {
    let mut s = empty_scene();
    let albedo = Vec3::splat(0.6);
    let m = lambert(&mut s, albedo);
    floor(&mut s, 3.0, m);
    // A horizontal square occluder of half-size 0.3 at height 1, centred at (0.5, 1, 0).
    let oc = Vec3::new(0.5, 1.0, 0.0);
    let hs = 0.3;
    quad(
        &mut s,
        [
            oc + Vec3::new(-hs, 0.0, hs),
            oc + Vec3::new(hs, 0.0, hs),
            oc + Vec3::new(hs, 0.0, -hs),
            oc + Vec3::new(-hs, 0.0, -hs),
        ],
        m,
    );
    top_camera(&mut s, CAM_H, FOV);
    let lp = Vec3::new(0.0, 2.0, 0.0);
    let i = Vec3::splat(20.0);
    s.lights.push(light(LightKind::Point, i, lp, Vec3::NEG_Y));
    let img = render(
        &s,
        RenderSettings {
            width: W,
            height: W,
            shadow_resolution: 1024,
            mode: Mode::Direct,
            ..Default::default()
        },
    );
    // The occluder (height 1, light at 2) projects to twice its size around (1, 0, 0).
    let shadow_centre = Vec3::new(1.0, 0.0, 0.0);
    let shadow_half = 2.0 * hs;
    // Inside the shadow, away from its edge, but not under the occluder as seen from above.
    let inside = shadow_centre + Vec3::new(shadow_half * 0.75, 0.0, 0.0);
    let (x, y) = pixel_of(inside);
    let v = img.at(x, y);
    assert!(
        v.iter().all(|&c| c == 0.0),
        "shadowed pixel {inside} is {v:?}"
    );
    // Outside the shadow: the analytic value.
    let outside = Vec3::new(-1.0, 0.0, 0.5);
    let (x, y) = pixel_of(outside);
    let d = lp - outside;
    let want = albedo / PI * i * (d.y / d.length()) / d.length_squared();
    let got = Vec3::from(img.at(x, y));
    assert!(
        ((got - want) / want).abs().max_element() < 0.01,
        "lit pixel {outside}: got {got}, want {want}"
    );
}

#[test]
fn shadow_stays_attached_to_its_caster() {
    let mut s = empty_scene();
    let m = lambert(&mut s, Vec3::splat(0.6));
    floor(&mut s, 3.0, m);
    // A box standing on the floor, lit from the side at a grazing-ish angle.
    // Off-centre, so that the camera above the origin sees the floor at the box's +X face.
    cube(
        &mut s,
        Vec3::new(-1.5, 0.0, -0.5),
        Vec3::new(-0.5, 1.0, 0.5),
        m,
    );
    top_camera(&mut s, CAM_H, FOV);
    let dir = Vec3::new(1.0, -0.6, 0.0).normalize();
    s.lights.push(light(
        LightKind::Directional,
        Vec3::splat(3.0),
        Vec3::ZERO,
        dir,
    ));
    let img = render(
        &s,
        RenderSettings {
            width: W,
            height: W,
            shadow_resolution: 1024,
            mode: Mode::Direct,
            ..Default::default()
        },
    );
    // One camera pixel is 2 * tan(30 deg) * 4 / 128 = 3.6 cm. The floor right next to the box's
    // +X face, 2 pixels out, must be in its shadow (which reaches 1/0.6 = 1.67 m beyond).
    let near = Vec3::new(-0.5 + 0.075, 0.0, 0.0);
    let (x, y) = pixel_of(near);
    let v = img.at(x, y);
    assert!(
        v.iter().all(|&c| c < 1e-4),
        "floor next to the caster {near} is lit: {v:?}"
    );
    // Beyond the shadow's end the floor is lit again, and on the lit side too.
    for p in [Vec3::new(1.4, 0.0, 0.0), Vec3::new(-1.0, 0.0, 1.2)] {
        let (x, y) = pixel_of(p);
        let v = img.at(x, y);
        assert!(v[0] > 0.1, "floor at {p} should be lit: {v:?}");
    }
}
