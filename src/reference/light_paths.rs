//! Light paths of one segment: a ray from a light (a point or spot light's position, or a point
//! on an emissive triangle) to the first surface it meets, joined to each vertex of the
//! camera's path. A lamp a few centimetres from a wall lights a spot on it a few centimetres
//! across and thousands of times brighter than the room; camera paths find that spot only by
//! chance and then as fireflies (a 4096-sample reference of such a room kept a relMSE of 0.03
//! of noise), where a ray from the lamp lands on it nearly every time. The three ways of making
//! a path light -> surface -> surface (the camera's path finding the light by next-event
//! estimation or by its BRDF, or the light's path joined to the camera's) are weighed by the
//! power heuristic, each with its density per unit area of the path's two last vertices.

use super::bvh::Hit;
use super::sampling::{cosine_hemisphere, uniform_cone, Distribution, Frame, Pcg32};
use super::world::{punctual, World};
use super::{offset_origin, Shading};
use crate::scene::LightKind;
use glam::Vec3;
use std::f32::consts::PI;

/// Where light paths start, chosen in proportion to power: each point and spot light, and the
/// emissive triangles together (a point on them drawn as next-event estimation draws it).
/// Directional lights start none: they light no spot much brighter than its surroundings.
pub struct LightStarts {
    choice: Option<Distribution>,
    /// Per entry of `choice`: a light's index in `World::lights`, or None for the emitters.
    sources: Vec<Option<usize>>,
    /// Per light of `World::lights`: the probability that it is chosen.
    light_share: Vec<f32>,
    /// The probability that the emitters are chosen.
    emitter_share: f32,
}

/// A light path's one vertex: what the light's ray met first.
pub struct LightVertex {
    hit: Hit,
    from: From,
}

enum From {
    /// World light `index`.
    Punctual(usize),
    /// A point `p` of emissive triangle `tri`, sending radiance `le` from its side `n` (unit).
    Emitter {
        p: Vec3,
        n: Vec3,
        tri: u32,
        le: Vec3,
        pdf_area: f32,
    },
}

/// The cosine of the cone a light's light paths leave in, uniformly over its solid angle: a
/// spot's outer cone, a point light's whole sphere (-1); none for a directional light.
fn spot_cos_max(kind: &LightKind) -> Option<f32> {
    match *kind {
        LightKind::Spot { outer_cone, .. } => Some(outer_cone.cos()),
        LightKind::Point => Some(-1.0),
        LightKind::Directional => None,
    }
}

impl LightStarts {
    pub fn new(world: &World) -> Self {
        let mut sources = Vec::new();
        let mut weights = Vec::new();
        for (i, l) in world.lights.iter().enumerate() {
            if let Some(cos_max) = spot_cos_max(&l.kind) {
                sources.push(Some(i));
                let rgb = l.radiance.x + l.radiance.y + l.radiance.z;
                weights.push((2.0 * PI * (1.0 - cos_max) * rgb / 3.0) as f64);
            }
        }
        if world.has_emitters() {
            sources.push(None);
            weights.push(world.emitter_power() as f64);
        }
        let choice = Distribution::new(&weights);
        let mut light_share = vec![0.0; world.lights.len()];
        let mut emitter_share = 0.0;
        if let Some(d) = &choice {
            for (k, s) in sources.iter().enumerate() {
                match s {
                    Some(i) => light_share[*i] = d.pmf(k),
                    None => emitter_share = d.pmf(k),
                }
            }
        }
        LightStarts {
            choice,
            sources,
            light_share,
            emitter_share,
        }
    }

    /// Whether any light starts light paths.
    pub fn any(&self) -> bool {
        self.choice.is_some()
    }

    /// Density per unit solid angle with which light `index` sends a light path along `dir`
    /// (from the light), its choice included.
    pub fn punctual_pdf(&self, world: &World, index: usize, dir: Vec3) -> f32 {
        let share = self.light_share.get(index).copied().unwrap_or(0.0);
        let l = &world.lights[index];
        match spot_cos_max(&l.kind) {
            Some(cos_max) if share > 0.0 => {
                let inside = matches!(l.kind, LightKind::Point) || l.direction.dot(dir) >= cos_max;
                if inside {
                    share / (2.0 * PI * (1.0 - cos_max))
                } else {
                    0.0
                }
            }
            _ => 0.0,
        }
    }

    /// Density per unit area of emitter and per unit solid angle with which a light path
    /// leaves a point of triangle `tri` (density per area `pdf_area`) along `dir`; `n_front`
    /// is the triangle's front normal.
    pub fn emitter_pdf(
        &self,
        world: &World,
        tri: u32,
        pdf_area: f32,
        n_front: Vec3,
        dir: Vec3,
    ) -> f32 {
        let both = world.emits_both_sides(tri);
        let cos = n_front.dot(dir);
        if !both && cos <= 0.0 {
            return 0.0;
        }
        let side = if both { 0.5 } else { 1.0 };
        self.emitter_share * pdf_area * side * cos.abs() / PI
    }

    /// A light path: a light by power, a direction from it, and the first surface met.
    pub fn sample(&self, world: &World, rng: &mut Pcg32) -> Option<LightVertex> {
        let d = self.choice.as_ref()?;
        let u_pick = rng.next_f32();
        let u_point = rng.next_2d();
        let u_dir = rng.next_2d();
        let u_side = rng.next_f32();
        match self.sources[d.sample(u_pick)] {
            Some(i) => {
                let l = &world.lights[i];
                let cos_max = spot_cos_max(&l.kind)?;
                let axis = if matches!(l.kind, LightKind::Point) {
                    Vec3::Z
                } else {
                    l.direction
                };
                let dir = Frame::new(axis).to_world(uniform_cone(cos_max, u_dir));
                let hit = world.intersect(l.position, dir, f32::INFINITY)?;
                Some(LightVertex {
                    hit,
                    from: From::Punctual(i),
                })
            }
            None => {
                let u_emitter = rng.next_f32();
                let e = world.sample_emitter(u_emitter, u_point)?;
                let front = !world.emits_both_sides(e.tri) || u_side < 0.5;
                let n = if front { e.n_front } else { -e.n_front };
                let le = world.emission(e.tri, e.uv, front);
                if le == Vec3::ZERO {
                    return None;
                }
                let dir = Frame::new(n).to_world(cosine_hemisphere(u_dir));
                let hit = world.intersect(offset_origin(e.p, n), dir, f32::INFINITY)?;
                Some(LightVertex {
                    hit,
                    from: From::Emitter {
                        p: e.p,
                        n,
                        tri: e.tri,
                        le,
                        pdf_area: e.pdf_area,
                    },
                })
            }
        }
    }
}

/// What the light path `lv` brings to the camera's vertex `a` (its path's throughput `beta`)
/// through its one bounce, weighed
/// against the camera path's own ways of making the same path. `emitters_joined`: whether
/// next-event estimation of the emitters runs at the vertex after `a` (a light path from an
/// emitter is joined only where it would, so that the same paths are counted).
pub(super) fn join(
    world: &World,
    starts: &LightStarts,
    lv: &LightVertex,
    a: &Shading,
    beta: Vec3,
    emitters_joined: bool,
) -> Vec3 {
    if matches!(lv.from, From::Emitter { .. }) && !emitters_joined {
        return Vec3::ZERO;
    }
    let surf_b = {
        // Seen from a, as the camera path would meet it.
        let to_b = world.hit_point(&lv.hit) - a.surf.p;
        let d2 = to_b.length_squared();
        if !(d2 > 0.0 && d2.is_finite()) {
            return Vec3::ZERO;
        }
        world.surface(&lv.hit, -to_b / d2.sqrt())
    };
    let to_b = surf_b.p - a.surf.p;
    let d2_ab = to_b.length_squared();
    let w_ab = to_b / d2_ab.sqrt();
    if a.surf.ng.dot(w_ab) <= 0.0 {
        return Vec3::ZERO;
    }
    let wi_a = a.frame.to_local(w_ab);
    let f_a = a.brdf.eval(a.wo_local, wi_a);
    if f_a == Vec3::ZERO {
        return Vec3::ZERO;
    }
    // What b sends towards a, over the density of the light path's landing on b (per area),
    // and the camera path's densities of the same path.
    let brdf_b = world.brdf(&surf_b);
    let frame_b = Frame::new(surf_b.ns);
    let wo_b = frame_b.to_local(-w_ab);
    // Per unit area at b, the density of a's BRDF sample landing there.
    let g_b = surf_b.ng.dot(-w_ab).abs() / d2_ab;
    let p_a = a.brdf.pdf(a.wo_local, wi_a) * g_b;
    let (sent, p_light, others) = match &lv.from {
        From::Punctual(i) => {
            let light = &world.lights[*i];
            let Some((wi, dist, irradiance)) = punctual(light, surf_b.p) else {
                return Vec3::ZERO;
            };
            if surf_b.ng.dot(wi) <= 0.0 {
                return Vec3::ZERO;
            }
            let wi_b = frame_b.to_local(wi);
            let f_b = brdf_b.eval(wo_b, wi_b);
            let p_light = starts.punctual_pdf(world, *i, -wi) * surf_b.ng.dot(wi) / (dist * dist);
            (f_b * wi_b.z * irradiance, p_light, [p_a, 0.0])
        }
        From::Emitter {
            p,
            n,
            tri,
            le,
            pdf_area,
        } => {
            let to_y = *p - surf_b.p;
            let d2 = to_y.length_squared();
            let wi = to_y / d2.sqrt();
            let cos_y = n.dot(-wi);
            if surf_b.ng.dot(wi) <= 0.0 || cos_y <= 0.0 {
                return Vec3::ZERO;
            }
            let wi_b = frame_b.to_local(wi);
            let f_b = brdf_b.eval(wo_b, wi_b);
            let n_front = world.front_normal(*tri);
            let p_light =
                starts.emitter_pdf(world, *tri, *pdf_area, n_front, -wi) * surf_b.ng.dot(wi) / d2;
            // Per unit area of b and of the emitter: next-event estimation at b, and b's BRDF
            // finding the emitter.
            let p_nee = p_a * pdf_area;
            let p_brdf = p_a * brdf_b.pdf(wo_b, wi_b) * cos_y / d2;
            (f_b * wi_b.z * *le * cos_y / d2, p_light, [p_nee, p_brdf])
        }
    };
    if sent == Vec3::ZERO || p_light.is_nan() || p_light <= 0.0 {
        return Vec3::ZERO;
    }
    let target = offset_origin(surf_b.p, surf_b.ng);
    if world.occluded(a.origin, target - a.origin, 1.0 - 1e-4) {
        return Vec3::ZERO;
    }
    let weight = super::sampling::power_heuristic_among(p_light, &others);
    beta * f_a * wi_a.z * g_b * sent * weight / p_light
}
