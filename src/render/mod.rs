//! The renderer: shadow maps, G-buffer and deferred lighting, recorded as declared passes.

pub mod emitter_lights;
pub mod gpu;
mod gpu_scene;
pub(crate) mod pipelines;
mod renderer;
pub mod shadows;

pub use gpu_scene::{mip_chain, GpuScene};
pub use renderer::{Mode, RenderSettings, Renderer, DRAW_PUSH_SIZE};
