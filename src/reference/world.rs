//! The scene flattened for path tracing: every instance's triangles in world space under one
//! BVH, per-vertex shading attributes, material lookups, the emissive triangles as a light
//! distribution, and the punctual lights.

use super::brdf::Brdf;
use super::bvh::{Bvh, Hit, TriGeom};
use super::sampling::Distribution;
use super::texture;
use crate::scene::{AlphaMode, Light, LightKind, Material, Scene, TexRef};
use glam::{Mat3, Vec2, Vec3, Vec4};

/// Per-vertex shading attributes in world space.
#[derive(Clone, Copy, Debug)]
struct ShadeVertex {
    n: Vec3,
    uv: Vec2,
    /// xyz tangent, w handedness (already multiplied by the sign of the instance determinant).
    t: Vec4,
}

#[derive(Clone, Copy, Debug)]
struct TriInfo {
    v: [u32; 3],
    material: u32,
    /// +1 when the world-space winding (cross(e1, e2)) points to the front, -1 for instances
    /// whose negative determinant mirrored the mesh.
    front: f32,
}

/// A point on a surface as the integrator sees it.
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    pub p: Vec3,
    /// Geometric normal, turned to the side the ray came from.
    pub ng: Vec3,
    /// Shading normal (interpolated, normal-mapped), on the same side as `ng`.
    pub ns: Vec3,
    /// Whether the ray arrived at the front face (the one the winding faces).
    pub front: bool,
    pub uv: Vec2,
    pub material: u32,
    pub tri: u32,
}

/// A point drawn on an emissive triangle, with its density per unit area.
#[derive(Clone, Copy, Debug)]
pub struct EmitterSample {
    pub p: Vec3,
    /// Front normal of the triangle (unit).
    pub n_front: Vec3,
    pub tri: u32,
    pub uv: Vec2,
    pub pdf_area: f32,
}

pub struct World<'s> {
    pub scene: &'s Scene,
    tris: Vec<TriGeom>,
    info: Vec<TriInfo>,
    verts: Vec<ShadeVertex>,
    bvh: Bvh,
    /// Emissive triangles (indices into `tris`), chosen in proportion to emitted power.
    emitter_tris: Vec<u32>,
    emitters: Option<Distribution>,
    /// Per triangle: probability density per unit area of light sampling landing on it.
    emitter_pdf_area: Vec<f32>,
    /// What the emissive triangles send out together (W; the textures at their average).
    emitter_power: f32,
    pub lights: Vec<Light>,
    /// Per material: it has an alpha cutoff that can reject hits.
    masked: Vec<bool>,
}

fn finite3(v: Vec3) -> bool {
    v.is_finite()
}

impl<'s> World<'s> {
    pub fn new(scene: &'s Scene) -> World<'s> {
        let mut tris = Vec::new();
        let mut info = Vec::new();
        let mut verts = Vec::new();
        for inst in &scene.instances {
            let Some(prim) = scene.primitives.get(inst.primitive as usize) else {
                continue;
            };
            let first = prim.first_index as usize;
            let Some(idx) = scene.indices.get(first..first + prim.index_count as usize) else {
                continue;
            };
            let (Some(&lo), Some(&hi)) = (idx.iter().min(), idx.iter().max()) else {
                continue;
            };
            if hi as usize >= scene.vertices.len() || !inst.world.is_finite() {
                continue;
            }
            let m3 = Mat3::from_mat4(inst.world);
            let det = m3.determinant();
            // Normals go by the inverse transpose; a singular transform flattens the mesh to
            // zero area, so any normal will do there.
            let normal_m = if det != 0.0 {
                m3.inverse().transpose()
            } else {
                Mat3::IDENTITY
            };
            let sign = if det < 0.0 { -1.0 } else { 1.0 };
            let base = verts.len() as u32;
            for v in &scene.vertices[lo as usize..=hi as usize] {
                let n = (normal_m * Vec3::from(v.normal)).normalize_or(Vec3::Z);
                let t = (m3 * Vec3::from_slice(&v.tangent[..3])).normalize_or(Vec3::X);
                verts.push(ShadeVertex {
                    n,
                    uv: Vec2::from(v.uv),
                    t: t.extend(if v.tangent[3] < 0.0 { -sign } else { sign }),
                });
            }
            for t in idx.chunks_exact(3) {
                let p = |i: u32| {
                    inst.world
                        .transform_point3(Vec3::from(scene.vertices[i as usize].position))
                };
                let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
                let g = TriGeom::new(a, b, c);
                // Degenerate and non-finite triangles can never be hit: leave them out.
                if !(finite3(a) && finite3(b) && finite3(c) && g.area() > 0.0) {
                    continue;
                }
                tris.push(g);
                info.push(TriInfo {
                    v: [base + t[0] - lo, base + t[1] - lo, base + t[2] - lo],
                    material: prim.material,
                    front: sign,
                });
            }
        }
        let (bvh, order) = Bvh::build(&tris);
        let tris: Vec<TriGeom> = order.iter().map(|&i| tris[i as usize]).collect();
        let info: Vec<TriInfo> = order.iter().map(|&i| info[i as usize]).collect();

        let material = |m: u32| scene.materials.get(m as usize);
        let mut emitter_tris = Vec::new();
        let mut weights = Vec::new();
        for (i, (g, inf)) in tris.iter().zip(&info).enumerate() {
            let Some(m) = material(inf.material) else {
                continue;
            };
            let e = m.emissive.max(Vec3::ZERO);
            if m.is_emissive() && e.is_finite() {
                // Power up to the texture's average, which only shapes the choice, not the
                // estimate (the density used is the one sampled with).
                let sides = if m.double_sided { 2.0 } else { 1.0 };
                emitter_tris.push(i as u32);
                weights.push((g.area() * (e.x + e.y + e.z) * sides) as f64);
            }
        }
        let emitters = Distribution::new(&weights);
        // The weights are area x (r + g + b) x sides; a Lambertian emitter sends pi x Le x area.
        let emitter_power = (std::f64::consts::PI / 3.0 * weights.iter().sum::<f64>()) as f32;
        let mut emitter_pdf_area = vec![0.0f32; tris.len()];
        if let Some(d) = &emitters {
            for (k, &t) in emitter_tris.iter().enumerate() {
                emitter_pdf_area[t as usize] = d.pmf(k) / tris[t as usize].area();
            }
        }
        let lights = scene
            .lights
            .iter()
            .filter(|l| {
                l.radiance.is_finite()
                    && l.radiance.max_element() > 0.0
                    && l.position.is_finite()
                    && l.direction.is_finite()
                    && l.direction.length_squared() > 0.0
            })
            .map(|l| Light {
                direction: l.direction.normalize(),
                radiance: l.radiance.max(Vec3::ZERO),
                ..l.clone()
            })
            .collect();
        let masked = scene
            .materials
            .iter()
            .map(|m| matches!(m.alpha_mode, AlphaMode::Mask(_)))
            .collect();
        World {
            scene,
            tris,
            info,
            verts,
            bvh,
            emitter_tris,
            emitters,
            emitter_pdf_area,
            emitter_power,
            lights,
            masked,
        }
    }

    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    pub fn emitter_count(&self) -> usize {
        self.emitter_tris.len()
    }

    fn material(&self, tri: u32) -> Option<&'s Material> {
        self.scene
            .materials
            .get(self.info[tri as usize].material as usize)
    }

    fn uv(&self, tri: u32, b1: f32, b2: f32) -> Vec2 {
        let v = self.info[tri as usize].v;
        let b0 = 1.0 - b1 - b2;
        self.verts[v[0] as usize].uv * b0
            + self.verts[v[1] as usize].uv * b1
            + self.verts[v[2] as usize].uv * b2
    }

    fn tex(&self, r: Option<TexRef>, uv: Vec2) -> Vec4 {
        match r.and_then(|r| self.scene.textures.get(r.texture as usize)) {
            Some(t) => texture::sample(t, uv),
            None => Vec4::ONE,
        }
    }

    /// False where an alpha-masked material cuts the surface away (no hit, no shadow).
    fn solid(&self, tri: u32, b1: f32, b2: f32) -> bool {
        let inf = &self.info[tri as usize];
        if !self
            .masked
            .get(inf.material as usize)
            .copied()
            .unwrap_or(false)
        {
            return true;
        }
        let Some(m) = self.material(tri) else {
            return true;
        };
        let AlphaMode::Mask(cutoff) = m.alpha_mode else {
            return true;
        };
        let uv = self.uv(tri, b1, b2);
        m.base_color.w * self.tex(m.base_color_tex, uv).w >= cutoff
    }

    /// The closest solid surface along the ray, within (0, tmax).
    pub fn intersect(&self, o: Vec3, d: Vec3, tmax: f32) -> Option<Hit> {
        self.bvh
            .closest(&self.tris, o, d, tmax, |t, b1, b2| self.solid(t, b1, b2))
    }

    /// Whether a solid surface blocks the segment o + t d, t in (0, tmax).
    pub fn occluded(&self, o: Vec3, d: Vec3, tmax: f32) -> bool {
        self.bvh
            .any(&self.tris, o, d, tmax, |t, b1, b2| self.solid(t, b1, b2))
    }

    /// Where on its triangle a hit lies.
    pub fn hit_point(&self, hit: &Hit) -> Vec3 {
        let g = &self.tris[hit.tri as usize];
        g.p0 + g.e1 * hit.b1 + g.e2 * hit.b2
    }

    /// Unit normal of the triangle's front face.
    pub fn front_normal(&self, tri: u32) -> Vec3 {
        let g = &self.tris[tri as usize];
        g.e1.cross(g.e2).normalize() * self.info[tri as usize].front
    }

    /// The surface at a hit, seen from direction `wo` (pointing away from the surface).
    pub fn surface(&self, hit: &Hit, wo: Vec3) -> Surface {
        let (tri, b1, b2) = (hit.tri, hit.b1, hit.b2);
        let g = &self.tris[tri as usize];
        let inf = &self.info[tri as usize];
        let p = g.p0 + g.e1 * b1 + g.e2 * b2;
        let nf = self.front_normal(tri);
        let b0 = 1.0 - b1 - b2;
        let [v0, v1, v2] = inf.v.map(|i| &self.verts[i as usize]);
        let uv = v0.uv * b0 + v1.uv * b1 + v2.uv * b2;
        let mut ns = (v0.n * b0 + v1.n * b1 + v2.n * b2).normalize_or(nf);
        let m = self.material(tri);
        if let Some(m) = m.filter(|m| m.normal_tex.is_some()) {
            let t = (v0.t.truncate() * b0 + v1.t.truncate() * b1 + v2.t.truncate() * b2)
                .reject_from_normalized(ns)
                .normalize_or_zero();
            if t != Vec3::ZERO {
                let b = ns.cross(t) * v0.t.w;
                let c = self.tex(m.normal_tex, uv).truncate() * 2.0 - Vec3::ONE;
                let c = Vec3::new(c.x * m.normal_scale, c.y * m.normal_scale, c.z);
                ns = (t * c.x + b * c.y + ns * c.z).normalize_or(ns);
            }
        }
        // Every surface reflects on both sides: turn both normals to the incoming side.
        let front = nf.dot(wo) >= 0.0;
        let ng = if front { nf } else { -nf };
        if ns.dot(ng) < 0.0 {
            ns = -ns;
        }
        // A shading normal facing away from the viewer makes the BRDF meaningless there.
        if ns.dot(wo) <= 1e-6 {
            ns = ng;
        }
        Surface {
            p,
            ng,
            ns,
            front,
            uv,
            material: inf.material,
            tri,
        }
    }

    /// The BRDF at a surface point, textures applied.
    pub fn brdf(&self, s: &Surface) -> Brdf {
        let Some(m) = self.scene.materials.get(s.material as usize) else {
            return Brdf::new(Vec3::ONE, 1.0, 1.0, 1.0, Vec3::ONE);
        };
        let base = m.base_color.truncate() * self.tex(m.base_color_tex, s.uv).truncate();
        let mr = self.tex(m.metallic_roughness_tex, s.uv);
        let specular = m.specular_factor * self.tex(m.specular_tex, s.uv).w;
        let specular_color = m.specular_color * self.tex(m.specular_color_tex, s.uv).truncate();
        Brdf::new(
            base,
            m.metallic * mr.z,
            m.roughness * mr.y,
            specular,
            specular_color,
        )
    }

    /// Radiance emitted from triangle `tri` at `uv` towards the side `front` says (front
    /// faces only unless the material is double-sided).
    pub fn emission(&self, tri: u32, uv: Vec2, front: bool) -> Vec3 {
        match self.material(tri) {
            Some(m) if m.is_emissive() && (front || m.double_sided) => {
                (m.emissive * self.tex(m.emissive_tex, uv).truncate()).max(Vec3::ZERO)
            }
            _ => Vec3::ZERO,
        }
    }

    /// Density per unit area with which `sample_emitter` lands on triangle `tri`.
    pub fn emitter_pdf_area(&self, tri: u32) -> f32 {
        self.emitter_pdf_area[tri as usize]
    }

    pub fn has_emitters(&self) -> bool {
        self.emitters.is_some()
    }

    /// The emissive triangles' power together (W), their textures taken at their average.
    pub fn emitter_power(&self) -> f32 {
        self.emitter_power
    }

    /// Whether triangle `tri` emits from its back as well as its front (a double-sided
    /// emissive material).
    pub fn emits_both_sides(&self, tri: u32) -> bool {
        self.material(tri)
            .is_some_and(|m| m.is_emissive() && m.double_sided)
    }

    /// A point on an emissive triangle: the triangle by power, then uniform over its area.
    /// None when the point falls on a masked-out texel.
    pub fn sample_emitter(&self, u_pick: f32, u: Vec2) -> Option<EmitterSample> {
        let d = self.emitters.as_ref()?;
        let tri = self.emitter_tris[d.sample(u_pick)];
        let (b1, b2) = super::sampling::uniform_triangle(u);
        if !self.solid(tri, b1, b2) {
            return None;
        }
        let g = &self.tris[tri as usize];
        Some(EmitterSample {
            p: g.p0 + g.e1 * b1 + g.e2 * b2,
            n_front: self.front_normal(tri),
            tri,
            uv: self.uv(tri, b1, b2),
            pdf_area: self.emitter_pdf_area(tri),
        })
    }
}

/// What a punctual light delivers at `p`: the unit direction towards it, the distance (infinite
/// for directional) and the irradiance on a surface facing it (W/m^2).
pub fn punctual(light: &Light, p: Vec3) -> Option<(Vec3, f32, Vec3)> {
    match light.kind {
        LightKind::Directional => Some((-light.direction, f32::INFINITY, light.radiance)),
        LightKind::Point | LightKind::Spot { .. } => {
            let to = light.position - p;
            let d2 = to.length_squared();
            if d2.is_nan() || d2 <= 0.0 {
                return None;
            }
            let d = d2.sqrt();
            let wi = to / d;
            let mut scale = 1.0 / d2;
            if let LightKind::Spot {
                inner_cone,
                outer_cone,
            } = light.kind
            {
                // glTF's smooth falloff between the cone angles.
                let s = 1.0 / (inner_cone.cos() - outer_cone.cos()).max(0.001);
                let offset = -outer_cone.cos() * s;
                let a = (light.direction.dot(-wi) * s + offset).clamp(0.0, 1.0);
                scale *= a * a;
            }
            if let Some(range) = light.range.filter(|r| *r > 0.0) {
                let r = d / range;
                let w = (1.0 - r * r * r * r).clamp(0.0, 1.0);
                scale *= w * w;
            }
            (scale > 0.0).then_some((wi, d, light.radiance * scale))
        }
    }
}
