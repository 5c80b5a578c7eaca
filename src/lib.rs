//! voxgi: real-time global illumination by deferred voxel shading (Villegas and Ramirez, 2016)
//! on Vulkan.

pub mod scene;
