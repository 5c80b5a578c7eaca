//! The corpus's references: each scene path-traced until two independent halves agree, kept in
//! a cache folder by the hash of the scene's bytes, its sky and the settings, so that a corpus
//! made again from the same seed, or a run stopped half way, renders nothing twice.

use super::{io_error, CorpusError, SceneRecord};
use crate::metrics::rel_mse;
use crate::output::{load_exr, save, write_bytes_atomic, RadianceImage};
use crate::reference::{render_full, ReferenceSettings};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

/// Bumped when the path tracer changes what it computes, or how far from converged it is at
/// a number of samples, so that cached references are made again (2: light paths, whose
/// references of rooms with a lamp near a wall are far less noisy; 3: the noise of dark
/// images judged at their display exposure too, [`noise_of`]).
pub const REFERENCE_VERSION: u32 = 3;

/// How the references are made.
#[derive(Clone, Debug)]
pub struct ReferenceOptions {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel of each half in the first round; every further round doubles them.
    pub spp_start: u32,
    /// The most samples per pixel in all.
    pub spp_max: u32,
    /// The reference's own error (an estimate of its relMSE against the converged image) that
    /// ends the rounds.
    pub noise_target: f64,
}

impl Default for ReferenceOptions {
    fn default() -> Self {
        ReferenceOptions {
            // On two cores a room lit by small emitters took 4 to 8 minutes at 128x128 and
            // 8192 samples per pixel; a corpus of 100 scenes at 96x96 takes about half a day
            // less (docs/corpus.md).
            width: 96,
            height: 96,
            spp_start: 64,
            spp_max: 8192,
            // A tenth of the classes' goal for the 90th percentile (relMSE 0.02).
            noise_target: 0.002,
        }
    }
}

/// What is kept beside a reference image.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ReferenceInfo {
    pub scene: String,
    pub key: String,
    pub width: u32,
    pub height: u32,
    /// Samples per pixel in all.
    pub spp: u32,
    /// relMSE of the two halves against each other, over 4: about the kept image's own relMSE
    /// against the converged one, which adds to every error measured against it.
    pub noise: f64,
    /// The same at the display exposure (both halves scaled by 2^`exposure`), where FLIP sees
    /// the images: larger than `noise` for images darker than the display's key.
    #[serde(default)]
    pub display_noise: f64,
    pub seconds: f64,
    /// Mean radiance (the three channels' mean over the pixels).
    pub mean: f64,
    /// The display exposure (stops) that puts the image's log-average luminance at 0.18: both
    /// images are shown at it for FLIP.
    pub exposure: f32,
}

/// A reference found in or added to the cache.
pub struct Reference {
    pub image: RadianceImage,
    pub info: ReferenceInfo,
}

/// The cache key: the scene file's bytes, its sky, the settings and [`REFERENCE_VERSION`].
pub fn key(
    dir: &Path,
    record: &SceneRecord,
    opts: &ReferenceOptions,
) -> Result<String, CorpusError> {
    let path = dir.join(&record.file);
    let bytes = std::fs::read(&path).map_err(|e| io_error(&path, e))?;
    let mut h = Sha256::new();
    h.update(&bytes);
    h.update(format!(
        "{:?} {} {} {} {} {} {}",
        record.sky,
        opts.width,
        opts.height,
        opts.spp_start,
        opts.spp_max,
        opts.noise_target,
        REFERENCE_VERSION
    ));
    let digest = h.finalize();
    Ok(digest[..8].iter().map(|b| format!("{b:02x}")).collect())
}

fn paths(cache: &Path, record: &SceneRecord, key: &str) -> (PathBuf, PathBuf) {
    let stem = format!("{}-{key}", record.name);
    (
        cache.join(format!("{stem}.exr")),
        cache.join(format!("{stem}.json")),
    )
}

/// The cached reference of `record`, if there is one for these settings.
pub fn cached(
    dir: &Path,
    cache: &Path,
    record: &SceneRecord,
    opts: &ReferenceOptions,
) -> Result<Option<Reference>, CorpusError> {
    let key = key(dir, record, opts)?;
    let (exr, json) = paths(cache, record, &key);
    if !json.exists() {
        return Ok(None);
    }
    let text = std::fs::read_to_string(&json).map_err(|e| io_error(&json, e))?;
    let info: ReferenceInfo = serde_json::from_str(&text).map_err(|e| io_error(&json, e))?;
    let image = load_exr(&exr).map_err(|e| io_error(&exr, e))?;
    Ok(Some(Reference { image, info }))
}

/// The reference of `record`: from the cache, or path-traced and kept there.
pub fn get(
    dir: &Path,
    cache: &Path,
    record: &SceneRecord,
    opts: &ReferenceOptions,
) -> Result<Reference, CorpusError> {
    if let Some(r) = cached(dir, cache, record, opts)? {
        return Ok(r);
    }
    let key = key(dir, record, opts)?;
    let scene = record.load(dir)?;
    let r = path_trace(&scene, &record.name, &key, opts);
    std::fs::create_dir_all(cache).map_err(|e| io_error(cache, e))?;
    let (exr, json) = paths(cache, record, &key);
    save(&r.image, &exr, 0.0).map_err(|e| io_error(&exr, e))?;
    // The record last: it marks the reference as whole.
    let text = serde_json::to_string_pretty(&r.info).expect("serializes") + "\n";
    write_bytes_atomic(&json, text.as_bytes()).map_err(|e| io_error(&json, e))?;
    Ok(r)
}

/// Two halves of independent samples, doubled each round until they agree within the target.
fn path_trace(
    scene: &crate::scene::Scene,
    name: &str,
    key: &str,
    opts: &ReferenceOptions,
) -> Reference {
    let start = std::time::Instant::now();
    let mut halves: [Option<RadianceImage>; 2] = [None, None];
    let mut spp_half = 0u32;
    let mut round = 0u64;
    let mut noise;
    loop {
        let add = spp_half.max(opts.spp_start);
        for (i, half) in halves.iter_mut().enumerate() {
            let img = render_full(
                scene,
                &ReferenceSettings {
                    width: opts.width,
                    height: opts.height,
                    spp: add,
                    seed: 2 * round + i as u64,
                    ..Default::default()
                },
            )
            .image;
            *half = Some(match half.take() {
                None => img,
                Some(h) => mix(&h, spp_half, &img, add),
            });
        }
        spp_half += add;
        round += 1;
        let [a, b] = [halves[0].as_ref().unwrap(), halves[1].as_ref().unwrap()];
        noise = noise_of(a, b);
        if noise.max() <= opts.noise_target || 2 * (spp_half + spp_half) > opts.spp_max {
            break;
        }
    }
    let [a, b] = halves.map(Option::unwrap);
    let image = mix(&a, 1, &b, 1);
    let mean = crate::hard::mean(&image);
    let info = ReferenceInfo {
        scene: name.to_string(),
        key: key.to_string(),
        width: opts.width,
        height: opts.height,
        spp: 2 * spp_half,
        noise: noise.radiance,
        display_noise: noise.display,
        seconds: start.elapsed().as_secs_f64(),
        mean,
        exposure: exposure_for(&image),
    };
    Reference { image, info }
}

/// A reference's own error, estimated from its two halves: relMSE of one against the other,
/// over 4, on the radiance (as the corpus measures the renderer) and at the display exposure
/// of their mean (as FLIP sees both images). relMSE's floor of 0.01 in the denominator hides
/// the noise of a dark image: a room lit by a dim sky through one window, whose pixels are
/// about 0.002, passed at 128 samples (0.0004) while its display was snow.
#[derive(Clone, Copy, Debug)]
pub struct Noise {
    pub radiance: f64,
    pub display: f64,
}

impl Noise {
    /// The larger: the rounds go on until both are under the target.
    pub fn max(&self) -> f64 {
        self.radiance.max(self.display)
    }
}

/// The noise of the mean of halves `a` and `b` (equal in samples), both ways.
pub fn noise_of(a: &RadianceImage, b: &RadianceImage) -> Noise {
    let scale = 2f64.powf(exposure_for(&mix(a, 1, b, 1)) as f64);
    Noise {
        radiance: rel_mse(a, b, 1.0) / 4.0,
        display: rel_mse(a, b, scale) / 4.0,
    }
}

/// The mean of `a` (of `na` samples) and `b` (of `nb`), weighed by their samples.
fn mix(a: &RadianceImage, na: u32, b: &RadianceImage, nb: u32) -> RadianceImage {
    let (wa, wb) = (na as f32 / (na + nb) as f32, nb as f32 / (na + nb) as f32);
    RadianceImage {
        pixels: a
            .pixels
            .iter()
            .zip(&b.pixels)
            .map(|(p, q)| std::array::from_fn(|c| p[c] * wa + q[c] * wb))
            .collect(),
        ..a.clone()
    }
}

/// The exposure (stops) that maps the log-average luminance of `img` to 0.18.
pub fn exposure_for(img: &RadianceImage) -> f32 {
    let n = img.pixels.len().max(1) as f64;
    let log_sum: f64 = img
        .pixels
        .iter()
        .map(|p| {
            let l = 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
            (l.max(0.0) + 1e-4).ln()
        })
        .sum();
    let average = (log_sum / n).exp();
    ((0.18 / average).log2() as f32).clamp(-20.0, 20.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exposure_puts_the_log_average_at_a_key_of_0_18() {
        let img = RadianceImage {
            width: 2,
            height: 1,
            pixels: vec![[0.045; 3], [0.045; 3]],
        };
        assert!((exposure_for(&img) - 2.0).abs() < 0.01);
    }

    /// Two halves of an image of `level`, their pixels `spread` above and below it by turns.
    fn dark_halves(level: f32, spread: f32) -> (RadianceImage, RadianceImage) {
        let img = |sign: f32| RadianceImage {
            width: 4,
            height: 4,
            pixels: (0..16)
                .map(|i| {
                    let s = if i % 2 == 0 { sign } else { -sign };
                    [level * (1.0 + s * spread); 3]
                })
                .collect(),
        };
        (img(1.0), img(-1.0))
    }

    #[test]
    fn a_dark_references_noise_is_judged_at_its_display_exposure() {
        let (a, b) = dark_halves(0.002, 0.2);
        let n = noise_of(&a, &b);
        // (2 * 0.0004)^2 / (0.002^2 + 0.01) / 4: far under any target.
        assert!(n.radiance < 1e-4, "{n:?}");
        // Scaled by about 87 (0.18 over the log-average, its guard of 1e-4 included), pixels
        // of 0.14 and 0.21 differ by 0.07: about 0.128 / 4.
        assert!((n.display - 0.0316).abs() < 0.001, "{n:?}");
        assert_eq!(n.max(), n.display);
        // A bright image's noise is its radiance's: the display scales it down.
        let (a, b) = dark_halves(2.0, 0.01);
        let n = noise_of(&a, &b);
        assert_eq!(n.max(), n.radiance, "{n:?}");
    }
}
