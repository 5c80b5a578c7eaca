//! glTF 2.0 loading: file and .glb container, buffers, the node walk, lights and camera.
//! Geometry details live in `geometry.rs`, materials and textures in `material.rs`.
//!
//! The document is parsed without the gltf crate's validation (real files break the rules in
//! harmless ways) and then read through its JSON structures only, checking every index and
//! byte range here, so that no input can make the loader panic.

use super::accessor::Buffers;
use super::animation::{Animation, Channel, Interpolation, Node, Property};
use super::geometry::{self, RawPrimitive, Topology};
use super::material::load_materials;
use super::{
    Aabb, Camera, Instance, Light, LightKind, Material, Primitive, Scene, SceneCamera, SceneError,
};
use super::{Vertex, DEFAULT_YFOV_DEGREES};
use glam::{DMat4, DVec3, Mat4, Quat, Vec2, Vec3, Vec4};
use gltf::json;
use json::accessor::{ComponentType, Type};
use json::mesh::{Mode, Semantic};
use json::validation::Checked;
use std::collections::HashMap;
use std::fmt;
use std::path::{Path, PathBuf};

/// Extensions whose data the loader reads.
const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_specular",
];

/// Required extensions without which the geometry itself cannot be read.
const GEOMETRY_COMPRESSION: &[&str] = &[
    "KHR_draco_mesh_compression",
    "EXT_meshopt_compression",
    "KHR_meshopt_compression",
];

/// Loads a glTF 2.0 scene (.gltf or .glb).
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let start = std::time::Instant::now();
    let scene = load_inner(path).map_err(|problem| SceneError {
        path: path.to_path_buf(),
        problem,
    })?;
    log::debug!(
        "loaded {} in {:.1} ms: {} triangles, {} instances, {} materials, {} lights",
        path.display(),
        start.elapsed().as_secs_f64() * 1e3,
        scene.triangle_count(),
        scene.instances.len(),
        scene.materials.len(),
        scene.lights.len()
    );
    for w in &scene.warnings {
        log::warn!("{}: {w}", path.display());
    }
    Ok(scene)
}

fn load_inner(path: &Path) -> Result<Scene, String> {
    let bytes = std::fs::read(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => "the file does not exist".to_string(),
        _ => format!("cannot read the file: {e}"),
    })?;
    let mut warnings = Vec::new();
    let (json_bytes, bin) = split_container(path, &bytes, &mut warnings)?;
    let root = parse_json(json_bytes, &mut warnings)?;

    let version = root.asset.version.trim();
    if !(version == "2" || version.starts_with("2.")) {
        warnings.push(format!(
            "asset.version is '{version}', not 2.x; reading it as glTF 2.0"
        ));
    }
    check_extensions(&root, &mut warnings)?;

    let base = path.parent().unwrap_or_else(|| Path::new("."));
    let buffers = load_buffers(&root, base, bin, &mut warnings)?;

    let placed = placements(json_bytes, root.nodes.len());
    let mut loader = Loader {
        root: &root,
        buffers: &buffers,
        warnings,
        vertices: Vec::new(),
        indices: Vec::new(),
        primitives: Vec::new(),
        instances: Vec::new(),
        lights: Vec::new(),
        mesh_cache: HashMap::new(),
        default_material_used: false,
        camera_nodes: Vec::new(),
        morph_warned: false,
        skin_warned: false,
        origin: DVec3::ZERO,
        nodes: root
            .nodes
            .iter()
            .zip(&placed)
            .map(|(n, &p)| rest_node(n, p))
            .collect(),
        placements: placed,
    };
    loader.origin = loader.find_origin();
    loader.walk()?;
    let animations = loader.animations();

    let Loader {
        vertices,
        indices,
        primitives,
        instances,
        lights,
        default_material_used,
        camera_nodes,
        mut warnings,
        origin,
        nodes,
        ..
    } = loader;

    let (mut materials, textures) = load_materials(&root, &buffers, base, &mut warnings);
    if default_material_used {
        materials.push(Material::default());
    }

    let bounds = instances.iter().fold(Aabb::EMPTY, |b, i| {
        b.union(
            &primitives[i.primitive as usize]
                .bounds
                .transformed(&i.world),
        )
    });
    // The first camera met is the view; a problem with another one is said only when it is
    // asked for (`--camera`).
    let cameras: Vec<SceneCamera> = camera_nodes
        .iter()
        .enumerate()
        .map(|(k, &(index, world))| {
            let mut problems = Vec::new();
            let camera = file_camera(&root, index, world, &bounds, &mut problems);
            if k == 0 {
                warnings.extend(problems.iter().cloned());
            }
            SceneCamera {
                index,
                name: root.cameras.get(index).and_then(|c| c.name.clone()),
                camera: camera.ok_or_else(|| problems.join("; ")),
            }
        })
        .collect();
    let camera = cameras
        .first()
        .and_then(|c| c.camera.clone().ok())
        .unwrap_or_else(|| default_camera(&bounds));

    Ok(Scene {
        source: path.to_path_buf(),
        vertices,
        indices,
        primitives,
        instances,
        materials,
        textures,
        lights,
        camera,
        cameras,
        bounds,
        origin,
        nodes,
        animations,
        environment: None,
        warnings,
    })
}

/// Finds the JSON text and the binary chunk (for .glb). Checks the .glb container by hand so
/// that a damaged header is a clear message rather than a failure deep in the parser.
fn split_container<'a>(
    path: &Path,
    bytes: &'a [u8],
    warnings: &mut Vec<String>,
) -> Result<(&'a [u8], Option<&'a [u8]>), String> {
    if bytes.is_empty() {
        return Err("the file is empty".into());
    }
    let is_glb_name = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
    if !bytes.starts_with(b"glTF") {
        let text = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
        let looks_like_json = text
            .iter()
            .find(|b| !b.is_ascii_whitespace())
            .is_some_and(|&b| b == b'{');
        if is_glb_name && !looks_like_json {
            let shown: String = bytes
                .iter()
                .take(4)
                .map(|&b| if b.is_ascii_graphic() { b as char } else { '?' })
                .collect();
            return Err(format!(
                "invalid .glb header: the file starts with '{shown}', not the 'glTF' magic"
            ));
        }
        if is_glb_name {
            warnings.push("the .glb file holds plain JSON; read as .gltf".into());
        }
        if text.len() != bytes.len() {
            warnings.push("the JSON starts with a UTF-8 byte order mark; ignored".into());
        }
        return Ok((text, None));
    }

    let u32_at =
        |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    if bytes.len() < 12 {
        return Err(format!(
            "truncated .glb: the file has {} bytes, less than the 12-byte header",
            bytes.len()
        ));
    }
    let version = u32_at(4);
    if version != 2 {
        return Err(format!(
            "invalid .glb header: container version {version}; only version 2 (glTF 2.0) is supported"
        ));
    }
    let declared = u32_at(8) as usize;
    if declared > bytes.len() {
        return Err(format!(
            "truncated .glb: the header declares {declared} bytes but the file has only {}",
            bytes.len()
        ));
    }
    if declared < bytes.len() {
        warnings.push(format!(
            "the .glb header declares {declared} bytes; the {} bytes after that are ignored",
            bytes.len() - declared
        ));
    }
    let total = declared;
    let mut at = 12;
    let mut json: Option<&[u8]> = None;
    let mut bin: Option<&[u8]> = None;
    let mut chunk = 0;
    while at < total {
        if total - at < 8 {
            if json.is_none() {
                return Err("truncated .glb: the JSON chunk header is cut off".into());
            }
            warnings.push(format!(
                "the .glb ends with {} stray bytes after its last chunk; ignored",
                total - at
            ));
            break;
        }
        let len = u32_at(at) as usize;
        let kind = &bytes[at + 4..at + 8];
        let start = at + 8;
        // As text where it is (JSON, BIN), '?' for any other byte: a damaged file's chunk type
        // may hold a line break, and the error stays one line.
        let kind_name: String = kind
            .iter()
            .map(|&b| if b.is_ascii_graphic() { b as char } else { '?' })
            .collect::<String>()
            .trim_end_matches('?')
            .to_string();
        if len > total - start {
            return Err(format!(
                "truncated .glb: chunk {chunk} ('{kind_name}') declares {len} bytes but only {} remain",
                total - start
            ));
        }
        let data = &bytes[start..start + len];
        match (chunk, kind) {
            (0, b"JSON") => json = Some(data),
            (0, _) => {
                return Err(format!(
                    "invalid .glb: the first chunk is '{kind_name}', not JSON"
                ))
            }
            (_, b"BIN\0") if bin.is_none() => bin = Some(data),
            // The .glb rules say unknown chunks are skipped.
            _ => {}
        }
        chunk += 1;
        at = start + len;
    }
    let json = json.ok_or("truncated .glb: there is no JSON chunk")?;
    Ok((json, bin))
}

/// Parses the glTF JSON without validation. gltf-json is stricter than the glTF spec in a few
/// places (a scene without `nodes`, an animation channel without a target node); such files
/// are retried once with those parts repaired.
fn parse_json(bytes: &[u8], warnings: &mut Vec<String>) -> Result<json::Root, String> {
    let first = match gltf::Gltf::from_slice_without_validation(bytes) {
        Ok(g) => return Ok(g.document.into_json()),
        Err(e) => e,
    };
    let mut repairs = Vec::new();
    if let Some(fixed) = repair_json(bytes, &mut repairs) {
        if let Ok(g) = gltf::Gltf::from_slice_without_validation(&fixed) {
            warnings.extend(repairs);
            return Ok(g.document.into_json());
        }
    }
    Err(describe_json_error(first))
}

fn repair_json(bytes: &[u8], repairs: &mut Vec<String>) -> Option<Vec<u8>> {
    let mut v: json::Value = json::deserialize::from_slice(bytes).ok()?;
    let root = v.as_object_mut()?;
    if let Some(scenes) = root.get_mut("scenes").and_then(|s| s.as_array_mut()) {
        for (i, scene) in scenes.iter_mut().enumerate() {
            if let Some(scene) = scene.as_object_mut() {
                if !scene.contains_key("nodes") {
                    scene.insert("nodes".to_string(), json::Value::Array(Vec::new()));
                    repairs.push(format!("scene {i} has no nodes; it is empty"));
                }
            }
        }
    }
    // The renderer does not animate; dropping animations loses nothing.
    if root.remove("animations").is_some() {
        repairs.push("animations could not be parsed; they are ignored".into());
    }
    if repairs.is_empty() {
        return None;
    }
    json::serialize::to_vec(&v).ok()
}

fn describe_json_error(e: gltf::Error) -> String {
    match e {
        gltf::Error::Deserialize(je) if je.is_eof() => format!(
            "the glTF JSON is truncated: it ends unexpectedly at line {}, column {}",
            je.line(),
            je.column()
        ),
        gltf::Error::Deserialize(je) if je.is_syntax() => format!("invalid JSON: {je}"),
        gltf::Error::Deserialize(je) => format!("the JSON is not a valid glTF 2.0 document: {je}"),
        other => format!("cannot parse the glTF: {other}"),
    }
}

fn check_extensions(root: &json::Root, warnings: &mut Vec<String>) -> Result<(), String> {
    for ext in &root.extensions_required {
        if GEOMETRY_COMPRESSION.contains(&ext.as_str()) {
            return Err(format!(
                "the file requires extension {ext} (compressed geometry), which this loader \
                 cannot decode"
            ));
        }
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            warnings.push(format!(
                "required extension {ext} is not supported; rendering without it"
            ));
        }
    }
    for ext in &root.extensions_used {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) && !root.extensions_required.contains(ext)
        {
            warnings.push(format!("extension {ext} is not supported; ignored"));
        }
    }
    Ok(())
}

/// Why a URI could not be read.
#[derive(Debug)]
pub enum UriError {
    Missing(PathBuf),
    Io(PathBuf, std::io::Error),
    BadData(String),
    Unsupported(String),
}

impl fmt::Display for UriError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            UriError::Missing(p) => write!(f, "{} does not exist", p.display()),
            UriError::Io(p, e) => write!(f, "cannot read {}: {e}", p.display()),
            UriError::BadData(e) => write!(f, "invalid data: URI: {e}"),
            UriError::Unsupported(s) => write!(f, "unsupported URI scheme '{s}'"),
        }
    }
}

/// Decodes %XX escapes (URIs in glTF are percent-encoded).
fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Reads the bytes behind a glTF URI: a `data:` URI, or a file relative to `base`.
pub fn read_uri(base: &Path, uri: &str) -> Result<Vec<u8>, UriError> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (header, data) = rest
            .split_once(',')
            .ok_or_else(|| UriError::BadData("no ',' before the data".into()))?;
        return if header.ends_with(";base64") {
            super::base64::decode(data).map_err(UriError::BadData)
        } else {
            Ok(percent_decode(data).into_bytes())
        };
    }
    // A scheme is letters before ':'; single letters are Windows drive names, not schemes.
    let scheme = uri.split_once(':').map(|(s, _)| s).filter(|s| {
        s.len() > 1
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
    });
    let file = match scheme {
        Some("file") => {
            let p = uri.trim_start_matches("file:");
            let p = p.strip_prefix("//").unwrap_or(p);
            PathBuf::from(percent_decode(p))
        }
        Some(other) => return Err(UriError::Unsupported(other.to_string())),
        None => base.join(percent_decode(uri)),
    };
    std::fs::read(&file).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => UriError::Missing(file),
        _ => UriError::Io(file, e),
    })
}

fn load_buffers(
    root: &json::Root,
    base: &Path,
    bin: Option<&[u8]>,
    warnings: &mut Vec<String>,
) -> Result<Buffers, String> {
    let mut data = Vec::with_capacity(root.buffers.len());
    for (i, b) in root.buffers.iter().enumerate() {
        let (mut bytes, name) = match &b.uri {
            None => match (i, bin) {
                (0, Some(bin)) => (bin.to_vec(), "the .glb BIN chunk".to_string()),
                _ => {
                    return Err(format!(
                        "buffer {i} has no uri and there is no .glb BIN chunk to supply it"
                    ))
                }
            },
            Some(uri) => {
                let shown = if uri.starts_with("data:") {
                    "an embedded data: URI".to_string()
                } else {
                    format!("'{uri}'")
                };
                let bytes = read_uri(base, uri).map_err(|e| match e {
                    UriError::Missing(p) => format!(
                        "missing buffer file '{uri}' (buffer {i}): {} does not exist",
                        p.display()
                    ),
                    other => format!("buffer {i} ({shown}): {other}"),
                })?;
                (bytes, shown)
            }
        };
        let declared = b.byte_length.0;
        if (bytes.len() as u64) < declared {
            return Err(format!(
                "buffer {i} ({name}) is shorter than declared: byteLength is {declared} but it has \
                 only {} bytes",
                bytes.len()
            ));
        }
        if bytes.len() as u64 > declared + 3 {
            warnings.push(format!(
                "buffer {i} ({name}) has {} bytes, more than its byteLength {declared}; the rest \
                 is ignored",
                bytes.len()
            ));
        }
        bytes.truncate(declared as usize);
        data.push(bytes);
    }
    Ok(Buffers { data })
}

struct Loader<'a> {
    root: &'a json::Root,
    buffers: &'a Buffers,
    warnings: Vec<String>,
    vertices: Vec<Vertex>,
    indices: Vec<u32>,
    primitives: Vec<Primitive>,
    instances: Vec<Instance>,
    lights: Vec<Light>,
    /// glTF mesh index -> the scene primitives made from it (a mesh is stored once).
    mesh_cache: HashMap<usize, Vec<u32>>,
    default_material_used: bool,
    /// Each camera of the file with the first node met that uses it: (camera index, node
    /// world matrix), in the order met.
    camera_nodes: Vec<(usize, Mat4)>,
    morph_warned: bool,
    skin_warned: bool,
    /// Each node's translation and matrix in f64.
    placements: Vec<Placement>,
    /// See `Scene::origin`.
    origin: DVec3,
    /// Every node of the file; the walk sets the parents of those it reaches.
    nodes: Vec<Node>,
}

fn mesh_label(index: usize, mesh: &json::Mesh) -> String {
    match &mesh.name {
        Some(n) => format!("mesh {index} ('{n}')"),
        None => format!("mesh {index}"),
    }
}

fn node_label(index: usize, node: &json::Node) -> String {
    match &node.name {
        Some(n) => format!("node {index} ('{n}')"),
        None => format!("node {index}"),
    }
}

/// A node's translation and matrix as its JSON writes them, in f64: gltf-json reads them as
/// f32, which rounds a node 1e5 m from the origin to 8 mm (100000.35 to 100000.3516). Rotations
/// and scales are relative and keep f32.
#[derive(Clone, Copy, Default)]
struct Placement {
    translation: Option<DVec3>,
    matrix: Option<DMat4>,
}

/// Each node's [`Placement`], read from the JSON text again (its numbers as f64); a node whose
/// numbers do not read so (or a document that does not) falls back to gltf-json's f32.
fn placements(json_bytes: &[u8], nodes: usize) -> Vec<Placement> {
    let mut out = vec![Placement::default(); nodes];
    let Ok(v) = json::deserialize::from_slice::<json::Value>(json_bytes) else {
        return out;
    };
    let Some(list) = v.get("nodes").and_then(|n| n.as_array()) else {
        return out;
    };
    let numbers = |v: Option<&json::Value>, n: usize| -> Option<Vec<f64>> {
        let a = v?.as_array()?;
        let xs: Vec<f64> = a.iter().filter_map(|x| x.as_f64()).collect();
        (a.len() == n && xs.len() == n).then_some(xs)
    };
    for (p, node) in out.iter_mut().zip(list) {
        p.translation = numbers(node.get("translation"), 3).map(|t| DVec3::from_slice(&t[..]));
        p.matrix = numbers(node.get("matrix"), 16).map(|m| DMat4::from_cols_slice(&m[..]));
    }
    out
}

/// A node's rotation, or None when it holds non-finite numbers. Rotations are meant to be unit
/// quaternions; exporters round them.
fn node_rotation(node: &json::Node) -> Option<Quat> {
    let r = Quat::from_array(node.rotation.map_or([0.0, 0.0, 0.0, 1.0], |r| r.0));
    if r.is_finite() && r.length_squared() > 1e-12 {
        Some(r.normalize())
    } else if r.is_finite() {
        Some(Quat::IDENTITY)
    } else {
        None
    }
}

/// A node's translation, in f64 where its JSON reads so.
fn node_translation(node: &json::Node, placed: Placement) -> DVec3 {
    placed
        .translation
        .unwrap_or_else(|| Vec3::from(node.translation.unwrap_or([0.0; 3])).as_dvec3())
}

/// A node's matrix, if it has one, in f64 where its JSON reads so.
fn node_matrix(node: &json::Node, placed: Placement) -> Option<DMat4> {
    let m = node.matrix?;
    Some(
        placed
            .matrix
            .unwrap_or_else(|| Mat4::from_cols_array(&m).as_dmat4()),
    )
}

/// A node's name and rest pose (no parent yet; the walk sets it).
fn rest_node(node: &json::Node, placed: Placement) -> Node {
    Node {
        name: node.name.clone(),
        parent: None,
        translation: node_translation(node, placed),
        rotation: node_rotation(node).unwrap_or(Quat::IDENTITY),
        scale: Vec3::from(node.scale.unwrap_or([1.0; 3])),
        matrix: node_matrix(node, placed),
    }
}

/// A node's local transform in f64, or None when it holds non-finite numbers.
fn local_transform(node: &json::Node, placed: Placement) -> Option<DMat4> {
    let m = match node_matrix(node, placed) {
        Some(m) => m,
        None => DMat4::from_scale_rotation_translation(
            Vec3::from(node.scale.unwrap_or([1.0; 3])).as_dvec3(),
            node_rotation(node)?.as_dquat(),
            node_translation(node, placed),
        ),
    };
    m.is_finite().then_some(m)
}

impl Loader<'_> {
    fn warn(&mut self, w: String) {
        self.warnings.push(w);
    }

    /// The nodes the walk starts from: the default scene, else scene 0, else every node that
    /// is nobody's child.
    fn root_nodes(&mut self) -> Vec<usize> {
        let root = self.root;
        let chosen = match root.scene {
            Some(s) if s.value() < root.scenes.len() => Some(s.value()),
            Some(s) => {
                self.warn(format!(
                    "the default scene {} does not exist; using {}",
                    s.value(),
                    if root.scenes.is_empty() {
                        "all root nodes"
                    } else {
                        "scene 0"
                    }
                ));
                (!root.scenes.is_empty()).then_some(0)
            }
            None => (!root.scenes.is_empty()).then_some(0),
        };
        match chosen {
            Some(s) => root.scenes[s].nodes.iter().map(|n| n.value()).collect(),
            None => {
                let mut is_child = vec![false; root.nodes.len()];
                for n in &root.nodes {
                    for c in n.children.iter().flatten() {
                        if let Some(flag) = is_child.get_mut(c.value()) {
                            *flag = true;
                        }
                    }
                }
                (0..root.nodes.len()).filter(|&n| !is_child[n]).collect()
            }
        }
    }

    /// Where the scene's meshes lie, in f64: the centre of their nodes' world positions, in
    /// steps of 1024 m. The scene is placed relative to it, so that a model 1e5 m from the file's origin keeps the
    /// precision it has at the origin (f32 world matrices would round it to 8 mm).
    fn find_origin(&mut self) -> DVec3 {
        let root = self.root;
        let mut stack: Vec<(usize, DMat4)> = self
            .root_nodes()
            .into_iter()
            .map(|n| (n, DMat4::IDENTITY))
            .collect();
        let mut visited = vec![false; root.nodes.len()];
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        while let Some((n, parent)) = stack.pop() {
            let Some(node) = root.nodes.get(n) else {
                continue;
            };
            if std::mem::replace(&mut visited[n], true) {
                continue;
            }
            let Some(local) = local_transform(node, self.placements[n]) else {
                continue;
            };
            let world = parent * local;
            if node.mesh.is_some() {
                let t = world.w_axis.truncate();
                lo = lo.min(t);
                hi = hi.max(t);
            }
            stack.extend(node.children.iter().flatten().map(|c| (c.value(), world)));
        }
        // In whole steps of 1024 m (exact in f32): a scene within 512 m of its file's origin
        // keeps its coordinates, and one further away ends up within 512 m of the new one,
        // where f32 resolves 30 um.
        let centre = ((lo + hi) * 0.5 / 1024.0).round() * 1024.0;
        if centre.is_finite() {
            centre
        } else {
            DVec3::ZERO
        }
    }

    /// Depth-first, pre-order walk of the chosen scene (children in file order).
    fn walk(&mut self) -> Result<(), String> {
        let root = self.root;
        let to_local = DMat4::from_translation(-self.origin);
        let mut stack: Vec<(usize, DMat4, Option<usize>)> = self
            .root_nodes()
            .into_iter()
            .rev()
            .map(|n| (n, to_local, None))
            .collect();
        let mut visited = vec![false; root.nodes.len()];
        while let Some((n, parent, parent_index)) = stack.pop() {
            let Some(node) = root.nodes.get(n) else {
                self.warn(format!(
                    "node {n} is referenced but does not exist (the file has {} nodes); ignored",
                    root.nodes.len()
                ));
                continue;
            };
            let label = node_label(n, node);
            if std::mem::replace(&mut visited[n], true) {
                self.warn(format!(
                    "{label} is reached a second time (a cycle or a second parent); ignored there"
                ));
                continue;
            }
            // In f64 down the hierarchy, rounded to f32 once, relative to the origin.
            let Some((world64, world)) = local_transform(node, self.placements[n])
                .map(|l| parent * l)
                .map(|w| (w, w.as_mat4()))
                .filter(|(_, w)| w.is_finite())
            else {
                self.warn(format!(
                    "{label} has a non-finite transform; it and its children are ignored"
                ));
                continue;
            };
            self.nodes[n].parent = parent_index;
            if let Some(mesh) = node.mesh {
                self.place_mesh(mesh.value(), n, node, world)?;
            }
            if node.skin.is_some() && !self.skin_warned {
                self.skin_warned = true;
                self.warn(format!(
                    "{label} is skinned; skinning is not supported, meshes are drawn unposed"
                ));
            }
            if let Some(cam) = node.camera {
                if self.camera_nodes.iter().all(|c| c.0 != cam.value()) {
                    self.camera_nodes.push((cam.value(), world));
                }
            }
            if let Some(l) = node
                .extensions
                .as_ref()
                .and_then(|e| e.khr_lights_punctual.as_ref())
            {
                self.place_light(l.light.value(), &label, world);
            }
            for c in node.children.iter().flatten().rev() {
                stack.push((c.value(), world64, Some(n)));
            }
        }
        Ok(())
    }

    /// The file's animations of node translation, rotation and scale. A channel that cannot
    /// be used (a missing node or accessor, keys out of order, counts that do not match) is
    /// skipped with a warning; morph-target weights are not animated.
    fn animations(&mut self) -> Vec<Animation> {
        use json::animation::Property as P;
        let root = self.root;
        let mut out = Vec::new();
        let mut weights_warned = false;
        for (ai, a) in root.animations.iter().enumerate() {
            let label = match &a.name {
                Some(n) => format!("animation {ai} ('{n}')"),
                None => format!("animation {ai}"),
            };
            let mut channels = Vec::new();
            for (ci, c) in a.channels.iter().enumerate() {
                let who = format!("{label} channel {ci}");
                let property = match c.target.path {
                    Checked::Valid(P::Translation) => Property::Translation,
                    Checked::Valid(P::Rotation) => Property::Rotation,
                    Checked::Valid(P::Scale) => Property::Scale,
                    Checked::Valid(P::MorphTargetWeights) => {
                        if !std::mem::replace(&mut weights_warned, true) {
                            self.warn(format!(
                                "{who} animates morph-target weights, which are not supported; \
                                 ignored"
                            ));
                        }
                        continue;
                    }
                    Checked::Invalid => {
                        self.warn(format!("{who} has an unknown target path; ignored"));
                        continue;
                    }
                };
                match self.channel(a, c, property, &who) {
                    Ok(ch) => channels.push(ch),
                    Err(e) => self.warn(format!("{who}: {e}; ignored")),
                }
            }
            if !channels.is_empty() {
                out.push(Animation {
                    name: a.name.clone(),
                    channels,
                });
            }
        }
        out
    }

    fn channel(
        &self,
        a: &json::Animation,
        c: &json::animation::Channel,
        property: Property,
        who: &str,
    ) -> Result<Channel, String> {
        use json::animation::Interpolation as I;
        let node = c.target.node.value();
        let Some(target) = self.root.nodes.get(node) else {
            return Err(format!("node {node} does not exist"));
        };
        if target.matrix.is_some() {
            return Err(format!(
                "node {node} is placed by a matrix, which glTF does not animate"
            ));
        }
        let Some(sampler) = a.samplers.get(c.sampler.value()) else {
            return Err(format!("sampler {} does not exist", c.sampler.value()));
        };
        let interpolation = match sampler.interpolation {
            Checked::Valid(I::Step) => Interpolation::Step,
            Checked::Valid(I::Linear) => Interpolation::Linear,
            Checked::Valid(I::CubicSpline) => Interpolation::CubicSpline,
            Checked::Invalid => return Err("unknown interpolation".into()),
        };
        let times = self
            .buffers
            .read_f32(self.root, sampler.input.value(), who)?;
        let values = self
            .buffers
            .read_f32(self.root, sampler.output.value(), who)?;
        if times.is_empty() {
            return Err("no keys".into());
        }
        if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|w| w[1] < w[0]) {
            return Err("key times are not finite and increasing".into());
        }
        if values.iter().any(|v| !v.is_finite()) {
            return Err("non-finite values".into());
        }
        let width = if property == Property::Rotation { 4 } else { 3 };
        let per_key = width
            * if interpolation == Interpolation::CubicSpline {
                3
            } else {
                1
            };
        if values.len() != times.len() * per_key {
            return Err(format!(
                "{} keys need {} output values, the accessor has {}",
                times.len(),
                times.len() * per_key,
                values.len()
            ));
        }
        Ok(Channel {
            node,
            property,
            interpolation,
            times,
            values,
        })
    }

    fn place_mesh(
        &mut self,
        mesh: usize,
        node_index: usize,
        node: &json::Node,
        world: Mat4,
    ) -> Result<(), String> {
        if mesh >= self.root.meshes.len() {
            self.warn(format!(
                "{} uses mesh {mesh}, which does not exist; ignored",
                node_label(node_index, node)
            ));
            return Ok(());
        }
        if !self.mesh_cache.contains_key(&mesh) {
            let prims = self.build_mesh(mesh)?;
            self.mesh_cache.insert(mesh, prims);
        }
        for &p in &self.mesh_cache[&mesh] {
            self.instances.push(Instance {
                primitive: p,
                node: node_index,
                node_name: node.name.clone(),
                world,
            });
        }
        Ok(())
    }

    /// Converts every drawable primitive of a mesh, appending to the shared arrays.
    fn build_mesh(&mut self, m: usize) -> Result<Vec<u32>, String> {
        let root = self.root;
        let mesh = &root.meshes[m];
        let mlabel = mesh_label(m, mesh);
        let mut out = Vec::new();
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let label = format!("{mlabel} primitive {p}");
            let topology = match prim.mode {
                Checked::Valid(Mode::Triangles) => Topology::Triangles,
                Checked::Valid(Mode::TriangleStrip) => Topology::Strip,
                Checked::Valid(Mode::TriangleFan) => Topology::Fan,
                Checked::Valid(other) => {
                    self.warn(format!(
                        "{label} draws {other:?}; only triangles are rendered, so it is skipped"
                    ));
                    continue;
                }
                Checked::Invalid => {
                    self.warn(format!("{label} has an unknown mode; skipped"));
                    continue;
                }
            };
            if prim.targets.is_some() && !self.morph_warned {
                self.morph_warned = true;
                self.warn(format!(
                    "{label} has morph targets; they are not supported and the base shape is drawn"
                ));
            }
            let Some(raw) = self.read_primitive(prim, &label, topology)? else {
                continue;
            };
            let Some(built) = geometry::build(raw, &label, &mut self.warnings) else {
                continue;
            };
            let base = self.vertices.len();
            if base + built.vertices.len() > u32::MAX as usize
                || self.indices.len() + built.indices.len() > u32::MAX as usize
            {
                return Err(format!(
                    "{label}: the scene has more than 2^32 vertices or indices"
                ));
            }
            let material = match prim.material {
                Some(mat) if mat.value() < root.materials.len() => mat.value() as u32,
                other => {
                    if let Some(mat) = other {
                        self.warn(format!(
                            "{label} uses material {}, which does not exist; the default material \
                             is used",
                            mat.value()
                        ));
                    }
                    self.default_material_used = true;
                    root.materials.len() as u32
                }
            };
            let first_index = self.indices.len() as u32;
            self.indices
                .extend(built.indices.iter().map(|&i| i + base as u32));
            self.vertices.extend(built.vertices);
            out.push(self.primitives.len() as u32);
            self.primitives.push(Primitive {
                first_index,
                index_count: built.indices.len() as u32,
                material,
                bounds: built.bounds,
            });
        }
        Ok(out)
    }

    /// Reads a primitive's attributes and triangles, or None (with a warning) when it has
    /// nothing to draw.
    fn read_primitive(
        &mut self,
        prim: &json::mesh::Primitive,
        label: &str,
        topology: Topology,
    ) -> Result<Option<RawPrimitive>, String> {
        let (root, buffers) = (self.root, self.buffers);
        let attr = |s: Semantic| prim.attributes.get(&Checked::Valid(s)).map(|a| a.value());

        let Some(pos_acc) = attr(Semantic::Positions) else {
            self.warn(format!("{label} has no POSITION attribute; skipped"));
            return Ok(None);
        };
        let who = format!("POSITION of {label}");
        let shape = buffers.shape(root, pos_acc, &who)?;
        if shape.ty != Type::Vec3 || shape.component != ComponentType::F32 {
            return Err(format!(
                "the POSITION accessor {pos_acc} of {label} is {}; expected VEC3 FLOAT",
                shape.describe()
            ));
        }
        let positions: Vec<Vec3> = buffers
            .read_f32(root, pos_acc, &who)?
            .chunks_exact(3)
            .map(Vec3::from_slice)
            .collect();
        let count = positions.len();

        // Optional attributes of the wrong kind are dropped (and regenerated) with a warning.
        let mut optional = |sem: Semantic,
                            name: &str,
                            ok: &dyn Fn(Type, ComponentType, bool) -> bool,
                            expected: &str|
         -> Result<Option<Vec<f32>>, String> {
            let Some(a) = attr(sem) else { return Ok(None) };
            let who = format!("{name} of {label}");
            let shape = buffers.shape(root, a, &who)?;
            if !ok(shape.ty, shape.component, shape.normalized) {
                self.warnings.push(format!(
                    "the {name} accessor {a} of {label} is {}, expected {expected}; ignored",
                    shape.describe()
                ));
                return Ok(None);
            }
            if shape.count != count {
                self.warnings.push(format!(
                    "the {name} accessor {a} of {label} has {} elements but POSITION has {count}; \
                     ignored",
                    shape.count
                ));
                return Ok(None);
            }
            buffers.read_f32(root, a, &who).map(Some)
        };
        let normals = optional(
            Semantic::Normals,
            "NORMAL",
            &|t, c, _| t == Type::Vec3 && c == ComponentType::F32,
            "VEC3 FLOAT",
        )?
        .map(|v| v.chunks_exact(3).map(Vec3::from_slice).collect());
        let uvs = optional(
            Semantic::TexCoords(0),
            "TEXCOORD_0",
            &|t, c, n| {
                t == Type::Vec2
                    && (c == ComponentType::F32
                        || (n && matches!(c, ComponentType::U8 | ComponentType::U16)))
            },
            "VEC2 FLOAT or normalized UNSIGNED_BYTE/UNSIGNED_SHORT",
        )?
        .map(|v| v.chunks_exact(2).map(Vec2::from_slice).collect());
        let tangents = optional(
            Semantic::Tangents,
            "TANGENT",
            &|t, c, _| t == Type::Vec4 && c == ComponentType::F32,
            "VEC4 FLOAT",
        )?
        .map(|v| v.chunks_exact(4).map(Vec4::from_slice).collect());

        let indices: Vec<u32> = match prim.indices {
            Some(a) => {
                let idx = buffers.read_indices(root, a.value(), &format!("indices of {label}"))?;
                if let Some((k, &bad)) = idx.iter().enumerate().find(|(_, &i)| i as usize >= count)
                {
                    return Err(format!(
                        "{label}: index {bad} (entry {k} of accessor {}) is out of range for its \
                         {count} vertices",
                        a.value()
                    ));
                }
                idx
            }
            None => {
                let n = u32::try_from(count)
                    .map_err(|_| format!("{label} has more than 2^32 vertices"))?;
                (0..n).collect()
            }
        };
        let (triangles, rest) = geometry::assemble(topology, &indices);
        if rest != 0 {
            self.warn(format!(
                "{label}: {rest} trailing indices do not make a whole triangle; ignored"
            ));
        }
        Ok(Some(RawPrimitive {
            positions,
            normals,
            uvs,
            tangents,
            triangles,
        }))
    }

    fn place_light(&mut self, index: usize, node: &str, world: Mat4) {
        let all: &[json::extensions::scene::khr_lights_punctual::Light] = self.root.as_ref();
        let Some(l) = all.get(index) else {
            self.warn(format!(
                "{node} uses light {index}, which does not exist; ignored"
            ));
            return;
        };
        use json::extensions::scene::khr_lights_punctual::Type as LType;
        let label = match &l.name {
            Some(n) => format!("light {index} ('{n}') on {node}"),
            None => format!("light {index} on {node}"),
        };
        let radiance = Vec3::from(l.color) * l.intensity;
        if !radiance.is_finite() {
            self.warn(format!(
                "{label} has a non-finite colour or intensity; skipped"
            ));
            return;
        }
        if radiance.min_element() < 0.0 {
            self.warn(format!(
                "{label} has a negative colour or intensity; skipped"
            ));
            return;
        }
        let position = world.transform_point3(Vec3::ZERO);
        let direction = world.transform_vector3(Vec3::NEG_Z).try_normalize();
        let kind = match l.type_ {
            Checked::Valid(LType::Point) => LightKind::Point,
            Checked::Valid(LType::Directional) => LightKind::Directional,
            Checked::Valid(LType::Spot) => {
                let spot = l.spot.clone().unwrap_or_else(|| {
                    self.warnings.push(format!(
                        "{label} is a spot light without cone angles; glTF defaults used"
                    ));
                    json::extensions::scene::khr_lights_punctual::Spot {
                        inner_cone_angle: 0.0,
                        outer_cone_angle: std::f32::consts::FRAC_PI_4,
                    }
                });
                let (inner, outer) = (spot.inner_cone_angle, spot.outer_cone_angle);
                if !inner.is_finite() || !outer.is_finite() {
                    self.warn(format!("{label} has non-finite cone angles; skipped"));
                    return;
                }
                let outer_c = outer.clamp(0.0, std::f32::consts::FRAC_PI_2);
                let inner_c = inner.clamp(0.0, outer_c);
                if (inner_c, outer_c) != (inner, outer) {
                    self.warn(format!(
                        "{label}: cone angles inner {inner}, outer {outer} clamped to \
                         {inner_c}, {outer_c} (0 <= inner <= outer <= pi/2)"
                    ));
                }
                LightKind::Spot {
                    inner_cone: inner_c,
                    outer_cone: outer_c,
                }
            }
            Checked::Invalid => {
                self.warn(format!("{label} has an unknown type; skipped"));
                return;
            }
        };
        let direction = match (direction, kind) {
            (Some(d), _) => d,
            // A point light shines everywhere; its direction is only informative.
            (None, LightKind::Point) => Vec3::NEG_Z,
            (None, _) => {
                self.warn(format!(
                    "{label}: its node's transform collapses the -Z axis, so it has no direction; \
                     skipped"
                ));
                return;
            }
        };
        if !position.is_finite() {
            self.warn(format!("{label} has a non-finite position; skipped"));
            return;
        }
        let range = match l.range {
            Some(r) if r.is_finite() && r > 0.0 => Some(r),
            Some(r) => {
                self.warn(format!(
                    "{label} has an invalid range {r}; treated as unlimited"
                ));
                None
            }
            None => None,
        };
        self.lights.push(Light {
            name: l.name.clone(),
            kind,
            radiance,
            range,
            position,
            direction,
        });
    }
}

/// A far plane for a camera at `eye` that contains the whole scene.
fn far_from_bounds(eye: Vec3, bounds: &Aabb, znear: f32) -> f32 {
    let mut far = 0.0f32;
    if !bounds.is_empty() {
        for corner in bounds.corners() {
            far = far.max(eye.distance(corner));
        }
    }
    let far = (far * 2.0).max(znear * 1000.0);
    if far.is_finite() {
        far
    } else {
        znear * 1000.0
    }
}

/// The file's camera, or None (with a warning) when it cannot be used.
fn file_camera(
    root: &json::Root,
    index: usize,
    world: Mat4,
    bounds: &Aabb,
    warnings: &mut Vec<String>,
) -> Option<Camera> {
    let Some(cam) = root.cameras.get(index) else {
        warnings.push(format!(
            "camera {index} does not exist; the default camera is used"
        ));
        return None;
    };
    let label = match &cam.name {
        Some(n) => format!("camera {index} ('{n}')"),
        None => format!("camera {index}"),
    };
    let p = match (&cam.type_, &cam.perspective) {
        (Checked::Valid(json::camera::Type::Perspective), Some(p)) => p,
        (Checked::Valid(json::camera::Type::Orthographic), _) => {
            warnings.push(format!(
                "{label} is orthographic, which is not supported; the default camera is used"
            ));
            return None;
        }
        _ => {
            warnings.push(format!(
                "{label} has no perspective projection; the default camera is used"
            ));
            return None;
        }
    };
    let yfov_ok = p.yfov.is_finite() && p.yfov > 0.0 && p.yfov < std::f32::consts::PI;
    let znear_ok = p.znear.is_finite() && p.znear > 0.0;
    if !(yfov_ok && znear_ok) {
        warnings.push(format!(
            "{label} has an invalid yfov {} or znear {}; the default camera is used",
            p.yfov, p.znear
        ));
        return None;
    }
    // The view must be rigid: drop any scale in the node's transform, keep where it looks.
    let eye = world.w_axis.truncate();
    let back = world.z_axis.truncate().try_normalize();
    let right = back.and_then(|b| world.y_axis.truncate().cross(b).try_normalize());
    let (Some(back), Some(right)) = (back, right) else {
        warnings.push(format!(
            "{label}: its node's transform is degenerate; the default camera is used"
        ));
        return None;
    };
    let up = back.cross(right);
    let rigid = Mat4::from_cols(
        right.extend(0.0),
        up.extend(0.0),
        back.extend(0.0),
        eye.extend(1.0),
    );
    let zfar = match p.zfar {
        Some(f) if f.is_finite() && f > p.znear => f,
        Some(f) => {
            warnings.push(format!(
                "{label} has an invalid zfar {f}; one is derived from the scene bounds"
            ));
            far_from_bounds(eye, bounds, p.znear)
        }
        None => far_from_bounds(eye, bounds, p.znear),
    };
    Some(Camera {
        name: cam.name.clone(),
        world: rigid,
        yfov: p.yfov,
        znear: p.znear,
        zfar,
        is_default: false,
    })
}

/// The CONVENTIONS.md default camera: yfov 40 degrees, looking along -Z at the bounds centre c
/// from (c.x, c.y, max.z + d), d = 0.5 max(extent.x, extent.y) / tan(20 degrees).
pub fn default_camera(bounds: &Aabb) -> Camera {
    let yfov = DEFAULT_YFOV_DEGREES.to_radians();
    // An empty scene (or one too large for f32 arithmetic) gets a camera at (0, 0, 1).
    let fallback = Camera {
        name: None,
        world: Mat4::from_translation(Vec3::Z),
        yfov,
        znear: 0.01,
        zfar: 100.0,
        is_default: true,
    };
    if bounds.is_empty() {
        return fallback;
    }
    let c = bounds.center();
    let e = bounds.extent();
    let mut d = 0.5 * e.x.max(e.y) / (0.5 * yfov).tan();
    if !(d > 0.0 && d.is_finite()) {
        // A scene with no width or height (a point, or a line along z): back off a little.
        d = e.z.max(1.0);
    }
    let eye = Vec3::new(c.x, c.y, bounds.max.z + d);
    // The box's nearest face is d away and its farthest d + extent.z: keep both well inside.
    let (znear, zfar) = (0.5 * d, 2.0 * (d + e.z));
    if !(eye.is_finite() && znear > 0.0 && zfar.is_finite() && zfar > znear) {
        return fallback;
    }
    Camera {
        name: None,
        world: Mat4::from_translation(eye),
        yfov,
        znear,
        zfar,
        is_default: true,
    }
}
