//! glTF animations and spinning nodes: loading (and skipping what cannot be used, with a
//! warning), poses over time, and the bounds a motion sweeps.

mod common;

use common::animated_scene;
use glam::{Mat4, Vec3};
use voxgi::scene::{load, Motion};

#[test]
fn animations_load_and_unusable_channels_are_skipped_with_a_warning() {
    let dir = common::temp_dir("anim-load");
    let s = load(&animated_scene(&dir)).unwrap();
    common::assert_well_formed(&s);
    assert_eq!(s.animations.len(), 1);
    assert_eq!(s.animations[0].channels.len(), 2, "{:?}", s.warnings);
    assert!((s.animations[0].duration() - 2.0).abs() < 1e-6);
    let joined = s.warnings.join("\n");
    assert!(
        joined.contains("channel 2") && joined.contains("increasing"),
        "{joined}"
    );
    assert!(
        joined.contains("channel 3") && joined.contains("node 7"),
        "{joined}"
    );
    assert_eq!(s.nodes[1].parent, Some(0));
    assert_eq!(s.nodes[2].parent, None);
}

#[test]
fn poses_follow_the_keys_loop_and_stay_inside_the_swept_bounds() {
    let dir = common::temp_dir("anim-pose");
    let s = load(&animated_scene(&dir)).unwrap();
    let motion = Motion {
        spin: None,
        animate: true,
    };
    // Only the child carries a mesh among the moving nodes; the static triangle stays.
    assert_eq!(motion.moving_nodes(&s), vec![1]);
    let child_at = |t: f32| motion.pose(&s, t)[0].1;
    let want = |parent: Vec3, angle: f32| {
        Mat4::from_translation(parent)
            * Mat4::from_translation(Vec3::Z)
            * Mat4::from_rotation_y(angle)
    };
    let quarter = std::f32::consts::FRAC_PI_2;
    for (t, parent, angle) in [
        (0.0, Vec3::ZERO, 0.0),
        (0.5, Vec3::new(1.0, 0.0, 0.0), quarter * 0.25),
        (1.5, Vec3::new(2.0, 0.5, 0.0), quarter * 0.75),
        (2.5, Vec3::new(1.0, 0.0, 0.0), quarter * 0.25), // looped
    ] {
        let got = child_at(t);
        assert!(
            got.abs_diff_eq(want(parent, angle), 1e-5),
            "t = {t}: {got:?}"
        );
    }
    // The rest pose is what the loader placed.
    let placed = s.instances.iter().find(|i| i.node == 1).unwrap().world;
    assert!(placed.abs_diff_eq(want(Vec3::ZERO, 0.0), 1e-6));

    let swept = motion.swept_bounds(&s);
    for k in 0..=40 {
        let t = k as f32 * 0.05;
        for p in [Vec3::ZERO, Vec3::X, Vec3::Y] {
            let q = child_at(t).transform_point3(p);
            assert!(
                q.cmpge(swept.min - 1e-4).all() && q.cmple(swept.max + 1e-4).all(),
                "t = {t}: {q:?} outside {swept:?}"
            );
        }
    }
    // The furthest +X reach: at 1 s, parent at x = 2 and the triangle's (1, 0, 0) turned
    // 45 degrees; and the static triangle at z = -3.
    let reach = 2.0 + std::f32::consts::FRAC_1_SQRT_2;
    assert!((swept.max.x - reach).abs() < 0.02 * reach, "{swept:?}");
    assert!(swept.min.z <= -3.0 + 1e-4, "{swept:?}");
}

#[test]
fn a_spin_turns_a_node_and_its_children_about_its_own_vertical_axis() {
    let dir = common::temp_dir("anim-spin");
    let s = load(&animated_scene(&dir)).unwrap();
    let motion = Motion {
        spin: Some(s.spin("parent").unwrap()),
        animate: false,
    };
    assert_eq!(motion.moving_nodes(&s), vec![1]);
    // 90 degrees per second: after 1 s the child (1 m along +Z of the parent) is 1 m along +X.
    let world = motion.pose(&s, 1.0)[0].1;
    let p = world.transform_point3(Vec3::ZERO);
    assert!(p.distance(Vec3::X) < 1e-5, "{p:?}");
    // A full turn comes back.
    let back = motion.pose(&s, 4.0)[0].1;
    assert!(back.abs_diff_eq(motion.pose(&s, 0.0)[0].1, 1e-5));
    // The swept bounds hold the whole circle.
    let b = motion.swept_bounds(&s);
    assert!(
        b.min.x <= -1.0 && b.max.x >= 1.0 && b.min.z <= -1.0,
        "{b:?}"
    );

    let e = s.spin("nope").unwrap_err();
    assert!(
        e.contains("nope") && e.contains("parent") && e.contains("animated.gltf"),
        "{e}"
    );
}

#[test]
fn a_node_placed_by_a_matrix_spins_about_the_vertical_through_its_origin() {
    use voxgi::scene::builder::*;
    // A unit cube placed by a matrix that scales it unevenly and moves it to (2, 0, 0).
    let mut b = SceneBuilder::new();
    let m = b.add_material(MaterialDesc::lambertian("white", [0.8; 3]));
    let cube = b.add_mesh("cube", vec![unit_cube(Some(m))]);
    let placed = Mat4::from_translation(Vec3::new(2.0, 0.0, 0.0))
        * Mat4::from_scale(Vec3::new(1.0, 2.0, 0.5));
    b.add_node(
        NodeDesc::new("placed")
            .mesh(cube)
            .matrix(placed.to_cols_array()),
    );
    let dir = common::temp_dir("anim-matrix-spin");
    let path = dir.join("matrix.gltf");
    b.write(&path).unwrap();
    let s = load(&path).unwrap();
    let motion = Motion {
        spin: Some(s.spin("placed").unwrap()),
        animate: false,
    };
    // 90 degrees per second: after 1 s the node's local +X (1 m: its x scale is 1) lies 1 m
    // along -Z of its origin, which stays put, and its local +Y keeps the scale of 2.
    let world = motion.pose(&s, 1.0)[0].1;
    let origin = Vec3::new(2.0, 0.0, 0.0) - s.origin.as_vec3();
    assert!(world.transform_point3(Vec3::ZERO).distance(origin) < 1e-5);
    let p = world.transform_point3(Vec3::X);
    assert!(p.distance(origin + Vec3::NEG_Z) < 1e-5, "{p:?}");
    let q = world.transform_point3(Vec3::Y);
    assert!(q.distance(origin + 2.0 * Vec3::Y) < 1e-5, "{q:?}");
}
