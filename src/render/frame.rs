//! The images whose size is the frame's: the G-buffer and its depth, the radiance the passes
//! write, and its host copy. A resize makes them again; nothing else changes size.

use crate::vk::{vk, Access, Buffer, Context, Graph, Image, ImageDesc, ResourceStates, VkResult};
use std::sync::Arc;

pub const GBUFFER_FORMATS: [vk::Format; 5] = [
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
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

pub struct FrameTargets {
    pub width: u32,
    pub height: u32,
    /// Position, normals, albedo, emission, specular (GBUFFER_FORMATS).
    pub gbuffer: Vec<Image>,
    pub depth: Image,
    /// Linear radiance (RGBA32F), which lighting writes and the trace adds to.
    pub hdr: Image,
    /// The mean of the frames' radiance (accumulate.rs), when frames are accumulated.
    pub history: Option<Image>,
    /// Its host copy, after a frame rendered with readback.
    pub readback: Buffer,
}

impl FrameTargets {
    /// The frame's images; with `accumulate`, the mean of the frames' radiance too.
    pub fn new(
        ctx: &Arc<Context>,
        width: u32,
        height: u32,
        accumulate: bool,
    ) -> VkResult<FrameTargets> {
        let (w, h) = (width, height);
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
        let history = if accumulate {
            Some(Image::new(
                ctx,
                "radiance mean",
                ImageDesc::d2(
                    vk::Format::R32G32B32A32_SFLOAT,
                    w,
                    h,
                    vk::ImageUsageFlags::STORAGE,
                ),
            )?)
        } else {
            None
        };
        let readback = Buffer::readback(ctx, "radiance readback", (w * h * 16) as u64)?;
        Ok(FrameTargets {
            width,
            height,
            gbuffer,
            depth,
            hdr,
            history,
            readback,
        })
    }

    /// Forgets the targets' tracked states (they are about to be freed).
    pub fn forget(&self, states: &mut ResourceStates) {
        let images = [&self.depth, &self.hdr].into_iter().chain(&self.history);
        for img in self.gbuffer.iter().chain(images) {
            states.forget(img.raw);
        }
        states.forget(self.readback.raw);
    }

    /// Copies the radiance image into the host buffer, then hands it to the host.
    pub fn record_readback(&self, ctx: &Context, g: &mut Graph, name: &str) {
        let (w, h) = (self.width, self.height);
        g.pass(name)
            .image(&self.hdr, Access::TransferRead)
            .buffer(&self.readback, Access::TransferWrite)
            .record(|cmd| unsafe {
                let extent = vk::Extent3D {
                    width: w,
                    height: h,
                    depth: 1,
                };
                let region = crate::vk::level_copy(0, 0, extent);
                ctx.device.cmd_copy_image_to_buffer(
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

    /// Linear radiance, RGB per pixel, row 0 at the top (after a frame with readback).
    pub fn radiance(&self) -> Vec<[f32; 3]> {
        let bytes = self
            .readback
            .mapped()
            .expect("readback buffer is host-visible");
        let (w, h) = (self.width as usize, self.height as usize);
        bytes[..w * h * 16]
            .chunks_exact(16)
            .map(|c| {
                let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
                [f(0), f(4), f(8)]
            })
            .collect()
    }
}
