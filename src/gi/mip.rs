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
        let levels = volumes.grid.mip_levels(paper);
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

    /// Zeroes the directional volumes where they reach past the grid (a padded base level,
    /// VoxelGrid::aniso_resolution): the mip passes write only the texels over the grid, and
    /// the coarser levels and the cones' samples at the grid's edge read these as empty.
    /// Needed once, before the first mip pass; nothing else writes there.
    pub fn record_clear_padding(&self, ctx: &Context, g: &mut Graph, volumes: &Volumes) {
        if volumes.faces[0].desc.extent.width == volumes.grid.texels_over_grid() {
            return;
        }
        let d = &ctx.device;
        let mut pass = g.pass("clear directional padding").untimed();
        let images: Vec<&crate::vk::Image> = volumes.directional().collect();
        for f in &images {
            pass = pass.image(f, Access::TransferWrite);
        }
        pass.record(|cmd| unsafe {
            for f in &images {
                d.cmd_clear_color_image(
                    cmd,
                    f.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &vk::ClearColorValue { float32: [0.0; 4] },
                    &[f.full_range()],
                );
            }
        });
    }

    /// `suffix` tells the passes after the bounce apart in timings.
    pub fn record(&self, ctx: &Context, g: &mut Graph, volumes: &Volumes, suffix: &str) {
        let d = &ctx.device;
        // Texels over the grid, at the base level and then each level: those past it (a padded
        // base level) stay as record_clear_padding left them.
        let m = volumes.grid.texels_over_grid();
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
                let over_grid = m.div_ceil(1 << level);
                pass.record(|cmd| dispatch(cmd, p, set, over_grid));
            }
        }
    }
}
