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
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_voxgi"))
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
    let name = s.source.display();
    let nv = s.vertices.len();
    assert!(
        s.indices.iter().all(|&i| (i as usize) < nv),
        "{name}: index out of range"
    );
    for v in &s.vertices {
        let all = v
            .position
            .iter()
            .chain(&v.normal)
            .chain(&v.uv)
            .chain(&v.tangent);
        assert!(
            all.clone().all(|x| x.is_finite()),
            "{name}: non-finite vertex {v:?}"
        );
        let n = glam::Vec3::from(v.normal);
        assert!(
            (n.length() - 1.0).abs() < 1e-3,
            "{name}: normal not unit {v:?}"
        );
        let t = glam::Vec3::from_slice(&v.tangent[..3]);
        assert!(
            (t.length() - 1.0).abs() < 1e-3,
            "{name}: tangent not unit {v:?}"
        );
        assert!(
            t.dot(n).abs() < 1e-3,
            "{name}: tangent not orthogonal {v:?}"
        );
        assert!(
            v.tangent[3] == 1.0 || v.tangent[3] == -1.0,
            "{name}: handedness {v:?}"
        );
    }
    for p in &s.primitives {
        assert_eq!(p.index_count % 3, 0);
        assert!(p.index_count > 0);
        assert!((p.first_index + p.index_count) as usize <= s.indices.len());
        assert!(
            (p.material as usize) < s.materials.len(),
            "{name}: material index"
        );
        assert!(!p.bounds.is_empty());
    }
    for i in &s.instances {
        assert!((i.primitive as usize) < s.primitives.len());
        assert!(i.world.is_finite());
    }
    for m in &s.materials {
        for t in [
            m.base_color_tex,
            m.metallic_roughness_tex,
            m.normal_tex,
            m.emissive_tex,
            m.specular_tex,
            m.specular_color_tex,
        ]
        .into_iter()
        .flatten()
        {
            let tex = &s.textures[t.texture as usize];
            assert_eq!(tex.rgba8.len(), (tex.width * tex.height * 4) as usize);
        }
        assert!(m.base_color.is_finite() && m.emissive.is_finite());
    }
    // Colour textures are sRGB, data textures linear.
    for m in &s.materials {
        let srgb = |t: Option<voxgi::scene::TexRef>| t.map(|t| s.textures[t.texture as usize].srgb);
        assert_ne!(srgb(m.base_color_tex), Some(false));
        assert_ne!(srgb(m.emissive_tex), Some(false));
        assert_ne!(srgb(m.specular_color_tex), Some(false));
        assert_ne!(srgb(m.normal_tex), Some(true));
        assert_ne!(srgb(m.metallic_roughness_tex), Some(true));
        assert_ne!(srgb(m.specular_tex), Some(true));
    }
    for l in &s.lights {
        assert!(l.radiance.is_finite() && l.position.is_finite());
        assert!((l.direction.length() - 1.0).abs() < 1e-4);
    }
    let c = &s.camera;
    assert!(c.world.is_finite() && c.yfov > 0.0 && c.znear > 0.0 && c.zfar > c.znear);
    if !s.instances.is_empty() {
        assert!(!s.bounds.is_empty());
    }
}
