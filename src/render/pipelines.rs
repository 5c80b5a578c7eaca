//! Shader modules, descriptor-set layouts and pipelines, each freed by its owner's Drop.

use crate::scene::Vertex;
use crate::vk::{vk, Context, VkError, VkResult};
use std::sync::Arc;

fn check<T>(r: Result<T, vk::Result>, call: &'static str) -> VkResult<T> {
    r.map_err(|result| VkError::Call { call, result })
}

pub fn spirv(name: &str) -> VkResult<Vec<u32>> {
    crate::shaders::words(name).ok_or_else(|| VkError::NoShader(name.into()))
}

struct Module<'a> {
    ctx: &'a Context,
    raw: vk::ShaderModule,
}

impl<'a> Module<'a> {
    fn new(ctx: &'a Context, name: &str) -> VkResult<Self> {
        let code = spirv(name)?;
        let info = vk::ShaderModuleCreateInfo::default().code(&code);
        let raw = check(
            unsafe { ctx.device.create_shader_module(&info, None) },
            "vkCreateShaderModule",
        )?;
        Ok(Module { ctx, raw })
    }
}

impl Drop for Module<'_> {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_shader_module(self.raw, None) };
    }
}

pub struct SetLayout {
    ctx: Arc<Context>,
    pub raw: vk::DescriptorSetLayout,
}

impl SetLayout {
    /// (binding, type, count, stages) per binding.
    pub fn new(
        ctx: &Arc<Context>,
        bindings: &[(u32, vk::DescriptorType, u32, vk::ShaderStageFlags)],
    ) -> VkResult<Self> {
        let b: Vec<_> = bindings
            .iter()
            .map(|&(binding, ty, count, stages)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(binding)
                    .descriptor_type(ty)
                    .descriptor_count(count)
                    .stage_flags(stages)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&b);
        let raw = check(
            unsafe { ctx.device.create_descriptor_set_layout(&info, None) },
            "vkCreateDescriptorSetLayout",
        )?;
        Ok(SetLayout {
            ctx: ctx.clone(),
            raw,
        })
    }
}

impl Drop for SetLayout {
    fn drop(&mut self) {
        unsafe {
            self.ctx
                .device
                .destroy_descriptor_set_layout(self.raw, None)
        };
    }
}

pub struct DescriptorPool {
    ctx: Arc<Context>,
    pub raw: vk::DescriptorPool,
}

impl DescriptorPool {
    pub fn new(
        ctx: &Arc<Context>,
        sizes: &[vk::DescriptorPoolSize],
        max_sets: u32,
    ) -> VkResult<Self> {
        let info = vk::DescriptorPoolCreateInfo::default()
            .pool_sizes(sizes)
            .max_sets(max_sets);
        let raw = check(
            unsafe { ctx.device.create_descriptor_pool(&info, None) },
            "vkCreateDescriptorPool",
        )?;
        Ok(DescriptorPool {
            ctx: ctx.clone(),
            raw,
        })
    }

    pub fn allocate(&self, layout: &SetLayout) -> VkResult<vk::DescriptorSet> {
        let layouts = [layout.raw];
        let info = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(self.raw)
            .set_layouts(&layouts);
        Ok(check(
            unsafe { self.ctx.device.allocate_descriptor_sets(&info) },
            "vkAllocateDescriptorSets",
        )?[0])
    }
}

/// One descriptor of a set, for `DescriptorPool::set`.
pub enum Desc<'a> {
    Uniform(&'a crate::vk::Buffer),
    Storage(&'a crate::vk::Buffer),
    /// A combined image sampler in SHADER_READ_ONLY_OPTIMAL.
    Sampled(vk::ImageView, vk::Sampler),
    /// A storage image in GENERAL.
    StorageImage(vk::ImageView),
}

/// A descriptor set with the layout made for it.
pub struct Set {
    pub layout: SetLayout,
    pub raw: vk::DescriptorSet,
}

impl Desc<'_> {
    fn ty(&self) -> vk::DescriptorType {
        match self {
            Desc::Uniform(_) => vk::DescriptorType::UNIFORM_BUFFER,
            Desc::Storage(_) => vk::DescriptorType::STORAGE_BUFFER,
            Desc::Sampled(..) => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
            Desc::StorageImage(_) => vk::DescriptorType::STORAGE_IMAGE,
        }
    }
}

/// Writes descriptors into `set` (which no submitted work may be using).
pub fn write_set(ctx: &Context, set: vk::DescriptorSet, descs: &[(u32, Desc)]) {
    let buffers: Vec<[vk::DescriptorBufferInfo; 1]> = descs
        .iter()
        .map(|(_, d)| match d {
            Desc::Uniform(b) | Desc::Storage(b) => [vk::DescriptorBufferInfo {
                buffer: b.raw,
                offset: 0,
                range: vk::WHOLE_SIZE,
            }],
            _ => [vk::DescriptorBufferInfo::default()],
        })
        .collect();
    let images: Vec<[vk::DescriptorImageInfo; 1]> = descs
        .iter()
        .map(|(_, d)| match d {
            Desc::Sampled(view, sampler) => [vk::DescriptorImageInfo {
                sampler: *sampler,
                image_view: *view,
                image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            }],
            Desc::StorageImage(view) => [vk::DescriptorImageInfo {
                sampler: vk::Sampler::null(),
                image_view: *view,
                image_layout: vk::ImageLayout::GENERAL,
            }],
            _ => [vk::DescriptorImageInfo::default()],
        })
        .collect();
    let writes: Vec<_> = descs
        .iter()
        .enumerate()
        .map(|(i, (b, d))| {
            let w = vk::WriteDescriptorSet::default()
                .dst_set(set)
                .dst_binding(*b)
                .descriptor_type(d.ty());
            match d {
                Desc::Uniform(_) | Desc::Storage(_) => w.buffer_info(&buffers[i]),
                _ => w.image_info(&images[i]),
            }
        })
        .collect();
    unsafe { ctx.device.update_descriptor_sets(&writes, &[]) };
}

impl DescriptorPool {
    /// Makes a layout from the descriptors' kinds, allocates a set and writes it.
    pub fn set(&self, stages: vk::ShaderStageFlags, descs: &[(u32, Desc)]) -> VkResult<Set> {
        let bindings: Vec<_> = descs.iter().map(|(b, d)| (*b, d.ty(), 1, stages)).collect();
        let layout = SetLayout::new(&self.ctx, &bindings)?;
        let raw = self.allocate(&layout)?;
        write_set(&self.ctx, raw, descs);
        Ok(Set { layout, raw })
    }
}

impl Drop for DescriptorPool {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_descriptor_pool(self.raw, None) };
    }
}

pub struct Pipeline {
    ctx: Arc<Context>,
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    /// The stages its push-constant range is visible to.
    pub push_stages: vk::ShaderStageFlags,
}

impl Pipeline {
    /// Binds this compute pipeline and its descriptor sets from set 0, for a dispatch.
    ///
    /// # Safety
    /// `cmd` is recording and the sets match the pipeline's layout.
    pub unsafe fn bind_compute(
        &self,
        d: &ash::Device,
        cmd: vk::CommandBuffer,
        sets: &[vk::DescriptorSet],
    ) {
        d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.raw);
        d.cmd_bind_descriptor_sets(
            cmd,
            vk::PipelineBindPoint::COMPUTE,
            self.layout,
            0,
            sets,
            &[],
        );
    }
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        unsafe {
            self.ctx.device.destroy_pipeline(self.raw, None);
            self.ctx.device.destroy_pipeline_layout(self.layout, None);
        }
    }
}

fn pipeline_layout(
    ctx: &Context,
    sets: &[&SetLayout],
    push_size: u32,
    push_stages: vk::ShaderStageFlags,
) -> VkResult<vk::PipelineLayout> {
    let raw_sets: Vec<_> = sets.iter().map(|s| s.raw).collect();
    let ranges = [vk::PushConstantRange::default()
        .stage_flags(push_stages)
        .offset(0)
        .size(push_size)];
    let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(&raw_sets);
    if push_size > 0 {
        info = info.push_constant_ranges(&ranges);
    }
    check(
        unsafe { ctx.device.create_pipeline_layout(&info, None) },
        "vkCreatePipelineLayout",
    )
}

/// Specialisation constants, all 32-bit, ids 0..n.
pub struct Spec(pub Vec<u32>);

impl Spec {
    fn entries(&self) -> Vec<vk::SpecializationMapEntry> {
        (0..self.0.len() as u32)
            .map(|i| vk::SpecializationMapEntry {
                constant_id: i,
                offset: i * 4,
                size: 4,
            })
            .collect()
    }
    fn data(&self) -> Vec<u8> {
        self.0.iter().flat_map(|v| v.to_le_bytes()).collect()
    }
}

pub fn compute(
    ctx: &Arc<Context>,
    shader: &str,
    sets: &[&SetLayout],
    push_size: u32,
    spec: &Spec,
) -> VkResult<Pipeline> {
    let module = Module::new(ctx, shader)?;
    let layout = pipeline_layout(ctx, sets, push_size, vk::ShaderStageFlags::COMPUTE)?;
    let entries = spec.entries();
    let data = spec.data();
    let spec_info = vk::SpecializationInfo::default()
        .map_entries(&entries)
        .data(&data);
    let stage = vk::PipelineShaderStageCreateInfo::default()
        .stage(vk::ShaderStageFlags::COMPUTE)
        .module(module.raw)
        .name(c"main")
        .specialization_info(&spec_info);
    let info = vk::ComputePipelineCreateInfo::default()
        .stage(stage)
        .layout(layout);
    let raw = unsafe {
        ctx.device
            .create_compute_pipelines(vk::PipelineCache::null(), &[info], None)
    };
    match raw {
        Ok(p) => {
            ctx.set_name(p[0], shader);
            Ok(Pipeline {
                ctx: ctx.clone(),
                raw: p[0],
                layout,
                push_stages: vk::ShaderStageFlags::COMPUTE,
            })
        }
        Err((_, result)) => {
            unsafe { ctx.device.destroy_pipeline_layout(layout, None) };
            Err(VkError::Call {
                call: "vkCreateComputePipelines",
                result,
            })
        }
    }
}

/// What a raster pipeline needs; dynamic rendering, so no render-pass object.
pub struct GraphicsDesc<'a> {
    pub name: &'a str,
    /// (stage, shader file) pairs.
    pub shaders: &'a [(vk::ShaderStageFlags, &'a str)],
    pub sets: &'a [&'a SetLayout],
    pub push_size: u32,
    pub spec: Spec,
    /// Which scene vertex attributes the vertex shader reads (0 position, 1 normal, 2 uv,
    /// 3 tangent); empty for none.
    pub vertex_input: &'a [u32],
    pub color_formats: &'a [vk::Format],
    pub depth_format: Option<vk::Format>,
    /// Depth bias (constant, slope) for shadow maps.
    pub depth_bias: Option<(f32, f32)>,
    pub cull: vk::CullModeFlags,
}

pub fn graphics(ctx: &Arc<Context>, desc: &GraphicsDesc) -> VkResult<Pipeline> {
    let modules = desc
        .shaders
        .iter()
        .map(|(_, name)| Module::new(ctx, name))
        .collect::<VkResult<Vec<_>>>()?;
    let push_stages = desc
        .shaders
        .iter()
        .fold(vk::ShaderStageFlags::empty(), |a, (s, _)| a | *s);
    let layout = pipeline_layout(ctx, desc.sets, desc.push_size, push_stages)?;
    let entries = desc.spec.entries();
    let data = desc.spec.data();
    let spec_info = vk::SpecializationInfo::default()
        .map_entries(&entries)
        .data(&data);
    let stages: Vec<_> = desc
        .shaders
        .iter()
        .zip(&modules)
        .map(|((stage, _), m)| {
            vk::PipelineShaderStageCreateInfo::default()
                .stage(*stage)
                .module(m.raw)
                .name(c"main")
                .specialization_info(&spec_info)
        })
        .collect();

    let bindings = [vk::VertexInputBindingDescription {
        binding: 0,
        stride: std::mem::size_of::<Vertex>() as u32,
        input_rate: vk::VertexInputRate::VERTEX,
    }];
    let attributes = [
        (0, vk::Format::R32G32B32_SFLOAT, 0),
        (1, vk::Format::R32G32B32_SFLOAT, 12),
        (2, vk::Format::R32G32_SFLOAT, 24),
        (3, vk::Format::R32G32B32A32_SFLOAT, 32),
    ]
    .into_iter()
    .filter(|(location, _, _)| desc.vertex_input.contains(location))
    .map(
        |(location, format, offset)| vk::VertexInputAttributeDescription {
            location,
            binding: 0,
            format,
            offset,
        },
    )
    .collect::<Vec<_>>();
    let vertex_input = if !desc.vertex_input.is_empty() {
        vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(&bindings)
            .vertex_attribute_descriptions(&attributes)
    } else {
        vk::PipelineVertexInputStateCreateInfo::default()
    };
    let input_assembly = vk::PipelineInputAssemblyStateCreateInfo::default()
        .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
    let viewport = vk::PipelineViewportStateCreateInfo::default()
        .viewport_count(1)
        .scissor_count(1);
    let mut raster = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(desc.cull)
        // With the negative-height viewport, counter-clockwise stays front-facing as in glTF.
        .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
        .line_width(1.0);
    if let Some((constant, slope)) = desc.depth_bias {
        raster = raster
            .depth_bias_enable(true)
            .depth_bias_constant_factor(constant)
            .depth_bias_slope_factor(slope)
            // Casters behind the light's near plane still cast.
            .depth_clamp_enable(true);
    }
    let multisample = vk::PipelineMultisampleStateCreateInfo::default()
        .rasterization_samples(vk::SampleCountFlags::TYPE_1);
    let depth = vk::PipelineDepthStencilStateCreateInfo::default()
        .depth_test_enable(desc.depth_format.is_some())
        .depth_write_enable(desc.depth_format.is_some())
        .depth_compare_op(vk::CompareOp::LESS);
    let blend_attachments: Vec<_> = desc
        .color_formats
        .iter()
        .map(|_| {
            vk::PipelineColorBlendAttachmentState::default()
                .color_write_mask(vk::ColorComponentFlags::RGBA)
        })
        .collect();
    let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
    let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
    let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
    let mut rendering = vk::PipelineRenderingCreateInfo::default()
        .color_attachment_formats(desc.color_formats)
        .depth_attachment_format(desc.depth_format.unwrap_or(vk::Format::UNDEFINED));
    let info = vk::GraphicsPipelineCreateInfo::default()
        .stages(&stages)
        .vertex_input_state(&vertex_input)
        .input_assembly_state(&input_assembly)
        .viewport_state(&viewport)
        .rasterization_state(&raster)
        .multisample_state(&multisample)
        .depth_stencil_state(&depth)
        .color_blend_state(&blend)
        .dynamic_state(&dynamic)
        .layout(layout)
        .push_next(&mut rendering);
    let raw = unsafe {
        ctx.device
            .create_graphics_pipelines(vk::PipelineCache::null(), &[info], None)
    };
    match raw {
        Ok(p) => {
            ctx.set_name(p[0], desc.name);
            Ok(Pipeline {
                ctx: ctx.clone(),
                raw: p[0],
                layout,
                push_stages,
            })
        }
        Err((_, result)) => {
            unsafe { ctx.device.destroy_pipeline_layout(layout, None) };
            Err(VkError::Call {
                call: "vkCreateGraphicsPipelines",
                result,
            })
        }
    }
}

/// Sets a viewport with negative height (y up, as in OpenGL and glTF) and a full scissor.
pub fn set_viewport(ctx: &Context, cmd: vk::CommandBuffer, width: u32, height: u32) {
    let viewport = vk::Viewport {
        x: 0.0,
        y: height as f32,
        width: width as f32,
        height: -(height as f32),
        min_depth: 0.0,
        max_depth: 1.0,
    };
    let scissor = vk::Rect2D {
        offset: vk::Offset2D { x: 0, y: 0 },
        extent: vk::Extent2D { width, height },
    };
    unsafe {
        ctx.device.cmd_set_viewport(cmd, 0, &[viewport]);
        ctx.device.cmd_set_scissor(cmd, 0, &[scissor]);
    }
}

/// A depth attachment cleared to 1 (the far plane).
pub fn cleared_depth(
    view: vk::ImageView,
    store: vk::AttachmentStoreOp,
) -> vk::RenderingAttachmentInfo<'static> {
    vk::RenderingAttachmentInfo::default()
        .image_view(view)
        .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(store)
        .clear_value(vk::ClearValue {
            depth_stencil: vk::ClearDepthStencilValue {
                depth: 1.0,
                stencil: 0,
            },
        })
}

/// The whole of a `width` x `height` target.
pub fn area(width: u32, height: u32) -> vk::Rect2D {
    vk::Rect2D {
        offset: vk::Offset2D { x: 0, y: 0 },
        extent: vk::Extent2D { width, height },
    }
}
