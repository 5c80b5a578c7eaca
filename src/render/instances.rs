//! The scene's instances as the passes draw them (each one's index range, material and world
//! transform) and their motion: which node moves each, and whether it is voxelized with the
//! dynamic geometry.

use super::gpu::as_bytes;
use super::gpu_scene::GpuScene;
use super::scene_set::SceneBindings;
use crate::scene::{Aabb, Scene};
use crate::vk::graph::PassBuilder;
use crate::vk::{vk, Access, Pipeline, VertexLayout};
use glam::Mat4;

/// Each draw's push constants (glsl: the Draw blocks of gbuffer, shadow and voxelize).
#[repr(C)]
#[derive(Clone, Copy)]
struct DrawPush {
    model: Mat4,
    material: u32,
    /// G-buffer: bit 0 mirrored transform. Shadow: the shadow view. Voxelize: flags.
    extra: u32,
}

/// Bytes of the per-draw push constants: up to the last member (the struct's size rounds up to
/// the matrix's alignment, past the shaders' block).
pub const DRAW_PUSH_SIZE: u32 = (std::mem::offset_of!(DrawPush, extra) + 4) as u32;

/// The scene's vertex attributes (crate::scene::Vertex) by location.
pub const POSITION: (u32, vk::Format, u32) = (0, vk::Format::R32G32B32_SFLOAT, 0);
pub const NORMAL: (u32, vk::Format, u32) = (1, vk::Format::R32G32B32_SFLOAT, 12);
pub const UV: (u32, vk::Format, u32) = (2, vk::Format::R32G32_SFLOAT, 24);
pub const TANGENT: (u32, vk::Format, u32) = (3, vk::Format::R32G32B32A32_SFLOAT, 32);

/// The scene's vertices with the given attributes.
pub fn vertices(attributes: &[(u32, vk::Format, u32)]) -> VertexLayout<'_> {
    VertexLayout {
        stride: std::mem::size_of::<crate::scene::Vertex>() as u32,
        attributes,
    }
}

pub struct Instances {
    /// Per instance: first index, index count, material.
    draws: Vec<(u32, u32, u32)>,
    /// World transform per instance (moving nodes edit these).
    pub transforms: Vec<Mat4>,
    /// Object-space bounds of each instance's primitive (which shadow views a move touches).
    bounds: Vec<Aabb>,
    /// Per instance: moved by a dynamic node (voxelized every frame).
    pub dynamic: Vec<bool>,
    /// The node of each instance.
    nodes: Vec<usize>,
    /// The static instances, then the dynamic ones (what each voxelization pass draws).
    kinds: [Vec<usize>; 2],
}

/// An instance a node move took elsewhere.
pub struct Moved {
    pub instance: usize,
    /// Where it was and where it goes, in world space.
    pub swept: Aabb,
    pub dynamic: bool,
}

impl Instances {
    /// The scene's instances; those of `dynamic_nodes` are voxelized every frame.
    pub fn new(scene: &Scene, dynamic_nodes: &[usize]) -> Instances {
        let primitive = |i: &crate::scene::Instance| &scene.primitives[i.primitive as usize];
        let dynamic: Vec<bool> = scene
            .instances
            .iter()
            .map(|i| dynamic_nodes.contains(&i.node))
            .collect();
        let kinds =
            [false, true].map(|d| (0..dynamic.len()).filter(|&i| dynamic[i] == d).collect());
        Instances {
            draws: scene
                .instances
                .iter()
                .map(|i| {
                    let p = primitive(i);
                    (p.first_index, p.index_count, p.material)
                })
                .collect(),
            transforms: scene.instances.iter().map(|i| i.world).collect(),
            bounds: scene
                .instances
                .iter()
                .map(|i| primitive(i).bounds)
                .collect(),
            dynamic,
            nodes: scene.instances.iter().map(|i| i.node).collect(),
            kinds,
        }
    }

    /// How many instances the scene has.
    pub fn count(&self) -> usize {
        self.draws.len()
    }

    /// The instances voxelized with the dynamic geometry (or, with `false`, the static ones).
    pub fn of_kind(&self, dynamic: bool) -> &[usize] {
        &self.kinds[dynamic as usize]
    }

    pub fn any_dynamic(&self) -> bool {
        self.dynamic.iter().any(|&d| d)
    }

    /// 1 where the instance's transform mirrors (its winding flips).
    pub fn mirrored(&self, instance: usize) -> u32 {
        self.transforms[instance].determinant().is_sign_negative() as u32
    }

    /// Moves every instance of a glTF node; an instance already there does not move.
    pub fn move_node(&mut self, node: usize, world: Mat4) -> Vec<Moved> {
        let mut moved = Vec::new();
        for i in 0..self.nodes.len() {
            if self.nodes[i] == node && self.transforms[i] != world {
                let b = &self.bounds[i];
                moved.push(Moved {
                    instance: i,
                    swept: b
                        .transformed(&self.transforms[i])
                        .union(&b.transformed(&world)),
                    dynamic: self.dynamic[i],
                });
                self.transforms[i] = world;
            }
        }
        moved
    }
}

/// What drawing the scene takes: the instances, the GPU scene's buffers and the shared sets.
pub struct SceneDraw<'a> {
    pub instances: &'a Instances,
    pub gpu: &'a GpuScene,
    pub sets: &'a SceneBindings,
}

impl SceneDraw<'_> {
    /// Declares the draws' reads of the vertex and index buffers.
    pub fn declare<'g, 'a, 'r>(&self, pass: PassBuilder<'g, 'a, 'r>) -> PassBuilder<'g, 'a, 'r> {
        pass.buffer(&self.gpu.vertices, Access::VertexBuffer)
            .buffer(&self.gpu.indices, Access::IndexBuffer)
    }

    /// Draws the instances `which` lists, in order, with `pipeline`, the scene set at set 0 and
    /// each one's material set at set 1; `extra` is each draw's last push constant.
    ///
    /// # Safety
    /// `cmd` is recording inside a rendering scope that `pipeline` fits.
    pub unsafe fn draw(
        &self,
        d: &ash::Device,
        cmd: vk::CommandBuffer,
        pipeline: &Pipeline,
        extra: impl Fn(usize) -> u32,
        which: impl IntoIterator<Item = usize>,
    ) {
        let (instances, gpu) = (self.instances, self.gpu);
        pipeline.bind(d, cmd);
        pipeline.bind_sets(d, cmd, 0, &[self.sets.scene_set()]);
        if instances.draws.is_empty() {
            return;
        }
        d.cmd_bind_vertex_buffers(cmd, 0, &[gpu.vertices.raw], &[0]);
        d.cmd_bind_index_buffer(cmd, gpu.indices.raw, 0, vk::IndexType::UINT32);
        let mut bound = u32::MAX;
        for i in which {
            let (first, count, material) = instances.draws[i];
            if material != bound {
                let set = self.sets.materials.sets[material as usize];
                pipeline.bind_sets(d, cmd, 1, &[set]);
                bound = material;
            }
            let push = DrawPush {
                model: instances.transforms[i],
                material,
                extra: extra(i),
            };
            pipeline.push(d, cmd, &as_bytes(&[push])[..DRAW_PUSH_SIZE as usize]);
            d.cmd_draw_indexed(cmd, count, 1, first, 0, 0);
        }
    }
}
