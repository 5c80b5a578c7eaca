//! Step 1: voxelization. Static geometry is voxelized once (again when a static node moves);
//! dynamic geometry is cleared and voxelized every frame while static voxels stay.

use super::volumes::{Volumes, VoxelData};
use crate::render::pipelines::{
    self, Desc, DescriptorPool, GraphicsDesc, Pipeline, Set, SetLayout, Spec,
};
use crate::render::GpuScene;
use crate::vk::{vk, Access, Context, Graph, VkResult};
use std::sync::Arc;

/// Push-constant flag: the static pass (the paper's pass writes its flag volume then).
pub const STATIC_PASS: u32 = 2;
/// Push-constant flag: the draw's emission is injected as a light (no voxel emission).
pub const EMITTER_LIGHT: u32 = 4;

pub struct Voxelizer {
    pub pipeline: Pipeline,
    static_target: Set,
    dynamic_target: Option<Set>,
    /// PAPER: zeroes the dynamic voxels (where the flag is 0).
    clear_dynamic: Option<(Pipeline, Set)>,
}

impl Voxelizer {
    pub fn new(
        ctx: &Arc<Context>,
        pool: &DescriptorPool,
        volumes: &Volumes,
        scene_layout: &SetLayout,
        material_layout: &SetLayout,
        paper: bool,
    ) -> VkResult<Voxelizer> {
        let frag = vk::ShaderStageFlags::FRAGMENT;
        // Each pass reaches its words through its table of addresses (binding 0).
        let static_target = pool.set(frag, &[(0, Desc::Storage(&volumes.words[0]))])?;
        let dynamic_target = match &volumes.data {
            VoxelData::Sums {
                dynamic_sums: Some(_),
                ..
            } => Some(pool.set(frag, &[(0, Desc::Storage(&volumes.words[1]))])?),
            _ => None,
        };
        let clear_dynamic = match &volumes.data {
            VoxelData::Paper { flag: Some(_), .. } => {
                let set = pool.set(
                    vk::ShaderStageFlags::COMPUTE,
                    &[(0, Desc::Storage(&volumes.words[0]))],
                )?;
                let p = pipelines::compute(
                    ctx,
                    "clear_dynamic.comp",
                    &[&set.layout],
                    4,
                    &Spec(vec![]),
                )?;
                Some((p, set))
            }
            _ => None,
        };
        let (geom, frag_shader) = if paper {
            ("voxelize.geom:PAPER", "voxelize.frag:PAPER")
        } else {
            ("voxelize.geom", "voxelize.frag")
        };
        let pipeline = pipelines::graphics(
            ctx,
            &GraphicsDesc {
                name: "voxelize",
                shaders: &[
                    (vk::ShaderStageFlags::VERTEX, "voxelize.vert"),
                    (vk::ShaderStageFlags::GEOMETRY, geom),
                    (vk::ShaderStageFlags::FRAGMENT, frag_shader),
                ],
                sets: &[scene_layout, material_layout, &static_target.layout],
                push_size: crate::render::DRAW_PUSH_SIZE,
                spec: Spec(vec![]),
                vertex_input: &[0, 1, 2],
                color_formats: &[],
                depth_format: None,
                depth_bias: None,
                cull: vk::CullModeFlags::NONE,
            },
        )?;
        Ok(Voxelizer {
            pipeline,
            static_target,
            dynamic_target,
            clear_dynamic,
        })
    }

    /// Accesses of the voxel data by a pass that writes it from the fragment stage.
    fn declare<'g, 'a, 'r>(
        pass: crate::vk::graph::PassBuilder<'g, 'a, 'r>,
        volumes: &'r Volumes,
        dynamic: bool,
        access: Access,
    ) -> crate::vk::graph::PassBuilder<'g, 'a, 'r> {
        let mut pass = pass.buffer(&volumes.words[dynamic as usize], Access::GraphicsBufferRead);
        for b in volumes.data.written_by(dynamic) {
            pass = pass.buffer(b, access);
        }
        pass
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
        match (&volumes.data, dynamic, &self.clear_dynamic) {
            (
                VoxelData::Paper {
                    albedo,
                    normal,
                    emission,
                    flag,
                },
                true,
                Some((p, set)),
            ) => {
                let mut pass = g
                    .pass(name)
                    .buffer(&volumes.words[0], Access::ComputeStorageRead);
                for b in [Some(albedo), Some(normal), emission.as_ref()]
                    .into_iter()
                    .flatten()
                {
                    pass = pass.buffer(b, Access::ComputeStorageReadWrite);
                }
                if let Some(f) = flag {
                    pass = pass.buffer(f, Access::ComputeStorageRead);
                }
                pass.record(|cmd| unsafe {
                    d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, p.raw);
                    d.cmd_bind_descriptor_sets(
                        cmd,
                        vk::PipelineBindPoint::COMPUTE,
                        p.layout,
                        0,
                        &[set.raw],
                        &[],
                    );
                    let voxels = n * n * n;
                    d.cmd_push_constants(
                        cmd,
                        p.layout,
                        vk::ShaderStageFlags::COMPUTE,
                        0,
                        &voxels.to_le_bytes(),
                    );
                    // In rows: 65535 groups is all a dimension must allow (162^3 voxels).
                    let groups = voxels.div_ceil(64);
                    d.cmd_dispatch(cmd, groups.min(4096), groups.div_ceil(4096), 1);
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

    /// Voxelizes the static (or, with `dynamic`, the dynamic) geometry. `draw` binds the scene
    /// and material sets and draws the instances of that kind with the given flags.
    #[allow(clippy::too_many_arguments)]
    pub fn record_voxelize(
        &self,
        ctx: &Context,
        g: &mut Graph,
        volumes: &Volumes,
        gpu: &GpuScene,
        dynamic: bool,
        name: &str,
        draw: &dyn Fn(vk::CommandBuffer, &Pipeline, u32),
    ) {
        let d = &ctx.device;
        let n = volumes.grid.resolution;
        let mut pass = Self::declare(
            g.pass(name),
            volumes,
            dynamic,
            Access::FragmentStorageReadWrite,
        )
        .buffer(&gpu.vertices, Access::VertexBuffer)
        .buffer(&gpu.indices, Access::IndexBuffer);
        for t in &gpu.textures {
            pass = pass.image(t, Access::FragmentSampled);
        }
        let target = if dynamic {
            self.dynamic_target.as_ref().unwrap_or(&self.static_target)
        } else {
            &self.static_target
        };
        pass.record(|cmd| unsafe {
            let info = vk::RenderingInfo::default()
                .render_area(pipelines::area(n, n))
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
            d.cmd_set_scissor(cmd, 0, &[pipelines::area(n, n)]);
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.pipeline.raw);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::GRAPHICS,
                self.pipeline.layout,
                2,
                &[target.raw],
                &[],
            );
            draw(cmd, &self.pipeline, if dynamic { 0 } else { STATIC_PASS });
            d.cmd_end_rendering(cmd);
        });
    }
}
