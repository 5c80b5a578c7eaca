//! The G-buffer pass: position, normal, albedo, emission and specular per pixel
//! (glsl/gbuffer.vert, glsl/gbuffer.frag).

use super::frame::{FrameTargets, DEPTH_FORMAT, GBUFFER_FORMATS};
use super::instances::{self, SceneDraw, DRAW_PUSH_SIZE, NORMAL, POSITION, TANGENT, UV};
use super::scene_set::SceneBindings;
use crate::vk::pipeline::{area, cleared_depth, set_viewport};
use crate::vk::{vk, Access, Bindings, Context, Graph, GraphicsDesc, Pass, Program, VkResult};
use std::sync::Arc;

pub struct GBufferPass {
    pass: Pass,
}

impl GBufferPass {
    pub fn new(ctx: &Arc<Context>, sets: &SceneBindings) -> VkResult<GBufferPass> {
        let program = Program::Graphics(GraphicsDesc {
            name: "gbuffer",
            shaders: &[
                (vk::ShaderStageFlags::VERTEX, "gbuffer.vert"),
                (vk::ShaderStageFlags::FRAGMENT, "gbuffer.frag"),
            ],
            vertices: Some(instances::vertices(&[POSITION, NORMAL, UV, TANGENT])),
            color_formats: &GBUFFER_FORMATS,
            depth_format: Some(DEPTH_FORMAT),
            depth_bias: None,
            cull: vk::CullModeFlags::NONE,
        });
        let shared = [&sets.scene, &sets.materials];
        let pass = Pass::new(ctx, program, &shared, vec![Bindings::new()], DRAW_PUSH_SIZE)?;
        Ok(GBufferPass { pass })
    }

    pub fn record(
        &self,
        ctx: &Context,
        g: &mut Graph,
        name: &str,
        targets: &FrameTargets,
        scene: &SceneDraw,
    ) {
        let d = &ctx.device;
        let (w, h) = (targets.width, targets.height);
        let mut pass = scene
            .declare(self.pass.declare(g.pass(name), 0))
            .image(&targets.depth, Access::DepthAttachmentWrite);
        for img in &targets.gbuffer {
            pass = pass.image(img, Access::ColorAttachmentWrite);
        }
        pass.record(|cmd| {
            let colors: Vec<_> = targets
                .gbuffer
                .iter()
                .map(|img| {
                    vk::RenderingAttachmentInfo::default()
                        .image_view(img.view)
                        .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                        .load_op(vk::AttachmentLoadOp::CLEAR)
                        .store_op(vk::AttachmentStoreOp::STORE)
                        .clear_value(vk::ClearValue {
                            color: vk::ClearColorValue { float32: [0.0; 4] },
                        })
                })
                .collect();
            let depth = cleared_depth(targets.depth.view, vk::AttachmentStoreOp::DONT_CARE);
            let info = vk::RenderingInfo::default()
                .render_area(area(w, h))
                .layer_count(1)
                .color_attachments(&colors)
                .depth_attachment(&depth);
            unsafe {
                d.cmd_begin_rendering(cmd, &info);
                set_viewport(ctx, cmd, w, h);
                let mirrored = |i| scene.instances.mirrored(i);
                let all = 0..scene.instances.count();
                scene.draw(d, cmd, &self.pass.pipeline, mirrored, all);
                d.cmd_end_rendering(cmd);
            }
        });
    }
}
