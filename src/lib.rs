//! voxgi: real-time global illumination by deferred voxel shading (Villegas and Ramirez, 2016)
//! on Vulkan.

pub mod bench;
pub mod gi;
pub mod hard;
pub mod metrics;
pub mod output;
pub mod reference;
pub mod render;
pub mod scene;
pub mod view;
pub mod vk;

/// SPIR-V of the shaders in glsl/, compiled by build.rs.
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));
}
