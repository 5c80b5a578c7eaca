//! Step 3: anisotropic mipmapping. The radiance volume to six directional volumes at half
//! resolution, then each of their mip levels from the one before; beside them (not --paper),
//! where their light goes.

use super::volumes::Volumes;
use crate::render::pipelines::{self, Desc, DescriptorPool, Pipeline, Set, Spec};
use crate::vk::{vk, Access, Context, Graph, VkResult};
use std::sync::Arc;

pub struct Mip {
    base: Pipeline,
    base_set: Set,
    volume: Option<Pipeline>,
    /// One set per level from 1: reads level - 1, writes level.
    level_sets: Vec<Set>,
}

impl Mip {
    pub fn new(
        ctx: &Arc<Context>,
        pool: &DescriptorPool,
        volumes: &Volumes,
        paper: bool,
    ) -> VkResult<Mip> {
        let comp = vk::ShaderStageFlags::COMPUTE;
        let mut descs = vec![(0, Desc::StorageImage(volumes.radiance.view))];
        for (i, f) in volumes.faces.iter().enumerate() {
            descs.push((1 + i as u32, Desc::StorageImage(f.level_view(0))));
        }
        if let Some(dir) = &volumes.emit_dir {
            descs.push((7, Desc::StorageImage(dir.view)));
        }
        if let Some(small) = &volumes.small_emission {
            descs.push((10, Desc::StorageImage(small.view)));
        }
        if let Some(dir) = &volumes.light_dir {
            descs.push((8, Desc::StorageImage(dir.level_view(0))));
        }
        if let Some(pos) = &volumes.light_pos {
            descs.push((9, Desc::StorageImage(pos.level_view(0))));
        }
        let base_set = pool.set(comp, &descs)?;
        let v = |s: &str| {
            if paper {
                format!("{s}:PAPER")
            } else {
                s.to_string()
            }
        };
        let base = pipelines::compute(
            ctx,
            &v("aniso_mip_base.comp"),
            &[&base_set.layout],
            0,
            &Spec(vec![]),
        )?;
        let levels = volumes.grid.mip_levels();
        let mut level_sets = Vec::new();
        for level in 1..levels {
            let mut descs = Vec::new();
            for (i, f) in volumes.faces.iter().enumerate() {
                descs.push((i as u32, Desc::StorageImage(f.level_view(level - 1))));
                descs.push((6 + i as u32, Desc::StorageImage(f.level_view(level))));
            }
            if let Some(dir) = &volumes.light_dir {
                descs.push((12, Desc::StorageImage(dir.level_view(level - 1))));
                descs.push((13, Desc::StorageImage(dir.level_view(level))));
            }
            if let Some(pos) = &volumes.light_pos {
                descs.push((14, Desc::StorageImage(pos.level_view(level - 1))));
                descs.push((15, Desc::StorageImage(pos.level_view(level))));
            }
            level_sets.push(pool.set(comp, &descs)?);
        }
        let volume = match level_sets.first() {
            Some(s) => Some(pipelines::compute(
                ctx,
                &v("aniso_mip_volume.comp"),
                &[&s.layout],
                0,
                &Spec(vec![]),
            )?),
            None => None,
        };
        Ok(Mip {
            base,
            base_set,
            volume,
            level_sets,
        })
    }

    /// `suffix` tells the passes after the bounce apart in timings.
    pub fn record(&self, ctx: &Context, g: &mut Graph, volumes: &Volumes, suffix: &str) {
        let d = &ctx.device;
        let m = volumes.grid.aniso_resolution();
        let dispatch = |cmd, p: &Pipeline, set: &Set, size: u32| unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, p.raw);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                p.layout,
                0,
                &[set.raw],
                &[],
            );
            let groups = size.div_ceil(4);
            d.cmd_dispatch(cmd, groups, groups, groups);
        };
        let base_name = format!("mip base{suffix}");
        let mut pass = g
            .pass(&base_name)
            .image(&volumes.radiance, Access::ComputeStorageRead);
        if let Some(dir) = &volumes.emit_dir {
            pass = pass.image(dir, Access::ComputeStorageRead);
        }
        if let Some(small) = &volumes.small_emission {
            pass = pass.image(small, Access::ComputeStorageRead);
        }
        for f in volumes.directional() {
            pass = pass.image(f, Access::ComputeStorageWrite);
        }
        pass.record(|cmd| dispatch(cmd, &self.base, &self.base_set, m));

        let name = format!("mip volume{suffix}");
        if let Some(p) = &self.volume {
            for (i, set) in self.level_sets.iter().enumerate() {
                let level = i as u32 + 1;
                let mut pass = g.pass(&name);
                for f in volumes.directional() {
                    pass = pass.image(f, Access::ComputeStorageReadWrite);
                }
                let size = (m >> level).max(1);
                pass.record(|cmd| dispatch(cmd, p, set, size));
            }
        }
    }
}
