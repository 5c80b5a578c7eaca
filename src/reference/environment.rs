//! The environment as a light source of the path tracer: its radiance where a path leaves the
//! scene, and, for an image, directions drawn in proportion to its texels' power (their
//! luminance times the solid angle they span), so that a small bright sun is found by next-event
//! estimation instead of by chance. A uniform environment is left to BRDF sampling, which
//! already draws directions as its cosine-weighted light does.

use super::sampling::Distribution;
use crate::scene::environment::{equirect_direction, equirect_uv};
use crate::scene::{EnvSource, Environment};
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

pub struct EnvLight<'s> {
    pub env: &'s Environment,
    /// For an image: one entry per texel, row by row; None for a uniform radiance (or an
    /// image that is black everywhere).
    texels: Option<Distribution>,
    size: (u32, u32),
}

impl<'s> EnvLight<'s> {
    /// `importance`: false leaves even an image to BRDF sampling (to measure what importance
    /// sampling buys).
    pub fn new(env: &'s Environment, importance: bool) -> EnvLight<'s> {
        let (texels, size) = match &env.source {
            EnvSource::Image(img) if importance => {
                let (w, h) = (img.width, img.height);
                let lum = |x: i64, y: i64| {
                    let t = img.texel(
                        x.rem_euclid(w as i64) as u32,
                        y.clamp(0, h as i64 - 1) as u32,
                    );
                    (0.2126 * t.x + 0.7152 * t.y + 0.0722 * t.z) as f64
                };
                // Bilinear filtering spreads a texel's radiance over its neighbours' area: each
                // texel is weighted by the brightest of its 3 x 3 neighbourhood, so that every
                // direction with light has a density (a lone bright texel would otherwise leave
                // the larger part of its light to BRDF sampling).
                let weights: Vec<f64> = (0..h as i64)
                    .flat_map(|y| (0..w as i64).map(move |x| (x, y)))
                    .map(|(x, y)| {
                        let sin = ((y as f64 + 0.5) / h as f64 * std::f64::consts::PI).sin();
                        let mut m = 0.0f64;
                        for dy in -1..=1 {
                            for dx in -1..=1 {
                                m = m.max(lum(x + dx, y + dy));
                            }
                        }
                        m * sin
                    })
                    .collect();
                (Distribution::new(&weights), (w, h))
            }
            _ => (None, (0, 0)),
        };
        EnvLight { env, texels, size }
    }

    pub fn radiance(&self, d: Vec3) -> Vec3 {
        self.env.radiance(d)
    }

    /// Whether next-event estimation samples it (else only BRDF sampling reaches it).
    pub fn is_sampled(&self) -> bool {
        self.texels.is_some()
    }

    /// A direction towards the environment (world space) and its density per solid angle.
    pub fn sample(&self, u_pick: f32, u: Vec2) -> Option<(Vec3, f32)> {
        let dist = self.texels.as_ref()?;
        let (w, h) = self.size;
        let i = dist.sample(u_pick);
        let (x, y) = (i as u32 % w, i as u32 / w);
        let (su, sv) = ((x as f32 + u.x) / w as f32, (y as f32 + u.y) / h as f32);
        let sin = (sv * PI).sin();
        if sin <= 0.0 {
            return None;
        }
        let pdf = dist.pmf(i) * (w * h) as f32 / (2.0 * PI * PI * sin);
        let d = self.env.to_world(equirect_direction(su, sv)).normalize();
        Some((d, pdf))
    }

    /// The density `sample` draws direction `d` with (0 where it never does).
    pub fn pdf(&self, d: Vec3) -> f32 {
        let Some(dist) = &self.texels else {
            return 0.0;
        };
        let (w, h) = self.size;
        let (u, v) = equirect_uv(self.env.to_image_frame(d));
        let x = ((u.rem_euclid(1.0) * w as f32) as u32).min(w - 1);
        let y = ((v * h as f32) as u32).min(h - 1);
        let sin = (v * PI).sin();
        if sin <= 0.0 {
            return 0.0;
        }
        dist.pmf((y * w + x) as usize) * (w * h) as f32 / (2.0 * PI * PI * sin)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::sampling::Pcg32;
    use crate::scene::environment::EnvImage;

    fn image_env(w: u32, h: u32, texel: impl Fn(u32, u32) -> Vec3, turn_deg: f32) -> Environment {
        let texels = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| texel(x, y))
            .collect();
        Environment::image(EnvImage::new("test.hdr", w, h, texels)).turned(turn_deg)
    }

    #[test]
    fn the_density_integrates_to_one_and_matches_the_draws() {
        let env = image_env(
            16,
            8,
            |x, y| Vec3::splat(1.0 + (x * 3 + y * 7) as f32 % 5.0),
            30.0,
        );
        let light = EnvLight::new(&env, true);
        // Integral of the pdf over the sphere by a fine uniform grid in (u, v).
        let (nu, nv) = (400, 200);
        let mut sum = 0.0f64;
        for j in 0..nv {
            for i in 0..nu {
                let (u, v) = ((i as f32 + 0.5) / nu as f32, (j as f32 + 0.5) / nv as f32);
                let d = env.to_world(equirect_direction(u, v));
                let area = 2.0 * PI * PI * (v * PI).sin() / (nu * nv) as f32;
                sum += (light.pdf(d) * area) as f64;
            }
        }
        assert!((sum - 1.0).abs() < 0.01, "integral {sum}");
        // A drawn direction's density is the one pdf() gives it.
        let mut rng = Pcg32::new(1, 2);
        for _ in 0..100 {
            let (d, pdf) = light.sample(rng.next_f32(), rng.next_2d()).unwrap();
            let again = light.pdf(d);
            assert!((pdf - again).abs() <= 1e-3 * pdf, "{pdf} {again} at {d}");
        }
    }
}
