//! voxgi: the command line.

use anyhow::{bail, Context as _, Result};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use voxgi::gi::GiSettings;
use voxgi::output::{self, RadianceImage};
use voxgi::render::{Mode, RenderSettings, Renderer};
use voxgi::scene::{self, Scene};
use voxgi::vk::{Context, ContextDesc};

const USAGE: &str = "\
voxgi: real-time global illumination by deferred voxel shading, on Vulkan

USAGE:
  voxgi render [SCENE] [--out FILE] [--width W] [--height H] [--mode MODE] [--mip L]
               [--voxels N] [--bounces N] [--paper] [--cones N] [--aperture DEG]
               [--step F] [--voxel-shadows] [--cone-shadows] [--no-tail]
               [--no-emitter-lights]
               [--frames N] [--exposure EV] [--shadow-res N] [--sun EL,AZ[,E]]
               [--spin NODE [--spin-speed DEG]] [--time T]
               [--validate] [--timings] [--device NAME]
  voxgi view [SCENE] [--width W] [--height H] [--mode MODE] [--voxels N] [--bounces N]
             [--paper] [--exposure EV] [--sun EL,AZ[,E]] [--spin NODE [--spin-speed DEG]]
             [--shadow-res N] [--no-vsync]
             [--frames N] [--screenshot FILE.png] [--resize FRAME:WxH].. [--press FRAME:KEY]..
             [--validate] [--timings] [--device NAME]
  voxgi info SCENE [render options]
  voxgi reference [SCENE] [--spp N] [--out FILE.exr] [--width W] [--height H] [--seed S]
                  [--sun EL,AZ[,E]] [--bounces N]
  voxgi compare A.exr REFERENCE.exr [--exposure EV]
  voxgi hard-cases [NAME..] [--size N] [--voxels N] [--ref-spp N] [--bounces N] [--no-tail]
                   [--ideal]
                   [--out FILE.md]
  voxgi bench SCENE [--sweep SPEC] [--out DIR] [--width W --height H] [--frames N]
              [--warmup N] [--ref-spp N] [--sun EL,AZ[,E]] [--exposure EV] [--validate]

  SCENE        a glTF 2.0 file (.gltf or .glb); render defaults to the bundled Cornell box
  --out FILE   .exr: linear radiance (RGB float); .png: display image (default voxgi.png)
  --width W, --height H   image size in pixels (default 512 x 512)
  --mode MODE  full (default): direct + cone-traced indirect light; direct: punctual lights
               with shadows, plus emission; indirect; ao; voxels-albedo, voxels-normal,
               voxels-emission, voxels-radiance: the first voxel along each ray
  --mip L      with voxels-radiance: the directional volumes at mip level L
  --voxels N   voxels per side of the grid (default 64)
  --bounces B  1: direct light in the voxels; 2 (default) to 8: plus B - 1 bounces between
               voxels (each one more bounce pass and mipmap, run when a light or node moves)
  --paper      the original's behaviour and constants (RGBA8 averages and volumes, 6 cones)
  --cones N, --aperture DEG, --step F   diffuse cones per pixel (16), their aperture (36),
               step as a fraction of the cone diameter (0.5)
  --voxel-shadows         voxel visibility by tracing the voxels (else the shadow maps)
  --cone-shadows          soft shadows: direct light shadowed by cones through the voxels
  --no-tail    the last bounce does not add the bounces after it (by default it adds them as
               a geometric series: the voxels' mean albedo times their closed share, at most
               0.6, is each further bounce's share of the one before)
  --no-emitter-lights     emitters smaller than a voxel stay voxel emission (by default up
               to four, the most powerful, light the scene as point lights with shadow maps)
  --frames N   frames to render (timings are medians over them; default 1, 5 with --timings)
  --exposure EV           display exposure for .png, in stops (default 0)
  --shadow-res N          shadow-map texels per side (default 2048)
  --sun EL,AZ[,E]         add a white directional light from elevation EL and azimuth AZ
                          (degrees; azimuth 0 is +Z, 90 is +X) with irradiance E W/m^2
                          (default 3): for scenes that bring no lights of their own
  --validate   Khronos validation with synchronization validation; any message fails the run
  --timings    print each pass's median GPU time
  --device NAME           use the Vulkan device whose name contains NAME
  --spin NODE  turn the node named NODE about its vertical axis (voxelized every frame, apart
               from the static geometry); glTF animations play
  --spin-speed DEG        degrees per second of --spin (default 90)
  --time T     render: the moving scene (animations, --spin) as it is T seconds in
  view         the renderer in a window with a free camera (keys: press H, or see the
               README); the title shows the settings and per-pass times
  --no-vsync   view: present without waiting for the display (mailbox or immediate)
  --frames N   view: render N frames, time advancing 1/60 s each, then exit
  --screenshot FILE.png   view: after the last frame, save the window's image
  --resize FRAME:WxH      view: ask for a new window size at frame FRAME (repeatable)
  --press FRAME:KEY       view: press KEY at frame FRAME, release it at the next (repeatable;
                          KEY as in the controls: a letter, a digit, [ ] - =, space, f12,
                          optionally shift+KEY), for scripted runs and tests
  reference    CPU path-traced ground truth (all cores; --spp default 64, --seed default 0);
               with --bounces B only the light a tracer with B bounces models (render's
               --bounces: B reflections of punctual lights' light besides the surface seen,
               B - 1 of emitters'), the best such a tracer can do
  hard-cases   runs the hard cases (light leaks, density, precision, degenerate input,
               extreme lights, cones at the edges; all of them or those named), each with
               --paper and the defaults at --voxels (default 64), --size (default 64)
               pixels and --bounces (default 2; --no-tail: without the bounces not traced),
               under validation; prints (and writes to --out) the markdown table of
               docs/hard-cases.md; fails when a default setting misses its goal; --ideal
               adds two columns, for the cases measured against the reference: the default
               image without the tail, its relMSE against the reference path tracer limited
               to the default column's bounces (reference --bounces), and that path
               tracer's own score in place of the real-time image
  compare      prints one JSON line: relMSE, MAE, RMSE (radiance) and FLIP (display images)
  bench        times each setting of a sweep (per-pass GPU medians and frame wall time over
               --frames, default 10, after --warmup, default 2) and measures its error
               against the reference (--ref-spp, default 256; cached in DIR/cache by scene
               content, size and spp); writes DIR (default bench/) results.csv, results.json,
               results.md and pareto.png. --sweep SPEC (default: default):
               SPEC := PART ('|' PART)*, the union of the parts; PART := PRESET | AXIS (';' AXIS)*
               AXIS := NAME=V1,V2,..: the cartesian product of the axes over the defaults
               presets: default (one axis at a time around the defaults: voxels 32..256 each
               also with the paper's settings, cones 1..16, aperture 30..90, step 0.25..1,
               bounces 1,2), tiny (32^3: default and paper). Axes: voxels, bounces, paper,
               cones, aperture, step, max-distance, start-offset, ao-falloff, voxel-shadows,
               cone-shadows, lod-offset, tail, emitter-lights.
               Example: --sweep 'voxels=32,64;cones=4,6;paper=0,1'
";

/// The Cornell box generated into assets/ (see voxgi::scene::builder).
fn default_scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.gltf")
}

struct Args {
    positional: Vec<String>,
    options: Vec<(String, Option<String>)>,
}

const FLAGS: &[&str] = &[
    "--validate",
    "--timings",
    "--help",
    "--paper",
    "--voxel-shadows",
    "--cone-shadows",
    "--no-tail",
    "--no-emitter-lights",
    "--no-vsync",
    "--ideal",
];
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
    "--mip",
    "--voxels",
    "--bounces",
    "--cones",
    "--aperture",
    "--step",
    "--spp",
    "--seed",
    "--sweep",
    "--warmup",
    "--ref-spp",
    "--size",
    "--spin",
    "--time",
    "--screenshot",
    "--resize",
    "--press",
    "--spin-speed",
];

impl Args {
    fn parse(args: &[String]) -> Result<Args> {
        let mut positional = Vec::new();
        let mut options = Vec::new();
        let mut it = args.iter();
        while let Some(a) = it.next() {
            if a == "-h" {
                options.push(("--help".to_string(), None));
            } else if FLAGS.contains(&a.as_str()) {
                options.push((a.clone(), None));
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
    /// Every value of a repeatable option, in order.
    fn values(&self, name: &str) -> Vec<&str> {
        self.options
            .iter()
            .filter(|(n, _)| n == name)
            .filter_map(|(_, v)| v.as_deref())
            .collect()
    }
    /// `--bounces B` if given, checked against the range every command allows.
    fn bounces(&self) -> Result<Option<u32>> {
        let Some(v) = self.value("--bounces") else {
            return Ok(None);
        };
        match v.parse::<u32>() {
            Ok(b) if (1..=voxgi::gi::MAX_BOUNCES).contains(&b) => Ok(Some(b)),
            _ => bail!(
                "--bounces must be 1 to {}, got {v:?}",
                voxgi::gi::MAX_BOUNCES
            ),
        }
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

/// Image, mode and voxel settings from the command line.
fn render_settings(args: &Args) -> Result<RenderSettings> {
    let width: u32 = args.number("--width", 512)?;
    let height: u32 = args.number("--height", 512)?;
    if width == 0 || height == 0 || width > 16384 || height > 16384 {
        bail!("image size {width}x{height} is out of range (1 to 16384)");
    }
    let mode: Mode = args
        .value("--mode")
        .unwrap_or("full")
        .parse()
        .map_err(anyhow::Error::msg)?;
    let shadow_resolution: u32 = args.number("--shadow-res", 2048)?;
    if !(16..=16384).contains(&shadow_resolution) {
        bail!("--shadow-res {shadow_resolution} is out of range (16 to 16384)");
    }
    let mip = args
        .value("--mip")
        .map(|_| args.number("--mip", 0u32))
        .transpose()?;
    if mip.is_some() && mode != Mode::VoxelsRadiance {
        bail!("--mip goes with --mode voxels-radiance");
    }
    Ok(RenderSettings {
        width,
        height,
        mode,
        shadow_resolution,
        timings: args.flag("--timings"),
        gi: gi_settings(args)?,
        mip,
        ..Default::default()
    })
}

/// The voxel passes' settings from the command line.
fn gi_settings(args: &Args) -> Result<GiSettings> {
    let voxels: u32 = args.number("--voxels", GiSettings::default().voxels)?;
    if !(4..=1024).contains(&voxels) {
        bail!("--voxels {voxels} is out of range (4 to 1024)");
    }
    let mut gi = if args.flag("--paper") {
        GiSettings::paper(voxels)
    } else {
        GiSettings {
            voxels,
            ..Default::default()
        }
    };
    gi.bounces = args.bounces()?.unwrap_or(gi.bounces);
    gi.cone_count = args.number("--cones", gi.cone_count)?;
    if !(1..=16).contains(&gi.cone_count) {
        bail!("--cones must be 1 to 16");
    }
    gi.cone_aperture_deg = args.number("--aperture", gi.cone_aperture_deg)?;
    if !(gi.cone_aperture_deg > 0.5 && gi.cone_aperture_deg < 179.0) {
        bail!("--aperture must be between 0.5 and 179 degrees");
    }
    gi.step_factor = args.number("--step", gi.step_factor)?;
    if !(gi.step_factor >= 0.05 && gi.step_factor <= 4.0) {
        bail!("--step must be between 0.05 and 4");
    }
    gi.voxel_shadows = args.flag("--voxel-shadows");
    gi.cone_shadows = args.flag("--cone-shadows");
    if args.flag("--no-tail") {
        gi.tail = false;
    }
    if args.flag("--no-emitter-lights") {
        gi.emitter_lights = false;
    }
    Ok(gi)
}

/// A scene with nothing to light it renders black: say so rather than leave a user guessing.
fn warn_if_unlit(scene: &Scene, path: &Path) {
    if scene.lights.is_empty() && !scene.materials.iter().any(|m| m.is_emissive()) {
        eprintln!(
            "warning: {}: the scene has no lights and no emission; the image is black \
             (--sun EL,AZ adds a light)",
            path.display()
        );
    }
}

/// `--spin NODE` and `--time T`: what moves and when the image is taken.
fn motion(args: &Args, scene: &Scene) -> Result<(scene::Motion, f32)> {
    let mut spin = args
        .value("--spin")
        .map(|name| scene.spin(name))
        .transpose()
        .map_err(anyhow::Error::msg)?;
    if let Some(s) = spin.as_mut() {
        s.degrees_per_second = args.number("--spin-speed", s.degrees_per_second)?;
        if !s.degrees_per_second.is_finite() || s.degrees_per_second.abs() > 36000.0 {
            bail!("--spin-speed must be a number of degrees per second, at most 36000");
        }
    } else if args.value("--spin-speed").is_some() {
        bail!("--spin-speed goes with --spin NODE");
    }
    let time: f32 = args.number("--time", 0.0)?;
    if !time.is_finite() || time < 0.0 {
        bail!("--time {time} must be a finite number of seconds, 0 or more");
    }
    Ok((
        scene::Motion {
            spin,
            animate: true,
        },
        time,
    ))
}

/// `voxgi view`: the renderer in a window.
fn view(args: &Args) -> Result<()> {
    let scene_path = match args.positional.as_slice() {
        [] => default_scene(),
        [s] => PathBuf::from(s),
        more => bail!("view takes one scene, got {}", more.len()),
    };
    let screenshot = args.value("--screenshot").map(PathBuf::from);
    if let Some(p) = &screenshot {
        let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("");
        if !ext.eq_ignore_ascii_case("png") {
            bail!("{}: screenshots are PNG files (.png)", p.display());
        }
    }
    let frames = args
        .value("--frames")
        .map(|_| args.number::<u32>("--frames", 1))
        .transpose()?;
    if frames == Some(0) {
        bail!("--frames must be 1 or more");
    }
    if screenshot.is_some() && frames.is_none() {
        bail!("--screenshot goes with --frames N (F12 saves screenshots while flying)");
    }
    let resizes = args
        .values("--resize")
        .into_iter()
        .map(voxgi::view::parse_resize)
        .collect::<Result<Vec<_>>>()?;
    let presses = args
        .values("--press")
        .into_iter()
        .map(voxgi::view::parse_press)
        .collect::<Result<Vec<_>>>()?;
    let settings = render_settings(args)?;
    let mut scene = load_scene(&scene_path)?;
    if let Some(spec) = args.value("--sun") {
        scene.lights.push(parse_sun(spec)?);
    }
    warn_if_unlit(&scene, &scene_path);
    let (motion, _) = motion(args, &scene)?;
    if args.value("--time").is_some() {
        bail!("--time goes with render (the window's scene time runs from 0)");
    }
    let validating = args.flag("--validate");
    let report = voxgi::view::run(voxgi::view::ViewOptions {
        scene,
        settings,
        vsync: !args.flag("--no-vsync"),
        frames,
        screenshot,
        resizes,
        presses,
        spin: motion.spin,
        exposure: args.number("--exposure", 0.0)?,
        timings: args.flag("--timings"),
        validate: validating,
        device: args.value("--device").map(String::from),
    })?;
    if let Some(ms) = report.median_frame_ms {
        eprintln!(
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
    let settings = render_settings(args)?;
    let (width, height, timings) = (settings.width, settings.height, settings.timings);
    let frames: u32 = args.number("--frames", if timings { 5 } else { 1 })?.max(1);
    let exposure: f32 = args.number("--exposure", 0.0)?;

    let mut scene = load_scene(&scene_path)?;
    if let Some(spec) = args.value("--sun") {
        scene.lights.push(parse_sun(spec)?);
    }
    warn_if_unlit(&scene, &scene_path);
    let (motion, time) = motion(args, &scene)?;
    let mut settings = settings;
    settings.dynamic_nodes = motion.prepare(&mut scene);
    let ctx = context(args)?;
    let stats = ctx.stats.clone();
    let validating = ctx.validating;
    eprintln!("device: {}", ctx.device_info);
    let image = {
        let mut renderer = Renderer::new(&ctx, &scene, settings)?;
        for (node, world) in motion.pose(&scene, time) {
            renderer.set_node_transform(node, world);
        }
        for f in 0..frames {
            renderer.render(f + 1 == frames)?;
        }
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
    let ctx = match context(args) {
        Ok(ctx) => ctx,
        Err(e) => {
            println!("device     none usable: {e}");
            return Ok(());
        }
    };
    println!("device     {}", ctx.device_info);
    // What a render with these options would run and allocate.
    let settings = render_settings(args)?;
    let mode = settings.mode;
    let renderer = Renderer::new(&ctx, &scene, settings)?;
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
    for e in renderer.emitter_lights() {
        let inst = &scene.instances[e.instance];
        println!(
            "emitter    instance {} ({}) as a light at {:?}: {:.4} W, smaller than a voxel",
            e.instance,
            inst.node_name.as_deref().unwrap_or("unnamed node"),
            e.position.to_array(),
            e.power().max_element(),
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
        bounces: args.bounces()?,
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

/// `voxgi bench`: the sweep, timing and error measurement live in voxgi::bench.
fn bench(args: &Args) -> Result<()> {
    let [scene] = args.positional.as_slice() else {
        bail!("bench takes one scene\n\n{USAGE}");
    };
    let d = voxgi::bench::BenchOptions::default();
    let opts = voxgi::bench::BenchOptions {
        scene: PathBuf::from(scene),
        sweep: args.value("--sweep").unwrap_or(&d.sweep).to_string(),
        out_dir: args.value("--out").map_or(d.out_dir.clone(), PathBuf::from),
        width: args.number("--width", d.width)?,
        height: args.number("--height", d.height)?,
        frames: args.number("--frames", d.frames)?,
        warmup: args.number("--warmup", d.warmup)?,
        ref_spp: args.number("--ref-spp", d.ref_spp)?,
        extra_lights: args
            .value("--sun")
            .map(parse_sun)
            .transpose()?
            .into_iter()
            .collect(),
        exposure: args.number("--exposure", d.exposure)?,
        validate: args.flag("--validate"),
        device: args.value("--device").map(String::from),
        command_line: voxgi::bench::shell_words(
            &std::iter::once("voxgi".to_string())
                .chain(std::env::args().skip(1))
                .collect::<Vec<_>>(),
        ),
        ..d
    };
    voxgi::bench::run(&opts)?;
    Ok(())
}

/// `voxgi hard-cases`: every case (or those named) with --paper and with the defaults.
fn hard_cases(args: &Args) -> Result<()> {
    use voxgi::hard::{self, Env, Row, CASES};
    for name in &args.positional {
        if !CASES.iter().any(|c| c.name == name) {
            let names: Vec<&str> = CASES.iter().map(|c| c.name).collect();
            bail!("no hard case {name:?} (the cases: {})", names.join(", "));
        }
    }
    let default_bounces = voxgi::gi::GiSettings::default().bounces;
    let bounces = args.bounces()?.unwrap_or(default_bounces);
    let tail = !args.flag("--no-tail");
    let default_label = match (bounces == default_bounces, tail) {
        (true, true) => "default".to_string(),
        (false, true) => format!("default, {bounces} bounces"),
        (true, false) => "default, no tail".to_string(),
        (false, false) => format!("default, {bounces} bounces, no tail"),
    };
    let ctx = Context::new(&ContextDesc {
        validate: true,
        device: args.value("--device").map(String::from),
        ..Default::default()
    })?;
    let mut env = Env::new(
        ctx,
        args.number("--size", 64)?,
        args.number("--voxels", 64)?,
        args.number("--ref-spp", 256)?,
    )?;
    env.bounces = bounces;
    env.tail = tail;
    env.ideal = args.flag("--ideal");
    let mut rows = Vec::new();
    for case in CASES
        .iter()
        .filter(|c| args.positional.is_empty() || args.positional.iter().any(|n| n == c.name))
    {
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
    if let Some(out) = args.value("--out") {
        output::write_bytes_atomic(Path::new(out), table.as_bytes())
            .with_context(|| format!("writing {out}"))?;
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
        "view" => view(&args),
        "info" => info(&args),
        "reference" => reference(&args),
        "compare" => compare(&args),
        "bench" => bench(&args),
        "hard-cases" => hard_cases(&args),
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
