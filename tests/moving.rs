//! Lights and nodes that move between frames (what the window's keys, animations and spins
//! do): the next frame must be what a fresh renderer makes of the moved scene, shadow maps
//! and voxel lighting included, and a frame where nothing moved must equal the one before.

mod gpu;
use glam::{Mat4, Vec3};
use gpu::*;
use voxgi::gi::GiSettings;
use voxgi::metrics::compare;
use voxgi::output::RadianceImage;
use voxgi::render::{Mode, RenderSettings, Renderer};
use voxgi::scene::{LightKind, Scene};

/// A floor and a wall, a floating square (its own node) casting a shadow, and a spot light.
fn scene() -> (Scene, usize) {
    let mut s = empty_scene();
    let m = lambert(&mut s, Vec3::splat(0.7));
    floor(&mut s, 2.0, m);
    quad(
        &mut s,
        [
            Vec3::new(-2.0, 0.0, -2.0),
            Vec3::new(2.0, 0.0, -2.0),
            Vec3::new(2.0, 2.0, -2.0),
            Vec3::new(-2.0, 2.0, -2.0),
        ],
        m,
    );
    let red = lambert(&mut s, Vec3::new(0.8, 0.1, 0.1));
    let first = s.instances.len();
    quad(
        &mut s,
        [
            Vec3::new(-0.4, 0.8, 0.4),
            Vec3::new(0.4, 0.8, 0.4),
            Vec3::new(0.4, 0.8, -0.4),
            Vec3::new(-0.4, 0.8, -0.4),
        ],
        red,
    );
    // Every quad is its own node; the square's is the one that moves.
    let node = s.instances[first].node;
    s.lights.push(light(
        LightKind::Spot {
            inner_cone: 0.5,
            outer_cone: 0.8,
        },
        Vec3::splat(40.0),
        Vec3::new(0.0, 1.9, 0.0),
        Vec3::NEG_Y,
    ));
    look_at(
        &mut s,
        Vec3::new(0.0, 2.5, 3.0),
        Vec3::new(0.0, 0.3, 0.0),
        60.0,
    );
    (s, node)
}

/// The scene with `node` placed at `world` from the start (what a fresh renderer should make of
/// a moved node).
fn moved_scene(s: &Scene, node: usize, world: Mat4) -> Scene {
    let mut s = s.clone();
    for i in s.instances.iter_mut().filter(|i| i.node == node) {
        i.world = world;
    }
    s
}

fn settings(node: usize) -> RenderSettings {
    RenderSettings {
        width: 48,
        height: 48,
        shadow_resolution: 256,
        mode: Mode::Full,
        gi: GiSettings {
            voxels: 32,
            ..Default::default()
        },
        dynamic_nodes: vec![node],
        // Still frames are compared for equality: one sample per pixel, no antialiasing mean.
        accumulate: 1,
        ..Default::default()
    }
}

fn image(r: &mut Renderer) -> RadianceImage {
    r.render(true).unwrap();
    RadianceImage {
        width: r.settings.width,
        height: r.settings.height,
        pixels: r.radiance(),
    }
}

#[test]
fn moved_lights_and_nodes_render_as_a_fresh_renderer_would() {
    let (s, node) = scene();
    let moved_light = {
        let mut l = s.lights[0].clone();
        l.position = Vec3::new(1.2, 1.9, 0.3);
        l.direction = Vec3::new(-0.5, -1.0, -0.2).normalize();
        l
    };
    let moved_node = Mat4::from_translation(Vec3::new(-0.7, 0.3, 0.2));

    let ctx = context();
    let stats = ctx.stats.clone();
    let (first, again, moved) = {
        let mut r = Renderer::new(&ctx, &s, settings(node)).unwrap();
        let first = image(&mut r);
        let again = image(&mut r);
        r.set_lights(std::slice::from_ref(&moved_light)).unwrap();
        r.set_node_transform(node, moved_node);
        (first, again, image(&mut r))
    };
    // Changing a light's kind is refused, not half done.
    {
        let mut r = Renderer::new(&ctx, &s, settings(node)).unwrap();
        let mut point = moved_light.clone();
        point.kind = LightKind::Point;
        assert!(r.set_lights(&[point]).is_err());
        assert!(r.set_lights(&[]).is_err());
    }
    let fresh = {
        let mut s2 = moved_scene(&s, node, moved_node);
        s2.lights[0] = moved_light;
        let mut r = Renderer::new(&ctx, &s2, settings(node)).unwrap();
        image(&mut r)
    };
    drop(ctx);
    assert_eq!(stats.count(), 0, "{}", stats.messages().join("\n"));

    // Nothing moved: the second frame (shadow maps kept from the first) is the first.
    assert_eq!(first.pixels, again.pixels, "a still frame changed");
    // The move is plain to see ...
    let change = compare(&moved, &first).rel_mse;
    assert!(
        change > 0.01,
        "the moved frame barely differs (relMSE {change})"
    );
    // ... and matches a renderer that started with the moved scene.
    let m = compare(&moved, &fresh);
    assert!(
        m.rel_mse < 1e-6,
        "moved vs fresh: relMSE {} (max of the frames' difference {change})",
        m.rel_mse
    );
}

#[test]
fn a_resized_renderer_keeps_its_voxels_and_matches_a_fresh_one() {
    let (s, node) = scene();
    let sized = |w: u32, h: u32| RenderSettings {
        width: w,
        height: h,
        ..settings(node)
    };
    let ctx = context();
    let stats = ctx.stats.clone();
    let (first, small, back) = {
        let mut r = Renderer::new(&ctx, &s, sized(48, 48)).unwrap();
        let first = image(&mut r);
        r.resize(40, 24).unwrap();
        let small = image(&mut r);
        r.resize(48, 48).unwrap();
        (first, small, image(&mut r))
    };
    let fresh_small = {
        let mut r = Renderer::new(&ctx, &s, sized(40, 24)).unwrap();
        image(&mut r)
    };
    drop(ctx);
    assert_eq!(stats.count(), 0, "{}", stats.messages().join("\n"));
    assert_eq!((small.width, small.height), (40, 24));
    assert_eq!(
        small.pixels, fresh_small.pixels,
        "resized frame differs from a fresh one"
    );
    assert_eq!(back.pixels, first.pixels, "resizing back changed the frame");
}

#[test]
fn a_turn_by_a_hair_changes_nothing() {
    // The bundled Cornell box turned as a whole, a full turn (the identity) and a full turn
    // less 7.5e-7 rad: the walls facing x and the floor now have normals with a tiny z of
    // either sign, which must not change how the cones are laid around them.
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.gltf");
    let mut s = voxgi::scene::load(&path).unwrap();
    let mut spin = s.spin("room").unwrap();
    spin.degrees_per_second = 360.0;
    let motion = voxgi::scene::Motion {
        spin: Some(spin),
        animate: false,
    };
    let dynamic = motion.prepare(&mut s);
    let ctx = context();
    let stats = ctx.stats.clone();
    let mut frames = Vec::new();
    for t in [1.0f32, 0.9999998] {
        let mut r = Renderer::new(
            &ctx,
            &s,
            RenderSettings {
                width: 64,
                height: 64,
                shadow_resolution: 256,
                gi: GiSettings {
                    voxels: 32,
                    ..Default::default()
                },
                dynamic_nodes: dynamic.clone(),
                ..Default::default()
            },
        )
        .unwrap();
        for (node, world) in motion.pose(&s, t) {
            r.set_node_transform(node, world);
        }
        frames.push(image(&mut r));
    }
    drop(ctx);
    assert_eq!(stats.count(), 0, "{}", stats.messages().join("\n"));
    let m = compare(&frames[1], &frames[0]);
    assert!(
        m.rel_mse < 1e-6,
        "relMSE {} between the two turns",
        m.rel_mse
    );
}

#[test]
fn a_node_moving_under_a_point_light_redraws_the_views_it_crosses() {
    // A point light's six views: moving the square redraws only the views its old and new
    // places touch; the frame must still be a fresh renderer's.
    let (mut s, node) = scene();
    s.lights[0] = light(
        LightKind::Point,
        Vec3::splat(8.0),
        Vec3::new(0.3, 1.6, 0.2),
        Vec3::NEG_Y,
    );
    let moved = Mat4::from_translation(Vec3::new(1.1, -0.4, 0.9));
    let ctx = context();
    let stats = ctx.stats.clone();
    let (before, after) = {
        let mut r = Renderer::new(&ctx, &s, settings(node)).unwrap();
        let before = image(&mut r);
        r.set_node_transform(node, moved);
        (before, image(&mut r))
    };
    let fresh = {
        let mut r = Renderer::new(&ctx, &moved_scene(&s, node, moved), settings(node)).unwrap();
        image(&mut r)
    };
    drop(ctx);
    assert_eq!(stats.count(), 0, "{}", stats.messages().join("\n"));
    let change = compare(&after, &before).rel_mse;
    assert!(change > 0.01, "the move barely shows (relMSE {change})");
    let m = compare(&after, &fresh).rel_mse;
    assert!(m < 1e-6, "moved vs fresh: relMSE {m}");
}

#[test]
fn a_still_frame_only_traces_and_a_moved_light_lights_the_voxels_again() {
    // A static scene with two bounces: the voxels' light (bounce included, which adds to the
    // radiance volume in place) is kept while nothing moves, and made again when a light moves.
    let (s, _) = scene();
    let settings = RenderSettings {
        timings: true,
        dynamic_nodes: Vec::new(),
        gi: GiSettings {
            voxels: 32,
            bounces: 2,
            ..Default::default()
        },
        ..settings(0)
    };
    let moved_light = {
        let mut l = s.lights[0].clone();
        l.position = Vec3::new(-0.9, 1.7, 0.6);
        l
    };
    let ctx = context();
    let stats = ctx.stats.clone();
    let runs = |r: &Renderer, pass: &str| {
        r.timer
            .as_ref()
            .expect("lavapipe has timestamps")
            .samples
            .iter()
            .find(|(name, _)| name == pass)
            .map_or(0, |(_, v)| v.len())
    };
    let (first, again, moved, counts) = {
        let mut r = Renderer::new(&ctx, &s, settings.clone()).unwrap();
        let first = image(&mut r);
        let again = image(&mut r);
        let still = ["inject", "bounce", "trace", "voxelize static"].map(|p| runs(&r, p));
        r.set_lights(std::slice::from_ref(&moved_light)).unwrap();
        let moved = image(&mut r);
        let after = ["inject", "bounce", "trace", "voxelize static"].map(|p| runs(&r, p));
        (first, again, moved, [still, after])
    };
    let fresh = {
        let mut s2 = s.clone();
        s2.lights[0] = moved_light;
        let mut r = Renderer::new(&ctx, &s2, settings).unwrap();
        image(&mut r)
    };
    drop(ctx);
    assert_eq!(stats.count(), 0, "{}", stats.messages().join("\n"));
    assert_eq!(
        counts,
        [[1, 1, 2, 1], [2, 2, 3, 1]],
        "inject, bounce, trace and voxelize runs after two still frames, then a moved light"
    );
    assert_eq!(first.pixels, again.pixels, "a still frame changed");
    let change = compare(&moved, &first).rel_mse;
    assert!(change > 0.01, "the light's move barely shows ({change})");
    let m = compare(&moved, &fresh).rel_mse;
    assert!(m < 1e-6, "moved light vs fresh: relMSE {m}");
}
