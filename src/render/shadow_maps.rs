//! The shadow maps: one depth layer per light view (shadows.rs fits the views), drawn again
//! only where a light or a caster moved (glsl/shadow.vert, glsl/shadow.frag). The punctual
//! lights' views and the area lights' views are two arrays of their own resolutions: an area
//! light's shadows are soft, and a coarser map gives the same penumbrae for a sixteenth of the
//! texels to draw and to filter.

use super::frame::DEPTH_FORMAT;
use super::instances::{self, SceneDraw, DRAW_PUSH_SIZE, POSITION, UV};
use super::scene_set::SceneBindings;
use crate::vk::pipeline::{area, cleared_depth, set_viewport};
use crate::vk::{
    vk, Access, Bindings, Context, Graph, GraphicsDesc, Image, ImageDesc, Pass, Program, Sampler,
    VkResult,
};
use std::sync::Arc;

/// How many views of each kind, and their resolutions (texels per side).
#[derive(Clone, Copy, Debug)]
pub struct ShadowLayout {
    /// The punctual lights' views: layers 0.. of `map`, views 0.. of the light table.
    pub views: u32,
    pub resolution: u32,
    /// The area lights' views: layers 0.. of `area_map`, views `views`.. of the light table.
    pub area_views: u32,
    pub area_resolution: u32,
}

pub struct ShadowMaps {
    /// One layer per punctual light view; a 1x1 stand-in when there is none (the shaders
    /// sample an array either way).
    pub map: Image,
    /// One layer per area light view (or the stand-in).
    pub area_map: Image,
    /// Hardware comparison with bilinear filtering: each tap is already a 2x2 PCF.
    pub sampler: Sampler,
    pass: Pass,
    pub layout: ShadowLayout,
    /// Per view, punctual then area: it must be drawn (first frame, its light moved, or a node
    /// moved through it).
    pub dirty: Vec<bool>,
}

/// A depth array of `views` layers of `resolution` texels per side, or a 1x1 stand-in.
fn depth_array(ctx: &Arc<Context>, name: &str, views: u32, resolution: u32) -> VkResult<Image> {
    let side = if views > 0 { resolution } else { 1 };
    Image::new(
        ctx,
        name,
        ImageDesc::d2(
            DEPTH_FORMAT,
            side,
            side,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
        )
        .layers(views.max(1)),
    )
}

impl ShadowMaps {
    pub fn new(
        ctx: &Arc<Context>,
        sets: &SceneBindings,
        layout: ShadowLayout,
    ) -> VkResult<ShadowMaps> {
        // Only the views the lights need.
        let map = depth_array(ctx, "shadow maps", layout.views, layout.resolution)?;
        let area_map = depth_array(
            ctx,
            "area light shadow maps",
            layout.area_views,
            layout.area_resolution,
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
            area_map,
            sampler,
            pass,
            layout,
            dirty: vec![true; (layout.views + layout.area_views) as usize],
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
        let l = self.layout;
        // Only the arrays with views to draw: the other keeps its layout and needs no barrier.
        let (punctual_dirty, area_dirty) = self.dirty.split_at(l.views as usize);
        let mut pass = scene.declare(self.pass.declare(g.pass(name), 0));
        if punctual_dirty.contains(&true) {
            pass = pass.image(&self.map, Access::DepthAttachmentWrite);
        }
        if area_dirty.contains(&true) {
            pass = pass.image(&self.area_map, Access::DepthAttachmentWrite);
        }
        pass.record(|cmd| {
            for (view, _) in self.dirty.iter().enumerate().filter(|(_, &d)| d) {
                let view = view as u32;
                let (layer, res) = if view < l.views {
                    (self.map.layer_view(view), l.resolution)
                } else {
                    (self.area_map.layer_view(view - l.views), l.area_resolution)
                };
                let depth = cleared_depth(layer, vk::AttachmentStoreOp::STORE);
                let info = vk::RenderingInfo::default()
                    .render_area(area(res, res))
                    .layer_count(1)
                    .depth_attachment(&depth);
                unsafe {
                    d.cmd_begin_rendering(cmd, &info);
                    set_viewport(ctx, cmd, res, res);
                    let shown = (0..scene.instances.count()).filter(|&i| !hides(i, view));
                    scene.draw(d, cmd, &self.pass.pipeline, |_| view, shown);
                    d.cmd_end_rendering(cmd);
                }
            }
        });
    }
}
