//! Helpers shared by the scene tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use voxgi::scene::Scene;

/// The shared real-world models (never copied into the project).
pub fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes")
}

/// Runs the voxgi binary; fails the test if it panicked. Returns (success, stdout, stderr).
pub fn voxgi(args: &[&str]) -> (bool, String, String) {
    voxgi_in(Path::new("."), args)
}

/// `voxgi` run in `dir` (for checking what it leaves in its working directory).
pub fn voxgi_in(dir: &Path, args: &[&str]) -> (bool, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_voxgi"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run voxgi");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "voxgi panicked:\n{stderr}");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    (out.status.success(), stdout, stderr)
}

/// A fresh, empty directory for one test's fixtures, under target/tmp.
pub fn temp_dir(test: &str) -> PathBuf {
    let dir =
        Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("voxgi-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Checks what every loaded scene must satisfy for the renderer to use it safely.
pub fn assert_well_formed(s: &Scene) {
    if let Err(e) = s.check() {
        panic!("{}: {e}", s.source.display());
    }
}

fn f32s(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// A parent node moved by a linear translation (0 -> (2,0,0) -> (2,1,0) over 2 s) holding a
/// child triangle turned by a linear rotation (0 -> 90 degrees about Y over 2 s), a static
/// triangle, and two channels that cannot be used.
pub fn animated_scene(dir: &std::path::Path) -> std::path::PathBuf {
    let q = glam::Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
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
