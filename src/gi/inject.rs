//! Step 2: voxel illumination. Direct light per voxel (shadowed by the shadow maps), plus
//! emission, into the radiance volume.

use super::volumes::{Volumes, VoxelData};
use crate::render::pipelines::{self, Desc, DescriptorPool, Pipeline, Set, SetLayout, Spec};
use crate::vk::{vk, Access, Context, Graph, Image, VkResult};
use std::sync::Arc;

/// The voxel data as the compute passes read it (bindings 0 to 3, 7 and 8 of
/// glsl/voxel_data.glsl).
pub fn voxel_data_descs<'a>(volumes: &'a Volumes) -> Vec<(u32, Desc<'a>)> {
    match &volumes.data {
        VoxelData::Sums {
            static_sums: s,
            dynamic_sums: d,
        } => {
            let or_dummy = |b: Option<&'a crate::vk::Buffer>, i: usize| {
                Desc::Storage(b.unwrap_or(&volumes.dummies[i]))
            };
            vec![
                (0, Desc::Storage(&s.albedo)),
                (1, or_dummy(s.emission.as_ref(), 1)),
                (2, or_dummy(d.as_ref().map(|d| &d.albedo), 2)),
                (3, or_dummy(d.as_ref().and_then(|d| d.emission.as_ref()), 3)),
                (7, Desc::Storage(&s.normal)),
                (8, or_dummy(d.as_ref().map(|d| &d.normal), 4)),
            ]
        }
        VoxelData::Paper {
            albedo,
            normal,
            emission,
            ..
        } => vec![
            (0, Desc::Storage(albedo)),
            (1, Desc::Storage(normal)),
            (
                2,
                Desc::Storage(emission.as_ref().unwrap_or(&volumes.dummies[2])),
            ),
        ],
    }
}

/// Declares a compute read of the voxel data.
pub fn read_voxel_data<'g, 'a, 'r>(
    mut pass: crate::vk::graph::PassBuilder<'g, 'a, 'r>,
    volumes: &'r Volumes,
) -> crate::vk::graph::PassBuilder<'g, 'a, 'r> {
    for b in volumes.dummies.iter().chain(volumes.data.read_by_shaders()) {
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
        suffix: &str,
    ) {
        let d = &ctx.device;
        let n = volumes.grid.resolution;
        let name = format!("inject{suffix}");
        let mut pass = read_voxel_data(g.pass(&name), volumes)
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
