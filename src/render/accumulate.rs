//! Antialiasing by accumulation. The conventions' pixel is the mean over its footprint, and one
//! shading sample at each pixel's centre aliases what changes within a pixel: silhouettes,
//! thin parts, normal-mapped highlights. While the view holds still, each frame draws its
//! G-buffer with the camera shifted by a sub-pixel offset ([`jitter`]: the first frame at the
//! pixel's centre, then a Halton sequence over the pixel) and this pass keeps the running mean
//! of the frames' radiance (glsl/accumulate.comp). The renderer starts the mean again wherever
//! the image changes for another reason: the camera, a light or a node moves, or the size.

use super::frame::FrameTargets;
use crate::vk::{Bindings, Context, Graph, Pass, Usage, VkResult};
use glam::Vec2;
use std::sync::Arc;

/// The radical inverse of `i` in `base`: the Halton sequence's coordinate.
fn radical_inverse(mut i: u32, base: u32) -> f32 {
    let mut f = 1.0;
    let mut r = 0.0;
    while i > 0 {
        f /= base as f32;
        r += f * (i % base) as f32;
        i /= base;
    }
    r
}

/// The sub-pixel offset of frame `index` of a mean, in pixels within [-0.5, 0.5)^2: frame 0 at
/// the centre (a single frame is the unjittered image), then Halton (2, 3), shifted by half a
/// pixel, spread evenly over the footprint.
pub fn jitter(index: u32) -> Vec2 {
    let h = Vec2::new(radical_inverse(index, 2), radical_inverse(index, 3));
    (h + Vec2::splat(0.5)).fract() - Vec2::splat(0.5)
}

/// This frame's share of the mean: `1 / (index + 1)` over the first `frames` frames, then 0
/// (the mean is complete: a still view renders the same frames again).
pub fn weight(index: u32, frames: u32) -> f32 {
    if index == 0 || index < frames {
        1.0 / (index + 1) as f32
    } else {
        0.0
    }
}

pub struct Accumulate {
    pass: Pass,
}

/// The radiance image and the mean (None: the targets keep no mean).
fn table(targets: &FrameTargets) -> Option<Bindings> {
    let history = targets.history.as_ref()?;
    Some(
        Bindings::new()
            .image("radiance", &targets.hdr, Usage::ReadWrite)
            .image("history", history, Usage::ReadWrite),
    )
}

impl Accumulate {
    /// The pass over `targets`, or None when they keep no mean.
    pub fn new(ctx: &Arc<Context>, targets: &FrameTargets) -> VkResult<Option<Accumulate>> {
        let Some(table) = table(targets) else {
            return Ok(None);
        };
        let pass = Pass::compute(ctx, "accumulate.comp", &[], table, 12)?;
        Ok(Some(Accumulate { pass }))
    }

    /// Points the pass at a resized frame's images (no frame may be in flight); they keep a
    /// mean as the ones it was made with did.
    pub fn retarget(&mut self, ctx: &Context, targets: &FrameTargets) -> VkResult<()> {
        let table = table(targets).expect("resized targets keep a mean");
        self.pass.rebind(ctx, 0, table, &[])
    }

    /// Blends this frame's radiance into the mean with `weight` (1 starts it again).
    pub fn record(
        &self,
        ctx: &Context,
        g: &mut Graph,
        name: &str,
        targets: &FrameTargets,
        weight: f32,
    ) {
        let (w, h) = (targets.width, targets.height);
        let push: Vec<u8> = [w.to_le_bytes(), h.to_le_bytes(), weight.to_le_bytes()].concat();
        let groups = [w.div_ceil(8), h.div_ceil(8), 1];
        self.pass.record_dispatch(ctx, g, name, &[], &push, groups);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_frame_is_the_centre_and_the_offsets_cover_the_pixel() {
        assert_eq!(jitter(0), Vec2::ZERO);
        let n = 64;
        let offsets: Vec<Vec2> = (0..n).map(jitter).collect();
        for o in &offsets {
            assert!(o.cmpge(Vec2::splat(-0.5)).all() && o.cmplt(Vec2::splat(0.5)).all());
        }
        // Evenly spread: every quarter of the pixel holds a quarter of the offsets (to one),
        // and their mean is the centre (to a sample's share).
        for q in 0..4 {
            let (sx, sy) = (q & 1 == 1, q & 2 == 2);
            let count = offsets
                .iter()
                .filter(|o| (o.x >= 0.0) == sx && (o.y >= 0.0) == sy)
                .count();
            assert!(
                (count as i32 - n as i32 / 4).abs() <= 1,
                "quarter {q}: {count}"
            );
        }
        let mean = offsets.iter().sum::<Vec2>() / n as f32;
        assert!(mean.abs().max_element() < 1.0 / n as f32, "{mean}");
    }

    #[test]
    fn the_weights_make_the_mean_of_the_first_frames() {
        // Blending with these weights gives the plain mean of the first `frames` values.
        let values = [3.0f32, 5.0, 10.0, 2.0];
        let mut m = 0.0;
        for (i, v) in values.iter().enumerate() {
            let w = weight(i as u32, 8);
            m += (v - m) * w;
        }
        assert!((m - 5.0).abs() < 1e-6, "{m}");
        assert_eq!(weight(0, 8), 1.0);
        // Complete: later frames leave it.
        assert_eq!(weight(8, 8), 0.0);
        assert_eq!(weight(100, 8), 0.0);
    }
}
