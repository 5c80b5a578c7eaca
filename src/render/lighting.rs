//! Direct light per pixel: the punctual lights (and emitters lit as lights) with their shadow
//! maps, plus emission, from the G-buffer into the radiance image
//! (glsl/deferred_lighting.comp). With area lights and the default's voxels, the pixels whose
//! shadow views may hide an emitter's faces behind what it rests on are listed, and a pass of
//! their own adds the light the voxels say those faces give (glsl/area_faces.comp).

use super::frame::FrameTargets;
use super::scene_set::SceneBindings;
use super::shadow_maps::ShadowMaps;
use crate::gi::{record_list_clear, Volumes, GBUFFER_NAMES};
use crate::vk::{
    vk, Bindings, Buffer, Context, Graph, Pass, ResourceStates, Sampler, Usage, VkResult,
};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

pub struct LightingPass {
    pass: Pass,
    faces: Option<AreaFaces>,
}

/// The area lights' faces pass: the list of pixels the lighting pass fills and the pass over it.
struct AreaFaces {
    list: Buffer,
    pass: Pass,
}

/// What the lighting pass and the faces pass read and write, given to `new` and `retarget`.
pub struct LightingInputs<'a> {
    pub targets: &'a FrameTargets,
    pub nearest: &'a Sampler,
    pub shadow: &'a ShadowMaps,
    /// The lit voxels, where the scene has area lights and the default's voxels are lit (not
    /// --paper's RGBA8 averages): their opacity says what an emitter's faces see.
    pub voxels: Option<&'a Volumes>,
}

/// The G-buffer, the area lights' shadow maps and the radiance image: what both passes use.
fn table(i: &LightingInputs, out: Usage) -> Bindings {
    i.targets
        .gbuffer
        .iter()
        .zip(GBUFFER_NAMES)
        .fold(Bindings::new(), |t, (img, name)| {
            t.sampled(name, img, i.nearest)
        })
        .sampled("area_shadow_map", &i.shadow.area_map, &i.shadow.sampler)
        .sampled("area_shadow_depth", &i.shadow.area_map, i.nearest)
        .image("out_radiance", &i.targets.hdr, out)
}

/// The lighting pass's table: the punctual lights' shadow maps too and, with the faces pass,
/// the list it appends to.
fn lighting_table(i: &LightingInputs, list: Option<&Buffer>) -> Bindings {
    table(i, Usage::Write)
        .sampled("shadow_map", &i.shadow.map, &i.shadow.sampler)
        .with(list, |t, l| t.buffer("FacesList", l, Usage::ReadWrite))
}

/// The faces pass's table: the list drives its dispatch, the voxels' opacity its segments, and
/// it adds to the lighting pass's image.
fn faces_table(i: &LightingInputs, voxels: &Volumes, list: &Buffer) -> Bindings {
    table(i, Usage::ReadWrite)
        .buffer("FacesList", list, Usage::Indirect)
        .image("radiance", &voxels.radiance, Usage::Read)
}

/// The list of pixels for the faces pass: an indirect dispatch's arguments, a count, then up to
/// one entry per pixel.
fn faces_list(ctx: &Arc<Context>, targets: &FrameTargets) -> VkResult<Buffer> {
    Buffer::new(
        ctx,
        "area faces pixels",
        16 + 4 * u64::from(targets.width) * u64::from(targets.height),
        vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::INDIRECT_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuOnly,
    )
}

impl LightingPass {
    pub fn new(
        ctx: &Arc<Context>,
        sets: &SceneBindings,
        inputs: &LightingInputs,
    ) -> VkResult<LightingPass> {
        let faces = inputs
            .voxels
            .map(|voxels| -> VkResult<AreaFaces> {
                let list = faces_list(ctx, inputs.targets)?;
                let table = faces_table(inputs, voxels, &list);
                let pass = Pass::compute(ctx, "area_faces.comp", &[&sets.scene], table, 0)?;
                Ok(AreaFaces { list, pass })
            })
            .transpose()?;
        let shader = match faces {
            Some(_) => "deferred_lighting.comp:AREA_FACES",
            None => "deferred_lighting.comp",
        };
        let table = lighting_table(inputs, faces.as_ref().map(|f| &f.list));
        let pass = Pass::compute(ctx, shader, &[&sets.scene], table, 0)?;
        Ok(LightingPass { pass, faces })
    }

    /// Points the passes at a resized frame's images (no frame may be in flight); the faces
    /// list is made again at the new size (`inputs.voxels` as given to `new`).
    pub fn retarget(
        &mut self,
        ctx: &Arc<Context>,
        sets: &SceneBindings,
        inputs: &LightingInputs,
        states: &mut ResourceStates,
    ) -> VkResult<()> {
        if let (Some(f), Some(voxels)) = (self.faces.as_mut(), inputs.voxels) {
            states.forget(f.list.raw);
            let list = faces_list(ctx, inputs.targets)?;
            f.pass
                .rebind(ctx, 0, faces_table(inputs, voxels, &list), &[&sets.scene])?;
            f.list = list;
        }
        let table = lighting_table(inputs, self.faces.as_ref().map(|f| &f.list));
        self.pass.rebind(ctx, 0, table, &[&sets.scene])
    }

    /// Whether the frame has the faces pass (`record_faces`) after this one.
    pub fn lists_faces(&self) -> bool {
        self.faces.is_some()
    }

    pub fn record(
        &self,
        ctx: &Context,
        g: &mut Graph,
        name: &str,
        targets: &FrameTargets,
        scene_set: vk::DescriptorSet,
    ) {
        if let Some(f) = &self.faces {
            record_list_clear(ctx, g, &f.list, name);
        }
        let (w, h) = (targets.width, targets.height);
        let groups = [w.div_ceil(8), h.div_ceil(8), 1];
        self.pass
            .record_dispatch(ctx, g, name, &[(0, scene_set)], &[], groups);
    }

    /// The light of the area lights' faces added at the pixels the lighting pass listed.
    /// Nothing without area lights or voxels.
    pub fn record_faces(
        &self,
        ctx: &Context,
        g: &mut Graph,
        name: &str,
        scene_set: vk::DescriptorSet,
    ) {
        let Some(f) = &self.faces else {
            return;
        };
        let d = &ctx.device;
        f.pass.declare(g.pass(name), 0).record(|cmd| unsafe {
            f.pass.bind(d, cmd, &[(0, scene_set)], 0);
            d.cmd_dispatch_indirect(cmd, f.list.raw, 0);
        });
    }
}
