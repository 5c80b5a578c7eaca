//! The random draws of the scene generator: one PCG stream per scene, so that a scene depends
//! only on its own seed and the same seed gives the same scene, byte for byte.

use rand_core::{RngCore, SeedableRng};
use rand_pcg::Pcg64Mcg;

/// A scene's random stream.
pub struct Draw(Pcg64Mcg);

impl Draw {
    pub fn new(seed: u64) -> Draw {
        Draw(Pcg64Mcg::seed_from_u64(seed))
    }

    /// Uniform in [0, 1), 53 bits.
    pub fn unit(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f32, hi: f32) -> f32 {
        (lo as f64 + (hi as f64 - lo as f64) * self.unit()) as f32
    }

    /// Log-uniform in [lo, hi) (both > 0): as likely between 1 and 10 as between 10 and 100.
    pub fn log_uniform(&mut self, lo: f32, hi: f32) -> f32 {
        let (a, b) = ((lo as f64).ln(), (hi as f64).ln());
        (a + (b - a) * self.unit()).exp() as f32
    }

    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        self.unit() < p
    }

    /// An integer in lo..=hi.
    pub fn int(&mut self, lo: u32, hi: u32) -> u32 {
        lo + (self.unit() * (hi - lo + 1) as f64)
            .floor()
            .min((hi - lo) as f64) as u32
    }

    /// One of `items`, each as likely.
    pub fn pick<T: Copy>(&mut self, items: &[T]) -> T {
        items[self.int(0, items.len() as u32 - 1) as usize]
    }

    /// One of `items` by weight.
    pub fn weighted<T: Copy>(&mut self, items: &[(f64, T)]) -> T {
        let total: f64 = items.iter().map(|(w, _)| w).sum();
        let mut x = self.unit() * total;
        for &(w, item) in items {
            if x < w {
                return item;
            }
            x -= w;
        }
        items[items.len() - 1].1
    }

    /// A grey or slightly tinted albedo of mean about `mean`.
    pub fn albedo(&mut self, lo: f32, hi: f32, tint: f32) -> [f32; 3] {
        let m = self.uniform(lo, hi);
        let mut c = [0.0; 3];
        for v in &mut c {
            *v = (m * (1.0 + self.uniform(-tint, tint))).clamp(0.01, 0.95);
        }
        c
    }

    /// A saturated colour of mean about `mean` (a coloured wall, a coloured emitter).
    pub fn colour(&mut self, mean: f32) -> [f32; 3] {
        let hue = self.uniform(0.0, 6.0);
        let s = self.uniform(0.4, 0.9);
        let rgb = hue_rgb(hue);
        let c = rgb.map(|v| 1.0 - s + s * v);
        let m = (c[0] + c[1] + c[2]) / 3.0;
        c.map(|v| (v * mean / m).clamp(0.01, 0.95))
    }
}

/// The fully saturated colour of hue `h` in [0, 6).
fn hue_rgb(h: f32) -> [f32; 3] {
    let x = 1.0 - ((h % 2.0) - 1.0).abs();
    match h as u32 {
        0 => [1.0, x, 0.0],
        1 => [x, 1.0, 0.0],
        2 => [0.0, 1.0, x],
        3 => [0.0, x, 1.0],
        4 => [x, 0.0, 1.0],
        _ => [1.0, 0.0, x],
    }
}

/// A scene's seed from the corpus's seed, its class and its number (splitmix64 over the three),
/// so that adding scenes to a corpus or classes to the generator leaves the others as they were.
pub fn scene_seed(corpus_seed: u64, class: &str, number: u32) -> u64 {
    let mut h = splitmix(corpus_seed);
    for b in class.bytes() {
        h = splitmix(h ^ b as u64);
    }
    splitmix(h ^ number as u64)
}

fn splitmix(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn draws_stay_in_range_and_repeat_from_a_seed() {
        let (mut a, mut b) = (Draw::new(7), Draw::new(7));
        for _ in 0..1000 {
            let x = a.uniform(2.0, 3.0);
            assert_eq!(x, b.uniform(2.0, 3.0));
            assert!((2.0..3.0).contains(&x));
            let l = a.log_uniform(0.01, 100.0);
            b.log_uniform(0.01, 100.0);
            assert!((0.01..=100.0).contains(&l), "{l}");
            let i = a.int(3, 5);
            b.int(3, 5);
            assert!((3..=5).contains(&i));
        }
        assert_ne!(scene_seed(1, "a", 0), scene_seed(1, "a", 1));
        assert_ne!(scene_seed(1, "a", 0), scene_seed(1, "b", 0));
        assert_ne!(scene_seed(1, "a", 0), scene_seed(2, "a", 0));
    }
}
