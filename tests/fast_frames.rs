//! Fast frames: the diffuse cones traced per block and upsampled (`trace_scale`), and over
//! frames from a reprojected history (`temporal`). Upsampling keeps surfaces apart; what a
//! moving camera uncovers converges to the whole cone set; a cut, a moved light and a moved
//! node start the history over with the whole set (no ghost).

mod gpu;
use glam::{Mat4, Vec3};
use gpu::*;
use voxgi::gi::GiSettings;
use voxgi::output::RadianceImage;
use voxgi::render::{Mode, RenderSettings, Renderer};
use voxgi::scene::Scene;

const SIZE: u32 = 128;

fn settings(mode: Mode, trace_scale: u32, temporal: u32) -> RenderSettings {
    RenderSettings {
        width: SIZE,
        height: SIZE,
        shadow_resolution: 512,
        mode,
        gi: GiSettings {
            voxels: 64,
            trace_scale,
            temporal,
            ..Default::default()
        },
        // The temporal trace alone: frames are compared with each other and with fresh
        // renderers' first frames, one sample per pixel (no antialiasing mean).
        accumulate: 1,
        ..Default::default()
    }
}

/// An axis-aligned box from `lo` to `hi` (its five faces but the bottom).
fn box_faces(s: &mut Scene, lo: Vec3, hi: Vec3, material: u32) -> usize {
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let (a, b) = (lo, hi);
    let quads = [
        [
            c(a.x, b.y, b.z),
            c(b.x, b.y, b.z),
            c(b.x, b.y, a.z),
            c(a.x, b.y, a.z),
        ],
        [
            c(a.x, a.y, b.z),
            c(b.x, a.y, b.z),
            c(b.x, b.y, b.z),
            c(a.x, b.y, b.z),
        ],
        [
            c(b.x, a.y, a.z),
            c(a.x, a.y, a.z),
            c(a.x, b.y, a.z),
            c(b.x, b.y, a.z),
        ],
        [
            c(b.x, a.y, b.z),
            c(b.x, a.y, a.z),
            c(b.x, b.y, a.z),
            c(b.x, b.y, b.z),
        ],
        [
            c(a.x, a.y, a.z),
            c(a.x, a.y, b.z),
            c(a.x, b.y, b.z),
            c(a.x, b.y, a.z),
        ],
    ];
    let tris: Vec<[Vec3; 3]> = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    mesh(s, &tris, material)
}

/// A red floor meeting a white wall at z = -1, lit by the sun, with a thin white pole (4 cm,
/// about two pixels wide) standing in front of the wall, and a box on the floor.
fn edges_scene() -> Scene {
    let (mut s, white) = corner_scene();
    box_faces(
        &mut s,
        Vec3::new(0.3, 0.0, -0.6),
        Vec3::new(0.34, 1.5, -0.56),
        white,
    );
    box_faces(
        &mut s,
        Vec3::new(-0.9, 0.0, -0.2),
        Vec3::new(-0.4, 0.4, 0.3),
        white,
    );
    s
}

/// Per pixel, |a - b| over the pixel's own (full-resolution) brightness, its largest channel.
fn worst_pixel(a: &RadianceImage, reference: &RadianceImage) -> (f32, usize) {
    let mut worst = (0.0f32, 0);
    for (i, (p, q)) in a.pixels.iter().zip(&reference.pixels).enumerate() {
        let level = q.iter().cloned().fold(0.0, f32::max).max(1e-3);
        let d = (0..3).map(|c| (p[c] - q[c]).abs()).fold(0.0, f32::max) / level;
        if d > worst.0 {
            worst = (d, i);
        }
    }
    worst
}

/// The share of pixels whose light is off by more than `by` of their own.
fn share_off(a: &RadianceImage, reference: &RadianceImage, by: f32) -> f64 {
    let off = a
        .pixels
        .iter()
        .zip(&reference.pixels)
        .filter(|(p, q)| {
            let level = q.iter().cloned().fold(0.0, f32::max).max(1e-3);
            (0..3).map(|c| (p[c] - q[c]).abs()).fold(0.0, f32::max) > by * level
        })
        .count();
    off as f64 / a.pixels.len() as f64
}

#[test]
fn upsampled_indirect_light_keeps_surfaces_apart() {
    // Each pixel's indirect light, traced per block of 2 or 4 and upsampled, against every
    // pixel tracing its own: at the floor's edge along the wall, on the pole in front of the
    // wall and around the box, no pixel takes another surface's light (the red floor's and the
    // white wall's differ by several times in red and green).
    let s = edges_scene();
    let full = frames(&s, settings(Mode::Indirect, 1, 0), 0, |_| {}, 0);
    for scale in [2, 4] {
        let up = frames(&s, settings(Mode::Indirect, scale, 0), 0, |_| {}, 0);
        let (d, i) = worst_pixel(&up, &full);
        let e = rel_mse(&up, &full);
        let off = share_off(&up, &full, 0.25);
        eprintln!("scale {scale}: worst pixel {d} at {i}, relMSE {e}, share off by 25%: {off}");
        // Measured (128x128, 64^3): scale 2 relMSE 1.3e-4, 0.04% of pixels off by more than
        // a quarter of their light, the worst by 1.03 (a floor pixel in the pole's contact
        // shadow, interpolated from floor blocks a pixel further out); scale 4 4.4e-4, 0.25%,
        // 0.95. Upsampled bilinearly without the surface test, scale 2 gave 1.9e-3, 0.72% and
        // 2.5 (the floor's light on the wall's foot and the wall's on the pole). Since the
        // tail's series weighs the voxels by their light (more of it in the corners the
        // pixels' blocks straddle), scale 4: 4.6e-4 -> 5.1e-4 and 0.26% -> 0.40% of the pixels
        // off by a quarter (the bound 0.4% -> 0.5%).
        let (max_e, max_off) = if scale == 2 {
            (2e-4, 1e-3)
        } else {
            (7e-4, 5e-3)
        };
        assert!(e < max_e, "scale {scale}: relMSE {e}");
        assert!(
            off < max_off,
            "scale {scale}: {off} of the pixels off by a quarter"
        );
        assert!(d < 1.5, "scale {scale}: pixel {i} off by {d} of its light");
    }
}

/// The edges scene with a glossy floor: red metal of roughness `roughness`, mirroring the
/// lit wall, the pole and the box in a blur.
fn glossy_scene(roughness: f32) -> Scene {
    let mut s = edges_scene();
    let floor = &mut s.materials[0];
    floor.metallic = 1.0;
    floor.roughness = roughness;
    floor.specular_factor = 1.0;
    // A faceted metal column: its 16 faces' normals part by 22.5 degrees (neighbours pass
    // the surface test) and their reflections by 45.
    let metal = lambert(&mut s, Vec3::splat(0.9));
    let m = &mut s.materials[metal as usize];
    m.metallic = 1.0;
    m.roughness = roughness;
    m.specular_factor = 1.0;
    let (centre, r, h) = (Vec3::new(0.9, 0.0, 0.1), 0.3, 1.0);
    let mut faces = Vec::new();
    for k in 0..16 {
        let at = |k: i32| {
            let a = k as f32 * std::f32::consts::TAU / 16.0;
            centre + Vec3::new(r * a.cos(), 0.0, -r * a.sin())
        };
        let (a, b) = (at(k), at(k + 1));
        let up = Vec3::Y * h;
        faces.push([a, b, b + up]);
        faces.push([a, b + up, a + up]);
    }
    mesh(&mut s, &faces, metal);
    s
}

#[test]
fn blocks_share_a_specular_cone_only_where_it_matches_the_pixels() {
    // The specular cones of the floor and the column traced per block of 4 and shared with
    // the pixels whose reflection lies within a quarter of the cone's half angle of the
    // block's, against every pixel tracing its own: reflections stay in place, and the
    // column's faces keep their own.
    for roughness in [0.35f32, 0.6] {
        let s = glossy_scene(roughness);
        let full = frames(&s, settings(Mode::Indirect, 1, 0), 0, |_| {}, 0);
        let up = frames(&s, settings(Mode::Indirect, 4, 0), 0, |_| {}, 0);
        let (d, i) = worst_pixel(&up, &full);
        let e = rel_mse(&up, &full);
        let off = share_off(&up, &full, 0.25);
        eprintln!(
            "roughness {roughness}: worst pixel {d} at {i}, relMSE {e}, share off by 25%: {off}"
        );
        // Measured (128x128, 64^3): roughness 0.35 relMSE 2.6e-3, 4.3% of the pixels off by
        // a quarter; 0.6: 7.3e-4, 2.9%. Every pixel's own narrow cone is no ground truth: its
        // steps band the floor and outline the box's reflection, which the blocks' cones do
        // less, so single pixels differ by far more than their light (no per-pixel bound).
        // Sharing regardless of the reflection's direction: 9.1e-3 and 5.3%, 3.2e-3 and 4.1%
        // (the column's faces took their neighbours' reflections).
        // Since the voxels hold a rough lobe's light (voxelize.frag's voxel_albedo) the metal
        // floor and column are lit in the voxels, where they were black, and the reflections
        // the blocks share carry that light: 0.35 relMSE 2.4e-3, 3.7% off; 0.6 2.5e-3 (7.3e-4
        // when the metals' voxels were black), 2.5%. Since their mirror lobes' light is in
        // the directional volumes too (the column's and the floor's, roughness 0.35 keeping
        // 65% of it there), 0.35: 3.6e-3, 4.0% off; sharing regardless of the reflection's
        // direction: 1.0e-2.
        // Since the tail's series weighs the voxels by their light: 0.35 3.6e-3 -> 4.1e-3, 0.6
        // 2.6e-3 -> 3.0e-3 (its bound 3e-3 -> 3.5e-3), the shares off the same.
        let (max_e, max_off) = if roughness < 0.5 {
            (4.5e-3, 0.05)
        } else {
            (3.5e-3, 0.035)
        };
        assert!(e < max_e, "roughness {roughness}: relMSE {e}");
        assert!(
            off < max_off,
            "roughness {roughness}: {off} of the pixels off by a quarter"
        );
    }
}

#[test]
fn the_specular_cones_floor_of_two_voxels_costs_a_near_mirror_nothing() {
    // A near-mirror floor and column (roughness 0.1: the narrowest cone, a tangent of 0.02)
    // reflecting the lit wall, the pole and the box, against the path tracer: the specular
    // cone no narrower than two voxels (the directional volumes from its first step) is as
    // accurate as one voxel wide (the full-resolution voxels filtered by hand, at half the
    // step), and a floor of eight voxels blurs the reflections (the setting acts).
    let s = glossy_scene(0.1);
    let truth = voxgi::reference::render(
        &s,
        &voxgi::reference::ReferenceSettings {
            width: SIZE,
            height: SIZE,
            spp: 64,
            ..Default::default()
        },
    );
    let error = |floor: f32| {
        let mut set = settings(Mode::Full, 4, 4);
        set.gi.specular_min_voxels = floor;
        rel_mse(&frames(&s, set, 0, |_| {}, 0), &truth)
    };
    let (one, two, eight) = (error(1.0), error(2.0), error(8.0));
    eprintln!("relMSE against the path tracer, floor 1 / 2 / 8 voxels: {one} / {two} / {eight}");
    // Measured (128x128, 64^3, 64 spp): 0.0398 / 0.0396 / 0.0966.
    assert!(two < 1.05 * one, "floor 2: {two}, floor 1: {one}");
    assert!(eight > 1.1 * two, "floor 8: {eight}, floor 2: {two}");
}

/// Each cell's distance in cells (along the farthest axis) to the nearest cell holding a
/// filled voxel, capped at 255, by brute force over the voxels.
fn empty_space_by_hand(dump: &voxgi::gi::VoxelDump) -> Vec<u32> {
    let (n, c) = (dump.resolution as usize, dump.empty_space_cell as usize);
    let m = n.div_ceil(c);
    let mut filled = Vec::new();
    for z in 0..m {
        for y in 0..m {
            for x in 0..m {
                let any = (z * c..((z + 1) * c).min(n)).any(|vz| {
                    (y * c..((y + 1) * c).min(n)).any(|vy| {
                        (x * c..((x + 1) * c).min(n)).any(|vx| dump.filled[vx + n * (vy + n * vz)])
                    })
                });
                if any {
                    filled.push([x as i64, y as i64, z as i64]);
                }
            }
        }
    }
    let mut dist = Vec::with_capacity(m * m * m);
    for z in 0..m as i64 {
        for y in 0..m as i64 {
            for x in 0..m as i64 {
                let d = filled
                    .iter()
                    .map(|f| (f[0] - x).abs().max((f[1] - y).abs()).max((f[2] - z).abs()))
                    .min()
                    .unwrap_or(255)
                    .min(255);
                dist.push(d as u32);
            }
        }
    }
    dist
}

#[test]
fn the_empty_space_volume_holds_each_cells_distance_to_the_nearest_filled_one() {
    // The edges scene at 64^3 (cells of 2 voxels, 32 a side) and 48^3 (24 a side), and after
    // its box moved (the volume is rebuilt with the voxels): against brute force.
    let s = edges_scene();
    for voxels in [64, 48] {
        let mut set = settings(Mode::Full, 4, 4);
        set.gi.voxels = voxels;
        let dump = render_voxels(&s, set);
        let got = dump.empty_space.clone().expect("the empty-space volume");
        assert_eq!(dump.empty_space_cell, 2, "{voxels}^3");
        let want = empty_space_by_hand(&dump);
        assert_eq!(got.len(), want.len(), "{voxels}^3");
        let wrong = got.iter().zip(&want).filter(|(a, b)| a != b).count();
        assert_eq!(wrong, 0, "{voxels}^3: {wrong} cells differ");
        // Filled cells, empty ones next to them and open space far from anything.
        assert!(want.contains(&0) && want.contains(&1) && want.iter().any(|&d| d >= 4));
    }
    let node = s.instances[3].node;
    let mut set = settings(Mode::Full, 4, 4);
    set.dynamic_nodes = vec![node];
    let ctx = context();
    let stats = ctx.stats.clone();
    let (before, after) = {
        let mut r = Renderer::new(&ctx, &s, set).expect("renderer");
        r.render(false).expect("frame");
        let before = r.read_voxels().expect("readback").expect("voxels");
        r.set_node_transform(node, Mat4::from_translation(Vec3::new(0.8, 0.0, 0.0)));
        r.render(false).expect("frame");
        (before, r.read_voxels().expect("readback").expect("voxels"))
    };
    drop(ctx);
    assert_eq!(stats.count(), 0, "{}", stats.messages().join("\n"));
    assert_ne!(before.empty_space, after.empty_space, "the box moved");
    assert_eq!(
        after.empty_space.clone().unwrap(),
        empty_space_by_hand(&after)
    );
}

#[test]
fn cones_that_skip_empty_space_see_what_they_saw() {
    // The skipped samples could read nothing, so the image stays (the samples after a jump
    // fall at other distances along the cone than without it): the near-mirror edges scene,
    // whose specular cones cross open space, and its diffuse light.
    let s = glossy_scene(0.1);
    for mode in [Mode::Full, Mode::Indirect] {
        let render = |skip: bool| {
            let mut set = settings(mode, 4, 4);
            set.gi.empty_space = skip;
            frames(&s, set, 0, |_| {}, 0)
        };
        let (on, off) = (render(true), render(false));
        let e = rel_mse(&on, &off);
        eprintln!("{mode:?}: relMSE with against without skipping {e}");
        // Measured (128x128, 64^3): 3.9e-5 and 4.1e-5.
        assert!(e < 1e-4, "{mode:?}: relMSE {e}");
    }
}

#[test]
fn a_moving_camera_converges_to_the_whole_cone_set() {
    // The camera steps sideways, and the surfaces behind the pole and the box it now sees
    // have no history: they trace a quarter of the cones a frame. N frames after it stops, the
    // image is near the whole set's from there (the rest of the history was reprojected); the
    // frames at rest trace every block afresh, so one more and it is the whole set's.
    let s = edges_scene();
    let mut moved = s.clone();
    look_at(
        &mut moved,
        Vec3::new(0.6, 1.2, 2.2),
        Vec3::new(0.6, 0.5, -1.0),
        60.0,
    );
    let whole = frames(&moved, settings(Mode::Full, 2, 0), 0, |_| {}, 0);
    let n = 4;
    let camera = moved.camera.clone();
    let step = |after: u32| {
        let camera = camera.clone();
        frames(
            &s,
            settings(Mode::Full, 2, n),
            2,
            move |r| r.camera = camera,
            after,
        )
    };
    let (first, done, rested) = (step(0), step(n - 1), step(n));
    let (e_first, e_done) = (rel_mse(&first, &whole), rel_mse(&done, &whole));
    let e_rested = rel_mse(&rested, &whole);
    eprintln!(
        "relMSE against the whole set: first frame {e_first}, frame {n} {e_done}, frame {} \
         {e_rested}",
        n + 1
    );
    // The first frame's uncovered blocks traced a quarter of the cones.
    assert!(
        e_first > 1e-6,
        "the first frame already matches ({e_first})"
    );
    assert!(e_done < 1e-4, "after {n} frames: relMSE {e_done}");
    // The same cones, summed by subsets: equal to rounding.
    assert!(
        e_rested < 1e-10,
        "after {} frames: relMSE {e_rested}",
        n + 1
    );
}

#[test]
fn a_camera_that_stops_ends_where_a_fresh_start_does() {
    // The camera glides over four frames and stops. Moving, each block's history is blended
    // from the blocks around where its surface was; at rest the blocks trace their cones
    // afresh (N frames) and then the antialiasing mean begins, so the still image is the one a
    // renderer started at that camera shows, mean and all.
    let s = edges_scene();
    let (from, to) = (Vec3::new(0.0, 1.2, 2.2), Vec3::new(0.6, 1.4, 2.0));
    let target = Vec3::new(0.3, 0.5, -1.0);
    let mut set = settings(Mode::Full, 4, 4);
    set.accumulate = 8;
    let mut start = s.clone();
    look_at(&mut start, from, target, 60.0);
    let mut end = s.clone();
    look_at(&mut end, to, target, 60.0);
    let rest = 4 + 8 + 2;
    let glided = render_with(&start, set.clone(), |r| {
        r.render(false).expect("frame");
        for k in 1..=4 {
            let mut at = s.clone();
            look_at(&mut at, from.lerp(to, k as f32 / 4.0), target, 60.0);
            r.camera = at.camera;
            r.render(false).expect("frame");
        }
        for _ in 0..rest {
            r.render(false).expect("frame");
        }
        r.render(true).expect("frame");
    });
    let fresh = frames(&end, set, 8 + 2, |_| {}, 0);
    let e = rel_mse(&glided, &fresh);
    let (d, i) = worst_pixel(&glided, &fresh);
    eprintln!("stopped against fresh: relMSE {e}, worst pixel {i} off by {d}");
    // The same cones summed by subsets, and the same frames of the mean: equal to rounding.
    assert!(e < 1e-10 && d < 1e-4, "relMSE {e}, pixel {i} off by {d}");
}

#[test]
fn a_camera_cut_starts_the_history_over() {
    let s = edges_scene();
    let mut moved = s.clone();
    look_at(
        &mut moved,
        Vec3::new(1.5, 1.0, 1.5),
        Vec3::new(-0.5, 0.3, -1.0),
        60.0,
    );
    let n = 4;
    let camera = moved.camera.clone();
    let cut = frames(
        &s,
        settings(Mode::Full, 2, n),
        3,
        |r| {
            r.camera = camera;
            r.discard_history();
        },
        0,
    );
    let fresh = frames(&moved, settings(Mode::Full, 2, n), 0, |_| {}, 0);
    let e = rel_mse(&cut, &fresh);
    assert!(
        e < 1e-9,
        "the frame after the cut differs from a first frame: {e}"
    );
}

#[test]
fn a_moved_light_is_followed_at_once() {
    let s = edges_scene();
    let mut moved = s.clone();
    moved.lights[0].direction = Vec3::new(0.6, -1.0, -0.3).normalize();
    let n = 4;
    let lights = moved.lights.clone();
    let followed = frames(
        &s,
        settings(Mode::Full, 2, n),
        n,
        |r| r.set_lights(&lights).expect("lights"),
        0,
    );
    // The frame the voxels are lit again traces every cone of every block.
    let fresh = frames(&moved, settings(Mode::Full, 2, n), n - 1, |_| {}, 0);
    let e = rel_mse(&followed, &fresh);
    assert!(e < 1e-6, "the frame after the light moved: relMSE {e}");
}

#[test]
fn a_moving_node_leaves_no_ghost() {
    // The box moves 0.8 m along x: the next frame is the one of a scene built with it there,
    // its old place included.
    let s = edges_scene();
    let node = s.instances[3].node;
    let shift = Mat4::from_translation(Vec3::new(0.8, 0.0, 0.0));
    let mut moved = s.clone();
    moved.instances[3].world = shift;
    let n = 4;
    let mut set = settings(Mode::Full, 2, n);
    set.dynamic_nodes = vec![node];
    let after = frames(&s, set.clone(), n, |r| r.set_node_transform(node, shift), 0);
    let fresh = frames(&moved, set, n - 1, |_| {}, 0);
    let e = rel_mse(&after, &fresh);
    let (d, i) = worst_pixel(&after, &fresh);
    assert!(
        e < 1e-4 && d < 0.01,
        "after the move: relMSE {e}, pixel {i} off by {d}"
    );
}

#[test]
fn every_mode_and_a_resize_stay_clean_with_upsampled_temporal_cones() {
    // The other modes, and a resized frame (new block images and histories): validation-clean
    // and finite (frames() checks both); after the resize the history starts over, so the
    // image is a fresh renderer's at that size.
    let s = edges_scene();
    for mode in [Mode::Ao, Mode::Indirect] {
        let img = frames(&s, settings(mode, 4, 4), 3, |_| {}, 0);
        assert!(img.pixels.iter().any(|p| p[1] > 0.0), "{mode:?} is black");
    }
    let resized = frames(
        &s,
        settings(Mode::Full, 4, 4),
        2,
        |r| r.resize(96, 64).expect("resize"),
        0,
    );
    let mut small = settings(Mode::Full, 4, 4);
    small.width = 96;
    small.height = 64;
    let fresh = frames(&s, small, 0, |_| {}, 0);
    assert_eq!((resized.width, resized.height), (96, 64));
    let e = rel_mse(&resized, &fresh);
    assert!(
        e < 1e-9,
        "the frame after a resize differs from a first frame: {e}"
    );
}
