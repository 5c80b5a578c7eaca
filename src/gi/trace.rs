//! Step 4: cone tracing per pixel (indirect diffuse, specular, ambient occlusion) added to the
//! direct light, and the debug views of the volumes. The diffuse cones may be traced per block
//! of pixels and kept over frames first (the gather pass), for the trace to upsample; the
//! pixels no block holds then get theirs in a pass of their own (the unmatched pass).

use super::bounce::cone_volumes;
use super::inject::{read_voxel_data, variant};
use super::volumes::Volumes;
use crate::vk::{
    vk, Bindings, Buffer, Context, Graph, Image, ImageDesc, Pass, ResourceStates, SharedSet, Usage,
    VkResult,
};
use glam::Mat4;
use gpu_allocator::MemoryLocation;
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
    /// Width and height in pixels.
    pub size: (u32, u32),
    pub gbuffer: &'a [Image],
    pub sampler: vk::Sampler,
    pub out: &'a Image,
}

/// Where the diffuse cones are traced: `scale` (1, 2 or 4) pixels per side of each block that
/// traces them once (1: every pixel), and with `temporal` N > 0, kept in a history reprojected
/// from frame to frame, what a moving camera uncovers traced a subset per frame over N frames
/// (glsl/diffuse_gather.comp).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TraceLayout {
    pub scale: u32,
    pub temporal: u32,
}

impl TraceLayout {
    /// Every pixel traces every cone, every frame (one pass, as the paper).
    pub fn direct(self) -> bool {
        self.scale <= 1 && self.temporal == 0
    }
}

/// What a frame tells the reduced-resolution trace about time.
#[derive(Clone, Copy, Debug)]
pub struct TraceFrame {
    /// The camera of the frame before (the history's).
    pub prev_view_proj: Mat4,
    /// Frames since the history began (0: this frame starts it): picks which history is read.
    pub index: u64,
    /// Picks the subset of cones a block that traces by subsets starts from; consecutive
    /// frames give consecutive numbers while the camera moves.
    pub subset: u64,
    /// Drop the history (the light in the voxels changed, the images are new, or a cut).
    pub reset: bool,
    /// The camera is the frame before's (the antialiasing's sub-pixel shift aside): blocks
    /// trace their cones afresh until they hold the whole set at their own pixels.
    pub still: bool,
}

/// The frame's images and the volumes cones sample: what the trace and the unmatched pass read.
fn frame_table(volumes: &Volumes, frame: &FrameImages) -> Bindings {
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

/// The trace's table: the frame's, and what the gather left with the list of pixels no block
/// holds.
fn trace_table(volumes: &Volumes, frame: &FrameImages, gather: Option<&Gather>) -> Bindings {
    frame_table(volumes, frame).with(gather, |t, g| {
        t.sampled_with("gathered", &g.gathered, frame.sampler)
            .sampled_with("gathered_specular", &g.specular, frame.sampler)
            .buffer("Unmatched", &g.unmatched, Usage::ReadWrite)
    })
}

/// The list of pixels no block holds (glsl/cone_trace.comp: an indirect dispatch's arguments,
/// a count, then up to one entry per pixel).
fn unmatched_list(ctx: &Arc<Context>, frame: &FrameImages) -> VkResult<Buffer> {
    let (w, h) = frame.size;
    Buffer::new(
        ctx,
        "trace unmatched pixels",
        16 + 4 * u64::from(w) * u64::from(h),
        vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::INDIRECT_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuOnly,
    )
}

/// The history of the temporal gather (one frame's): its sums, their places and normals with
/// how much was traced afresh since the camera stopped, and those fresh sums.
struct History {
    sums: Image,
    place: Image,
    normal: Image,
    fresh: Image,
}

impl History {
    fn new(ctx: &Arc<Context>, w: u32, h: u32, k: usize) -> VkResult<History> {
        let usage = vk::ImageUsageFlags::STORAGE;
        let image = |name: &str, format| {
            Image::new(
                ctx,
                &format!("trace history {name} {k}"),
                ImageDesc::d2(format, w, h, usage),
            )
        };
        Ok(History {
            sums: image("sums", vk::Format::R32G32B32A32_SFLOAT)?,
            place: image("place", vk::Format::R32G32B32A32_SFLOAT)?,
            normal: image("normal", vk::Format::R32G32B32A32_SFLOAT)?,
            fresh: image("fresh", vk::Format::R32G32B32A32_SFLOAT)?,
        })
    }
}

/// The diffuse cones at reduced resolution or over frames: the per-block results and, when
/// temporal, two histories that frames read and write in turn; and for the pixels no block
/// holds, their list and the pass that traces them.
struct Gather {
    pass: Pass,
    gathered: Image,
    specular: Image,
    histories: Vec<History>,
    unmatched: Buffer,
    unmatched_pass: Pass,
}

impl Gather {
    fn images(
        ctx: &Arc<Context>,
        frame: &FrameImages,
        layout: TraceLayout,
    ) -> VkResult<(Image, Image, Vec<History>)> {
        let (w, h) = frame.size;
        let (bw, bh) = (w.div_ceil(layout.scale), h.div_ceil(layout.scale));
        // Written by the gather, sampled by the trace.
        let per_block = |name: &str, format| {
            let usage = vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::SAMPLED;
            Image::new(ctx, name, ImageDesc::d2(format, bw, bh, usage))
        };
        let gathered = per_block("trace gathered", vk::Format::R32G32B32A32_SFLOAT)?;
        let specular = per_block("trace gathered specular", vk::Format::R16G16B16A16_SFLOAT)?;
        let histories = if layout.temporal > 0 {
            (0..2)
                .map(|k| History::new(ctx, bw, bh, k))
                .collect::<VkResult<Vec<_>>>()?
        } else {
            Vec::new()
        };
        Ok((gathered, specular, histories))
    }

    /// Instance k reads history k and writes the other one.
    fn tables(
        volumes: &Volumes,
        frame: &FrameImages,
        gathered: &Image,
        specular: &Image,
        histories: &[History],
    ) -> Vec<Bindings> {
        let base = || {
            let t = Bindings::new()
                .sampled_with("gb_position", &frame.gbuffer[0], frame.sampler)
                .sampled_with("gb_normals", &frame.gbuffer[1], frame.sampler)
                .sampled_with("gb_emission", &frame.gbuffer[3], frame.sampler)
                .image("gathered", gathered, Usage::Write)
                .image("gathered_specular", specular, Usage::Write);
            cone_volumes(t, volumes, true)
        };
        if histories.is_empty() {
            return vec![base()];
        }
        (0..2)
            .map(|k| {
                let (a, b) = (&histories[k], &histories[1 - k]);
                base()
                    .image("history_in", &a.sums, Usage::Read)
                    .image("history_place_in", &a.place, Usage::Read)
                    .image("history_normal_in", &a.normal, Usage::Read)
                    .image("history_out", &b.sums, Usage::Write)
                    .image("history_place_out", &b.place, Usage::Write)
                    .image("history_normal_out", &b.normal, Usage::Write)
                    .image("history_fresh_in", &a.fresh, Usage::Read)
                    .image("history_fresh_out", &b.fresh, Usage::Write)
            })
            .collect()
    }

    fn new(
        ctx: &Arc<Context>,
        scene: &SharedSet,
        volumes: &Volumes,
        frame: &FrameImages,
        layout: TraceLayout,
    ) -> VkResult<Gather> {
        let (gathered, specular, histories) = Gather::images(ctx, frame, layout)?;
        let shader = if layout.temporal > 0 {
            "diffuse_gather.comp:TEMPORAL"
        } else {
            "diffuse_gather.comp"
        };
        let pass = Pass::new(
            ctx,
            crate::vk::Program::Compute(shader),
            &[scene],
            Gather::tables(volumes, frame, &gathered, &specular, &histories),
            GATHER_PUSH_SIZE,
        )?;
        let unmatched = unmatched_list(ctx, frame)?;
        let unmatched_pass = Pass::compute(
            ctx,
            "cone_trace.comp:UNMATCHED",
            &[scene],
            Gather::unmatched_table(volumes, frame, &unmatched),
            TRACE_PUSH_SIZE,
        )?;
        Ok(Gather {
            pass,
            gathered,
            specular,
            histories,
            unmatched,
            unmatched_pass,
        })
    }

    fn unmatched_table(volumes: &Volumes, frame: &FrameImages, list: &Buffer) -> Bindings {
        frame_table(volumes, frame).buffer("Unmatched", list, Usage::Indirect)
    }
}

/// mat4 prev_view_proj, uint scale, subsets, frame index, reset, still.
const GATHER_PUSH_SIZE: u32 = 64 + 20;
/// uint mode, scale.
const TRACE_PUSH_SIZE: u32 = 8;

/// The voxel views' table: the voxels, the volumes and the image they write.
fn view_table(volumes: &Volumes, out: &Image) -> Bindings {
    let table = read_voxel_data(Bindings::new(), volumes)
        .image("view_out", out, Usage::Write)
        .with(volumes.glossy_radiance.as_ref(), |t, g| {
            t.sampled("glossy_radiance_tex", g, &volumes.sampler)
        });
    cone_volumes(table, volumes, true)
}

pub struct Trace {
    pub layout: TraceLayout,
    trace: Pass,
    view: Pass,
    gather: Option<Gather>,
}

impl Trace {
    pub fn new(
        ctx: &Arc<Context>,
        scene: &SharedSet,
        volumes: &Volumes,
        frame: &FrameImages,
        paper: bool,
        layout: TraceLayout,
    ) -> VkResult<Trace> {
        let gather = match layout.direct() || paper {
            true => None,
            false => Some(Gather::new(ctx, scene, volumes, frame, layout)?),
        };
        let shader = match &gather {
            Some(_) => "cone_trace.comp:UPSAMPLED".to_string(),
            None => variant("cone_trace.comp", paper),
        };
        let trace = Pass::compute(
            ctx,
            &shader,
            &[scene],
            trace_table(volumes, frame, gather.as_ref()),
            TRACE_PUSH_SIZE,
        )?;
        let view = Pass::compute(
            ctx,
            &variant("voxel_view.comp", paper),
            &[scene],
            view_table(volumes, frame.out),
            4,
        )?;
        Ok(Trace {
            layout,
            trace,
            view,
            gather,
        })
    }

    /// Points the passes at new G-buffer and output images (a resized frame). The sets must
    /// not be in use (the frames before have been waited for).
    pub fn retarget(
        &mut self,
        ctx: &Arc<Context>,
        scene: &SharedSet,
        volumes: &Volumes,
        frame: &FrameImages,
        states: &mut ResourceStates,
    ) -> VkResult<()> {
        if let Some(g) = self.gather.as_mut() {
            let old = g
                .histories
                .iter()
                .flat_map(|h| [&h.sums, &h.place, &h.normal]);
            for img in old.chain([&g.gathered, &g.specular]) {
                states.forget(img.raw);
            }
            states.forget(g.unmatched.raw);
            let (gathered, specular, histories) = Gather::images(ctx, frame, self.layout)?;
            let tables = Gather::tables(volumes, frame, &gathered, &specular, &histories);
            for (k, t) in tables.into_iter().enumerate() {
                g.pass.rebind(ctx, k, t, &[scene])?;
            }
            let unmatched = unmatched_list(ctx, frame)?;
            let table = Gather::unmatched_table(volumes, frame, &unmatched);
            g.unmatched_pass.rebind(ctx, 0, table, &[scene])?;
            g.gathered = gathered;
            g.specular = specular;
            g.histories = histories;
            g.unmatched = unmatched;
        }
        self.trace.rebind(
            ctx,
            0,
            trace_table(volumes, frame, self.gather.as_ref()),
            &[scene],
        )?;
        self.view
            .rebind(ctx, 0, view_table(volumes, frame.out), &[scene])
    }

    /// Whether the diffuse cones are traced per block or over frames, in a pass of their
    /// own before the trace ([`Trace::record_gather`]).
    pub fn gathers(&self) -> bool {
        self.gather.is_some()
    }

    /// Cones per pixel (`mode` below 10), or a view of the voxels. After a gather, the list of
    /// pixels no block holds is emptied first (under the same name).
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
        let (p, bytes) = if debug {
            (&self.view, (mode as u32 - 10).to_le_bytes().to_vec())
        } else {
            (&self.trace, self.trace_push(mode))
        };
        if let (false, Some(gather)) = (debug, &self.gather) {
            super::record_list_clear(ctx, g, &gather.unmatched, name);
        }
        p.declare(g.pass(name), 0).record(|cmd| unsafe {
            p.bind(d, cmd, &[(0, scene_set)], 0);
            p.pipeline.push(d, cmd, &bytes);
            d.cmd_dispatch(cmd, size.0.div_ceil(8), size.1.div_ceil(8), 1);
        });
    }

    /// The trace's push constants (and the unmatched pass's): mode, scale.
    fn trace_push(&self, mode: TraceMode) -> Vec<u8> {
        [mode as u32, self.layout.scale.max(1)]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect()
    }

    /// The diffuse cones of the pixels the trace listed (no block holds them), added to its
    /// image. Nothing when the trace does not gather.
    pub fn record_unmatched(
        &self,
        ctx: &Context,
        g: &mut Graph,
        scene_set: vk::DescriptorSet,
        mode: TraceMode,
        name: &str,
    ) {
        let Some(gather) = &self.gather else {
            return;
        };
        let d = &ctx.device;
        let bytes = self.trace_push(mode);
        let p = &gather.unmatched_pass;
        p.declare(g.pass(name), 0).record(|cmd| unsafe {
            p.bind(d, cmd, &[(0, scene_set)], 0);
            p.pipeline.push(d, cmd, &bytes);
            d.cmd_dispatch_indirect(cmd, gather.unmatched.raw, 0);
        });
    }

    /// The diffuse cones per block (and over frames), before the trace upsamples them; `time`
    /// says which frame of the history this is. Nothing when the trace does not gather.
    pub fn record_gather(
        &self,
        ctx: &Context,
        g: &mut Graph,
        scene_set: vk::DescriptorSet,
        time: &TraceFrame,
        name: &str,
    ) {
        let Some(gather) = &self.gather else {
            return;
        };
        let d = &ctx.device;
        let instance = if gather.histories.is_empty() {
            0
        } else {
            (time.index % 2) as usize
        };
        let mut push: Vec<u8> = time
            .prev_view_proj
            .to_cols_array()
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let subsets = self.layout.temporal;
        for v in [
            self.layout.scale.max(1),
            subsets,
            (time.subset % subsets.max(1) as u64) as u32,
            time.reset as u32,
            time.still as u32,
        ] {
            push.extend(v.to_le_bytes());
        }
        let e = gather.gathered.desc.extent;
        let blocks = (e.width, e.height);
        let p = &gather.pass;
        p.declare(g.pass(name), instance).record(|cmd| unsafe {
            p.bind(d, cmd, &[(0, scene_set)], instance);
            p.pipeline.push(d, cmd, &push);
            d.cmd_dispatch(cmd, blocks.0.div_ceil(8), blocks.1.div_ceil(8), 1);
        });
    }
}
