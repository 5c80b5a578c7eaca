//! Step 4: cone tracing per pixel (indirect diffuse, specular, ambient occlusion) added to the
//! direct light, and the debug views of the volumes.

use super::bounce::cone_volumes;
use super::inject::{read_voxel_data, variant};
use super::volumes::Volumes;
use crate::vk::{vk, Bindings, Context, Graph, Image, Pass, SharedSet, Usage, VkResult};
use std::sync::Arc;

/// What the trace pass writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TraceMode {
    Full = 0,
    Indirect = 1,
    Ao = 2,
    /// Debug views: the first voxel along each camera ray.
    VoxelAlbedo = 10,
    VoxelNormal = 11,
    VoxelEmission = 12,
    VoxelRadiance = 13,
    /// The directional volumes at frame.trace.w's mip level.
    Directional = 14,
}

/// The G-buffer's images by their names in the shaders (glsl/cone_trace.comp,
/// glsl/deferred_lighting.comp), in the order of the renderer's G-buffer.
pub const GBUFFER_NAMES: [&str; 5] = [
    "gb_position",
    "gb_normals",
    "gb_albedo",
    "gb_emission",
    "gb_specular",
];

/// What the trace reads of the frame: the G-buffer (each image with its sampler), and the
/// radiance it adds to.
pub struct FrameImages<'a> {
    pub gbuffer: &'a [Image],
    pub sampler: vk::Sampler,
    pub out: &'a Image,
}

/// The trace's table: the frame's images and the volumes cones sample.
fn trace_table(volumes: &Volumes, frame: &FrameImages) -> Bindings {
    let table = frame
        .gbuffer
        .iter()
        .zip(GBUFFER_NAMES)
        .fold(Bindings::new(), |t, (img, name)| {
            t.sampled_with(name, img, frame.sampler)
        })
        .image("radiance_out", frame.out, Usage::ReadWrite);
    cone_volumes(table, volumes, true)
}

/// The voxel views' table: the voxels, the volumes and the image they write.
fn view_table(volumes: &Volumes, out: &Image) -> Bindings {
    let table = read_voxel_data(Bindings::new(), volumes).image("view_out", out, Usage::Write);
    cone_volumes(table, volumes, true)
}

pub struct Trace {
    trace: Pass,
    view: Pass,
}

impl Trace {
    pub fn new(
        ctx: &Arc<Context>,
        scene: &SharedSet,
        volumes: &Volumes,
        frame: &FrameImages,
        paper: bool,
    ) -> VkResult<Trace> {
        let trace = Pass::compute(
            ctx,
            &variant("cone_trace.comp", paper),
            &[scene],
            trace_table(volumes, frame),
            4,
        )?;
        let view = Pass::compute(
            ctx,
            &variant("voxel_view.comp", paper),
            &[scene],
            view_table(volumes, frame.out),
            4,
        )?;
        Ok(Trace { trace, view })
    }

    /// Points the passes at new G-buffer and output images (a resized frame). The sets must
    /// not be in use (the frames before have been waited for).
    pub fn retarget(
        &mut self,
        ctx: &Context,
        scene: &SharedSet,
        volumes: &Volumes,
        frame: &FrameImages,
    ) -> VkResult<()> {
        self.trace
            .rebind(ctx, 0, trace_table(volumes, frame), &[scene])?;
        self.view
            .rebind(ctx, 0, view_table(volumes, frame.out), &[scene])
    }

    /// Cones per pixel (`mode` below 10), or a view of the voxels.
    pub fn record(
        &self,
        ctx: &Context,
        g: &mut Graph,
        scene_set: vk::DescriptorSet,
        size: (u32, u32),
        mode: TraceMode,
        name: &str,
    ) {
        let d = &ctx.device;
        let debug = (mode as u32) >= 10;
        let (p, push) = if debug {
            (&self.view, mode as u32 - 10)
        } else {
            (&self.trace, mode as u32)
        };
        p.declare(g.pass(name), 0).record(|cmd| unsafe {
            p.bind(d, cmd, &[(0, scene_set)], 0);
            p.pipeline.push(d, cmd, &push.to_le_bytes());
            d.cmd_dispatch(cmd, size.0.div_ceil(8), size.1.div_ceil(8), 1);
        });
    }
}
