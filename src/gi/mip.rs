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

    /// The directional volumes' base level from the radiance volume.
    pub fn record_base(&self, ctx: &Context, g: &mut Graph, volumes: &Volumes, name: &str) {
        let mut pass = g
            .pass(name)
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
        let size = volumes.grid.aniso_resolution();
        pass.record(|cmd| dispatch(ctx, cmd, &self.base, &self.base_set, size));
    }

    /// Each mip level of the directional volumes from the one before (a pass per level).
    pub fn record_levels(&self, ctx: &Context, g: &mut Graph, volumes: &Volumes, name: &str) {
        let Some(p) = &self.volume else {
            return;
        };
        let m = volumes.grid.aniso_resolution();
        for (i, set) in self.level_sets.iter().enumerate() {
            let level = i as u32 + 1;
            let mut pass = g.pass(name);
            for f in volumes.directional() {
                pass = pass.image(f, Access::ComputeStorageReadWrite);
            }
            let size = (m >> level).max(1);
            pass.record(|cmd| dispatch(ctx, cmd, p, set, size));
        }
    }
}

/// Binds `p` with `set` and dispatches over a `size`^3 volume.
fn dispatch(ctx: &Context, cmd: vk::CommandBuffer, p: &Pipeline, set: &Set, size: u32) {
    let groups = size.div_ceil(4);
    unsafe {
        p.bind_compute(&ctx.device, cmd, &[set.raw]);
        ctx.device.cmd_dispatch(cmd, groups, groups, groups);
    }
}
