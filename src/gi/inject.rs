//! Step 2: voxel illumination. Direct light per voxel (shadowed by the shadow maps), plus
//! emission, into the radiance volume.

use super::volumes::{Volumes, VoxelData};
use crate::vk::{vk, Bindings, Context, Graph, Image, Pass, Sampler, SharedSet, Usage, VkResult};
use std::sync::Arc;

/// The voxel data as the compute passes read it (glsl/voxel_data.glsl): the tables of the
/// words' addresses (the static and the dynamic pass's) and a read of every buffer of words
/// they point to, or --paper's images.
pub fn read_voxel_data(table: Bindings, volumes: &Volumes) -> Bindings {
    let table = match &volumes.data {
        VoxelData::Paper(p) => return p.bind_texels(table, [Usage::Read; 3]),
        VoxelData::Sums { .. } => table
            .addresses("StaticWords", &volumes.words[0])
            .addresses("DynamicWords", &volumes.words[1]),
    };
    volumes
        .data
        .buffers()
        .into_iter()
        .fold(table, |t, b| t.reaches(b, Usage::Read))
}

/// A compute shader's name, or its paper variant's.
pub fn variant(shader: &str, paper: bool) -> String {
    if paper {
        format!("{shader}:PAPER")
    } else {
        shader.to_string()
    }
}

/// The shadow maps the voxels are lit through: the punctual lights' array, the area lights', and
/// their comparison sampler.
#[derive(Clone, Copy)]
pub struct ShadowMapsIn<'a> {
    pub map: &'a Image,
    pub area_map: &'a Image,
    pub sampler: &'a Sampler,
}

pub struct Inject {
    pass: Pass,
}

impl Inject {
    pub fn new(
        ctx: &Arc<Context>,
        scene: &SharedSet,
        volumes: &Volumes,
        shadow_maps: ShadowMapsIn,
        paper: bool,
    ) -> VkResult<Inject> {
        let table = read_voxel_data(Bindings::new(), volumes)
            .sampled("shadow_map", shadow_maps.map, shadow_maps.sampler)
            .sampled("area_shadow_map", shadow_maps.area_map, shadow_maps.sampler)
            .image("radiance", &volumes.radiance, Usage::Write)
            .with(volumes.emit_dir.as_ref(), |t, d| {
                t.image("emit_dir", d, Usage::Write)
            })
            .with(volumes.small_emission.as_ref(), |t, s| {
                t.image("small_emission", s, Usage::Write)
            })
            .with(volumes.back_radiance.as_ref(), |t, b| {
                t.image("back_radiance", b, Usage::Write)
            })
            .with(volumes.glossy_radiance.as_ref(), |t, g| {
                t.image("glossy_radiance", g, Usage::Write)
            });
        let shader = variant("inject_radiance.comp", paper);
        Ok(Inject {
            pass: Pass::compute(ctx, &shader, &[scene], table, 0)?,
        })
    }

    pub fn record(
        &self,
        ctx: &Context,
        g: &mut Graph,
        volumes: &Volumes,
        scene_set: vk::DescriptorSet,
        name: &str,
    ) {
        let d = &ctx.device;
        let groups = volumes.grid.resolution.div_ceil(4);
        self.pass.declare(g.pass(name), 0).record(|cmd| unsafe {
            self.pass.bind(d, cmd, &[(0, scene_set)], 0);
            d.cmd_dispatch(cmd, groups, groups, groups);
        });
    }
}
