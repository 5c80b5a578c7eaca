//! The ground-truth reference: a CPU path tracer over the same loaded [`Scene`] that follows
//! `../shared/CONVENTIONS.md` exactly, written apart from the real-time path (src/render and
//! glsl/) so that it can judge it.
//!
//! Unidirectional path tracing with next-event estimation: punctual lights are sampled
//! directly; emissive triangles are sampled by area in proportion to their power and combined
//! with BRDF sampling by multiple importance sampling (power heuristic). One light path of one
//! segment a sample (a light's ray to the first surface it meets) is joined to every vertex of
//! the camera's path and weighed against those ways (`light_paths`). Paths end by Russian
//! roulette. A path that leaves the scene takes the environment's radiance (black without
//! one); an environment image is also sampled directly, in proportion to its texels' power,
//! and combined with BRDF sampling by the power heuristic. Each pixel is the mean of samples jittered over its
//! footprint; every pixel has its own random stream derived from the seed and its index, so a
//! seed gives the same image bit for bit whatever the number of threads.

pub mod brdf;
pub mod bvh;
pub mod environment;
pub mod light_paths;
pub mod sampling;
pub mod texture;
pub mod world;

use crate::output::RadianceImage;
use crate::scene::Scene;
use environment::EnvLight;
use glam::Vec3;
use light_paths::LightStarts;
use rayon::prelude::*;
use sampling::{power_heuristic, power_heuristic_among, Frame, Pcg32};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;
use world::{punctual, World};

#[derive(Clone, Debug)]
pub struct ReferenceSettings {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    pub seed: u64,
    /// A hard cap on path length (bounces), far beyond where Russian roulette ends paths;
    /// it only guards against endless paths in closed scenes of albedo 1. 1 gives direct
    /// light only: emission and next-event estimation at the first hit, no bounce.
    pub max_depth: u32,
    /// Light bounces as voxel cone tracing counts them (`GiSettings::bounces`), or all of them
    /// (None). With B: a punctual light's light reflects off at most B surfaces before the one
    /// seen, and an emitter's off B - 1 (cones gather an emitter's direct light, so it counts
    /// as a bounce). What a tracer with B bounces could reach at best.
    pub bounces: Option<u32>,
    /// Bounces before Russian roulette starts.
    pub rr_depth: u32,
    /// A progress bar on stderr (only drawn where `console::bars_shown`).
    pub progress: bool,
    /// Next-event estimation of an environment image by its texels' power (off: the
    /// environment is found by BRDF sampling alone, to measure what this buys).
    pub env_sampling: bool,
    /// Light paths joined to the camera's (light_paths.rs; off: the camera's paths alone, to
    /// measure what they buy).
    pub light_paths: bool,
}

impl Default for ReferenceSettings {
    fn default() -> Self {
        ReferenceSettings {
            width: 512,
            height: 512,
            spp: 64,
            seed: 0,
            max_depth: 1024,
            bounces: None,
            rr_depth: 3,
            progress: false,
            env_sampling: true,
            light_paths: true,
        }
    }
}

/// A finished render: the image, and what tells how far it is from converged.
#[derive(Clone, Debug)]
pub struct ReferenceOutput {
    pub image: RadianceImage,
    /// Per pixel and channel: the estimated variance of the pixel's mean (sample variance / spp).
    pub variance: RadianceImage,
    /// Samples dropped because they came out NaN or infinite (should stay 0).
    pub bad_samples: u64,
    pub seconds: f64,
    /// Of `seconds`, what building the scene's BVH took (before any sample).
    pub setup_seconds: f64,
}

/// Renders the scene's camera view: linear radiance per pixel.
pub fn render(scene: &Scene, settings: &ReferenceSettings) -> RadianceImage {
    render_full(scene, settings).image
}

/// `render` with the per-pixel variance estimate and statistics.
pub fn render_full(scene: &Scene, settings: &ReferenceSettings) -> ReferenceOutput {
    let start = Instant::now();
    let (w, h) = (settings.width.max(1), settings.height.max(1));
    let spp = settings.spp.max(1);
    let world = World::new(scene);
    let env = scene
        .environment
        .as_ref()
        .map(|e| EnvLight::new(e, settings.env_sampling));
    let camera = CameraRays::new(scene, w, h);
    let starts = Some(LightStarts::new(&world)).filter(|s| settings.light_paths && s.any());
    let setup_seconds = start.elapsed().as_secs_f64();
    let bad = AtomicU64::new(0);
    let progress = if settings.progress {
        crate::console::bar(h as u64, &format!("path tracing {w}x{h}, {spp} spp, rows"))
    } else {
        indicatif::ProgressBar::hidden()
    };
    let mut rows: Vec<Vec<([f32; 3], [f32; 3])>> = vec![Vec::new(); h as usize];
    rows.par_iter_mut().enumerate().for_each(|(y, row)| {
        *row = (0..w)
            .map(|x| {
                let pixel = y as u64 * w as u64 + x as u64;
                let mut rng = Pcg32::for_pixel(settings.seed, pixel);
                let (mut sum, mut sum2) = ([0f64; 3], [0f64; 3]);
                for _ in 0..spp {
                    let j = rng.next_2d();
                    let d = camera.direction(x as f32 + j.x, y as f32 + j.y);
                    let l = trace(
                        &world,
                        env.as_ref(),
                        starts.as_ref(),
                        camera.eye,
                        d,
                        &mut rng,
                        settings,
                    );
                    if !l.is_finite() {
                        bad.fetch_add(1, Ordering::Relaxed);
                        continue;
                    }
                    for c in 0..3 {
                        sum[c] += l[c] as f64;
                        sum2[c] += (l[c] as f64) * (l[c] as f64);
                    }
                }
                let n = spp as f64;
                let mean = sum.map(|s| s / n);
                let var = std::array::from_fn(|c| {
                    if spp > 1 {
                        ((sum2[c] / n - mean[c] * mean[c]).max(0.0) / (n - 1.0)) as f32
                    } else {
                        0.0
                    }
                });
                (mean.map(|m| m as f32), var)
            })
            .collect();
        progress.inc(1);
    });
    progress.finish_and_clear();
    let (pixels, variance) = rows.into_iter().flatten().unzip();
    ReferenceOutput {
        image: RadianceImage {
            width: w,
            height: h,
            pixels,
        },
        variance: RadianceImage {
            width: w,
            height: h,
            pixels: variance,
        },
        bad_samples: bad.into_inner(),
        seconds: start.elapsed().as_secs_f64(),
        setup_seconds,
    }
}

/// Primary rays of the scene camera (perspective, yfov, aspect = width / height).
struct CameraRays {
    eye: Vec3,
    right: Vec3,
    up: Vec3,
    forward: Vec3,
    tan_half: f32,
    aspect: f32,
    w: f32,
    h: f32,
}

impl CameraRays {
    fn new(scene: &Scene, w: u32, h: u32) -> Self {
        let c = &scene.camera;
        let m = c.world;
        CameraRays {
            eye: c.eye(),
            right: m.transform_vector3(Vec3::X).normalize_or(Vec3::X),
            up: m.transform_vector3(Vec3::Y).normalize_or(Vec3::Y),
            forward: m.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Z),
            tan_half: (c.yfov * 0.5).tan(),
            aspect: w as f32 / h as f32,
            w: w as f32,
            h: h as f32,
        }
    }

    /// The unit direction through image position (x, y) in pixels (0, 0 = top left corner).
    fn direction(&self, x: f32, y: f32) -> Vec3 {
        let sx = (x / self.w * 2.0 - 1.0) * self.tan_half * self.aspect;
        let sy = (1.0 - y / self.h * 2.0) * self.tan_half;
        (self.forward + self.right * sx + self.up * sy).normalize()
    }
}

/// Moves a ray origin off the surface along the geometric normal by a few float ulps of its
/// coordinates (the integer-offset idea of Waechter and Binder, Ray Tracing Gems ch. 6), so
/// the offset scales with the position's magnitude instead of a scene-size epsilon.
fn offset_origin(p: Vec3, n: Vec3) -> Vec3 {
    const NEAR_ORIGIN: f32 = 1.0 / 32.0;
    const FLOAT_SCALE: f32 = 1.0 / 65536.0;
    const INT_SCALE: f32 = 256.0;
    let f = |p: f32, n: f32| -> f32 {
        if p.abs() < NEAR_ORIGIN {
            return p + FLOAT_SCALE * n;
        }
        let ulps = (INT_SCALE * n) as i32;
        // Moving the bit pattern away from zero grows |p|; towards zero shrinks it.
        let ulps = if p < 0.0 { -ulps } else { ulps };
        f32::from_bits((p.to_bits() as i32).wrapping_add(ulps) as u32)
    };
    Vec3::new(f(p.x, n.x), f(p.y, n.y), f(p.z, n.z))
}

/// One path from the camera: the radiance it carries back.
#[allow(clippy::too_many_arguments)]
fn trace(
    world: &World,
    env: Option<&EnvLight>,
    starts: Option<&LightStarts>,
    eye: Vec3,
    dir: Vec3,
    rng: &mut Pcg32,
    s: &ReferenceSettings,
) -> Vec3 {
    let mut l = Vec3::ZERO;
    let mut beta = Vec3::ONE;
    let (mut o, mut d) = (eye, dir);
    // Density (solid angle) of the BRDF sample that made the current ray; 0 for camera rays,
    // whose emission hits are not also reachable by light sampling.
    let mut bsdf_pdf = 0.0f32;
    // Punctual lights are sampled at every hit up to depth B, emitters up to B - 1; emission
    // met by BSDF sampling at depth B pairs (MIS) with the emitter sampled at B - 1.
    let max_depth = s
        .bounces
        .map_or(s.max_depth, |b| (b + 1).min(s.max_depth))
        .max(1);
    let emitter_depths = s.bounces.unwrap_or(u32::MAX);
    let light_vertex = starts.and_then(|st| st.sample(world, rng).map(|v| (st, v)));
    // The light path's density of landing on a vertex is weighed against the camera path's
    // of reaching it (per unit area there), which needs the vertex before: for the last
    // vertex, that density and its normal, where a light path could have been joined there.
    let mut last: Option<(f32, Vec3)> = None;
    for depth in 0..max_depth {
        let Some(hit) = world.intersect(o, d, f32::INFINITY) else {
            // Left the scene: the environment, weighted against its direct sampling at the
            // vertex before (which pairs with this escape as an emitter's sample does).
            if let Some(env) = env {
                let weight = if bsdf_pdf > 0.0 && env.is_sampled() {
                    power_heuristic(bsdf_pdf, env.pdf(d))
                } else {
                    1.0
                };
                l += beta * env.radiance(d) * weight;
            }
            break;
        };
        let wo = -d;
        let surf = world.surface(&hit, wo);
        // Per unit area here, the density of the last vertex's BRDF sample landing here.
        let reach = (bsdf_pdf > 0.0).then(|| bsdf_pdf * surf.ng.dot(wo).abs() / (hit.t * hit.t));
        let le = world.emission(surf.tri, surf.uv, surf.front);
        if le != Vec3::ZERO {
            let weight = emission_weight(world, starts, &surf, wo, hit.t, bsdf_pdf, last);
            l += beta * le * weight;
        }
        let brdf = world.brdf(&surf);
        let frame = Frame::new(surf.ns);
        let v = Shading {
            wo_local: frame.to_local(wo),
            origin: offset_origin(surf.p, surf.ng),
            surf,
            brdf,
            frame,
            reach,
        };
        l += beta * punctual_lights(world, starts, &v);
        if world.has_emitters() && depth < emitter_depths {
            l += beta * emitter_light(world, starts, &v, rng);
        }
        if let Some(env) = env.filter(|e| e.is_sampled() && depth < emitter_depths) {
            l += beta * env_light(world, env, &v, rng);
        }
        // The light path joined here, where the vertex after this one would look for its light.
        if let Some((st, lv)) = &light_vertex {
            if depth + 1 < max_depth {
                l += light_paths::join(world, st, lv, &v, beta, depth + 1 < emitter_depths);
            }
        }
        let Shading {
            surf,
            brdf,
            frame,
            wo_local,
            origin,
            ..
        } = v;
        // A light path could have been joined at the vertex before this one (it had one).
        last = reach
            .filter(|_| depth < emitter_depths)
            .map(|r| (r, surf.ng));

        let u_lobe = rng.next_f32();
        let u = rng.next_2d();
        let Some((wi_local, f, pdf)) = brdf.sample(wo_local, u_lobe, u) else {
            break;
        };
        let wi = frame.to_world(wi_local);
        // Directions under the geometric surface would leak through it.
        if surf.ng.dot(wi) <= 0.0 {
            break;
        }
        beta *= f * wi_local.z / pdf;
        bsdf_pdf = pdf;
        if depth + 1 >= s.rr_depth {
            let q = beta.max_element().min(0.95);
            if q.is_nan() || q <= 0.0 || rng.next_f32() >= q {
                break;
            }
            beta /= q;
        }
        o = origin;
        d = wi;
    }
    l
}

/// A vertex of the camera's path, as its light is estimated there.
pub(crate) struct Shading {
    surf: world::Surface,
    brdf: brdf::Brdf,
    frame: Frame,
    wo_local: Vec3,
    /// Where rays leave from (off the surface on its `ng` side).
    origin: Vec3,
    /// Per unit area here, the density of the last vertex's BRDF sample landing here (None for
    /// the vertex the camera sees).
    reach: Option<f32>,
}

/// The weight of an emitter that the camera path met at `surf` (seen along `-wo`), `t` from
/// the last vertex, whose BRDF sample of density `bsdf_pdf` (0: the camera's ray) found it:
/// against next-event estimation there and, where `last` says a light path could have been
/// joined there, that light path.
fn emission_weight(
    world: &World,
    starts: Option<&LightStarts>,
    surf: &world::Surface,
    wo: Vec3,
    t: f32,
    bsdf_pdf: f32,
    last: Option<(f32, Vec3)>,
) -> f32 {
    if bsdf_pdf <= 0.0 {
        return 1.0;
    }
    let cos_light = surf.ng.dot(wo).abs();
    let pe = world.emitter_pdf_area(surf.tri);
    match (last, starts) {
        (Some((reach_last, ng_last)), Some(st)) => {
            // Per unit area of the last vertex and of this one: its BRDF finding the emitter,
            // next-event estimation there, a light path landing there.
            let n_front = world.front_normal(surf.tri);
            let p_brdf = reach_last * bsdf_pdf * cos_light / (t * t);
            let p_light =
                st.emitter_pdf(world, surf.tri, pe, n_front, wo) * ng_last.dot(wo).abs() / (t * t);
            power_heuristic_among(p_brdf, &[reach_last * pe, p_light])
        }
        _ => power_heuristic(bsdf_pdf, pe * t * t / cos_light),
    }
}

/// The punctual lights' light leaving `v` towards the camera path, each weighed against a
/// light path from it landing there (their densities per unit area there; both end at the
/// light's one point).
fn punctual_lights(world: &World, starts: Option<&LightStarts>, v: &Shading) -> Vec3 {
    let mut l = Vec3::ZERO;
    for (index, light) in world.lights.iter().enumerate() {
        let Some((wi, dist, irradiance)) = punctual(light, v.surf.p) else {
            continue;
        };
        if v.surf.ng.dot(wi) <= 0.0 {
            continue;
        }
        let wi_local = v.frame.to_local(wi);
        let f = v.brdf.eval(v.wo_local, wi_local);
        if f == Vec3::ZERO {
            continue;
        }
        let tmax = if dist.is_finite() {
            (light.position - v.origin).length() * (1.0 - 1e-5)
        } else {
            f32::INFINITY
        };
        if world.occluded(v.origin, wi, tmax) {
            continue;
        }
        let weight = match (v.reach, starts) {
            (Some(reach), Some(st)) => {
                let p_light =
                    st.punctual_pdf(world, index, -wi) * v.surf.ng.dot(wi) / (dist * dist);
                power_heuristic_among(reach, &[p_light])
            }
            _ => 1.0,
        };
        l += f * wi_local.z * irradiance * weight;
    }
    l
}

/// Next-event estimation of one point on the emitters from `v`, weighed against `v`'s BRDF
/// finding it and, past the camera's first vertex, a light path from it landing at `v`.
fn emitter_light(
    world: &World,
    starts: Option<&LightStarts>,
    v: &Shading,
    rng: &mut Pcg32,
) -> Vec3 {
    let u_pick = rng.next_f32();
    let u = rng.next_2d();
    let Some(e) = world.sample_emitter(u_pick, u) else {
        return Vec3::ZERO;
    };
    let to = e.p - v.surf.p;
    let d2 = to.length_squared();
    let wi = to / d2.sqrt();
    let cos_light = e.n_front.dot(-wi);
    let le = world.emission(e.tri, e.uv, cos_light > 0.0);
    if le == Vec3::ZERO || v.surf.ng.dot(wi) <= 0.0 || d2 <= 0.0 {
        return Vec3::ZERO;
    }
    let wi_local = v.frame.to_local(wi);
    let f = v.brdf.eval(v.wo_local, wi_local);
    let light_pdf = e.pdf_area * d2 / cos_light.abs();
    if f == Vec3::ZERO || !(light_pdf > 0.0 && light_pdf.is_finite()) {
        return Vec3::ZERO;
    }
    let side = if cos_light > 0.0 {
        e.n_front
    } else {
        -e.n_front
    };
    let target = offset_origin(e.p, side);
    if world.occluded(v.origin, target - v.origin, 1.0 - 1e-4) {
        return Vec3::ZERO;
    }
    let p_brdf = v.brdf.pdf(v.wo_local, wi_local);
    let weight = match (v.reach, starts) {
        (Some(reach), Some(st)) => {
            // Per unit area here and on the emitter, as where the camera path meets an
            // emitter.
            let g = cos_light.abs() / d2;
            let p_light =
                st.emitter_pdf(world, e.tri, e.pdf_area, e.n_front, -wi) * v.surf.ng.dot(wi) / d2;
            power_heuristic_among(reach * e.pdf_area, &[reach * p_brdf * g, p_light])
        }
        _ => power_heuristic(light_pdf, p_brdf),
    };
    f * wi_local.z * le * weight / light_pdf
}

/// Next-event estimation of the environment image from `v`, weighed against `v`'s BRDF
/// leaving the scene the same way.
fn env_light(world: &World, env: &EnvLight, v: &Shading, rng: &mut Pcg32) -> Vec3 {
    let u_pick = rng.next_f32();
    let u = rng.next_2d();
    let Some((wi, light_pdf)) = env.sample(u_pick, u) else {
        return Vec3::ZERO;
    };
    if v.surf.ng.dot(wi) <= 0.0 || light_pdf <= 0.0 {
        return Vec3::ZERO;
    }
    let wi_local = v.frame.to_local(wi);
    let f = v.brdf.eval(v.wo_local, wi_local);
    if f == Vec3::ZERO || world.occluded(v.origin, wi, f32::INFINITY) {
        return Vec3::ZERO;
    }
    let weight = power_heuristic(light_pdf, v.brdf.pdf(v.wo_local, wi_local));
    f * wi_local.z * env.radiance(wi) * weight / light_pdf
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_moves_off_the_plane_on_the_normal_side() {
        for p in [Vec3::ZERO, Vec3::new(100.0, -3.0, 0.01), Vec3::splat(-7.5)] {
            for n in [Vec3::Y, Vec3::NEG_Y, Vec3::new(0.6, 0.0, -0.8)] {
                let q = offset_origin(p, n);
                assert!((q - p).dot(n) > 0.0, "{p} {n} {q}");
                assert!((q - p).length() < 4e-5 * (1.0 + p.abs().max_element()));
            }
        }
    }
}
