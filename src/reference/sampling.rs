//! Random numbers and the warps that turn them into directions and points.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// PCG32 (O'Neill 2014, XSH-RR output): 64 bits of state, independent streams for free, so each
/// pixel gets its own stream and the image does not depend on which thread rendered it.
#[derive(Clone, Debug)]
pub struct Pcg32 {
    state: u64,
    inc: u64,
}

const PCG_MULT: u64 = 6_364_136_223_846_793_005;

/// SplitMix64's finaliser: spreads neighbouring integers (pixel indices, seeds) over all bits.
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

impl Pcg32 {
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut r = Pcg32 {
            state: 0,
            inc: (stream << 1) | 1,
        };
        r.next_u32();
        r.state = r.state.wrapping_add(seed);
        r.next_u32();
        r
    }

    /// The stream for one pixel of a render with the given seed.
    pub fn for_pixel(seed: u64, pixel: u64) -> Self {
        Pcg32::new(mix64(seed ^ mix64(pixel)), pixel)
    }

    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(PCG_MULT).wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }

    /// Uniform in [0, 1): 24 random bits, so 1.0 itself never comes out.
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    pub fn next_2d(&mut self) -> Vec2 {
        let x = self.next_f32();
        Vec2::new(x, self.next_f32())
    }
}

/// An orthonormal frame around a unit normal (z), for moving directions in and out of the
/// local shading space where the BRDF is written.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub t: Vec3,
    pub b: Vec3,
    pub n: Vec3,
}

impl Frame {
    pub fn new(n: Vec3) -> Self {
        let (t, b) = n.any_orthonormal_pair();
        Frame { t, b, n }
    }
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.t), v.dot(self.b), v.dot(self.n))
    }
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.t * v.x + self.b * v.y + self.n * v.z
    }
}

/// Cosine-weighted direction on the +z hemisphere; its density is z / pi.
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), (1.0 - u.x).max(0.0).sqrt())
}

/// A GGX microfacet normal drawn from the distribution of normals visible from `wo` (local
/// frame, wo.z > 0), by the spherical-cap construction of Dupuy and Benyoub (2023): in the
/// stretched (alpha = 1) space the visible normals are a uniform cap plus the view direction.
pub fn ggx_visible_normal(wo: Vec3, alpha: f32, u: Vec2) -> Vec3 {
    let v = Vec3::new(wo.x * alpha, wo.y * alpha, wo.z).normalize();
    let phi = 2.0 * PI * u.x;
    let z = (1.0 - u.y) * (1.0 + v.z) - v.z;
    let s = (1.0 - z * z).max(0.0).sqrt();
    let h = Vec3::new(s * phi.cos(), s * phi.sin(), z) + v;
    Vec3::new(h.x * alpha, h.y * alpha, h.z.max(0.0)).normalize_or(Vec3::Z)
}

/// Barycentric coordinates (b1, b2) of a uniformly distributed point on a triangle.
pub fn uniform_triangle(u: Vec2) -> (f32, f32) {
    let s = u.x.sqrt();
    (u.y * s, 1.0 - s)
}

/// The power heuristic (beta = 2) weight of a strategy with density `a` against one with `b`.
pub fn power_heuristic(a: f32, b: f32) -> f32 {
    power_heuristic_among(a, &[b])
}

/// The power heuristic weight of a strategy with density `a` among strategies with densities
/// `a` and `others` (all in one measure).
pub fn power_heuristic_among(a: f32, others: &[f32]) -> f32 {
    let a2 = a * a;
    let sum = a2 + others.iter().map(|b| b * b).sum::<f32>();
    if sum > 0.0 && sum.is_finite() {
        a2 / sum
    } else if a.is_infinite() {
        1.0
    } else {
        0.0
    }
}

/// A direction within `cos_max` of +z (a cone), uniform over its solid angle
/// 2 pi (1 - cos_max); -1 gives the whole sphere.
pub fn uniform_cone(cos_max: f32, u: Vec2) -> Vec3 {
    let z = 1.0 - u.x * (1.0 - cos_max);
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A discrete distribution proportional to given non-negative weights, sampled by inverting its
/// cumulative sum.
#[derive(Clone, Debug, Default)]
pub struct Distribution {
    /// cdf[i] = sum of weights before and including i, divided by the total.
    cdf: Vec<f32>,
    pmf: Vec<f32>,
}

impl Distribution {
    /// None when no weight is positive.
    pub fn new(weights: &[f64]) -> Option<Self> {
        let total: f64 = weights.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let mut acc = 0.0;
        let mut cdf = Vec::with_capacity(weights.len());
        for w in weights {
            acc += w;
            cdf.push((acc / total) as f32);
        }
        // Guard the last entry so a draw just below 1 always lands somewhere.
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        let pmf = weights.iter().map(|w| (w / total) as f32).collect();
        Some(Distribution { cdf, pmf })
    }

    /// An index with probability pmf(index); never one of zero weight.
    pub fn sample(&self, u: f32) -> usize {
        let i = self
            .cdf
            .partition_point(|&c| c <= u)
            .min(self.cdf.len() - 1);
        if self.pmf[i] > 0.0 {
            return i;
        }
        // Rounding put u on a zero-weight entry's boundary: take the next one with weight.
        (i..self.pmf.len())
            .chain(0..i)
            .find(|&j| self.pmf[j] > 0.0)
            .unwrap_or(i)
    }

    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf[i]
    }

    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pcg_is_uniform_and_reproducible() {
        let mut a = Pcg32::for_pixel(7, 123);
        let mut b = Pcg32::for_pixel(7, 123);
        let mut mean = 0.0f64;
        for _ in 0..100_000 {
            let x = a.next_f32();
            assert_eq!(x, b.next_f32());
            assert!((0.0..1.0).contains(&x));
            mean += x as f64;
        }
        assert!((mean / 100_000.0 - 0.5).abs() < 0.005);
        assert_ne!(
            Pcg32::for_pixel(7, 123).next_u32(),
            Pcg32::for_pixel(8, 123).next_u32()
        );
    }

    #[test]
    fn visible_normals_face_the_viewer_and_reflect_into_the_hemisphere_mostly() {
        let mut rng = Pcg32::new(1, 1);
        let wo = Vec3::new(0.6, 0.0, 0.8);
        for _ in 0..10_000 {
            let h = ggx_visible_normal(wo, 0.3, rng.next_2d());
            assert!((h.length() - 1.0).abs() < 1e-4);
            assert!(h.z >= 0.0 && h.dot(wo) >= -1e-6, "{h}");
        }
    }

    #[test]
    fn distribution_follows_weights() {
        let d = Distribution::new(&[1.0, 0.0, 3.0]).unwrap();
        assert_eq!(d.pmf(0), 0.25);
        assert_eq!(d.sample(0.0), 0);
        assert_eq!(d.sample(0.2499), 0);
        assert_eq!(d.sample(0.25), 2);
        assert_eq!(d.sample(0.99999), 2);
        assert!(Distribution::new(&[0.0, 0.0]).is_none());
    }
}
