//! The glTF 2.0 metallic-roughness BRDF (specification appendix B) with KHR_materials_specular,
//! written here independently of the real-time shaders so that it can judge them.
//!
//! All directions are in the local shading frame: z is the shading normal, `wo` points to the
//! viewer and `wi` to the light, both unit length.

use super::sampling::{cosine_hemisphere, ggx_visible_normal};
use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, PI};

/// Below this alpha the GGX lobe is a near-delta that f32 cannot evaluate reliably; a roughness
/// of 0 is rendered as alpha = 1e-3 (a mirror blurred by about 0.1 degree).
pub const MIN_ALPHA: f32 = 1e-3;

/// The BRDF's parameters at one surface point (textures already applied).
#[derive(Clone, Copy, Debug)]
pub struct Brdf {
    pub base_color: Vec3,
    pub metallic: f32,
    /// GGX alpha = roughness^2.
    pub alpha: f32,
    /// Dielectric Fresnel at normal incidence: min(0.04 x specularColor, 1) x specular.
    pub dielectric_f0: Vec3,
    /// Dielectric Fresnel at grazing incidence: specular.
    pub dielectric_f90: f32,
}

fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

impl Brdf {
    pub fn new(
        base_color: Vec3,
        metallic: f32,
        roughness: f32,
        specular: f32,
        specular_color: Vec3,
    ) -> Self {
        let roughness = roughness.clamp(0.0, 1.0);
        let specular = specular.max(0.0);
        Brdf {
            base_color: base_color.max(Vec3::ZERO),
            metallic: metallic.clamp(0.0, 1.0),
            alpha: (roughness * roughness).max(MIN_ALPHA),
            dielectric_f0: (0.04 * specular_color.max(Vec3::ZERO)).min(Vec3::ONE) * specular,
            dielectric_f90: specular,
        }
    }

    /// True when the BRDF is exactly Lambertian (no specular lobe at all).
    fn is_lambertian(&self) -> bool {
        self.metallic == 0.0 && self.dielectric_f90 == 0.0 && self.dielectric_f0 == Vec3::ZERO
    }

    fn dielectric_fresnel(&self, cos: f32) -> Vec3 {
        let w = schlick_weight(cos);
        self.dielectric_f0 + (Vec3::splat(self.dielectric_f90) - self.dielectric_f0) * w
    }

    fn metal_fresnel(&self, cos: f32) -> Vec3 {
        let w = schlick_weight(cos);
        self.base_color + (Vec3::ONE - self.base_color) * w
    }

    /// Trowbridge-Reitz (GGX) normal distribution D(h), for cos(n, h) = `nh`.
    fn d(&self, nh: f32) -> f32 {
        let a2 = self.alpha * self.alpha;
        let k = nh * nh * (a2 - 1.0) + 1.0;
        a2 / (PI * k * k)
    }

    /// Height-correlated Smith visibility V = G / (4 |n.l| |n.v|).
    fn v(&self, nl: f32, nv: f32) -> f32 {
        let a2 = self.alpha * self.alpha;
        let gv = nl * (nv * nv * (1.0 - a2) + a2).sqrt();
        let gl = nv * (nl * nl * (1.0 - a2) + a2).sqrt();
        0.5 / (gv + gl)
    }

    /// Smith's masking G1 for one direction.
    fn g1(&self, nv: f32) -> f32 {
        let a2 = self.alpha * self.alpha;
        2.0 * nv / (nv + (a2 + (1.0 - a2) * nv * nv).sqrt())
    }

    /// f(wo, wi): the material is mix(dielectric, metal, metallic); the dielectric is a
    /// Fresnel-weighted mix of the Lambertian base and the specular layer
    /// ((1 - max(F)) x base + F x specular, as KHR_materials_specular defines it).
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        let (nv, nl) = (wo.z, wi.z);
        if nv <= 0.0 || nl <= 0.0 {
            return Vec3::ZERO;
        }
        let diffuse = self.base_color * FRAC_1_PI;
        if self.is_lambertian() {
            return diffuse;
        }
        let h = (wo + wi).normalize_or_zero();
        if h == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let vh = wo.dot(h).max(0.0);
        let spec = self.d(h.z.max(0.0)) * self.v(nl, nv);
        let fd = self.dielectric_fresnel(vh);
        let dielectric = (1.0 - fd.max_element()) * diffuse + fd * spec;
        let metal = self.metal_fresnel(vh) * spec;
        dielectric * (1.0 - self.metallic) + metal * self.metallic
    }

    /// Probability of sampling the specular lobe rather than the diffuse one, from how much
    /// each is worth when seen from `wo` (any choice in (0, 1) is unbiased; this one is cheap
    /// and follows the Fresnel split).
    fn specular_probability(&self, wo: Vec3) -> f32 {
        if self.is_lambertian() {
            return 0.0;
        }
        let nv = wo.z.max(0.0);
        let fd = self.dielectric_fresnel(nv).max_element();
        let spec =
            (1.0 - self.metallic) * fd + self.metallic * self.metal_fresnel(nv).max_element();
        let diff = (1.0 - self.metallic) * (1.0 - fd) * self.base_color.max_element();
        if diff <= 0.0 {
            return 1.0;
        }
        (spec / (spec + diff)).clamp(0.1, 0.9)
    }

    /// Density (solid angle) of the visible-normal GGX lobe producing `wi`.
    fn specular_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let h = (wo + wi).normalize_or_zero();
        if h.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        // D_v(h) / (4 wo.h) with D_v(h) = G1(wo) wo.h D(h) / wo.z.
        self.g1(wo.z) * self.d(h.z) / (4.0 * wo.z)
    }

    /// Density (solid angle) with which `sample` produces `wi`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let ps = self.specular_probability(wo);
        let mut pdf = (1.0 - ps) * wi.z * FRAC_1_PI;
        if ps > 0.0 {
            pdf += ps * self.specular_pdf(wo, wi);
        }
        pdf
    }

    /// Draws `wi` (one lobe chosen by `u_lobe`, then its warp); returns wi, f and the
    /// density of the whole mixture, so the estimate f cos / pdf is one-sample MIS over lobes.
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: Vec2) -> Option<(Vec3, Vec3, f32)> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if u_lobe < self.specular_probability(wo) {
            let h = ggx_visible_normal(wo, self.alpha, u);
            2.0 * wo.dot(h) * h - wo
        } else {
            cosine_hemisphere(u)
        };
        if wi.z <= 0.0 {
            return None;
        }
        let pdf = self.pdf(wo, wi);
        if pdf.is_nan() || pdf <= 0.0 || pdf.is_infinite() {
            return None;
        }
        Some((wi, self.eval(wo, wi), pdf))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::sampling::Pcg32;

    fn dir(theta_deg: f32, phi_deg: f32) -> Vec3 {
        let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
        Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
    }

    /// Estimates the directional albedo both ways: by uniform hemisphere integration of
    /// f cos, and by the sampler's f cos / pdf. They agree only if pdf is the sampler's density.
    fn albedo_two_ways(b: &Brdf, wo: Vec3) -> (Vec3, Vec3) {
        let mut rng = Pcg32::new(3, 5);
        let n = 400_000;
        let (mut uniform, mut sampled) = (Vec3::ZERO, Vec3::ZERO);
        for _ in 0..n {
            let u = rng.next_2d();
            let z = u.x;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * PI * u.y;
            let wi = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            uniform += b.eval(wo, wi) * wi.z * 2.0 * PI;
            if let Some((wi, f, pdf)) = b.sample(wo, rng.next_f32(), rng.next_2d()) {
                sampled += f * wi.z / pdf;
            }
        }
        (uniform / n as f32, sampled / n as f32)
    }

    #[test]
    fn lambertian_is_exact() {
        let b = Brdf::new(Vec3::new(0.8, 0.5, 0.2), 0.0, 0.7, 0.0, Vec3::ONE);
        let wo = dir(30.0, 10.0);
        let wi = dir(50.0, 200.0);
        assert_eq!(b.eval(wo, wi), Vec3::new(0.8, 0.5, 0.2) / PI);
        assert_eq!(b.pdf(wo, wi), wi.z / PI);
    }

    #[test]
    fn sampling_density_matches_the_samples() {
        for (metal, rough, spec) in [
            (0.0, 0.5, 1.0),
            (1.0, 0.3, 1.0),
            (0.5, 0.8, 0.5),
            (1.0, 0.6, 1.0),
        ] {
            let b = Brdf::new(Vec3::new(0.9, 0.6, 0.3), metal, rough, spec, Vec3::ONE);
            for theta in [0.0, 40.0, 75.0] {
                let (u, s) = albedo_two_ways(&b, dir(theta, 30.0));
                assert!(
                    (u - s).abs().max_element() < 0.01 + 0.02 * u.max_element(),
                    "metal {metal} rough {rough} theta {theta}: uniform {u}, sampled {s}"
                );
                assert!(s.max_element() <= 1.0 + 0.02, "gains energy: {s}");
            }
        }
    }

    #[test]
    fn white_furnace_of_the_metal_lobe_stays_below_one() {
        // A white metal with Smith masking loses energy to multiple scattering but never gains.
        let b = Brdf::new(Vec3::ONE, 1.0, 0.2, 1.0, Vec3::ONE);
        let (_, s) = albedo_two_ways(&b, dir(20.0, 0.0));
        assert!(s.max_element() > 0.9 && s.max_element() <= 1.005, "{s}");
    }
}
