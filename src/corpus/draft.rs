//! A scene as a class draws it, before it is written: its parts, lights, camera and sky in
//! metres about the origin, then scaled and moved as a whole into a glTF document.

use crate::scene::builder::{
    CameraDesc, LightDesc, LightType, MaterialDesc, NodeDesc, PrimitiveDesc, SceneBuilder,
};
use glam::{DVec3, Mat4, Vec3};

/// A light placed in the draft: shining along `direction` (directional and spot lights).
struct PlacedLight {
    desc: LightDesc,
    position: Vec3,
    direction: Vec3,
}

/// What a class draws.
pub struct Draft {
    materials: Vec<MaterialDesc>,
    parts: Vec<(String, Vec<PrimitiveDesc>)>,
    lights: Vec<PlacedLight>,
    camera: Option<(Vec3, Vec3, f32)>,
    /// A uniform sky's radiance (`--env R,G,B`), if the scene has one.
    pub sky: Option<[f32; 3]>,
    /// The drawn parameters, in words.
    pub notes: Vec<String>,
}

impl Draft {
    pub fn new() -> Draft {
        Draft {
            materials: Vec::new(),
            parts: Vec::new(),
            lights: Vec::new(),
            camera: None,
            sky: None,
            notes: Vec::new(),
        }
    }

    pub fn note(&mut self, s: impl Into<String>) {
        self.notes.push(s.into());
    }

    pub fn material(&mut self, m: MaterialDesc) -> usize {
        self.materials.push(m);
        self.materials.len() - 1
    }

    /// A Lambertian material of this albedo.
    pub fn matte(&mut self, name: &str, albedo: [f32; 3]) -> usize {
        self.material(MaterialDesc::lambertian(name, albedo))
    }

    /// An emitter of radiance `radiance` (any scale; the colour is kept in emissiveFactor at
    /// most 1, the rest in the strength), white 0.8 where it reflects.
    pub fn emitter(&mut self, name: &str, radiance: [f32; 3]) -> usize {
        let peak = radiance.iter().fold(0f32, |m, &c| m.max(c)).max(1e-6);
        self.material(
            MaterialDesc::lambertian(name, [0.8; 3]).emissive(radiance.map(|c| c / peak), peak),
        )
    }

    pub fn parts(&mut self, name: &str, parts: Vec<PrimitiveDesc>) {
        if !parts.is_empty() {
            self.parts.push((name.to_string(), parts));
        }
    }

    /// A point light of `intensity` W/sr (white times `colour`).
    pub fn point(&mut self, name: &str, position: Vec3, colour: [f32; 3], intensity: f32) {
        self.lights.push(PlacedLight {
            desc: LightDesc::new(name, LightType::Point, colour, intensity),
            position,
            direction: Vec3::NEG_Y,
        });
    }

    /// A spot light at `position` aimed at `target` (cone half-angles in radians).
    #[allow(clippy::too_many_arguments)]
    pub fn spot(
        &mut self,
        name: &str,
        position: Vec3,
        target: Vec3,
        colour: [f32; 3],
        intensity: f32,
        inner: f32,
        outer: f32,
    ) {
        self.lights.push(PlacedLight {
            desc: LightDesc::new(
                name,
                LightType::Spot {
                    inner_cone_angle: inner,
                    outer_cone_angle: outer,
                },
                colour,
                intensity,
            ),
            position,
            direction: (target - position).normalize(),
        });
    }

    /// A sun of irradiance `irradiance` W/m^2 from elevation and azimuth (radians; azimuth 0
    /// is +Z, pi/2 is +X, as `--sun`).
    pub fn sun(&mut self, elevation: f32, azimuth: f32, colour: [f32; 3], irradiance: f32) {
        let towards = Vec3::new(
            elevation.cos() * azimuth.sin(),
            elevation.sin(),
            elevation.cos() * azimuth.cos(),
        );
        self.lights.push(PlacedLight {
            desc: LightDesc::new("sun", LightType::Directional, colour, irradiance),
            position: Vec3::ZERO,
            direction: -towards,
        });
    }

    pub fn camera(&mut self, eye: Vec3, target: Vec3, yfov_deg: f32) {
        self.camera = Some((eye, target, yfov_deg));
    }

    /// The glTF document: every length times `scale` (point and spot intensities times
    /// `scale`^2, so that what they light is as bright), then moved by `offset` through a root
    /// node (in f64, as a far scene's file holds it).
    pub fn finish(self, scale: f32, offset: DVec3) -> SceneBuilder {
        let mut b = SceneBuilder::new();
        for m in self.materials {
            b.add_material(m);
        }
        let s = Mat4::from_scale(Vec3::splat(scale));
        for (name, parts) in self.parts {
            let parts = parts
                .into_iter()
                .map(|p| super::shapes::transformed(p, s))
                .collect();
            super::shapes::add_parts(&mut b, &name, parts);
        }
        for l in self.lights {
            let mut desc = l.desc;
            if desc.kind != LightType::Directional {
                desc.intensity *= scale * scale;
            }
            let light = b.add_light(desc.clone());
            b.add_node(
                NodeDesc::new(desc.name.as_deref().unwrap_or("light"))
                    .light(light)
                    .translation((l.position * scale).to_array())
                    .rotation(facing(l.direction).to_array()),
            );
        }
        if let Some((eye, target, fov)) = self.camera {
            let cam = b.add_camera(CameraDesc {
                name: Some("camera".into()),
                yfov: fov.to_radians(),
                znear: 0.005 * scale,
                zfar: None,
                aspect_ratio: None,
            });
            let world =
                Mat4::look_at_rh(eye * scale, target * scale, up_for(target - eye)).inverse();
            let (_, rotation, _) = world.to_scale_rotation_translation();
            b.add_node(
                NodeDesc::new("camera")
                    .camera(cam)
                    .translation((eye * scale).to_array())
                    .rotation(rotation.normalize().to_array()),
            );
        }
        if offset != DVec3::ZERO {
            b.wrap_roots(NodeDesc::new("far away").translation(offset.to_array()));
        }
        b
    }
}

/// +Y, or -Z for a view straight up or down.
fn up_for(dir: Vec3) -> Vec3 {
    if dir.normalize().cross(Vec3::Y).length() < 1e-3 {
        Vec3::NEG_Z
    } else {
        Vec3::Y
    }
}

/// The rotation that turns -Z to `dir`.
fn facing(dir: Vec3) -> glam::Quat {
    let world = Mat4::look_at_rh(Vec3::ZERO, dir, up_for(dir)).inverse();
    world.to_scale_rotation_translation().1.normalize()
}
