//! Step 2: voxel illumination. Direct light per voxel (shadowed by the shadow maps), plus
//! emission, into the radiance volume.

use super::volumes::Volumes;
use crate::render::pipelines::{self, Desc, DescriptorPool, Pipeline, Set, SetLayout, Spec};
use crate::vk::{vk, Access, Context, Graph, Image, VkResult};
use std::sync::Arc;

/// The voxel data as the compute passes read it (glsl/voxel_data.glsl): the address tables of
/// the static pass (binding 0) and the dynamic one (binding 2; zeros without dynamic geometry).
pub fn voxel_data_descs(volumes: &Volumes) -> Vec<(u32, Desc<'_>)> {
    vec![
        (0, Desc::Storage(&volumes.words[0])),
        (2, Desc::Storage(&volumes.words[1])),
    ]
}

/// Declares a compute read of the voxel data: the words through their addresses, and the
/// tables of addresses.
pub fn read_voxel_data<'g, 'a, 'r>(
    mut pass: crate::vk::graph::PassBuilder<'g, 'a, 'r>,
    volumes: &'r Volumes,
) -> crate::vk::graph::PassBuilder<'g, 'a, 'r> {
    for b in volumes.words.iter().chain(volumes.data.read_by_shaders()) {
        pass = pass.buffer(b, Access::ComputeStorageRead);
    }
    pass
}

pub struct Inject {
    pipeline: Pipeline,
    set: Set,
}

impl Inject {
    pub fn new(
        ctx: &Arc<Context>,
        pool: &DescriptorPool,
        volumes: &Volumes,
        scene_layout: &SetLayout,
        shadow_map: (vk::ImageView, vk::Sampler),
        paper: bool,
    ) -> VkResult<Inject> {
        let mut descs = voxel_data_descs(volumes);
        descs.push((4, Desc::Sampled(shadow_map.0, shadow_map.1)));
        descs.push((5, Desc::StorageImage(volumes.radiance.view)));
        if let Some(dir) = &volumes.emit_dir {
            descs.push((6, Desc::StorageImage(dir.view)));
        }
        if let Some(small) = &volumes.small_emission {
            descs.push((10, Desc::StorageImage(small.view)));
        }
        let set = pool.set(vk::ShaderStageFlags::COMPUTE, &descs)?;
        let shader = if paper {
            "inject_radiance.comp:PAPER"
        } else {
            "inject_radiance.comp"
        };
        let pipeline =
            pipelines::compute(ctx, shader, &[scene_layout, &set.layout], 0, &Spec(vec![]))?;
        Ok(Inject { pipeline, set })
    }

    pub fn record(
        &self,
        ctx: &Context,
        g: &mut Graph,
        volumes: &Volumes,
        scene_set: vk::DescriptorSet,
        shadow_map: &Image,
        name: &str,
    ) {
        let d = &ctx.device;
        let n = volumes.grid.resolution;
        let mut pass = read_voxel_data(g.pass(name), volumes)
            .image(shadow_map, Access::ComputeSampled)
            .image(&volumes.radiance, Access::ComputeStorageWrite);
        if let Some(dir) = &volumes.emit_dir {
            pass = pass.image(dir, Access::ComputeStorageWrite);
        }
        if let Some(small) = &volumes.small_emission {
            pass = pass.image(small, Access::ComputeStorageWrite);
        }
        pass.record(|cmd| unsafe {
            self.pipeline
                .bind_compute(d, cmd, &[scene_set, self.set.raw]);
            let groups = n.div_ceil(4);
            d.cmd_dispatch(cmd, groups, groups, groups);
        });
    }
}
