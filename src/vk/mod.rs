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
    #[error(
        "GPU memory allocation {name:?} ({} MiB) failed with {} MiB in use{}: {}",
        mib(*size),
        mib(*in_use),
        budget.map_or(String::new(), |b| format!(" of the --memory-budget {} MiB", mib(b))),
        alloc_reason(error)
    )]
    Alloc {
        name: String,
        size: u64,
        in_use: u64,
        budget: Option<u64>,
        error: gpu_allocator::AllocationError,
    },
    #[error(
        "the Vulkan device was lost ({call}: a driver reset, a GPU hang or a removed device); \
         the frame was abandoned"
    )]
    DeviceLost { call: &'static str },
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
        self.map_err(|result| match result {
            vk::Result::ERROR_DEVICE_LOST => VkError::DeviceLost { call },
            _ => VkError::Call { call, result },
        })
    }
}

/// Bytes as MiB with one decimal.
fn mib(bytes: u64) -> String {
    format!("{:.1}", bytes as f64 / 1048576.0)
}

/// What an allocation failure means, in a few words.
fn alloc_reason(e: &gpu_allocator::AllocationError) -> String {
    match e {
        gpu_allocator::AllocationError::OutOfMemory => {
            "out of device memory (a smaller --voxels, image or --shadow-res may fit)".into()
        }
        other => other.to_string(),
    }
}
