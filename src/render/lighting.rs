//! Direct light per pixel: the punctual lights (and emitters lit as lights) with their shadow
//! maps, plus emission, from the G-buffer into the radiance image
//! (glsl/deferred_lighting.comp).

use super::frame::FrameTargets;
use super::scene_set::SceneBindings;
use super::shadow_maps::ShadowMaps;
use crate::gi::GBUFFER_NAMES;
use crate::vk::{vk, Bindings, Context, Graph, Pass, Sampler, Usage, VkResult};
use std::sync::Arc;

pub struct LightingPass {
    pass: Pass,
}

/// The frame's images the pass reads and writes, and the shadow maps it samples.
fn table(targets: &FrameTargets, nearest: &Sampler, shadow: &ShadowMaps) -> Bindings {
    targets
        .gbuffer
        .iter()
        .zip(GBUFFER_NAMES)
        .fold(Bindings::new(), |t, (img, name)| {
            t.sampled(name, img, nearest)
        })
        .sampled("shadow_map", &shadow.map, &shadow.sampler)
        .sampled("area_shadow_map", &shadow.area_map, &shadow.sampler)
        .sampled("area_shadow_depth", &shadow.area_map, nearest)
        .image("out_radiance", &targets.hdr, Usage::Write)
}

impl LightingPass {
    pub fn new(
        ctx: &Arc<Context>,
        sets: &SceneBindings,
        targets: &FrameTargets,
        nearest: &Sampler,
        shadow: &ShadowMaps,
    ) -> VkResult<LightingPass> {
        let table = table(targets, nearest, shadow);
        let pass = Pass::compute(ctx, "deferred_lighting.comp", &[&sets.scene], table, 0)?;
        Ok(LightingPass { pass })
    }

    /// Points the pass at a resized frame's images (no frame may be in flight).
    pub fn retarget(
        &mut self,
        ctx: &Context,
        sets: &SceneBindings,
        targets: &FrameTargets,
        nearest: &Sampler,
        shadow: &ShadowMaps,
    ) -> VkResult<()> {
        let table = table(targets, nearest, shadow);
        self.pass.rebind(ctx, 0, table, &[&sets.scene])
    }

    pub fn record(
        &self,
        ctx: &Context,
        g: &mut Graph,
        name: &str,
        targets: &FrameTargets,
        scene_set: vk::DescriptorSet,
    ) {
        let (w, h) = (targets.width, targets.height);
        let groups = [w.div_ceil(8), h.div_ceil(8), 1];
        self.pass
            .record_dispatch(ctx, g, name, &[(0, scene_set)], &[], groups);
    }
}
