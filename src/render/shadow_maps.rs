//! The shadow maps: one depth layer per light view (shadows.rs fits the views), drawn again
//! only where a light or a caster moved (glsl/shadow.vert, glsl/shadow.frag).

use super::frame::DEPTH_FORMAT;
use super::instances::{self, SceneDraw, DRAW_PUSH_SIZE, POSITION, UV};
use super::scene_set::SceneBindings;
use crate::vk::pipeline::{area, cleared_depth, set_viewport};
use crate::vk::{
    vk, Access, Bindings, Context, Graph, GraphicsDesc, Image, ImageDesc, Pass, Program, Sampler,
    VkResult,
};
use std::sync::Arc;

pub struct ShadowMaps {
    /// One layer per view; a 1x1 stand-in when nothing casts shadows (the shaders sample an
    /// array either way).
    pub map: Image,
    /// Hardware comparison with bilinear filtering: each tap is already a 2x2 PCF.
    pub sampler: Sampler,
    pass: Pass,
    resolution: u32,
    /// Per view: it must be drawn (first frame, its light moved, or a node moved through it).
    pub dirty: Vec<bool>,
}

impl ShadowMaps {
    pub fn new(
        ctx: &Arc<Context>,
        sets: &SceneBindings,
        views: u32,
        resolution: u32,
    ) -> VkResult<ShadowMaps> {
        // Only the views the lights need.
        let side = if views > 0 { resolution } else { 1 };
        let map = Image::new(
            ctx,
            "shadow maps",
            ImageDesc::d2(
                DEPTH_FORMAT,
                side,
                side,
                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
            )
            .layers(views.max(1)),
        )?;
        let sampler = Sampler::new(
            ctx,
            &vk::SamplerCreateInfo::default()
                .mag_filter(vk::Filter::LINEAR)
                .min_filter(vk::Filter::LINEAR)
                .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
                .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
                .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
                .compare_enable(true)
                .compare_op(vk::CompareOp::LESS_OR_EQUAL),
        )?;
        let program = Program::Graphics(GraphicsDesc {
            name: "shadow",
            shaders: &[
                (vk::ShaderStageFlags::VERTEX, "shadow.vert"),
                (vk::ShaderStageFlags::FRAGMENT, "shadow.frag"),
            ],
            vertices: Some(instances::vertices(&[POSITION, UV])),
            color_formats: &[],
            depth_format: Some(DEPTH_FORMAT),
            depth_bias: Some((1.0, 1.5)),
            cull: vk::CullModeFlags::NONE,
        });
        let shared = [&sets.scene, &sets.materials];
        let pass = Pass::new(ctx, program, &shared, vec![Bindings::new()], DRAW_PUSH_SIZE)?;
        Ok(ShadowMaps {
            map,
            sampler,
            pass,
            resolution,
            dirty: vec![true; views as usize],
        })
    }

    pub fn any_dirty(&self) -> bool {
        self.dirty.iter().any(|&d| d)
    }

    /// Draws the views that changed; `hides(instance, view)`: the instance casts no shadow in
    /// that view (an emitter light's own faces would hide it).
    pub fn record(
        &self,
        ctx: &Context,
        g: &mut Graph,
        name: &str,
        scene: &SceneDraw,
        hides: impl Fn(usize, u32) -> bool,
    ) {
        let d = &ctx.device;
        let res = self.resolution;
        let pass = scene
            .declare(self.pass.declare(g.pass(name), 0))
            .image(&self.map, Access::DepthAttachmentWrite);
        pass.record(|cmd| {
            for (view, _) in self.dirty.iter().enumerate().filter(|(_, &d)| d) {
                let view = view as u32;
                let depth = cleared_depth(self.map.layer_view(view), vk::AttachmentStoreOp::STORE);
                let info = vk::RenderingInfo::default()
                    .render_area(area(res, res))
                    .layer_count(1)
                    .depth_attachment(&depth);
                unsafe {
                    d.cmd_begin_rendering(cmd, &info);
                    set_viewport(ctx, cmd, res, res);
                    scene.draw(d, cmd, &self.pass.pipeline, |_| view, |i| !hides(i, view));
                    d.cmd_end_rendering(cmd);
                }
            }
        });
    }
}
