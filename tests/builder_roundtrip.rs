//! Scenes made with the builder load back with the same triangles, materials, lights,
//! transforms and camera.

mod common;

use glam::{Mat4, Quat, Vec3};
use std::path::PathBuf;
use voxgi::scene::builder::{
    quad, CameraDesc, LightDesc, LightType, MaterialDesc, NodeDesc, PrimitiveDesc, SceneBuilder,
};
use voxgi::scene::{load, AlphaMode, LightKind, Material, Scene};

const FLAT_TRIANGLES: [[f32; 3]; 9] = [
    // Counter-clockwise seen from +Z.
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    // Counter-clockwise seen from +X.
    [0.0, 0.0, 0.0],
    [0.0, 0.0, -1.0],
    [0.0, 1.0, 0.0],
    // Tilted.
    [1.0, 2.0, 3.0],
    [2.0, 2.5, 3.0],
    [1.0, 3.0, 4.0],
];

const SPOT_ROTATION: [f32; 4] = [
    -std::f32::consts::FRAC_1_SQRT_2,
    0.0,
    0.0,
    std::f32::consts::FRAC_1_SQRT_2,
];
const TRS_ROTATION: [f32; 4] = [
    0.0,
    0.0,
    std::f32::consts::FRAC_1_SQRT_2,
    std::f32::consts::FRAC_1_SQRT_2,
];
const MATRIX: [f32; 16] = [
    0.0, 0.0, -3.0, 0.0, // x axis -> -Z, scaled 3
    0.0, 1.0, 0.0, 0.0, //
    -1.0, 0.0, 0.0, 0.0, // z axis -> -X: a mirror
    5.0, 6.0, 7.0, 1.0,
];

fn shiny() -> MaterialDesc {
    MaterialDesc {
        name: Some("shiny".into()),
        base_color: [0.2, 0.4, 0.6, 0.8],
        base_color_texture: None,
        metallic: 0.7,
        roughness: 0.3,
        emissive: [1.0, 0.5, 0.25],
        emissive_strength: Some(4.0),
        specular_factor: Some(0.5),
        double_sided: true,
    }
}

fn unit_quad(material: Option<usize>) -> PrimitiveDesc {
    quad(
        [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
        [0.0, 0.0, 1.0],
        material,
    )
}

fn test_scene() -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let shiny = b.add_material(shiny());
    b.add_material(MaterialDesc::lambertian("matte", [0.5, 0.5, 0.5]));
    let q = b.add_mesh("quad", vec![unit_quad(Some(shiny))]);
    let flat = b.add_triangles("flat", &FLAT_TRIANGLES, None, None);
    b.add_node(
        NodeDesc::new("trs")
            .mesh(q)
            .translation([1.0, 2.0, 3.0])
            .rotation(TRS_ROTATION)
            .scale([2.0, 2.0, 2.0]),
    );
    b.add_node(NodeDesc::new("matrix").mesh(flat).matrix(MATRIX));
    let child = b.add_node(
        NodeDesc::new("mirrored child")
            .mesh(q)
            .translation([1.0, 0.0, 0.0])
            .scale([-1.0, 1.0, 1.0]),
    );
    b.add_node(
        NodeDesc::new("parent")
            .translation([0.0, 10.0, 0.0])
            .child(child),
    );
    let point = b.add_light(LightDesc::new(
        "point",
        LightType::Point,
        [1.0, 0.5, 0.25],
        8.0,
    ));
    let mut spot = LightDesc::new(
        "spot",
        LightType::Spot {
            inner_cone_angle: 0.3,
            outer_cone_angle: 0.6,
        },
        [1.0, 1.0, 1.0],
        2.0,
    );
    spot.range = Some(5.0);
    let spot = b.add_light(spot);
    let sun = b.add_light(LightDesc::new(
        "sun",
        LightType::Directional,
        [1.0, 1.0, 0.5],
        3.0,
    ));
    let wide = b.add_light(LightDesc::new(
        "too wide",
        LightType::Spot {
            inner_cone_angle: 1.0,
            outer_cone_angle: 2.0,
        },
        [1.0; 3],
        1.0,
    ));
    b.add_node(
        NodeDesc::new("point")
            .light(point)
            .translation([0.0, 1.0, 0.0]),
    );
    b.add_node(
        NodeDesc::new("spot")
            .light(spot)
            .translation([0.0, 3.0, 0.0])
            .rotation(SPOT_ROTATION),
    );
    b.add_node(NodeDesc::new("sun").light(sun));
    b.add_node(NodeDesc::new("wide").light(wide));
    let cam = b.add_camera(CameraDesc {
        name: Some("eye".into()),
        yfov: 0.9,
        znear: 0.05,
        zfar: None,
        aspect_ratio: Some(1.5),
    });
    b.add_node(
        NodeDesc::new("camera")
            .camera(cam)
            .translation([0.0, 0.0, 10.0]),
    );
    b
}

fn write_and_load(test: &str, b: &SceneBuilder) -> (Scene, PathBuf) {
    let dir = common::temp_dir(test);
    let path = dir.join("scene.gltf");
    b.write(&path).unwrap();
    let s = load(&path).unwrap_or_else(|e| panic!("{e}"));
    common::assert_well_formed(&s);
    (s, path)
}

fn close(a: Mat4, b: Mat4) -> bool {
    a.abs_diff_eq(b, 1e-5)
}

fn instance<'a>(s: &'a Scene, node: &str) -> &'a voxgi::scene::Instance {
    s.instances
        .iter()
        .find(|i| i.node_name.as_deref() == Some(node))
        .unwrap_or_else(|| panic!("no instance for {node}"))
}

#[test]
fn builder_output_is_valid_deterministic_and_written_atomically() {
    let b = test_scene();
    let text = b.to_gltf();
    assert_eq!(text, test_scene().to_gltf());
    if let Err(e) = gltf::Gltf::from_slice(text.as_bytes()) {
        panic!("{e:?}");
    }
    if let Err(e) = gltf::Gltf::from_slice(&b.to_glb()) {
        panic!("{e:?}");
    }
    let dir = common::temp_dir("atomic");
    let path = dir.join("out.gltf");
    b.write(&path).unwrap();
    b.write(&path).unwrap();
    assert_eq!(std::fs::read_to_string(&path).unwrap(), text);
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name())
        .collect();
    assert_eq!(names.len(), 1, "temporary files left behind: {names:?}");
}

#[test]
fn triangles_and_instances_round_trip() {
    let (s, _) = write_and_load("roundtrip-geometry", &test_scene());
    assert!(
        s.warnings.iter().all(|w| w.contains("too wide")),
        "{:?}",
        s.warnings
    );
    // The quad mesh is stored once and drawn by two nodes.
    assert_eq!(s.primitives.len(), 2);
    assert_eq!(s.instances.len(), 3);
    assert_eq!(
        instance(&s, "trs").primitive,
        instance(&s, "mirrored child").primitive
    );
    assert_eq!(s.stored_triangle_count(), 2 + 3);
    assert_eq!(s.triangle_count(), 2 * 2 + 3);

    // The quad keeps its indexed vertices and normals.
    let qp = &s.primitives[instance(&s, "trs").primitive as usize];
    assert_eq!(qp.index_count, 6);
    let idx = &s.indices[qp.first_index as usize..][..6];
    let corners: Vec<[f32; 3]> = idx
        .iter()
        .map(|&i| s.vertices[i as usize].position)
        .collect();
    assert_eq!(
        corners[..3],
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]
    );
    assert!(idx
        .iter()
        .all(|&i| s.vertices[i as usize].normal == [0.0, 0.0, 1.0]));
    assert_eq!(qp.bounds.min, Vec3::ZERO);
    assert_eq!(qp.bounds.max, Vec3::new(1.0, 1.0, 0.0));

    // The non-indexed mesh comes back triangle by triangle, in order.
    let fp = &s.primitives[instance(&s, "matrix").primitive as usize];
    let got: Vec<[f32; 3]> = s.indices[fp.first_index as usize..][..fp.index_count as usize]
        .iter()
        .map(|&i| s.vertices[i as usize].position)
        .collect();
    assert_eq!(got, FLAT_TRIANGLES);

    // Transforms: TRS, matrix, and a parent-child chain.
    let trs = Mat4::from_scale_rotation_translation(
        Vec3::splat(2.0),
        Quat::from_array(TRS_ROTATION),
        Vec3::new(1.0, 2.0, 3.0),
    );
    assert!(close(instance(&s, "trs").world, trs));
    assert!(close(
        instance(&s, "matrix").world,
        Mat4::from_cols_array(&MATRIX)
    ));
    let chain = Mat4::from_translation(Vec3::new(0.0, 10.0, 0.0))
        * Mat4::from_scale_rotation_translation(Vec3::new(-1.0, 1.0, 1.0), Quat::IDENTITY, Vec3::X);
    assert!(close(instance(&s, "mirrored child").world, chain));

    // Bounds: the union of the transformed primitive bounds.
    let expected = s.instances.iter().fold(voxgi::scene::Aabb::EMPTY, |b, i| {
        b.union(
            &s.primitives[i.primitive as usize]
                .bounds
                .transformed(&i.world),
        )
    });
    assert_eq!(s.bounds, expected);
    assert!((s.bounds.max.y - 11.0).abs() < 1e-5);
}

#[test]
fn negative_scale_flips_winding() {
    let (s, _) = write_and_load("roundtrip-winding", &test_scene());
    assert!(instance(&s, "mirrored child").flips_winding());
    assert!(!instance(&s, "trs").flips_winding());
    // The matrix node has determinant -3 (x axis to -Z, z axis to -X): a mirror.
    assert!((Mat4::from_cols_array(&MATRIX).determinant() + 3.0).abs() < 1e-6);
    assert!(instance(&s, "matrix").flips_winding());
}

#[test]
fn generated_flat_normals_face_the_front() {
    let (s, _) = write_and_load("roundtrip-normals", &test_scene());
    let fp = &s.primitives[instance(&s, "matrix").primitive as usize];
    let idx = &s.indices[fp.first_index as usize..][..fp.index_count as usize];
    for (k, t) in idx.chunks_exact(3).enumerate() {
        let v: Vec<_> = t.iter().map(|&i| s.vertices[i as usize]).collect();
        let p: Vec<Vec3> = v.iter().map(|v| Vec3::from(v.position)).collect();
        let face = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
        for corner in &v {
            let n = Vec3::from(corner.normal);
            assert!((n - face).length() < 1e-6, "triangle {k}: {n} vs {face}");
        }
    }
    let first = s.vertices[idx[0] as usize].normal;
    assert_eq!(first, [0.0, 0.0, 1.0]);
    assert_eq!(s.vertices[idx[3] as usize].normal, [1.0, 0.0, 0.0]);
    // Flat normals mean one vertex per corner.
    assert!(idx.windows(2).all(|w| w[1] == w[0] + 1));
}

#[test]
fn materials_round_trip() {
    let (s, _) = write_and_load("roundtrip-materials", &test_scene());
    // Two file materials plus the default one for the primitive without a material.
    assert_eq!(s.materials.len(), 3);
    let m = &s.materials[s.primitives[instance(&s, "trs").primitive as usize].material as usize];
    assert_eq!(m.name.as_deref(), Some("shiny"));
    assert_eq!(m.base_color.to_array(), [0.2, 0.4, 0.6, 0.8]);
    assert_eq!((m.metallic, m.roughness), (0.7, 0.3));
    assert_eq!(m.emissive, Vec3::new(4.0, 2.0, 1.0));
    assert_eq!(m.specular_factor, 0.5);
    assert_eq!(m.specular_color, Vec3::ONE);
    assert!(m.double_sided);
    assert_eq!(m.alpha_mode, AlphaMode::Opaque);
    let matte = &s.materials[1];
    assert_eq!((matte.metallic, matte.specular_factor), (0.0, 0.0));
    assert!(!matte.is_emissive());
    let d = &s.materials[s.primitives[instance(&s, "matrix").primitive as usize].material as usize];
    let def = Material::default();
    assert_eq!(d.name, None);
    assert_eq!(
        (d.base_color, d.metallic, d.roughness),
        (def.base_color, def.metallic, def.roughness)
    );
    assert_eq!(d.specular_factor, 1.0);
}

#[test]
fn lights_round_trip() {
    let (s, _) = write_and_load("roundtrip-lights", &test_scene());
    assert_eq!(s.lights.len(), 4);
    let by = |n: &str| {
        s.lights
            .iter()
            .find(|l| l.name.as_deref() == Some(n))
            .unwrap()
    };
    let point = by("point");
    assert_eq!(point.kind, LightKind::Point);
    assert_eq!(point.radiance, Vec3::new(8.0, 4.0, 2.0));
    assert_eq!(point.position, Vec3::new(0.0, 1.0, 0.0));
    assert_eq!(point.range, None);

    let spot = by("spot");
    assert_eq!(
        spot.kind,
        LightKind::Spot {
            inner_cone: 0.3,
            outer_cone: 0.6
        }
    );
    assert_eq!(spot.range, Some(5.0));
    assert!((spot.position - Vec3::new(0.0, 3.0, 0.0)).length() < 1e-6);
    assert!(
        (spot.direction - Vec3::NEG_Y).length() < 1e-6,
        "{}",
        spot.direction
    );

    let sun = by("sun");
    assert_eq!(sun.kind, LightKind::Directional);
    assert_eq!(sun.radiance, Vec3::new(3.0, 3.0, 1.5));
    assert_eq!(sun.direction, Vec3::NEG_Z);

    let wide = by("too wide");
    assert_eq!(
        wide.kind,
        LightKind::Spot {
            inner_cone: 1.0,
            outer_cone: std::f32::consts::FRAC_PI_2
        }
    );
    assert!(s
        .warnings
        .iter()
        .any(|w| w.contains("too wide") && w.contains("clamped")));
}

#[test]
fn far_translations_are_read_to_the_micrometre() {
    // 100000.35 is no f32 (it would read as 100000.3516): the loader reads node translations as
    // the JSON's f64 and places the scene relative to its origin, where a mesh and a point light
    // 5 cm from it keep their places to within f32's step there (30 um), in a child node too.
    for far in [1e5 + 0.35, 1e6 + 0.35] {
        let mut b = SceneBuilder::new();
        let mesh = b.add_mesh("quad", vec![unit_quad(None)]);
        let l = b.add_light(LightDesc::new("point", LightType::Point, [1.0; 3], 1.0));
        let light = b.add_node(
            NodeDesc::new("light")
                .light(l)
                .translation([0.0, 0.05, 0.0]),
        );
        b.add_node(
            NodeDesc::new("far")
                .mesh(mesh)
                .translation([far, 2.0, -far])
                .child(light),
        );
        let (s, _) = write_and_load("roundtrip-far", &b);
        let placed = s.origin + instance(&s, "far").world.w_axis.truncate().as_dvec3();
        let want = glam::DVec3::new(far, 2.0, -far);
        assert!(
            (placed - want).abs().max_element() < 3e-5,
            "{far}: {placed}"
        );
        let lit = s.origin + s.lights[0].position.as_dvec3();
        let want = glam::DVec3::new(far, 2.05, -far);
        assert!(
            (lit - want).abs().max_element() < 3e-5,
            "{far}: light at {lit}"
        );
        let node = s
            .nodes
            .iter()
            .find(|n| n.name.as_deref() == Some("far"))
            .expect("the node");
        assert_eq!(node.translation, glam::DVec3::new(far, 2.0, -far));
    }
}

#[test]
fn camera_round_trips_with_a_derived_far_plane() {
    let (s, _) = write_and_load("roundtrip-camera", &test_scene());
    let c = &s.camera;
    assert!(!c.is_default);
    assert_eq!(c.name.as_deref(), Some("eye"));
    assert_eq!((c.yfov, c.znear), (0.9, 0.05));
    assert_eq!(c.eye(), Vec3::new(0.0, 0.0, 10.0));
    // Infinite in the file: finite, containing the whole scene.
    assert!(c.zfar.is_finite() && c.zfar >= 50.0);
    for i in 0..8 {
        let b = s.bounds;
        let corner = Vec3::select(
            glam::BVec3::new(i & 1 == 0, i & 2 == 0, i & 4 == 0),
            b.min,
            b.max,
        );
        assert!(c.eye().distance(corner) < c.zfar);
    }
}

#[test]
fn glb_and_gltf_load_the_same() {
    let b = test_scene();
    let (a, path) = write_and_load("roundtrip-glb", &b);
    let glb_path = path.with_extension("glb");
    std::fs::write(&glb_path, b.to_glb()).unwrap();
    let g = load(&glb_path).unwrap();
    assert_eq!(a.vertices, g.vertices);
    assert_eq!(a.indices, g.indices);
    assert_eq!(a.instances.len(), g.instances.len());
    assert_eq!(a.lights.len(), g.lights.len());
    assert_eq!(a.warnings, g.warnings);
}

#[test]
fn empty_scene_gets_a_finite_default_camera() {
    let (s, _) = write_and_load("roundtrip-empty", &SceneBuilder::new());
    assert!(s.instances.is_empty() && s.bounds.is_empty());
    assert!(s.camera.is_default);
    assert_eq!(s.camera.eye(), Vec3::new(0.0, 0.0, 1.0));
    assert_eq!(s.triangle_count(), 0);
}
