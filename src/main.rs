//! voxgi: the command line (clap). Bad input is one error line on stderr and exit status 1;
//! `voxgi help COMMAND` and `--help` print the options.

use anyhow::{anyhow, bail, Context as _, Result};
use clap::{Args, Parser, Subcommand};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use voxgi::gi::{GiSettings, MAX_BOUNCES};
use voxgi::output::{self, RadianceImage};
use voxgi::render::{Mode, RenderSettings, Renderer};
use voxgi::scene::{self, Scene};
use voxgi::vk::{Context, ContextDesc};

mod commands;

#[derive(Parser)]
#[command(
    name = "voxgi",
    version,
    about = "voxgi: real-time global illumination by deferred voxel shading, on Vulkan",
    arg_required_else_help = true
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// More log lines on stderr: -v details, -vv everything (RUST_LOG overrides)
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    verbose: u8,
    /// Warnings and errors only on stderr, no progress bars
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    quiet: bool,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to an image (EXR radiance or PNG display)
    ///
    /// Without a scene, the bundled Cornell box.
    Render(RenderCmd),
    /// The renderer in a window with a free camera
    ///
    /// Keys: press H, or see the README. The title shows the settings and per-pass times.
    View(ViewCmd),
    /// What a scene holds and what a render of it would run and allocate
    Info(InfoCmd),
    /// CPU path-traced ground truth (all cores)
    Reference(ReferenceCmd),
    /// relMSE, MAE, RMSE and FLIP of an image against a reference, as one JSON line
    Compare(CompareCmd),
    /// Run the hard cases and print their table
    ///
    /// Light leaks, density, precision, degenerate input, extreme lights, cones at the edges:
    /// all of them or those named, each with --paper and the defaults, under validation.
    /// Prints the markdown table of docs/hard-cases.md and fails when a default setting misses
    /// its goal.
    HardCases(HardCasesCmd),
    /// Time a sweep of settings and measure each one's error against the reference
    ///
    /// Per-pass GPU medians and frame wall time over --frames after --warmup; writes DIR
    /// results.csv, results.json, results.md and pareto.png.
    Bench(BenchCmd),
    /// Fuzz the glTF and GLB loader with damaged copies of seed scenes
    ///
    /// The bundled Cornell box (as .gltf and .glb) and any files given, damaged: bytes set,
    /// cut or inserted, JSON numbers set to awkward values, structures broken (node cycles,
    /// deep hierarchies, accessors beyond their buffers, keys removed or of another type).
    /// Every case must load into a well-formed scene or fail with a one-line error naming the
    /// file; panics, hangs and other outcomes are listed, and the exit status is 1.
    FuzzLoader(FuzzCmd),
    /// Render thousands of frames with a moving node and moving lights, watching memory
    ///
    /// Every frame moves the node (--spin NODE, the scene's animations, or else the first node
    /// with a mesh), circles the point lights and spots and swings the directional lights and
    /// spots, so each frame voxelizes, lights and bounces again. Samples host memory (VmRSS),
    /// GPU allocations and the timing lists; fails when host memory grows by more than
    /// --max-growth over the run (after its first tenth), GPU memory changes, the timing lists
    /// grow without bound, an image holds NaN or Inf, or validation (--validate) says anything.
    Soak(SoakCmd),
    /// Every scene given in every mode, default and --paper, under validation
    ///
    /// Each run renders --frames frames with a node and the lights moving (as soak does; a
    /// scene without punctual lights gets --sun 50,30,4). Prints a markdown table of the
    /// validation messages, the frames with NaN or Inf pixels and the NaN or Inf voxels left in
    /// the volumes, per scene and mode; exit status 1 if any is not 0.
    ValidationSweep(SweepCmd),
    /// A generated scene corpus: its scenes, references and the renderer's error on them
    ///
    /// `voxgi corpus generate --out DIR`, then `voxgi corpus run DIR --split held-out`
    /// (docs/corpus.md).
    Corpus(commands::corpus::CorpusCmd),
    /// Print a shell completion script (bash, zsh or fish)
    ///
    /// bash: `source <(voxgi completions bash)`; zsh: `voxgi completions zsh > ~/.zfunc/_voxgi`
    /// (with ~/.zfunc in fpath); fish: `voxgi completions fish > ~/.config/fish/completions/voxgi.fish`.
    Completions(CompletionsCmd),
}

#[derive(Args)]
struct CompletionsCmd {
    /// bash, zsh or fish
    #[arg(value_parser = ["bash", "zsh", "fish"])]
    shell: String,
}

/// `--bounces B`: 1 to MAX_BOUNCES.
fn bounces_range() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..=MAX_BOUNCES as i64)
}

/// An image side: 1 to 16384 pixels.
fn side_range() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..=16384)
}

#[derive(Args, Clone)]
struct SizeOpts {
    /// Image width in pixels
    #[arg(long, default_value_t = 512, value_parser = side_range())]
    width: u32,
    /// Image height in pixels
    #[arg(long, default_value_t = 512, value_parser = side_range())]
    height: u32,
}

/// The voxel passes' settings.
#[derive(Args, Clone)]
struct GiOpts {
    /// Voxels per side of the grid
    #[arg(long, default_value_t = GiSettings::default().voxels,
          value_parser = clap::value_parser!(u32).range(4..=1024))]
    voxels: u32,
    /// 1: direct light in the voxels; 2 (default) to 8: plus B - 1 bounces between voxels
    /// (each one more bounce pass and mipmap, run when a light or node moves)
    #[arg(long, value_name = "B", value_parser = bounces_range())]
    bounces: Option<u32>,
    /// The original's behaviour and constants (RGBA8 averages and volumes, 6 cones)
    #[arg(long)]
    paper: bool,
    /// Diffuse cones per pixel (default 16)
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=16))]
    cones: Option<u32>,
    /// Aperture of the diffuse cones in degrees (default 36)
    #[arg(long, value_name = "DEG", value_parser = aperture)]
    aperture: Option<f32>,
    /// Diffuse cones per voxel in the bounces (default 12; the paper 6)
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=16))]
    bounce_cones: Option<u32>,
    /// Aperture of the bounces' cones in degrees (default 36; the paper 60)
    #[arg(long, value_name = "DEG", value_parser = aperture)]
    bounce_aperture: Option<f32>,
    /// Cone step as a fraction of the cone diameter (default 0.5)
    #[arg(long, value_name = "F", value_parser = step)]
    step: Option<f32>,
    /// Voxel visibility by tracing the voxels (else the shadow maps)
    #[arg(long)]
    voxel_shadows: bool,
    /// Soft shadows: direct light shadowed by cones through the voxels
    #[arg(long)]
    cone_shadows: bool,
    /// With --paper: the original's slips reproduced (its light pass reading the -X
    /// directional volume for all six directions; normals not swapped on a winding flip)
    #[arg(long, requires = "paper")]
    paper_slips: bool,
    /// The last bounce does not add the bounces after it (by default it adds them as a
    /// geometric series whose ratio is the voxels' albedo times their closed share, their mean
    /// weighted by the light each gathered, at most 0.8)
    #[arg(long)]
    no_tail: bool,
    /// Emissive surfaces stay voxel emission, lit by the cones (by default up to eight, the
    /// most powerful, are area lights: exact per pixel, with soft shadows)
    #[arg(long, alias = "no-emitter-lights")]
    no_area_lights: bool,
    /// Trace the diffuse cones once per block of S x S pixels (1, 2 or 4) and upsample them by
    /// position and normal (default 4; not with --paper)
    #[arg(long, value_name = "S", value_parser = trace_scale, conflicts_with = "paper")]
    trace_scale: Option<u32>,
    /// Keep the diffuse cones over frames, in a history reprojected from the frame before;
    /// surfaces a moving camera uncovers trace every N-th cone a frame (0: every cone every
    /// frame; default 4; not with --paper)
    #[arg(long, value_name = "N", conflicts_with = "paper",
          value_parser = clap::value_parser!(u32).range(0..=16))]
    temporal: Option<u32>,
    /// The specular cone's narrowest diameter in voxels, 1 to 8 (default 2: a near-mirror's
    /// cone steps a voxel at a time, not half a voxel as with 1; not with --paper)
    #[arg(long, value_name = "VOXELS", value_parser = specular_min, conflicts_with = "paper")]
    specular_min: Option<f32>,
    /// Cones do not jump across empty space (by default they skip the samples that could
    /// read nothing: the same image, faster in open scenes)
    #[arg(long)]
    no_empty_space: bool,
    /// Voxels do not hold the light of their surfaces' backs apart (by default a
    /// zero-thickness surface with nothing behind it reflects on both sides, as a path
    /// tracer's does)
    #[arg(long)]
    no_backs: bool,
    /// Every voxel gathers its own bounce light (by default the one-sided voxels of a 4x4x4
    /// block that lie in one plane with nothing in front and face one way share one gather)
    #[arg(long)]
    no_bounce_share: bool,
}

fn trace_scale(s: &str) -> Result<u32, String> {
    match s.parse::<u32>() {
        Ok(v @ (1 | 2 | 4)) => Ok(v),
        _ => Err("must be 1, 2 or 4".into()),
    }
}

fn aperture(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(a) if a > 0.5 && a < 179.0 => Ok(a),
        _ => Err("must be between 0.5 and 179 degrees".into()),
    }
}

fn step(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(f) if (0.05..=4.0).contains(&f) => Ok(f),
        _ => Err("must be between 0.05 and 4".into()),
    }
}

fn specular_min(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(f) if (1.0..=8.0).contains(&f) => Ok(f),
        _ => Err("must be between 1 and 8 (voxels)".into()),
    }
}

fn mode(s: &str) -> Result<Mode, String> {
    s.parse()
}

/// What `render`, `view` and `info` share: the image, the mode and the voxel settings.
#[derive(Args, Clone)]
struct RenderOpts {
    #[command(flatten)]
    size: SizeOpts,
    /// full: direct + cone-traced indirect light; direct: punctual lights with shadows, plus
    /// emission; indirect; ao; voxels-albedo, voxels-normal, voxels-emission,
    /// voxels-radiance: the first voxel along each ray
    #[arg(long, default_value = "full", value_parser = mode)]
    mode: Mode,
    /// With --mode voxels-radiance: the directional volumes at mip level L
    #[arg(long, value_name = "L")]
    mip: Option<u32>,
    /// Shadow-map texels per side (punctual lights)
    #[arg(long, default_value_t = 2048,
          value_parser = clap::value_parser!(u32).range(16..=16384))]
    shadow_res: u32,
    /// Shadow-map texels per side of the area lights (emissive surfaces), whose soft shadows
    /// need fewer
    #[arg(long, default_value_t = 512,
          value_parser = clap::value_parser!(u32).range(16..=16384))]
    area_shadow_res: u32,
    /// Print each pass's median GPU time
    #[arg(long)]
    timings: bool,
    /// Antialiasing: while the view holds still, the image is the mean of N frames drawn at
    /// sub-pixel offsets (each pixel the mean over its footprint); 1 is off
    #[arg(long, value_name = "N", default_value_t = 8,
          value_parser = clap::value_parser!(u32).range(1..=1024))]
    accumulate: u32,
    #[command(flatten)]
    gi: GiOpts,
}

#[derive(Args, Clone)]
struct DeviceOpts {
    /// Khronos validation with synchronization validation; any message fails the run
    #[arg(long)]
    validate: bool,
    /// Use the Vulkan device whose name contains NAME
    #[arg(long, value_name = "NAME")]
    device: Option<String>,
    /// Refuse GPU allocations beyond MIB mebibytes in all, as a device out of memory would
    #[arg(long, value_name = "MIB", value_parser = clap::value_parser!(u64).range(1..=1 << 40))]
    memory_budget: Option<u64>,
}

impl DeviceOpts {
    fn budget_bytes(&self) -> Option<u64> {
        self.memory_budget.map(|m| m << 20)
    }
}

#[derive(Args, Clone)]
struct SunOpt {
    /// Add a white directional light from elevation EL and azimuth AZ (degrees; azimuth 0 is
    /// +Z, 90 is +X) with irradiance E W/m^2 (default 3): for scenes without lights
    #[arg(long, value_name = "EL,AZ[,E]", value_parser = parse_sun)]
    sun: Option<scene::Light>,
}

/// Light from beyond the scene (CONVENTIONS.md, "Environment").
#[derive(Args, Clone)]
struct EnvOpts {
    /// Light from every direction in which a ray leaves the scene: a uniform radiance R,G,B
    /// (W/sr/m^2), or an equirectangular .hdr or .exr image of linear radiance (row 0 looks
    /// up, its centre along -Z); background pixels show it
    #[arg(long, value_name = "R,G,B|FILE")]
    env: Option<String>,
    /// Multiplies the environment's radiance
    #[arg(long, value_name = "S", default_value_t = 1.0, requires = "env")]
    env_strength: f32,
    /// Turns the environment about +Y by DEG degrees, counter-clockwise seen from above
    #[arg(
        long,
        value_name = "DEG",
        default_value_t = 0.0,
        requires = "env",
        allow_hyphen_values = true
    )]
    env_rotate: f32,
}

impl EnvOpts {
    fn environment(&self) -> Result<Option<scene::Environment>> {
        self.env
            .as_deref()
            .map(|spec| scene::Environment::from_spec(spec, self.env_strength, self.env_rotate))
            .transpose()
            .map_err(|e| anyhow!(e))
    }
}

#[derive(Args, Clone)]
struct SpinOpts {
    /// Turn the node named NODE about its vertical axis (voxelized every frame, apart from the
    /// static geometry); glTF animations play
    #[arg(long, value_name = "NODE")]
    spin: Option<String>,
    /// Degrees per second of --spin (default 90)
    #[arg(long, value_name = "DEG", requires = "spin")]
    spin_speed: Option<f32>,
}

/// Where the camera is: one of the file's, or an eye and a target.
#[derive(Args, Clone)]
struct CameraOpts {
    /// View through the file's camera NAME, or the one of index INDEX in its cameras
    #[arg(long, value_name = "NAME|INDEX", conflicts_with = "eye")]
    camera: Option<String>,
    /// Place the camera at X,Y,Z (the file's coordinates, metres), looking at --target
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_point, requires = "target", allow_hyphen_values = true)]
    eye: Option<glam::DVec3>,
    /// The point the camera looks at (with --eye)
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_point, requires = "eye", allow_hyphen_values = true)]
    target: Option<glam::DVec3>,
    /// The camera's up direction (with --eye; default 0,1,0)
    #[arg(long, value_name = "X,Y,Z", value_parser = parse_point, requires = "eye", allow_hyphen_values = true)]
    up: Option<glam::DVec3>,
    /// Vertical field of view in degrees (with --eye; default the scene camera's)
    #[arg(long, value_name = "DEG", requires = "eye")]
    fov: Option<f32>,
}

impl CameraOpts {
    fn view(&self) -> Option<scene::ViewSpec> {
        if let Some(c) = &self.camera {
            return Some(scene::ViewSpec::Camera(c.clone()));
        }
        Some(scene::ViewSpec::LookAt {
            eye: self.eye?,
            target: self.target?,
            up: self.up.map_or(glam::Vec3::Y, |u| u.as_vec3()),
            yfov_deg: self.fov,
        })
    }

    /// Places `scene`'s camera as asked (nothing asked: the file's first camera or the
    /// default).
    fn apply(&self, scene: &mut Scene) -> Result<()> {
        if let Some(v) = self.view() {
            scene.set_view(&v).map_err(|e| anyhow!(e))?;
        }
        Ok(())
    }
}

/// `X,Y,Z`: three finite numbers.
fn parse_point(s: &str) -> Result<glam::DVec3, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| "expected X,Y,Z".to_string())?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(glam::DVec3::new(*x, *y, *z)),
        _ => Err("expected three finite numbers X,Y,Z".into()),
    }
}

/// What `render` and `view` share: the scene, how it is rendered, lit, moved and shown.
#[derive(Args)]
struct ShowOpts {
    /// A glTF 2.0 file (.gltf or .glb); default: the bundled Cornell box
    scene: Option<PathBuf>,
    #[command(flatten)]
    render: RenderOpts,
    /// Display exposure (a .png's, the window's), in stops
    #[arg(long, value_name = "EV", default_value_t = 0.0)]
    exposure: f32,
    #[command(flatten)]
    sun: SunOpt,
    #[command(flatten)]
    env: EnvOpts,
    #[command(flatten)]
    spin: SpinOpts,
    #[command(flatten)]
    camera: CameraOpts,
}

impl ShowOpts {
    /// The render settings, then the scene (with `--sun`, warned about when nothing lights
    /// it) and what moves in it.
    fn load(&self) -> Result<(RenderSettings, Scene, scene::Motion)> {
        let path = self.scene.clone().unwrap_or_else(default_scene);
        let settings = self.render.settings()?;
        let mut scene = scene_with_sun(&path, &self.sun, &self.env)?;
        self.camera.apply(&mut scene)?;
        warn_if_unlit(&scene, &path);
        let motion = motion(&self.spin, &scene)?;
        Ok((settings, scene, motion))
    }
}

#[derive(Args)]
struct RenderCmd {
    #[command(flatten)]
    show: ShowOpts,
    /// .exr: linear radiance (RGB float); .png: display image
    #[arg(long, default_value = "voxgi.png")]
    out: PathBuf,
    /// Frames to render (timings are medians over them; default: --accumulate's, at least 5
    /// with --timings)
    #[arg(long, value_name = "N")]
    frames: Option<u32>,
    /// The moving scene (animations, --spin) as it is T seconds in
    #[arg(long, value_name = "T")]
    time: Option<f32>,
    #[command(flatten)]
    device: DeviceOpts,
}

#[derive(Args)]
struct ViewCmd {
    #[command(flatten)]
    show: ShowOpts,
    /// Present without waiting for the display (mailbox or immediate)
    #[arg(long)]
    no_vsync: bool,
    /// Render N frames, time advancing 1/60 s each, then exit
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..))]
    frames: Option<u32>,
    /// After the last frame, save the window's image (with --frames)
    #[arg(long, value_name = "FILE.png", requires = "frames")]
    screenshot: Option<PathBuf>,
    /// Ask for a new window size at frame FRAME (repeatable)
    #[arg(long, value_name = "FRAME:WxH", value_parser = resize)]
    resize: Vec<(u32, u32, u32)>,
    /// Press KEY at frame FRAME, release it at the next (repeatable; KEY as in the controls: a
    /// letter, a digit, [ ] - =, space, f12, optionally shift+KEY)
    #[arg(long, value_name = "FRAME:KEY", value_parser = press)]
    press: Vec<(u32, winit::keyboard::KeyCode, bool)>,
    #[command(flatten)]
    device: DeviceOpts,
}

fn resize(s: &str) -> Result<(u32, u32, u32), String> {
    voxgi::view::parse_resize(s).map_err(|e| e.to_string())
}

fn press(s: &str) -> Result<(u32, winit::keyboard::KeyCode, bool), String> {
    voxgi::view::parse_press(s).map_err(|e| e.to_string())
}

#[derive(Args)]
struct InfoCmd {
    /// A glTF 2.0 file (.gltf or .glb)
    scene: Vec<PathBuf>,
    #[command(flatten)]
    render: RenderOpts,
    #[command(flatten)]
    env: EnvOpts,
    #[command(flatten)]
    camera: CameraOpts,
    #[command(flatten)]
    device: DeviceOpts,
}

#[derive(Args)]
struct ReferenceCmd {
    /// A glTF 2.0 file (.gltf or .glb); default: the bundled Cornell box
    scene: Option<PathBuf>,
    /// Samples per pixel
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(1..=1 << 20))]
    spp: u32,
    /// .exr: linear radiance (RGB float); .png: display image
    #[arg(long, default_value = "reference.exr")]
    out: PathBuf,
    #[command(flatten)]
    size: SizeOpts,
    /// Seed of the random sequences
    #[arg(long, default_value_t = 0)]
    seed: u64,
    #[command(flatten)]
    sun: SunOpt,
    #[command(flatten)]
    env: EnvOpts,
    #[command(flatten)]
    camera: CameraOpts,
    /// Only the light a tracer with B bounces models (render's --bounces: B reflections of
    /// punctual lights' light besides the surface seen, B - 1 of emitters'), the best such a
    /// tracer can do
    #[arg(long, value_name = "B", value_parser = bounces_range())]
    bounces: Option<u32>,
    /// Camera paths alone, without the light paths joined to them (to measure what those
    /// buy: the noise of a lamp's bright spot on a nearby surface)
    #[arg(long)]
    no_light_paths: bool,
    /// Display exposure for .png, in stops
    #[arg(long, value_name = "EV", default_value_t = 0.0)]
    exposure: f32,
}

#[derive(Args)]
struct CompareCmd {
    /// A.exr REFERENCE.exr
    images: Vec<PathBuf>,
    /// Display exposure of both images for FLIP, in stops
    #[arg(long, value_name = "EV", default_value_t = 0.0)]
    exposure: f32,
}

#[derive(Args)]
struct SoakCmd {
    #[command(flatten)]
    show: ShowOpts,
    /// Frames to render
    #[arg(long, value_name = "N", default_value_t = 10_000, value_parser = clap::value_parser!(u32).range(1..))]
    frames: u32,
    /// Frames between two samples of memory
    #[arg(long, value_name = "N", default_value_t = 100, value_parser = clap::value_parser!(u32).range(1..))]
    sample_every: u32,
    /// Largest relative growth of host memory allowed over the run (after its first tenth)
    #[arg(long, value_name = "F", default_value_t = 0.01)]
    max_growth: f64,
    /// Also write the samples here (frame, host bytes, GPU bytes, timing entries)
    #[arg(long, value_name = "FILE.csv")]
    csv: Option<PathBuf>,
    #[command(flatten)]
    device: DeviceOpts,
}

#[derive(Args)]
struct SweepCmd {
    /// glTF 2.0 files (.gltf or .glb)
    #[arg(required = true)]
    scenes: Vec<PathBuf>,
    /// Frames per run
    #[arg(long, value_name = "N", default_value_t = 30, value_parser = clap::value_parser!(u32).range(1..))]
    frames: u32,
    /// Image side in pixels
    #[arg(long, value_name = "N", default_value_t = 32, value_parser = side_range())]
    size: u32,
    /// Voxels per side of the grid
    #[arg(long, value_name = "N", default_value_t = 32, value_parser = clap::value_parser!(u32).range(4..=1024))]
    voxels: u32,
    /// Also write the table here
    #[arg(long, value_name = "FILE.md")]
    out: Option<PathBuf>,
    /// Use the Vulkan device whose name contains NAME
    #[arg(long, value_name = "NAME")]
    device: Option<String>,
}

#[derive(Args)]
struct FuzzCmd {
    /// More seeds: glTF or GLB files (the files beside them are copied along)
    seeds: Vec<PathBuf>,
    /// Cases to run
    #[arg(long, default_value_t = 10_000)]
    cases: u64,
    /// Of the random sequence (the same seed gives the same cases)
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// A case that takes longer is a hang, in seconds
    #[arg(long, value_name = "SECS", default_value_t = 10.0)]
    time_limit: f64,
    /// Where the damaged files are written, and the findings kept (default: a directory in
    /// the system's temporary directory)
    #[arg(long, value_name = "DIR")]
    scratch: Option<PathBuf>,
}

#[derive(Args)]
struct HardCasesCmd {
    /// Cases to run (default: all)
    names: Vec<String>,
    /// Image side in pixels
    #[arg(long, default_value_t = 64, value_parser = side_range())]
    size: u32,
    /// Voxels per side of the grid
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u32).range(4..=1024))]
    voxels: u32,
    /// Samples per pixel of the references
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..))]
    ref_spp: u32,
    /// Light bounces of the default column
    #[arg(long, value_name = "B", value_parser = bounces_range())]
    bounces: Option<u32>,
    /// The default column without the bounces not traced
    #[arg(long)]
    no_tail: bool,
    /// Two more columns for the cases measured against the reference: the default image without
    /// the tail against the path tracer limited to the same bounces, and that path tracer's own
    /// score in place of the real-time image
    #[arg(long)]
    ideal: bool,
    /// Also write the table here
    #[arg(long, value_name = "FILE.md")]
    out: Option<PathBuf>,
    /// Use the Vulkan device whose name contains NAME
    #[arg(long, value_name = "NAME")]
    device: Option<String>,
}

#[derive(Args)]
struct BenchCmd {
    /// A glTF 2.0 file (.gltf or .glb)
    scene: Vec<PathBuf>,
    /// SPEC := PART ('|' PART)*, the union of the parts; PART := PRESET | AXIS (';' AXIS)*;
    /// AXIS := NAME=V1,V2,..: the cartesian product of the axes over the defaults. Presets:
    /// default (one axis at a time around the defaults), tiny (32^3: default and paper). Axes:
    /// voxels, bounces, paper, cones, aperture, bounce-cones, bounce-aperture, step,
    /// max-distance, start-offset, ao-falloff, voxel-shadows, cone-shadows, paper-slips,
    /// lod-offset, tail, area-lights, trace-scale, temporal, specular-min, empty-space, backs,
    /// bounce-share
    #[arg(long, default_value = "default")]
    sweep: String,
    /// Where the results go
    #[arg(long, value_name = "DIR", default_value = "bench")]
    out: PathBuf,
    /// Image width in pixels
    #[arg(long, default_value_t = 512)]
    width: u32,
    /// Image height in pixels
    #[arg(long, default_value_t = 512)]
    height: u32,
    /// Frames timed per setting
    #[arg(long, default_value_t = 10)]
    frames: u32,
    /// Frames rendered before the timed ones
    #[arg(long, default_value_t = 2)]
    warmup: u32,
    /// Samples per pixel of the reference (cached in DIR/cache by scene content, size and spp)
    #[arg(long, default_value_t = 256)]
    ref_spp: u32,
    /// The moving camera: swung about the scene's vertical axis by up to DEG degrees and back
    /// over 8 frames (timed), its last frame at the start again (its error measured)
    #[arg(long, value_name = "DEG", default_value_t = 10.0)]
    orbit: f32,
    #[command(flatten)]
    sun: SunOpt,
    #[command(flatten)]
    env: EnvOpts,
    #[command(flatten)]
    camera: CameraOpts,
    /// Display exposure of both images for FLIP, in stops
    #[arg(long, value_name = "EV", default_value_t = 0.0)]
    exposure: f32,
    /// Frames in the still image's antialiasing mean (1: off; see render --accumulate)
    #[arg(long, value_name = "N", default_value_t = 8,
          value_parser = clap::value_parser!(u32).range(1..=1024))]
    accumulate: u32,
    #[command(flatten)]
    device: DeviceOpts,
}

/// The Cornell box generated into assets/ (see voxgi::scene::builder).
fn default_scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.gltf")
}

/// A scene, its warnings logged (by scene::load, with the file's name).
fn load_scene(path: &Path) -> Result<Scene> {
    Ok(scene::load(path)?)
}

fn context(device: &DeviceOpts) -> Result<std::sync::Arc<Context>> {
    Ok(Context::new(&ContextDesc {
        validate: device.validate,
        device: device.device.clone(),
        memory_budget: device.budget_bytes(),
        lose_device_after: lose_device_after(),
        ..Default::default()
    })?)
}

/// VOXGI_TEST_LOSE_DEVICE_AFTER=N: the submission after N fails as on a lost device (tests
/// only: lavapipe cannot lose its device).
fn lose_device_after() -> Option<u32> {
    std::env::var("VOXGI_TEST_LOSE_DEVICE_AFTER")
        .ok()
        .and_then(|v| v.parse().ok())
}

/// Fails the run if validation reported anything (the messages were printed as they came).
fn check_validation(stats: &voxgi::vk::MessageStats, validating: bool) -> Result<()> {
    if validating && stats.count() > 0 {
        bail!("validation reported {} message(s)", stats.count());
    }
    Ok(())
}

/// `--sun EL,AZ[,E]`: a directional light shining from elevation EL, azimuth AZ.
fn parse_sun(spec: &str) -> Result<scene::Light, String> {
    let v: Vec<f32> = spec
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| "expected EL,AZ[,E] in degrees and W/m^2".to_string())?;
    let (el, az, e) = match v.as_slice() {
        [el, az] => (*el, *az, 3.0),
        [el, az, e] => (*el, *az, *e),
        _ => return Err("expected EL,AZ[,E]".into()),
    };
    if !(el.is_finite() && az.is_finite() && e.is_finite() && e >= 0.0) {
        return Err("values must be finite and E >= 0".into());
    }
    let (el, az) = (el.to_radians(), az.to_radians());
    let towards_sun = glam::Vec3::new(el.cos() * az.sin(), el.sin(), el.cos() * az.cos());
    Ok(scene::Light {
        name: Some("sun".into()),
        kind: scene::LightKind::Directional,
        radiance: glam::Vec3::splat(e),
        range: None,
        position: glam::Vec3::ZERO,
        direction: -towards_sun.normalize(),
    })
}

impl GiOpts {
    fn settings(&self) -> GiSettings {
        let mut gi = if self.paper {
            GiSettings::paper(self.voxels)
        } else {
            GiSettings {
                voxels: self.voxels,
                ..Default::default()
            }
        };
        gi.bounces = self.bounces.unwrap_or(gi.bounces);
        gi.cone_count = self.cones.unwrap_or(gi.cone_count);
        gi.cone_aperture_deg = self.aperture.unwrap_or(gi.cone_aperture_deg);
        gi.bounce_cone_count = self.bounce_cones.unwrap_or(gi.bounce_cone_count);
        gi.bounce_cone_aperture_deg = self.bounce_aperture.unwrap_or(gi.bounce_cone_aperture_deg);
        gi.step_factor = self.step.unwrap_or(gi.step_factor);
        gi.voxel_shadows = self.voxel_shadows;
        gi.cone_shadows = self.cone_shadows;
        gi.paper_slips = self.paper_slips;
        gi.tail &= !self.no_tail;
        gi.area_lights &= !self.no_area_lights;
        gi.trace_scale = self.trace_scale.unwrap_or(gi.trace_scale);
        gi.temporal = self.temporal.unwrap_or(gi.temporal);
        gi.specular_min_voxels = self.specular_min.unwrap_or(gi.specular_min_voxels);
        gi.empty_space &= !self.no_empty_space;
        gi.backs &= !self.no_backs;
        gi.bounce_share &= !self.no_bounce_share;
        gi
    }
}

impl RenderOpts {
    fn settings(&self) -> Result<RenderSettings> {
        if self.mip.is_some() && self.mode != Mode::VoxelsRadiance {
            bail!("--mip goes with --mode voxels-radiance");
        }
        Ok(RenderSettings {
            width: self.size.width,
            height: self.size.height,
            mode: self.mode,
            shadow_resolution: self.shadow_res,
            area_shadow_resolution: self.area_shadow_res,
            accumulate: self.accumulate,
            timings: self.timings,
            gi: self.gi.settings(),
            mip: self.mip,
            ..Default::default()
        })
    }
}

/// A scene with nothing to light it renders black: say so rather than leave a user guessing.
fn warn_if_unlit(scene: &Scene, path: &Path) {
    if scene.lights.is_empty()
        && scene.environment.is_none()
        && !scene.materials.iter().any(|m| m.is_emissive())
    {
        log::warn!(
            "{}: the scene has no lights and no emission; the image is black \
             (--sun EL,AZ adds a light)",
            path.display()
        );
    }
}

/// `--spin NODE` and its speed: what moves.
fn motion(spin: &SpinOpts, scene: &Scene) -> Result<scene::Motion> {
    let mut s = spin
        .spin
        .as_ref()
        .map(|name| scene.spin(name))
        .transpose()
        .map_err(anyhow::Error::msg)?;
    if let (Some(s), Some(speed)) = (s.as_mut(), spin.spin_speed) {
        if !speed.is_finite() || speed.abs() > 36000.0 {
            bail!("--spin-speed must be a number of degrees per second, at most 36000");
        }
        s.degrees_per_second = speed;
    }
    Ok(scene::Motion {
        spin: s,
        animate: true,
    })
}

/// The scene of a command, with `--sun` and `--env` added.
fn scene_with_sun(path: &Path, sun: &SunOpt, env: &EnvOpts) -> Result<Scene> {
    let environment = env.environment()?;
    let mut scene = load_scene(path)?;
    scene.lights.extend(sun.sun.clone());
    scene.environment = environment;
    Ok(scene)
}

/// `voxgi view`: the renderer in a window.
fn view(c: ViewCmd) -> Result<()> {
    if let Some(p) = &c.screenshot {
        let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("");
        if !ext.eq_ignore_ascii_case("png") {
            bail!("{}: screenshots are PNG files (.png)", p.display());
        }
    }
    let (settings, scene, motion) = c.show.load()?;
    let validating = c.device.validate;
    let report = voxgi::view::run(voxgi::view::ViewOptions {
        scene,
        settings,
        vsync: !c.no_vsync,
        frames: c.frames,
        screenshot: c.screenshot,
        resizes: c.resize,
        presses: c.press,
        spin: motion.spin,
        exposure: c.show.exposure,
        timings: c.show.render.timings,
        validate: validating,
        memory_budget: c.device.budget_bytes(),
        device: c.device.device,
    })?;
    if let Some(ms) = report.median_frame_ms {
        log::info!(
            "{} frames, median frame time {ms:.1} ms (submit to fence)",
            report.frames
        );
    }
    if !report.leaked.is_empty() {
        bail!(
            "GPU memory still allocated at exit: {}",
            report.leaked.join(", ")
        );
    }
    if validating && report.validation_messages > 0 {
        bail!(
            "validation reported {} message(s)",
            report.validation_messages
        );
    }
    Ok(())
}

fn render(c: RenderCmd) -> Result<()> {
    let out = c.out;
    let ext = out.extension().and_then(|e| e.to_str()).unwrap_or("");
    if !ext.eq_ignore_ascii_case("exr") && !ext.eq_ignore_ascii_case("png") {
        bail!(
            "{}: unsupported output format (use .exr for radiance or .png for display)",
            out.display()
        );
    }
    let (mut settings, mut scene, motion) = c.show.load()?;
    let (width, height, timings) = (settings.width, settings.height, settings.timings);
    // By default the image is the whole antialiasing mean.
    let frames = c
        .frames
        .unwrap_or(settings.accumulate.max(if timings { 5 } else { 1 }))
        .max(1);
    let time = c.time.unwrap_or(0.0);
    if !time.is_finite() || time < 0.0 {
        bail!("--time {time} must be a finite number of seconds, 0 or more");
    }

    settings.dynamic_nodes = motion.prepare(&mut scene);
    let ctx = context(&c.device)?;
    let stats = ctx.stats.clone();
    let validating = ctx.validating;
    log::info!("device: {}", ctx.device_info);
    let image = {
        let mut renderer = Renderer::new(&ctx, &scene, settings)?;
        for (node, world) in motion.pose(&scene, time) {
            renderer.set_node_transform(node, world);
        }
        let bar = if frames > 1 {
            voxgi::console::bar(frames as u64, "rendering, frames")
        } else {
            indicatif::ProgressBar::hidden()
        };
        for f in 0..frames {
            renderer.render(f + 1 == frames)?;
            bar.inc(1);
        }
        bar.finish_and_clear();
        if let Some(t) = &renderer.timer {
            print!("{}", t.report());
            let mut f = renderer.frame_ms.clone();
            f.sort_by(|a, b| a.total_cmp(b));
            println!(
                "  {:<16} {:9.3} ms  (submit to fence, median of {}; lavapipe's timestamps can \
                 miss compute work)",
                "frame wall",
                f[f.len() / 2],
                f.len()
            );
        } else if timings {
            log::warn!("the device has no timestamps; no timings");
        }
        RadianceImage {
            width,
            height,
            pixels: renderer.radiance(),
        }
    };
    drop(ctx);
    check_validation(&stats, validating)?;
    if image.has_non_finite() {
        bail!("the rendered image has NaN or Inf pixels; nothing written");
    }
    output::save(&image, &out, c.show.exposure)?;
    log::info!("wrote {}", out.display());
    Ok(())
}

/// `voxgi soak`: the run lives in voxgi::soak; this picks what moves and judges the report.
fn soak(c: SoakCmd) -> Result<()> {
    if !(c.max_growth.is_finite() && c.max_growth >= 0.0) {
        bail!(
            "--max-growth {} must be a finite fraction, 0 or more",
            c.max_growth
        );
    }
    let (settings, mut scene, motion) = c.show.load()?;
    // No --spin and no animation: the first node with a mesh.
    let motion = voxgi::soak::moving_something(&scene, motion).ok_or_else(|| {
        anyhow!(
            "{}: no node with a mesh that can be moved (give --spin NODE)",
            scene.source.display()
        )
    })?;
    let mut settings = settings;
    settings.dynamic_nodes = motion.prepare(&mut scene);
    if scene.lights.is_empty() {
        log::info!("the scene has no punctual light; only the node moves");
    }
    let ctx = context(&c.device)?;
    let stats = ctx.stats.clone();
    let validating = ctx.validating;
    log::info!("device: {}", ctx.device_info);
    let opts = voxgi::soak::SoakOptions {
        frames: c.frames,
        sample_every: c.sample_every,
        ..Default::default()
    };
    let report = {
        let mut renderer = Renderer::new(&ctx, &scene, settings)?;
        let report = voxgi::soak::run(&mut renderer, &scene, &motion, &opts, |s| {
            log::info!(
                "frame {:>6}  host {:>8.1} MiB  GPU {:>7.1} MiB  timing entries {}",
                s.frame,
                s.host_bytes as f64 / 1048576.0,
                s.gpu_bytes as f64 / 1048576.0,
                s.timing_entries
            );
        })?;
        if let Some(t) = &renderer.timer {
            print!("{}", t.report());
        }
        report
    };
    drop(ctx);
    if let Some(path) = &c.csv {
        let mut csv = String::from("frame,host_bytes,gpu_bytes,timing_entries\n");
        for s in &report.samples {
            csv.push_str(&format!(
                "{},{},{},{}\n",
                s.frame, s.host_bytes, s.gpu_bytes, s.timing_entries
            ));
        }
        output::write_bytes_atomic(path, csv.as_bytes())?;
    }
    println!(
        "{} frames in {:.0} s: host memory {:+.3}% (the median of the last fifth against the \
         first, after the run's first tenth; slope {:.2} bytes/frame), GPU memory change {} \
         bytes, timing entries at most {}, {} non-finite frame(s), {} validation message(s){}",
        c.frames,
        report.seconds,
        100.0 * report.host_growth(),
        report.host_slope(),
        report.gpu_change(),
        report.max_timing_entries(),
        report.non_finite_frames,
        stats.count(),
        if validating { "" } else { " (not validating)" }
    );
    check_validation(&stats, validating)?;
    // The renderer's lists hold at most twice TIMED_FRAMES frames each: the frame times and
    // one list per pass (a frame records fewer than 64 passes).
    let max_entries = 2 * voxgi::vk::timing::TIMED_FRAMES * 65;
    let problems = report.problems(c.max_growth, max_entries);
    if !problems.is_empty() {
        bail!("{}", problems.join("; "));
    }
    Ok(())
}

/// `voxgi validation-sweep`: scenes x modes x (default, --paper) under one validated context.
fn validation_sweep(c: SweepCmd) -> Result<()> {
    let ctx = Context::new(&ContextDesc {
        validate: true,
        device: c.device.clone(),
        ..Default::default()
    })?;
    log::info!("device: {}", ctx.device_info);
    let mut table = String::from(
        "| scene | mode | messages (default / --paper) | frames with NaN or Inf | NaN or Inf \
         voxels | seconds |\n|---|---|---|---|---|---|\n",
    );
    let mut failed = Vec::new();
    let start = std::time::Instant::now();
    let bar = voxgi::console::bar(
        (c.scenes.len() * Mode::ALL.len() * 2) as u64,
        "validation sweep, runs",
    );
    for path in &c.scenes {
        let mut scene = load_scene(path)?;
        if scene.lights.is_empty() {
            scene
                .lights
                .push(parse_sun("50,30,4").map_err(|e| anyhow!(e))?);
        }
        let name = path
            .file_stem()
            .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
        let Some(motion) = voxgi::soak::moving_something(&scene, scene::Motion::default()) else {
            bail!("{}: no node with a mesh that can be moved", path.display());
        };
        let dynamic = motion.prepare(&mut scene);
        for mode in Mode::ALL {
            let mut cells = Vec::new();
            for paper in [false, true] {
                let settings = RenderSettings {
                    width: c.size,
                    height: c.size,
                    mode,
                    shadow_resolution: 256,
                    area_shadow_resolution: 64,
                    dynamic_nodes: dynamic.clone(),
                    gi: if paper {
                        GiSettings::paper(c.voxels)
                    } else {
                        GiSettings {
                            voxels: c.voxels,
                            ..Default::default()
                        }
                    },
                    ..Default::default()
                };
                bar.inc(1);
                let run = voxgi::soak::sweep_run(&ctx, &scene, &motion, settings, c.frames)
                    .with_context(|| format!("{} in {mode:?} mode", path.display()))?;
                if run.messages + run.non_finite_frames as usize + run.non_finite_voxels > 0 {
                    failed.push(format!(
                        "{name} {mode:?}{}",
                        if paper { " --paper" } else { "" }
                    ));
                }
                cells.push(run);
            }
            let (d, p) = (&cells[0], &cells[1]);
            let row = format!(
                "| {name} | {} | {} / {} | {} / {} | {} / {} | {:.1} / {:.1} |\n",
                Mode::NAMES.split(", ").nth(mode as usize).unwrap_or("?"),
                d.messages,
                p.messages,
                d.non_finite_frames,
                p.non_finite_frames,
                d.non_finite_voxels,
                p.non_finite_voxels,
                d.seconds,
                p.seconds
            );
            eprint!("{row}");
            table.push_str(&row);
        }
    }
    drop(ctx);
    print!("{table}");
    println!(
        "{} scene(s) x {} modes x 2, {} frames each, {:.0} s",
        c.scenes.len(),
        Mode::ALL.len(),
        c.frames,
        start.elapsed().as_secs_f64()
    );
    if let Some(out) = &c.out {
        output::write_bytes_atomic(out, table.as_bytes())?;
    }
    if !failed.is_empty() {
        bail!("not clean: {}", failed.join(", "));
    }
    Ok(())
}

/// `voxgi completions SHELL`: the script, from the command line's own definitions.
fn completions(c: CompletionsCmd) -> Result<()> {
    use clap::CommandFactory;
    use clap_complete::Shell;
    let shell = match c.shell.as_str() {
        "bash" => Shell::Bash,
        "zsh" => Shell::Zsh,
        _ => Shell::Fish,
    };
    clap_complete::generate(shell, &mut Cli::command(), "voxgi", &mut std::io::stdout());
    Ok(())
}

fn info(c: InfoCmd) -> Result<()> {
    let scene_path = match c.scene.as_slice() {
        [s] => s.clone(),
        _ => bail!("info takes one scene (voxgi help info)"),
    };
    let environment = c.env.environment()?;
    let mut scene = load_scene(&scene_path)?;
    scene.environment = environment;
    c.camera.apply(&mut scene)?;
    print_scene(&scene);
    let ctx = match context(&c.device) {
        Ok(ctx) => ctx,
        Err(e) => {
            println!("device     none usable: {e}");
            return Ok(());
        }
    };
    println!("device     {}", ctx.device_info);
    print_render(&ctx, &scene, &c.render)
}

/// `info`'s account of the scene: its geometry, materials, environment, lights, animations,
/// bounds and cameras.
fn print_scene(scene: &Scene) {
    println!("scene      {}", scene.source.display());
    println!("triangles  {}", scene.triangle_count());
    println!(
        "instances  {} of {} primitives, {} vertices",
        scene.instances.len(),
        scene.primitives.len(),
        scene.vertices.len()
    );
    println!(
        "materials  {} ({} emissive), {} textures",
        scene.materials.len(),
        scene.materials.iter().filter(|m| m.is_emissive()).count(),
        scene.textures.len()
    );
    if let Some(e) = &scene.environment {
        println!("environment {}", e.describe());
    }
    println!("lights     {}", scene.lights.len());
    for l in &scene.lights {
        println!(
            "  {:?} {:?} radiance {:?} at {:?} towards {:?}",
            l.name.as_deref().unwrap_or("-"),
            l.kind,
            l.radiance.to_array(),
            l.position.to_array(),
            l.direction.to_array()
        );
    }
    if !scene.animations.is_empty() {
        println!("animations {}", scene.animations.len());
        for a in &scene.animations {
            println!(
                "  {:?}: {} channel(s), {:.2} s",
                a.name.as_deref().unwrap_or("-"),
                a.channels.len(),
                a.duration()
            );
        }
    }
    if scene.bounds.is_empty() {
        println!("bounds     empty");
    } else {
        println!(
            "bounds     {:?} to {:?}",
            scene.bounds.min.to_array(),
            scene.bounds.max.to_array()
        );
    }
    let cam = &scene.camera;
    println!(
        "camera     {} at {:?}, yfov {:.1} deg, near {} far {}",
        if cam.is_default {
            "default".to_string()
        } else {
            format!("{:?}", cam.name.as_deref().unwrap_or("unnamed"))
        },
        cam.eye().to_array(),
        cam.yfov.to_degrees(),
        cam.znear,
        cam.zfar
    );
    if !scene.cameras.is_empty() {
        let list: Vec<String> = scene
            .cameras
            .iter()
            .map(|c| {
                let name = c
                    .name
                    .as_deref()
                    .map_or(String::new(), |n| format!(" {n:?}"));
                let usable = if c.camera.is_ok() { "" } else { " (unusable)" };
                format!("{}{name}{usable}", c.index)
            })
            .collect();
        println!("cameras    {} (--camera NAME|INDEX)", list.join(", "));
    }
}

/// `info`'s account of a render with these options: its passes, grid, area lights and GPU
/// memory.
fn print_render(ctx: &std::sync::Arc<Context>, scene: &Scene, render: &RenderOpts) -> Result<()> {
    // What a render with these options would run and allocate.
    let settings = render.settings()?;
    let mode = settings.mode;
    let renderer = Renderer::new(ctx, scene, settings)?;
    println!(
        "passes     {} ({mode:?} mode)",
        renderer.passes().join(", ")
    );
    if let Some(gi) = &renderer.gi {
        let g = gi.volumes.grid;
        println!(
            "grid       {0}^3 voxels of {1:.4} m from {2:?}, {3}",
            g.resolution,
            g.voxel_size(),
            g.origin.to_array(),
            if gi.settings.paper {
                "paper"
            } else {
                "default"
            }
        );
    }
    for e in renderer.area_lights() {
        let inst = &scene.instances[e.instance];
        println!(
            "area light instance {} ({}) at {:?}: {} triangles as {}, {} edges per pixel, \
             {:.4} W{}",
            e.instance,
            inst.node_name.as_deref().unwrap_or("unnamed node"),
            e.position.to_array(),
            e.triangles,
            e.describe(),
            e.edges(),
            e.power().max_element(),
            if e.two_sided { ", two-sided" } else { "" },
        );
    }
    let mut report = ctx.allocator().generate_report().allocations;
    report.sort_by_key(|a| std::cmp::Reverse(a.size));
    let total: u64 = report.iter().map(|a| a.size).sum();
    println!(
        "GPU memory {:.1} MiB in {} allocations:",
        total as f64 / 1048576.0,
        report.len()
    );
    for a in report.iter().filter(|a| !a.name.starts_with("texture ")) {
        println!("  {:<44} {:>10.2} MiB", a.name, a.size as f64 / 1048576.0);
    }
    let textures: Vec<_> = report
        .iter()
        .filter(|a| a.name.starts_with("texture "))
        .collect();
    if !textures.is_empty() {
        let bytes: u64 = textures.iter().map(|a| a.size).sum();
        println!(
            "  {:<44} {:>10.2} MiB",
            format!("{} textures", textures.len()),
            bytes as f64 / 1048576.0
        );
    }
    drop(renderer);
    Ok(())
}

/// `voxgi reference`: the CPU path tracer (src/reference) on the same scene `render` builds.
fn reference(c: ReferenceCmd) -> Result<()> {
    let scene_path = c.scene.clone().unwrap_or_else(default_scene);
    let out = c.out;
    let ext = out.extension().and_then(|e| e.to_str()).unwrap_or("");
    if !ext.eq_ignore_ascii_case("exr") && !ext.eq_ignore_ascii_case("png") {
        bail!("{}: unsupported output format (use .exr)", out.display());
    }
    let settings = voxgi::reference::ReferenceSettings {
        width: c.size.width,
        height: c.size.height,
        spp: c.spp,
        seed: c.seed,
        bounces: c.bounces,
        progress: true,
        light_paths: !c.no_light_paths,
        ..Default::default()
    };
    let (w, h, spp) = (settings.width, settings.height, settings.spp);
    let mut scene = scene_with_sun(&scene_path, &c.sun, &c.env)?;
    c.camera.apply(&mut scene)?;
    if scene.lights.is_empty()
        && scene.environment.is_none()
        && !scene.materials.iter().any(|m| m.is_emissive())
    {
        log::warn!(
            "{}: no lights and no emission; the image is black",
            scene_path.display()
        );
    }
    let r = voxgi::reference::render_full(&scene, &settings);
    if r.bad_samples > 0 {
        log::warn!("{} NaN/Inf samples were dropped", r.bad_samples);
    }
    output::save(&r.image, &out, c.exposure)?;
    log::info!(
        "wrote {} ({w}x{h}, {spp} spp, {:.2} s)",
        out.display(),
        r.seconds
    );
    Ok(())
}

/// `voxgi compare A B`: B is the reference.
fn fuzz_loader(c: FuzzCmd) -> Result<()> {
    use voxgi::scene::fuzz::{self, FuzzSettings, Seed};
    let mut seeds = Seed::builtin();
    for p in &c.seeds {
        seeds.push(Seed::from_file(p).map_err(|e| anyhow::anyhow!(e))?);
    }
    let scratch = c
        .scratch
        .clone()
        .unwrap_or_else(|| std::env::temp_dir().join(format!("voxgi-fuzz-{}", std::process::id())));
    let settings = FuzzSettings {
        cases: c.cases,
        seed: c.seed,
        time_limit: std::time::Duration::from_secs_f64(c.time_limit.max(0.001)),
        scratch: scratch.clone(),
        threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    // The findings list the panics; their messages need not fill the terminal meanwhile.
    std::panic::set_hook(Box::new(|_| {}));
    let start = std::time::Instant::now();
    let report = fuzz::run(&seeds, &settings)
        .with_context(|| format!("{}: cannot write the cases", scratch.display()))?;
    let _ = std::panic::take_hook();
    println!(
        "{} cases in {:.0} s ({} seeds): {} loaded, {} rejected with a one-line error; {} \
         findings; slowest case {:.0} ms",
        report.cases,
        start.elapsed().as_secs_f64(),
        seeds.len(),
        report.loaded,
        report.rejected,
        report.findings.len(),
        report.slowest.as_secs_f64() * 1e3
    );
    for f in &report.findings {
        println!(
            "{:?}: case {} ({}: {}): {} [{}]",
            f.kind,
            f.case,
            f.seed,
            f.mutation,
            f.message.lines().next().unwrap_or(""),
            f.file.display()
        );
    }
    if report.findings.is_empty() {
        let _ = std::fs::remove_dir_all(&scratch);
        Ok(())
    } else {
        bail!(
            "{} findings (the damaged files are kept in {})",
            report.findings.len(),
            scratch.display()
        )
    }
}

fn compare(c: CompareCmd) -> Result<()> {
    let [pa, pb] = c.images.as_slice() else {
        bail!("compare takes two images, A.exr and REFERENCE.exr (voxgi help compare)");
    };
    let (a, b) = (output::load_exr(pa)?, output::load_exr(pb)?);
    let m = voxgi::metrics::try_compare(&a, &b, c.exposure)
        .with_context(|| format!("{} against {}", pa.display(), pb.display()))?;
    println!("{}", m.to_json());
    Ok(())
}

/// `voxgi bench`: the sweep, timing and error measurement live in voxgi::bench.
fn bench(c: BenchCmd) -> Result<()> {
    let [scene] = c.scene.as_slice() else {
        bail!("bench takes one scene (voxgi help bench)");
    };
    let opts = voxgi::bench::BenchOptions {
        scene: scene.clone(),
        sweep: c.sweep,
        out_dir: c.out,
        width: c.width,
        height: c.height,
        frames: c.frames,
        warmup: c.warmup,
        ref_spp: c.ref_spp,
        orbit_deg: c.orbit,
        extra_lights: c.sun.sun.into_iter().collect(),
        environment: c.env.environment()?,
        exposure: c.exposure,
        accumulate: c.accumulate,
        validate: c.device.validate,
        memory_budget: c.device.budget_bytes(),
        view: c.camera.view(),
        device: c.device.device,
        command_line: voxgi::bench::shell_words(
            &std::iter::once("voxgi".to_string())
                .chain(std::env::args().skip(1))
                .collect::<Vec<_>>(),
        ),
        ..Default::default()
    };
    voxgi::bench::run(&opts)?;
    Ok(())
}

/// `voxgi hard-cases`: every case (or those named) with --paper and with the defaults.
fn hard_cases(c: HardCasesCmd) -> Result<()> {
    use voxgi::hard::{self, Env, Row, CASES};
    for name in &c.names {
        if !CASES.iter().any(|k| k.name == name) {
            let names: Vec<&str> = CASES.iter().map(|k| k.name).collect();
            bail!("no hard case {name:?} (the cases: {})", names.join(", "));
        }
    }
    let default_bounces = GiSettings::default().bounces;
    let bounces = c.bounces.unwrap_or(default_bounces);
    let tail = !c.no_tail;
    let default_label = match (bounces == default_bounces, tail) {
        (true, true) => "default".to_string(),
        (false, true) => format!("default, {bounces} bounces"),
        (true, false) => "default, no tail".to_string(),
        (false, false) => format!("default, {bounces} bounces, no tail"),
    };
    let ctx = Context::new(&ContextDesc {
        validate: true,
        device: c.device.clone(),
        ..Default::default()
    })?;
    let mut env = Env::new(ctx, c.size, c.voxels, c.ref_spp)?;
    env.bounces = bounces;
    env.tail = tail;
    env.ideal = c.ideal;
    let mut rows = Vec::new();
    let chosen: Vec<_> = CASES
        .iter()
        .filter(|k| c.names.is_empty() || c.names.iter().any(|n| n == k.name))
        .collect();
    let bar = voxgi::console::bar(chosen.len() as u64, "hard cases");
    for case in chosen {
        bar.inc(1);
        let paper = env.run(case, &env.settings(true));
        let default = env.run(case, &env.settings(false));
        eprintln!(
            "{:24} paper {:>12.5}  default {:>12.5}  goal {}{}{}",
            case.name,
            paper.value,
            default.value,
            case.goal,
            if default.passed(case.goal) {
                ""
            } else {
                "  FAILS"
            },
            default.ideal.map_or(String::new(), |v| format!(
                "  (path tracer, same bounces: {v:.5}; the defaults against it: {:.5})",
                default.cones.unwrap_or(f64::NAN)
            ))
        );
        rows.push(Row {
            case,
            paper,
            default,
        });
    }
    let table = hard::table(&rows, &default_label, env.ideal);
    print!("{table}");
    if let Some(out) = &c.out {
        output::write_bytes_atomic(out, table.as_bytes())
            .with_context(|| format!("writing {}", out.display()))?;
    }
    let failed: Vec<&str> = rows
        .iter()
        .filter(|r| !r.default.passed(r.case.goal))
        .map(|r| r.case.name)
        .collect();
    if !failed.is_empty() {
        bail!("the defaults miss the goal of: {}", failed.join(", "));
    }
    Ok(())
}

/// A clap error as one line: its message and any suggestion ("a similar argument exists").
fn one_line(e: &clap::Error) -> String {
    let text = e.render().to_string();
    let mut parts = Vec::new();
    for line in text.lines().map(str::trim) {
        if line.starts_with("Usage:") || line.starts_with("For more information") {
            break;
        }
        if !line.is_empty() {
            parts.push(line.trim_start_matches("error: ").to_string());
        }
    }
    // "not provided:" runs on into what was not provided.
    parts.iter().fold(String::new(), |mut out, p| {
        if !out.is_empty() {
            out.push_str(if out.ends_with(':') { " " } else { "; " });
        }
        out.push_str(p);
        out
    })
}

/// Output piped into a program that stops reading (`voxgi render --help | head`) ends the
/// process quietly, as other command-line tools' does, instead of a panic in `println!`: Rust
/// ignores SIGPIPE, so the write fails with EPIPE, and the print macros panic on that.
#[cfg(unix)]
fn quiet_broken_pipe() {
    // SAFETY: restores the default action of one signal before any thread is started.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

#[cfg(not(unix))]
fn quiet_broken_pipe() {}

fn main() -> ExitCode {
    quiet_broken_pipe();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            return match e.kind() {
                ErrorKind::DisplayHelp
                | ErrorKind::DisplayVersion
                | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
                    print!("{}", e.render());
                    ExitCode::SUCCESS
                }
                _ => {
                    eprintln!("voxgi: error: {}", one_line(&e));
                    ExitCode::FAILURE
                }
            };
        }
    };
    voxgi::console::init_logging(if cli.quiet {
        -1
    } else {
        cli.verbose.min(2) as i8
    });
    let result = match cli.command {
        Command::Render(c) => render(c),
        Command::View(c) => view(c),
        Command::Info(c) => info(c),
        Command::Reference(c) => reference(c),
        Command::Compare(c) => compare(c),
        Command::FuzzLoader(c) => fuzz_loader(c),
        Command::Bench(c) => bench(c),
        Command::HardCases(c) => hard_cases(c),
        Command::Soak(c) => soak(c),
        Command::ValidationSweep(c) => validation_sweep(c),
        Command::Completions(c) => completions(c),
        Command::Corpus(c) => commands::corpus::corpus(c),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("voxgi: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// The number after "default " in `render`'s help for `--long`.
    fn help_default(long: &str) -> f32 {
        let cmd = Cli::command();
        let render = cmd.find_subcommand("render").expect("render subcommand");
        let arg = render
            .get_arguments()
            .find(|a| a.get_long() == Some(long))
            .unwrap_or_else(|| panic!("no --{long}"));
        let help = arg.get_help().expect("help text").to_string();
        let rest = help
            .split("default ")
            .skip(1)
            .find(|r| r.starts_with(|c: char| c.is_ascii_digit()))
            .unwrap_or_else(|| panic!("--{long}: no \"default N\" in {help:?}"));
        let number: String = rest
            .chars()
            .take_while(|c| c.is_ascii_digit() || *c == '.')
            .collect();
        number
            .parse()
            .unwrap_or_else(|_| panic!("--{long}: {number:?} in {help:?}"))
    }

    /// Options whose default lives in `GiSettings` name it in their help; the two must agree.
    #[test]
    fn help_states_the_settings_defaults() {
        let gi = GiSettings::default();
        let cases = [
            ("cones", gi.cone_count as f32),
            ("aperture", gi.cone_aperture_deg),
            ("bounce-cones", gi.bounce_cone_count as f32),
            ("bounce-aperture", gi.bounce_cone_aperture_deg),
            ("step", gi.step_factor),
            ("trace-scale", gi.trace_scale as f32),
            ("temporal", gi.temporal as f32),
            ("specular-min", gi.specular_min_voxels),
        ];
        for (long, default) in cases {
            assert_eq!(help_default(long), default, "--{long}'s help");
        }
    }
}
