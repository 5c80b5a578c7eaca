//! The environment on the GPU (glsl/environment.glsl): its equirectangular image with a mip
//! chain (a 1x1 image for a uniform radiance, a black one without an environment), sampled
//! by cones at the level of their aperture, and the frame uniform that turns and scales it.

use crate::output::luminance;
use crate::scene::environment::{equirect_direction, EnvImage};
use crate::scene::{EnvSource, Environment, Light, LightKind};
use crate::vk::{vk, Context, Image, ImageDesc, Sampler, VkResult};
use glam::{Vec3, Vec4};
use half::f16;
use std::f32::consts::PI;
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
/// there is an environment (2 when no cone traces it and the lighting pass lights by it:
/// [`LIGHTS_DIRECTLY`]).
/// The uniform's w when the lighting pass lights by the environment (glsl/environment.glsl:
/// environment_lights_directly).
pub const LIGHTS_DIRECTLY: f32 = 2.0;

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

/// An environment image's sun taken out as a directional light: the real-time renderer lights
/// it with a shadow map and injects it into the voxels, where through the cones alone a sun a
/// degree wide gave no shadows and, averaged over a 36-degree cone, reached rooms only as a
/// glow. What is left keeps the rest of the sky (the sun's texels filled with their
/// surroundings). The reference path tracer keeps the image whole.
pub struct SunSplit {
    /// Directional, W/m^2 at strength 1, shining along the sun's direction reversed.
    pub sun: Light,
    pub rest: Environment,
}

/// The brightest texel's region counts as a sun when it is at least this many times the
/// image's mean radiance ...
const SUN_CONTRAST: f32 = 50.0;
/// ... and spans at most this solid angle (sr; a disk of about 3 degrees' radius).
const SUN_MAX_SOLID_ANGLE: f32 = 0.01;

/// Splits the sun off an environment image (None for a uniform one, or an image without a
/// small region much brighter than the rest).
pub fn split_sun(env: &Environment) -> Option<SunSplit> {
    let EnvSource::Image(img) = &env.source else {
        return None;
    };
    let (w, h) = (img.width as usize, img.height as usize);
    let solid = |y: usize| {
        let v = (y as f32 + 0.5) / h as f32;
        (2.0 * PI / w as f32) * (PI / h as f32) * (v * PI).sin()
    };
    let (mut total, mut area) = (0.0f64, 0.0f64);
    let mut brightest = (0usize, 0.0f32);
    for y in 0..h {
        for x in 0..w {
            let l = luminance(img.texels[y * w + x]);
            total += (l * solid(y)) as f64;
            area += solid(y) as f64;
            if l > brightest.1 {
                brightest = (y * w + x, l);
            }
        }
    }
    let mean = (total / area) as f32;
    // (Texels are finite: the loader refuses others.)
    if brightest.1 <= SUN_CONTRAST * mean {
        return None;
    }
    // The region around the brightest texel above a hundredth of it (and well above the sky).
    let threshold = (brightest.1 * 0.01).max(SUN_CONTRAST * mean * 0.5);
    let mut inside = vec![false; w * h];
    let mut stack = vec![brightest.0];
    let mut region = Vec::new();
    inside[brightest.0] = true;
    let mut region_area = 0.0;
    while let Some(i) = stack.pop() {
        region.push(i);
        region_area += solid(i / w);
        if region_area > SUN_MAX_SOLID_ANGLE {
            return None;
        }
        for (x, y) in neighbours(i % w, i / w, w, h) {
            let j = y * w + x;
            if !inside[j] && luminance(img.texels[j]) > threshold {
                inside[j] = true;
                stack.push(j);
            }
        }
    }
    // The sky behind the sun: the mean of the texels around the region.
    let (mut ring, mut ring_n) = (Vec3::ZERO, 0.0);
    for &i in &region {
        for (x, y) in neighbours(i % w, i / w, w, h) {
            if !inside[y * w + x] {
                ring += img.texels[y * w + x];
                ring_n += 1.0;
            }
        }
    }
    let fill = if ring_n > 0.0 {
        ring / ring_n
    } else {
        Vec3::ZERO
    };
    let mut texels = img.texels.clone();
    let (mut irradiance, mut towards) = (Vec3::ZERO, Vec3::ZERO);
    for &i in &region {
        let (x, y) = (i % w, i / w);
        let excess = (img.texels[i] - fill).max(Vec3::ZERO);
        let d = equirect_direction((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
        irradiance += excess * solid(y);
        towards += d * luminance(excess) * solid(y);
        texels[i] = img.texels[i].min(fill);
    }
    let towards = env.to_world(towards.normalize_or_zero());
    if towards == Vec3::ZERO {
        return None;
    }
    let sun = Light {
        name: Some("the environment's sun".into()),
        kind: LightKind::Directional,
        radiance: irradiance,
        range: None,
        position: Vec3::ZERO,
        direction: -towards,
    };
    let rest = Environment {
        strength: env.strength,
        rotation: env.rotation,
        ..Environment::image(EnvImage {
            texels,
            ..(**img).clone()
        })
    };
    Some(SunSplit { sun, rest })
}

/// The 8 neighbours of texel (x, y): around the horizon the image wraps, at the poles it
/// stops.
fn neighbours(x: usize, y: usize, w: usize, h: usize) -> impl Iterator<Item = (usize, usize)> {
    (-1i64..=1)
        .flat_map(|dy| (-1i64..=1).map(move |dx| (dx, dy)))
        .filter(|&d| d != (0, 0))
        .filter_map(move |(dx, dy)| {
            let ny = y as i64 + dy;
            (0..h as i64)
                .contains(&ny)
                .then(|| ((x as i64 + dx).rem_euclid(w as i64) as usize, ny as usize))
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::environment::daylight_sky;

    #[test]
    fn the_bundled_skys_sun_becomes_a_directional_light() {
        let mut env = Environment::image(daylight_sky(512, 256, 40.0, 30.0, 20.0));
        let split = split_sun(&env).expect("a sun");
        let (el, az) = (40f32.to_radians(), 30f32.to_radians());
        let towards = Vec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos());
        assert!(
            (-split.sun.direction).dot(towards) > 0.9999,
            "{}",
            split.sun.direction
        );
        // The generator's sun: 20 W/m^2 of colour (1, 0.95, 0.88).
        let e = split.sun.radiance;
        assert!(
            (e - Vec3::new(20.0, 19.0, 17.6)).abs().max_element() < 0.3,
            "{e}"
        );
        // What is left has no texel brighter than the glow around the sun.
        let EnvSource::Image(rest) = &split.rest.source else {
            unreachable!()
        };
        assert!(rest.texels.iter().all(|t| t.max_element() < 10.0));
        // Turned, the light turns with it.
        env.rotation = 90f32.to_radians();
        let turned = split_sun(&env).unwrap();
        assert!((-turned.sun.direction).dot(env.to_world(towards)) > 0.9999);
        // A uniform sky, or one without a small bright spot, keeps everything.
        assert!(split_sun(&Environment::uniform(Vec3::ONE)).is_none());
        let overcast = Environment::image(daylight_sky(64, 32, 40.0, 30.0, 0.0));
        assert!(split_sun(&overcast).is_none());
    }
}
