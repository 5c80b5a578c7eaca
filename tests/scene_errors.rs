//! Broken files: each is a clear error (naming the file and the problem) or a warning, and
//! never a panic. Fixtures are made with the builder plus edits of the JSON.

mod common;

use common::temp_dir;
use gltf::json::Value;
use std::path::{Path, PathBuf};
use voxgi::scene::builder::{quad, MaterialDesc, NodeDesc, PrimitiveDesc, SceneBuilder};
use voxgi::scene::{load, Scene, SceneError};

/// One grey quad (indexed, with normals) on one node.
fn quad_scene() -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let grey = b.add_material(MaterialDesc::lambertian("grey", [0.5, 0.5, 0.5]));
    let mesh = b.add_mesh(
        "quad",
        vec![quad(
            [
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            [0.0, 0.0, 1.0],
            Some(grey),
        )],
    );
    b.add_node(NodeDesc::new("quad").mesh(mesh));
    b
}

fn edit(text: &str, f: impl FnOnce(&mut Value)) -> String {
    let mut v: Value = gltf::json::deserialize::from_str(text).unwrap();
    f(&mut v);
    gltf::json::serialize::to_string_pretty(&v).unwrap()
}

fn write(dir: &Path, name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// Loads expecting failure; checks the message names the file and contains every `needle`.
fn expect_error(path: &Path, needles: &[&str]) -> SceneError {
    let e = match load(path) {
        Ok(_) => panic!("{} loaded but should not", path.display()),
        Err(e) => e,
    };
    let msg = e.to_string();
    let file = path.file_name().unwrap().to_string_lossy();
    assert!(
        msg.contains(&*file),
        "message does not name the file: {msg}"
    );
    for n in needles {
        assert!(msg.contains(n), "message lacks {n:?}: {msg}");
    }
    e
}

fn expect_warning(s: &Scene, needles: &[&str]) {
    assert!(
        s.warnings
            .iter()
            .any(|w| needles.iter().all(|n| w.contains(n))),
        "no warning with {needles:?} in {:?}",
        s.warnings
    );
}

#[test]
fn nonexistent_file() {
    let dir = temp_dir("nonexistent");
    expect_error(&dir.join("nowhere.gltf"), &["does not exist"]);
}

#[test]
fn truncated_gltf() {
    let dir = temp_dir("truncated-gltf");
    let text = quad_scene().to_gltf();
    let p = write(&dir, "half.gltf", &text[..text.len() / 2]);
    expect_error(&p, &["truncated"]);
    let p = write(&dir, "empty.gltf", "");
    expect_error(&p, &["empty"]);
}

#[test]
fn invalid_json() {
    let dir = temp_dir("invalid-json");
    let p = write(
        &dir,
        "garbage.gltf",
        "{ \"asset\": { \"version\": \"2.0\" }, oops }",
    );
    expect_error(&p, &["invalid JSON", "line 1"]);
    let p = write(&dir, "array.gltf", "[1, 2, 3]");
    expect_error(&p, &["not a valid glTF"]);
    let p = write(&dir, "noasset.gltf", "{ \"nodes\": [] }");
    expect_error(&p, &["asset"]);
    let deep = format!("{}{}", "[".repeat(10_000), "]".repeat(10_000));
    let p = write(&dir, "deep.gltf", deep);
    load(&p).unwrap_err();
}

#[test]
fn truncated_and_invalid_glb() {
    let dir = temp_dir("glb");
    let glb = quad_scene().to_glb();
    let ok = write(&dir, "ok.glb", &glb);
    let s = load(&ok).unwrap();
    assert_eq!(s.triangle_count(), 2);

    let p = write(&dir, "half.glb", &glb[..glb.len() / 2]);
    expect_error(&p, &["truncated"]);
    let p = write(&dir, "tiny.glb", &glb[..7]);
    expect_error(&p, &["truncated", "12-byte header"]);

    // Found by the fuzzer: the BIN chunk's type turned into a line break and its length past
    // the end; the message showed the type as it was, over two lines.
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let bin_header = 20 + json_len;
    let mut broken_chunk = glb.clone();
    broken_chunk[bin_header..bin_header + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    broken_chunk[bin_header + 4..bin_header + 8].copy_from_slice(b"}\n\n ");
    let p = write(&dir, "chunk.glb", &broken_chunk);
    let e = expect_error(&p, &["truncated .glb: chunk 1 ('}')"]);
    assert!(!e.to_string().contains('\n'), "{e}");

    let mut wrong_magic = glb.clone();
    wrong_magic[..4].copy_from_slice(b"glTX");
    let p = write(&dir, "magic.glb", &wrong_magic);
    expect_error(&p, &["invalid .glb header", "glTX"]);

    let mut version1 = glb.clone();
    version1[4..8].copy_from_slice(&1u32.to_le_bytes());
    let p = write(&dir, "version.glb", &version1);
    expect_error(&p, &["invalid .glb header", "version 1"]);

    let mut not_json = glb.clone();
    not_json[16..20].copy_from_slice(b"BIN\0");
    let p = write(&dir, "chunk.glb", &not_json);
    expect_error(&p, &["first chunk", "not JSON"]);

    // A BIN chunk shorter than the buffer's byteLength.
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let bin_at = 20 + json_len;
    let mut short = glb[..bin_at + 8 + 8].to_vec();
    short[bin_at..bin_at + 4].copy_from_slice(&8u32.to_le_bytes());
    let n = short.len() as u32;
    short[8..12].copy_from_slice(&n.to_le_bytes());
    let p = write(&dir, "shortbin.glb", &short);
    expect_error(&p, &["buffer 0", "shorter than declared"]);
}

#[test]
fn missing_and_short_bin() {
    let dir = temp_dir("bin");
    let text = quad_scene().to_gltf();
    let external = edit(&text, |v| v["buffers"][0]["uri"] = "geometry.bin".into());
    let p = write(&dir, "missing.gltf", &external);
    expect_error(&p, &["missing buffer file", "geometry.bin"]);

    write(&dir, "geometry.bin", [0u8; 16]);
    let p = write(&dir, "short.gltf", &external);
    expect_error(&p, &["buffer 0", "geometry.bin", "shorter than declared"]);

    let bad64 = edit(&text, |v| {
        v["buffers"][0]["uri"] = "data:application/octet-stream;base64,@@@@".into()
    });
    let p = write(&dir, "base64.gltf", &bad64);
    expect_error(&p, &["buffer 0", "base64"]);

    let web = edit(&text, |v| {
        v["buffers"][0]["uri"] = "https://example.com/x.bin".into()
    });
    let p = write(&dir, "web.gltf", &web);
    expect_error(&p, &["unsupported URI scheme", "https"]);
}

#[test]
fn external_bin_with_escaped_name_loads() {
    let dir = temp_dir("external-bin");
    let b = quad_scene();
    let glb = b.to_glb();
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let bin = &glb[20 + json_len + 8..];
    write(&dir, "my geometry.bin", bin);
    let text = edit(&b.to_gltf(), |v| {
        v["buffers"][0]["uri"] = "my%20geometry.bin".into()
    });
    let p = write(&dir, "external.gltf", text);
    let s = load(&p).unwrap();
    assert_eq!(s.triangle_count(), 2);
}

#[test]
fn accessor_out_of_range() {
    let dir = temp_dir("accessor-range");
    let text = quad_scene().to_gltf();
    let big = edit(&text, |v| v["accessors"][0]["count"] = 1000.into());
    let p = write(&dir, "count.gltf", big);
    expect_error(
        &p,
        &["accessor 0", "mesh 0 ('quad')", "POSITION", "out of range"],
    );

    let offset = edit(&text, |v| {
        v["accessors"][2]["byteOffset"] = 4_000_000_000u64.into()
    });
    let p = write(&dir, "offset.gltf", offset);
    expect_error(
        &p,
        &["accessor 2", "indices of mesh 0 ('quad')", "out of range"],
    );

    let view = edit(&text, |v| {
        v["bufferViews"][1]["byteLength"] = 1_000_000.into()
    });
    let p = write(&dir, "view.gltf", view);
    expect_error(&p, &["bufferView 1", "buffer 0"]);

    let missing = edit(&text, |v| {
        v["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = 99.into()
    });
    let p = write(&dir, "noaccessor.gltf", missing);
    expect_error(&p, &["accessor 99", "NORMAL of mesh 0 ('quad')"]);
}

#[test]
fn index_out_of_range() {
    let dir = temp_dir("index-range");
    let mut b = SceneBuilder::new();
    let mesh = b.add_mesh(
        "bad indices",
        vec![PrimitiveDesc {
            positions: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            indices: Some(vec![0, 1, 7]),
            ..Default::default()
        }],
    );
    b.add_node(NodeDesc::new("n").mesh(mesh));
    let p = write(&dir, "indices.gltf", b.to_gltf());
    expect_error(&p, &["index 7", "bad indices", "out of range"]);
}

#[test]
fn wrong_position_type() {
    let dir = temp_dir("position-type");
    let text = edit(&quad_scene().to_gltf(), |v| {
        v["accessors"][0]["type"] = "VEC2".into();
        v["accessors"][0]["min"] = Value::Null;
        v["accessors"][0]["max"] = Value::Null;
    });
    let p = write(&dir, "vec2.gltf", text);
    expect_error(&p, &["POSITION", "VEC2 FLOAT", "expected VEC3 FLOAT"]);
}

#[test]
fn nan_positions_drop_their_triangles() {
    let dir = temp_dir("nan");
    let mut b = SceneBuilder::new();
    let nan = f32::NAN;
    let mesh = b.add_triangles(
        "spiky",
        &[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [nan, 0.0, 1.0],
            [0.0, f32::INFINITY, 1.0],
        ],
        None,
        None,
    );
    b.add_node(NodeDesc::new("n").mesh(mesh));
    let p = write(&dir, "nan.gltf", b.to_gltf());
    let s = load(&p).unwrap();
    common::assert_well_formed(&s);
    assert_eq!(s.triangle_count(), 1);
    expect_warning(&s, &["spiky", "NaN"]);
    assert!(s.bounds.max.is_finite());
}

#[test]
fn meshes_without_triangles_are_skipped() {
    let dir = temp_dir("no-triangles");
    let mut b = quad_scene();
    let nan = [f32::NAN; 3];
    let empty = b.add_triangles("all nan", &[nan, nan, nan], None, None);
    b.add_node(NodeDesc::new("empty").mesh(empty));
    let two = b.add_mesh(
        "two points",
        vec![PrimitiveDesc {
            positions: vec![[0.0; 3], [1.0, 0.0, 0.0]],
            ..Default::default()
        }],
    );
    b.add_node(NodeDesc::new("two").mesh(two));
    let text = edit(&b.to_gltf(), |v| {
        // The quad mesh gets a second primitive drawn as points.
        let p = v["meshes"][0]["primitives"][0].clone();
        let mut points = p.clone();
        points["mode"] = 0.into();
        v["meshes"][0]["primitives"]
            .as_array_mut()
            .unwrap()
            .push(points);
    });
    let p = write(&dir, "empty.gltf", text);
    let s = load(&p).unwrap();
    common::assert_well_formed(&s);
    assert_eq!(s.triangle_count(), 2);
    expect_warning(&s, &["all nan", "no triangles"]);
    expect_warning(&s, &["two points", "no triangles"]);
    expect_warning(&s, &["mesh 0 ('quad') primitive 1", "Points", "skipped"]);
}

#[test]
fn undecodable_and_missing_textures_are_warnings() {
    let dir = temp_dir("textures");
    let mut b = quad_scene();
    let broken = b.add_image("broken.png");
    let missing = b.add_image("missing.png");
    let good = b.add_image("good.png");
    let mut mats = Vec::new();
    for (name, img) in [("b", broken), ("m", missing), ("g", good)] {
        mats.push(b.add_material(MaterialDesc {
            base_color_texture: Some(img),
            ..MaterialDesc::lambertian(name, [1.0; 3])
        }));
    }
    for (k, &m) in mats.iter().enumerate() {
        let mut q = quad(
            [
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            [0.0, 0.0, 1.0],
            Some(m),
        );
        q.uvs = Some(vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]);
        let mesh = b.add_mesh(&format!("textured {k}"), vec![q]);
        b.add_node(NodeDesc::new("t").mesh(mesh));
    }
    write(
        &dir,
        "broken.png",
        b"\x89PNG\r\n\x1a\n this is not really a png",
    );
    let mut img = image::RgbaImage::new(2, 3);
    img.put_pixel(1, 2, image::Rgba([10, 20, 30, 40]));
    img.save(dir.join("good.png")).unwrap();
    let p = write(&dir, "textures.gltf", b.to_gltf());
    let s = load(&p).unwrap();
    common::assert_well_formed(&s);
    expect_warning(&s, &["broken.png", "could not be decoded"]);
    expect_warning(&s, &["missing.png", "does not exist"]);
    let by_name = |n: &str| {
        s.materials
            .iter()
            .find(|m| m.name.as_deref() == Some(n))
            .unwrap()
    };
    assert!(by_name("b").base_color_tex.is_none());
    assert!(by_name("m").base_color_tex.is_none());
    let t = by_name("g").base_color_tex.unwrap();
    let tex = &s.textures[t.texture as usize];
    assert!(tex.srgb);
    assert_eq!((tex.width, tex.height), (2, 3));
    assert_eq!(&tex.rgba8[(2 * 2 + 1) * 4..][..4], &[10, 20, 30, 40]);

    // Unsupported formats (KTX2 here) take the same warning path.
    let ktx = edit(&b.to_gltf(), |v| {
        v["images"][2]["uri"] = "texture.ktx2".into()
    });
    write(&dir, "texture.ktx2", b"\xABKTX 20\xBB\r\n\x1a\n rest of it");
    let p = write(&dir, "ktx.gltf", ktx);
    let s = load(&p).unwrap();
    expect_warning(&s, &["texture.ktx2", "not in a supported image format"]);
    assert!(s.materials.iter().all(|m| m.base_color_tex.is_none()));
}

#[test]
fn extensions_required_and_used() {
    let dir = temp_dir("extensions");
    let text = quad_scene().to_gltf();
    let draco = edit(&text, |v| {
        v["extensionsUsed"] = vec!["KHR_draco_mesh_compression"].into();
        v["extensionsRequired"] = vec!["KHR_draco_mesh_compression"].into();
    });
    let p = write(&dir, "draco.gltf", draco);
    expect_error(&p, &["KHR_draco_mesh_compression", "compressed geometry"]);

    let other = edit(&text, |v| {
        v["extensionsUsed"] = vec!["EXT_unknown_a", "EXT_unknown_b"].into();
        v["extensionsRequired"] = vec!["EXT_unknown_b"].into();
    });
    let p = write(&dir, "unknown.gltf", other);
    let s = load(&p).unwrap();
    expect_warning(&s, &["EXT_unknown_a", "not supported"]);
    expect_warning(&s, &["EXT_unknown_b", "required"]);
    assert_eq!(s.triangle_count(), 2);
}

#[test]
fn bad_references_are_warnings() {
    let dir = temp_dir("references");
    let text = edit(&quad_scene().to_gltf(), |v| {
        v["meshes"][0]["primitives"][0]["material"] = 42.into();
        v["scenes"][0]["nodes"] = vec![0, 0, 17].into();
        v["nodes"][0]["children"] = vec![0].into();
        v["nodes"][0]["camera"] = 5.into();
    });
    let p = write(&dir, "refs.gltf", text);
    let s = load(&p).unwrap();
    common::assert_well_formed(&s);
    assert_eq!(s.triangle_count(), 2);
    expect_warning(&s, &["material 42", "default material"]);
    expect_warning(&s, &["node 17", "does not exist"]);
    expect_warning(&s, &["node 0 ('quad')", "second time"]);
    expect_warning(&s, &["camera 5"]);
    assert!(s.camera.is_default);
    assert_eq!(s.materials.len(), 2);
}
