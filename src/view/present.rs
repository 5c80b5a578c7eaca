//! The window's last passes: the display image (exposure, tone curve, sRGB, as `voxgi render`
//! writes a PNG) and its copy into the acquired swapchain image, plus screenshots.

use crate::vk::VkResult;
use crate::vk::{vk, Access, Bindings, Buffer, Context, Graph, Image, ImageDesc, Pass, Usage};
use std::sync::Arc;

#[repr(C)]
#[derive(Clone, Copy)]
struct DisplayPush {
    scale: f32,
    encode_srgb: u32,
}

/// Where a frame goes: an acquired swapchain image.
pub struct Target {
    pub image: vk::Image,
    pub extent: vk::Extent2D,
    pub encode_srgb: bool,
    /// The image can be copied from (else screenshots read the display image).
    pub readable: bool,
    /// Its bytes are B, G, R, A (else R, G, B, A).
    pub bgra: bool,
}

pub struct Display {
    ctx: Arc<Context>,
    pass: Pass,
    image: Image,
    /// Host copy of the last screenshot asked for, and its width, height and byte order
    /// (true: B, G, R, A).
    shot: Option<Buffer>,
    shot_shape: (u32, u32, bool),
    width: u32,
    height: u32,
}

/// A screenshot: 8-bit RGB rows, top first.
pub struct Shot {
    pub width: u32,
    pub height: u32,
    pub rgb: Vec<u8>,
}

impl Display {
    /// For a renderer whose radiance image is `radiance` (width x height).
    pub fn new(ctx: &Arc<Context>, radiance: &Image) -> VkResult<Display> {
        let (width, height) = (radiance.desc.extent.width, radiance.desc.extent.height);
        let image = Image::new(
            ctx,
            "display",
            ImageDesc::d2(
                vk::Format::R8G8B8A8_UNORM,
                width,
                height,
                vk::ImageUsageFlags::STORAGE | vk::ImageUsageFlags::TRANSFER_SRC,
            ),
        )?;
        let table = Bindings::new()
            .image("radiance", radiance, Usage::Read)
            .image("display", &image, Usage::Write);
        let push = std::mem::size_of::<DisplayPush>() as u32;
        let pass = Pass::compute(ctx, "display.comp", &[], table, push)?;
        Ok(Display {
            ctx: ctx.clone(),
            pass,
            image,
            shot: None,
            shot_shape: (0, 0, false),
            width,
            height,
        })
    }

    /// Records the display pass and the copy to `target`; with `screenshot`, also a copy of
    /// the window's image into host memory for [`Display::screenshot`].
    pub fn record(
        &mut self,
        g: &mut Graph,
        target: &Target,
        exposure: f32,
        screenshot: bool,
    ) -> VkResult<()> {
        let d = &self.ctx.device;
        let push = DisplayPush {
            scale: 2f32.powf(exposure),
            encode_srgb: (!target.encode_srgb) as u32,
        };
        let p = &self.pass;
        p.declare(g.pass("display"), 0).record(|cmd| unsafe {
            p.bind(d, cmd, &[], 0);
            p.pipeline
                .push(d, cmd, crate::render::gpu::as_bytes(&[push]));
            d.cmd_dispatch(cmd, self.width.div_ceil(8), self.height.div_ceil(8), 1);
        });

        if screenshot && self.shot.is_none() {
            let bytes = target.extent.width.max(self.width) as u64
                * target.extent.height.max(self.height) as u64
                * 4;
            self.shot = Some(Buffer::readback(&self.ctx, "screenshot", bytes)?);
        }
        let shot_from_display = screenshot && !target.readable;
        if screenshot {
            self.shot_shape = if shot_from_display {
                (self.width, self.height, false)
            } else {
                (target.extent.width, target.extent.height, target.bgra)
            };
        }
        let shot = self.shot.as_ref().filter(|_| screenshot);
        let color = vk::ImageSubresourceRange {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            base_mip_level: 0,
            level_count: 1,
            base_array_layer: 0,
            layer_count: 1,
        };
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        };
        // The frame's submission waits for the acquire at the transfer stage.
        g.acquired(target.image, vk::PipelineStageFlags2::TRANSFER);
        let (w, h) = (self.width, self.height);
        let corner = |x: u32, y: u32| vk::Offset3D {
            x: x as i32,
            y: y as i32,
            z: 1,
        };
        g.pass("present")
            .image(&self.image, Access::TransferRead)
            .external_image(target.image, color, Access::TransferWrite)
            .record(|cmd| {
                let region = vk::ImageBlit::default()
                    .src_subresource(layers)
                    .src_offsets([vk::Offset3D::default(), corner(w, h)])
                    .dst_subresource(layers)
                    .dst_offsets([
                        vk::Offset3D::default(),
                        corner(target.extent.width, target.extent.height),
                    ]);
                unsafe {
                    d.cmd_blit_image(
                        cmd,
                        self.image.raw,
                        vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                        target.image,
                        vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                        &[region],
                        vk::Filter::NEAREST,
                    )
                };
            });
        if let Some(b) = shot {
            let (sw, sh) = (self.shot_shape.0, self.shot_shape.1);
            let copy = vk::BufferImageCopy::default()
                .image_subresource(layers)
                .image_extent(vk::Extent3D {
                    width: sw,
                    height: sh,
                    depth: 1,
                });
            let pass = g.pass("screenshot").buffer(b, Access::TransferWrite);
            let (pass, src) = if shot_from_display {
                (
                    pass.image(&self.image, Access::TransferRead),
                    self.image.raw,
                )
            } else {
                (
                    pass.external_image(target.image, color, Access::TransferRead),
                    target.image,
                )
            };
            pass.record(|cmd| unsafe {
                d.cmd_copy_image_to_buffer(
                    cmd,
                    src,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    b.raw,
                    &[copy],
                )
            });
        }
        g.barrier("to present")
            .external_image(target.image, color, Access::Present)
            .record(|_| {});
        if let Some(b) = shot {
            g.barrier("screenshot to host")
                .buffer(b, Access::HostRead)
                .record(|_| {});
        }
        Ok(())
    }

    /// The screenshot taken by the last frame recorded with `screenshot` (after it finished).
    pub fn screenshot(&self) -> Option<Shot> {
        let bytes = self.shot.as_ref()?.mapped()?;
        let (w, h, bgra) = self.shot_shape;
        let mut rgb = Vec::with_capacity((w * h * 3) as usize);
        for px in bytes[..(w * h * 4) as usize].chunks_exact(4) {
            if bgra {
                rgb.extend([px[2], px[1], px[0]]);
            } else {
                rgb.extend([px[0], px[1], px[2]]);
            }
        }
        Some(Shot {
            width: w,
            height: h,
            rgb,
        })
    }
}
