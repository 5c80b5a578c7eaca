//! The scene as the renderer sees it, loaded from glTF 2.0 per `../shared/CONVENTIONS.md`.
//!
//! Geometry stays in object space (one shared vertex and index buffer); instances place
//! primitives in the world, so nodes can move between frames without re-uploading vertices.

use glam::{Mat4, Vec3, Vec4};
use std::path::PathBuf;

mod accessor;
pub mod animation;
mod base64;
pub mod builder;
pub mod environment;
pub mod fuzz;
mod geometry;
mod load;
mod material;
pub use animation::{Animation, Motion, Node, Spin, SPIN_DEGREES_PER_SECOND};
pub use environment::{EnvSource, Environment};
pub use load::{default_camera, load};

/// Vertical field of view of the CONVENTIONS.md default camera.
pub const DEFAULT_YFOV_DEGREES: f32 = 40.0;

/// One vertex as uploaded to the GPU (std430-compatible, 48 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
    /// xyz tangent, w handedness (+1 or -1), per the glTF spec.
    pub tangent: [f32; 4],
}

/// A range of the shared index buffer drawn with one material. Index values are absolute
/// (already offset into `Scene::vertices`).
#[derive(Clone, Debug)]
pub struct Primitive {
    pub first_index: u32,
    pub index_count: u32,
    pub material: u32,
    /// Object-space bounds of the primitive.
    pub bounds: Aabb,
}

/// A primitive placed in the world by a node.
#[derive(Clone, Debug)]
pub struct Instance {
    pub primitive: u32,
    pub node: usize,
    pub node_name: Option<String>,
    pub world: Mat4,
}

impl Instance {
    /// Negative-determinant transforms mirror the mesh, flipping its winding.
    pub fn flips_winding(&self) -> bool {
        self.world.determinant() < 0.0
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaMode {
    Opaque,
    Mask(f32),
    Blend,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TexRef {
    /// Index into `Scene::textures`.
    pub texture: u32,
    /// Which TEXCOORD set; only 0 is uploaded, others fall back to 0 with a warning.
    pub tex_coord: u32,
}

/// glTF metallic-roughness material with the extensions the renderer reads.
#[derive(Clone, Debug)]
pub struct Material {
    pub name: Option<String>,
    pub base_color: Vec4,
    pub base_color_tex: Option<TexRef>,
    pub metallic: f32,
    pub roughness: f32,
    /// Roughness in G, metalness in B (linear).
    pub metallic_roughness_tex: Option<TexRef>,
    pub normal_tex: Option<TexRef>,
    pub normal_scale: f32,
    /// emissiveFactor x KHR_materials_emissive_strength (radiance, HDR).
    pub emissive: Vec3,
    pub emissive_tex: Option<TexRef>,
    /// KHR_materials_specular specularFactor (default 1).
    pub specular_factor: f32,
    /// Specular factor in the A channel (linear).
    pub specular_tex: Option<TexRef>,
    /// KHR_materials_specular specularColorFactor (default 1,1,1).
    pub specular_color: Vec3,
    pub specular_color_tex: Option<TexRef>,
    pub alpha_mode: AlphaMode,
    pub double_sided: bool,
}

impl Default for Material {
    /// The glTF default material.
    fn default() -> Self {
        Material {
            name: None,
            base_color: Vec4::ONE,
            base_color_tex: None,
            metallic: 1.0,
            roughness: 1.0,
            metallic_roughness_tex: None,
            normal_tex: None,
            normal_scale: 1.0,
            emissive: Vec3::ZERO,
            emissive_tex: None,
            specular_factor: 1.0,
            specular_tex: None,
            specular_color: Vec3::ONE,
            specular_color_tex: None,
            alpha_mode: AlphaMode::Opaque,
            double_sided: false,
        }
    }
}

impl Material {
    pub fn is_emissive(&self) -> bool {
        self.emissive.max_element() > 0.0
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    MirroredRepeat,
    ClampToEdge,
}

/// A decoded image in one colour space, with its sampler. An image used both as sRGB colour
/// and as linear data appears twice.
#[derive(Clone, Debug)]
pub struct Texture {
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// Tightly packed RGBA8 texels, row 0 first.
    pub rgba8: Vec<u8>,
    pub srgb: bool,
    pub wrap_s: Wrap,
    pub wrap_t: Wrap,
    /// Nearest magnification filter (else linear).
    pub mag_nearest: bool,
    /// Nearest minification filter (else linear); mipmapping is always on.
    pub min_nearest: bool,
}

impl Texture {
    /// Each byte value's linear light: decoded from sRGB where the texture holds sRGB.
    pub fn linear_table(&self) -> Vec<f32> {
        (0..256)
            .map(|i| {
                let c = i as f32 / 255.0;
                if !self.srgb {
                    c
                } else if c <= 0.04045 {
                    c / 12.92
                } else {
                    ((c + 0.055) / 1.055).powf(2.4)
                }
            })
            .collect()
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    Directional,
    Point,
    /// Cone angles in radians, 0 <= inner <= outer <= pi/2.
    Spot {
        inner_cone: f32,
        outer_cone: f32,
    },
}

/// A KHR_lights_punctual light, read radiometrically (CONVENTIONS.md).
#[derive(Clone, Debug)]
pub struct Light {
    pub name: Option<String>,
    pub kind: LightKind,
    /// intensity x color: W/sr for point and spot, W/m^2 for directional.
    pub radiance: Vec3,
    pub range: Option<f32>,
    pub position: Vec3,
    /// Unit world direction the light shines along (the node's -Z axis).
    pub direction: Vec3,
}

/// A view asked for on the command line: one of the file's cameras, or an eye and a target.
#[derive(Clone, Debug, PartialEq)]
pub enum ViewSpec {
    /// `--camera NAME|INDEX`.
    Camera(String),
    /// `--eye X,Y,Z --target X,Y,Z [--up X,Y,Z] [--fov DEG]`, in the file's coordinates.
    LookAt {
        eye: glam::DVec3,
        target: glam::DVec3,
        up: Vec3,
        yfov_deg: Option<f32>,
    },
}

/// One of the file's cameras.
#[derive(Clone, Debug)]
pub struct SceneCamera {
    /// Its index in the file's `cameras`.
    pub index: usize,
    pub name: Option<String>,
    /// The camera, or why it cannot be used (orthographic, a degenerate node, ...).
    pub camera: Result<Camera, String>,
}

#[derive(Clone, Debug)]
pub struct Camera {
    pub name: Option<String>,
    /// Camera-to-world transform (the camera looks along its -Z, +Y up).
    pub world: Mat4,
    /// Vertical field of view in radians.
    pub yfov: f32,
    pub znear: f32,
    pub zfar: f32,
    /// True when no camera was in the file and the CONVENTIONS.md default was built.
    pub is_default: bool,
}

impl Camera {
    pub fn eye(&self) -> Vec3 {
        self.world.w_axis.truncate()
    }
    pub fn view(&self) -> Mat4 {
        self.world.inverse()
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }
    pub fn extend(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
    pub fn extent(&self) -> Vec3 {
        self.max - self.min
    }
    /// The eight corners (min/max per axis by the bits of the index).
    pub fn corners(&self) -> [Vec3; 8] {
        std::array::from_fn(|i| {
            Vec3::new(
                if i & 1 == 0 { self.min.x } else { self.max.x },
                if i & 2 == 0 { self.min.y } else { self.max.y },
                if i & 4 == 0 { self.min.z } else { self.max.z },
            )
        })
    }
    /// World bounds of this box under a transform.
    pub fn transformed(&self, m: &Mat4) -> Aabb {
        let mut out = Aabb::EMPTY;
        if self.is_empty() {
            return out;
        }
        for p in self.corners() {
            out.extend(m.transform_point3(p));
        }
        out
    }
}

/// A loaded scene. `warnings` lists what was tolerated (and how) while loading.
#[derive(Clone, Debug)]
pub struct Scene {
    pub source: PathBuf,
    pub vertices: Vec<Vertex>,
    pub indices: Vec<u32>,
    pub primitives: Vec<Primitive>,
    pub instances: Vec<Instance>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub lights: Vec<Light>,
    /// The view: the file's first camera met, or the CONVENTIONS.md default.
    pub camera: Camera,
    /// Every camera of the file that a node uses, placed by the first such node, in the
    /// order met (`--camera` picks one).
    pub cameras: Vec<SceneCamera>,
    /// World bounds of all instances (EMPTY for an empty scene).
    pub bounds: Aabb,
    /// The file's coordinates of this scene's (0, 0, 0), the centre of the meshes' nodes in whole
    /// steps of 1024 m (zero for a scene near its file's origin): instances,
    /// lights, cameras and bounds are relative to it (precision far from the file's origin);
    /// add it for the file's coordinates.
    pub origin: glam::DVec3,
    /// The file's nodes (for animation; `Instance::node` indexes them).
    pub nodes: Vec<Node>,
    /// Node animations (translation, rotation, scale).
    pub animations: Vec<Animation>,
    /// Light from beyond the scene (none unless asked for: `--env`).
    pub environment: Option<Environment>,
    pub warnings: Vec<String>,
}

/// How far past everything else the grid reaches where a ground is left out, in its size:
/// chosen on the corpus's tune split (0.5 against 1.0: openings' 90th percentile 0.113 against
/// 0.130).
const GROUND_MARGIN: f32 = 0.5;
/// A flat instance this many times wider than everything else is a ground: the voxel grid
/// leaves out its far part. As wide as the grid then is, so that no ground is cut to less than
/// a narrower one keeps (4 kept a ground 3.8 times its room's width whole, its voxels twice as
/// coarse as a wider ground's).
const GROUND_SPAN: f32 = 1.0 + 2.0 * GROUND_MARGIN;

impl Scene {
    /// What the voxel grid covers: the bounds, or where a ground plane reaches far past
    /// everything else (a small building on a large ground), everything else widened by
    /// GROUND_MARGIN of its size on each side, and down to the ground. The grid spans its
    /// largest extent in 64 voxels by default: a ground 10 times the building's gave voxels as
    /// wide as a room's walls are apart. Beyond the grid the cones see the environment.
    pub fn voxel_bounds(&self) -> Aabb {
        if !self.animations.is_empty() {
            return self.bounds;
        }
        let boxes: Vec<Aabb> = self
            .instances
            .iter()
            .map(|i| self.instance_bounds(i))
            .collect();
        // The axes along which an instance is thinner than a thousandth of its width.
        let thin = |b: &Aabb| {
            b.extent()
                .cmple(Vec3::splat(1e-3 * b.extent().max_element()))
        };
        let flat = |b: &Aabb| thin(b).any();
        // The widest flat instance is the ground if it is far wider than all the rest
        // together (the rest counts every other instance: a room of single quads keeps its
        // walls and its floor), and something that is not flat stands on it (a lamp's quad
        // over a floor is no building).
        if boxes.iter().all(flat) {
            return self.bounds;
        }
        let Some(widest) = (0..boxes.len())
            .filter(|&i| flat(&boxes[i]))
            .max_by(|&a, &b| {
                let w = |i: usize| boxes[i].extent().max_element();
                w(a).total_cmp(&w(b))
            })
        else {
            return self.bounds;
        };
        let g = &boxes[widest];
        let rest = (boxes.iter().enumerate())
            .filter(|&(i, _)| i != widest)
            .fold(Aabb::EMPTY, |r, (_, b)| r.union(b));
        let span = rest.extent().max_element();
        if g.extent().max_element() <= GROUND_SPAN * span {
            return self.bounds;
        }
        let pad = Vec3::splat(span * GROUND_MARGIN);
        // Across its plane the ground stays in, however high above it the rest floats.
        let min = Vec3::select(thin(g), (rest.min - pad).min(g.min), rest.min - pad);
        let max = Vec3::select(thin(g), (rest.max + pad).max(g.max), rest.max + pad);
        Aabb {
            min: min.max(self.bounds.min),
            max: max.min(self.bounds.max),
        }
    }

    /// An instance's world bounds (its primitive's box, transformed).
    fn instance_bounds(&self, inst: &Instance) -> Aabb {
        let mut b = Aabb::EMPTY;
        if let Some(p) = self.primitives.get(inst.primitive as usize) {
            for c in p.bounds.corners() {
                b.extend(inst.world.transform_point3(c));
            }
        }
        b
    }
}

impl Scene {
    /// Views the scene as `view` says.
    pub fn set_view(&mut self, view: &ViewSpec) -> Result<(), String> {
        match view {
            ViewSpec::Camera(spec) => self.use_camera(spec),
            ViewSpec::LookAt {
                eye,
                target,
                up,
                yfov_deg,
            } => self.look_from(*eye, *target, *up, *yfov_deg),
        }
    }

    /// Views the scene through the file's camera named `spec`, or of index `spec` in the
    /// file's `cameras`; an error names the file and the cameras it has.
    pub fn use_camera(&mut self, spec: &str) -> Result<(), String> {
        let by_index = spec.trim().parse::<usize>().ok();
        let found = self.cameras.iter().find(|c| match by_index {
            Some(i) => c.index == i,
            None => c.name.as_deref() == Some(spec),
        });
        let Some(found) = found else {
            let have: Vec<String> = self
                .cameras
                .iter()
                .map(|c| match &c.name {
                    Some(n) => format!("{} ({n:?})", c.index),
                    None => c.index.to_string(),
                })
                .collect();
            return Err(format!(
                "{}: no camera {spec:?} (the cameras its nodes use: {})",
                self.source.display(),
                if have.is_empty() {
                    "none".to_string()
                } else {
                    have.join(", ")
                }
            ));
        };
        match &found.camera {
            Ok(c) => {
                self.camera = c.clone();
                Ok(())
            }
            Err(why) => Err(format!("{}: {why}", self.source.display())),
        }
    }

    /// Views the scene from `eye` towards `target` (the file's coordinates, in f64 as
    /// `Scene::origin` is) with `up` and a vertical field of view of `yfov_deg` degrees (the
    /// current camera's when None). The near plane is a thousandth of the distance to the
    /// target at most, the far plane holds the whole scene.
    pub fn look_from(
        &mut self,
        eye: glam::DVec3,
        target: glam::DVec3,
        up: Vec3,
        yfov_deg: Option<f32>,
    ) -> Result<(), String> {
        let (e, t) = (
            (eye - self.origin).as_vec3(),
            (target - self.origin).as_vec3(),
        );
        let dir = t - e;
        let yfov = yfov_deg.map_or(self.camera.yfov, f32::to_radians);
        if !(e.is_finite() && t.is_finite() && up.is_finite()) {
            return Err("--eye, --target and --up must be finite".into());
        }
        if dir.length() <= 0.0 || dir.normalize().cross(up).length() < 1e-4 {
            return Err(
                "--target must differ from --eye, and --up must not lie along the view".into(),
            );
        }
        if !(yfov > 0.0 && yfov < std::f32::consts::PI) {
            return Err("--fov must lie between 0 and 180 degrees".into());
        }
        let znear = self.camera.znear.min(1e-3 * dir.length()).max(1e-6);
        let mut zfar = self.camera.zfar.max(znear * 1000.0);
        if !self.bounds.is_empty() {
            for c in self.bounds.corners() {
                zfar = zfar.max(2.0 * e.distance(c));
            }
        }
        self.camera = Camera {
            name: None,
            world: glam::Mat4::look_at_rh(e, t, up).inverse(),
            yfov,
            znear,
            zfar,
            is_default: false,
        };
        Ok(())
    }

    pub fn triangle_count(&self) -> usize {
        self.instances
            .iter()
            .map(|i| self.primitives[i.primitive as usize].index_count as usize / 3)
            .sum()
    }

    /// Triangles stored once per primitive, however many instances draw them (the counts in
    /// `scenes/README.md` are of this kind).
    pub fn stored_triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// What the renderer relies on in a loaded scene: indices, primitives, instances, materials
    /// and textures that refer to what exists, finite numbers, unit normals and tangents, a
    /// usable camera. The first broken rule, if any.
    pub fn check(&self) -> Result<(), String> {
        let nv = self.vertices.len();
        if let Some(i) = self.indices.iter().find(|&&i| i as usize >= nv) {
            return Err(format!("index {i} of {nv} vertices"));
        }
        for v in &self.vertices {
            let all = v
                .position
                .iter()
                .chain(&v.normal)
                .chain(&v.uv)
                .chain(&v.tangent);
            if !all.clone().all(|x| x.is_finite()) {
                return Err(format!("a non-finite vertex {v:?}"));
            }
            let n = Vec3::from(v.normal);
            let t = Vec3::from_slice(&v.tangent[..3]);
            if (n.length() - 1.0).abs() >= 1e-3 || (t.length() - 1.0).abs() >= 1e-3 {
                return Err(format!("a normal or tangent not of unit length {v:?}"));
            }
            if t.dot(n).abs() >= 1e-3 || (v.tangent[3] != 1.0 && v.tangent[3] != -1.0) {
                return Err(format!("a tangent frame that is not one {v:?}"));
            }
        }
        for (k, p) in self.primitives.iter().enumerate() {
            let end = p.first_index as usize + p.index_count as usize;
            if p.index_count == 0 || p.index_count % 3 != 0 || end > self.indices.len() {
                return Err(format!("primitive {k}'s indices"));
            }
            if p.material as usize >= self.materials.len() || p.bounds.is_empty() {
                return Err(format!("primitive {k}'s material or bounds"));
            }
        }
        for (k, i) in self.instances.iter().enumerate() {
            if i.primitive as usize >= self.primitives.len() || !i.world.is_finite() {
                return Err(format!("instance {k}'s primitive or transform"));
            }
        }
        for (k, m) in self.materials.iter().enumerate() {
            let textures = [
                (m.base_color_tex, Some(true)),
                (m.emissive_tex, Some(true)),
                (m.specular_color_tex, Some(true)),
                (m.metallic_roughness_tex, Some(false)),
                (m.normal_tex, Some(false)),
                (m.specular_tex, Some(false)),
            ];
            for (t, srgb) in textures {
                let Some(t) = t else { continue };
                let Some(tex) = self.textures.get(t.texture as usize) else {
                    return Err(format!(
                        "material {k}: texture {} does not exist",
                        t.texture
                    ));
                };
                if tex.rgba8.len() as u64 != tex.width as u64 * tex.height as u64 * 4 {
                    return Err(format!("texture {}: its size and pixels", t.texture));
                }
                // Colour textures are sRGB, data textures linear.
                if Some(tex.srgb) != srgb {
                    return Err(format!("texture {}: its colour space", t.texture));
                }
            }
            if !m.base_color.is_finite() || !m.emissive.is_finite() {
                return Err(format!("material {k}: a non-finite colour"));
            }
        }
        for (k, l) in self.lights.iter().enumerate() {
            let unit = (l.direction.length() - 1.0).abs() < 1e-4;
            if !l.radiance.is_finite() || !l.position.is_finite() || !unit {
                return Err(format!("light {k}: a non-finite or non-unit part"));
            }
        }
        let c = &self.camera;
        if !(c.world.is_finite() && c.yfov > 0.0 && c.znear > 0.0 && c.zfar > c.znear) {
            return Err("the camera".into());
        }
        if !self.instances.is_empty() && self.bounds.is_empty() {
            return Err("empty bounds around instances".into());
        }
        Ok(())
    }
}

/// A scene file that cannot be used. The message names the file and the problem.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {problem}")]
pub struct SceneError {
    pub path: PathBuf,
    pub problem: String,
}
