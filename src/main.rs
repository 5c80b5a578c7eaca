//! voxgi: the command line.

use anyhow::{bail, Context as _, Result};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use voxgi::output::{self, RadianceImage};
use voxgi::render::{Mode, RenderSettings, Renderer};
use voxgi::scene::{self, Scene};
use voxgi::vk::{Context, ContextDesc};

const USAGE: &str = "\
voxgi: real-time global illumination by deferred voxel shading, on Vulkan

USAGE:
  voxgi render [SCENE] [--out FILE] [--width W] [--height H] [--mode MODE]
               [--frames N] [--exposure EV] [--shadow-res N]
               [--validate] [--timings] [--device NAME]
  voxgi info SCENE [--device NAME]
  voxgi reference [SCENE] [--spp N] [--out FILE.exr] [--width W] [--height H] [--seed S]
                  [--sun EL,AZ[,E]]
  voxgi compare A.exr REFERENCE.exr [--exposure EV]

  SCENE        a glTF 2.0 file (.gltf or .glb); render defaults to the bundled Cornell box
  --out FILE   .exr: linear radiance (RGB float); .png: display image (default voxgi.png)
  --width W, --height H   image size in pixels (default 512 x 512)
  --mode MODE  direct: punctual lights with shadows, plus emission
  --frames N   frames to render (timings are medians over them; default 1, 5 with --timings)
  --exposure EV           display exposure for .png, in stops (default 0)
  --shadow-res N          shadow-map texels per side (default 2048)
  --sun EL,AZ[,E]         add a white directional light from elevation EL and azimuth AZ
                          (degrees; azimuth 0 is +Z, 90 is +X) with irradiance E W/m^2
                          (default 3): for scenes that bring no lights of their own
  --validate   Khronos validation with synchronization validation; any message fails the run
  --timings    print each pass's median GPU time
  --device NAME           use the Vulkan device whose name contains NAME
  reference    CPU path-traced ground truth (all cores; --spp default 64, --seed default 0)
  compare      prints one JSON line: relMSE, MAE, RMSE (radiance) and FLIP (display images)
";

/// The Cornell box generated into assets/ (see voxgi::scene::builder).
fn default_scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.gltf")
}

struct Args {
    positional: Vec<String>,
    options: Vec<(String, Option<String>)>,
}

const FLAGS: &[&str] = &["--validate", "--timings", "--help"];
const VALUED: &[&str] = &[
    "--out",
    "--width",
    "--height",
    "--mode",
    "--frames",
    "--exposure",
    "--shadow-res",
    "--device",
    "--sun",
    "--spp",
    "--seed",
];

impl Args {
    fn parse(args: &[String]) -> Result<Args> {
        let mut positional = Vec::new();
        let mut options = Vec::new();
        let mut it = args.iter();
        while let Some(a) = it.next() {
            if FLAGS.contains(&a.as_str()) || a == "-h" {
                options.push((a.replace("-h", "--help"), None));
            } else if VALUED.contains(&a.as_str()) {
                let v = it.next().with_context(|| format!("{a} needs a value"))?;
                options.push((a.clone(), Some(v.clone())));
            } else if a.starts_with("--") {
                bail!("unknown option {a}\n\n{USAGE}");
            } else {
                positional.push(a.clone());
            }
        }
        Ok(Args {
            positional,
            options,
        })
    }
    fn flag(&self, name: &str) -> bool {
        self.options.iter().any(|(n, _)| n == name)
    }
    fn value(&self, name: &str) -> Option<&str> {
        self.options
            .iter()
            .rev()
            .find(|(n, _)| n == name)
            .and_then(|(_, v)| v.as_deref())
    }
    fn number<T: std::str::FromStr>(&self, name: &str, default: T) -> Result<T> {
        match self.value(name) {
            None => Ok(default),
            Some(v) => v
                .parse()
                .map_err(|_| anyhow::anyhow!("{name} {v:?} is not a valid number")),
        }
    }
}

fn load_scene(path: &Path) -> Result<Scene> {
    let scene = scene::load(path)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    Ok(scene)
}

fn context(args: &Args) -> Result<std::sync::Arc<Context>> {
    Ok(Context::new(&ContextDesc {
        validate: args.flag("--validate"),
        device: args.value("--device").map(String::from),
        ..Default::default()
    })?)
}

/// Fails the run if validation reported anything (the messages were printed as they came).
fn check_validation(stats: &voxgi::vk::MessageStats, validating: bool) -> Result<()> {
    if validating && stats.count() > 0 {
        bail!("validation reported {} message(s)", stats.count());
    }
    Ok(())
}

/// `--sun EL,AZ[,E]`: a directional light shining from elevation EL, azimuth AZ.
fn parse_sun(spec: &str) -> Result<scene::Light> {
    let v: Vec<f32> = spec
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| anyhow::anyhow!("--sun {spec:?}: expected EL,AZ[,E] in degrees and W/m^2"))?;
    let (el, az, e) = match v.as_slice() {
        [el, az] => (*el, *az, 3.0),
        [el, az, e] => (*el, *az, *e),
        _ => bail!("--sun {spec:?}: expected EL,AZ[,E]"),
    };
    if !(el.is_finite() && az.is_finite() && e.is_finite() && e >= 0.0) {
        bail!("--sun {spec:?}: values must be finite and E >= 0");
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

fn render(args: &Args) -> Result<()> {
    let scene_path = match args.positional.as_slice() {
        [] => default_scene(),
        [s] => PathBuf::from(s),
        more => bail!("render takes one scene, got {}", more.len()),
    };
    let out = PathBuf::from(args.value("--out").unwrap_or("voxgi.png"));
    let ext = out.extension().and_then(|e| e.to_str()).unwrap_or("");
    if !ext.eq_ignore_ascii_case("exr") && !ext.eq_ignore_ascii_case("png") {
        bail!(
            "{}: unsupported output format (use .exr for radiance or .png for display)",
            out.display()
        );
    }
    let width: u32 = args.number("--width", 512)?;
    let height: u32 = args.number("--height", 512)?;
    if width == 0 || height == 0 || width > 16384 || height > 16384 {
        bail!("image size {width}x{height} is out of range (1 to 16384)");
    }
    let mode: Mode = args
        .value("--mode")
        .unwrap_or("direct")
        .parse()
        .map_err(anyhow::Error::msg)?;
    let timings = args.flag("--timings");
    let frames: u32 = args.number("--frames", if timings { 5 } else { 1 })?.max(1);
    let exposure: f32 = args.number("--exposure", 0.0)?;
    let shadow_resolution: u32 = args.number("--shadow-res", 2048)?;
    if !(16..=16384).contains(&shadow_resolution) {
        bail!("--shadow-res {shadow_resolution} is out of range (16 to 16384)");
    }

    let mut scene = load_scene(&scene_path)?;
    if let Some(spec) = args.value("--sun") {
        scene.lights.push(parse_sun(spec)?);
    }
    if scene.lights.is_empty() && !scene.materials.iter().any(|m| m.is_emissive()) {
        eprintln!(
            "warning: {}: the scene has no lights and no emission; the image is black",
            scene_path.display()
        );
    }
    let ctx = context(args)?;
    let stats = ctx.stats.clone();
    let validating = ctx.validating;
    eprintln!("device: {}", ctx.device_info);
    let settings = RenderSettings {
        width,
        height,
        mode,
        shadow_resolution,
        timings,
        ..Default::default()
    };
    let image = {
        let mut renderer = Renderer::new(&ctx, &scene, settings)?;
        for f in 0..frames {
            renderer.render(f + 1 == frames)?;
        }
        if let Some(t) = &renderer.timer {
            print!("{}", t.report());
        } else if timings {
            eprintln!("warning: the device has no timestamps; no timings");
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
    output::save(&image, &out, exposure)?;
    eprintln!("wrote {}", out.display());
    Ok(())
}

fn info(args: &Args) -> Result<()> {
    let [scene_path] = args.positional.as_slice() else {
        bail!("info takes one scene\n\n{USAGE}");
    };
    let scene = load_scene(Path::new(scene_path))?;
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
    if scene.bounds.is_empty() {
        println!("bounds     empty");
    } else {
        println!(
            "bounds     {:?} to {:?}",
            scene.bounds.min.to_array(),
            scene.bounds.max.to_array()
        );
    }
    let c = &scene.camera;
    println!(
        "camera     {} at {:?}, yfov {:.1} deg, near {} far {}",
        if c.is_default {
            "default".to_string()
        } else {
            format!("{:?}", c.name.as_deref().unwrap_or("unnamed"))
        },
        c.eye().to_array(),
        c.yfov.to_degrees(),
        c.znear,
        c.zfar
    );
    match context(args) {
        Ok(ctx) => println!("device     {}", ctx.device_info),
        Err(e) => println!("device     none usable: {e}"),
    }
    Ok(())
}

/// `voxgi reference`: the CPU path tracer (src/reference) on the same scene `render` builds.
fn reference(args: &Args) -> Result<()> {
    let scene_path = match args.positional.as_slice() {
        [] => default_scene(),
        [s] => PathBuf::from(s),
        more => bail!("reference takes one scene, got {}", more.len()),
    };
    let out = PathBuf::from(args.value("--out").unwrap_or("reference.exr"));
    let ext = out.extension().and_then(|e| e.to_str()).unwrap_or("");
    if !ext.eq_ignore_ascii_case("exr") && !ext.eq_ignore_ascii_case("png") {
        bail!("{}: unsupported output format (use .exr)", out.display());
    }
    let settings = voxgi::reference::ReferenceSettings {
        width: args.number("--width", 512)?,
        height: args.number("--height", 512)?,
        spp: args.number("--spp", 64)?,
        seed: args.number("--seed", 0)?,
        progress: true,
        ..Default::default()
    };
    let (w, h, spp) = (settings.width, settings.height, settings.spp);
    let exposure: f32 = args.number("--exposure", 0.0)?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        bail!("image size {w}x{h} is out of range (1 to 16384)");
    }
    if !(1..=1 << 20).contains(&spp) {
        bail!("--spp {spp} is out of range (1 to 1048576)");
    }
    let mut scene = load_scene(&scene_path)?;
    if let Some(spec) = args.value("--sun") {
        scene.lights.push(parse_sun(spec)?);
    }
    if scene.lights.is_empty() && !scene.materials.iter().any(|m| m.is_emissive()) {
        eprintln!(
            "warning: {}: no lights and no emission; the image is black",
            scene_path.display()
        );
    }
    let r = voxgi::reference::render_full(&scene, &settings);
    if r.bad_samples > 0 {
        eprintln!("warning: {} NaN/Inf samples were dropped", r.bad_samples);
    }
    output::save(&r.image, &out, exposure)?;
    eprintln!(
        "wrote {} ({w}x{h}, {spp} spp, {:.2} s)",
        out.display(),
        r.seconds
    );
    Ok(())
}

/// `voxgi compare A B`: B is the reference.
fn compare(args: &Args) -> Result<()> {
    let [pa, pb] = args.positional.as_slice() else {
        bail!("compare takes two images, A.exr and REFERENCE.exr\n\n{USAGE}");
    };
    let (a, b) = (
        output::load_exr(Path::new(pa))?,
        output::load_exr(Path::new(pb))?,
    );
    let m = voxgi::metrics::try_compare(&a, &b, args.number("--exposure", 0.0)?)
        .with_context(|| format!("{pa} against {pb}"))?;
    println!("{}", m.to_json());
    Ok(())
}

fn run() -> Result<()> {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    let Some(cmd) = argv.first() else {
        print!("{USAGE}");
        return Ok(());
    };
    let args = Args::parse(&argv[1..])?;
    if args.flag("--help") {
        print!("{USAGE}");
        return Ok(());
    }
    match cmd.as_str() {
        "render" => render(&args),
        "info" => info(&args),
        "reference" => reference(&args),
        "compare" => compare(&args),
        "--help" | "-h" | "help" => {
            print!("{USAGE}");
            Ok(())
        }
        "--version" => {
            println!("voxgi {}", env!("CARGO_PKG_VERSION"));
            Ok(())
        }
        other => bail!("unknown command {other:?}\n\n{USAGE}"),
    }
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("voxgi: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
