//! The renderer: shadow maps, G-buffer and deferred lighting, recorded as declared passes, and
//! the voxel passes of crate::gi, composed by `Renderer`.

mod accumulate;
pub mod area_lights;
pub mod environment;
mod frame;
mod gbuffer;
pub mod gpu;
mod gpu_scene;
mod instances;
mod lighting;
pub mod ltc;
mod renderer;
mod scene_set;
mod shadow_maps;
pub mod shadows;

pub use gpu_scene::{mip_chain, GpuScene};
pub use instances::DRAW_PUSH_SIZE;
pub use renderer::{Mode, RenderSettings, Renderer, Step};
