//! Step 3: anisotropic mipmapping. The radiance volume to six directional volumes at half
//! resolution, then each of their mip levels from the one before; beside them (not --paper),
//! where their light goes.

use super::inject::variant;
use super::volumes::Volumes;
use crate::vk::{vk, Bindings, Context, Graph, Pass, Usage, VkResult};
use std::sync::Arc;

/// The directional volumes' names in the shaders, in the order of `Volumes::faces`.
const FACES: [&str; 6] = ["nx", "px", "ny", "py", "nz", "pz"];

pub struct Mip {
    base: Pass,
    /// One instance per level from 1: reads level - 1, writes level.
    levels: Option<Pass>,
    paper: bool,
}

impl Mip {
    pub fn new(ctx: &Arc<Context>, volumes: &Volumes, paper: bool) -> VkResult<Mip> {
        let mut base = Bindings::new().image("radiance", &volumes.radiance, Usage::Read);
        for (f, name) in volumes.faces.iter().zip(FACES) {
            base = base.image_view(&format!("face_{name}"), f, f.level_view(0), Usage::Write);
        }
        let base = base
            .with(volumes.emit_dir.as_ref(), |t, d| {
                t.image("emit_dir", d, Usage::Read)
            })
            .with(volumes.small_emission.as_ref(), |t, s| {
                t.image("small_emission", s, Usage::Read)
            })
            .with(volumes.back_radiance.as_ref(), |t, b| {
                t.image("back_radiance", b, Usage::Read)
            })
            .with(volumes.glossy_radiance.as_ref(), |t, g| {
                t.image("glossy_radiance", g, Usage::Read)
            })
            .with(volumes.light_dir.as_ref(), |t, d| {
                t.image_view("light_dir", d, d.level_view(0), Usage::Write)
            })
            .with(volumes.light_pos.as_ref(), |t, p| {
                t.image_view("light_pos", p, p.level_view(0), Usage::Write)
            })
            .with(volumes.thin_walls.as_ref(), |t, [a, b]| {
                t.image_view("thin_walls_xy", a, a.level_view(0), Usage::Write)
                    .image_view("thin_walls_z", b, b.level_view(0), Usage::Write)
            });
        // The default's passes push whether they make the thin walls (4 bytes).
        let push = if paper { 0 } else { 4 };
        let base = Pass::compute(ctx, &variant("aniso_mip_base.comp", paper), &[], base, push)?;

        let tables: Vec<Bindings> = (1..volumes.grid.mip_levels())
            .map(|level| {
                // Level - 1 read, level written: one image bound twice (a one-texel stand-in,
                // the thin walls without a bounce, its one view both ways; the pass skips it).
                let pair = |t: Bindings, name: &str, img: &crate::vk::Image| {
                    t.image_view(
                        &format!("src_{name}"),
                        img,
                        img.level_view(level - 1),
                        Usage::Read,
                    )
                    .image_view(
                        &format!("dst_{name}"),
                        img,
                        img.level_view(level),
                        Usage::Write,
                    )
                };
                let mut t = Bindings::new();
                for (f, name) in volumes.faces.iter().zip(FACES) {
                    t = pair(t, name, f);
                }
                t.with(volumes.light_dir.as_ref(), |t, d| pair(t, "dir", d))
                    .with(volumes.light_pos.as_ref(), |t, p| pair(t, "pos", p))
                    .with(volumes.thin_walls.as_ref(), |t, [a, b]| {
                        pair(pair(t, "thin_walls_xy", a), "thin_walls_z", b)
                    })
            })
            .collect();
        let levels = if tables.is_empty() {
            None
        } else {
            let shader = variant("aniso_mip_volume.comp", paper);
            Some(Pass::new(
                ctx,
                crate::vk::Program::Compute(&shader),
                &[],
                tables,
                push,
            )?)
        };
        Ok(Mip {
            base,
            levels,
            paper,
        })
    }

    /// What the passes push: whether they make the thin walls (not --paper, which has none).
    fn push(&self, walls: bool) -> Option<bool> {
        (!self.paper).then_some(walls)
    }

    /// The directional volumes' base level from the radiance volume; with `walls`, also the
    /// thin walls' (which hold through the bounces: they change with the voxels, not the light).
    pub fn record_base(
        &self,
        ctx: &Context,
        g: &mut Graph,
        volumes: &Volumes,
        name: &str,
        walls: bool,
    ) {
        let size = volumes.grid.aniso_resolution();
        self.base
            .declare(g.pass(name), 0)
            .record(|cmd| dispatch(ctx, cmd, &self.base, 0, size, self.push(walls)));
    }

    /// Each mip level of the directional volumes from the one before (a pass per level); with
    /// `walls`, also the thin walls'.
    pub fn record_levels(
        &self,
        ctx: &Context,
        g: &mut Graph,
        volumes: &Volumes,
        name: &str,
        walls: bool,
    ) {
        let Some(p) = &self.levels else {
            return;
        };
        let m = volumes.grid.aniso_resolution();
        for level in 1..volumes.grid.mip_levels() {
            let instance = level as usize - 1;
            let size = (m >> level).max(1);
            p.declare(g.pass(name), instance)
                .record(|cmd| dispatch(ctx, cmd, p, instance, size, self.push(walls)));
        }
    }
}

/// Binds instance `instance` of `p`, pushes `walls` (not --paper) and dispatches over a
/// `size`^3 volume.
fn dispatch(
    ctx: &Context,
    cmd: vk::CommandBuffer,
    p: &Pass,
    instance: usize,
    size: u32,
    walls: Option<bool>,
) {
    let groups = size.div_ceil(4);
    unsafe {
        p.bind(&ctx.device, cmd, &[], instance);
        if let Some(walls) = walls {
            p.pipeline
                .push(&ctx.device, cmd, &(walls as u32).to_le_bytes());
        }
        ctx.device.cmd_dispatch(cmd, groups, groups, groups);
    }
}
