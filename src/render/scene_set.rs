//! The descriptor sets the passes share: the scene's (set 0 of every pass that includes
//! glsl/common.glsl: the frame's uniforms, the materials, the lights and their shadow views) and
//! one per material (set 1 of the passes that draw the scene: its textures, glsl/material.glsl).

use super::gpu::{as_bytes, FrameUniforms, GpuMaterial};
use super::gpu_scene::GpuScene;
use crate::scene::{Material, Scene, TexRef};
use crate::vk::{vk, Bindings, Buffer, Context, SharedSet, Usage, VkResult};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

pub struct SceneBindings {
    /// The frame's uniforms (glsl/common.glsl: Frame), written before each frame.
    frame_ubo: Buffer,
    pub scene: SharedSet,
    /// One set per material (a default material when the scene has none).
    pub materials: SharedSet,
}

impl SceneBindings {
    pub fn new(ctx: &Arc<Context>, scene: &Scene, gpu: &GpuScene) -> VkResult<SceneBindings> {
        let frame_ubo = Buffer::new(
            ctx,
            "frame uniforms",
            std::mem::size_of::<FrameUniforms>() as u64,
            vk::BufferUsageFlags::UNIFORM_BUFFER,
            MemoryLocation::CpuToGpu,
        )?;
        let table = Bindings::new()
            .uniform("frame", &frame_ubo)
            .uniform("Lights", &gpu.lights.lights)
            .uniform("ShadowViews", &gpu.lights.shadow_views)
            .uniform("AreaPolygons", &gpu.lights.area_polygons)
            .uniform("AreaVertices", &gpu.lights.area_vertices)
            .uniform("AreaEdges", &gpu.lights.area_edges)
            .buffer("LtcTable", &gpu.lights.ltc, Usage::Read)
            .sampled(
                "environment_map",
                &gpu.environment,
                &gpu.environment_sampler,
            );
        let scene_set = SharedSet::new(ctx, "scene set", 0, vec![table])?;
        let default_material = [Material::default()];
        let materials = if scene.materials.is_empty() {
            &default_material[..]
        } else {
            &scene.materials[..]
        };
        let tables = materials
            .iter()
            .enumerate()
            .map(|(i, m)| material_table(gpu, i, m))
            .collect();
        let materials = SharedSet::new(ctx, "material sets", 1, tables)?;
        Ok(SceneBindings {
            frame_ubo,
            scene: scene_set,
            materials,
        })
    }

    pub fn scene_set(&self) -> vk::DescriptorSet {
        self.scene.sets[0]
    }

    /// The next frame's uniforms; the frame before was waited for.
    pub fn write_uniforms(&mut self, u: &FrameUniforms) {
        self.frame_ubo.write(0, as_bytes(std::slice::from_ref(u)));
    }
}

/// Material `index`'s factors and textures by their names in glsl/material.glsl (the white
/// texture where it has none, or names one the scene lacks).
fn material_table(gpu: &GpuScene, index: usize, m: &Material) -> Bindings {
    let slots = [
        ("t_base_color", m.base_color_tex),
        ("t_metallic_roughness", m.metallic_roughness_tex),
        ("t_normal", m.normal_tex),
        ("t_emissive", m.emissive_tex),
        ("t_specular", m.specular_tex),
        ("t_specular_color", m.specular_color_tex),
    ];
    let factors = Bindings::new().uniform_range(
        "MaterialFactors",
        &gpu.materials,
        index as u64 * gpu.material_stride,
        std::mem::size_of::<GpuMaterial>() as u64,
    );
    slots.iter().fold(factors, |t, &(name, tex)| {
        let i = tex
            .map(|t: TexRef| t.texture as usize)
            .unwrap_or(gpu.white());
        let i = if i < gpu.textures.len() {
            i
        } else {
            gpu.white()
        };
        let sampler = gpu.samplers[gpu.texture_samplers[i]].raw;
        t.sampled_with(name, &gpu.textures[i], sampler)
    })
}
