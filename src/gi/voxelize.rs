//! Step 1: voxelization. Static geometry is voxelized once (again when a static node moves);
//! dynamic geometry is cleared and voxelized again in a frame where a node moved (or the static
//! voxels were made again) while static voxels stay.

use super::volumes::{Volumes, VoxelData};
use super::VoxelDraws;
use crate::vk::pipeline::area;
use crate::vk::{
    vk, Access, Bindings, Buffer, Context, Graph, GraphicsDesc, Pass, Program, SharedSet, Usage,
    VertexLayout, VkResult,
};
use std::sync::Arc;

/// Push-constant flag: the static pass (the paper's pass writes its flag volume then).
pub const STATIC_PASS: u32 = 2;
/// Push-constant flag: the draw's emission is injected as a light (no voxel emission).
pub const EMITTER_LIGHT: u32 = 4;

pub struct Voxelizer {
    /// Two instances: the static pass's words, then the dynamic pass's (the paper's passes
    /// share one set of volumes, its r32ui images).
    pub pass: Pass,
    /// PAPER: zeroes the dynamic voxels (where the flag is 0).
    clear_dynamic: Option<Pass>,
}

impl Voxelizer {
    /// `shared`: the scene's set and the materials' sets; `vertices`: the scene's positions,
    /// normals and texture coordinates; `push_size`: each draw's push constants.
    pub fn new(
        ctx: &Arc<Context>,
        shared: &[&SharedSet],
        volumes: &Volumes,
        vertices: VertexLayout,
        push_size: u32,
        paper: bool,
    ) -> VkResult<Voxelizer> {
        // Each default pass reaches its words through its table of addresses; it writes them
        // all. The paper's passes bind its images (and the flags: the static pass writes them,
        // the dynamic one reads them).
        let target = |dynamic: bool| match &volumes.data {
            VoxelData::Paper(p) => p.bind_words(Bindings::new(), Usage::ReadWrite).image(
                "paper_flag",
                &p.flag,
                Usage::ReadWrite,
            ),
            VoxelData::Sums { .. } => {
                // The dynamic table points nowhere without dynamic geometry (and that pass
                // never runs then).
                let words = &volumes.words[dynamic as usize];
                volumes
                    .data
                    .written_by(dynamic)
                    .into_iter()
                    .fold(Bindings::new().addresses("Target", words), |t, b| {
                        t.reaches(b, Usage::ReadWrite)
                    })
            }
        };
        let clear_dynamic = match &volumes.data {
            VoxelData::Paper(p) if p.dynamic => {
                let table = p
                    .bind_texels(
                        Bindings::new(),
                        [Usage::ReadWrite, Usage::Write, Usage::Write],
                    )
                    .image("paper_flag", &p.flag, Usage::Read);
                Some(Pass::compute(ctx, "clear_dynamic.comp", &[], table, 4)?)
            }
            _ => None,
        };
        let (geom, frag) = if paper {
            ("voxelize.geom:PAPER", "voxelize.frag:PAPER")
        } else {
            ("voxelize.geom", "voxelize.frag")
        };
        let program = Program::Graphics(GraphicsDesc {
            name: "voxelize",
            shaders: &[
                (vk::ShaderStageFlags::VERTEX, "voxelize.vert"),
                (vk::ShaderStageFlags::GEOMETRY, geom),
                (vk::ShaderStageFlags::FRAGMENT, frag),
            ],
            vertices: Some(vertices),
            color_formats: &[],
            depth_format: None,
            depth_bias: None,
            cull: vk::CullModeFlags::NONE,
        });
        let pass = Pass::new(
            ctx,
            program,
            shared,
            vec![target(false), target(true)],
            push_size,
        )?;
        Ok(Voxelizer {
            pass,
            clear_dynamic,
        })
    }

    /// Clears what the static (or, with `dynamic`, the dynamic) voxelization rebuilds (the
    /// paper's static pass clears all, its dynamic pass the voxels not flagged static).
    pub fn record_clear(
        &self,
        ctx: &Context,
        g: &mut Graph,
        volumes: &Volumes,
        dynamic: bool,
        name: &str,
    ) {
        let d = &ctx.device;
        let n = volumes.grid.resolution;
        match (dynamic, &self.clear_dynamic, &volumes.data) {
            (true, Some(p), VoxelData::Paper(v)) => {
                p.declare(g.pass(name), 0).record(|cmd| unsafe {
                    p.bind(d, cmd, &[], 0);
                    p.pipeline.push(d, cmd, &(v.emissive as u32).to_le_bytes());
                    let groups = n.div_ceil(8);
                    d.cmd_dispatch(cmd, groups, groups, groups);
                });
            }
            (false, _, VoxelData::Paper(v)) => {
                // The static pass starts from empty volumes (and no static flags).
                let images = v.images();
                let mut pass = g.pass(name);
                for &i in &images {
                    pass = pass.image(i, Access::TransferWrite);
                }
                pass.record(|cmd| unsafe {
                    let zero = vk::ClearColorValue { uint32: [0; 4] };
                    for i in &images {
                        let range = [i.full_range()];
                        let layout = vk::ImageLayout::TRANSFER_DST_OPTIMAL;
                        d.cmd_clear_color_image(cmd, i.raw, layout, &zero, &range);
                    }
                });
            }
            _ => {
                // A fill clears what this pass rebuilds (the paper's static pass clears all).
                let mut pass = g.pass(name);
                for b in volumes.data.written_by(dynamic) {
                    pass = pass.buffer(b, Access::TransferWrite);
                }
                let buffers: Vec<vk::Buffer> = volumes
                    .data
                    .written_by(dynamic)
                    .iter()
                    .map(|b| b.raw)
                    .collect();
                pass.record(|cmd| unsafe {
                    for b in &buffers {
                        d.cmd_fill_buffer(cmd, *b, 0, vk::WHOLE_SIZE, 0);
                    }
                });
            }
        }
    }

    /// Voxelizes the static (or, with `dynamic`, the dynamic) geometry. `draws` binds the scene
    /// and material sets and draws the instances of that kind with the given flags.
    ///
    /// The default's draws add into buffers reached by address, one rendering scope for all.
    /// The paper's average into storage images, and each draw is a command of its own with a
    /// barrier after it: synchronization validation sees every image write, and it cannot
    /// tell compare-and-swap atomics (which need no order among draws) from plain writes, so
    /// it asks for an order between commands that write the same texels. Its textures are
    /// bound per material, which rules out one multi-draw call (docs/porting.md).
    #[allow(clippy::too_many_arguments)]
    pub fn record_voxelize(
        &self,
        ctx: &Context,
        g: &mut Graph,
        volumes: &Volumes,
        geometry: (&Buffer, &Buffer),
        dynamic: bool,
        name: &str,
        draws: VoxelDraws,
    ) {
        let d = &ctx.device;
        let n = volumes.grid.resolution;
        let pass = self
            .pass
            .declare(g.pass(name), dynamic as usize)
            .buffer(geometry.0, Access::VertexBuffer)
            .buffer(geometry.1, Access::IndexBuffer);
        let (steps, per_step) = match &volumes.data {
            VoxelData::Paper(_) => (draws.count, 1),
            VoxelData::Sums { .. } => (1, draws.count),
        };
        let flags = if dynamic { 0 } else { STATIC_PASS };
        pass.record_steps(steps, |cmd, step| unsafe {
            let info = vk::RenderingInfo::default()
                .render_area(area(n, n))
                .layer_count(1);
            d.cmd_begin_rendering(cmd, &info);
            // A plain viewport: the geometry shader already maps voxels to pixels.
            d.cmd_set_viewport(
                cmd,
                0,
                &[vk::Viewport {
                    x: 0.0,
                    y: 0.0,
                    width: n as f32,
                    height: n as f32,
                    min_depth: 0.0,
                    max_depth: 1.0,
                }],
            );
            d.cmd_set_scissor(cmd, 0, &[area(n, n)]);
            self.pass.bind(d, cmd, &[], dynamic as usize);
            let first = step * per_step;
            (draws.draw)(cmd, &self.pass.pipeline, flags, first..first + per_step);
            d.cmd_end_rendering(cmd);
        });
    }
}
