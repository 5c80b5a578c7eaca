//! Step 4: cone tracing per pixel (indirect diffuse, specular, ambient occlusion) added to the
//! direct light, and the debug views of the volumes.

use super::bounce::cone_set;
use super::inject::{read_voxel_data, voxel_data_descs};
use super::volumes::Volumes;
use crate::render::pipelines::{self, Desc, DescriptorPool, Pipeline, Set, SetLayout, Spec};
use crate::vk::{vk, Access, Context, Graph, Image, VkResult};
use std::sync::Arc;

/// What the trace pass writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TraceMode {
    Full = 0,
    Indirect = 1,
    Ao = 2,
    /// Debug views: the first voxel along each camera ray.
    VoxelAlbedo = 10,
    VoxelNormal = 11,
    VoxelEmission = 12,
    VoxelRadiance = 13,
    /// The directional volumes at frame.trace.w's mip level.
    Directional = 14,
}

/// The trace set's frame-sized images: the G-buffer (bindings 0 to 4) and the output (5).
fn frame_descs<'a>(
    gbuffer: &[(vk::ImageView, vk::Sampler)],
    out: &'a Image,
) -> Vec<(u32, Desc<'a>)> {
    let mut descs: Vec<(u32, Desc)> = gbuffer
        .iter()
        .enumerate()
        .map(|(i, &(v, s))| (i as u32, Desc::Sampled(v, s)))
        .collect();
    descs.push((5, Desc::StorageImage(out.view)));
    descs
}

pub struct Trace {
    trace: Pipeline,
    trace_set: Set,
    view: Pipeline,
    view_set: Set,
    cones: Set,
}

impl Trace {
    pub fn new(
        ctx: &Arc<Context>,
        pool: &DescriptorPool,
        volumes: &Volumes,
        scene_layout: &SetLayout,
        gbuffer: &[(vk::ImageView, vk::Sampler)],
        out: &Image,
        paper: bool,
    ) -> VkResult<Trace> {
        let comp = vk::ShaderStageFlags::COMPUTE;
        let trace_set = pool.set(comp, &frame_descs(gbuffer, out))?;
        let cones = cone_set(pool, volumes, true)?;
        let v = |s: &str| {
            if paper {
                format!("{s}:PAPER")
            } else {
                s.to_string()
            }
        };
        let trace = pipelines::compute(
            ctx,
            &v("cone_trace.comp"),
            &[scene_layout, &trace_set.layout, &cones.layout],
            4,
            &Spec(vec![]),
        )?;
        let mut descs = voxel_data_descs(volumes);
        descs.push((5, Desc::StorageImage(out.view)));
        let view_set = pool.set(comp, &descs)?;
        let view = pipelines::compute(
            ctx,
            &v("voxel_view.comp"),
            &[scene_layout, &view_set.layout, &cones.layout],
            4,
            &Spec(vec![]),
        )?;
        Ok(Trace {
            trace,
            trace_set,
            view,
            view_set,
            cones,
        })
    }

    /// Points the passes at new G-buffer and output images (a resized frame). The sets must
    /// not be in use (the frames before have been waited for).
    pub fn retarget(&self, ctx: &Context, gbuffer: &[(vk::ImageView, vk::Sampler)], out: &Image) {
        pipelines::write_set(ctx, self.trace_set.raw, &frame_descs(gbuffer, out));
        pipelines::write_set(ctx, self.view_set.raw, &[(5, Desc::StorageImage(out.view))]);
    }

    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        ctx: &Context,
        g: &mut Graph,
        volumes: &Volumes,
        scene_set: vk::DescriptorSet,
        gbuffer: &[Image],
        out: &Image,
        mode: TraceMode,
        name: &str,
    ) {
        let d = &ctx.device;
        let (w, h) = (out.width(), out.height());
        let debug = (mode as u32) >= 10;
        let mut pass = if debug {
            read_voxel_data(g.pass(name), volumes).image(out, Access::ComputeStorageWrite)
        } else {
            let mut p = g.pass(name).image(out, Access::ComputeStorageReadWrite);
            for img in gbuffer {
                p = p.image(img, Access::ComputeSampled);
            }
            p
        };
        pass = pass.image(&volumes.radiance, Access::ComputeSampled);
        if let Some(dir) = &volumes.emit_dir {
            pass = pass.image(dir, Access::ComputeSampled);
        }
        for f in volumes.directional() {
            pass = pass.image(f, Access::ComputeSampled);
        }
        let (p, set, push) = if debug {
            (&self.view, &self.view_set, mode as u32 - 10)
        } else {
            (&self.trace, &self.trace_set, mode as u32)
        };
        pass.record(|cmd| unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, p.raw);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                p.layout,
                0,
                &[scene_set, set.raw, self.cones.raw],
                &[],
            );
            d.cmd_push_constants(
                cmd,
                p.layout,
                vk::ShaderStageFlags::COMPUTE,
                0,
                &push.to_le_bytes(),
            );
            d.cmd_dispatch(cmd, w.div_ceil(8), h.div_ceil(8), 1);
        });
    }
}
