//! The second bounce: each voxel gathers light from the directional volumes with diffuse cones
//! and adds what it reflects to its radiance (then the mips run again).

use super::inject::{read_voxel_data, voxel_data_descs};
use super::volumes::Volumes;
use crate::render::gpu::as_bytes;
use crate::render::pipelines::{self, Desc, DescriptorPool, Pipeline, Set, SetLayout, Spec};
use crate::vk::{vk, Access, Buffer, Context, Graph, VkResult};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

pub struct Bounce {
    list_pipeline: Pipeline,
    pipeline: Pipeline,
    set: Set,
    cone_set: Set,
    /// The filled voxels (voxel_list.comp), after the bounce's dispatch arguments and count.
    list: Buffer,
}

/// Room in the voxel list: every voxel of a small grid; surfaces (about N^2 per side of the
/// grid they cross) beyond that, so that 512^3 stays within a 128 MiB storage buffer.
fn list_capacity(n: u32) -> u64 {
    let n = n as u64;
    (n * n * n).min(64 * n * n)
}

/// The directional volumes as cones sample them (bindings 1 to 6) and where their light goes
/// (7, except for --paper), with the full-resolution radiance volume at binding 0 when
/// `full_res`.
pub fn cone_set(pool: &DescriptorPool, volumes: &Volumes, full_res: bool) -> VkResult<Set> {
    let s = volumes.sampler.raw;
    let mut descs = Vec::new();
    if full_res {
        descs.push((0, Desc::Sampled(volumes.radiance.view, s)));
        if let Some(dir) = &volumes.emit_dir {
            descs.push((8, Desc::Sampled(dir.view, s)));
        }
    }
    for (i, f) in volumes.faces.iter().enumerate() {
        descs.push((1 + i as u32, Desc::Sampled(f.view, s)));
    }
    if let Some(dir) = &volumes.light_dir {
        descs.push((7, Desc::Sampled(dir.view, s)));
    }
    if let Some(pos) = &volumes.light_pos {
        descs.push((9, Desc::Sampled(pos.view, s)));
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
        let list = Buffer::new(
            ctx,
            "voxel list",
            16 + 4 * list_capacity(volumes.grid.resolution),
            vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::INDIRECT_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        let mut descs = voxel_data_descs(volumes);
        descs.push((5, Desc::StorageImage(volumes.radiance.view)));
        descs.push((6, Desc::Storage(&list)));
        if let Some(dir) = &volumes.emit_dir {
            descs.push((9, Desc::StorageImage(dir.view)));
        }
        let set = pool.set(vk::ShaderStageFlags::COMPUTE, &descs)?;
        let cone_set = cone_set(pool, volumes, false)?;
        let variant = |name: &str| {
            if paper {
                format!("{name}:PAPER")
            } else {
                name.to_string()
            }
        };
        let list_pipeline = pipelines::compute(
            ctx,
            &variant("voxel_list.comp"),
            &[scene_layout, &set.layout],
            0,
            &Spec(vec![]),
        )?;
        let shader = variant("inject_bounce.comp");
        let pipeline = pipelines::compute(
            ctx,
            &shader,
            &[scene_layout, &set.layout, &cone_set.layout],
            0,
            &Spec(vec![]),
        )?;
        Ok(Bounce {
            list_pipeline,
            pipeline,
            set,
            cone_set,
            list,
        })
    }

    pub fn record(
        &self,
        ctx: &Context,
        g: &mut Graph,
        volumes: &Volumes,
        scene_set: vk::DescriptorSet,
        voxels_changed: bool,
        name: &str,
    ) {
        let d = &ctx.device;
        // The list holds until the voxels change (static ones once, dynamic ones every frame).
        if voxels_changed {
            self.record_list(d, g, volumes, scene_set);
        }
        let mut pass = read_voxel_data(g.pass(name), volumes)
            .image(&volumes.radiance, Access::ComputeStorageReadWrite)
            .buffer(&self.list, Access::ComputeIndirectRead);
        if let Some(dir) = &volumes.emit_dir {
            pass = pass.image(dir, Access::ComputeStorageReadWrite);
        }
        for f in volumes.directional() {
            pass = pass.image(f, Access::ComputeSampled);
        }
        pass.record(|cmd| unsafe {
            self.pipeline
                .bind_compute(d, cmd, &[scene_set, self.set.raw, self.cone_set.raw]);
            d.cmd_dispatch_indirect(cmd, self.list.raw, 0);
        });
    }

    /// Clears the list's count and dispatch, then lists the filled voxels.
    fn record_list(
        &self,
        d: &ash::Device,
        g: &mut Graph,
        volumes: &Volumes,
        scene_set: vk::DescriptorSet,
    ) {
        g.pass("voxel list clear")
            .buffer(&self.list, Access::TransferWrite)
            .untimed()
            .record(|cmd| unsafe {
                // Dispatch (0, 1, 1), count 0.
                d.cmd_update_buffer(cmd, self.list.raw, 0, as_bytes(&[0u32, 1, 1, 0]));
            });
        read_voxel_data(g.pass("voxel list"), volumes)
            .buffer(&self.list, Access::ComputeStorageReadWrite)
            .record(|cmd| unsafe {
                self.list_pipeline
                    .bind_compute(d, cmd, &[scene_set, self.set.raw]);
                let groups = volumes.grid.resolution.div_ceil(4);
                d.cmd_dispatch(cmd, groups, groups, groups);
            });
    }
}
