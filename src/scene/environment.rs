//! Light from beyond the scene (../shared/CONVENTIONS.md, "Environment"): a uniform radiance, or
//! an equirectangular HDR image with a strength and a turn about +Y. Radiance arrives from
//! every direction in which a ray leaves the scene without hitting anything; background pixels
//! show it.

use glam::Vec3;
use std::f32::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The environment of a scene (none unless asked for).
#[derive(Clone, Debug)]
pub struct Environment {
    pub source: EnvSource,
    /// Multiplies the radiance (default 1).
    pub strength: f32,
    /// Turn about +Y in radians, counter-clockwise seen from above.
    pub rotation: f32,
}

#[derive(Clone, Debug)]
pub enum EnvSource {
    /// The same radiance R, G, B (W/sr/m^2) from every direction.
    Uniform(Vec3),
    /// An equirectangular image of linear radiance.
    Image(Arc<EnvImage>),
}

/// An equirectangular image: row 0 looks straight up, the centre along -Z.
#[derive(Clone, Debug)]
pub struct EnvImage {
    pub path: PathBuf,
    pub width: u32,
    pub height: u32,
    /// Row by row from the top, linear radiance.
    pub texels: Vec<Vec3>,
}

impl EnvImage {
    pub fn texel(&self, x: u32, y: u32) -> Vec3 {
        self.texels[(y * self.width + x) as usize]
    }

    /// Bilinear lookup at image coordinates (u, v) in [0, 1]: u wraps, v clamps.
    pub fn bilinear(&self, u: f32, v: f32) -> Vec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = u * w as f32 - 0.5;
        let y = (v * h as f32 - 0.5).clamp(0.0, (h - 1) as f32);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let xi = |i: i64| i.rem_euclid(w) as u32;
        let yi = |j: i64| j.clamp(0, h - 1) as u32;
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = self
            .texel(xi(x0), yi(y0))
            .lerp(self.texel(xi(x0 + 1), yi(y0)), fx);
        let bottom = self
            .texel(xi(x0), yi(y0 + 1))
            .lerp(self.texel(xi(x0 + 1), yi(y0 + 1)), fx);
        top.lerp(bottom, fy)
    }
}

/// Image coordinates of a direction in the image's own frame.
pub fn equirect_uv(d: Vec3) -> (f32, f32) {
    let u = 0.5 + d.x.atan2(-d.z) / (2.0 * PI);
    let v = d.y.clamp(-1.0, 1.0).acos() / PI;
    (u, v)
}

/// The direction (in the image's own frame) that image coordinates (u, v) look along.
pub fn equirect_direction(u: f32, v: f32) -> Vec3 {
    let phi = (u - 0.5) * 2.0 * PI;
    let theta = v * PI;
    let s = theta.sin();
    Vec3::new(s * phi.sin(), theta.cos(), -s * phi.cos())
}

impl Environment {
    pub fn uniform(radiance: Vec3) -> Environment {
        Environment {
            source: EnvSource::Uniform(radiance),
            strength: 1.0,
            rotation: 0.0,
        }
    }

    /// `--env`: "R,G,B" (a uniform radiance) or the path of an .hdr or .exr image; an error
    /// names the file and the problem.
    pub fn from_spec(spec: &str, strength: f32, rotate_deg: f32) -> Result<Environment, String> {
        if !(strength.is_finite() && strength >= 0.0) {
            return Err(format!("--env-strength {strength}: must be 0 or more"));
        }
        if !rotate_deg.is_finite() {
            return Err(format!(
                "--env-rotate {rotate_deg}: not a number of degrees"
            ));
        }
        let source = match parse_rgb(spec) {
            Some(rgb) => {
                if !rgb.is_finite() || rgb.min_element() < 0.0 {
                    return Err(format!(
                        "--env {spec}: a radiance must be finite and not negative"
                    ));
                }
                EnvSource::Uniform(rgb)
            }
            None => EnvSource::Image(Arc::new(load_image(Path::new(spec))?)),
        };
        Ok(Environment {
            source,
            strength,
            rotation: rotate_deg.to_radians(),
        })
    }

    /// From the world into the image's frame: the environment is turned by `rotation`, so a
    /// world direction looks up the image at the direction turned back.
    pub fn to_image_frame(&self, d: Vec3) -> Vec3 {
        let (s, c) = (-self.rotation).sin_cos();
        // Rotation about +Y by -rotation (right-handed: counter-clockwise seen from above).
        Vec3::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z)
    }

    /// From the image's frame into the world.
    pub fn to_world(&self, d: Vec3) -> Vec3 {
        let (s, c) = self.rotation.sin_cos();
        Vec3::new(c * d.x + s * d.z, d.y, -s * d.x + c * d.z)
    }

    /// Radiance arriving from direction `d` (unit, world space; the direction light travels
    /// against: the way a ray leaves the scene).
    pub fn radiance(&self, d: Vec3) -> Vec3 {
        match &self.source {
            EnvSource::Uniform(rgb) => *rgb * self.strength,
            EnvSource::Image(img) => {
                let (u, v) = equirect_uv(self.to_image_frame(d));
                img.bilinear(u, v) * self.strength
            }
        }
    }

    /// A short description for logs and `info`.
    pub fn describe(&self) -> String {
        let turn = if self.rotation != 0.0 {
            format!(", turned {} degrees", self.rotation.to_degrees())
        } else {
            String::new()
        };
        match &self.source {
            EnvSource::Uniform(rgb) => {
                let l = *rgb * self.strength;
                format!("uniform radiance {},{},{}", l.x, l.y, l.z)
            }
            EnvSource::Image(img) => format!(
                "{} ({}x{}), strength {}{turn}",
                img.path.display(),
                img.width,
                img.height,
                self.strength
            ),
        }
    }
}

fn parse_rgb(spec: &str) -> Option<Vec3> {
    let parts: Vec<&str> = spec.split(',').collect();
    if parts.len() != 3 {
        return None;
    }
    let v: Vec<f32> = parts
        .iter()
        .map(|p| p.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .ok()?;
    Some(Vec3::new(v[0], v[1], v[2]))
}

/// Reads an equirectangular .hdr (Radiance RGBE) or .exr image of linear radiance.
pub fn load_image(path: &Path) -> Result<EnvImage, String> {
    let err = |problem: String| format!("{}: {problem}", path.display());
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    if !matches!(ext.as_deref(), Some("hdr") | Some("exr")) {
        return Err(err(
            "not an environment (give R,G,B for a uniform radiance, or an .hdr or .exr image)"
                .into(),
        ));
    }
    let reader = image::ImageReader::open(path).map_err(|e| err(e.to_string()))?;
    let img = reader
        .with_guessed_format()
        .map_err(|e| err(e.to_string()))?
        .decode()
        .map_err(|e| err(format!("does not decode: {e}")))?
        .into_rgb32f();
    let (width, height) = (img.width(), img.height());
    if width == 0 || height == 0 {
        return Err(err("the image is empty".into()));
    }
    let texels: Vec<Vec3> = img.pixels().map(|p| Vec3::from_array(p.0)).collect();
    if let Some(bad) = texels
        .iter()
        .position(|t| !t.is_finite() || t.min_element() < 0.0)
    {
        return Err(err(format!(
            "texel ({}, {}) is {} (radiance must be finite and not negative)",
            bad as u32 % width,
            bad as u32 / width,
            texels[bad]
        )));
    }
    Ok(EnvImage {
        path: path.to_path_buf(),
        width,
        height,
        texels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mapping_follows_the_conventions() {
        // Row 0 looks straight up; the image's centre looks along -Z; u grows towards +X.
        assert!((equirect_uv(Vec3::Y).1).abs() < 1e-6);
        let (u, v) = equirect_uv(Vec3::NEG_Z);
        assert!((u - 0.5).abs() < 1e-6 && (v - 0.5).abs() < 1e-6);
        assert!((equirect_uv(Vec3::X).0 - 0.75).abs() < 1e-6);
        for d in [Vec3::X, Vec3::new(0.3, -0.5, 0.8).normalize(), Vec3::NEG_Z] {
            let (u, v) = equirect_uv(d);
            assert!((equirect_direction(u, v) - d).length() < 1e-5, "{d}");
        }
    }

    #[test]
    fn a_turn_is_counter_clockwise_seen_from_above() {
        let mut env = Environment::uniform(Vec3::ONE);
        env.rotation = 90f32.to_radians();
        // Seen from above (+Y), counter-clockwise takes +X to -Z: what the image shows along
        // +X now lies along -Z.
        let d = env.to_world(Vec3::X);
        assert!((d - Vec3::NEG_Z).length() < 1e-6, "{d}");
        assert!((env.to_image_frame(d) - Vec3::X).length() < 1e-6);
    }

    #[test]
    fn a_spec_is_a_radiance_or_a_file() {
        let env = Environment::from_spec("0.5, 1,2", 2.0, 0.0).unwrap();
        assert_eq!(env.radiance(Vec3::Y), Vec3::new(1.0, 2.0, 4.0));
        let e = Environment::from_spec("sky.png", 1.0, 0.0).unwrap_err();
        assert!(e.contains("sky.png") && e.contains(".hdr"), "{e}");
        let e = Environment::from_spec("missing.hdr", 1.0, 0.0).unwrap_err();
        assert!(e.starts_with("missing.hdr:"), "{e}");
        assert!(Environment::from_spec("1,-1,1", 1.0, 0.0).is_err());
        assert!(Environment::from_spec("1,1,1", -1.0, 0.0).is_err());
    }
}
