//! The second bounce: each voxel gathers light from the directional volumes with diffuse cones
//! and adds what it reflects to its radiance (then the mips run again).

use super::inject::{read_voxel_data, voxel_data_descs};
use super::volumes::Volumes;
use crate::render::pipelines::{self, Desc, DescriptorPool, Pipeline, Set, SetLayout, Spec};
use crate::vk::{vk, Access, Context, Graph, VkResult};
use std::sync::Arc;

pub struct Bounce {
    pipeline: Pipeline,
    set: Set,
    cone_set: Set,
}

/// The directional volumes as cones sample them (bindings 1 to 6), with the full-resolution
/// radiance volume at binding 0 when `full_res`.
pub fn cone_set(pool: &DescriptorPool, volumes: &Volumes, full_res: bool) -> VkResult<Set> {
    let s = volumes.sampler.raw;
    let mut descs = Vec::new();
    if full_res {
        descs.push((0, Desc::Sampled(volumes.radiance.view, s)));
    }
    for (i, f) in volumes.faces.iter().enumerate() {
        descs.push((1 + i as u32, Desc::Sampled(f.view, s)));
    }
    pool.set(vk::ShaderStageFlags::COMPUTE, &descs)
}

impl Bounce {
    pub fn new(
        ctx: &Arc<Context>,
        pool: &DescriptorPool,
        volumes: &Volumes,
        scene_layout: &SetLayout,
        paper: bool,
    ) -> VkResult<Bounce> {
        let mut descs = voxel_data_descs(volumes);
        descs.push((5, Desc::StorageImage(volumes.radiance.view)));
        let set = pool.set(vk::ShaderStageFlags::COMPUTE, &descs)?;
        let cone_set = cone_set(pool, volumes, false)?;
        let shader = if paper {
            "inject_bounce.comp:PAPER"
        } else {
            "inject_bounce.comp"
        };
        let pipeline = pipelines::compute(
            ctx,
            shader,
            &[scene_layout, &set.layout, &cone_set.layout],
            0,
            &Spec(vec![]),
        )?;
        Ok(Bounce {
            pipeline,
            set,
            cone_set,
        })
    }

    pub fn record(
        &self,
        ctx: &Context,
        g: &mut Graph,
        volumes: &Volumes,
        scene_set: vk::DescriptorSet,
    ) {
        let d = &ctx.device;
        let n = volumes.grid.resolution;
        let mut pass = read_voxel_data(g.pass("bounce"), volumes)
            .image(&volumes.radiance, Access::ComputeStorageReadWrite);
        for f in &volumes.faces {
            pass = pass.image(f, Access::ComputeSampled);
        }
        pass.record(|cmd| unsafe {
            let p = &self.pipeline;
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, p.raw);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                p.layout,
                0,
                &[scene_set, self.set.raw, self.cone_set.raw],
                &[],
            );
            let groups = n.div_ceil(4);
            d.cmd_dispatch(cmd, groups, groups, groups);
        });
    }
}
