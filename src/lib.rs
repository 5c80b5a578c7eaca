//! voxgi: real-time global illumination by deferred voxel shading (Villegas and Ramirez, 2016)
//! on Vulkan.

pub mod bench;
pub mod console;
pub mod corpus;
pub mod gi;
pub mod hard;
pub mod metrics;
pub mod output;
pub mod reference;
pub mod render;
pub mod scene;
pub mod soak;
pub mod view;
pub mod vk;

/// SPIR-V of the shaders in glsl/, compiled by build.rs.
pub mod shaders {
    include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

    /// The SPIR-V words of a compiled shader ("file" or "file:VARIANT").
    pub fn words(name: &str) -> Option<Vec<u32>> {
        let (_, bytes) = SPIRV.iter().find(|(n, _)| *n == name)?;
        Some(
            bytes
                .chunks_exact(4)
                .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
                .collect(),
        )
    }
}
