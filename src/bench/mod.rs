//! `voxgi bench`: renders a sweep of voxel settings, measures each one's GPU time per pass and
//! frame wall time, and its error against the path-traced reference of the same view; writes
//! results.csv, results.json, results.md and pareto.png.
//!
//! The reference is rendered once per scene content, size and sample count and kept in a cache
//! directory (`reference-<hash>-<w>x<h>-<spp>.exr`, with its variance estimate beside it).

pub mod chart;
mod font;
pub mod pareto;
pub mod report;
pub mod sweep;

pub use sweep::Setting;

use crate::gi::GiSettings;
use crate::metrics::{self, Metrics};
use crate::output::{self, RadianceImage};
use crate::reference::{self, ReferenceSettings};
use crate::render::{Mode, RenderSettings, Renderer};
use crate::scene::{self, Light, Scene};
use crate::vk::{Context, ContextDesc};
use std::path::PathBuf;
use std::sync::Arc;

#[derive(Clone, Debug)]
pub struct BenchOptions {
    pub scene: PathBuf,
    /// A sweep spec (see [`sweep`]).
    pub sweep: String,
    /// Where the results go.
    pub out_dir: PathBuf,
    /// Where references are cached (None: `out_dir/cache`).
    pub cache_dir: Option<PathBuf>,
    pub width: u32,
    pub height: u32,
    /// Frames timed per setting, after `warmup` frames that are not.
    pub frames: u32,
    pub warmup: u32,
    /// Samples per pixel of the reference.
    pub ref_spp: u32,
    /// The moving camera's swing about the scene's vertical axis, in degrees (see
    /// [`ORBIT_FRAMES`]).
    pub orbit_deg: f32,
    /// Lights added to the scene (the command line's `--sun`), part of the cache key.
    pub extra_lights: Vec<Light>,
    /// Light from beyond the scene (`--env`).
    pub environment: Option<crate::scene::Environment>,
    /// Display exposure of both images for FLIP.
    pub exposure: f32,
    /// Frames in the still image's antialiasing mean (RenderSettings::accumulate; 1: off).
    pub accumulate: u32,
    pub validate: bool,
    pub device: Option<String>,
    /// `--memory-budget`, bytes.
    pub memory_budget: Option<u64>,
    /// `--camera` or `--eye`/`--target`: the view instead of the file's.
    pub view: Option<crate::scene::ViewSpec>,
    /// The command line, quoted in results.md.
    pub command_line: String,
}

impl Default for BenchOptions {
    fn default() -> Self {
        BenchOptions {
            scene: PathBuf::new(),
            sweep: "default".into(),
            out_dir: PathBuf::from("bench"),
            cache_dir: None,
            width: 512,
            height: 512,
            frames: 10,
            warmup: 2,
            ref_spp: 256,
            orbit_deg: 10.0,
            extra_lights: Vec::new(),
            environment: None,
            exposure: 0.0,
            accumulate: RenderSettings::default().accumulate,
            validate: false,
            device: None,
            memory_budget: None,
            view: None,
            command_line: String::new(),
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum BenchError {
    #[error("--sweep {spec:?}: {reason}")]
    Sweep { spec: String, reason: String },
    #[error("{0}")]
    Options(String),
    #[error(transparent)]
    Scene(#[from] scene::SceneError),
    #[error(transparent)]
    Output(#[from] output::OutputError),
    #[error("{0}")]
    Vulkan(#[from] crate::vk::VkError),
    #[error("setting {label:?}: {reason}")]
    Setting { label: String, reason: String },
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

/// Median and extremes of a set of timings, in milliseconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spread {
    pub median: f64,
    pub min: f64,
    pub max: f64,
}

impl Spread {
    /// None for no samples.
    pub fn of(samples: &[f64]) -> Option<Spread> {
        let mut s: Vec<f64> = samples.iter().copied().filter(|v| v.is_finite()).collect();
        if s.is_empty() {
            return None;
        }
        s.sort_by(f64::total_cmp);
        let n = s.len();
        let median = if n % 2 == 1 {
            s[n / 2]
        } else {
            0.5 * (s[n / 2 - 1] + s[n / 2])
        };
        Some(Spread {
            median,
            min: s[0],
            max: s[n - 1],
        })
    }
}

/// One measured setting.
#[derive(Clone, Debug)]
pub struct Row {
    /// 1-based, in sweep order (the chart's point labels).
    pub index: usize,
    pub label: String,
    pub gi: GiSettings,
    /// GPU time per pass (timestamps) in the frames after the lights moved, in the order the
    /// passes ran.
    pub passes: Vec<(String, Spread)>,
    /// Submission to fence per frame after the lights moved (shadows, voxels and trace run).
    pub frame: Spread,
    /// Submission to fence per still frame (G-buffer, direct light and trace; a temporal trace
    /// traces no cones there).
    pub still: Spread,
    /// Submission to fence per frame of the moving camera.
    pub moving: Spread,
    /// The still frame's error.
    pub metrics: Metrics,
    /// The error of the moving camera's last frame, back where it started.
    pub moving_metrics: Metrics,
    /// The error of the first frame after the lights moved.
    pub relit_metrics: Metrics,
    /// How long the path tracer takes to reach the still frame's relMSE (None: not within
    /// the samples tried, see [`PtPoint`]).
    pub pt_ms: Option<f64>,
    /// Not beaten in both still-frame time and relMSE by another setting.
    pub pareto: bool,
}

/// The path tracer (`voxgi reference`, seed 1: not the reference's own samples) at one
/// sample count: its time without the BVH build, and its relMSE against the reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PtPoint {
    pub spp: u32,
    pub ms: f64,
    pub rel_mse: f64,
}

/// Everything a run measured, and what it was run on.
#[derive(Clone, Debug)]
pub struct BenchResults {
    pub options: BenchOptions,
    pub device: String,
    pub reference_path: PathBuf,
    /// The reference came from the cache.
    pub reference_cached: bool,
    /// relMSE that the reference's own noise adds, estimated from its variance (None when the
    /// cache has no variance image).
    pub reference_noise: Option<f64>,
    pub rows: Vec<Row>,
    /// The path tracer's time against its error, 1, 2, 4, .. spp.
    pub pt_curve: Vec<PtPoint>,
}

/// The words of a command line joined for a POSIX shell: any word with characters a shell
/// would read specially is single-quoted.
pub fn shell_words(words: &[String]) -> String {
    let plain = |c: char| c.is_ascii_alphanumeric() || "_-./=,:+^@%".contains(c);
    words
        .iter()
        .map(|w| {
            if !w.is_empty() && w.chars().all(plain) {
                w.clone()
            } else {
                format!("'{}'", w.replace('\'', "'\\''"))
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// FNV-1a, 64 bits: stable across runs and Rust versions, unlike `DefaultHasher`.
struct Fnv(u64);

impl Fnv {
    fn new() -> Fnv {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    fn bytes(&mut self, b: &[u8]) -> &mut Fnv {
        // Length first, so that consecutive fields cannot run into each other.
        for &x in (b.len() as u64).to_le_bytes().iter().chain(b) {
            self.0 ^= x as u64;
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
        self
    }
}

/// The reference's cache key: the scene file's bytes, the lights added to it, the reference
/// settings and the crate version (a new path tracer may converge elsewhere).
pub fn reference_key(
    scene_bytes: &[u8],
    extra_lights: &[Light],
    settings: &ReferenceSettings,
) -> String {
    let mut h = Fnv::new();
    h.bytes(env!("CARGO_PKG_VERSION").as_bytes())
        .bytes(scene_bytes);
    for l in extra_lights {
        h.bytes(format!("{:?}", l.kind).as_bytes());
        for v in [l.radiance, l.position, l.direction] {
            for x in v.to_array() {
                h.bytes(&x.to_bits().to_le_bytes());
            }
        }
        h.bytes(&l.range.unwrap_or(-1.0).to_bits().to_le_bytes());
    }
    for x in [
        settings.seed,
        settings.max_depth as u64,
        settings.rr_depth as u64,
    ] {
        h.bytes(&x.to_le_bytes());
    }
    // Only when set, so that the full references keep their keys.
    if let Some(b) = settings.bounces {
        h.bytes(&(b as u64).to_le_bytes());
    }
    format!(
        "{:016x}-{}x{}-{}",
        h.0, settings.width, settings.height, settings.spp
    )
}

/// Mean over pixels and channels of var / (R^2 + eps): what comparing a perfect image against
/// this noisy reference would give as relMSE.
fn noise_rel_mse(image: &RadianceImage, variance: &RadianceImage) -> f64 {
    let mut sum = 0.0;
    for (p, v) in image.pixels.iter().zip(&variance.pixels) {
        for c in 0..3 {
            let r = p[c] as f64;
            sum += v[c] as f64 / (r * r + metrics::REL_MSE_EPSILON);
        }
    }
    sum / (image.pixels.len() * 3).max(1) as f64
}

/// The reference from the cache when it is there and of the right size, else rendered and
/// stored. Returns (image, path, cached, noise).
fn reference(
    scene: &Scene,
    opts: &BenchOptions,
    scene_bytes: &[u8],
) -> Result<(RadianceImage, PathBuf, bool, Option<f64>), BenchError> {
    let settings = ReferenceSettings {
        width: opts.width,
        height: opts.height,
        spp: opts.ref_spp,
        progress: true,
        ..Default::default()
    };
    let dir = opts
        .cache_dir
        .clone()
        .unwrap_or_else(|| opts.out_dir.join("cache"));
    let mut key = reference_key(scene_bytes, &opts.extra_lights, &settings);
    // An environment (--env): its own references, by its radiance, texels, strength and turn.
    if let Some(e) = &opts.environment {
        let mut h = Fnv::new();
        h.bytes(&e.strength.to_bits().to_le_bytes())
            .bytes(&e.rotation.to_bits().to_le_bytes());
        match &e.source {
            crate::scene::EnvSource::Uniform(rgb) => {
                h.bytes(
                    &rgb.to_array()
                        .map(f32::to_bits)
                        .map(u32::to_le_bytes)
                        .concat(),
                );
            }
            crate::scene::EnvSource::Image(img) => {
                h.bytes(&[img.width, img.height].map(u32::to_le_bytes).concat());
                for t in &img.texels {
                    h.bytes(
                        &t.to_array()
                            .map(f32::to_bits)
                            .map(u32::to_le_bytes)
                            .concat(),
                    );
                }
            }
        }
        key = format!("e{:016x}-{key}", h.0);
    }
    // A view asked for (--camera, --eye): its own references; without one the keys stay.
    if let Some(v) = &opts.view {
        key = format!(
            "v{:016x}-{key}",
            Fnv::new().bytes(format!("{v:?}").as_bytes()).0
        );
    }
    let path = dir.join(format!("reference-{key}.exr"));
    let var_path = dir.join(format!("reference-{key}-var.exr"));
    if path.exists() {
        match output::load_exr(&path) {
            Ok(img)
                if (img.width, img.height) == (opts.width, opts.height)
                    && !img.has_non_finite() =>
            {
                let noise = output::load_exr(&var_path)
                    .ok()
                    .filter(|v| (v.width, v.height) == (img.width, img.height))
                    .map(|v| noise_rel_mse(&img, &v));
                log::info!("reference: cached {}", path.display());
                return Ok((img, path, true, noise));
            }
            Ok(img) => log::warn!(
                "{}: cached reference is {}x{} (or not finite); rendering it again",
                path.display(),
                img.width,
                img.height
            ),
            Err(e) => log::warn!("{e}; rendering the reference again"),
        }
    }
    log::info!(
        "reference: path tracing {}x{} at {} spp on the CPU",
        opts.width,
        opts.height,
        opts.ref_spp
    );
    let r = reference::render_full(scene, &settings);
    if r.bad_samples > 0 {
        log::warn!("the reference dropped {} NaN/Inf samples", r.bad_samples);
    }
    std::fs::create_dir_all(&dir).map_err(|source| BenchError::Io {
        path: dir.clone(),
        source,
    })?;
    // The variance first: a reference found in the cache then always has its variance.
    output::save(&r.variance, &var_path, 0.0)?;
    output::save(&r.image, &path, 0.0)?;
    log::info!("reference: {:.1} s, cached {}", r.seconds, path.display());
    let noise = noise_rel_mse(&r.image, &r.variance);
    Ok((r.image, path, false, Some(noise)))
}

impl BenchOptions {
    fn check(&self) -> Result<(), BenchError> {
        let bad = |m: String| Err(BenchError::Options(m));
        let (w, h) = (self.width, self.height);
        if w == 0 || h == 0 || w > 16384 || h > 16384 {
            return bad(format!("image size {w}x{h} is out of range (1 to 16384)"));
        }
        if !(1..=100_000).contains(&self.frames) {
            return bad(format!(
                "--frames {} is out of range (1 to 100000)",
                self.frames
            ));
        }
        if self.warmup > 100_000 {
            return bad(format!(
                "--warmup {} is out of range (0 to 100000)",
                self.warmup
            ));
        }
        if !(1..=1 << 20).contains(&self.ref_spp) {
            return bad(format!(
                "--ref-spp {} is out of range (1 to 1048576)",
                self.ref_spp
            ));
        }
        if !(self.orbit_deg.is_finite() && self.orbit_deg.abs() <= 180.0) {
            return bad(format!(
                "--orbit {} is out of range (-180 to 180 degrees)",
                self.orbit_deg
            ));
        }
        if !self.exposure.is_finite() {
            return bad("--exposure must be finite".into());
        }
        if self.out_dir.as_os_str().is_empty() {
            return bad("--out needs a directory".into());
        }
        if self.out_dir.exists() && !self.out_dir.is_dir() {
            return bad(format!("{}: not a directory", self.out_dir.display()));
        }
        Ok(())
    }
}

/// What one setting's frames measured, and its images.
struct Measured {
    passes: Vec<(String, Spread)>,
    frame: Spread,
    still: Spread,
    moving: Spread,
    image: RadianceImage,
    relit_image: RadianceImage,
    moving_image: RadianceImage,
}

/// Frames of the moving camera: swung out to one side and the other and back.
pub const ORBIT_FRAMES: u32 = 8;

/// Warm-up frames, then `frames` timed ones, then one with readback for the image.
fn measure(
    ctx: &Arc<Context>,
    scene: &Scene,
    opts: &BenchOptions,
    setting: &Setting,
) -> Result<Measured, String> {
    let settings = RenderSettings {
        width: opts.width,
        height: opts.height,
        mode: Mode::Full,
        timings: true,
        gi: setting.gi.clone(),
        accumulate: opts.accumulate,
        ..Default::default()
    };
    let mut r = Renderer::new(ctx, scene, settings).map_err(|e| e.to_string())?;
    for _ in 0..opts.warmup {
        r.render(false).map_err(|e| e.to_string())?;
    }
    // Only the timed frames count (the first frame also voxelizes the static geometry).
    r.frame_ms.clear();
    if let Some(t) = r.timer.as_mut() {
        t.samples.clear();
    }
    // Each timed frame is one after the lights moved: shadow maps, voxel lighting and bounces
    // run, as every setting's cost lies there as well as in the trace (a still frame of a
    // still scene only traces).
    for _ in 0..opts.frames {
        r.relight();
        r.render(false).map_err(|e| e.to_string())?;
    }
    let passes = r
        .timer
        .as_ref()
        .map(|t| {
            t.samples
                .iter()
                .filter_map(|(name, v)| Spread::of(v).map(|s| (name.clone(), s)))
                .collect()
        })
        .unwrap_or_default();
    let frame = Spread::of(&r.frame_ms).ok_or("no frame was timed")?;
    let image = |r: &Renderer| RadianceImage {
        width: opts.width,
        height: opts.height,
        pixels: r.radiance(),
    };
    // The first frame after the lights moved, as shown.
    r.relight();
    r.render(true).map_err(|e| e.to_string())?;
    let relit_image = image(&r);
    // Still frames (a temporal trace keeps its blocks' cones: it traces none).
    r.frame_ms.clear();
    for _ in 0..opts.frames {
        r.render(false).map_err(|e| e.to_string())?;
    }
    let still = Spread::of(&r.frame_ms).ok_or("no frame was timed")?;
    // The still image once its antialiasing mean is complete (the relit frame was its first).
    for _ in opts.frames + 2..=r.settings.accumulate {
        r.render(false).map_err(|e| e.to_string())?;
    }
    r.render(true).map_err(|e| e.to_string())?;
    let still_image = image(&r);
    // The moving camera: about the vertical axis through the scene's centre, by
    // orbit x sin(2 pi k / ORBIT_FRAMES) in frame k, so the last frame is at the start again
    // and its error is against the same reference, after a temporal history went through the
    // motion (reprojected each frame, disoccluded at the sides).
    let start = r.camera.world;
    let centre = scene.bounds.center();
    r.frame_ms.clear();
    for k in 1..=ORBIT_FRAMES {
        let phase = std::f32::consts::TAU * k as f32 / ORBIT_FRAMES as f32;
        let angle = if k == ORBIT_FRAMES {
            0.0
        } else {
            opts.orbit_deg.to_radians() * phase.sin()
        };
        r.camera.world = glam::Mat4::from_translation(centre)
            * glam::Mat4::from_rotation_y(angle)
            * glam::Mat4::from_translation(-centre)
            * start;
        r.render(k == ORBIT_FRAMES).map_err(|e| e.to_string())?;
    }
    let moving = Spread::of(&r.frame_ms).ok_or("no frame was timed")?;
    Ok(Measured {
        passes,
        frame,
        still,
        moving,
        image: still_image,
        relit_image,
        moving_image: image(&r),
    })
}

/// The path tracer's error at 1, 2, 4, .. spp until it is at most `target` relMSE or reaches
/// half the reference's samples.
fn path_tracer_curve(
    scene: &Scene,
    opts: &BenchOptions,
    reference: &RadianceImage,
    target: f64,
) -> Result<Vec<PtPoint>, BenchError> {
    let mut curve = Vec::new();
    let mut spp = 1;
    loop {
        let settings = ReferenceSettings {
            width: opts.width,
            height: opts.height,
            spp,
            seed: 1,
            ..Default::default()
        };
        let r = reference::render_full(scene, &settings);
        let m = metrics::try_compare(&r.image, reference, opts.exposure)
            .map_err(|e| BenchError::Options(format!("path tracer at {spp} spp: {e}")))?;
        let point = PtPoint {
            spp,
            ms: (r.seconds - r.setup_seconds) * 1e3,
            rel_mse: m.rel_mse,
        };
        log::info!(
            "path tracer: {spp} spp {:.1} ms relMSE {:.5}",
            point.ms,
            point.rel_mse
        );
        curve.push(point);
        if m.rel_mse <= target || spp * 2 > (opts.ref_spp / 2).max(1) {
            return Ok(curve);
        }
        spp *= 2;
    }
}

/// The path tracer's time to reach relMSE `target`: interpolated between the sample counts
/// that bracket it (log time against log error); below 1 spp's error, 1 spp's time scaled as
/// error goes with 1 / samples; past the most samples tried, extrapolated along the last two
/// points' error = a / spp + b (b: the reference's own noise and the tracer's bias). None when
/// the curve is empty or `target` is at or below b (no sample count gets there).
pub fn equal_error_ms(curve: &[PtPoint], target: f64) -> Option<f64> {
    let Some(k) = curve.iter().position(|p| p.rel_mse <= target) else {
        let [.., p, q] = curve else {
            return None;
        };
        let (x1, x2) = (1.0 / p.spp as f64, 1.0 / q.spp as f64);
        let a = (p.rel_mse - q.rel_mse) / (x1 - x2);
        let b = q.rel_mse - a * x2;
        if a.is_nan() || a <= 0.0 || target <= b {
            return None;
        }
        let spp = a / (target - b);
        return Some(q.ms * spp / q.spp as f64);
    };
    let b = curve[k];
    if k == 0 {
        return Some(b.ms * (b.rel_mse / target).max(0.0));
    }
    let a = curve[k - 1];
    if a.rel_mse <= b.rel_mse || target <= 0.0 {
        return Some(b.ms);
    }
    let t = (target.ln() - a.rel_mse.ln()) / (b.rel_mse.ln() - a.rel_mse.ln());
    Some((a.ms.ln() + t * (b.ms.ln() - a.ms.ln())).exp())
}

/// Runs the benchmark and writes its outputs into `opts.out_dir` (all of them, or none on
/// error; the reference cache is kept either way).
pub fn run(opts: &BenchOptions) -> Result<BenchResults, BenchError> {
    opts.check()?;
    let settings = sweep::parse(&opts.sweep).map_err(|reason| BenchError::Sweep {
        spec: opts.sweep.clone(),
        reason,
    })?;
    let scene_bytes = std::fs::read(&opts.scene).map_err(|source| BenchError::Io {
        path: opts.scene.clone(),
        source,
    })?;
    // scene::load logs its warnings.
    let mut scene = scene::load(&opts.scene)?;
    scene.lights.extend(opts.extra_lights.iter().cloned());
    scene.environment = opts.environment.clone();
    if let Some(v) = &opts.view {
        scene.set_view(v).map_err(BenchError::Options)?;
    }
    if scene.lights.is_empty()
        && scene.environment.is_none()
        && !scene.materials.iter().any(|m| m.is_emissive())
    {
        log::warn!(
            "{}: no lights and no emission; every image is black",
            opts.scene.display()
        );
    }

    // The device first: a machine without one fails before the long reference render.
    let ctx = Context::new(&ContextDesc {
        validate: opts.validate,
        device: opts.device.clone(),
        memory_budget: opts.memory_budget,
        ..Default::default()
    })?;
    let device = ctx.device_info.to_string();
    log::info!("device: {device}");
    if ctx.timestamp_valid_bits == 0 {
        log::warn!("the device has no timestamps; only frame wall times");
    }
    let (reference, reference_path, reference_cached, reference_noise) =
        reference(&scene, opts, &scene_bytes)?;

    let n = settings.len();
    let mut rows = Vec::with_capacity(n);
    let bar = crate::console::bar(n as u64, "bench, settings");
    for (k, setting) in settings.iter().enumerate() {
        bar.inc(1);
        let fail = |reason: String| BenchError::Setting {
            label: setting.label.clone(),
            reason,
        };
        let Measured {
            passes,
            frame,
            still,
            moving,
            image,
            relit_image,
            moving_image,
        } = measure(&ctx, &scene, opts, setting).map_err(fail)?;
        if opts.validate && ctx.stats.count() > 0 {
            return Err(fail(format!(
                "validation reported {} message(s)",
                ctx.stats.count()
            )));
        }
        let m = metrics::try_compare(&image, &reference, opts.exposure)
            .map_err(|e| fail(e.to_string()))?;
        let relit = metrics::try_compare(&relit_image, &reference, opts.exposure)
            .map_err(|e| fail(e.to_string()))?;
        let moved = metrics::try_compare(&moving_image, &reference, opts.exposure)
            .map_err(|e| fail(e.to_string()))?;
        log::info!(
            "[{}/{n}] {:<28} still {:.1} ms  moving {:.1} ms  relit {:.1} ms  relMSE {:.5} \
             (moving {:.5}, relit {:.5})  FLIP {:.4}",
            k + 1,
            setting.label,
            still.median,
            moving.median,
            frame.median,
            m.rel_mse,
            moved.rel_mse,
            relit.rel_mse,
            m.flip
        );
        rows.push(Row {
            index: k + 1,
            label: setting.label.clone(),
            gi: setting.gi.clone(),
            passes,
            frame,
            still,
            moving,
            metrics: m,
            moving_metrics: moved,
            relit_metrics: relit,
            pt_ms: None,
            pareto: false,
        });
    }
    drop(ctx);

    let target = rows
        .iter()
        .map(|r| r.metrics.rel_mse)
        .fold(f64::INFINITY, f64::min);
    let pt_curve = path_tracer_curve(&scene, opts, &reference, target)?;
    for row in rows.iter_mut() {
        row.pt_ms = equal_error_ms(&pt_curve, row.metrics.rel_mse);
    }
    let points: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| (r.still.median, r.metrics.rel_mse))
        .collect();
    for (row, on) in rows.iter_mut().zip(pareto::front(&points)) {
        row.pareto = on;
    }
    let results = BenchResults {
        options: opts.clone(),
        device,
        reference_path,
        reference_cached,
        reference_noise,
        rows,
        pt_curve,
    };
    report::write_all(&results, &opts.out_dir)?;
    log::info!(
        "wrote {}/{{results.csv, results.json, results.md, pareto.png}}",
        opts.out_dir.display()
    );
    Ok(results)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shell_words_quote_what_a_shell_would_split() {
        let w = |v: &[&str]| shell_words(&v.iter().map(|s| s.to_string()).collect::<Vec<_>>());
        assert_eq!(w(&["voxgi", "bench", "a.gltf"]), "voxgi bench a.gltf");
        assert_eq!(
            w(&["--sweep", "voxels=32;paper=0,1"]),
            "--sweep 'voxels=32;paper=0,1'"
        );
        assert_eq!(w(&["it's", ""]), "'it'\\''s' ''");
    }

    #[test]
    fn equal_error_time_interpolates_the_path_tracer_log_log() {
        let p = |spp: u32, ms: f64, rel_mse: f64| PtPoint { spp, ms, rel_mse };
        // Error halving with each doubling of time: 1/spp.
        let curve = [p(1, 10.0, 0.08), p(2, 20.0, 0.04), p(4, 40.0, 0.02)];
        let at = |e: f64| equal_error_ms(&curve, e).unwrap();
        assert!((at(0.04) - 20.0).abs() < 1e-9);
        // Between 2 and 4 spp: error 0.04 / 1.5 takes 30 ms.
        assert!((at(0.04 / 1.5) - 30.0).abs() < 1e-9, "{}", at(0.04 / 1.5));
        // Above 1 spp's error: less than 1 spp's time, in proportion.
        assert!((at(0.16) - 5.0).abs() < 1e-9);
        // Below every point: along error = 0.08 / spp, 8 spp.
        assert!((at(0.01) - 80.0).abs() < 1e-9, "{}", at(0.01));
        // An error floor of 0.01 (the reference's noise): 0.012 takes 32 spp, 0.01 never.
        let floor = [p(1, 10.0, 0.09), p(2, 20.0, 0.05)];
        let t = equal_error_ms(&floor, 0.0125).unwrap();
        assert!((t - 320.0).abs() < 1e-6, "{t}");
        assert_eq!(equal_error_ms(&floor, 0.01), None);
    }

    #[test]
    fn spread_median_of_odd_and_even_counts() {
        let s = Spread::of(&[3.0, 1.0, 2.0]).unwrap();
        assert_eq!((s.median, s.min, s.max), (2.0, 1.0, 3.0));
        assert_eq!(Spread::of(&[4.0, 1.0, 2.0, 3.0]).unwrap().median, 2.5);
        assert!(Spread::of(&[]).is_none());
    }

    #[test]
    fn reference_key_follows_content_and_settings() {
        let s = ReferenceSettings {
            width: 64,
            height: 32,
            spp: 16,
            ..Default::default()
        };
        let k = reference_key(b"scene", &[], &s);
        assert!(k.ends_with("-64x32-16"), "{k}");
        assert_eq!(k, reference_key(b"scene", &[], &s));
        assert_ne!(k, reference_key(b"scene!", &[], &s));
        assert_ne!(
            k,
            reference_key(
                b"scene",
                &[],
                &ReferenceSettings {
                    seed: 1,
                    ..s.clone()
                }
            )
        );
        let sun = Light {
            name: None,
            kind: crate::scene::LightKind::Directional,
            radiance: glam::Vec3::splat(3.0),
            range: None,
            position: glam::Vec3::ZERO,
            direction: glam::Vec3::NEG_Y,
        };
        assert_ne!(k, reference_key(b"scene", &[sun], &s));
    }
}
