//! Shader modules, descriptor-set layouts, descriptor pools and pipelines, each freed by its
//! owner's Drop. Pipelines are checked against their shaders' reflected interface when they
//! are made: the push-constant range and every binding a shader uses must match the layout.

use super::reflect::{self, Interface};
use super::{Check, Context, VkError, VkResult};
use ash::vk;
use std::sync::Arc;

/// A compiled shader ("file" or "file:VARIANT") and its reflected interface.
pub struct Shader {
    pub name: String,
    pub words: Vec<u32>,
    pub interface: Interface,
}

impl Shader {
    pub fn load(name: &str) -> VkResult<Shader> {
        let words = crate::shaders::words(name).ok_or_else(|| VkError::NoShader(name.into()))?;
        let interface = reflect::reflect(&words).map_err(|problem| VkError::Interface {
            what: name.into(),
            problem,
        })?;
        Ok(Shader {
            name: name.into(),
            words,
            interface,
        })
    }
}

struct Module<'a> {
    ctx: &'a Context,
    raw: vk::ShaderModule,
}

impl<'a> Module<'a> {
    fn new(ctx: &'a Context, shader: &Shader) -> VkResult<Self> {
        let info = vk::ShaderModuleCreateInfo::default().code(&shader.words);
        let raw = unsafe { ctx.device.create_shader_module(&info, None) }
            .check("vkCreateShaderModule")?;
        Ok(Module { ctx, raw })
    }
}

impl Drop for Module<'_> {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_shader_module(self.raw, None) };
    }
}

/// One binding of a set layout, by its GLSL name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LayoutBinding {
    pub binding: u32,
    pub name: String,
    pub ty: vk::DescriptorType,
    pub stages: vk::ShaderStageFlags,
}

/// A descriptor-set layout that knows its bindings' names, so that a pipeline can check that
/// its shaders find there what they declare.
pub struct SetLayout {
    ctx: Arc<Context>,
    pub raw: vk::DescriptorSetLayout,
    pub bindings: Vec<LayoutBinding>,
}

impl SetLayout {
    pub fn new(ctx: &Arc<Context>, bindings: Vec<LayoutBinding>) -> VkResult<Self> {
        let b: Vec<_> = bindings
            .iter()
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b.binding)
                    .descriptor_type(b.ty)
                    .descriptor_count(1)
                    .stage_flags(b.stages)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&b);
        let raw = unsafe { ctx.device.create_descriptor_set_layout(&info, None) }
            .check("vkCreateDescriptorSetLayout")?;
        Ok(SetLayout {
            ctx: ctx.clone(),
            raw,
            bindings,
        })
    }

    /// An empty layout, for a set index no shader of a pipeline uses.
    pub fn empty(ctx: &Arc<Context>) -> VkResult<Self> {
        SetLayout::new(ctx, Vec::new())
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

/// A descriptor pool sized for the sets of one owner.
pub struct DescriptorPool {
    ctx: Arc<Context>,
    pub raw: vk::DescriptorPool,
}

impl DescriptorPool {
    /// Room for `sets` sets of the given layouts (each layout counted once per set of it).
    pub fn for_layouts(ctx: &Arc<Context>, layouts: &[&SetLayout]) -> VkResult<Self> {
        let mut sizes: Vec<vk::DescriptorPoolSize> = Vec::new();
        for b in layouts.iter().flat_map(|l| &l.bindings) {
            match sizes.iter_mut().find(|s| s.ty == b.ty) {
                Some(s) => s.descriptor_count += 1,
                None => sizes.push(vk::DescriptorPoolSize {
                    ty: b.ty,
                    descriptor_count: 1,
                }),
            }
        }
        let info = vk::DescriptorPoolCreateInfo::default()
            .pool_sizes(&sizes)
            .max_sets(layouts.len().max(1) as u32);
        let raw = unsafe { ctx.device.create_descriptor_pool(&info, None) }
            .check("vkCreateDescriptorPool")?;
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
        Ok(unsafe { self.ctx.device.allocate_descriptor_sets(&info) }
            .check("vkAllocateDescriptorSets")?[0])
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
    pub bind_point: vk::PipelineBindPoint,
    /// The stages its push-constant range is visible to.
    pub push_stages: vk::ShaderStageFlags,
}

impl Pipeline {
    /// Binds this pipeline.
    ///
    /// # Safety
    /// `cmd` is recording.
    pub unsafe fn bind(&self, d: &ash::Device, cmd: vk::CommandBuffer) {
        d.cmd_bind_pipeline(cmd, self.bind_point, self.raw);
    }

    /// Binds descriptor sets from set `first` on.
    ///
    /// # Safety
    /// `cmd` is recording and the sets match the pipeline's layout.
    pub unsafe fn bind_sets(
        &self,
        d: &ash::Device,
        cmd: vk::CommandBuffer,
        first: u32,
        sets: &[vk::DescriptorSet],
    ) {
        d.cmd_bind_descriptor_sets(cmd, self.bind_point, self.layout, first, sets, &[]);
    }

    /// Pushes constants to every stage of the range.
    ///
    /// # Safety
    /// `cmd` is recording and `bytes` fits the pipeline's push-constant range.
    pub unsafe fn push(&self, d: &ash::Device, cmd: vk::CommandBuffer, bytes: &[u8]) {
        d.cmd_push_constants(cmd, self.layout, self.push_stages, 0, bytes);
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

/// Checks the shaders against the pipeline's layout: the push-constant block's size, and that
/// each binding a shader uses is in the set layout of its index, under the same name and type.
fn check_interface(what: &str, shaders: &[Shader], sets: &[&SetLayout], push: u32) -> VkResult<()> {
    let err = |problem: String| VkError::Interface {
        what: what.into(),
        problem,
    };
    let declared = shaders
        .iter()
        .map(|s| s.interface.push_constants)
        .max()
        .unwrap_or(0);
    if declared != push {
        return Err(err(format!(
            "its shaders' push constants take {declared} bytes, the pipeline pushes {push}"
        )));
    }
    for s in shaders {
        for b in &s.interface.bindings {
            let found = sets
                .get(b.set as usize)
                .and_then(|l| l.bindings.iter().find(|l| l.binding == b.binding));
            match found {
                Some(l)
                    if l.name == b.name && l.ty == b.ty && l.stages.contains(s.interface.stage) => {
                }
                Some(l) => {
                    return Err(err(format!(
                    "{} uses set {} binding {} as {:?} ({:?}), the layout has {:?} ({:?}, {:?})",
                    s.name, b.set, b.binding, b.name, b.ty, l.name, l.ty, l.stages
                )))
                }
                None => {
                    return Err(err(format!(
                        "{} uses set {} binding {} ({:?}), which the layout lacks",
                        s.name, b.set, b.binding, b.name
                    )))
                }
            }
        }
    }
    Ok(())
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
    unsafe { ctx.device.create_pipeline_layout(&info, None) }.check("vkCreatePipelineLayout")
}

/// A compute pipeline of `shader` over `sets` (by set index) pushing `push_size` bytes.
pub fn compute(
    ctx: &Arc<Context>,
    shader: &Shader,
    sets: &[&SetLayout],
    push_size: u32,
) -> VkResult<Pipeline> {
    check_interface(&shader.name, std::slice::from_ref(shader), sets, push_size)?;
    let module = Module::new(ctx, shader)?;
    let stages = vk::ShaderStageFlags::COMPUTE;
    let layout = pipeline_layout(ctx, sets, push_size, stages)?;
    let stage = vk::PipelineShaderStageCreateInfo::default()
        .stage(stages)
        .module(module.raw)
        .name(c"main");
    let info = vk::ComputePipelineCreateInfo::default()
        .stage(stage)
        .layout(layout);
    let raw = unsafe {
        ctx.device
            .create_compute_pipelines(vk::PipelineCache::null(), &[info], None)
    };
    match raw {
        Ok(p) => {
            ctx.set_name(p[0], &shader.name);
            Ok(Pipeline {
                ctx: ctx.clone(),
                raw: p[0],
                layout,
                bind_point: vk::PipelineBindPoint::COMPUTE,
                push_stages: stages,
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

/// How vertices are laid out in the vertex buffer (binding 0).
#[derive(Clone, Copy, Debug)]
pub struct VertexLayout<'a> {
    pub stride: u32,
    /// (location, format, offset) of each attribute the vertex shader reads.
    pub attributes: &'a [(u32, vk::Format, u32)],
}

/// What a raster pipeline draws with; dynamic rendering, so no render-pass object.
pub struct GraphicsDesc<'a> {
    pub name: &'a str,
    /// (stage, shader) pairs, by the compiled shaders' names.
    pub shaders: &'a [(vk::ShaderStageFlags, &'a str)],
    /// None: no vertex buffer (the vertex shader makes its own).
    pub vertices: Option<VertexLayout<'a>>,
    pub color_formats: &'a [vk::Format],
    pub depth_format: Option<vk::Format>,
    /// Depth bias (constant, slope) for shadow maps.
    pub depth_bias: Option<(f32, f32)>,
    pub cull: vk::CullModeFlags,
}

pub fn graphics(
    ctx: &Arc<Context>,
    desc: &GraphicsDesc,
    shaders: &[Shader],
    sets: &[&SetLayout],
    push_size: u32,
) -> VkResult<Pipeline> {
    check_interface(desc.name, shaders, sets, push_size)?;
    let modules = shaders
        .iter()
        .map(|s| Module::new(ctx, s))
        .collect::<VkResult<Vec<_>>>()?;
    let push_stages = desc
        .shaders
        .iter()
        .fold(vk::ShaderStageFlags::empty(), |a, (s, _)| a | *s);
    let layout = pipeline_layout(ctx, sets, push_size, push_stages)?;
    let stages: Vec<_> = desc
        .shaders
        .iter()
        .zip(&modules)
        .map(|((stage, _), m)| {
            vk::PipelineShaderStageCreateInfo::default()
                .stage(*stage)
                .module(m.raw)
                .name(c"main")
        })
        .collect();

    let bindings: Vec<_> = desc
        .vertices
        .iter()
        .map(|v| vk::VertexInputBindingDescription {
            binding: 0,
            stride: v.stride,
            input_rate: vk::VertexInputRate::VERTEX,
        })
        .collect();
    let attributes: Vec<_> = desc
        .vertices
        .iter()
        .flat_map(|v| v.attributes)
        .map(
            |&(location, format, offset)| vk::VertexInputAttributeDescription {
                location,
                binding: 0,
                format,
                offset,
            },
        )
        .collect();
    let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
        .vertex_binding_descriptions(&bindings)
        .vertex_attribute_descriptions(&attributes);
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
                bind_point: vk::PipelineBindPoint::GRAPHICS,
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
    unsafe {
        ctx.device.cmd_set_viewport(cmd, 0, &[viewport]);
        ctx.device.cmd_set_scissor(cmd, 0, &[area(width, height)]);
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
