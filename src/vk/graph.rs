//! Passes declare what they read and write by access type; the barriers between passes are
//! derived here, in one place, from those declarations and the tracked state of each resource.
//! Every pass also gets a debug label and a timestamp scope.

use super::{Buffer, Context, Image, PassTimer};
use ash::vk;
use std::collections::HashMap;
use std::ffi::CString;

/// How a pass touches a resource.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Access {
    TransferRead,
    TransferWrite,
    HostRead,
    VertexBuffer,
    IndexBuffer,
    /// Storage buffer or uniform-like data read by the vertex/geometry/fragment stages.
    GraphicsBufferRead,
    ColorAttachmentWrite,
    /// Depth test and write.
    DepthAttachmentWrite,
    FragmentSampled,
    ComputeSampled,
    ComputeStorageRead,
    ComputeStorageWrite,
    ComputeStorageReadWrite,
    /// The arguments of an indirect dispatch, and storage reads of the same buffer by the
    /// dispatched shader.
    ComputeIndirectRead,
    /// Storage image or buffer atomics from the fragment stage (voxelization).
    FragmentStorageReadWrite,
    /// Handed to the presentation engine (a swapchain image; the present waits on a
    /// semaphore signalled after the frame, so no stage or access is needed).
    Present,
}

/// The synchronization scope and layout an access needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AccessInfo {
    pub stage: vk::PipelineStageFlags2,
    pub access: vk::AccessFlags2,
    pub layout: vk::ImageLayout,
    pub writes: bool,
}

impl Access {
    pub fn info(self) -> AccessInfo {
        use vk::AccessFlags2 as A;
        use vk::ImageLayout as L;
        use vk::PipelineStageFlags2 as S;
        let (stage, access, layout, writes) = match self {
            Access::TransferRead => (
                S::TRANSFER,
                A::TRANSFER_READ,
                L::TRANSFER_SRC_OPTIMAL,
                false,
            ),
            Access::TransferWrite => (
                S::TRANSFER,
                A::TRANSFER_WRITE,
                L::TRANSFER_DST_OPTIMAL,
                true,
            ),
            Access::HostRead => (S::HOST, A::HOST_READ, L::GENERAL, false),
            Access::VertexBuffer => (
                S::VERTEX_ATTRIBUTE_INPUT,
                A::VERTEX_ATTRIBUTE_READ,
                L::UNDEFINED,
                false,
            ),
            Access::IndexBuffer => (S::INDEX_INPUT, A::INDEX_READ, L::UNDEFINED, false),
            Access::GraphicsBufferRead => (
                S::VERTEX_SHADER | S::GEOMETRY_SHADER | S::FRAGMENT_SHADER,
                A::SHADER_STORAGE_READ | A::UNIFORM_READ,
                L::UNDEFINED,
                false,
            ),
            Access::ColorAttachmentWrite => (
                S::COLOR_ATTACHMENT_OUTPUT,
                A::COLOR_ATTACHMENT_WRITE | A::COLOR_ATTACHMENT_READ,
                L::COLOR_ATTACHMENT_OPTIMAL,
                true,
            ),
            Access::DepthAttachmentWrite => (
                S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
                A::DEPTH_STENCIL_ATTACHMENT_READ | A::DEPTH_STENCIL_ATTACHMENT_WRITE,
                L::DEPTH_ATTACHMENT_OPTIMAL,
                true,
            ),
            Access::FragmentSampled => (
                S::FRAGMENT_SHADER,
                A::SHADER_SAMPLED_READ,
                L::SHADER_READ_ONLY_OPTIMAL,
                false,
            ),
            Access::ComputeSampled => (
                S::COMPUTE_SHADER,
                A::SHADER_SAMPLED_READ,
                L::SHADER_READ_ONLY_OPTIMAL,
                false,
            ),
            Access::ComputeStorageRead => (
                S::COMPUTE_SHADER,
                A::SHADER_STORAGE_READ | A::UNIFORM_READ,
                L::GENERAL,
                false,
            ),
            Access::ComputeStorageWrite => {
                (S::COMPUTE_SHADER, A::SHADER_STORAGE_WRITE, L::GENERAL, true)
            }
            Access::ComputeStorageReadWrite => (
                S::COMPUTE_SHADER,
                A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE,
                L::GENERAL,
                true,
            ),
            Access::ComputeIndirectRead => (
                S::DRAW_INDIRECT | S::COMPUTE_SHADER,
                A::INDIRECT_COMMAND_READ | A::SHADER_STORAGE_READ,
                L::UNDEFINED,
                false,
            ),
            Access::FragmentStorageReadWrite => (
                S::FRAGMENT_SHADER,
                A::SHADER_STORAGE_READ | A::SHADER_STORAGE_WRITE,
                L::GENERAL,
                true,
            ),
            Access::Present => (S::NONE, A::NONE, L::PRESENT_SRC_KHR, false),
        };
        AccessInfo {
            stage,
            access,
            layout,
            writes,
        }
    }
}

/// What is known about one resource between passes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct State {
    pub layout: vk::ImageLayout,
    /// Stage and access of the last write (or layout transition), if any.
    pub last_write: Option<(vk::PipelineStageFlags2, vk::AccessFlags2)>,
    /// Stages and accesses that have read since the last write, already made visible.
    pub read_stages: vk::PipelineStageFlags2,
    pub read_access: vk::AccessFlags2,
}

impl Default for State {
    fn default() -> Self {
        State {
            layout: vk::ImageLayout::UNDEFINED,
            last_write: None,
            read_stages: vk::PipelineStageFlags2::NONE,
            read_access: vk::AccessFlags2::NONE,
        }
    }
}

/// A derived barrier: source and destination scopes and the layouts (images only).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Barrier {
    pub src_stage: vk::PipelineStageFlags2,
    pub src_access: vk::AccessFlags2,
    pub dst_stage: vk::PipelineStageFlags2,
    pub dst_access: vk::AccessFlags2,
    pub old_layout: vk::ImageLayout,
    pub new_layout: vk::ImageLayout,
}

/// The one place barriers come from: given a resource's state and the next access, returns the
/// barrier needed (if any) and updates the state. `is_image` decides whether layouts matter.
pub fn derive(state: &mut State, access: Access, is_image: bool) -> Option<Barrier> {
    let next = access.info();
    let new_layout = if is_image {
        next.layout
    } else {
        vk::ImageLayout::UNDEFINED
    };
    let (write_stage, write_access) = state
        .last_write
        .unwrap_or((vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE));
    let transition = is_image && state.layout != new_layout;

    if transition {
        // A layout transition is a write: it waits for the last write and every reader since.
        let b = Barrier {
            src_stage: write_stage | state.read_stages,
            src_access: write_access,
            dst_stage: next.stage,
            dst_access: next.access,
            old_layout: state.layout,
            new_layout,
        };
        *state = State {
            layout: new_layout,
            last_write: Some(if next.writes {
                (next.stage, next.access)
            } else {
                (next.stage, vk::AccessFlags2::NONE)
            }),
            read_stages: if next.writes {
                vk::PipelineStageFlags2::NONE
            } else {
                next.stage
            },
            read_access: if next.writes {
                vk::AccessFlags2::NONE
            } else {
                next.access
            },
        };
        Some(b)
    } else if next.writes {
        // Write after write (memory dependency) or write after read (execution dependency).
        let src_stage = write_stage | state.read_stages;
        let b = (!src_stage.is_empty()).then_some(Barrier {
            src_stage,
            src_access: write_access,
            dst_stage: next.stage,
            dst_access: next.access,
            old_layout: state.layout,
            new_layout: state.layout,
        });
        state.last_write = Some((next.stage, next.access));
        state.read_stages = vk::PipelineStageFlags2::NONE;
        state.read_access = vk::AccessFlags2::NONE;
        b
    } else {
        // Read after write, unless this stage and access already saw the write.
        let seen =
            state.read_stages.contains(next.stage) && state.read_access.contains(next.access);
        let b = (state.last_write.is_some() && !seen).then_some(Barrier {
            src_stage: write_stage,
            src_access: write_access,
            dst_stage: next.stage,
            dst_access: next.access,
            old_layout: state.layout,
            new_layout: state.layout,
        });
        state.read_stages |= next.stage;
        state.read_access |= next.access;
        b
    }
}

/// Tracked state of every resource, kept across command buffers (one queue, submitted in order).
#[derive(Default)]
pub struct ResourceStates {
    map: HashMap<u64, State>,
}

impl ResourceStates {
    /// Forgets a resource (when it is destroyed, so a new one with the same handle starts fresh).
    pub fn forget(&mut self, handle: impl vk::Handle) {
        self.map.remove(&handle.as_raw());
    }
    /// A swapchain image just acquired: its contents are undefined, and the frame's submission
    /// waits for the acquire at `stage`, so the first barrier starts from that stage (which
    /// puts its layout transition after the acquire).
    pub fn acquired(&mut self, image: vk::Image, stage: vk::PipelineStageFlags2) {
        self.map.insert(
            vk::Handle::as_raw(image),
            State {
                last_write: Some((stage, vk::AccessFlags2::NONE)),
                ..State::default()
            },
        );
    }
    fn get(&mut self, raw: u64) -> &mut State {
        self.map.entry(raw).or_default()
    }
}

/// A resource as the graph tracks it: by its handle (and an image's range).
#[derive(Clone, Copy)]
pub enum Tracked {
    Image(vk::Image, vk::ImageSubresourceRange),
    Buffer(vk::Buffer),
}

impl Tracked {
    /// All of an image.
    pub fn image(image: &Image) -> Tracked {
        Tracked::Image(image.raw, image.full_range())
    }
    fn raw(&self) -> u64 {
        match self {
            Tracked::Image(i, _) => vk::Handle::as_raw(*i),
            Tracked::Buffer(b) => vk::Handle::as_raw(*b),
        }
    }
}

/// One resource, whatever its range.
impl PartialEq for Tracked {
    fn eq(&self, other: &Tracked) -> bool {
        std::mem::discriminant(self) == std::mem::discriminant(other) && self.raw() == other.raw()
    }
}

impl std::fmt::Debug for Tracked {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Tracked::Image(..) => write!(f, "Image({:#x})", self.raw()),
            Tracked::Buffer(_) => write!(f, "Buffer({:#x})", self.raw()),
        }
    }
}

/// Records passes into one command buffer.
pub struct Graph<'a> {
    ctx: &'a Context,
    pub cmd: vk::CommandBuffer,
    states: &'a mut ResourceStates,
    timer: Option<&'a mut PassTimer>,
    /// Test hook: the pass of this name records without its barriers (to prove that
    /// synchronization validation catches a missing one).
    pub omit_barriers_of: Option<String>,
    /// The passes recorded, in order: each one's debug label and timing name.
    pub labels: Vec<String>,
}

/// A pass being declared; `record` emits its barriers, label and timestamps and runs it.
pub struct PassBuilder<'g, 'a, 'r> {
    graph: &'g mut Graph<'a>,
    name: &'r str,
    uses: Vec<(Tracked, Access)>,
    /// A pass (labelled and timed), or only the barriers its accesses need.
    is_pass: bool,
}

impl<'a> Graph<'a> {
    pub fn new(
        ctx: &'a Context,
        cmd: vk::CommandBuffer,
        states: &'a mut ResourceStates,
        timer: Option<&'a mut PassTimer>,
    ) -> Self {
        Graph {
            ctx,
            cmd,
            states,
            timer,
            omit_barriers_of: None,
            labels: Vec::new(),
        }
    }

    /// See [`ResourceStates::acquired`].
    pub fn acquired(&mut self, image: vk::Image, stage: vk::PipelineStageFlags2) {
        self.states.acquired(image, stage);
    }

    /// A pass: its declared accesses' barriers, then its commands inside a debug label and a
    /// timestamp scope of its name.
    pub fn pass<'g, 'r>(&'g mut self, name: &'r str) -> PassBuilder<'g, 'a, 'r> {
        PassBuilder {
            graph: self,
            name,
            uses: Vec::new(),
            is_pass: true,
        }
    }

    /// Only the barriers that hand resources on to their next access (the host, presentation):
    /// no commands, so no label or timing. `name` tells it apart in validation messages.
    pub fn barrier<'g, 'r>(&'g mut self, name: &'r str) -> PassBuilder<'g, 'a, 'r> {
        PassBuilder {
            graph: self,
            name,
            uses: Vec::new(),
            is_pass: false,
        }
    }
}

impl<'r> PassBuilder<'_, '_, 'r> {
    pub fn image(mut self, image: &Image, access: Access) -> Self {
        self.uses.push((Tracked::image(image), access));
        self
    }
    pub fn buffer(mut self, buffer: &Buffer, access: Access) -> Self {
        self.uses.push((Tracked::Buffer(buffer.raw), access));
        self
    }
    /// A resource by its handle (a pass's declared accesses, vk::pass).
    pub fn tracked(mut self, resource: Tracked, access: Access) -> Self {
        self.uses.push((resource, access));
        self
    }
    /// An image owned elsewhere (a swapchain image), tracked by its handle like the others.
    pub fn external_image(
        mut self,
        image: vk::Image,
        range: vk::ImageSubresourceRange,
        access: Access,
    ) -> Self {
        self.uses.push((Tracked::Image(image, range), access));
        self
    }

    pub fn record<R>(self, body: impl FnOnce(vk::CommandBuffer) -> R) -> R {
        let mut body = Some(body);
        let mut r = None;
        self.record_steps(1, |cmd, _| r = body.take().map(|b| b(cmd)));
        r.expect("one step ran")
    }

    /// A pass of `steps` commands that each touch its resources as declared, with the
    /// barriers those accesses need between one step and the next (a write after a write: the
    /// paper's voxelization, whose draws average into the same images). The test hook omits
    /// them all by the pass's name, or only those between steps by "NAME between steps".
    pub fn record_steps(self, steps: usize, mut body: impl FnMut(vk::CommandBuffer, usize)) {
        let g = self.graph;
        let device = &g.ctx.device;
        let cmd = g.cmd;
        let omit = g.omit_barriers_of.as_deref() == Some(self.name);
        let between = format!("{} between steps", self.name);
        let omit_between = omit || g.omit_barriers_of.as_deref() == Some(between.as_str());
        *g.ctx.stats.recording.lock().unwrap() = Some(self.name.to_string());
        let label = CString::new(self.name).unwrap_or_default();
        let labelled = self
            .is_pass
            .then_some(g.ctx.debug_device.as_ref())
            .flatten();
        if self.is_pass {
            g.labels.push(self.name.to_string());
        }
        if let Some(dd) = labelled {
            unsafe {
                dd.cmd_begin_debug_utils_label(
                    cmd,
                    &vk::DebugUtilsLabelEXT::default().label_name(&label),
                )
            };
        }
        emit_barriers(g, &self.uses, omit);
        let scope = match (self.is_pass, g.timer.as_mut()) {
            (true, Some(t)) => Some(t.begin(device, cmd, self.name)),
            _ => None,
        };
        for step in 0..steps {
            if step > 0 {
                emit_barriers(g, &self.uses, omit_between);
            }
            body(cmd, step);
        }
        if let (Some(t), Some(scope)) = (g.timer.as_mut(), scope) {
            // Timing only: wait for this pass's work before its end timestamp, so that a pass's
            // time is its own (lavapipe otherwise finishes compute work at the next barrier,
            // outside every scope).
            let wait = [vk::MemoryBarrier2::default()
                .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
                .dst_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
            unsafe {
                device.cmd_pipeline_barrier2(
                    cmd,
                    &vk::DependencyInfo::default().memory_barriers(&wait),
                )
            };
            t.end(device, cmd, scope);
        }
        if let Some(dd) = labelled {
            unsafe { dd.cmd_end_debug_utils_label(cmd) };
        }
        *g.ctx.stats.recording.lock().unwrap() = None;
    }
}

/// Derives the barriers the accesses need from the tracked states, and records them (unless
/// `omit`: the test hook; the states move on all the same).
fn emit_barriers(g: &mut Graph, uses: &[(Tracked, Access)], omit: bool) {
    let mut image_barriers = Vec::new();
    let mut buffer_barriers = Vec::new();
    for (res, access) in uses {
        let st = g.states.get(res.raw());
        match *res {
            Tracked::Image(raw, range) => {
                if let Some(b) = derive(st, *access, true) {
                    image_barriers.push(
                        vk::ImageMemoryBarrier2::default()
                            .src_stage_mask(b.src_stage)
                            .src_access_mask(b.src_access)
                            .dst_stage_mask(b.dst_stage)
                            .dst_access_mask(b.dst_access)
                            .old_layout(b.old_layout)
                            .new_layout(b.new_layout)
                            .image(raw)
                            .subresource_range(range),
                    );
                }
            }
            Tracked::Buffer(raw) => {
                if let Some(b) = derive(st, *access, false) {
                    buffer_barriers.push(
                        vk::BufferMemoryBarrier2::default()
                            .src_stage_mask(b.src_stage)
                            .src_access_mask(b.src_access)
                            .dst_stage_mask(b.dst_stage)
                            .dst_access_mask(b.dst_access)
                            .buffer(raw)
                            .offset(0)
                            .size(vk::WHOLE_SIZE),
                    );
                }
            }
        }
    }
    if omit || (image_barriers.is_empty() && buffer_barriers.is_empty()) {
        return;
    }
    let dep = vk::DependencyInfo::default()
        .image_memory_barriers(&image_barriers)
        .buffer_memory_barriers(&buffer_barriers);
    unsafe { g.ctx.device.cmd_pipeline_barrier2(g.cmd, &dep) };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_write_transitions_from_undefined() {
        let mut s = State::default();
        let b = derive(&mut s, Access::ColorAttachmentWrite, true).unwrap();
        assert_eq!(b.old_layout, vk::ImageLayout::UNDEFINED);
        assert_eq!(b.new_layout, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
        assert_eq!(b.src_access, vk::AccessFlags2::NONE);
    }

    #[test]
    fn read_after_write_waits_for_the_writer() {
        let mut s = State::default();
        derive(&mut s, Access::ComputeStorageWrite, true);
        let b = derive(&mut s, Access::ComputeStorageRead, true).unwrap();
        assert_eq!(b.src_stage, vk::PipelineStageFlags2::COMPUTE_SHADER);
        assert_eq!(b.src_access, vk::AccessFlags2::SHADER_STORAGE_WRITE);
        // A second read of the same kind is already visible.
        assert!(derive(&mut s, Access::ComputeStorageRead, true).is_none());
    }

    #[test]
    fn write_after_read_waits_for_all_readers() {
        let mut s = State::default();
        derive(&mut s, Access::TransferWrite, false);
        derive(&mut s, Access::VertexBuffer, false);
        derive(&mut s, Access::ComputeStorageRead, false);
        let b = derive(&mut s, Access::TransferWrite, false).unwrap();
        assert!(b
            .src_stage
            .contains(vk::PipelineStageFlags2::VERTEX_ATTRIBUTE_INPUT));
        assert!(b
            .src_stage
            .contains(vk::PipelineStageFlags2::COMPUTE_SHADER));
        assert!(b.src_stage.contains(vk::PipelineStageFlags2::TRANSFER));
    }

    #[test]
    fn reads_of_an_unwritten_buffer_need_nothing() {
        let mut s = State::default();
        assert!(derive(&mut s, Access::VertexBuffer, false).is_none());
        assert!(derive(&mut s, Access::IndexBuffer, false).is_none());
    }

    #[test]
    fn an_acquired_image_waits_for_the_acquire_and_ends_ready_to_present() {
        use ash::vk::Handle;
        let mut states = ResourceStates::default();
        let image = vk::Image::from_raw(7);
        states.acquired(image, vk::PipelineStageFlags2::TRANSFER);
        let s = states.get(7);
        let b = derive(s, Access::TransferWrite, true).unwrap();
        assert_eq!(b.old_layout, vk::ImageLayout::UNDEFINED);
        // The transition chains with the acquire semaphore's wait at the transfer stage.
        assert_eq!(b.src_stage, vk::PipelineStageFlags2::TRANSFER);
        let b = derive(s, Access::Present, true).unwrap();
        assert_eq!(b.new_layout, vk::ImageLayout::PRESENT_SRC_KHR);
        assert_eq!(b.src_access, vk::AccessFlags2::TRANSFER_WRITE);
    }

    #[test]
    fn layout_change_between_reads_is_a_transition() {
        let mut s = State::default();
        derive(&mut s, Access::ColorAttachmentWrite, true);
        let b = derive(&mut s, Access::ComputeSampled, true).unwrap();
        assert_eq!(b.new_layout, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
        assert_eq!(
            b.src_access,
            vk::AccessFlags2::COLOR_ATTACHMENT_WRITE | vk::AccessFlags2::COLOR_ATTACHMENT_READ
        );
        let b = derive(&mut s, Access::TransferRead, true).unwrap();
        assert_eq!(b.old_layout, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL);
        assert!(b
            .src_stage
            .contains(vk::PipelineStageFlags2::COMPUTE_SHADER));
    }
}
