//! Every scene in ../shared/scenes renders in `direct` mode with zero validation messages and
//! no NaN or Inf pixel. Scenes without lights get a sun so that shadows are exercised too.

mod gpu;
use glam::Vec3;
use std::path::{Path, PathBuf};
use voxgi::render::{Mode, RenderSettings};
use voxgi::scene::{self, Light, LightKind};

fn shared_scenes() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes");
    let mut out = Vec::new();
    for dir in std::fs::read_dir(&root).expect("../shared/scenes is beside the project") {
        let dir = dir.unwrap().path();
        if !dir.is_dir() {
            continue;
        }
        for f in std::fs::read_dir(&dir).unwrap() {
            let f = f.unwrap().path();
            if matches!(
                f.extension().and_then(|e| e.to_str()),
                Some("gltf") | Some("glb")
            ) {
                out.push(f);
            }
        }
    }
    out.sort();
    out
}

fn render_scene(path: &Path, mode: Mode) {
    let mut s = scene::load(path).unwrap_or_else(|e| panic!("{e}"));
    if s.lights.is_empty() {
        s.lights.push(Light {
            name: Some("sun".into()),
            kind: LightKind::Directional,
            radiance: Vec3::splat(3.0),
            range: None,
            position: Vec3::ZERO,
            direction: Vec3::new(-0.3, -1.0, -0.4).normalize(),
        });
    }
    let img = gpu::render(
        &s,
        RenderSettings {
            width: 64,
            height: 64,
            shadow_resolution: 512,
            mode,
            gi: voxgi::gi::GiSettings {
                voxels: 64,
                ..Default::default()
            },
            ..Default::default()
        },
    );
    let bad = img
        .pixels
        .iter()
        .flatten()
        .filter(|v| !v.is_finite())
        .count();
    assert_eq!(bad, 0, "{}: {bad} NaN/Inf values", path.display());
    // Something must be lit, unless the scene is flat edge-on to the default camera (which
    // looks along -Z): TwoSidedPlane lies in the XZ plane.
    let e = s.bounds.extent();
    let edge_on = s.camera.is_default && (e.x == 0.0 || e.y == 0.0);
    let lit = img
        .pixels
        .iter()
        .filter(|p| p.iter().any(|&c| c > 0.0))
        .count();
    assert!(lit > 0 || edge_on, "{}: the image is black", path.display());
}

#[test]
fn every_shared_scene_renders_clean() {
    let scenes = shared_scenes();
    assert!(
        scenes.len() >= 17,
        "expected the shared scenes, found {scenes:?}"
    );
    for s in &scenes {
        eprintln!("rendering {}", s.display());
        render_scene(s, Mode::Direct);
    }
}

#[test]
fn every_shared_scene_renders_full_frames_at_64_cubed() {
    for s in &shared_scenes() {
        eprintln!("rendering {}", s.display());
        render_scene(s, Mode::Full);
    }
}
