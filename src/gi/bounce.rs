//! The second bounce: each voxel gathers light from the directional volumes with diffuse cones
//! and adds what it reflects to its radiance (then the mips run again). The last bounce also
//! adds the bounces not traced, as a geometric series (glsl/bounce_tail.comp).

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
    /// Except for --paper, which adds a voxel's bounce light as it gathers it.
    tail: Option<Tail>,
}

/// What the gather leaves for bounce_tail.comp, which adds it to the voxels.
struct Tail {
    pipeline: Pipeline,
    /// Per listed voxel, the light it reflects (four half floats).
    reflected: Buffer,
    /// Sums over the listed voxels of albedo times closed share, and their count (64-bit fixed
    /// point each).
    reflectance: Buffer,
    /// Whether the last bounce adds the bounces after it (GiSettings::tail).
    enabled: bool,
}

/// Bytes of the reflectance sums: r, g, b and count, two words each.
const REFLECTANCE_BYTES: u64 = 32;

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
        tail: bool,
    ) -> VkResult<Bounce> {
        let capacity = list_capacity(volumes.grid.resolution);
        let list = Buffer::new(
            ctx,
            "voxel list",
            16 + 4 * capacity,
            vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::INDIRECT_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        let buffers = if paper {
            None
        } else {
            let reflected = Buffer::new(
                ctx,
                "bounce reflected",
                8 * capacity,
                vk::BufferUsageFlags::STORAGE_BUFFER,
                MemoryLocation::GpuOnly,
            )?;
            let reflectance = Buffer::new(
                ctx,
                "bounce reflectance",
                REFLECTANCE_BYTES,
                vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuOnly,
            )?;
            Some((reflected, reflectance))
        };
        let mut descs = voxel_data_descs(volumes);
        descs.push((5, Desc::StorageImage(volumes.radiance.view)));
        descs.push((6, Desc::Storage(&list)));
        if let Some(dir) = &volumes.emit_dir {
            descs.push((9, Desc::StorageImage(dir.view)));
        }
        if let Some((reflected, reflectance)) = &buffers {
            descs.push((11, Desc::Storage(reflected)));
            descs.push((12, Desc::Storage(reflectance)));
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
        let tail = match buffers {
            Some((reflected, reflectance)) => Some(Tail {
                pipeline: pipelines::compute(
                    ctx,
                    "bounce_tail.comp",
                    &[scene_layout, &set.layout],
                    4,
                    &Spec(vec![]),
                )?,
                reflected,
                reflectance,
                enabled: tail,
            }),
            None => None,
        };
        Ok(Bounce {
            list_pipeline,
            pipeline,
            set,
            cone_set,
            list,
            tail,
        })
    }

    /// Clears the list's count and dispatch arguments.
    pub fn record_list_clear(&self, ctx: &Context, g: &mut Graph, name: &str) {
        g.pass(name)
            .buffer(&self.list, Access::TransferWrite)
            .record(|cmd| unsafe {
                // Dispatch (0, 1, 1), count 0.
                ctx.device
                    .cmd_update_buffer(cmd, self.list.raw, 0, as_bytes(&[0u32, 1, 1, 0]));
            });
    }

    /// Lists the filled voxels (the list holds until the voxels change: static ones once,
    /// dynamic ones every frame).
    pub fn record_list(
        &self,
        ctx: &Context,
        g: &mut Graph,
        volumes: &Volumes,
        scene_set: vk::DescriptorSet,
        name: &str,
    ) {
        read_voxel_data(g.pass(name), volumes)
            .buffer(&self.list, Access::ComputeStorageReadWrite)
            .record(|cmd| unsafe {
                self.list_pipeline
                    .bind_compute(&ctx.device, cmd, &[scene_set, self.set.raw]);
                let groups = volumes.grid.resolution.div_ceil(4);
                ctx.device.cmd_dispatch(cmd, groups, groups, groups);
            });
    }

    /// Whether the gather leaves its light to an add pass and sums the reflectance (all but
    /// --paper, whose gather adds to the radiance itself).
    pub fn adds_separately(&self) -> bool {
        self.tail.is_some()
    }

    /// Clears the reflectance sums the gather adds to.
    pub fn record_sums_clear(&self, ctx: &Context, g: &mut Graph, name: &str) {
        let Some(tail) = &self.tail else {
            return;
        };
        g.pass(name)
            .buffer(&tail.reflectance, Access::TransferWrite)
            .record(|cmd| unsafe {
                ctx.device
                    .cmd_fill_buffer(cmd, tail.reflectance.raw, 0, REFLECTANCE_BYTES, 0);
            });
    }

    /// Each listed voxel gathers light from the directional volumes.
    pub fn record_gather(
        &self,
        ctx: &Context,
        g: &mut Graph,
        volumes: &Volumes,
        scene_set: vk::DescriptorSet,
        name: &str,
    ) {
        let mut pass =
            read_voxel_data(g.pass(name), volumes).buffer(&self.list, Access::ComputeIndirectRead);
        pass = match &self.tail {
            Some(tail) => pass
                .buffer(&tail.reflected, Access::ComputeStorageWrite)
                .buffer(&tail.reflectance, Access::ComputeStorageReadWrite),
            // --paper: the gather adds to the radiance itself.
            None => pass.image(&volumes.radiance, Access::ComputeStorageReadWrite),
        };
        for f in volumes.directional() {
            pass = pass.image(f, Access::ComputeSampled);
        }
        pass.record(|cmd| unsafe {
            self.pipeline.bind_compute(
                &ctx.device,
                cmd,
                &[scene_set, self.set.raw, self.cone_set.raw],
            );
            ctx.device.cmd_dispatch_indirect(cmd, self.list.raw, 0);
        });
    }

    /// Adds what the gather left to the voxels' radiance; `last`: the last bounce, which also
    /// adds the bounces not traced.
    pub fn record_add(
        &self,
        ctx: &Context,
        g: &mut Graph,
        volumes: &Volumes,
        scene_set: vk::DescriptorSet,
        last: bool,
        name: &str,
    ) {
        let d = &ctx.device;
        let Some(tail) = &self.tail else {
            return;
        };
        let mut pass = read_voxel_data(g.pass(name), volumes)
            .image(&volumes.radiance, Access::ComputeStorageReadWrite)
            .buffer(&self.list, Access::ComputeIndirectRead)
            .buffer(&tail.reflected, Access::ComputeStorageRead)
            .buffer(&tail.reflectance, Access::ComputeStorageRead);
        if let Some(dir) = &volumes.emit_dir {
            pass = pass.image(dir, Access::ComputeStorageReadWrite);
        }
        let push = u32::from(last && tail.enabled);
        pass.record(|cmd| unsafe {
            tail.pipeline
                .bind_compute(d, cmd, &[scene_set, self.set.raw]);
            d.cmd_push_constants(
                cmd,
                tail.pipeline.layout,
                tail.pipeline.push_stages,
                0,
                as_bytes(&[push]),
            );
            d.cmd_dispatch_indirect(cmd, self.list.raw, 0);
        });
    }
}
