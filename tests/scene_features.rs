//! Legal but less common glTF features: strips and fans, sparse accessors, normalized
//! texture coordinates, textures without a usable source, scenes without nodes.

mod common;

use glam::Vec3;
use gltf::json::Value;
use std::path::{Path, PathBuf};
use voxgi::scene::builder::{NodeDesc, PrimitiveDesc, SceneBuilder};
use voxgi::scene::{load, Scene};

fn edit(text: &str, f: impl FnOnce(&mut Value)) -> String {
    let mut v: Value = gltf::json::deserialize::from_str(text).unwrap();
    f(&mut v);
    gltf::json::serialize::to_string_pretty(&v).unwrap()
}

/// The builder's buffer as raw bytes (the BIN chunk of its .glb form).
fn buffer_bytes(b: &SceneBuilder) -> Vec<u8> {
    let glb = b.to_glb();
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let at = 20 + json_len;
    let len = u32::from_le_bytes(glb[at..at + 4].try_into().unwrap()) as usize;
    glb[at + 8..at + 8 + len].to_vec()
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn loaded(p: &Path) -> Scene {
    let s = load(p).unwrap_or_else(|e| panic!("{e}"));
    common::assert_well_formed(&s);
    s
}

/// A non-indexed primitive over four points in the z = 0 plane.
fn four_points(order: [[f32; 3]; 4]) -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let m = b.add_mesh(
        "four",
        vec![PrimitiveDesc {
            positions: order.to_vec(),
            ..Default::default()
        }],
    );
    b.add_node(NodeDesc::new("four").mesh(m));
    b
}

#[test]
fn strips_and_fans_become_front_facing_triangles() {
    let dir = common::temp_dir("strip-fan");
    let strip = four_points([
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ]);
    let text = edit(&strip.to_gltf(), |v| {
        v["meshes"][0]["primitives"][0]["mode"] = 5.into()
    });
    let fan = four_points([
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ]);
    let fan_text = edit(&fan.to_gltf(), |v| {
        v["meshes"][0]["primitives"][0]["mode"] = 6.into()
    });
    for (name, t) in [("strip.gltf", text), ("fan.gltf", fan_text)] {
        let s = loaded(&write(&dir, name, t));
        assert_eq!(s.triangle_count(), 2, "{name}");
        assert!(
            s.vertices.iter().all(|v| v.normal == [0.0, 0.0, 1.0]),
            "{name}: every triangle must face +Z"
        );
        assert!(s.warnings.is_empty(), "{name}: {:?}", s.warnings);
    }
}

#[test]
fn sparse_accessors_substitute_values() {
    let dir = common::temp_dir("sparse");
    let b = four_points([
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ]);
    let mut bin = buffer_bytes(&b);
    let base = bin.len();
    bin.extend_from_slice(&1u32.to_le_bytes());
    for x in [5.0f32, 6.0, 7.0] {
        bin.extend_from_slice(&x.to_le_bytes());
    }
    write(&dir, "sparse.bin", &bin);
    let sparse = |v: &mut Value, with_view: bool| {
        v["buffers"][0] = serde_like(&[
            ("byteLength", bin.len().into()),
            ("uri", "sparse.bin".into()),
        ]);
        let views = v["bufferViews"].as_array_mut().unwrap();
        let n = views.len();
        views.push(serde_like(&[
            ("buffer", 0.into()),
            ("byteOffset", base.into()),
            ("byteLength", 4.into()),
        ]));
        views.push(serde_like(&[
            ("buffer", 0.into()),
            ("byteOffset", (base + 4).into()),
            ("byteLength", 12.into()),
        ]));
        let acc = &mut v["accessors"][0];
        if !with_view {
            acc.as_object_mut().unwrap().remove("bufferView");
        }
        acc["sparse"] = serde_like(&[
            ("count", 1.into()),
            (
                "indices",
                serde_like(&[("bufferView", n.into()), ("componentType", 5125.into())]),
            ),
            ("values", serde_like(&[("bufferView", (n + 1).into())])),
        ]);
    };
    let with_view = edit(&b.to_gltf(), |v| sparse(v, true));
    let s = loaded(&write(&dir, "sparse.gltf", with_view));
    let positions: Vec<[f32; 3]> = s
        .indices
        .iter()
        .map(|&i| s.vertices[i as usize].position)
        .collect();
    assert_eq!(
        positions[..3],
        [[0.0, 0.0, 0.0], [5.0, 6.0, 7.0], [0.0, 1.0, 0.0]]
    );

    // Without a bufferView the base values are zeros.
    let zeros = edit(&b.to_gltf(), |v| sparse(v, false));
    let s = loaded(&write(&dir, "sparse-zeros.gltf", zeros));
    let positions: Vec<[f32; 3]> = s
        .indices
        .iter()
        .map(|&i| s.vertices[i as usize].position)
        .collect();
    assert_eq!(positions[..3], [[0.0; 3], [5.0, 6.0, 7.0], [0.0; 3]]);
}

fn serde_like(fields: &[(&str, Value)]) -> Value {
    let mut m = gltf::json::Value::Object(Default::default());
    for (k, v) in fields {
        m[*k] = v.clone();
    }
    m
}

#[test]
fn normalized_texture_coordinates_are_scaled() {
    let dir = common::temp_dir("normalized-uv");
    let b = four_points([
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ]);
    let mut bin = buffer_bytes(&b);
    let base = bin.len();
    for uv in [[0u16, 0], [65535, 0], [0, 65535], [32768, 65535]] {
        for c in uv {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    write(&dir, "uv.bin", &bin);
    let text = edit(&b.to_gltf(), |v| {
        v["buffers"][0] = serde_like(&[("byteLength", bin.len().into()), ("uri", "uv.bin".into())]);
        let nv = v["bufferViews"].as_array().unwrap().len();
        v["bufferViews"].as_array_mut().unwrap().push(serde_like(&[
            ("buffer", 0.into()),
            ("byteOffset", base.into()),
            ("byteLength", 16.into()),
        ]));
        let na = v["accessors"].as_array().unwrap().len();
        v["accessors"].as_array_mut().unwrap().push(serde_like(&[
            ("bufferView", nv.into()),
            ("componentType", 5123.into()),
            ("normalized", true.into()),
            ("count", 4.into()),
            ("type", "VEC2".into()),
        ]));
        v["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = na.into();
    });
    let s = loaded(&write(&dir, "uv.gltf", text));
    let uvs: Vec<[f32; 2]> = s
        .indices
        .iter()
        .map(|&i| s.vertices[i as usize].uv)
        .collect();
    assert_eq!(uvs[..3], [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
    // Generated tangents follow +U, which is +X here.
    let t = s.vertices[s.indices[0] as usize].tangent;
    assert!((Vec3::from_slice(&t[..3]) - Vec3::X).length() < 1e-6 && t[3] == 1.0);
}

#[test]
fn textures_without_a_source_and_scenes_without_nodes() {
    let dir = common::temp_dir("no-source");
    let mut b = four_points([
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ]);
    let img = b.add_image("unused.png");
    b.add_material(voxgi::scene::builder::MaterialDesc {
        base_color_texture: Some(img),
        ..Default::default()
    });
    let text = edit(&b.to_gltf(), |v| {
        v["textures"][0].as_object_mut().unwrap().remove("source");
        v["textures"][0]["extensions"] =
            serde_like(&[("KHR_texture_basisu", serde_like(&[("source", 0.into())]))]);
        v["extensionsUsed"] = vec!["KHR_texture_basisu"].into();
    });
    let s = loaded(&write(&dir, "basisu.gltf", text));
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("texture 0 has no source image")),
        "{:?}",
        s.warnings
    );
    assert!(s.warnings.iter().any(|w| w.contains("KHR_texture_basisu")));

    let empty = r#"{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"name": "nothing"}]}"#;
    let s = loaded(&write(&dir, "empty.gltf", empty));
    assert!(s.instances.is_empty());
    assert!(s.camera.is_default);

    // No scenes at all: every root node is drawn.
    let text = edit(
        &four_points([[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0; 3]]).to_gltf(),
        |v| {
            v.as_object_mut().unwrap().remove("scenes");
            v.as_object_mut().unwrap().remove("scene");
        },
    );
    let s = loaded(&write(&dir, "noscene.gltf", text));
    assert_eq!(s.instances.len(), 1);
}
