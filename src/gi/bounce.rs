//! The second bounce: each voxel gathers light from the directional volumes with diffuse cones
//! and adds what it reflects to its radiance (then the mips run again). The last bounce also
//! adds the bounces not traced, as a geometric series (glsl/bounce_tail.comp).

use super::inject::{read_voxel_data, variant};
use super::volumes::{Volumes, BOUNCE_BLOCK};
use super::GiSettings;
use crate::vk::{vk, Access, Bindings, Buffer, Context, Graph, Pass, SharedSet, Usage, VkResult};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

pub struct Bounce {
    list_pass: Pass,
    gather: Pass,
    /// Each block of voxels gathers once for its one-sided voxels in a plane, before the
    /// gather (`GiSettings::bounce_share`; inject_bounce.comp's SHARE).
    share: Option<Pass>,
    /// The filled voxels (voxel_list.comp), after the bounce's dispatch arguments and count.
    list: Buffer,
    /// Entries the list holds.
    capacity: u64,
    /// The count the last listing reached (copied after it; it counts past the capacity).
    count: Buffer,
    /// Except for --paper, which adds a voxel's bounce light as it gathers it.
    tail: Option<Tail>,
}

/// What the gather leaves for bounce_tail.comp, which adds it to the voxels.
struct Tail {
    /// Instance k reads what bounce k (mod 2) reflected, and the bounce before's.
    pass: Pass,
    /// Per listed voxel, the light it reflects (four half floats), written by the bounces in
    /// turn: the last bounce's tail follows only the order of light that bounce added (its
    /// light less the bounce before's), since the orders before it are traced.
    reflected: [Buffer; 2],
    /// Sums over the listed voxels of albedo times closed share, and their count (64-bit fixed
    /// point each).
    reflectance: Buffer,
    /// Whether the last bounce adds the bounces after it (GiSettings::tail).
    enabled: bool,
}

/// Bytes of the tail's sums (glsl/inject_bounce.comp): r, g, b and their weight, two words
/// each, over the voxels' fronts and then over the open backs, weighted by the light each
/// voxel gathered and then evenly (checked against the shaders' REFLECTANCE_WORDS).
const REFLECTANCE_BYTES: u64 = 128;

/// The first room in the voxel list: every voxel of a small grid; surfaces (about N^2 per side
/// of the grid they cross) beyond that, so that 512^3 starts within a 128 MiB storage buffer. A
/// frame that lists more grows it ([`Bounce::overflow`], `Gi::fit_voxel_list`).
pub fn list_capacity(n: u32) -> u64 {
    let n = n as u64;
    (n * n * n).min(64 * n * n)
}

/// The most a list can hold: every voxel, within what one storage buffer may span and one
/// allocation may take (each entry 4 bytes in the list and, but for --paper, 8 in what the
/// gather leaves, 16 with the backs' light).
pub fn list_capacity_limit(ctx: &Context, n: u32, paper: bool, backs: bool) -> u64 {
    let entry = match (paper, backs) {
        (true, _) => 4,
        (false, false) => 8,
        // A second entry a voxel for its back's light.
        (false, true) => 16,
    };
    let span = (ctx.properties.limits.max_storage_buffer_range as u64).min(ctx.max_allocation);
    (n as u64).pow(3).min((span - 16) / entry)
}

/// The directional volumes as cones sample them (glsl/cone_tracing.glsl), and where their
/// light goes (except for --paper); with `full_res`, also the full-resolution radiance volume
/// and its light directions.
pub fn cone_volumes(table: Bindings, volumes: &Volumes, full_res: bool) -> Bindings {
    let s = &volumes.sampler;
    let mut t = table;
    if full_res {
        t = t
            .sampled("radiance_tex", &volumes.radiance, s)
            .with(volumes.emit_dir.as_ref(), |t, d| {
                t.sampled("emit_dir_tex", d, s)
            })
            .with(volumes.back_radiance.as_ref(), |t, b| {
                t.sampled("back_radiance_tex", b, s)
            });
    }
    for (f, name) in volumes
        .faces
        .iter()
        .zip(["nx", "px", "ny", "py", "nz", "pz"])
    {
        t = t.sampled(&format!("aniso_{name}"), f, s);
    }
    t.with(volumes.light_dir.as_ref(), |t, d| {
        t.sampled("light_dir", d, s)
    })
    .with(volumes.light_pos.as_ref(), |t, p| {
        t.sampled("light_pos", p, s)
    })
    .with(volumes.thin_walls.as_ref(), |t, [a, b]| {
        let s = &volumes.level_sampler;
        t.sampled("thin_walls_xy", a, s)
            .sampled("thin_walls_z", b, s)
    })
    .with(volumes.empty_space.as_ref(), |t, e| {
        t.image("empty_space", e, Usage::Read)
    })
}

impl Bounce {
    pub fn new(
        ctx: &Arc<Context>,
        scene: &SharedSet,
        volumes: &Volumes,
        settings: &GiSettings,
        capacity: u64,
    ) -> VkResult<Bounce> {
        let (paper, tail, bounces) = (settings.paper, settings.tail, settings.bounces);
        let count = Buffer::readback(ctx, "voxel list count", 4)?;
        let list = Buffer::new(
            ctx,
            "voxel list",
            16 + 4 * capacity,
            vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::INDIRECT_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST
                | vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
        )?;
        let buffers = if paper {
            None
        } else {
            // The second is written from the third bounce on (odd bounces); with two it is
            // bound but neither written nor read.
            // With the backs' light a second entry a voxel.
            let per_voxel = if volumes.holds_backs() { 16 } else { 8 };
            let reflected = |k: usize| {
                let entries = if k == 0 || bounces >= 3 { capacity } else { 1 };
                Buffer::new(
                    ctx,
                    &format!("bounce reflected {k}"),
                    per_voxel * entries,
                    vk::BufferUsageFlags::STORAGE_BUFFER,
                    MemoryLocation::GpuOnly,
                )
            };
            let reflected = [reflected(0)?, reflected(1)?];
            let reflectance = Buffer::new(
                ctx,
                "bounce reflectance",
                REFLECTANCE_BYTES,
                vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
                MemoryLocation::GpuOnly,
            )?;
            Some((reflected, reflectance))
        };
        let list_pass = Pass::compute(
            ctx,
            &variant("voxel_list.comp", paper),
            &[scene],
            read_voxel_data(Bindings::new(), volumes).buffer("VoxelList", &list, Usage::ReadWrite),
            0,
        )?;
        let gather = |k: usize| {
            let t = read_voxel_data(Bindings::new(), volumes)
                .buffer("VoxelList", &list, Usage::Indirect)
                .with(buffers.as_ref(), |t, (reflected, reflectance)| {
                    t.buffer("Reflected", &reflected[k], Usage::Write).buffer(
                        "Reflectance",
                        reflectance,
                        Usage::ReadWrite,
                    )
                });
            // --paper: the gather adds to the radiance itself.
            let t = if paper {
                t.image("radiance", &volumes.radiance, Usage::ReadWrite)
            } else {
                t
            };
            let t = t.with(volumes.bounce_blocks.as_ref(), |t, [g, f]| {
                t.image("block_gather", g, Usage::Read)
                    .image("block_first", f, Usage::Read)
            });
            cone_volumes(t, volumes, false)
        };
        let instances = if paper { 1 } else { 2 };
        let gather = Pass::new(
            ctx,
            crate::vk::Program::Compute(&variant("inject_bounce.comp", paper)),
            &[scene],
            (0..instances).map(gather).collect(),
            0,
        )?;
        let share = match &volumes.bounce_blocks {
            Some([gathers, firsts]) if settings.bounce_share => {
                let t = read_voxel_data(Bindings::new(), volumes)
                    .image("block_gather", gathers, Usage::Write)
                    .image("block_first", firsts, Usage::Write);
                Some(Pass::compute(
                    ctx,
                    "inject_bounce.comp:SHARE",
                    &[scene],
                    cone_volumes(t, volumes, false),
                    0,
                )?)
            }
            _ => None,
        };
        let tail = match buffers {
            Some((reflected, reflectance)) => {
                let add = |k: usize| {
                    read_voxel_data(Bindings::new(), volumes)
                        .image("radiance", &volumes.radiance, Usage::ReadWrite)
                        .buffer("VoxelList", &list, Usage::Indirect)
                        .buffer("Reflected", &reflected[k], Usage::Read)
                        .buffer("ReflectedBefore", &reflected[1 - k], Usage::Read)
                        .buffer("Reflectance", &reflectance, Usage::Read)
                        .with(volumes.emit_dir.as_ref(), |t, d| {
                            t.image("emit_dir", d, Usage::ReadWrite)
                        })
                        .with(volumes.back_radiance.as_ref(), |t, b| {
                            t.image("back_radiance", b, Usage::ReadWrite)
                        })
                        .with(volumes.glossy_radiance.as_ref(), |t, g| {
                            t.image("glossy_radiance", g, Usage::ReadWrite)
                        })
                };
                let pass = Pass::new(
                    ctx,
                    crate::vk::Program::Compute("bounce_tail.comp"),
                    &[scene],
                    vec![add(0), add(1)],
                    8,
                )?;
                Some(Tail {
                    pass,
                    reflected,
                    reflectance,
                    enabled: tail,
                })
            }
            None => None,
        };
        Ok(Bounce {
            list_pass,
            gather,
            share,
            list,
            capacity,
            count,
            tail,
        })
    }

    /// Clears the list's count and dispatch arguments.
    pub fn record_list_clear(&self, ctx: &Context, g: &mut Graph, name: &str) {
        super::record_list_clear(ctx, g, &self.list, name);
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
        let p = &self.list_pass;
        p.declare(g.pass(name), 0).record(|cmd| unsafe {
            p.bind(&ctx.device, cmd, &[(0, scene_set)], 0);
            let groups = volumes.grid.resolution.div_ceil(4);
            ctx.device.cmd_dispatch(cmd, groups, groups, groups);
        });
        // The count, for the host to see whether the list held every filled voxel.
        g.pass(name)
            .buffer(&self.list, Access::TransferRead)
            .buffer(&self.count, Access::TransferWrite)
            .record(|cmd| unsafe {
                let region = vk::BufferCopy::default().src_offset(12).size(4);
                ctx.device
                    .cmd_copy_buffer(cmd, self.list.raw, self.count.raw, &[region]);
            });
        g.barrier("voxel list count to host")
            .buffer(&self.count, Access::HostRead)
            .record(|_| {});
    }

    /// After a frame that listed the voxels: how many were filled, when the list could not
    /// hold them all (those beyond its capacity got no bounce).
    pub fn overflow(&self) -> Option<u64> {
        let bytes = self.count.mapped().expect("the count is host-visible");
        let count = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]) as u64;
        (count > self.capacity).then_some(count)
    }

    pub fn capacity(&self) -> u64 {
        self.capacity
    }

    /// Every buffer it made (for a graph's states to forget when it is freed).
    pub fn buffers(&self) -> Vec<vk::Buffer> {
        let mut v = vec![self.list.raw, self.count.raw];
        if let Some(t) = &self.tail {
            v.extend([t.reflected[0].raw, t.reflected[1].raw, t.reflectance.raw]);
        }
        v
    }

    /// Whether one-sided voxels share their gather within blocks (FLAG_BOUNCE_SHARE).
    pub fn shares(&self) -> bool {
        self.share.is_some()
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

    /// The instance bounce `bounce` (2 on) records with: which reflected buffer it writes.
    fn instance(&self, bounce: u32) -> usize {
        if self.tail.is_some() {
            (bounce % 2) as usize
        } else {
            0
        }
    }

    /// Each block of voxels gathers once for its one-sided voxels in a plane (with
    /// `GiSettings::bounce_share`; before each bounce's gather).
    pub fn record_share(
        &self,
        ctx: &Context,
        g: &mut Graph,
        volumes: &Volumes,
        scene_set: vk::DescriptorSet,
        name: &str,
    ) {
        let p = self
            .share
            .as_ref()
            .expect("a shared gather without sharing");
        // One invocation a block, in rows of at most 65535 groups of 64.
        let m = volumes.grid.resolution.div_ceil(BOUNCE_BLOCK) as u64;
        let groups = (m * m * m).div_ceil(64);
        let x = groups.min(65535);
        let y = groups.div_ceil(x);
        p.record_dispatch(
            ctx,
            g,
            name,
            &[(0, scene_set)],
            &[],
            [x as u32, y as u32, 1],
        );
    }

    /// Each listed voxel gathers light from the directional volumes (bounce `bounce`, 2 on).
    pub fn record_gather(
        &self,
        ctx: &Context,
        g: &mut Graph,
        scene_set: vk::DescriptorSet,
        bounce: u32,
        name: &str,
    ) {
        let p = &self.gather;
        let k = self.instance(bounce);
        p.declare(g.pass(name), k).record(|cmd| unsafe {
            p.bind(&ctx.device, cmd, &[(0, scene_set)], k);
            ctx.device.cmd_dispatch_indirect(cmd, self.list.raw, 0);
        });
    }

    /// Adds what bounce `bounce` (2 on) gathered to the voxels' radiance; `last`: the last
    /// bounce, which also adds the bounces not traced.
    pub fn record_add(
        &self,
        ctx: &Context,
        g: &mut Graph,
        scene_set: vk::DescriptorSet,
        bounce: u32,
        last: bool,
        name: &str,
    ) {
        let d = &ctx.device;
        let Some(tail) = &self.tail else {
            return;
        };
        // Whether a bounce before this one left its light in the other buffer.
        let push: Vec<u8> = [u32::from(last && tail.enabled), u32::from(bounce >= 3)]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let p = &tail.pass;
        let k = self.instance(bounce);
        p.declare(g.pass(name), k).record(|cmd| unsafe {
            p.bind(d, cmd, &[(0, scene_set)], k);
            p.pipeline.push(d, cmd, &push);
            d.cmd_dispatch_indirect(cmd, self.list.raw, 0);
        });
    }
}

#[cfg(test)]
mod tests {
    use super::REFLECTANCE_BYTES;
    use crate::vk::reflect::shader_interface;

    #[test]
    fn the_tail_sums_are_as_large_as_the_shaders_declare() {
        for shader in ["inject_bounce.comp", "bounce_tail.comp"] {
            let block = shader_interface(shader).unwrap();
            let sums = block
                .struct_named("Reflectance")
                .expect("the Reflectance block");
            assert_eq!(sums.size as u64, REFLECTANCE_BYTES, "{shader}");
        }
    }
}
