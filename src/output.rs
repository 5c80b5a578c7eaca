//! Image output per CONVENTIONS.md: `.exr` holds linear radiance (RGB 32-bit float, no exposure
//! or tone mapping); `.png` holds the display image (exposure, a tone curve, then sRGB).
//! Files are written to a temporary name and renamed, so no half-written output is left.

use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{path}: unsupported output format (use .exr for radiance or .png for display)")]
    Format { path: PathBuf },
    #[error("{path}: cannot write the image: {reason}")]
    Write { path: PathBuf, reason: String },
    #[error("{path}: cannot read the image: {reason}")]
    Read { path: PathBuf, reason: String },
}

/// Rec. 709 luminance of linear RGB (glsl/common.glsl's `luminance`).
pub fn luminance(c: glam::Vec3) -> f32 {
    c.dot(glam::Vec3::new(0.2126, 0.7152, 0.0722))
}

/// A linear-radiance image, row 0 at the top.
#[derive(Clone, Debug)]
pub struct RadianceImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 3]>,
}

impl RadianceImage {
    pub fn at(&self, x: u32, y: u32) -> [f32; 3] {
        self.pixels[(y * self.width + x) as usize]
    }
    pub fn has_non_finite(&self) -> bool {
        self.pixels.iter().flatten().any(|v| !v.is_finite())
    }
}

/// ACES filmic curve (Narkowicz's fit), applied per channel.
fn tone(x: f32) -> f32 {
    let x = x.max(0.0);
    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

fn srgb_encode(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        v * 12.92
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// The display image: radiance x 2^exposure, tone curve, sRGB, 8 bits.
pub fn display(img: &RadianceImage, exposure: f32) -> image::RgbImage {
    let scale = 2f32.powf(exposure);
    let mut out = image::RgbImage::new(img.width, img.height);
    for (p, px) in out.pixels_mut().zip(&img.pixels) {
        for (out, &v) in p.0.iter_mut().zip(px) {
            let v = if v.is_finite() { v } else { 0.0 };
            *out = (srgb_encode(tone(v * scale)) * 255.0 + 0.5) as u8;
        }
    }
    out
}

fn temp_path(path: &Path) -> PathBuf {
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(format!(".tmp-{}", std::process::id()));
    path.with_file_name(name)
}

fn write_atomic(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), OutputError> {
    let tmp = temp_path(path);
    let result = write(&tmp).and_then(|_| std::fs::rename(&tmp, path).map_err(|e| e.to_string()));
    if let Err(reason) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(OutputError::Write {
            path: path.to_path_buf(),
            reason,
        });
    }
    Ok(())
}

/// Writes `bytes` to `path` through a temporary file, so that no half-written file is left.
pub fn write_bytes_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    write_atomic(path, |tmp| {
        std::fs::write(tmp, bytes).map_err(|e| e.to_string())
    })
}

/// Writes `.exr` (radiance) or `.png` (display image), chosen by the extension.
pub fn save(img: &RadianceImage, path: &Path, exposure: f32) -> Result<(), OutputError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("exr") => write_atomic(path, |tmp| {
            let data: Vec<f32> = img.pixels.iter().flatten().copied().collect();
            let buf = image::Rgb32FImage::from_raw(img.width, img.height, data)
                .ok_or("image size does not match its pixels")?;
            buf.save_with_format(tmp, image::ImageFormat::OpenExr)
                .map_err(|e| e.to_string())
        }),
        Some("png") => write_atomic(path, |tmp| {
            display(img, exposure)
                .save_with_format(tmp, image::ImageFormat::Png)
                .map_err(|e| e.to_string())
        }),
        _ => Err(OutputError::Format {
            path: path.to_path_buf(),
        }),
    }
}

/// Reads an `.exr` written by this program or another renderer.
pub fn load_exr(path: &Path) -> Result<RadianceImage, OutputError> {
    let err = |reason: String| OutputError::Read {
        path: path.to_path_buf(),
        reason,
    };
    let img = image::ImageReader::open(path)
        .map_err(|e| err(e.to_string()))?
        .with_guessed_format()
        .map_err(|e| err(e.to_string()))?
        .decode()
        .map_err(|e| err(e.to_string()))?
        .into_rgb32f();
    Ok(RadianceImage {
        width: img.width(),
        height: img.height(),
        pixels: img.pixels().map(|p| p.0).collect(),
    })
}
