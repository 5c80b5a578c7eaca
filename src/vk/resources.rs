//! Thin RAII wrappers: each owns its Vulkan object and named allocation and frees them in Drop.

use super::{Check, Context, VkResult};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

pub struct Buffer {
    ctx: Arc<Context>,
    pub raw: vk::Buffer,
    pub size: u64,
    allocation: Option<Allocation>,
    pub name: String,
}

impl Buffer {
    /// A host-visible buffer that copies from the device land in (a readback).
    pub fn readback(ctx: &Arc<Context>, name: &str, size: u64) -> VkResult<Buffer> {
        Buffer::new(
            ctx,
            name,
            size,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )
    }

    pub fn new(
        ctx: &Arc<Context>,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> VkResult<Buffer> {
        let size = size.max(4);
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(usage)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        let raw = unsafe { ctx.device.create_buffer(&info, None) }.check("vkCreateBuffer")?;
        let requirements = unsafe { ctx.device.get_buffer_memory_requirements(raw) };
        let allocation = ctx.allocate(&AllocationCreateDesc {
            name,
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                unsafe { ctx.device.destroy_buffer(raw, None) };
                return Err(e);
            }
        };
        let bound = unsafe {
            ctx.device
                .bind_buffer_memory(raw, allocation.memory(), allocation.offset())
        };
        let buffer = Buffer {
            ctx: ctx.clone(),
            raw,
            size,
            allocation: Some(allocation),
            name: name.into(),
        };
        bound.check("vkBindBufferMemory")?;
        ctx.set_name(raw, name);
        Ok(buffer)
    }

    /// A host-visible buffer filled with `data`.
    pub fn with_data(
        ctx: &Arc<Context>,
        name: &str,
        data: &[u8],
        usage: vk::BufferUsageFlags,
    ) -> VkResult<Buffer> {
        let mut b = Buffer::new(
            ctx,
            name,
            data.len() as u64,
            usage,
            MemoryLocation::CpuToGpu,
        )?;
        b.write(0, data);
        Ok(b)
    }

    /// Where shaders reach it (GL_EXT_buffer_reference); made with SHADER_DEVICE_ADDRESS.
    pub fn address(&self) -> u64 {
        let info = vk::BufferDeviceAddressInfo::default().buffer(self.raw);
        unsafe { self.ctx.device.get_buffer_device_address(&info) }
    }

    /// Host-visible bytes (None for device-only memory).
    pub fn mapped(&self) -> Option<&[u8]> {
        self.allocation.as_ref()?.mapped_slice()
    }

    pub fn mapped_mut(&mut self) -> Option<&mut [u8]> {
        self.allocation.as_mut()?.mapped_slice_mut()
    }

    /// Copies bytes into a host-visible buffer.
    pub fn write(&mut self, offset: usize, data: &[u8]) {
        let name = self.name.clone();
        let slice = self
            .mapped_mut()
            .unwrap_or_else(|| panic!("buffer {name} is not host-visible"));
        slice[offset..offset + data.len()].copy_from_slice(data);
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_buffer(self.raw, None) };
        if let Some(a) = self.allocation.take() {
            let _ = self.ctx.allocator().free(a);
        }
    }
}

/// What an image is made of.
#[derive(Clone, Debug)]
pub struct ImageDesc {
    pub format: vk::Format,
    pub extent: vk::Extent3D,
    pub image_type: vk::ImageType,
    pub mip_levels: u32,
    pub array_layers: u32,
    pub usage: vk::ImageUsageFlags,
    pub flags: vk::ImageCreateFlags,
    /// View the whole image as a 2D array (even with one layer).
    pub array_view: bool,
}

impl ImageDesc {
    pub fn d2(format: vk::Format, width: u32, height: u32, usage: vk::ImageUsageFlags) -> Self {
        ImageDesc {
            format,
            extent: vk::Extent3D {
                width,
                height,
                depth: 1,
            },
            image_type: vk::ImageType::TYPE_2D,
            mip_levels: 1,
            array_layers: 1,
            usage,
            flags: vk::ImageCreateFlags::empty(),
            array_view: false,
        }
    }
    pub fn d3(format: vk::Format, size: u32, usage: vk::ImageUsageFlags) -> Self {
        ImageDesc {
            extent: vk::Extent3D {
                width: size,
                height: size,
                depth: size,
            },
            image_type: vk::ImageType::TYPE_3D,
            ..Self::d2(format, size, size, usage)
        }
    }
    pub fn mips(mut self, levels: u32) -> Self {
        self.mip_levels = levels;
        self
    }
    pub fn layers(mut self, layers: u32) -> Self {
        self.array_layers = layers;
        self.array_view = true;
        self
    }
}

pub fn aspect_of(format: vk::Format) -> vk::ImageAspectFlags {
    match format {
        vk::Format::D32_SFLOAT | vk::Format::D16_UNORM | vk::Format::X8_D24_UNORM_PACK32 => {
            vk::ImageAspectFlags::DEPTH
        }
        vk::Format::D24_UNORM_S8_UINT | vk::Format::D32_SFLOAT_S8_UINT => {
            vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
        }
        _ => vk::ImageAspectFlags::COLOR,
    }
}

pub struct Image {
    ctx: Arc<Context>,
    pub raw: vk::Image,
    pub desc: ImageDesc,
    /// A view of every level and layer.
    pub view: vk::ImageView,
    /// One 2D view per array layer (for rendering into layers), empty for 1-layer images.
    pub layer_views: Vec<vk::ImageView>,
    /// One view per mip level of a mipmapped 3D image (storage writes take a single level).
    pub level_views: Vec<vk::ImageView>,
    /// Views of every level and layer in other formats (an image made MUTABLE_FORMAT).
    pub format_views: Vec<(vk::Format, vk::ImageView)>,
    allocation: Option<Allocation>,
    pub name: String,
}

impl Image {
    pub fn new(ctx: &Arc<Context>, name: &str, desc: ImageDesc) -> VkResult<Image> {
        let info = vk::ImageCreateInfo::default()
            .image_type(desc.image_type)
            .format(desc.format)
            .extent(desc.extent)
            .mip_levels(desc.mip_levels)
            .array_layers(desc.array_layers)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage)
            .flags(desc.flags)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let raw = unsafe { ctx.device.create_image(&info, None) }.check("vkCreateImage")?;
        let requirements = unsafe { ctx.device.get_image_memory_requirements(raw) };
        let allocation = match ctx.allocate(&AllocationCreateDesc {
            name,
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        }) {
            Ok(a) => a,
            Err(e) => {
                unsafe { ctx.device.destroy_image(raw, None) };
                return Err(e);
            }
        };
        let mut image = Image {
            ctx: ctx.clone(),
            raw,
            desc: desc.clone(),
            view: vk::ImageView::null(),
            layer_views: Vec::new(),
            level_views: Vec::new(),
            format_views: Vec::new(),
            allocation: None,
            name: name.into(),
        };
        let bound = unsafe {
            ctx.device
                .bind_image_memory(raw, allocation.memory(), allocation.offset())
        };
        image.allocation = Some(allocation);
        bound.check("vkBindImageMemory")?;
        ctx.set_name(raw, name);

        let view_type = match (desc.image_type, desc.array_view) {
            (vk::ImageType::TYPE_3D, _) => vk::ImageViewType::TYPE_3D,
            (_, false) => vk::ImageViewType::TYPE_2D,
            (_, true) => vk::ImageViewType::TYPE_2D_ARRAY,
        };
        image.view = image.make_view(
            view_type,
            desc.format,
            0,
            desc.array_layers,
            0,
            desc.mip_levels,
        )?;
        if desc.image_type == vk::ImageType::TYPE_3D && desc.mip_levels > 1 {
            for level in 0..desc.mip_levels {
                let v = image.make_view(view_type, desc.format, 0, 1, level, 1)?;
                image.level_views.push(v);
            }
        }
        if desc.array_layers > 1 {
            for layer in 0..desc.array_layers {
                let v = image.make_view(vk::ImageViewType::TYPE_2D, desc.format, layer, 1, 0, 1)?;
                image.layer_views.push(v);
            }
        }
        Ok(image)
    }

    /// A view of the whole image in another format of its class (the image made with
    /// MUTABLE_FORMAT), kept with the image; a second call for one format returns the first
    /// view.
    pub fn view_as(&mut self, format: vk::Format) -> VkResult<vk::ImageView> {
        if let Some(&(_, v)) = self.format_views.iter().find(|(f, _)| *f == format) {
            return Ok(v);
        }
        let view_type = match (self.desc.image_type, self.desc.array_view) {
            (vk::ImageType::TYPE_3D, _) => vk::ImageViewType::TYPE_3D,
            (_, false) => vk::ImageViewType::TYPE_2D,
            (_, true) => vk::ImageViewType::TYPE_2D_ARRAY,
        };
        let (layers, levels) = (self.desc.array_layers, self.desc.mip_levels);
        let v = self.make_view(view_type, format, 0, layers, 0, levels)?;
        self.format_views.push((format, v));
        Ok(v)
    }

    /// The view of another format made by `view_as`.
    pub fn format_view(&self, format: vk::Format) -> Option<vk::ImageView> {
        self.format_views
            .iter()
            .find(|(f, _)| *f == format)
            .map(|&(_, v)| v)
    }

    #[allow(clippy::too_many_arguments)]
    fn make_view(
        &self,
        view_type: vk::ImageViewType,
        format: vk::Format,
        base_layer: u32,
        layers: u32,
        base_level: u32,
        levels: u32,
    ) -> VkResult<vk::ImageView> {
        let info = vk::ImageViewCreateInfo::default()
            .image(self.raw)
            .view_type(view_type)
            .format(format)
            .subresource_range(vk::ImageSubresourceRange {
                aspect_mask: aspect_of(self.desc.format),
                base_mip_level: base_level,
                level_count: levels,
                base_array_layer: base_layer,
                layer_count: layers,
            });
        let view =
            unsafe { self.ctx.device.create_image_view(&info, None) }.check("vkCreateImageView")?;
        // Validation messages name the view a shader accessed.
        let mut part = match (layers, levels) {
            (1, 1) if self.desc.array_layers > 1 => format!(" layer {base_layer}"),
            (_, 1) if self.desc.mip_levels > 1 => format!(" level {base_level}"),
            _ => String::new(),
        };
        if format != self.desc.format {
            part += &format!(" as {format:?}");
        }
        self.ctx.set_name(view, &format!("{}{part}", self.name));
        Ok(view)
    }

    /// A view of one mip level (the whole view for images without level views).
    pub fn level_view(&self, level: u32) -> vk::ImageView {
        self.level_views
            .get(level as usize)
            .copied()
            .unwrap_or(self.view)
    }

    /// A 2D view of one array layer (the whole view for single-layer images).
    pub fn layer_view(&self, layer: u32) -> vk::ImageView {
        self.layer_views
            .get(layer as usize)
            .copied()
            .unwrap_or(self.view)
    }

    pub fn aspect(&self) -> vk::ImageAspectFlags {
        aspect_of(self.desc.format)
    }

    pub fn full_range(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange {
            aspect_mask: self.aspect(),
            base_mip_level: 0,
            level_count: self.desc.mip_levels,
            base_array_layer: 0,
            layer_count: self.desc.array_layers,
        }
    }

    pub fn width(&self) -> u32 {
        self.desc.extent.width
    }
    pub fn height(&self) -> u32 {
        self.desc.extent.height
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        unsafe {
            for (_, v) in self.format_views.drain(..).rev() {
                self.ctx.device.destroy_image_view(v, None);
            }
            for v in self.level_views.drain(..).rev() {
                self.ctx.device.destroy_image_view(v, None);
            }
            for v in self.layer_views.drain(..).rev() {
                self.ctx.device.destroy_image_view(v, None);
            }
            if self.view != vk::ImageView::null() {
                self.ctx.device.destroy_image_view(self.view, None);
            }
            self.ctx.device.destroy_image(self.raw, None);
        }
        if let Some(a) = self.allocation.take() {
            let _ = self.ctx.allocator().free(a);
        }
    }
}

pub struct Sampler {
    ctx: Arc<Context>,
    pub raw: vk::Sampler,
}

impl Sampler {
    pub fn new(ctx: &Arc<Context>, info: &vk::SamplerCreateInfo) -> VkResult<Sampler> {
        let raw = unsafe { ctx.device.create_sampler(info, None) }.check("vkCreateSampler")?;
        Ok(Sampler {
            ctx: ctx.clone(),
            raw,
        })
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        unsafe { self.ctx.device.destroy_sampler(self.raw, None) };
    }
}

/// The copy between a buffer at `offset` and one mip level of a colour image's first layer,
/// `extent` texels of it (depth 1 for 2D images).
pub fn level_copy(offset: u64, level: u32, extent: vk::Extent3D) -> vk::BufferImageCopy {
    vk::BufferImageCopy::default()
        .buffer_offset(offset)
        .image_subresource(vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: level,
            base_array_layer: 0,
            layer_count: 1,
        })
        .image_extent(extent)
}
