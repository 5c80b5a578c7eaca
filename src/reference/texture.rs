//! Texture lookups on the CPU: bilinear filtering of the full-resolution image with the
//! texture's wrap modes. No mipmaps: the reference averages many samples per pixel, which
//! integrates the texture over the pixel footprint exactly where a mip chain approximates it.

use crate::scene::{Texture, Wrap};
use glam::{Vec2, Vec4};
use std::sync::OnceLock;

/// sRGB-encoded 8-bit value to linear, for all 256 values.
fn srgb_table() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| {
        let mut t = [0.0; 256];
        for (i, v) in t.iter_mut().enumerate() {
            let c = i as f32 / 255.0;
            *v = if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            };
        }
        t
    })
}

fn wrap(i: i64, n: u32, mode: Wrap) -> usize {
    let n = n as i64;
    (match mode {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::ClampToEdge => i.clamp(0, n - 1),
        Wrap::MirroredRepeat => {
            let m = i.rem_euclid(2 * n);
            if m >= n {
                2 * n - 1 - m
            } else {
                m
            }
        }
    }) as usize
}

/// One texel as linear RGBA (sRGB textures decode colour; alpha is always linear).
fn texel(t: &Texture, x: usize, y: usize) -> Vec4 {
    let i = (y * t.width as usize + x) * 4;
    let p = &t.rgba8[i..i + 4];
    let a = p[3] as f32 / 255.0;
    if t.srgb {
        let lut = srgb_table();
        Vec4::new(
            lut[p[0] as usize],
            lut[p[1] as usize],
            lut[p[2] as usize],
            a,
        )
    } else {
        Vec4::new(p[0] as f32, p[1] as f32, p[2] as f32, p[3] as f32) / 255.0
    }
}

/// Samples at glTF texture coordinates (0, 0 is the first texel of the first row). Decoding
/// to linear happens before filtering, as sRGB formats do on the GPU.
pub fn sample(t: &Texture, uv: Vec2) -> Vec4 {
    if t.width == 0 || t.height == 0 || t.rgba8.len() < (t.width * t.height * 4) as usize {
        return Vec4::ONE;
    }
    let uv = if uv.is_finite() { uv } else { Vec2::ZERO };
    // Keep coordinates in a range where f32 -> i64 stays exact (repeat is periodic anyway).
    let x = (uv.x as f64 * t.width as f64 - 0.5).clamp(-1e15, 1e15);
    let y = (uv.y as f64 * t.height as f64 - 0.5).clamp(-1e15, 1e15);
    if t.mag_nearest {
        let (xi, yi) = ((x + 0.5).floor() as i64, (y + 0.5).floor() as i64);
        return texel(t, wrap(xi, t.width, t.wrap_s), wrap(yi, t.height, t.wrap_t));
    }
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
    let (x0, y0) = (x0 as i64, y0 as i64);
    let xs = [wrap(x0, t.width, t.wrap_s), wrap(x0 + 1, t.width, t.wrap_s)];
    let ys = [
        wrap(y0, t.height, t.wrap_t),
        wrap(y0 + 1, t.height, t.wrap_t),
    ];
    let top = texel(t, xs[0], ys[0]).lerp(texel(t, xs[1], ys[0]), fx);
    let bottom = texel(t, xs[0], ys[1]).lerp(texel(t, xs[1], ys[1]), fx);
    top.lerp(bottom, fy)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tex(w: u32, h: u32, texels: &[[u8; 4]], srgb: bool, wrap_mode: Wrap) -> Texture {
        Texture {
            name: "t".into(),
            width: w,
            height: h,
            rgba8: texels.iter().flatten().copied().collect(),
            srgb,
            wrap_s: wrap_mode,
            wrap_t: wrap_mode,
            mag_nearest: false,
            min_nearest: false,
        }
    }

    #[test]
    fn bilinear_with_wraps() {
        let t = tex(
            2,
            1,
            &[[0, 0, 0, 255], [255, 255, 255, 255]],
            false,
            Wrap::Repeat,
        );
        // Texel centres give the texels; halfway between them the mean.
        assert_eq!(sample(&t, Vec2::new(0.25, 0.5)).x, 0.0);
        assert_eq!(sample(&t, Vec2::new(0.75, 0.5)).x, 1.0);
        assert!((sample(&t, Vec2::new(0.5, 0.5)).x - 0.5).abs() < 1e-6);
        // Repeat: u = 0 is halfway between the last and the first texel.
        assert!((sample(&t, Vec2::new(0.0, 0.5)).x - 0.5).abs() < 1e-6);
        assert_eq!(sample(&t, Vec2::new(1.25, 7.0)).x, 0.0);
        let c = tex(
            2,
            1,
            &[[0, 0, 0, 255], [255, 255, 255, 255]],
            false,
            Wrap::ClampToEdge,
        );
        assert_eq!(sample(&c, Vec2::new(0.0, 0.5)).x, 0.0);
        assert_eq!(sample(&c, Vec2::new(5.0, 0.5)).x, 1.0);
        let m = tex(
            2,
            1,
            &[[0, 0, 0, 255], [255, 255, 255, 255]],
            false,
            Wrap::MirroredRepeat,
        );
        // Mirrored: texels 2 and 3 are texels 1 and 0.
        assert_eq!(sample(&m, Vec2::new(1.25, 0.5)).x, 1.0);
        assert_eq!(sample(&m, Vec2::new(1.75, 0.5)).x, 0.0);
    }

    #[test]
    fn srgb_decodes_colour_not_alpha() {
        let t = tex(1, 1, &[[188, 188, 188, 128]], true, Wrap::Repeat);
        let v = sample(&t, Vec2::splat(0.5));
        assert!((v.x - 0.5029).abs() < 1e-3, "{v}");
        assert!((v.w - 128.0 / 255.0).abs() < 1e-6);
    }
}
