//! The Vulkan layer: context, RAII resources, passes with declared accesses, timings.

mod commands;
mod context;
pub mod graph;
pub mod pass;
pub mod pipeline;
pub mod reflect;
mod resources;
pub mod timing;

pub use commands::CommandPool;
pub use context::{Context, ContextDesc, DeviceInfo, MessageStats};
pub use graph::{Access, Graph, ResourceStates, Tracked};
pub use pass::{AddressTable, Bindings, Pass, Program, SharedSet, Usage};
pub use pipeline::{GraphicsDesc, Pipeline, VertexLayout};
pub use resources::{level_copy, Buffer, Image, ImageDesc, Sampler};
pub use timing::PassTimer;

pub use ash::vk;

/// Errors of the Vulkan layer.
#[derive(Debug, thiserror::Error)]
pub enum VkError {
    #[error("cannot load the Vulkan loader (libvulkan.so.1): {0}")]
    Loader(String),
    #[error("{call} failed: {result}")]
    Call {
        call: &'static str,
        result: vk::Result,
    },
    #[error("no Vulkan device is usable: {0}")]
    NoDevice(String),
    #[error("the Vulkan device {device} lacks what the renderer needs: {missing}")]
    Missing { device: String, missing: String },
    #[error("the Khronos validation layer (VK_LAYER_KHRONOS_validation) was asked for but is not installed")]
    NoValidationLayer,
    #[error("GPU memory allocation {name:?} failed: {source}")]
    Alloc {
        name: String,
        source: gpu_allocator::AllocationError,
    },
    /// A call the renderer cannot honour as asked (the message says why).
    #[error("{0}")]
    Request(String),
    #[error("shader {0} is not among the compiled shaders")]
    NoShader(String),
    /// A pass or pipeline whose shaders and Rust side disagree (a binding, a type, a use, the
    /// push constants): a bug in voxgi, caught when the pass is made.
    #[error("{what}: {problem}")]
    Interface { what: String, problem: String },
    #[error(
        "a {grid}^3 grid needs {} MiB for {what}; one buffer holds at most {} MiB here \
         (maxMemoryAllocationSize, and 2^31 words) and a 3D image at most {max_side} texels a \
         side (maxImageDimension3D); use --voxels {largest} or less",
        bytes >> 20,
        limit >> 20
    )]
    GridTooLarge {
        grid: u32,
        what: String,
        bytes: u64,
        limit: u64,
        max_side: u32,
        largest: u32,
    },
}

pub type VkResult<T> = Result<T, VkError>;

/// Maps a raw `vk::Result` into a `VkError` naming the call.
pub(crate) trait Check<T> {
    fn check(self, call: &'static str) -> VkResult<T>;
}

impl<T> Check<T> for Result<T, vk::Result> {
    fn check(self, call: &'static str) -> VkResult<T> {
        self.map_err(|result| VkError::Call { call, result })
    }
}
