use super::emitter_lights::{self, EmitterLight};
use super::gpu::{as_bytes, FrameUniforms};
use super::gpu_scene::{light_table, GpuScene};
use super::pipelines::{self, Desc, DescriptorPool, GraphicsDesc, Pipeline, SetLayout, Spec};
use crate::gi::{Dirty, Gi, GiInputs, GiSettings, StepInputs, TraceMode};
use crate::scene::{Camera, Material, Scene, TexRef};
use crate::vk::{
    vk, Access, Buffer, Context, Graph, Image, ImageDesc, PassTimer, ResourceStates, Sampler,
    VkError, VkResult,
};
use glam::{Mat4, Vec4};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// What the image shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Direct and indirect light (cone traced), plus emission.
    Full,
    /// Punctual lights with shadows, plus emission.
    Direct,
    /// Only the cone-traced indirect light.
    Indirect,
    /// Ambient occlusion from the voxels (grey).
    Ao,
    /// The first voxel along each camera ray: its albedo, normal, emission or radiance
    /// (radiance with `mip`: the directional volumes at that level).
    VoxelsAlbedo,
    VoxelsNormal,
    VoxelsEmission,
    VoxelsRadiance,
}

impl Mode {
    pub const NAMES: &'static str =
        "full, direct, indirect, ao, voxels-albedo, voxels-normal, voxels-emission, voxels-radiance";

    /// Whether the voxel passes run at all.
    pub fn uses_voxels(self) -> bool {
        self != Mode::Direct
    }
    /// Whether the voxels are lit (inject and mips).
    pub fn lights_voxels(self) -> bool {
        matches!(
            self,
            Mode::Full | Mode::Indirect | Mode::Ao | Mode::VoxelsRadiance
        )
    }
    /// Whether the image comes from the G-buffer (else from walking the voxels).
    pub fn shades_pixels(self) -> bool {
        matches!(self, Mode::Full | Mode::Direct | Mode::Indirect | Mode::Ao)
    }
}

impl std::str::FromStr for Mode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Ok(match s {
            "full" => Mode::Full,
            "direct" => Mode::Direct,
            "indirect" => Mode::Indirect,
            "ao" => Mode::Ao,
            "voxels-albedo" => Mode::VoxelsAlbedo,
            "voxels-normal" => Mode::VoxelsNormal,
            "voxels-emission" => Mode::VoxelsEmission,
            "voxels-radiance" => Mode::VoxelsRadiance,
            other => {
                return Err(format!(
                    "unknown render mode {other:?} (the modes are: {})",
                    Mode::NAMES
                ))
            }
        })
    }
}

/// One step of a frame. [`Renderer::steps`] lists a frame's in the order recorded; recording
/// and [`Renderer::passes`] (what `voxgi info` shows) walk the same list, and a step's name is
/// its pass's debug label and its name in `--timings`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// The shadow views that changed (every one on the first frame).
    Shadows,
    /// A pass of the voxel side: voxelization, light injection, mipmaps, bounces.
    Voxels(crate::gi::Step),
    GBuffer,
    /// Direct light per pixel from the G-buffer and the shadow maps.
    Lighting,
    /// Cones per pixel, added to the direct light (the modes that shade pixels).
    Trace,
    /// The first voxel along each camera ray (the voxel modes).
    VoxelView,
    /// The radiance image copied to host memory.
    Readback,
}

impl Step {
    pub fn name(&self) -> String {
        match self {
            Step::Shadows => "shadows".into(),
            Step::Voxels(s) => s.name(),
            Step::GBuffer => "gbuffer".into(),
            Step::Lighting => "lighting".into(),
            Step::Trace => "trace".into(),
            Step::VoxelView => "voxel view".into(),
            Step::Readback => "readback".into(),
        }
    }
}

#[derive(Clone, Debug)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub mode: Mode,
    /// Texels per side of each shadow-map view.
    pub shadow_resolution: u32,
    /// PCF kernel radius in texels (a (2r+1)^2 grid of bilinear comparisons).
    pub pcf_radius: u32,
    /// Normal offset of shadow lookups, in texels.
    pub normal_offset: f32,
    pub timings: bool,
    /// The voxel passes' settings.
    pub gi: GiSettings,
    /// With `Mode::VoxelsRadiance`: show the directional volumes at this mip level.
    pub mip: Option<u32>,
    /// Nodes that move between frames: voxelized every frame, apart from the static voxels.
    pub dynamic_nodes: Vec<usize>,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            width: 512,
            height: 512,
            mode: Mode::Full,
            shadow_resolution: 2048,
            pcf_radius: 1,
            normal_offset: 1.5,
            timings: false,
            gi: GiSettings::default(),
            mip: None,
            dynamic_nodes: Vec::new(),
        }
    }
}

const GBUFFER_FORMATS: [vk::Format; 5] = [
    vk::Format::R32G32B32A32_SFLOAT,
    vk::Format::R16G16B16A16_SFLOAT,
    vk::Format::R16G16B16A16_SFLOAT,
    vk::Format::R16G16B16A16_SFLOAT,
    vk::Format::R16G16B16A16_SFLOAT,
];
const GBUFFER_NAMES: [&str; 5] = [
    "gbuffer position",
    "gbuffer normals",
    "gbuffer albedo",
    "gbuffer emission",
    "gbuffer specular",
];
const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;
/// Texture bindings per material (glsl/material.glsl).
const MATERIAL_TEXTURES: u32 = 6;

/// Bytes of the per-draw push constants (the voxelization pipeline shares them).
pub const DRAW_PUSH_SIZE: u32 = std::mem::size_of::<DrawPush>() as u32;

#[repr(C)]
#[derive(Clone, Copy)]
struct DrawPush {
    model: Mat4,
    material: u32,
    /// G-buffer: bit 0 mirrored transform. Shadow: the shadow view.
    extra: u32,
}

/// The images whose size is the frame's: G-buffer, depth, radiance, and its readback.
fn frame_images(
    ctx: &Arc<Context>,
    w: u32,
    h: u32,
) -> VkResult<(Vec<Image>, Image, Image, Buffer)> {
    let gbuffer = GBUFFER_FORMATS
        .iter()
        .zip(GBUFFER_NAMES)
        .map(|(&f, name)| {
            Image::new(
                ctx,
                name,
                ImageDesc::d2(
                    f,
                    w,
                    h,
                    vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
                ),
            )
        })
        .collect::<VkResult<Vec<_>>>()?;
    let depth = Image::new(
        ctx,
        "gbuffer depth",
        ImageDesc::d2(
            DEPTH_FORMAT,
            w,
            h,
            vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
        ),
    )?;
    let hdr = Image::new(
        ctx,
        "radiance",
        ImageDesc::d2(
            vk::Format::R32G32B32A32_SFLOAT,
            w,
            h,
            vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC,
        ),
    )?;
    let readback = Buffer::new(
        ctx,
        "radiance readback",
        (w * h * 16) as u64,
        vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuToCpu,
    )?;
    Ok((gbuffer, depth, hdr, readback))
}

/// Renders a scene; owns every GPU object it uses (freed in Drop, the context last).
pub struct Renderer {
    pub settings: RenderSettings,
    pub camera: Camera,
    /// World transform per scene instance (moving nodes edits these).
    pub transforms: Vec<Mat4>,
    instances: Vec<(u32, u32, u32)>, // (first index, index count, material)
    frame_ubo: Buffer,
    gbuffer: Vec<Image>,
    depth: Image,
    shadow_map: Image,
    hdr: Image,
    readback: Buffer,
    gbuffer_pipeline: Pipeline,
    shadow_pipeline: Pipeline,
    lighting_pipeline: Pipeline,
    _scene_layout: SetLayout,
    _material_layout: SetLayout,
    material_sets: Vec<vk::DescriptorSet>,
    _lighting_layout: SetLayout,
    _pool: DescriptorPool,
    scene_set: vk::DescriptorSet,
    lighting_set: vk::DescriptorSet,
    nearest: Sampler,
    _shadow_sampler: Sampler,
    gpu: GpuScene,
    states: ResourceStates,
    pub timer: Option<PassTimer>,
    _command_pool: CommandPool,
    cmd: vk::CommandBuffer,
    /// Test hook: record this pass without its barriers.
    pub omit_barriers_of: Option<String>,
    /// The scene's lights (set_lights replaces them).
    lights: Vec<crate::scene::Light>,
    /// Emitters smaller than a voxel, lit as lights after the scene's (emitter_lights.rs).
    emitters: Vec<EmitterLight>,
    /// Per instance: the emitter light it is, if any.
    emitter_of: Vec<Option<usize>>,
    /// Per shadow view: it must be drawn (first frame, its light moved, or a node moved
    /// through its frustum).
    shadow_views_dirty: Vec<bool>,
    /// Object-space bounds of each instance's primitive (which shadow views a move touches).
    instance_bounds: Vec<crate::scene::Aabb>,
    /// The scene's bounds (light views are fitted to them).
    bounds: crate::scene::Aabb,
    /// Per instance: moved by a dynamic node (voxelized every frame).
    dynamic_instances: Vec<bool>,
    /// The node of each instance.
    instance_nodes: Vec<usize>,
    /// The voxel passes (absent in direct mode).
    pub gi: Option<Gi>,
    specular_needed: bool,
    /// Wall time of each frame from submission to its fence, in milliseconds.
    pub frame_ms: Vec<f64>,
    /// The passes the last frame recorded, in order, by their debug labels.
    pub recorded: Vec<String>,
    ctx: Arc<Context>,
}

impl Renderer {
    pub fn new(ctx: &Arc<Context>, scene: &Scene, settings: RenderSettings) -> VkResult<Renderer> {
        let mut states = ResourceStates::default();
        let gi_settings = &settings.gi;
        // Only where the voxels are lit: the views of the voxels' materials show every
        // emitter's emission.
        let emitters =
            if settings.mode.lights_voxels() && gi_settings.emitter_lights && !gi_settings.paper {
                let grid = crate::gi::VoxelGrid::fit(&scene.bounds, gi_settings.voxels);
                emitter_lights::find(scene, grid.voxel_size())
            } else {
                Vec::new()
            };
        let mut emitter_of = vec![None; scene.instances.len()];
        for (k, e) in emitters.iter().enumerate() {
            emitter_of[e.instance] = Some(k);
        }
        let gpu = GpuScene::upload(
            ctx,
            scene,
            &mut states,
            &emitters,
            settings.shadow_resolution,
            settings.pcf_radius,
        )?;
        let (w, h) = (settings.width, settings.height);

        let frame_ubo = Buffer::new(
            ctx,
            "frame uniforms",
            std::mem::size_of::<FrameUniforms>() as u64,
            vk::BufferUsageFlags::UNIFORM_BUFFER,
            MemoryLocation::CpuToGpu,
        )?;
        // Only the views the lights need; a 1x1 stand-in when nothing casts shadows. Array
        // views even for one layer, as the shader samples a 2D array.
        let shadow_res = if gpu.shadow_view_count > 0 {
            settings.shadow_resolution
        } else {
            1
        };
        let shadow_map = Image::new(
            ctx,
            "shadow maps",
            ImageDesc::d2(
                DEPTH_FORMAT,
                shadow_res,
                shadow_res,
                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
            )
            .layers(gpu.shadow_view_count.max(1)),
        )?;
        let (gbuffer, depth, hdr, readback) = frame_images(ctx, w, h)?;

        let all = vk::ShaderStageFlags::VERTEX
            | vk::ShaderStageFlags::GEOMETRY
            | vk::ShaderStageFlags::FRAGMENT
            | vk::ShaderStageFlags::COMPUTE;
        let scene_layout = SetLayout::new(
            ctx,
            &[
                (0, vk::DescriptorType::UNIFORM_BUFFER, 1, all),
                (1, vk::DescriptorType::STORAGE_BUFFER, 1, all),
                (3, vk::DescriptorType::STORAGE_BUFFER, 1, all),
                (4, vk::DescriptorType::STORAGE_BUFFER, 1, all),
            ],
        )?;
        let cis = vk::DescriptorType::COMBINED_IMAGE_SAMPLER;
        let frag = vk::ShaderStageFlags::FRAGMENT;
        // Per-material textures: lavapipe cannot index sampler arrays dynamically.
        let material_layout = SetLayout::new(
            ctx,
            &(0..MATERIAL_TEXTURES)
                .map(|b| (b, cis, 1, frag))
                .collect::<Vec<_>>(),
        )?;
        let material_count = scene.materials.len().max(1) as u32;
        let comp = vk::ShaderStageFlags::COMPUTE;
        let lighting_layout = SetLayout::new(
            ctx,
            &[
                (0, cis, 1, comp),
                (1, cis, 1, comp),
                (2, cis, 1, comp),
                (3, cis, 1, comp),
                (4, cis, 1, comp),
                (5, cis, 1, comp),
                (6, vk::DescriptorType::STORAGE_IMAGE, 1, comp),
            ],
        )?;
        let pool = DescriptorPool::new(
            ctx,
            &[
                vk::DescriptorPoolSize {
                    ty: vk::DescriptorType::UNIFORM_BUFFER,
                    descriptor_count: 1,
                },
                vk::DescriptorPoolSize {
                    ty: vk::DescriptorType::STORAGE_BUFFER,
                    descriptor_count: 3,
                },
                vk::DescriptorPoolSize {
                    ty: cis,
                    descriptor_count: material_count * MATERIAL_TEXTURES + 6,
                },
                vk::DescriptorPoolSize {
                    ty: vk::DescriptorType::STORAGE_IMAGE,
                    descriptor_count: 1,
                },
            ],
            2 + material_count,
        )?;
        let scene_set = pool.allocate(&scene_layout)?;
        let lighting_set = pool.allocate(&lighting_layout)?;
        let material_sets = (0..material_count)
            .map(|_| pool.allocate(&material_layout))
            .collect::<VkResult<Vec<_>>>()?;

        let nearest = Sampler::new(
            ctx,
            &vk::SamplerCreateInfo::default()
                .mag_filter(vk::Filter::NEAREST)
                .min_filter(vk::Filter::NEAREST)
                .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
                .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
                .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE),
        )?;
        // Hardware comparison with bilinear filtering: each tap is already a 2x2 PCF.
        let shadow_sampler = Sampler::new(
            ctx,
            &vk::SamplerCreateInfo::default()
                .mag_filter(vk::Filter::LINEAR)
                .min_filter(vk::Filter::LINEAR)
                .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
                .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
                .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
                .compare_enable(true)
                .compare_op(vk::CompareOp::LESS_OR_EQUAL),
        )?;

        // Descriptor writes.
        {
            let buf = |b: &Buffer| {
                [vk::DescriptorBufferInfo {
                    buffer: b.raw,
                    offset: 0,
                    range: vk::WHOLE_SIZE,
                }]
            };
            let ubo = buf(&frame_ubo);
            let mats = buf(&gpu.materials);
            let lights = buf(&gpu.lights);
            let views = buf(&gpu.shadow_views);
            let tex_info = |t: Option<TexRef>| {
                let i = t.map(|t| t.texture as usize).unwrap_or(gpu.white());
                let i = if i < gpu.textures.len() {
                    i
                } else {
                    gpu.white()
                };
                [vk::DescriptorImageInfo {
                    sampler: gpu.samplers[gpu.texture_samplers[i]].raw,
                    image_view: gpu.textures[i].view,
                    image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                }]
            };
            let default_material = [Material::default()];
            let materials = if scene.materials.is_empty() {
                &default_material[..]
            } else {
                &scene.materials[..]
            };
            let mat_infos: Vec<[[vk::DescriptorImageInfo; 1]; 6]> = materials
                .iter()
                .map(|m| {
                    [
                        tex_info(m.base_color_tex),
                        tex_info(m.metallic_roughness_tex),
                        tex_info(m.normal_tex),
                        tex_info(m.emissive_tex),
                        tex_info(m.specular_tex),
                        tex_info(m.specular_color_tex),
                    ]
                })
                .collect();
            let gb_infos: Vec<[vk::DescriptorImageInfo; 1]> = gbuffer
                .iter()
                .map(|img| {
                    [vk::DescriptorImageInfo {
                        sampler: nearest.raw,
                        image_view: img.view,
                        image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                    }]
                })
                .collect();
            let shadow_info = [vk::DescriptorImageInfo {
                sampler: shadow_sampler.raw,
                image_view: shadow_map.view,
                image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            }];
            let hdr_info = [vk::DescriptorImageInfo {
                sampler: vk::Sampler::null(),
                image_view: hdr.view,
                image_layout: vk::ImageLayout::GENERAL,
            }];
            let w = |set, binding, ty| {
                vk::WriteDescriptorSet::default()
                    .dst_set(set)
                    .dst_binding(binding)
                    .descriptor_type(ty)
            };
            let sb = vk::DescriptorType::STORAGE_BUFFER;
            let mut writes = vec![
                w(scene_set, 0, vk::DescriptorType::UNIFORM_BUFFER).buffer_info(&ubo),
                w(scene_set, 1, sb).buffer_info(&mats),
                w(scene_set, 3, sb).buffer_info(&lights),
                w(scene_set, 4, sb).buffer_info(&views),
                w(lighting_set, 5, cis).image_info(&shadow_info),
                w(lighting_set, 6, vk::DescriptorType::STORAGE_IMAGE).image_info(&hdr_info),
            ];
            for (i, info) in gb_infos.iter().enumerate() {
                writes.push(w(lighting_set, i as u32, cis).image_info(info));
            }
            for (set, infos) in material_sets.iter().zip(&mat_infos) {
                for (b, info) in infos.iter().enumerate() {
                    writes.push(w(*set, b as u32, cis).image_info(info));
                }
            }
            unsafe { ctx.device.update_descriptor_sets(&writes, &[]) };
        }

        let spec = || Spec(vec![]);
        let push_size = std::mem::size_of::<DrawPush>() as u32;
        let gbuffer_pipeline = pipelines::graphics(
            ctx,
            &GraphicsDesc {
                name: "gbuffer",
                shaders: &[
                    (vk::ShaderStageFlags::VERTEX, "gbuffer.vert"),
                    (vk::ShaderStageFlags::FRAGMENT, "gbuffer.frag"),
                ],
                sets: &[&scene_layout, &material_layout],
                push_size,
                spec: spec(),
                vertex_input: &[0, 1, 2, 3],
                color_formats: &GBUFFER_FORMATS,
                depth_format: Some(DEPTH_FORMAT),
                depth_bias: None,
                cull: vk::CullModeFlags::NONE,
            },
        )?;
        let shadow_pipeline = pipelines::graphics(
            ctx,
            &GraphicsDesc {
                name: "shadow",
                shaders: &[
                    (vk::ShaderStageFlags::VERTEX, "shadow.vert"),
                    (vk::ShaderStageFlags::FRAGMENT, "shadow.frag"),
                ],
                sets: &[&scene_layout, &material_layout],
                push_size,
                spec: spec(),
                vertex_input: &[0, 2],
                color_formats: &[],
                depth_format: Some(DEPTH_FORMAT),
                depth_bias: Some((1.0, 1.5)),
                cull: vk::CullModeFlags::NONE,
            },
        )?;
        let lighting_pipeline = pipelines::compute(
            ctx,
            "deferred_lighting.comp",
            &[&scene_layout, &lighting_layout],
            0,
            &spec(),
        )?;

        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(ctx.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        let command_pool = CommandPool {
            raw: unsafe { ctx.device.create_command_pool(&pool_info, None) }.map_err(|result| {
                VkError::Call {
                    call: "vkCreateCommandPool",
                    result,
                }
            })?,
            ctx: ctx.clone(),
        };
        let cmd = unsafe {
            ctx.device.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default()
                    .command_pool(command_pool.raw)
                    .command_buffer_count(1),
            )
        }
        .map_err(|result| VkError::Call {
            call: "vkAllocateCommandBuffers",
            result,
        })?[0];
        let timer = if settings.timings {
            PassTimer::new(ctx, 64)?
        } else {
            None
        };

        let dynamic_instances: Vec<bool> = scene
            .instances
            .iter()
            .map(|i| settings.dynamic_nodes.contains(&i.node))
            .collect();
        let gi = if settings.mode.uses_voxels() {
            let gbuffer_views = gbuffer.iter().map(|i| (i.view, nearest.raw)).collect();
            Some(Gi::new(
                ctx,
                scene,
                &settings.gi,
                settings.mode.lights_voxels(),
                dynamic_instances.iter().any(|&d| d),
                GiInputs {
                    scene_layout: &scene_layout,
                    material_layout: &material_layout,
                    shadow_map: (shadow_map.view, shadow_sampler.raw),
                    gbuffer: gbuffer_views,
                    out: &hdr,
                    emitter_lights: &emitters,
                },
            )?)
        } else {
            None
        };
        let specular_needed = scene
            .materials
            .iter()
            .any(|m| m.metallic > 0.0 || m.specular_factor > 0.0);

        Ok(Renderer {
            camera: scene.camera.clone(),
            transforms: scene.instances.iter().map(|i| i.world).collect(),
            instances: scene
                .instances
                .iter()
                .map(|i| {
                    let p = &scene.primitives[i.primitive as usize];
                    (p.first_index, p.index_count, p.material)
                })
                .collect(),
            lights: scene.lights.clone(),
            emitters,
            emitter_of,
            bounds: scene.bounds,
            shadow_views_dirty: vec![true; gpu.shadow_view_count as usize],
            instance_bounds: scene
                .instances
                .iter()
                .map(|i| scene.primitives[i.primitive as usize].bounds)
                .collect(),
            dynamic_instances,
            instance_nodes: scene.instances.iter().map(|i| i.node).collect(),
            gi,
            specular_needed,
            frame_ms: Vec::new(),
            recorded: Vec::new(),
            settings,
            frame_ubo,
            gbuffer,
            depth,
            shadow_map,
            hdr,
            readback,
            gbuffer_pipeline,
            shadow_pipeline,
            lighting_pipeline,
            _scene_layout: scene_layout,
            _material_layout: material_layout,
            material_sets,
            _lighting_layout: lighting_layout,
            _pool: pool,
            scene_set,
            lighting_set,
            nearest,
            _shadow_sampler: shadow_sampler,
            gpu,
            states,
            timer,
            _command_pool: command_pool,
            cmd,
            omit_barriers_of: None,
            ctx: ctx.clone(),
        })
    }

    fn write_uniforms(&mut self) {
        let (w, h) = (self.settings.width, self.settings.height);
        let view = self.camera.view();
        let proj = Mat4::perspective_rh(
            self.camera.yfov,
            w as f32 / h as f32,
            self.camera.znear,
            self.camera.zfar,
        );
        let u = FrameUniforms {
            view_proj: proj * view,
            view,
            proj,
            eye: self.camera.eye().extend(1.0),
            counts: [
                (self.lights.len() + self.emitters.len()) as u32,
                w,
                h,
                self.gpu.shadow_view_count,
            ],
            shadow: Vec4::new(
                self.settings.shadow_resolution as f32,
                self.settings.normal_offset,
                self.settings.pcf_radius as f32,
                0.0,
            ),
            ..Default::default()
        };
        let mut u = u;
        if let Some(gi) = &self.gi {
            let grid = gi.volumes.grid;
            let s = &gi.settings;
            u.grid = grid.origin.extend(grid.size);
            u.grid_info = [
                grid.resolution,
                s.bounces,
                gi.cones.len() as u32,
                gi.flags(),
            ];
            u.cone = Vec4::new(
                (s.cone_aperture_deg.to_radians() * 0.5).tan(),
                s.step_factor,
                s.max_distance,
                gi.emission_scale,
            );
            u.trace = Vec4::new(
                s.start_offset,
                s.ao_falloff / grid.voxel_size(),
                if self.specular_needed { 1.0 } else { 0.0 },
                self.settings.mip.unwrap_or(0) as f32,
            );
            u.tuning = Vec4::new(s.lod_offset, gi.radiance_scale, 0.0, 0.0);
            for (dst, c) in u.cones.iter_mut().zip(&gi.cones) {
                *dst = *c;
            }
        }
        self.frame_ubo.write(0, as_bytes(&[u]));
    }

    /// Draws the instances `include` accepts; `extra` is each draw's last push constant.
    fn draw_instances(
        &self,
        cmd: vk::CommandBuffer,
        pipeline: &Pipeline,
        extra: impl Fn(usize) -> u32,
        include: impl Fn(usize) -> bool,
    ) {
        let d = &self.ctx.device;
        unsafe {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline.raw);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::GRAPHICS,
                pipeline.layout,
                0,
                &[self.scene_set],
                &[],
            );
            if self.instances.is_empty() {
                return;
            }
            d.cmd_bind_vertex_buffers(cmd, 0, &[self.gpu.vertices.raw], &[0]);
            d.cmd_bind_index_buffer(cmd, self.gpu.indices.raw, 0, vk::IndexType::UINT32);
            let stages = pipeline.push_stages;
            let mut bound = u32::MAX;
            for (i, &(first, count, material)) in self.instances.iter().enumerate() {
                if !include(i) {
                    continue;
                }
                if material != bound {
                    d.cmd_bind_descriptor_sets(
                        cmd,
                        vk::PipelineBindPoint::GRAPHICS,
                        pipeline.layout,
                        1,
                        &[self.material_sets[material as usize]],
                        &[],
                    );
                    bound = material;
                }
                let push = DrawPush {
                    model: self.transforms[i],
                    material,
                    extra: extra(i),
                };
                d.cmd_push_constants(cmd, pipeline.layout, stages, 0, as_bytes(&[push]));
                d.cmd_draw_indexed(cmd, count, 1, first, 0, 0);
            }
        }
    }

    /// Renders one frame and waits for it. With `readback`, the radiance image is copied to
    /// host memory for `radiance()`.
    pub fn render(&mut self, readback: bool) -> VkResult<()> {
        self.render_with(readback, &[], &[], &mut |_, _| {})
    }

    /// Renders one frame, letting `after` record further passes that read the radiance image
    /// (a window's display pass) in the same command buffer, whose submission waits for
    /// `waits` and signals `signals`; then waits for it.
    pub fn render_with(
        &mut self,
        readback: bool,
        waits: &[vk::SemaphoreSubmitInfo],
        signals: &[vk::SemaphoreSubmitInfo],
        after: &mut dyn FnMut(&mut Graph, &Image),
    ) -> VkResult<()> {
        self.write_uniforms();
        let ctx = self.ctx.clone();
        let d = &ctx.device;
        let cmd = self.cmd;
        unsafe {
            d.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty())
                .map_err(|result| VkError::Call {
                    call: "vkResetCommandBuffer",
                    result,
                })?;
            d.begin_command_buffer(
                cmd,
                &vk::CommandBufferBeginInfo::default()
                    .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )
            .map_err(|result| VkError::Call {
                call: "vkBeginCommandBuffer",
                result,
            })?;
        }
        let mut states = std::mem::take(&mut self.states);
        let mut timer = self.timer.take();
        {
            let mut g = Graph::new(&ctx, cmd, &mut states, timer.as_mut());
            g.omit_barriers_of = self.omit_barriers_of.clone();
            self.record(&mut g, readback);
            after(&mut g, &self.hdr);
            self.recorded = std::mem::take(&mut g.labels);
        }
        self.states = states;
        unsafe { d.end_command_buffer(cmd) }.map_err(|result| VkError::Call {
            call: "vkEndCommandBuffer",
            result,
        })?;
        let start = std::time::Instant::now();
        let submitted = ctx.submit_and_wait_with(cmd, waits, signals);
        self.frame_ms.push(start.elapsed().as_secs_f64() * 1e3);
        if let Some(t) = timer.as_mut() {
            t.collect()?;
        }
        self.timer = timer;
        submitted?;
        self.shadow_views_dirty.fill(false);
        // The voxels now hold the geometry and its light until a node or a light moves.
        if let Some(gi) = self.gi.as_mut() {
            gi.mark_clean();
        }
        Ok(())
    }

    /// The steps of a frame drawn when `shadows` (a shadow view must be drawn again) and `voxels`
    /// say what changed, in the order recorded.
    fn steps_when(&self, shadows: bool, voxels: Dirty, readback: bool) -> Vec<Step> {
        let mut steps = Vec::new();
        // A shadow view changes only when its light moves or a node moves through it.
        if shadows {
            steps.push(Step::Shadows);
        }
        if let Some(gi) = &self.gi {
            steps.extend(gi.steps(voxels).into_iter().map(Step::Voxels));
        }
        let mode = self.settings.mode;
        if mode.shades_pixels() {
            steps.push(Step::GBuffer);
        }
        if matches!(mode, Mode::Full | Mode::Direct) {
            steps.push(Step::Lighting);
        }
        if self.gi.is_some() {
            steps.push(if mode.shades_pixels() {
                Step::Trace
            } else {
                Step::VoxelView
            });
        }
        if readback {
            steps.push(Step::Readback);
        }
        steps
    }

    /// The steps the next frame records.
    pub fn steps(&self, readback: bool) -> Vec<Step> {
        let voxels = self.gi.as_ref().map_or(Dirty::NONE, |gi| gi.dirty);
        let shadows = self.shadow_views_dirty.iter().any(|&d| d);
        self.steps_when(shadows, voxels, readback)
    }

    /// The passes of `voxgi render`'s first frame, in order, by the names their debug labels
    /// and `--timings` give them: every shadow view is drawn, the voxels made and lit; later
    /// frames record only what changed (a still frame: the G-buffer, lighting and trace), and
    /// the last one the readback.
    pub fn passes(&self) -> Vec<String> {
        let shadows = self.gpu.shadow_view_count > 0;
        self.steps_when(shadows, Dirty::ALL, true)
            .iter()
            .map(Step::name)
            .collect()
    }

    fn record(&self, g: &mut Graph, readback: bool) {
        for step in self.steps(readback) {
            self.record_step(g, step);
        }
    }

    fn record_step(&self, g: &mut Graph, step: Step) {
        match step {
            Step::Shadows => self.record_shadows(g),
            Step::Voxels(s) => self.record_voxels(g, s),
            Step::GBuffer => self.record_gbuffer(g),
            Step::Lighting => self.record_lighting(g),
            Step::Trace | Step::VoxelView => self.record_trace(g),
            Step::Readback => self.record_readback(g),
        }
    }

    /// Draws the shadow views that changed.
    fn record_shadows(&self, g: &mut Graph) {
        let ctx = &self.ctx;
        let d = &ctx.device;
        let res = self.settings.shadow_resolution;
        let name = Step::Shadows.name();
        let mut pass = g
            .pass(&name)
            .image(&self.shadow_map, Access::DepthAttachmentWrite)
            .buffer(&self.gpu.vertices, Access::VertexBuffer)
            .buffer(&self.gpu.indices, Access::IndexBuffer);
        // Alpha-masked materials sample their base colour.
        for t in &self.gpu.textures {
            pass = pass.image(t, Access::FragmentSampled);
        }
        pass.record(|cmd| {
            for view in 0..self.gpu.shadow_view_count {
                if !self.shadow_views_dirty[view as usize] {
                    continue;
                }
                let depth = pipelines::cleared_depth(
                    self.shadow_map.layer_view(view),
                    vk::AttachmentStoreOp::STORE,
                );
                let info = vk::RenderingInfo::default()
                    .render_area(pipelines::area(res, res))
                    .layer_count(1)
                    .depth_attachment(&depth);
                unsafe { d.cmd_begin_rendering(cmd, &info) };
                pipelines::set_viewport(ctx, cmd, res, res);
                // An emitter light's own faces would hide it (its centre may be inside).
                let own = |i: usize| {
                    self.emitter_of[i].is_some_and(|k| {
                        let v = &self.gpu.light_views[self.lights.len() + k];
                        (v.first..v.first + v.views.len() as u32).contains(&view)
                    })
                };
                self.draw_instances(cmd, &self.shadow_pipeline, |_| view, |i| !own(i));
                unsafe { d.cmd_end_rendering(cmd) };
            }
        });
    }

    /// One voxel step; voxelization draws the instances of its kind (static or dynamic).
    fn record_voxels(&self, g: &mut Graph, step: crate::gi::Step) {
        let Some(gi) = &self.gi else {
            return;
        };
        let draw = |dynamic: bool| {
            move |cmd: vk::CommandBuffer, p: &Pipeline, flags: u32| {
                self.draw_instances(
                    cmd,
                    p,
                    |i| {
                        let light = self.emitter_of[i].map_or(0, |_| crate::gi::EMITTER_LIGHT);
                        self.mirrored(i) | flags | light
                    },
                    |i| self.dynamic_instances[i] == dynamic,
                )
            }
        };
        let inputs = StepInputs {
            gpu: &self.gpu,
            scene_set: self.scene_set,
            shadow_map: &self.shadow_map,
            draw_static: &draw(false),
            draw_dynamic: &draw(true),
        };
        gi.record_step(&self.ctx, g, step, &inputs);
    }

    /// Cones per pixel, or the first voxel along each camera ray (the voxel modes).
    fn record_trace(&self, g: &mut Graph) {
        let Some(gi) = &self.gi else {
            return;
        };
        let name = if self.settings.mode.shades_pixels() {
            Step::Trace
        } else {
            Step::VoxelView
        }
        .name();
        let trace_mode = match self.settings.mode {
            Mode::Full => TraceMode::Full,
            Mode::Indirect => TraceMode::Indirect,
            Mode::Ao => TraceMode::Ao,
            Mode::VoxelsAlbedo => TraceMode::VoxelAlbedo,
            Mode::VoxelsNormal => TraceMode::VoxelNormal,
            Mode::VoxelsEmission => TraceMode::VoxelEmission,
            Mode::VoxelsRadiance if self.settings.mip.is_some() => TraceMode::Directional,
            Mode::VoxelsRadiance => TraceMode::VoxelRadiance,
            Mode::Direct => unreachable!("direct mode has no voxel passes"),
        };
        gi.trace.record(
            &self.ctx,
            g,
            &gi.volumes,
            self.scene_set,
            &self.gbuffer,
            &self.hdr,
            trace_mode,
            &name,
        );
    }

    fn record_gbuffer(&self, g: &mut Graph) {
        let ctx = &self.ctx;
        let d = &ctx.device;
        let (w, h) = (self.settings.width, self.settings.height);
        let name = Step::GBuffer.name();
        let mut pass = g
            .pass(&name)
            .image(&self.depth, Access::DepthAttachmentWrite)
            .buffer(&self.gpu.vertices, Access::VertexBuffer)
            .buffer(&self.gpu.indices, Access::IndexBuffer);
        for img in &self.gbuffer {
            pass = pass.image(img, Access::ColorAttachmentWrite);
        }
        for t in &self.gpu.textures {
            pass = pass.image(t, Access::FragmentSampled);
        }
        pass.record(|cmd| {
            let colors: Vec<_> = self
                .gbuffer
                .iter()
                .map(|img| {
                    vk::RenderingAttachmentInfo::default()
                        .image_view(img.view)
                        .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                        .load_op(vk::AttachmentLoadOp::CLEAR)
                        .store_op(vk::AttachmentStoreOp::STORE)
                        .clear_value(vk::ClearValue {
                            color: vk::ClearColorValue { float32: [0.0; 4] },
                        })
                })
                .collect();
            let depth = pipelines::cleared_depth(self.depth.view, vk::AttachmentStoreOp::DONT_CARE);
            let info = vk::RenderingInfo::default()
                .render_area(pipelines::area(w, h))
                .layer_count(1)
                .color_attachments(&colors)
                .depth_attachment(&depth);
            unsafe { d.cmd_begin_rendering(cmd, &info) };
            pipelines::set_viewport(ctx, cmd, w, h);
            self.draw_instances(cmd, &self.gbuffer_pipeline, |i| self.mirrored(i), |_| true);
            unsafe { d.cmd_end_rendering(cmd) };
        });
    }

    fn record_lighting(&self, g: &mut Graph) {
        let d = &self.ctx.device;
        let (w, h) = (self.settings.width, self.settings.height);
        let name = Step::Lighting.name();
        let mut pass = g
            .pass(&name)
            .image(&self.shadow_map, Access::ComputeSampled)
            .image(&self.hdr, Access::ComputeStorageWrite);
        for img in &self.gbuffer {
            pass = pass.image(img, Access::ComputeSampled);
        }
        pass.record(|cmd| unsafe {
            let p = &self.lighting_pipeline;
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, p.raw);
            d.cmd_bind_descriptor_sets(
                cmd,
                vk::PipelineBindPoint::COMPUTE,
                p.layout,
                0,
                &[self.scene_set, self.lighting_set],
                &[],
            );
            d.cmd_dispatch(cmd, w.div_ceil(8), h.div_ceil(8), 1);
        });
    }

    fn record_readback(&self, g: &mut Graph) {
        let d = &self.ctx.device;
        let (w, h) = (self.settings.width, self.settings.height);
        {
            g.pass(&Step::Readback.name())
                .image(&self.hdr, Access::TransferRead)
                .buffer(&self.readback, Access::TransferWrite)
                .record(|cmd| unsafe {
                    let region = vk::BufferImageCopy::default()
                        .image_subresource(vk::ImageSubresourceLayers {
                            aspect_mask: vk::ImageAspectFlags::COLOR,
                            mip_level: 0,
                            base_array_layer: 0,
                            layer_count: 1,
                        })
                        .image_extent(vk::Extent3D {
                            width: w,
                            height: h,
                            depth: 1,
                        });
                    d.cmd_copy_image_to_buffer(
                        cmd,
                        self.hdr.raw,
                        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                        self.readback.raw,
                        &[region],
                    );
                });
            g.barrier("to host")
                .buffer(&self.readback, Access::HostRead)
                .record(|_| {});
        }
    }

    fn mirrored(&self, instance: usize) -> u32 {
        self.transforms[instance].determinant().is_sign_negative() as u32
    }

    /// Moves every instance of a glTF node: the next frame voxelizes again the geometry of
    /// its kind (dynamic or static), lights the voxels again and draws again the shadow views
    /// it moves through. Setting the transform it has changes nothing.
    pub fn set_node_transform(&mut self, node: usize, world: Mat4) {
        let (mut moved_static, mut moved_dynamic) = (false, false);
        let mut moved = Vec::new();
        for (i, &n) in self.instance_nodes.iter().enumerate() {
            if n == node && self.transforms[i] != world {
                moved.push(i);
                // Where it was and where it goes: the views that see either draw again.
                let b = &self.instance_bounds[i];
                let swept = b
                    .transformed(&self.transforms[i])
                    .union(&b.transformed(&world));
                let views = self.gpu.light_views.iter().flat_map(|l| &l.views);
                for (dirty, v) in self.shadow_views_dirty.iter_mut().zip(views) {
                    *dirty |= super::shadows::may_see(&v.view_proj, &swept);
                }
                self.transforms[i] = world;
                moved_static |= !self.dynamic_instances[i];
                moved_dynamic |= self.dynamic_instances[i];
            }
        }
        if let Some(gi) = self.gi.as_mut() {
            gi.dirty.static_voxels |= moved_static;
            gi.dirty.dynamic_voxels |= moved_dynamic;
        }
        // An emitter light goes with its faces: its views draw again and the voxels are lit
        // again.
        let mut moved_light = false;
        for k in 0..self.emitters.len() {
            if moved.contains(&self.emitters[k].instance) {
                self.emitters[k].place(&world);
                let v = &self.gpu.light_views[self.lights.len() + k];
                let views = v.first as usize..v.first as usize + v.views.len();
                self.shadow_views_dirty[views].fill(true);
                moved_light = true;
            }
        }
        if moved_light {
            self.write_lights();
            if let Some(gi) = self.gi.as_mut() {
                gi.dirty.lights = true;
            }
        }
    }

    /// The emitters smaller than a voxel that light the scene as lights.
    pub fn emitter_lights(&self) -> &[EmitterLight] {
        &self.emitters
    }

    /// Writes the lights and their shadow views (the scene's and the emitters') for the next
    /// frame; the previous frame was waited for, so nothing on the GPU reads them now.
    fn write_lights(&mut self) {
        let (views, gpu_lights) = light_table(
            &self.lights,
            &self.emitters,
            &self.bounds,
            self.settings.shadow_resolution,
            self.settings.pcf_radius,
        );
        let all_views: Vec<_> = views.iter().flat_map(|v| v.views.iter().copied()).collect();
        if !gpu_lights.is_empty() {
            self.gpu.lights.write(0, as_bytes(&gpu_lights));
        }
        if !all_views.is_empty() {
            self.gpu.shadow_views.write(0, as_bytes(&all_views));
        }
        self.gpu.light_views = views;
    }

    /// A new frame size: the G-buffer, radiance and readback images are made again at the
    /// new size; the scene, the shadow maps and the voxels stay (no voxelization again).
    pub fn resize(&mut self, width: u32, height: u32) -> VkResult<()> {
        if (width, height) == (self.settings.width, self.settings.height) {
            return Ok(());
        }
        let (gbuffer, depth, hdr, readback) = frame_images(&self.ctx, width, height)?;
        let mut descs: Vec<(u32, Desc)> = gbuffer
            .iter()
            .enumerate()
            .map(|(i, img)| (i as u32, Desc::Sampled(img.view, self.nearest.raw)))
            .collect();
        descs.push((6, Desc::StorageImage(hdr.view)));
        // Every frame before was waited for: the sets are not in use.
        pipelines::write_set(&self.ctx, self.lighting_set, &descs);
        if let Some(gi) = &self.gi {
            let views: Vec<_> = gbuffer.iter().map(|i| (i.view, self.nearest.raw)).collect();
            gi.trace.retarget(&self.ctx, &views, &hdr);
        }
        for img in self.gbuffer.iter().chain([&self.depth, &self.hdr]) {
            self.states.forget(img.raw);
        }
        self.states.forget(self.readback.raw);
        self.gbuffer = gbuffer;
        self.depth = depth;
        self.hdr = hdr;
        self.readback = readback;
        self.settings.width = width;
        self.settings.height = height;
        Ok(())
    }

    /// Moves or changes the lights (one per scene light, each of its kind as loaded, so the
    /// shadow views keep their number): the next frame draws their shadow maps and lights the
    /// voxels with them.
    pub fn set_lights(&mut self, lights: &[crate::scene::Light]) -> VkResult<()> {
        use super::shadows::light_views;
        let views = light_views(
            lights,
            &self.bounds,
            self.settings.shadow_resolution,
            self.settings.pcf_radius,
        );
        let counts: Vec<usize> = views.iter().map(|v| v.views.len()).collect();
        let before: Vec<usize> = self.gpu.light_views[..self.lights.len()]
            .iter()
            .map(|v| v.views.len())
            .collect();
        if lights.len() != self.lights.len() || counts != before {
            return Err(VkError::Request(
                "set_lights: the lights must keep their number and kinds".into(),
            ));
        }
        self.lights = lights.to_vec();
        self.write_lights();
        self.relight();
        Ok(())
    }

    /// The next frame draws every shadow map and lights the voxels again (bounces included),
    /// as after a light moved; the benchmark times such frames.
    pub fn relight(&mut self) {
        self.shadow_views_dirty.fill(true);
        if let Some(gi) = self.gi.as_mut() {
            gi.dirty.lights = true;
        }
    }

    /// Debug readback of the voxel volumes as the last frame left them (None in direct mode).
    pub fn read_voxels(&mut self) -> VkResult<Option<crate::gi::VoxelDump>> {
        match &self.gi {
            Some(gi) => Ok(Some(gi.read_voxels(&self.ctx, &mut self.states)?)),
            None => Ok(None),
        }
    }

    /// Non-finite values in the lit volumes as the last frame left them, one level at a time
    /// (None in direct mode).
    pub fn count_non_finite(&mut self) -> VkResult<Option<crate::gi::NonFinite>> {
        match &self.gi {
            Some(gi) => Ok(Some(gi.count_non_finite(&self.ctx, &mut self.states)?)),
            None => Ok(None),
        }
    }

    /// Linear radiance, RGB per pixel, row 0 at the top (after `render(true)`).
    pub fn radiance(&self) -> Vec<[f32; 3]> {
        let bytes = self
            .readback
            .mapped()
            .expect("readback buffer is host-visible");
        let (w, h) = (self.settings.width as usize, self.settings.height as usize);
        bytes[..w * h * 16]
            .chunks_exact(16)
            .map(|c| {
                let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
                [f(0), f(4), f(8)]
            })
            .collect()
    }

    /// The frame's linear radiance (RGBA32F, storage in GENERAL), for passes that follow.
    pub fn radiance_image(&self) -> &Image {
        &self.hdr
    }

    pub fn context(&self) -> &Arc<Context> {
        &self.ctx
    }
}

impl Drop for Renderer {
    fn drop(&mut self) {
        // The fields free themselves after this, once the device has finished with them.
        unsafe {
            let _ = self.ctx.device.device_wait_idle();
        }
    }
}

/// The renderer's command pool, freed on drop (also when `Renderer::new` fails half way).
struct CommandPool {
    raw: vk::CommandPool,
    ctx: Arc<Context>,
}

impl Drop for CommandPool {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_command_pool(self.raw, None) };
    }
}
