//! glTF animations and spinning nodes: loading (and skipping what cannot be used, with a
//! warning), poses over time, and the bounds a motion sweeps.

mod common;

use glam::{Mat4, Quat, Vec3};
use voxgi::scene::{load, Motion};

fn f32s(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// A parent node moved by a linear translation (0 -> (2,0,0) -> (2,1,0) over 2 s) holding a
/// child triangle turned by a linear rotation (0 -> 90 degrees about Y over 2 s), a static
/// triangle, and two channels that cannot be used.
fn animated_scene(dir: &std::path::Path) -> std::path::PathBuf {
    let q = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    let mut bin = Vec::new();
    bin.extend(f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0])); // 0: positions
    bin.extend(f32s(&[0.0, 1.0, 2.0])); // 36: times
    bin.extend(f32s(&[0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 2.0, 1.0, 0.0])); // 48: translations
    bin.extend(f32s(&[0.0, 2.0])); // 84: rotation times
    bin.extend(f32s(&[0.0, 0.0, 0.0, 1.0, q.x, q.y, q.z, q.w])); // 92: rotations
    bin.extend(f32s(&[1.0, 0.0])); // 124: times out of order
    std::fs::write(dir.join("anim.bin"), &bin).unwrap();
    let view = |offset: usize, len: usize| {
        format!(r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{len}}}"#)
    };
    let acc = |view: usize, count: usize, ty: &str, minmax: &str| {
        format!(
            r#"{{"bufferView":{view},"componentType":5126,"count":{count},"type":"{ty}"{minmax}}}"#
        )
    };
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "scene": 0,
  "scenes": [{{"nodes": [0, 2]}}],
  "nodes": [
    {{"name": "parent", "children": [1]}},
    {{"name": "child", "mesh": 0, "translation": [0, 0, 1]}},
    {{"name": "static", "mesh": 0, "translation": [0, 0, -3]}}
  ],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}}}]}}],
  "buffers": [{{"uri": "anim.bin", "byteLength": {len}}}],
  "bufferViews": [{v0}, {v1}, {v2}, {v3}, {v4}, {v5}],
  "accessors": [{a0}, {a1}, {a2}, {a3}, {a4}, {a5}],
  "animations": [{{
    "name": "move",
    "samplers": [
      {{"input": 1, "output": 2, "interpolation": "LINEAR"}},
      {{"input": 3, "output": 4}},
      {{"input": 5, "output": 2}}
    ],
    "channels": [
      {{"sampler": 0, "target": {{"node": 0, "path": "translation"}}}},
      {{"sampler": 1, "target": {{"node": 1, "path": "rotation"}}}},
      {{"sampler": 2, "target": {{"node": 0, "path": "scale"}}}},
      {{"sampler": 0, "target": {{"node": 7, "path": "translation"}}}}
    ]
  }}]
}}"#,
        len = bin.len(),
        v0 = view(0, 36),
        v1 = view(36, 12),
        v2 = view(48, 36),
        v3 = view(84, 8),
        v4 = view(92, 32),
        v5 = view(124, 8),
        a0 = acc(0, 3, "VEC3", r#","min":[0,0,0],"max":[1,1,0]"#),
        a1 = acc(1, 3, "SCALAR", r#","min":[0],"max":[2]"#),
        a2 = acc(2, 3, "VEC3", ""),
        a3 = acc(3, 2, "SCALAR", r#","min":[0],"max":[2]"#),
        a4 = acc(4, 2, "VEC4", ""),
        a5 = acc(5, 2, "SCALAR", r#","min":[0],"max":[1]"#),
    );
    let path = dir.join("animated.gltf");
    std::fs::write(&path, json).unwrap();
    path
}

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
