//! Builds small glTF 2.0 files in code: for tests, and for the bundled default scene.
//!
//! Output is a single `.gltf` with its buffer embedded as a base64 `data:` URI. The same
//! input always gives a byte-identical file (objects are written in a fixed order, floats in
//! Rust's shortest round-trip form), so generated assets can be checked into git and
//! verified by regenerating them.
//!
//! ```no_run
//! use voxgi::scene::builder::{MaterialDesc, NodeDesc, SceneBuilder};
//! let mut b = SceneBuilder::new();
//! let white = b.add_material(MaterialDesc::lambertian("white", [0.8, 0.8, 0.8]));
//! let tri = b.add_triangles("tri", &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], None, Some(white));
//! b.add_node(NodeDesc::new("tri").mesh(tri).translation([0.0, 0.0, -2.0]));
//! b.write(std::path::Path::new("tri.gltf")).unwrap();
//! ```

use super::base64;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A metallic-roughness material (glTF defaults from `Default`).
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialDesc {
    pub name: Option<String>,
    pub base_color: [f32; 4],
    /// Index returned by [`SceneBuilder::add_image`].
    pub base_color_texture: Option<usize>,
    pub metallic: f32,
    pub roughness: f32,
    pub emissive: [f32; 3],
    /// Written as KHR_materials_emissive_strength when set.
    pub emissive_strength: Option<f32>,
    /// Written as KHR_materials_specular.specularFactor when set.
    pub specular_factor: Option<f32>,
    pub double_sided: bool,
}

impl Default for MaterialDesc {
    fn default() -> Self {
        MaterialDesc {
            name: None,
            base_color: [1.0; 4],
            base_color_texture: None,
            metallic: 1.0,
            roughness: 1.0,
            emissive: [0.0; 3],
            emissive_strength: None,
            specular_factor: None,
            double_sided: false,
        }
    }
}

impl MaterialDesc {
    /// A purely diffuse material: metallic 0 and specularFactor 0 (CONVENTIONS.md: exactly
    /// Lambertian with albedo = base colour).
    pub fn lambertian(name: &str, albedo: [f32; 3]) -> Self {
        MaterialDesc {
            name: Some(name.to_string()),
            base_color: [albedo[0], albedo[1], albedo[2], 1.0],
            metallic: 0.0,
            roughness: 1.0,
            specular_factor: Some(0.0),
            ..Default::default()
        }
    }

    /// Adds emission: radiance = `color` x `strength` (via KHR_materials_emissive_strength).
    pub fn emissive(mut self, color: [f32; 3], strength: f32) -> Self {
        self.emissive = color;
        self.emissive_strength = Some(strength);
        self
    }
}

/// One primitive: triangles (a list, or indexed) with optional normals and UVs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PrimitiveDesc {
    pub positions: Vec<[f32; 3]>,
    pub normals: Option<Vec<[f32; 3]>>,
    pub uvs: Option<Vec<[f32; 2]>>,
    /// None writes a non-indexed primitive (every 3 positions form a triangle).
    pub indices: Option<Vec<u32>>,
    /// Index returned by [`SceneBuilder::add_material`]; None uses the glTF default material.
    pub material: Option<usize>,
}

impl PrimitiveDesc {
    /// A non-indexed triangle list.
    pub fn triangles(positions: &[[f32; 3]], material: Option<usize>) -> Self {
        PrimitiveDesc {
            positions: positions.to_vec(),
            material,
            ..Default::default()
        }
    }
}

/// A KHR_lights_punctual light type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightType {
    Point,
    Spot {
        inner_cone_angle: f32,
        outer_cone_angle: f32,
    },
    Directional,
}

#[derive(Clone, Debug, PartialEq)]
pub struct LightDesc {
    pub name: Option<String>,
    pub kind: LightType,
    pub color: [f32; 3],
    pub intensity: f32,
    pub range: Option<f32>,
}

impl LightDesc {
    pub fn new(name: &str, kind: LightType, color: [f32; 3], intensity: f32) -> Self {
        LightDesc {
            name: Some(name.to_string()),
            kind,
            color,
            intensity,
            range: None,
        }
    }
}

/// A perspective camera.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraDesc {
    pub name: Option<String>,
    /// Vertical field of view, radians.
    pub yfov: f32,
    pub znear: f32,
    /// None: infinite projection.
    pub zfar: Option<f32>,
    pub aspect_ratio: Option<f32>,
}

/// A node: TRS or matrix transform, optional mesh, light, camera and children.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodeDesc {
    pub name: Option<String>,
    /// In f64, as glTF's JSON numbers are: a node far from the origin keeps its place to the
    /// micrometre (f32 would round 100000.35 to 100000.3516).
    pub translation: Option<[f64; 3]>,
    /// Unit quaternion, x y z w.
    pub rotation: Option<[f32; 4]>,
    pub scale: Option<[f32; 3]>,
    /// Column-major; when set, TRS fields are not written.
    pub matrix: Option<[f32; 16]>,
    pub mesh: Option<usize>,
    pub light: Option<usize>,
    pub camera: Option<usize>,
    pub children: Vec<usize>,
}

impl NodeDesc {
    pub fn new(name: &str) -> Self {
        NodeDesc {
            name: Some(name.to_string()),
            ..Default::default()
        }
    }
    pub fn mesh(mut self, mesh: usize) -> Self {
        self.mesh = Some(mesh);
        self
    }
    pub fn light(mut self, light: usize) -> Self {
        self.light = Some(light);
        self
    }
    pub fn camera(mut self, camera: usize) -> Self {
        self.camera = Some(camera);
        self
    }
    pub fn translation<T: Into<f64> + Copy>(mut self, t: [T; 3]) -> Self {
        self.translation = Some(t.map(Into::into));
        self
    }
    pub fn rotation(mut self, xyzw: [f32; 4]) -> Self {
        self.rotation = Some(xyzw);
        self
    }
    pub fn scale(mut self, s: [f32; 3]) -> Self {
        self.scale = Some(s);
        self
    }
    pub fn matrix(mut self, m: [f32; 16]) -> Self {
        self.matrix = Some(m);
        self
    }
    pub fn child(mut self, node: usize) -> Self {
        self.children.push(node);
        self
    }
}

#[derive(Clone, Debug)]
struct MeshDesc {
    name: String,
    primitives: Vec<PrimitiveDesc>,
}

/// Collects a glTF document; nodes that are nobody's child become the scene's roots.
#[derive(Clone, Debug, Default)]
pub struct SceneBuilder {
    materials: Vec<MaterialDesc>,
    images: Vec<String>,
    meshes: Vec<MeshDesc>,
    nodes: Vec<NodeDesc>,
    lights: Vec<LightDesc>,
    cameras: Vec<CameraDesc>,
}

impl SceneBuilder {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn add_material(&mut self, m: MaterialDesc) -> usize {
        self.materials.push(m);
        self.materials.len() - 1
    }

    /// A texture whose image is the file at `uri` (relative to the .gltf); returns the index
    /// for `MaterialDesc::base_color_texture`.
    pub fn add_image(&mut self, uri: &str) -> usize {
        self.images.push(uri.to_string());
        self.images.len() - 1
    }

    pub fn add_mesh(&mut self, name: &str, primitives: Vec<PrimitiveDesc>) -> usize {
        self.meshes.push(MeshDesc {
            name: name.to_string(),
            primitives,
        });
        self.meshes.len() - 1
    }

    /// A one-primitive mesh from a triangle list (3 positions per triangle).
    pub fn add_triangles(
        &mut self,
        name: &str,
        positions: &[[f32; 3]],
        normals: Option<&[[f32; 3]]>,
        material: Option<usize>,
    ) -> usize {
        let mut p = PrimitiveDesc::triangles(positions, material);
        p.normals = normals.map(|n| n.to_vec());
        self.add_mesh(name, vec![p])
    }

    pub fn add_node(&mut self, node: NodeDesc) -> usize {
        self.nodes.push(node);
        self.nodes.len() - 1
    }

    pub fn add_light(&mut self, light: LightDesc) -> usize {
        self.lights.push(light);
        self.lights.len() - 1
    }

    pub fn add_camera(&mut self, camera: CameraDesc) -> usize {
        self.cameras.push(camera);
        self.cameras.len() - 1
    }

    /// Multiplies the intensity of every point and spot light (e.g. by s^2 when the scene is
    /// scaled by s, so that irradiance stays the same).
    pub fn scale_punctual_intensities(&mut self, factor: f32) {
        for l in &mut self.lights {
            if l.kind != LightType::Directional {
                l.intensity *= factor;
            }
        }
    }

    /// Makes `root` the parent of every node that had none.
    pub fn wrap_roots(&mut self, mut root: NodeDesc) -> usize {
        let mut is_child = vec![false; self.nodes.len()];
        for n in &self.nodes {
            for &c in &n.children {
                is_child[c] = true;
            }
        }
        root.children
            .extend((0..self.nodes.len()).filter(|&i| !is_child[i]));
        self.add_node(root)
    }

    /// The document as `.gltf` JSON text with the buffer embedded.
    pub fn to_gltf(&self) -> String {
        self.json_and_bin(true).0
    }

    /// The document as binary glTF (.glb): JSON chunk, then the buffer as the BIN chunk.
    pub fn to_glb(&self) -> Vec<u8> {
        let (json, bin) = self.json_and_bin(false);
        let mut json = json.into_bytes();
        // Chunks are 4-byte aligned: JSON pads with spaces, BIN with zeros.
        while json.len() % 4 != 0 {
            json.push(b' ');
        }
        let mut bin = bin;
        while bin.len() % 4 != 0 {
            bin.push(0);
        }
        let bin_chunk = if bin.is_empty() { 0 } else { 8 + bin.len() };
        let total = 12 + 8 + json.len() + bin_chunk;
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json);
        if !bin.is_empty() {
            out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
            out.extend_from_slice(b"BIN\0");
            out.extend_from_slice(&bin);
        }
        out
    }

    /// JSON text and the binary buffer; `embed` puts the buffer in a data: URI (for .gltf),
    /// otherwise the buffer has no uri (the .glb BIN chunk).
    fn json_and_bin(&self, embed: bool) -> (String, Vec<u8>) {
        let mut bin = BinWriter::default();
        let meshes: Vec<Json> = self
            .meshes
            .iter()
            .map(|m| {
                let prims = m
                    .primitives
                    .iter()
                    .map(|p| primitive_json(p, &mut bin))
                    .collect();
                obj(vec![("name", s(&m.name)), ("primitives", Json::Arr(prims))])
            })
            .collect();

        let mut used: Vec<&str> = Vec::new();
        let materials: Vec<Json> = self
            .materials
            .iter()
            .map(|m| material_json(m, &mut used))
            .collect();
        if !self.lights.is_empty() {
            used.push("KHR_lights_punctual");
        }
        used.sort_unstable();
        used.dedup();

        let mut is_child = vec![false; self.nodes.len()];
        for n in &self.nodes {
            for &c in &n.children {
                if let Some(f) = is_child.get_mut(c) {
                    *f = true;
                }
            }
        }
        let roots: Vec<Json> = (0..self.nodes.len())
            .filter(|&i| !is_child[i])
            .map(int)
            .collect();

        let mut root: Vec<(&str, Json)> = vec![(
            "asset",
            obj(vec![
                ("generator", s("voxgi scene builder")),
                ("version", s("2.0")),
            ]),
        )];
        if !used.is_empty() {
            root.push((
                "extensionsUsed",
                Json::Arr(used.iter().map(|e| s(e)).collect()),
            ));
        }
        root.push(("scene", int(0)));
        let mut scene = vec![("name", s("Scene"))];
        if !roots.is_empty() {
            scene.push(("nodes", Json::Arr(roots)));
        }
        root.push(("scenes", Json::Arr(vec![obj(scene)])));
        push_nonempty(
            &mut root,
            "nodes",
            self.nodes.iter().map(node_json).collect(),
        );
        push_nonempty(&mut root, "meshes", meshes);
        push_nonempty(&mut root, "materials", materials);
        push_nonempty(
            &mut root,
            "textures",
            (0..self.images.len())
                .map(|i| obj(vec![("source", int(i))]))
                .collect(),
        );
        push_nonempty(
            &mut root,
            "images",
            self.images
                .iter()
                .map(|u| obj(vec![("uri", s(u))]))
                .collect(),
        );
        push_nonempty(
            &mut root,
            "cameras",
            self.cameras.iter().map(camera_json).collect(),
        );
        push_nonempty(&mut root, "accessors", std::mem::take(&mut bin.accessors));
        push_nonempty(&mut root, "bufferViews", std::mem::take(&mut bin.views));
        if !bin.data.is_empty() {
            let mut buffer = vec![("byteLength", int(bin.data.len()))];
            if embed {
                let uri = format!(
                    "data:application/octet-stream;base64,{}",
                    base64::encode(&bin.data)
                );
                buffer.push(("uri", Json::Str(uri)));
            }
            root.push(("buffers", Json::Arr(vec![obj(buffer)])));
        }
        if !self.lights.is_empty() {
            let lights = self.lights.iter().map(light_json).collect();
            root.push((
                "extensions",
                obj(vec![(
                    "KHR_lights_punctual",
                    obj(vec![("lights", Json::Arr(lights))]),
                )]),
            ));
        }
        let mut out = String::new();
        obj(root).write(&mut out, 0);
        out.push('\n');
        (out, bin.data)
    }

    /// Writes the `.gltf` atomically: a temporary file in the same folder, then a rename, so
    /// readers never see half a file.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        static SERIAL: AtomicUsize = AtomicUsize::new(0);
        let text = self.to_gltf();
        let dir = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let name = path.file_name().ok_or_else(|| {
            std::io::Error::new(std::io::ErrorKind::InvalidInput, "path has no file name")
        })?;
        let tmp = dir.join(format!(
            ".{}.tmp-{}-{}",
            name.to_string_lossy(),
            std::process::id(),
            SERIAL.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(dir)?;
        let result = (|| {
            let mut f = std::fs::File::create(&tmp)?;
            f.write_all(text.as_bytes())?;
            f.sync_all()?;
            std::fs::rename(&tmp, path)
        })();
        if result.is_err() {
            let _ = std::fs::remove_file(&tmp);
        }
        result
    }
}

/// Minimal JSON tree with ordered objects, so output order is fixed.
enum Json {
    /// Already formatted.
    Num(String),
    Str(String),
    Bool(bool),
    Arr(Vec<Json>),
    Obj(Vec<(String, Json)>),
}

fn obj(fields: Vec<(&str, Json)>) -> Json {
    Json::Obj(
        fields
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect(),
    )
}

fn s(text: &str) -> Json {
    Json::Str(text.to_string())
}

fn int(v: usize) -> Json {
    Json::Num(v.to_string())
}

/// JSON has no NaN or infinity: such values are written as null (the file then fails to load,
/// which is the honest outcome for a broken factor).
fn num(v: f32) -> Json {
    if v.is_finite() {
        Json::Num(format!("{v}"))
    } else {
        Json::Num("null".into())
    }
}

fn nums(v: &[f32]) -> Json {
    Json::Arr(v.iter().map(|&x| num(x)).collect())
}

/// f64s as the shortest text that reads back as the same f64.
fn nums64(v: &[f64]) -> Json {
    Json::Arr(
        v.iter()
            .map(|&x| {
                Json::Num(if x.is_finite() {
                    format!("{x}")
                } else {
                    "null".into()
                })
            })
            .collect(),
    )
}

fn push_nonempty(root: &mut Vec<(&str, Json)>, key: &'static str, items: Vec<Json>) {
    if !items.is_empty() {
        root.push((key, Json::Arr(items)));
    }
}

impl Json {
    fn write(&self, out: &mut String, depth: usize) {
        let pad = |out: &mut String, d: usize| out.extend(std::iter::repeat_n("  ", d));
        match self {
            Json::Num(n) => out.push_str(n),
            Json::Bool(b) => out.push_str(if *b { "true" } else { "false" }),
            Json::Str(text) => {
                out.push('"');
                for c in text.chars() {
                    match c {
                        '"' => out.push_str("\\\""),
                        '\\' => out.push_str("\\\\"),
                        '\n' => out.push_str("\\n"),
                        c if (c as u32) < 0x20 => {
                            let _ = write!(out, "\\u{:04x}", c as u32);
                        }
                        c => out.push(c),
                    }
                }
                out.push('"');
            }
            Json::Arr(items) if items.is_empty() => out.push_str("[]"),
            // Short numeric arrays (vectors, matrices) read best on one line.
            Json::Arr(items) if items.iter().all(|i| matches!(i, Json::Num(_))) => {
                out.push('[');
                for (k, i) in items.iter().enumerate() {
                    if k > 0 {
                        out.push_str(", ");
                    }
                    i.write(out, depth);
                }
                out.push(']');
            }
            Json::Arr(items) => {
                out.push_str("[\n");
                for (k, i) in items.iter().enumerate() {
                    pad(out, depth + 1);
                    i.write(out, depth + 1);
                    out.push_str(if k + 1 < items.len() { ",\n" } else { "\n" });
                }
                pad(out, depth);
                out.push(']');
            }
            Json::Obj(fields) if fields.is_empty() => out.push_str("{}"),
            Json::Obj(fields) => {
                out.push_str("{\n");
                for (k, (key, v)) in fields.iter().enumerate() {
                    pad(out, depth + 1);
                    Json::Str(key.clone()).write(out, depth + 1);
                    out.push_str(": ");
                    v.write(out, depth + 1);
                    out.push_str(if k + 1 < fields.len() { ",\n" } else { "\n" });
                }
                pad(out, depth);
                out.push('}');
            }
        }
    }
}

/// The binary buffer with its views and accessors.
#[derive(Default)]
struct BinWriter {
    data: Vec<u8>,
    views: Vec<Json>,
    accessors: Vec<Json>,
}

const FLOAT: usize = 5126;
const UNSIGNED_INT: usize = 5125;
const ARRAY_BUFFER: usize = 34962;
const ELEMENT_ARRAY_BUFFER: usize = 34963;

impl BinWriter {
    /// Appends little-endian 4-byte words as a view + accessor; returns the accessor index.
    fn push(
        &mut self,
        words: &[u32],
        count: usize,
        ty: &str,
        component: usize,
        target: usize,
        bounds: Option<(Vec<f32>, Vec<f32>)>,
    ) -> usize {
        let offset = self.data.len();
        for w in words {
            self.data.extend_from_slice(&w.to_le_bytes());
        }
        self.views.push(obj(vec![
            ("buffer", int(0)),
            ("byteOffset", int(offset)),
            ("byteLength", int(words.len() * 4)),
            ("target", int(target)),
        ]));
        let mut acc = vec![
            ("bufferView", int(self.views.len() - 1)),
            ("componentType", int(component)),
            ("count", int(count)),
            ("type", s(ty)),
        ];
        if let Some((min, max)) = bounds {
            acc.push(("min", nums(&min)));
            acc.push(("max", nums(&max)));
        }
        self.accessors.push(obj(acc));
        self.accessors.len() - 1
    }

    fn floats<const N: usize>(&mut self, v: &[[f32; N]], ty: &str, with_bounds: bool) -> usize {
        let words: Vec<u32> = v.iter().flatten().map(|x| x.to_bits()).collect();
        let mut bounds = None;
        if with_bounds {
            // min/max over finite values only: JSON cannot hold NaN, and test files carry some.
            let mut min = [f32::INFINITY; N];
            let mut max = [f32::NEG_INFINITY; N];
            for e in v.iter().filter(|e| e.iter().all(|x| x.is_finite())) {
                for c in 0..N {
                    min[c] = min[c].min(e[c]);
                    max[c] = max[c].max(e[c]);
                }
            }
            if min[0].is_finite() {
                bounds = Some((min.to_vec(), max.to_vec()));
            }
        }
        self.push(&words, v.len(), ty, FLOAT, ARRAY_BUFFER, bounds)
    }
}

fn primitive_json(p: &PrimitiveDesc, bin: &mut BinWriter) -> Json {
    let mut attrs = vec![("POSITION", int(bin.floats(&p.positions, "VEC3", true)))];
    if let Some(n) = &p.normals {
        attrs.push(("NORMAL", int(bin.floats(n, "VEC3", false))));
    }
    if let Some(uv) = &p.uvs {
        attrs.push(("TEXCOORD_0", int(bin.floats(uv, "VEC2", false))));
    }
    let mut fields = vec![("attributes", obj(attrs))];
    if let Some(idx) = &p.indices {
        let a = bin.push(
            idx,
            idx.len(),
            "SCALAR",
            UNSIGNED_INT,
            ELEMENT_ARRAY_BUFFER,
            None,
        );
        fields.push(("indices", int(a)));
    }
    if let Some(m) = p.material {
        fields.push(("material", int(m)));
    }
    obj(fields)
}

fn material_json(m: &MaterialDesc, used: &mut Vec<&'static str>) -> Json {
    let mut pbr = vec![("baseColorFactor", nums(&m.base_color))];
    if let Some(t) = m.base_color_texture {
        pbr.push(("baseColorTexture", obj(vec![("index", int(t))])));
    }
    pbr.push(("metallicFactor", num(m.metallic)));
    pbr.push(("roughnessFactor", num(m.roughness)));
    let mut fields = Vec::new();
    if let Some(n) = &m.name {
        fields.push(("name", s(n)));
    }
    fields.push(("pbrMetallicRoughness", obj(pbr)));
    if m.emissive != [0.0; 3] {
        fields.push(("emissiveFactor", nums(&m.emissive)));
    }
    let mut ext = Vec::new();
    if let Some(e) = m.emissive_strength {
        used.push("KHR_materials_emissive_strength");
        ext.push((
            "KHR_materials_emissive_strength",
            obj(vec![("emissiveStrength", num(e))]),
        ));
    }
    if let Some(f) = m.specular_factor {
        used.push("KHR_materials_specular");
        ext.push((
            "KHR_materials_specular",
            obj(vec![("specularFactor", num(f))]),
        ));
    }
    if !ext.is_empty() {
        fields.push(("extensions", obj(ext)));
    }
    if m.double_sided {
        fields.push(("doubleSided", Json::Bool(true)));
    }
    obj(fields)
}

fn node_json(n: &NodeDesc) -> Json {
    let mut f = Vec::new();
    if let Some(name) = &n.name {
        f.push(("name", s(name)));
    }
    if let Some(m) = n.mesh {
        f.push(("mesh", int(m)));
    }
    if let Some(c) = n.camera {
        f.push(("camera", int(c)));
    }
    if !n.children.is_empty() {
        f.push((
            "children",
            Json::Arr(n.children.iter().map(|&c| int(c)).collect()),
        ));
    }
    match n.matrix {
        Some(m) => f.push(("matrix", nums(&m))),
        None => {
            if let Some(t) = n.translation {
                f.push(("translation", nums64(&t)));
            }
            if let Some(r) = n.rotation {
                f.push(("rotation", nums(&r)));
            }
            if let Some(sc) = n.scale {
                f.push(("scale", nums(&sc)));
            }
        }
    }
    if let Some(l) = n.light {
        f.push((
            "extensions",
            obj(vec![("KHR_lights_punctual", obj(vec![("light", int(l))]))]),
        ));
    }
    obj(f)
}

fn light_json(l: &LightDesc) -> Json {
    let mut f = Vec::new();
    if let Some(n) = &l.name {
        f.push(("name", s(n)));
    }
    let ty = match l.kind {
        LightType::Point => "point",
        LightType::Spot { .. } => "spot",
        LightType::Directional => "directional",
    };
    f.push(("type", s(ty)));
    f.push(("color", nums(&l.color)));
    f.push(("intensity", num(l.intensity)));
    if let Some(r) = l.range {
        f.push(("range", num(r)));
    }
    if let LightType::Spot {
        inner_cone_angle,
        outer_cone_angle,
    } = l.kind
    {
        f.push((
            "spot",
            obj(vec![
                ("innerConeAngle", num(inner_cone_angle)),
                ("outerConeAngle", num(outer_cone_angle)),
            ]),
        ));
    }
    obj(f)
}

fn camera_json(c: &CameraDesc) -> Json {
    let mut p = Vec::new();
    if let Some(a) = c.aspect_ratio {
        p.push(("aspectRatio", num(a)));
    }
    p.push(("yfov", num(c.yfov)));
    if let Some(z) = c.zfar {
        p.push(("zfar", num(z)));
    }
    p.push(("znear", num(c.znear)));
    let mut f = Vec::new();
    if let Some(n) = &c.name {
        f.push(("name", s(n)));
    }
    f.push(("type", s("perspective")));
    f.push(("perspective", obj(p)));
    obj(f)
}

/// An indexed quad with a flat normal; corners in any cyclic order, wound so that its front
/// faces along `normal`.
pub fn quad(corners: [[f32; 3]; 4], normal: [f32; 3], material: Option<usize>) -> PrimitiveDesc {
    let sub = |a: [f32; 3], b: [f32; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let (e1, e2) = (sub(corners[1], corners[0]), sub(corners[2], corners[0]));
    let cross = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    let facing = cross[0] * normal[0] + cross[1] * normal[1] + cross[2] * normal[2];
    let indices = if facing >= 0.0 {
        vec![0, 1, 2, 0, 2, 3]
    } else {
        vec![0, 2, 1, 0, 3, 2]
    };
    PrimitiveDesc {
        positions: corners.to_vec(),
        normals: Some(vec![normal; 4]),
        uvs: None,
        indices: Some(indices),
        material,
    }
}

/// Joins primitives that share a material into one (indices rebased).
pub fn merge(parts: &[PrimitiveDesc]) -> PrimitiveDesc {
    let mut out = PrimitiveDesc {
        material: parts.first().and_then(|p| p.material),
        normals: Some(Vec::new()),
        indices: Some(Vec::new()),
        ..Default::default()
    };
    for p in parts {
        let base = out.positions.len() as u32;
        let idx: Vec<u32> = match &p.indices {
            Some(i) => i.clone(),
            None => (0..p.positions.len() as u32).collect(),
        };
        out.positions.extend_from_slice(&p.positions);
        if let (Some(all), Some(n)) = (out.normals.as_mut(), &p.normals) {
            all.extend_from_slice(n);
        } else {
            out.normals = None;
        }
        if let Some(all) = out.indices.as_mut() {
            all.extend(idx.iter().map(|i| i + base));
        }
    }
    out
}

/// A unit cube centred on the origin with outward flat normals (24 vertices, 12 triangles).
pub fn unit_cube(material: Option<usize>) -> PrimitiveDesc {
    let h = 0.5;
    let faces: [([f32; 3], [[f32; 3]; 4]); 6] = [
        (
            [1.0, 0.0, 0.0],
            [[h, -h, -h], [h, h, -h], [h, h, h], [h, -h, h]],
        ),
        (
            [-1.0, 0.0, 0.0],
            [[-h, -h, -h], [-h, -h, h], [-h, h, h], [-h, h, -h]],
        ),
        (
            [0.0, 1.0, 0.0],
            [[-h, h, -h], [-h, h, h], [h, h, h], [h, h, -h]],
        ),
        (
            [0.0, -1.0, 0.0],
            [[-h, -h, -h], [h, -h, -h], [h, -h, h], [-h, -h, h]],
        ),
        (
            [0.0, 0.0, 1.0],
            [[-h, -h, h], [h, -h, h], [h, h, h], [-h, h, h]],
        ),
        (
            [0.0, 0.0, -1.0],
            [[-h, -h, -h], [-h, h, -h], [h, h, -h], [h, -h, -h]],
        ),
    ];
    let quads: Vec<PrimitiveDesc> = faces.iter().map(|(n, c)| quad(*c, *n, material)).collect();
    merge(&quads)
}

/// Where the bundled default scene lives, relative to the crate root.
pub const DEFAULT_SCENE_PATH: &str = "assets/cornell-box.gltf";

/// The bundled default scene: a 2 m Cornell-type box of our own design, open at the front
/// (+Z), floor at y = 0. White floor, ceiling and back wall; red left (-X) and green right
/// (+X) walls; a tall and a short white box; a 0.5 m x 0.5 m emissive panel just below the
/// ceiling (radiance (1, 0.9, 0.75) x 10 via KHR_materials_emissive_strength); and a point
/// light (2 W/sr) under the panel so direct lighting casts sharp shadows. Every material is
/// Lambertian (metallic 0, specularFactor 0). There is no camera: the CONVENTIONS.md default
/// camera looks in through the open front, framing the box's 2 m height exactly.
///
/// All numbers are literals (no trigonometry at build time) so the file is byte-identical on
/// every platform.
pub fn default_cornell_box() -> SceneBuilder {
    let mut b = SceneBuilder::new();
    let white = b.add_material(MaterialDesc::lambertian("white", [0.73, 0.73, 0.73]));
    let red = b.add_material(MaterialDesc::lambertian("red", [0.63, 0.065, 0.05]));
    let green = b.add_material(MaterialDesc::lambertian("green", [0.14, 0.45, 0.091]));
    let light = b.add_material(
        MaterialDesc::lambertian("light", [0.78, 0.78, 0.78]).emissive([1.0, 0.9, 0.75], 10.0),
    );

    let (lo, hi, top) = (-1.0, 1.0, 2.0);
    let white_walls = merge(&[
        // floor
        quad(
            [[lo, 0.0, lo], [hi, 0.0, lo], [hi, 0.0, hi], [lo, 0.0, hi]],
            [0.0, 1.0, 0.0],
            Some(white),
        ),
        // ceiling
        quad(
            [[lo, top, lo], [hi, top, lo], [hi, top, hi], [lo, top, hi]],
            [0.0, -1.0, 0.0],
            Some(white),
        ),
        // back wall
        quad(
            [[lo, 0.0, lo], [hi, 0.0, lo], [hi, top, lo], [lo, top, lo]],
            [0.0, 0.0, 1.0],
            Some(white),
        ),
    ]);
    let left = quad(
        [[lo, 0.0, lo], [lo, 0.0, hi], [lo, top, hi], [lo, top, lo]],
        [1.0, 0.0, 0.0],
        Some(red),
    );
    let right = quad(
        [[hi, 0.0, lo], [hi, 0.0, hi], [hi, top, hi], [hi, top, lo]],
        [-1.0, 0.0, 0.0],
        Some(green),
    );
    let room = b.add_mesh("room", vec![white_walls, left, right]);
    let (l, y) = (0.25, 1.98);
    let panel = b.add_mesh(
        "light panel",
        vec![quad(
            [[-l, y, -l], [l, y, -l], [l, y, l], [-l, y, l]],
            [0.0, -1.0, 0.0],
            Some(light),
        )],
    );
    // One cube mesh placed twice: exercises instancing.
    let cube = b.add_mesh("box", vec![unit_cube(Some(white))]);
    let point = b.add_light(LightDesc::new(
        "point light",
        LightType::Point,
        [1.0, 0.9, 0.75],
        2.0,
    ));

    b.add_node(NodeDesc::new("room").mesh(room));
    b.add_node(NodeDesc::new("light panel").mesh(panel));
    // Rotations about +Y: (0, sin(a/2), 0, cos(a/2)) for a = +18 and -18 degrees.
    b.add_node(
        NodeDesc::new("tall box")
            .mesh(cube)
            .translation([-0.42, 0.6, -0.3])
            .rotation([0.0, 0.15643446, 0.0, 0.98768834])
            .scale([0.6, 1.2, 0.6]),
    );
    b.add_node(
        NodeDesc::new("short box")
            .mesh(cube)
            .translation([0.42, 0.3, 0.35])
            .rotation([0.0, -0.15643446, 0.0, 0.98768834])
            .scale([0.6, 0.6, 0.6]),
    );
    b.add_node(
        NodeDesc::new("point light")
            .light(point)
            .translation([0.0, 1.8, 0.0]),
    );
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn output_is_deterministic_and_escaped() {
        let mut b = default_cornell_box();
        b.add_node(NodeDesc::new("quote \" and \\ and \n"));
        let a = b.to_gltf();
        assert_eq!(a, b.clone().to_gltf());
        assert!(a.contains(r#""quote \" and \\ and \n""#));
        assert!(a.contains("data:application/octet-stream;base64,"));
    }

    #[test]
    fn quads_face_their_normal() {
        let q = quad(
            [
                [0.0, 0.0, 0.0],
                [0.0, 0.0, 1.0],
                [1.0, 0.0, 1.0],
                [1.0, 0.0, 0.0],
            ],
            [0.0, 1.0, 0.0],
            None,
        );
        let p = &q.positions;
        let i = q.indices.unwrap();
        let (a, b, c) = (p[i[0] as usize], p[i[1] as usize], p[i[2] as usize]);
        let e1 = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let e2 = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        assert!(e1[2] * e2[0] - e1[0] * e2[2] > 0.0);
    }
}
