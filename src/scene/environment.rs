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
    /// An image of `width` x `height` texels of linear radiance, row by row from the top;
    /// `name` stands for its file in messages.
    pub fn new(name: &str, width: u32, height: u32, texels: Vec<Vec3>) -> EnvImage {
        assert_eq!(
            texels.len(),
            (width * height) as usize,
            "{name}: texel count"
        );
        EnvImage {
            path: PathBuf::from(name),
            width,
            height,
            texels,
        }
    }

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

    /// An image environment at strength 1, not turned.
    pub fn image(img: EnvImage) -> Environment {
        Environment {
            source: EnvSource::Image(Arc::new(img)),
            strength: 1.0,
            rotation: 0.0,
        }
    }

    /// The same, turned by `deg` degrees about +Y (counter-clockwise seen from above).
    pub fn turned(mut self, deg: f32) -> Environment {
        self.rotation = deg.to_radians();
        self
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

/// A clear daylight sky (equirectangular, `width` x `height`): blue at the zenith, pale at
/// the horizon, a brown ground below it, and a sun of angular radius 0.75 degrees (wider than
/// the real one, so that a 512-texel image holds it) towards elevation `sun_el_deg` and
/// azimuth `sun_az_deg` (as `--sun`: 0 is +Z, 90 is +X) that gives `sun_irradiance` W/m^2 to
/// a surface facing it. The sky alone gives an open floor about 2.6 W/m^2. Radiance units are
/// W/sr/m^2, as the scenes' lights. The project's `assets/sky.hdr` is
/// `daylight_sky(512, 256, 40, 30, 20)`.
pub fn daylight_sky(
    width: u32,
    height: u32,
    sun_el_deg: f32,
    sun_az_deg: f32,
    sun_irradiance: f32,
) -> EnvImage {
    let (el, az) = (sun_el_deg.to_radians(), sun_az_deg.to_radians());
    let sun = Vec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos());
    let sun_radius = 0.75f32.to_radians();
    let zenith = Vec3::new(0.30, 0.50, 1.00);
    let horizon = Vec3::new(1.00, 0.97, 0.92);
    let ground = Vec3::new(0.30, 0.25, 0.20) * 0.5;
    let direction = |x: u32, y: u32| {
        equirect_direction(
            (x as f32 + 0.5) / width as f32,
            (y as f32 + 0.5) / height as f32,
        )
    };
    let mut texels = Vec::with_capacity((width * height) as usize);
    let mut sun_texels = Vec::new();
    let mut sun_solid_angle = 0.0f32;
    for y in 0..height {
        let v = (y as f32 + 0.5) / height as f32;
        let texel_solid_angle = (2.0 * PI / width as f32) * (PI / height as f32) * (v * PI).sin();
        for x in 0..width {
            let d = direction(x, y);
            let up = d.y.max(0.0).powf(0.4);
            let sky = horizon.lerp(zenith, up);
            // A glow around the sun, and a soft horizon line into the ground.
            let glow = Vec3::new(1.0, 0.85, 0.6)
                * 1.5
                * (-(d.dot(sun).clamp(-1.0, 1.0).acos()) / 0.15).exp();
            let above = ((d.y + 0.02) / 0.04).clamp(0.0, 1.0);
            texels.push(ground.lerp(sky + glow, above));
            if d.dot(sun) >= sun_radius.cos() {
                sun_texels.push(texels.len() - 1);
                sun_solid_angle += texel_solid_angle;
            }
        }
    }
    if sun_texels.is_empty() {
        // Too coarse an image for the disk: the texel the sun lies in.
        let (u, v) = equirect_uv(sun);
        let x = ((u * width as f32) as u32).min(width - 1);
        let y = ((v * height as f32) as u32).min(height - 1);
        sun_texels.push((y * width + x) as usize);
        sun_solid_angle = (2.0 * PI / width as f32) * (PI / height as f32) * (v * PI).sin();
    }
    let sun_radiance = Vec3::new(1.0, 0.95, 0.88) * sun_irradiance / sun_solid_angle;
    for i in sun_texels {
        texels[i] += sun_radiance;
    }
    EnvImage {
        path: PathBuf::from(format!(
            "daylight sky {width}x{height}, sun at {sun_el_deg},{sun_az_deg}"
        )),
        width,
        height,
        texels,
    }
}

/// Writes an environment image as Radiance .hdr (RGBE).
pub fn save_hdr(img: &EnvImage, path: &Path) -> Result<(), String> {
    let err = |e: String| format!("{}: {e}", path.display());
    let file = std::fs::File::create(path).map_err(|e| err(e.to_string()))?;
    let pixels: Vec<image::Rgb<f32>> = img
        .texels
        .iter()
        .map(|t| image::Rgb(t.to_array()))
        .collect();
    image::codecs::hdr::HdrEncoder::new(std::io::BufWriter::new(file))
        .encode(&pixels, img.width as usize, img.height as usize)
        .map_err(|e| err(e.to_string()))
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

#[cfg(test)]
mod sky_tests {
    use super::*;

    fn bundled() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/sky.hdr")
    }

    /// Writes assets/sky.hdr (run once: `cargo test write_the_bundled_sky -- --ignored`).
    #[test]
    #[ignore = "writes assets/sky.hdr, which is committed; run by hand to make it again"]
    fn write_the_bundled_sky() {
        save_hdr(&daylight_sky(512, 256, 40.0, 30.0, 20.0), &bundled()).unwrap();
    }

    /// The bundled sky is the generator's, within what RGBE keeps (1% of a texel's largest
    /// channel), and its sun gives the irradiance asked for.
    #[test]
    fn the_bundled_sky_is_the_generators() {
        let sky = daylight_sky(512, 256, 40.0, 30.0, 20.0);
        let file = load_image(&bundled()).unwrap();
        assert_eq!((file.width, file.height), (512, 256));
        for (a, b) in file.texels.iter().zip(&sky.texels) {
            assert!(
                (*a - *b).abs().max_element() <= 0.01 * b.max_element() + 1e-6,
                "{a} {b}"
            );
        }
        // Irradiance on a surface facing the sun, from the texels brighter than the sky.
        let (el, az) = (40f32.to_radians(), 30f32.to_radians());
        let sun = Vec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos());
        let mut e = 0.0;
        for y in 0..sky.height {
            let v = (y as f32 + 0.5) / sky.height as f32;
            let solid = (2.0 * PI / sky.width as f32) * (PI / sky.height as f32) * (v * PI).sin();
            for x in 0..sky.width {
                let t = sky.texel(x, y);
                if t.y > 100.0 {
                    let d = equirect_direction((x as f32 + 0.5) / sky.width as f32, v);
                    e += t.y * solid * d.dot(sun);
                }
            }
        }
        assert!((e - 20.0 * 0.95).abs() < 0.2, "sun irradiance {e}");
    }
}
