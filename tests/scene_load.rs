//! Every model in ../shared/scenes loads, with the properties each one exists to exercise.

mod common;

use common::{assert_well_formed, scenes_dir};
use glam::Vec3;
use std::collections::BTreeMap;
use std::path::PathBuf;
use voxgi::scene::{load, AlphaMode, LightKind, Scene};

/// The .gltf/.glb files under a folder (recursively), sorted.
fn models_in(dir: &std::path::Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p
                .extension()
                .is_some_and(|x| x.eq_ignore_ascii_case("gltf") || x.eq_ignore_ascii_case("glb"))
            {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// Loads the one model in a scenes/ folder.
fn load_folder(folder: &str) -> Scene {
    let models = models_in(&scenes_dir().join(folder));
    assert_eq!(
        models.len(),
        1,
        "{folder}: expected one model, found {models:?}"
    );
    load(&models[0]).unwrap_or_else(|e| panic!("{e}"))
}

/// The triangle column of scenes/README.md: folder -> count. A row may name several folders
/// ("A, B") with one shared count or one count each ("7,774 / 5,240").
fn readme_triangle_counts() -> BTreeMap<String, usize> {
    let text = std::fs::read_to_string(scenes_dir().join("README.md")).unwrap();
    let mut out = BTreeMap::new();
    for line in text.lines() {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if cells.len() < 4 {
            continue;
        }
        let counts: Vec<Option<usize>> = cells[2]
            .split('/')
            .map(|c| c.trim().replace(',', "").parse().ok())
            .collect();
        if counts.iter().any(Option::is_none) {
            continue;
        }
        let folders: Vec<&str> = cells[1].split(',').map(str::trim).collect();
        for (k, f) in folders.iter().enumerate() {
            let c = if counts.len() == 1 {
                counts[0]
            } else {
                counts[k]
            };
            out.insert(f.to_string(), c.unwrap());
        }
    }
    out
}

#[test]
fn every_shared_scene_loads_with_the_documented_triangle_count() {
    let table = readme_triangle_counts();
    assert!(table.len() >= 15, "README table not understood: {table:?}");
    let mut folders: Vec<PathBuf> = std::fs::read_dir(scenes_dir())
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_dir())
        .collect();
    folders.sort();
    let mut checked = 0;
    for folder in folders {
        let name = folder.file_name().unwrap().to_string_lossy().to_string();
        let models = models_in(&folder);
        assert!(!models.is_empty(), "{name}: no model");
        for m in models {
            let s = load(&m).unwrap_or_else(|e| panic!("{e}"));
            assert_well_formed(&s);
            // The table counts each mesh's triangles once, however many nodes draw it.
            if let Some(&expected) = table.get(&name) {
                assert_eq!(s.stored_triangle_count(), expected, "{name}");
                checked += 1;
            }
        }
    }
    assert!(checked >= 15);
}

#[test]
fn triangle_counts_of_the_brief() {
    // Scenes without instancing: drawn triangles equal stored ones.
    for (folder, n) in [
        ("Sponza", 262_267),
        ("CornellBox-Original", 32),
        ("Box", 12),
        ("BoxTextured", 12),
        ("TwoSidedPlane", 2),
        ("LightsPunctualLamp", 6_000),
        ("DamagedHelmet", 15_452),
    ] {
        let s = load_folder(folder);
        assert_eq!(s.triangle_count(), n, "{folder}");
        assert_eq!(s.stored_triangle_count(), n, "{folder}");
    }
    // Instanced meshes are stored once and drawn per node.
    let nv = load_folder("CornellBox-nvpro");
    assert_eq!(
        (nv.stored_triangle_count(), nv.triangle_count()),
        (16_720, 16_732)
    );
    let neg = load_folder("NegativeScaleTest");
    assert_eq!(
        (neg.stored_triangle_count(), neg.triangle_count()),
        (3_884, 7_724)
    );
    assert!(neg.instances.len() > neg.primitives.len());
}

#[test]
fn cornell_box_nvpro_loads_despite_breaking_the_rules() {
    let s = load_folder("CornellBox-nvpro");
    assert!(!s.warnings.is_empty());
    assert!(
        s.warnings.iter().any(|w| w.contains("NV_materials_mdl")),
        "{:?}",
        s.warnings
    );
    // It has a camera: a perspective one with a finite far plane.
    assert!(!s.camera.is_default);
    assert!((s.camera.yfov - 0.717_541_46).abs() < 1e-6);
    assert_eq!((s.camera.znear, s.camera.zfar), (0.1, 1000.0));
    assert!((s.camera.eye() - Vec3::new(0.0, 0.0, 19.992092)).length() < 1e-4);
    // emissiveFactor 10 without the strength extension.
    assert!(s.materials.iter().any(|m| m.emissive == Vec3::splat(10.0)));
}

#[test]
fn sponza_has_alpha_masked_materials_and_textures() {
    let s = load_folder("Sponza");
    assert!(s
        .materials
        .iter()
        .any(|m| matches!(m.alpha_mode, AlphaMode::Mask(c) if c > 0.0 && c < 1.0)));
    assert!(s.textures.len() > 50);
    assert!(s.materials.iter().any(|m| m.normal_tex.is_some()));
}

#[test]
fn emissive_strength_gives_hdr_emission() {
    let s = load_folder("EmissiveStrengthTest");
    assert!(s.materials.iter().any(|m| m.emissive.max_element() > 1.0));
}

#[test]
fn lights_punctual_lamp_has_five_point_lights() {
    let s = load_folder("LightsPunctualLamp");
    let points: Vec<_> = s
        .lights
        .iter()
        .filter(|l| l.kind == LightKind::Point)
        .collect();
    assert_eq!(points.len(), 5);
    assert!(points.iter().all(|l| l.radiance.max_element() > 0.0));
    // Light 0 ('Point'): radiance = color x intensity 15, placed by its node's matrix.
    let first = points
        .iter()
        .find(|l| l.name.as_deref() == Some("Point"))
        .unwrap();
    let expected = Vec3::new(1.0, 0.631_875, 0.239_099_76) * 15.0;
    assert!((first.radiance - expected).abs().max_element() < 1e-4);
    let at = Vec3::new(0.046_223_555, 0.907_797_3, 0.006_696_629);
    assert!((first.position - at).abs().max_element() < 1e-6);
}

#[test]
fn negative_scale_nodes_flip_winding() {
    let s = load_folder("NegativeScaleTest");
    assert!(s.instances.iter().any(|i| i.flips_winding()));
    assert!(s.instances.iter().any(|i| !i.flips_winding()));
}

#[test]
fn specular_test_reads_khr_materials_specular() {
    let s = load_folder("SpecularTest");
    assert!(s.materials.iter().any(|m| m.specular_factor < 1.0));
    assert!(s.materials.iter().any(|m| m.specular_color != Vec3::ONE));
    assert!(s
        .materials
        .iter()
        .any(|m| m.specular_tex.is_some() || m.specular_color_tex.is_some()));
}

#[test]
fn two_sided_plane_is_double_sided() {
    let s = load_folder("TwoSidedPlane");
    assert!(s.materials.iter().all(|m| m.double_sided));
}

#[test]
fn alpha_blend_mode_test_has_all_modes() {
    let s = load_folder("AlphaBlendModeTest");
    let modes: Vec<AlphaMode> = s.materials.iter().map(|m| m.alpha_mode).collect();
    assert!(modes.contains(&AlphaMode::Opaque));
    assert!(modes.contains(&AlphaMode::Blend));
    assert!(modes.iter().any(|m| matches!(m, AlphaMode::Mask(_))));
}

#[test]
fn supplied_tangents_are_kept() {
    // The mirror test supplies tangents with both handednesses.
    let s = load_folder("NormalTangentMirrorTest");
    assert!(s.vertices.iter().any(|v| v.tangent[3] < 0.0));
    assert!(s.vertices.iter().any(|v| v.tangent[3] > 0.0));
}

#[test]
fn cornell_box_original_uses_the_conventions_default_camera() {
    let s = load_folder("CornellBox-Original");
    assert!(s.camera.is_default);
    // Bounds: the union of the transformed primitive bounds, recomputed from the vertices.
    let mut b = voxgi::scene::Aabb::EMPTY;
    for i in &s.instances {
        let p = &s.primitives[i.primitive as usize];
        for &k in &s.indices[p.first_index as usize..(p.first_index + p.index_count) as usize] {
            b.extend(
                i.world
                    .transform_point3(Vec3::from(s.vertices[k as usize].position)),
            );
        }
    }
    assert!((b.min - s.bounds.min).abs().max_element() < 1e-5);
    assert!((b.max - s.bounds.max).abs().max_element() < 1e-5);

    let c = s.bounds.center();
    let e = s.bounds.extent();
    let d = 0.5 * e.x.max(e.y) / 20f32.to_radians().tan();
    let eye = Vec3::new(c.x, c.y, s.bounds.max.z + d);
    assert!((s.camera.eye() - eye).abs().max_element() <= 1e-6 * eye.length().max(1.0));
    assert!((s.camera.yfov - 40f32.to_radians()).abs() < 1e-7);
    // Looking along -Z with +Y up: no rotation.
    let r = s.camera.world;
    assert_eq!(r.x_axis, glam::Vec4::X);
    assert_eq!(r.y_axis, glam::Vec4::Y);
    assert_eq!(r.z_axis, glam::Vec4::Z);
    // The whole box lies between the clip planes.
    assert!(s.camera.znear < d && s.camera.zfar > d + e.z);
}
