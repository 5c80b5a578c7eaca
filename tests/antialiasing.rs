//! Antialiasing by accumulation (render/accumulate.rs): while the view holds still, the image
//! is the mean of frames drawn at sub-pixel offsets, which approaches the mean over each
//! pixel's footprint (what the conventions call a pixel); the first frame is the pixel centres;
//! anything that changes the view starts the mean again; a complete mean holds still.

mod gpu;
use glam::{Mat4, Vec3};
use gpu::*;
use voxgi::gi::GiSettings;
use voxgi::output::RadianceImage;
use voxgi::render::{Mode, RenderSettings};
use voxgi::scene::Scene;

const SIZE: u32 = 64;

fn settings(mode: Mode, size: u32, accumulate: u32) -> RenderSettings {
    RenderSettings {
        width: size,
        height: size,
        shadow_resolution: 512,
        mode,
        gi: GiSettings {
            voxels: 32,
            ..Default::default()
        },
        accumulate,
        ..Default::default()
    }
}

/// A lit floor and wall with a thin pole and a slanted box in front: silhouettes, a shadow
/// edge and a pole narrower than a pixel at 64x64.
fn scene() -> Scene {
    let (mut s, white) = corner_scene();
    // The pole: 1.5 cm wide, about a third of a pixel at 64x64.
    quad(
        &mut s,
        [
            Vec3::new(0.3, 0.0, -0.5),
            Vec3::new(0.315, 0.0, -0.5),
            Vec3::new(0.315, 1.5, -0.5),
            Vec3::new(0.3, 1.5, -0.5),
        ],
        white,
    );
    // A box face turned 30 degrees: edges that cross the pixel grid at a slant.
    let turn = Mat4::from_rotation_y(0.5);
    let c =
        |x: f32, y: f32| turn.transform_point3(Vec3::new(x, y, 0.0)) + Vec3::new(-0.6, 0.0, 0.0);
    quad(
        &mut s,
        [c(-0.3, 0.0), c(0.3, 0.0), c(0.3, 0.7), c(-0.3, 0.7)],
        white,
    );
    s
}

/// The mean of each k x k block of pixels.
fn box_down(img: &RadianceImage, k: u32) -> RadianceImage {
    let (w, h) = (img.width / k, img.height / k);
    let mut pixels = vec![[0.0f32; 3]; (w * h) as usize];
    for y in 0..img.height {
        for x in 0..img.width {
            let p = img.pixels[(y * img.width + x) as usize];
            let d = &mut pixels[((y / k) * w + x / k) as usize];
            for c in 0..3 {
                d[c] += p[c] / (k * k) as f32;
            }
        }
    }
    RadianceImage {
        width: w,
        height: h,
        pixels,
    }
}

#[test]
fn the_mean_approaches_each_pixels_footprint() {
    // The footprint's mean: the image at 4x the resolution, one sample per pixel, averaged
    // over 4 x 4 blocks. Direct light: edges, the pole and the shadow are what alias.
    let s = scene();
    let fine = frames(&s, settings(Mode::Direct, 4 * SIZE, 1), 0, |_| {}, 0);
    let footprint = box_down(&fine, 4);
    let single = frames(&s, settings(Mode::Direct, SIZE, 16), 0, |_| {}, 0);
    let mean = frames(&s, settings(Mode::Direct, SIZE, 16), 15, |_| {}, 0);
    let (e_single, e_mean) = (rel_mse(&single, &footprint), rel_mse(&mean, &footprint));
    eprintln!("relMSE against the footprints' mean: one sample {e_single}, 16 frames {e_mean}");
    assert!(e_single > 1e-3, "the scene does not alias ({e_single})");
    assert!(
        e_mean < 0.05 * e_single,
        "the mean of 16 frames {e_mean} against one sample {e_single}"
    );
}

#[test]
fn the_first_frame_samples_the_pixel_centres_and_a_complete_mean_holds_still() {
    let s = scene();
    let off = frames(&s, settings(Mode::Full, SIZE, 1), 0, |_| {}, 0);
    let first = frames(&s, settings(Mode::Full, SIZE, 8), 0, |_| {}, 0);
    assert_eq!(
        off.pixels, first.pixels,
        "the first frame is not the unjittered one"
    );
    let second = frames(&s, settings(Mode::Full, SIZE, 8), 1, |_| {}, 0);
    assert!(
        rel_mse(&second, &first) > 0.0,
        "the second frame did not move"
    );
    // Frames 8 and 10 of a mean of 8: complete, the same.
    let done = frames(&s, settings(Mode::Full, SIZE, 8), 7, |_| {}, 0);
    let later = frames(&s, settings(Mode::Full, SIZE, 8), 9, |_| {}, 0);
    assert_eq!(done.pixels, later.pixels, "a complete mean changed");
}

#[test]
fn a_moved_camera_light_or_node_starts_the_mean_again() {
    // Direct mode (no temporal trace, whose history a moving camera keeps): the frame after
    // the change is exactly a fresh renderer's first frame of the changed scene.
    let s = scene();
    let set = || settings(Mode::Direct, SIZE, 8);

    let mut turned = s.clone();
    look_at(
        &mut turned,
        Vec3::new(0.4, 1.3, 2.1),
        Vec3::new(0.0, 0.5, -1.0),
        55.0,
    );
    let camera = turned.camera.clone();
    let after = frames(&s, set(), 5, |r| r.camera = camera, 0);
    let fresh = frames(&turned, set(), 0, |_| {}, 0);
    assert_eq!(after.pixels, fresh.pixels, "after the camera moved");

    let mut relit = s.clone();
    relit.lights[0].direction = Vec3::new(0.5, -1.0, -0.4).normalize();
    let lights = relit.lights.clone();
    let after = frames(&s, set(), 5, |r| r.set_lights(&lights).expect("lights"), 0);
    let fresh = frames(&relit, set(), 0, |_| {}, 0);
    assert_eq!(after.pixels, fresh.pixels, "after the light moved");

    let node = s.instances[3].node;
    let shift = Mat4::from_translation(Vec3::new(0.5, 0.0, 0.2));
    let mut moved = s.clone();
    moved.instances[3].world = shift;
    let after = frames(&s, set(), 5, |r| r.set_node_transform(node, shift), 0);
    let fresh = frames(&moved, set(), 0, |_| {}, 0);
    assert_eq!(after.pixels, fresh.pixels, "after the node moved");
}

#[test]
fn a_resize_starts_the_mean_again_at_the_new_size() {
    // Full mode: the history and the mean are made again at the new size; the frame after is
    // a fresh renderer's first frame there. Validation-clean and finite (frames() checks).
    let s = scene();
    let after = frames(
        &s,
        settings(Mode::Full, SIZE, 8),
        4,
        |r| r.resize(48, 40).expect("resize"),
        0,
    );
    let fresh = frames(
        &s,
        RenderSettings {
            width: 48,
            height: 40,
            ..settings(Mode::Full, SIZE, 8)
        },
        0,
        |_| {},
        0,
    );
    let e = rel_mse(&after, &fresh);
    assert!(e < 1e-9, "after the resize: relMSE {e}");
}
