//! The window's surface and swapchain (ash-window), freed in reverse order of creation.

use crate::vk::{vk, Context, VkError, VkResult};
use ash::khr;
use std::sync::Arc;
use winit::raw_window_handle::{RawDisplayHandle, RawWindowHandle};

fn call(call: &'static str) -> impl Fn(vk::Result) -> VkError {
    move |result| VkError::Call { call, result }
}

pub struct Surface {
    /// The instance must outlive the surface.
    _ctx: Arc<Context>,
    pub loader: khr::surface::Instance,
    pub raw: vk::SurfaceKHR,
}

impl Surface {
    /// A surface for the window; the window must outlive it.
    pub fn new(
        ctx: &Arc<Context>,
        display: RawDisplayHandle,
        window: RawWindowHandle,
    ) -> VkResult<Surface> {
        let raw =
            unsafe { ash_window::create_surface(&ctx.entry, &ctx.instance, display, window, None) }
                .map_err(call("vkCreate*SurfaceKHR"))?;
        let loader = khr::surface::Instance::new(&ctx.entry, &ctx.instance);
        let surface = Surface {
            _ctx: ctx.clone(),
            loader,
            raw,
        };
        let supported = unsafe {
            surface.loader.get_physical_device_surface_support(
                ctx.physical_device,
                ctx.queue_family,
                raw,
            )
        }
        .map_err(call("vkGetPhysicalDeviceSurfaceSupportKHR"))?;
        if !supported {
            return Err(VkError::Missing {
                device: ctx.device_info.name.clone(),
                missing: "presentation to this window from its queue".into(),
            });
        }
        Ok(surface)
    }
}

impl Drop for Surface {
    fn drop(&mut self) {
        unsafe { self.loader.destroy_surface(self.raw, None) };
    }
}

/// What the swapchain is asked for.
#[derive(Clone, Copy, Debug)]
pub struct SwapchainDesc {
    pub width: u32,
    pub height: u32,
    /// FIFO (wait for vertical blank); else mailbox or immediate where offered.
    pub vsync: bool,
}

pub struct Swapchain {
    ctx: Arc<Context>,
    loader: khr::swapchain::Device,
    pub raw: vk::SwapchainKHR,
    pub images: Vec<vk::Image>,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    pub present_mode: vk::PresentModeKHR,
    /// The images can be copied from (screenshots of the window itself).
    pub readable: bool,
    /// Signalled by acquires, in turn (one more than images: the one in use is never reused
    /// before its frame's fence).
    acquired: Vec<vk::Semaphore>,
    next_acquire: usize,
    /// Signalled by the frame that draws image i, waited for by its present.
    rendered: Vec<vk::Semaphore>,
}

/// An acquired image and the semaphore its frame waits for.
pub struct Acquired {
    pub index: u32,
    pub ready: vk::Semaphore,
    pub rendered: vk::Semaphore,
    /// The swapchain still works but no longer matches the surface: recreate after presenting.
    pub suboptimal: bool,
}

impl Swapchain {
    /// A swapchain for `surface`, or None while the window has no area (minimized).
    pub fn new(
        ctx: &Arc<Context>,
        surface: &Surface,
        desc: SwapchainDesc,
    ) -> VkResult<Option<Swapchain>> {
        let pd = ctx.physical_device;
        let (caps, formats, modes) = unsafe {
            (
                surface
                    .loader
                    .get_physical_device_surface_capabilities(pd, surface.raw)
                    .map_err(call("vkGetPhysicalDeviceSurfaceCapabilitiesKHR"))?,
                surface
                    .loader
                    .get_physical_device_surface_formats(pd, surface.raw)
                    .map_err(call("vkGetPhysicalDeviceSurfaceFormatsKHR"))?,
                surface
                    .loader
                    .get_physical_device_surface_present_modes(pd, surface.raw)
                    .map_err(call("vkGetPhysicalDeviceSurfacePresentModesKHR"))?,
            )
        };
        let extent = if caps.current_extent.width != u32::MAX {
            caps.current_extent
        } else {
            vk::Extent2D {
                width: desc
                    .width
                    .clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: desc
                    .height
                    .clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        };
        if extent.width == 0 || extent.height == 0 {
            return Ok(None);
        }
        // The display pass encodes sRGB itself; an sRGB format would encode twice, so it is
        // taken only when nothing else is offered (the pass then leaves the encoding to it).
        let preference = [
            vk::Format::B8G8R8A8_UNORM,
            vk::Format::R8G8B8A8_UNORM,
            vk::Format::A8B8G8R8_UNORM_PACK32,
            vk::Format::B8G8R8A8_SRGB,
            vk::Format::R8G8B8A8_SRGB,
        ];
        let blit_dst = |f: vk::Format| unsafe {
            ctx.instance
                .get_physical_device_format_properties(pd, f)
                .optimal_tiling_features
                .contains(vk::FormatFeatureFlags::BLIT_DST)
        };
        let Some(format) = preference
            .iter()
            .filter_map(|&want| formats.iter().find(|f| f.format == want))
            .find(|f| blit_dst(f.format))
            .copied()
        else {
            return Err(VkError::Missing {
                device: ctx.device_info.name.clone(),
                missing: format!(
                    "an 8-bit RGBA/BGRA swapchain format that can be blitted to (the surface \
                     offers {:?})",
                    formats.iter().map(|f| f.format).collect::<Vec<_>>()
                ),
            });
        };
        if !caps
            .supported_usage_flags
            .contains(vk::ImageUsageFlags::TRANSFER_DST)
        {
            return Err(VkError::Missing {
                device: ctx.device_info.name.clone(),
                missing: "swapchain images that can be copied to (TRANSFER_DST)".into(),
            });
        }
        let readable = caps
            .supported_usage_flags
            .contains(vk::ImageUsageFlags::TRANSFER_SRC);
        let mut usage = vk::ImageUsageFlags::TRANSFER_DST;
        if readable {
            usage |= vk::ImageUsageFlags::TRANSFER_SRC;
        }
        let present_mode = if desc.vsync {
            vk::PresentModeKHR::FIFO
        } else {
            [vk::PresentModeKHR::MAILBOX, vk::PresentModeKHR::IMMEDIATE]
                .into_iter()
                .find(|m| modes.contains(m))
                .unwrap_or(vk::PresentModeKHR::FIFO)
        };
        let mut count = caps.min_image_count + 1;
        if caps.max_image_count > 0 {
            count = count.min(caps.max_image_count);
        }
        let alpha = [
            vk::CompositeAlphaFlagsKHR::OPAQUE,
            vk::CompositeAlphaFlagsKHR::INHERIT,
            vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
            vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED,
        ]
        .into_iter()
        .find(|a| caps.supported_composite_alpha.contains(*a))
        .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE);
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(surface.raw)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(
                if caps
                    .supported_transforms
                    .contains(vk::SurfaceTransformFlagsKHR::IDENTITY)
                {
                    vk::SurfaceTransformFlagsKHR::IDENTITY
                } else {
                    caps.current_transform
                },
            )
            .composite_alpha(alpha)
            .present_mode(present_mode)
            .clipped(true);
        let loader = khr::swapchain::Device::new(&ctx.instance, &ctx.device);
        let raw = unsafe { loader.create_swapchain(&info, None) }
            .map_err(call("vkCreateSwapchainKHR"))?;
        let mut chain = Swapchain {
            ctx: ctx.clone(),
            loader,
            raw,
            images: Vec::new(),
            format: format.format,
            extent,
            present_mode,
            readable,
            acquired: Vec::new(),
            next_acquire: 0,
            rendered: Vec::new(),
        };
        chain.images = unsafe { chain.loader.get_swapchain_images(raw) }
            .map_err(call("vkGetSwapchainImagesKHR"))?;
        for (i, &img) in chain.images.iter().enumerate() {
            ctx.set_name(img, &format!("swapchain image {i}"));
        }
        let semaphore = || unsafe {
            ctx.device
                .create_semaphore(&vk::SemaphoreCreateInfo::default(), None)
                .map_err(call("vkCreateSemaphore"))
        };
        for _ in 0..chain.images.len() + 1 {
            chain.acquired.push(semaphore()?);
        }
        for _ in 0..chain.images.len() {
            chain.rendered.push(semaphore()?);
        }
        Ok(Some(chain))
    }

    /// Whether the display pass must encode sRGB (the format does not).
    pub fn encodes_srgb(&self) -> bool {
        matches!(
            self.format,
            vk::Format::B8G8R8A8_SRGB | vk::Format::R8G8B8A8_SRGB
        )
    }

    /// The next image, or None when the swapchain no longer fits the surface.
    pub fn acquire(&mut self) -> VkResult<Option<Acquired>> {
        let ready = self.acquired[self.next_acquire];
        let r = unsafe {
            self.loader
                .acquire_next_image(self.raw, u64::MAX, ready, vk::Fence::null())
        };
        match r {
            Ok((index, suboptimal)) => {
                self.next_acquire = (self.next_acquire + 1) % self.acquired.len();
                Ok(Some(Acquired {
                    index,
                    ready,
                    rendered: self.rendered[index as usize],
                    suboptimal,
                }))
            }
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(None),
            Err(e) => Err(VkError::Call {
                call: "vkAcquireNextImageKHR",
                result: e,
            }),
        }
    }

    /// Presents image `index`; false when the swapchain must be recreated.
    pub fn present(&self, image: &Acquired) -> VkResult<bool> {
        let waits = [image.rendered];
        let chains = [self.raw];
        let indices = [image.index];
        let info = vk::PresentInfoKHR::default()
            .wait_semaphores(&waits)
            .swapchains(&chains)
            .image_indices(&indices);
        match unsafe { self.loader.queue_present(self.ctx.queue, &info) } {
            Ok(suboptimal) => Ok(!suboptimal && !image.suboptimal),
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => Ok(false),
            Err(e) => Err(VkError::Call {
                call: "vkQueuePresentKHR",
                result: e,
            }),
        }
    }
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        unsafe {
            // Presents still queued use the images and semaphores.
            let _ = self.ctx.device.queue_wait_idle(self.ctx.queue);
            for &s in self.acquired.iter().chain(&self.rendered) {
                self.ctx.device.destroy_semaphore(s, None);
            }
            self.loader.destroy_swapchain(self.raw, None);
        }
    }
}
