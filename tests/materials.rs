//! Emission leaves front faces only (both when double-sided, CONVENTIONS.md), mirrored
//! instances keep their front side, and alphaMode MASK cuts surfaces and their shadows.

mod gpu;
use glam::{Mat4, Vec3};
use gpu::*;
use voxgi::render::{Mode, RenderSettings};
use voxgi::scene::{AlphaMode, LightKind, Material, Scene};

const W: u32 = 32;

fn settings() -> RenderSettings {
    RenderSettings {
        width: W,
        height: W,
        shadow_resolution: 256,
        mode: Mode::Direct,
        ..Default::default()
    }
}

/// A floor quad facing +Y (or -Y when `down`), seen from above.
fn emissive_floor(down: bool, double_sided: bool, world: Mat4) -> Scene {
    let mut s = empty_scene();
    let le = Vec3::new(17.0, 3.0, 0.5);
    let m = emitter(&mut s, Vec3::ZERO, le, double_sided);
    floor(&mut s, 3.0, m);
    if down {
        let v = &mut s.vertices;
        v.swap(1, 3);
        for x in v.iter_mut() {
            x.normal = [0.0, -1.0, 0.0];
        }
    }
    s.instances[0].world = world;
    top_camera(&mut s, 2.0, 40.0);
    s
}

#[test]
fn emission_is_exact_from_the_front_only() {
    let le = [17.0, 3.0, 0.5];
    let img = render(&emissive_floor(false, false, Mat4::IDENTITY), settings());
    for p in &img.pixels {
        for c in 0..3 {
            assert!((p[c] - le[c]).abs() <= le[c] * 1e-3, "front face: {p:?}");
        }
    }
    let img = render(&emissive_floor(true, false, Mat4::IDENTITY), settings());
    assert!(
        img.pixels.iter().flatten().all(|&v| v == 0.0),
        "the back of a one-sided emitter must not emit"
    );
    let img = render(&emissive_floor(true, true, Mat4::IDENTITY), settings());
    assert!(
        img.pixels
            .iter()
            .all(|p| (p[0] - le[0]).abs() <= le[0] * 1e-3),
        "a double-sided emitter emits from its back"
    );
}

#[test]
fn mirrored_instance_keeps_its_front_face() {
    // Mirroring in X flips the triangles' winding; glTF says the front stays the front.
    let mirror = Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
    let img = render(&emissive_floor(false, false, mirror), settings());
    assert!(
        img.pixels.iter().all(|p| (p[0] - 17.0).abs() < 0.02),
        "a mirrored emitter facing the camera must emit"
    );
    let img = render(&emissive_floor(true, false, mirror), settings());
    assert!(img.pixels.iter().flatten().all(|&v| v == 0.0));
}

#[test]
fn alpha_mask_cuts_the_surface_and_its_shadow() {
    let mut s = empty_scene();
    let floor_m = lambert(&mut s, Vec3::splat(0.5));
    floor(&mut s, 3.0, floor_m);
    // A large panel between the light and the floor, with alpha below its cutoff.
    s.materials.push(Material {
        base_color: glam::Vec4::new(1.0, 0.0, 0.0, 0.3),
        metallic: 0.0,
        specular_factor: 0.0,
        alpha_mode: AlphaMode::Mask(0.5),
        ..Material::default()
    });
    let panel = s.materials.len() as u32 - 1;
    let y = 1.0;
    quad(
        &mut s,
        [
            Vec3::new(-2.0, y, 2.0),
            Vec3::new(2.0, y, 2.0),
            Vec3::new(2.0, y, -2.0),
            Vec3::new(-2.0, y, -2.0),
        ],
        panel,
    );
    top_camera(&mut s, 3.0, 40.0);
    s.lights.push(light(
        LightKind::Directional,
        Vec3::splat(2.0),
        Vec3::ZERO,
        Vec3::NEG_Y,
    ));
    let img = render(&s, settings());
    // Seen through the cut panel: the floor, fully lit (no shadow, no red).
    let want = 0.5 / std::f32::consts::PI * 2.0;
    for p in &img.pixels {
        assert!(
            (p[0] - want).abs() < want * 0.01 && (p[1] - p[0]).abs() < 1e-4,
            "{p:?}, want grey {want}"
        );
    }
    // The same panel opaque hides the floor and is red.
    s.materials[panel as usize].alpha_mode = AlphaMode::Opaque;
    let img = render(&s, settings());
    let c = img.at(W / 2, W / 2);
    assert!(c[0] > 0.1 && c[1] == 0.0, "opaque panel: {c:?}");
}
