//! The environment on the GPU (glsl/environment.glsl): its equirectangular image with a mip
//! chain (a 1x1 image for a uniform radiance, a black one without an environment), sampled
//! by cones at the level of their aperture, and the frame uniform that turns and scales it.

use crate::scene::{EnvSource, Environment};
use crate::vk::{vk, Context, Image, ImageDesc, Sampler, VkResult};
use glam::{Vec3, Vec4};
use half::f16;
use std::sync::Arc;

/// RGBA16F texels (filterable on every device), stored divided by `texel_scale`.
pub const FORMAT: vk::Format = vk::Format::R16G16B16A16_SFLOAT;

/// What the stored texels are multiplied by: a sun of 1e6 in an HDR image would overflow half
/// floats (65504), so the brightest texel is stored at 32768 at most.
pub fn texel_scale(env: Option<&Environment>) -> f32 {
    let max = match env.map(|e| &e.source) {
        None => 0.0,
        Some(EnvSource::Uniform(rgb)) => rgb.max_element(),
        Some(EnvSource::Image(img)) => img
            .texels
            .iter()
            .map(|t| t.max_element())
            .fold(0.0, f32::max),
    };
    (max / 32768.0).max(1.0)
}

/// The frame uniform: strength (times the texel scale), the turn's cosine and sine, 1 when
/// there is an environment.
pub fn uniform(env: Option<&Environment>) -> Vec4 {
    match env {
        Some(e) => Vec4::new(
            e.strength * texel_scale(env),
            e.rotation.cos(),
            e.rotation.sin(),
            1.0,
        ),
        None => Vec4::new(0.0, 1.0, 0.0, 0.0),
    }
}

/// The image's levels, finest first, as RGBA16F bytes, by 2x2 box filtering in (u, v).
pub fn levels(env: Option<&Environment>) -> Vec<(u32, u32, Vec<u8>)> {
    let scale = texel_scale(env);
    let (w, h, texels): (u32, u32, Vec<Vec3>) = match env.map(|e| &e.source) {
        None => (1, 1, vec![Vec3::ZERO]),
        Some(EnvSource::Uniform(rgb)) => (1, 1, vec![*rgb / scale]),
        Some(EnvSource::Image(img)) => (
            img.width,
            img.height,
            img.texels.iter().map(|t| *t / scale).collect(),
        ),
    };
    let bytes = |t: &[Vec3]| -> Vec<u8> {
        t.iter()
            .flat_map(|v| [v.x, v.y, v.z, 1.0])
            .flat_map(|x| f16::from_f32(x).to_le_bytes())
            .collect()
    };
    let mut out = vec![(w, h, bytes(&texels))];
    let (mut w, mut h, mut level) = (w, h, texels);
    while w > 1 || h > 1 {
        let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
        let mut next = vec![Vec3::ZERO; (nw * nh) as usize];
        for y in 0..nh {
            for x in 0..nw {
                let xs = [(2 * x).min(w - 1), (2 * x + 1).min(w - 1)];
                let ys = [(2 * y).min(h - 1), (2 * y + 1).min(h - 1)];
                let mut sum = Vec3::ZERO;
                for &sy in &ys {
                    for &sx in &xs {
                        sum += level[(sy * w + sx) as usize];
                    }
                }
                next[(y * nw + x) as usize] = sum * 0.25;
            }
        }
        out.push((nw, nh, bytes(&next)));
        (w, h, level) = (nw, nh, next);
    }
    out
}

/// The image for `levels` (filled by the scene's upload).
pub fn image(ctx: &Arc<Context>, levels: &[(u32, u32, Vec<u8>)]) -> VkResult<Image> {
    let (w, h, _) = levels[0];
    let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
    let desc = ImageDesc::d2(FORMAT, w, h, usage).mips(levels.len() as u32);
    Image::new(ctx, "environment", desc)
}

/// Trilinear; around the horizon it repeats, at the poles it clamps.
pub fn sampler(ctx: &Arc<Context>) -> VkResult<Sampler> {
    let info = vk::SamplerCreateInfo::default()
        .mag_filter(vk::Filter::LINEAR)
        .min_filter(vk::Filter::LINEAR)
        .mipmap_mode(vk::SamplerMipmapMode::LINEAR)
        .address_mode_u(vk::SamplerAddressMode::REPEAT)
        .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
        .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
        .max_lod(vk::LOD_CLAMP_NONE);
    Sampler::new(ctx, &info)
}
