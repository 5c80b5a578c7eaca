//! `voxgi view`: the renderer in a window (winit, ash-window), with a free camera, live
//! settings, moving scenes and the per-pass timings in the title bar.

mod camera;
mod present;
mod swapchain;

pub use camera::FlyCamera;
pub use present::{Display, Shot, Target};
pub use swapchain::{Acquired, Surface, Swapchain, SwapchainDesc};

use crate::render::{Mode, RenderSettings, Renderer};
use crate::scene::{Light, LightKind, Motion, Scene, Spin};
use crate::vk::{vk, Context, ContextDesc};
use anyhow::{anyhow, bail, Context as _, Result};
use glam::{Quat, Vec3};
use std::collections::HashSet;
use std::ffi::CStr;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::{Window, WindowId};

/// The keys and what they do (printed by H and listed in the README).
pub const CONTROLS: &[(&str, &str)] = &[
    ("W A S D", "fly forward, left, back, right"),
    ("E or Space / Q or C", "fly up / down"),
    ("Shift (held)", "fly four times faster"),
    ("mouse drag (any button)", "look around"),
    ("scroll wheel", "flying speed x1.25 per step up, /1.25 down"),
    ("R", "reset the camera to the scene's camera"),
    (
        "1 .. 8",
        "render mode: full, direct, indirect, ao, voxels-albedo, voxels-normal, \
         voxels-emission, voxels-radiance",
    ),
    ("M", "next render mode"),
    (
        "[ / ]",
        "voxels-radiance: one mip level down / up (the directional volumes)",
    ),
    ("G", "GI on / off (off: direct light only, no voxel work)"),
    ("B", "bounces: 1, 2, 3, 4"),
    (
        "V / Shift+V",
        "voxel resolution up / down (16, 32, 64, 128, 256 per side)",
    ),
    (
        "L / Shift+L (held)",
        "turn the main light about the scene's vertical axis",
    ),
    ("P", "pause / resume animations and the spin"),
    (
        "Y",
        "environment strength (--env): x1, x2, x4, off, x0.25, x0.5 of --env-strength",
    ),
    ("- / =", "exposure down / up one stop"),
    ("T", "print the per-pass timings"),
    (
        "K",
        "print the camera as the options that render it (--eye, --target, --up, --fov)",
    ),
    ("F12", "save a screenshot (voxgi-view-N.png)"),
    ("H", "print these controls"),
    ("Esc", "quit"),
];

const MODES: [Mode; 8] = Mode::ALL;
const LETTERS: [KeyCode; 26] = [
    KeyCode::KeyA,
    KeyCode::KeyB,
    KeyCode::KeyC,
    KeyCode::KeyD,
    KeyCode::KeyE,
    KeyCode::KeyF,
    KeyCode::KeyG,
    KeyCode::KeyH,
    KeyCode::KeyI,
    KeyCode::KeyJ,
    KeyCode::KeyK,
    KeyCode::KeyL,
    KeyCode::KeyM,
    KeyCode::KeyN,
    KeyCode::KeyO,
    KeyCode::KeyP,
    KeyCode::KeyQ,
    KeyCode::KeyR,
    KeyCode::KeyS,
    KeyCode::KeyT,
    KeyCode::KeyU,
    KeyCode::KeyV,
    KeyCode::KeyW,
    KeyCode::KeyX,
    KeyCode::KeyY,
    KeyCode::KeyZ,
];
/// What the Y key steps the environment's strength through, times --env-strength.
const ENV_FACTORS: [f32; 6] = [1.0, 2.0, 4.0, 0.0, 0.25, 0.5];

const DIGITS: [KeyCode; 10] = [
    KeyCode::Digit0,
    KeyCode::Digit1,
    KeyCode::Digit2,
    KeyCode::Digit3,
    KeyCode::Digit4,
    KeyCode::Digit5,
    KeyCode::Digit6,
    KeyCode::Digit7,
    KeyCode::Digit8,
    KeyCode::Digit9,
];
const VOXEL_STEPS: [u32; 5] = [16, 32, 64, 128, 256];
/// Frames per second of scene time with `--frames` (a fixed step, so runs repeat exactly).
pub const FRAMES_PER_SECOND: f32 = 60.0;
pub const FIXED_DT: f32 = 1.0 / FRAMES_PER_SECOND;
/// How fast L turns the main light.
const LIGHT_DEGREES_PER_SECOND: f32 = 45.0;

pub fn mode_name(m: Mode) -> &'static str {
    match m {
        Mode::Full => "full",
        Mode::Direct => "direct",
        Mode::Indirect => "indirect",
        Mode::Ao => "ao",
        Mode::VoxelsAlbedo => "voxels-albedo",
        Mode::VoxelsNormal => "voxels-normal",
        Mode::VoxelsEmission => "voxels-emission",
        Mode::VoxelsRadiance => "voxels-radiance",
    }
}

/// What `voxgi view` was asked for.
pub struct ViewOptions {
    /// The scene (lights added on the command line included).
    pub scene: Scene,
    /// Starting settings; width and height are the window's starting size.
    pub settings: RenderSettings,
    pub vsync: bool,
    /// Render this many frames (time advancing by [`FIXED_DT`] each), then exit.
    pub frames: Option<u32>,
    /// After the last frame, save the window's image here (PNG).
    pub screenshot: Option<PathBuf>,
    /// (frame, width, height): ask for a new window size at that frame (for tests).
    pub resizes: Vec<(u32, u32, u32)>,
    /// (frame, key, shift): press a key at that frame and release it at the next (scripted
    /// runs and tests).
    pub presses: Vec<(u32, KeyCode, bool)>,
    pub spin: Option<Spin>,
    pub exposure: f32,
    /// Print the per-pass timings at the end.
    pub timings: bool,
    pub validate: bool,
    pub device: Option<String>,
    /// `--memory-budget`, bytes.
    pub memory_budget: Option<u64>,
}

/// What a run did, for the command line to report.
pub struct ViewReport {
    pub frames: u32,
    /// Median frame time over the last renderer's frames (submit to fence), ms.
    pub median_frame_ms: Option<f64>,
    pub validation_messages: usize,
    pub leaked: Vec<String>,
}

/// The GPU objects of the current settings and window size, dropped together (display
/// first, it reads the renderer's image).
struct Live {
    display: Display,
    renderer: Renderer,
}

/// The window and what presents to it, dropped in reverse order of creation.
struct Windowed {
    live: Option<Live>,
    swapchain: Option<Swapchain>,
    surface: Surface,
    window: Window,
}

struct App {
    ctx: Arc<Context>,
    opts: ViewOptions,
    win: Option<Windowed>,
    camera: FlyCamera,
    motion: Motion,
    dynamic_nodes: Vec<usize>,
    // Live settings.
    mode: Mode,
    gi_on: bool,
    bounces: u32,
    voxels: u32,
    mip: Option<u32>,
    exposure: f32,
    /// Times --env-strength (the Y key).
    env_factor: f32,
    paused: bool,
    /// Settings changed: rebuild the renderer before the next frame.
    rebuild: bool,
    /// The swapchain no longer matches the window.
    recreate: bool,
    // Time.
    time: f32,
    /// Frames the clock advanced (not paused).
    steps: u32,
    light_angle: f32,
    last_instant: Instant,
    frame: u32,
    // Input.
    held: HashSet<KeyCode>,
    shift: bool,
    dragging: u32,
    cursor: Option<(f64, f64)>,
    screenshot_next: Option<PathBuf>,
    screenshots_taken: u32,
    /// Keys pressed by `--press`, released at the next frame.
    scripted_held: Vec<(KeyCode, bool)>,
    /// The frame whose scripted keys were pressed (a frame can be tried again when the
    /// window is not ready).
    pressed_at: Option<u32>,
    title_at: Instant,
    /// The window's title as last set.
    title: String,
    error: Option<anyhow::Error>,
}

/// Runs the window until it is closed (or `--frames` are done).
pub fn run(opts: ViewOptions) -> Result<ViewReport> {
    let event_loop = EventLoop::new().map_err(|e| {
        anyhow!(
            "cannot open a window: {e} (is DISPLAY or WAYLAND_DISPLAY set? Without a screen, \
             run under xvfb-run)"
        )
    })?;
    let display = event_loop
        .display_handle()
        .context("the window system's display handle")?
        .as_raw();
    let instance_extensions = ash_window::enumerate_required_extensions(display)
        .context("the window system's Vulkan surface extensions")?
        .iter()
        .map(|&p| unsafe { CStr::from_ptr(p) }.to_owned())
        .collect();
    let ctx = Context::new(&ContextDesc {
        validate: opts.validate,
        device: opts.device.clone(),
        instance_extensions,
        device_extensions: vec![ash::khr::swapchain::NAME.to_owned()],
        memory_budget: opts.memory_budget,
        ..Default::default()
    })?;
    log::info!("device: {}", ctx.device_info);
    let stats = ctx.stats.clone();

    let mut opts = opts;
    let motion = Motion {
        spin: opts.spin.clone(),
        animate: true,
    };
    let dynamic_nodes = motion.prepare(&mut opts.scene);
    let camera = FlyCamera::new(&opts.scene.camera, &opts.scene.bounds);
    let s = &opts.settings;
    let mut app = App {
        ctx: ctx.clone(),
        camera,
        motion,
        dynamic_nodes,
        mode: s.mode,
        gi_on: true,
        bounces: s.gi.bounces,
        voxels: s.gi.voxels,
        mip: s.mip,
        exposure: opts.exposure,
        env_factor: 1.0,
        paused: false,
        rebuild: true,
        recreate: true,
        time: 0.0,
        steps: 0,
        light_angle: 0.0,
        last_instant: Instant::now(),
        frame: 0,
        held: HashSet::new(),
        shift: false,
        dragging: 0,
        cursor: None,
        screenshot_next: None,
        screenshots_taken: 0,
        scripted_held: Vec::new(),
        pressed_at: None,
        title_at: Instant::now(),
        title: String::new(),
        error: None,
        win: None,
        opts,
    };
    if app.opts.frames.is_none() {
        print_controls();
    }
    event_loop
        .run_app(&mut app)
        .map_err(|e| anyhow!("the window's event loop failed: {e}"))?;

    let median_frame_ms = app
        .win
        .as_ref()
        .and_then(|w| w.live.as_ref())
        .and_then(|l| {
            let mut f = l.renderer.frame_ms.clone();
            f.sort_by(|a, b| a.total_cmp(b));
            f.get(f.len() / 2).copied()
        });
    if app.opts.timings {
        if let Some(live) = app.win.as_ref().and_then(|w| w.live.as_ref()) {
            print_timings(&live.renderer);
        }
    }
    if app.opts.frames.is_some() {
        // What the title bar said last (scripted runs have no one to read it).
        println!("title: {}", app.title);
    }
    let frames = app.frame;
    let error = app.error.take();
    // Everything on the GPU goes before the leak report.
    drop(app.win.take());
    let leaked = ctx.live_allocations();
    drop(app);
    drop(ctx);
    if let Some(e) = error {
        return Err(e);
    }
    Ok(ViewReport {
        frames,
        median_frame_ms,
        validation_messages: stats.count(),
        leaked,
    })
}

fn print_controls() {
    println!("controls:");
    for (keys, what) in CONTROLS {
        println!("  {keys:<24} {what}");
    }
}

/// The fly camera as `--eye X,Y,Z --target X,Y,Z --up X,Y,Z --fov DEG` in the file's
/// coordinates, for `voxgi render` and the others to view the scene as the window does (the up
/// direction keeps a file camera's roll until the camera moves).
pub fn camera_options(camera: &FlyCamera, scene: &Scene) -> String {
    let c = camera.camera();
    let eye = c.world.w_axis.truncate().as_dvec3() + scene.origin;
    let forward = (-c.world.z_axis.truncate()).normalize().as_dvec3();
    let up = c.world.y_axis.truncate().normalize().as_dvec3();
    // Micrometres and micro-radians: what f32 world positions near the origin hold.
    let num = |x: f64| {
        let s = format!("{x:.6}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        if s == "-0" {
            "0".to_string()
        } else {
            s.to_string()
        }
    };
    let p = |v: glam::DVec3| format!("{},{},{}", num(v.x), num(v.y), num(v.z));
    format!(
        "--eye {} --target {} --up {} --fov {}",
        p(eye),
        p(eye + forward),
        p(up),
        num(c.yfov.to_degrees() as f64)
    )
}

fn print_timings(r: &Renderer) {
    match &r.timer {
        Some(t) => print!("{}", t.report()),
        None => println!("the device has no timestamps; no per-pass timings"),
    }
    let mut f = r.frame_ms.clone();
    if !f.is_empty() {
        f.sort_by(|a, b| a.total_cmp(b));
        println!(
            "  {:<16} {:9.3} ms  (submit to fence, median of {})",
            "frame wall",
            f[f.len() / 2],
            f.len()
        );
    }
}

/// The main light (the first directional one, else the first) turned by `degrees` about the
/// vertical axis through the scene's centre.
fn turned_lights(scene: &Scene, degrees: f32) -> Vec<Light> {
    let main = scene
        .lights
        .iter()
        .position(|l| l.kind == LightKind::Directional)
        .unwrap_or(0);
    let q = Quat::from_rotation_y(degrees.to_radians());
    let centre = if scene.bounds.is_empty() {
        Vec3::ZERO
    } else {
        scene.bounds.center()
    };
    let mut lights = scene.lights.clone();
    if let Some(l) = lights.get_mut(main) {
        l.direction = q * l.direction;
        l.position = centre + q * (l.position - centre);
    }
    lights
}

impl App {
    fn settings(&self, width: u32, height: u32) -> RenderSettings {
        let mut s = self.opts.settings.clone();
        s.width = width;
        s.height = height;
        s.mode = if self.gi_on { self.mode } else { Mode::Direct };
        s.mip = if s.mode == Mode::VoxelsRadiance {
            self.mip
        } else {
            None
        };
        s.gi.voxels = self.voxels;
        s.gi.bounces = self.bounces;
        s.dynamic_nodes = self.dynamic_nodes.clone();
        // The title shows the passes' times.
        s.timings = true;
        s
    }

    /// The live renderer's environment at --env-strength times the Y key's factor.
    fn apply_env_factor(&mut self) {
        if let Some(mut win) = self.win.take() {
            self.apply_env_factor_to(&mut win);
            self.win = Some(win);
        }
    }

    fn apply_env_factor_to(&self, win: &mut Windowed) {
        let base = self.opts.scene.environment.as_ref().map(|e| e.strength);
        if let (Some(live), Some(base)) = (win.live.as_mut(), base) {
            live.renderer
                .set_environment_strength(base * self.env_factor);
        }
    }

    fn describe(&self) -> String {
        let mode = if self.gi_on {
            mode_name(self.mode).to_string()
        } else {
            "direct (GI off)".to_string()
        };
        let mip = match (self.mode, self.mip) {
            (Mode::VoxelsRadiance, Some(m)) if self.gi_on => format!(" mip {m}"),
            _ => String::new(),
        };
        let sky = match self.opts.scene.environment {
            Some(_) => format!(" | sky x{}", self.env_factor),
            None => String::new(),
        };
        format!(
            "{mode}{mip} | {} bounce{} | {}^3 | EV {:+}{sky}",
            self.bounces,
            if self.bounces == 1 { "" } else { "s" },
            self.voxels,
            self.exposure
        )
    }

    fn update_title(&mut self) {
        let Some(win) = &self.win else { return };
        let scene = self
            .opts
            .scene
            .source
            .file_stem()
            .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
        let mut title = format!("voxgi | {scene} | {}", self.describe());
        if let Some(live) = &win.live {
            if let Some(ms) = live.renderer.frame_ms.last() {
                title.push_str(&format!(" | {ms:.1} ms"));
            }
            if let Some(t) = &live.renderer.timer {
                let passes: Vec<String> = t
                    .samples
                    .iter()
                    .filter_map(|(n, v)| v.last().map(|ms| format!("{n} {ms:.2}")))
                    .collect();
                if !passes.is_empty() {
                    title.push_str(&format!(" | {}", passes.join(", ")));
                }
            }
        }
        win.window.set_title(&title);
        self.title = title;
    }

    fn key(&mut self, code: KeyCode, pressed: bool, repeat: bool, el: &ActiveEventLoop) {
        if !pressed {
            self.held.remove(&code);
            return;
        }
        self.held.insert(code);
        if repeat {
            return;
        }
        let mut changed = true;
        match code {
            KeyCode::Escape => {
                el.exit();
                changed = false;
            }
            KeyCode::KeyR => {
                self.camera.reset();
                changed = false;
            }
            _ if DIGITS[1..=MODES.len()].contains(&code) => {
                let i = DIGITS[1..].iter().position(|&k| k == code).unwrap_or(0);
                self.mode = MODES[i];
                self.gi_on = true;
                self.rebuild = true;
            }
            KeyCode::KeyM => {
                let i = MODES.iter().position(|&m| m == self.mode).unwrap_or(0);
                self.mode = MODES[(i + 1) % MODES.len()];
                self.gi_on = true;
                self.rebuild = true;
            }
            KeyCode::BracketLeft | KeyCode::BracketRight if self.mode == Mode::VoxelsRadiance => {
                let levels = self.voxels.ilog2() + 1;
                self.mip = match (code, self.mip) {
                    (KeyCode::BracketRight, None) => Some(0),
                    (KeyCode::BracketRight, Some(m)) => Some((m + 1).min(levels - 1)),
                    (_, Some(0)) | (_, None) => None,
                    (_, Some(m)) => Some(m - 1),
                };
                self.rebuild = true;
            }
            KeyCode::KeyG => {
                self.gi_on = !self.gi_on;
                self.rebuild = true;
            }
            KeyCode::KeyB => {
                self.bounces = self.bounces % 4 + 1;
                self.rebuild = true;
            }
            KeyCode::KeyV => {
                let i = VOXEL_STEPS
                    .iter()
                    .position(|&v| v >= self.voxels)
                    .unwrap_or(VOXEL_STEPS.len() - 1);
                let j = if self.shift {
                    i.saturating_sub(1)
                } else {
                    (i + 1).min(VOXEL_STEPS.len() - 1)
                };
                self.voxels = VOXEL_STEPS[j];
                self.mip = None;
                self.rebuild = true;
            }
            KeyCode::KeyP => self.paused = !self.paused,
            KeyCode::KeyY => {
                if self.opts.scene.environment.is_some() {
                    let i = ENV_FACTORS.iter().position(|&f| f == self.env_factor);
                    self.env_factor = ENV_FACTORS[i.map_or(0, |i| (i + 1) % ENV_FACTORS.len())];
                    self.apply_env_factor();
                } else {
                    println!("no environment (--env R,G,B or --env FILE.hdr)");
                    changed = false;
                }
            }
            KeyCode::Minus => self.exposure -= 1.0,
            KeyCode::Equal => self.exposure += 1.0,
            KeyCode::KeyT => {
                if let Some(live) = self.win.as_ref().and_then(|w| w.live.as_ref()) {
                    print_timings(&live.renderer);
                }
                changed = false;
            }
            KeyCode::KeyK => {
                println!("{}", camera_options(&self.camera, &self.opts.scene));
                changed = false;
            }
            KeyCode::F12 => {
                self.screenshots_taken += 1;
                self.screenshot_next = Some(PathBuf::from(format!(
                    "voxgi-view-{}.png",
                    self.screenshots_taken
                )));
                changed = false;
            }
            KeyCode::KeyH => {
                print_controls();
                changed = false;
            }
            _ => changed = false,
        }
        if changed {
            println!("{}", self.describe());
            self.update_title();
        }
    }

    /// Makes sure the swapchain fits the window and the renderer fits both; false while the
    /// window has no area.
    fn ready(&mut self) -> Result<bool> {
        let Some(mut win) = self.win.take() else {
            return Ok(false);
        };
        let ready = self.ready_window(&mut win);
        self.win = Some(win);
        ready
    }

    fn ready_window(&mut self, win: &mut Windowed) -> Result<bool> {
        let size = win.window.inner_size();
        if size.width == 0 || size.height == 0 {
            return Ok(false);
        }
        let fits = win
            .swapchain
            .as_ref()
            .is_some_and(|s| s.extent.width == size.width && s.extent.height == size.height);
        if self.recreate || !fits {
            // The old swapchain goes first (it waits for its presents).
            win.live = None;
            win.swapchain = None;
            win.swapchain = Swapchain::new(
                &self.ctx,
                &win.surface,
                SwapchainDesc {
                    width: size.width,
                    height: size.height,
                    vsync: self.opts.vsync,
                },
            )?;
            self.recreate = false;
        }
        let Some(chain) = &win.swapchain else {
            return Ok(false);
        };
        let (w, h) = (chain.extent.width, chain.extent.height);
        let live_fits = win
            .live
            .as_ref()
            .is_some_and(|l| l.renderer.settings.width == w && l.renderer.settings.height == h);
        if !self.rebuild && !live_fits {
            if let Some(live) = win.live.as_mut() {
                // Same settings, new size: the renderer keeps its voxels and shadow maps.
                live.renderer.resize(w, h)?;
                live.display = Display::new(&self.ctx, live.renderer.radiance_image())?;
                return Ok(true);
            }
        }
        if self.rebuild || win.live.is_none() {
            win.live = None;
            let settings = self.settings(w, h);
            let renderer = match Renderer::new(&self.ctx, &self.opts.scene, settings) {
                Ok(r) => r,
                Err(e @ crate::vk::VkError::GridTooLarge { .. }) if self.voxels > 16 => {
                    log::warn!("{e}");
                    self.voxels /= 2;
                    return Ok(false);
                }
                Err(e) => return Err(e.into()),
            };
            let display = Display::new(&self.ctx, renderer.radiance_image())?;
            win.live = Some(Live { display, renderer });
            self.rebuild = false;
            self.apply_env_factor_to(win);
        }
        Ok(true)
    }

    fn frame(&mut self, el: &ActiveEventLoop) -> Result<()> {
        if let Some(&(_, w, h)) = self.opts.resizes.iter().find(|r| r.0 == self.frame) {
            if let Some(win) = &self.win {
                let _ = win.window.request_inner_size(PhysicalSize::new(w, h));
            }
        }
        self.scripted_keys(el);
        if !self.ready()? {
            return Ok(());
        }
        // Time: fixed steps with --frames (runs repeat exactly), else the wall clock.
        let now = Instant::now();
        let dt = match self.opts.frames {
            Some(_) => FIXED_DT,
            None => (now - self.last_instant).as_secs_f32().min(0.1),
        };
        self.last_instant = now;
        if !self.paused {
            self.steps += 1;
            // Counted in whole steps with --frames, so that frame N is at exactly N/60 s, as
            // `voxgi render --time` poses it.
            self.time = match self.opts.frames {
                Some(_) => self.steps as f32 / FRAMES_PER_SECOND,
                None => self.time + dt,
            };
        }
        self.fly(dt);
        let turn = match (self.held.contains(&KeyCode::KeyL), self.shift) {
            (false, _) => 0.0,
            (true, false) => 1.0,
            (true, true) => -1.0,
        };
        let last_frame = self.opts.frames.is_some_and(|n| self.frame + 1 >= n);
        let shot_path = if last_frame {
            self.opts.screenshot.clone()
        } else {
            None
        }
        .or_else(|| self.screenshot_next.take());

        let win = self.win.as_mut().expect("ready() checked the window");
        let chain = win.swapchain.as_mut().expect("ready() made the swapchain");
        let live = win.live.as_mut().expect("ready() made the renderer");
        if turn != 0.0 && !self.opts.scene.lights.is_empty() {
            self.light_angle += turn * LIGHT_DEGREES_PER_SECOND * dt;
            live.renderer
                .set_lights(&turned_lights(&self.opts.scene, self.light_angle))?;
        }
        for (node, world) in self.motion.pose(&self.opts.scene, self.time) {
            live.renderer.set_node_transform(node, world);
        }
        live.renderer.camera = self.camera.camera();

        let Some(image) = chain.acquire()? else {
            self.recreate = true;
            return Ok(());
        };
        let target = Target {
            image: chain.images[image.index as usize],
            extent: chain.extent,
            encode_srgb: chain.encodes_srgb(),
            readable: chain.readable,
            bgra: matches!(
                chain.format,
                vk::Format::B8G8R8A8_UNORM | vk::Format::B8G8R8A8_SRGB
            ),
        };
        let waits = [vk::SemaphoreSubmitInfo::default()
            .semaphore(image.ready)
            .stage_mask(vk::PipelineStageFlags2::TRANSFER)];
        let signals = [vk::SemaphoreSubmitInfo::default()
            .semaphore(image.rendered)
            .stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
        let exposure = self.exposure;
        let mut recorded = Ok(());
        let Live { display, renderer } = live;
        renderer.render_with(false, &waits, &signals, &mut |g| {
            recorded = display.record(g, &target, exposure, shot_path.is_some());
        })?;
        recorded?;
        if !chain.present(&image)? {
            self.recreate = true;
        }
        if let Some(path) = shot_path {
            let shot = display
                .screenshot()
                .ok_or_else(|| anyhow!("the screenshot was not read back"))?;
            save_png(&path, &shot)?;
            log::info!(
                "saved {} ({}x{}, frame {})",
                path.display(),
                shot.width,
                shot.height,
                self.frame + 1
            );
        }
        self.frame += 1;
        if self.title_at.elapsed() > Duration::from_millis(500) || last_frame {
            self.title_at = Instant::now();
            self.update_title();
        }
        if last_frame {
            el.exit();
        }
        Ok(())
    }

    /// `--press`: releases last frame's keys, then presses this frame's.
    fn scripted_keys(&mut self, el: &ActiveEventLoop) {
        if self.pressed_at == Some(self.frame) {
            return;
        }
        for (code, shift) in std::mem::take(&mut self.scripted_held) {
            self.shift = shift;
            self.key(code, false, false, el);
        }
        let now: Vec<(KeyCode, bool)> = self
            .opts
            .presses
            .iter()
            .filter(|p| p.0 == self.frame)
            .map(|p| (p.1, p.2))
            .collect();
        for (code, shift) in now {
            self.shift = shift;
            self.key(code, true, false, el);
            self.scripted_held.push((code, shift));
        }
        self.pressed_at = Some(self.frame);
    }

    fn fly(&mut self, dt: f32) {
        let axis = |plus: &[KeyCode], minus: &[KeyCode]| {
            let on = |keys: &[KeyCode]| keys.iter().any(|k| self.held.contains(k)) as i32 as f32;
            on(plus) - on(minus)
        };
        let dir = Vec3::new(
            axis(&[KeyCode::KeyD], &[KeyCode::KeyA]),
            axis(
                &[KeyCode::KeyE, KeyCode::Space],
                &[KeyCode::KeyQ, KeyCode::KeyC],
            ),
            axis(&[KeyCode::KeyW], &[KeyCode::KeyS]),
        );
        self.camera.fly(dir, dt, self.shift);
    }
}

/// Writes a screenshot whole or not at all.
pub fn save_png(path: &std::path::Path, shot: &Shot) -> Result<()> {
    use image::ImageEncoder;
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(
            &shot.rgb,
            shot.width,
            shot.height,
            image::ExtendedColorType::Rgb8,
        )
        .with_context(|| format!("{}: encoding the PNG", path.display()))?;
    crate::output::write_bytes_atomic(path, &bytes)
        .with_context(|| format!("{}: writing the screenshot", path.display()))?;
    Ok(())
}

impl ApplicationHandler for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.win.is_some() {
            return;
        }
        let s = &self.opts.settings;
        let attrs = Window::default_attributes()
            .with_title("voxgi")
            .with_inner_size(PhysicalSize::new(s.width, s.height));
        let made = (|| -> Result<Windowed> {
            let window = el.create_window(attrs).context("creating the window")?;
            let surface = Surface::new(
                &self.ctx,
                window.display_handle()?.as_raw(),
                window.window_handle()?.as_raw(),
            )?;
            Ok(Windowed {
                live: None,
                swapchain: None,
                surface,
                window,
            })
        })();
        match made {
            Ok(w) => {
                self.win = Some(w);
                self.update_title();
            }
            Err(e) => {
                self.error = Some(e);
                el.exit();
            }
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => el.exit(),
            WindowEvent::Resized(_) => {
                if let Some(w) = &self.win {
                    w.window.request_redraw();
                }
            }
            WindowEvent::ModifiersChanged(m) => self.shift = m.state().shift_key(),
            WindowEvent::KeyboardInput { event, .. } => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    let pressed = event.state == ElementState::Pressed;
                    self.key(code, pressed, event.repeat, el);
                }
            }
            WindowEvent::MouseInput { state, .. } => {
                self.dragging = match state {
                    ElementState::Pressed => self.dragging + 1,
                    ElementState::Released => self.dragging.saturating_sub(1),
                };
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let Some((x, y)) = self.cursor {
                    if self.dragging > 0 {
                        self.camera
                            .look((position.x - x) as f32, (position.y - y) as f32);
                    }
                }
                self.cursor = Some((position.x, position.y));
            }
            WindowEvent::CursorLeft { .. } => self.cursor = None,
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => (p.y / 40.0) as f32,
                };
                self.camera.scroll(steps);
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.frame(el) {
                    self.error = Some(e);
                    el.exit();
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, el: &ActiveEventLoop) {
        let Some(win) = &self.win else { return };
        let size = win.window.inner_size();
        if size.width == 0 || size.height == 0 {
            // Minimized: nothing to draw until a resize.
            el.set_control_flow(ControlFlow::wait_duration(Duration::from_millis(100)));
        } else {
            el.set_control_flow(ControlFlow::Poll);
            win.window.request_redraw();
        }
    }
}

/// Checks a `--resize FRAME:WxH` value.
pub fn parse_resize(spec: &str) -> Result<(u32, u32, u32)> {
    let bad = || anyhow!("--resize {spec:?}: expected FRAME:WIDTHxHEIGHT, e.g. 20:320x240");
    let (frame, size) = spec.split_once(':').ok_or_else(bad)?;
    let (w, h) = size.split_once('x').ok_or_else(bad)?;
    let (frame, w, h) = (
        frame.trim().parse().map_err(|_| bad())?,
        w.trim().parse::<u32>().map_err(|_| bad())?,
        h.trim().parse::<u32>().map_err(|_| bad())?,
    );
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        bail!("--resize {spec:?}: the size is out of range (1 to 16384)");
    }
    Ok((frame, w, h))
}

/// Checks a `--press FRAME:KEY` value: KEY is a letter, a digit, one of `[ ] - =`, `space`,
/// `esc` or `f12`, optionally after `shift+`.
pub fn parse_press(spec: &str) -> Result<(u32, KeyCode, bool)> {
    let bad = || {
        anyhow!(
            "--press {spec:?}: expected FRAME:KEY (KEY: a letter, a digit, [ ] - =, space, esc, \
             f12, optionally shift+KEY), e.g. 10:3 or 20:shift+v"
        )
    };
    let (frame, key) = spec.split_once(':').ok_or_else(bad)?;
    let frame: u32 = frame.trim().parse().map_err(|_| bad())?;
    let key = key.trim().to_ascii_lowercase();
    let (shift, key) = match key.strip_prefix("shift+") {
        Some(k) => (true, k.to_string()),
        None => (false, key),
    };
    let code = match key.as_str() {
        "space" => KeyCode::Space,
        "esc" => KeyCode::Escape,
        "f12" => KeyCode::F12,
        "[" => KeyCode::BracketLeft,
        "]" => KeyCode::BracketRight,
        "-" => KeyCode::Minus,
        "=" => KeyCode::Equal,
        k if k.len() == 1 => {
            let c = k.chars().next().unwrap_or(' ');
            match c {
                'a'..='z' => LETTERS[(c as u8 - b'a') as usize],
                '0'..='9' => DIGITS[(c as u8 - b'0') as usize],
                _ => return Err(bad()),
            }
        }
        _ => return Err(bad()),
    };
    Ok((frame, code, shift))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scripted_presses_and_resizes_parse_or_say_why_not() {
        assert_eq!(parse_press("10:3").unwrap(), (10, KeyCode::Digit3, false));
        assert_eq!(parse_press("0:Shift+V").unwrap(), (0, KeyCode::KeyV, true));
        assert_eq!(
            parse_press("4:[").unwrap(),
            (4, KeyCode::BracketLeft, false)
        );
        assert_eq!(parse_press("7:f12").unwrap(), (7, KeyCode::F12, false));
        for bad in ["", "3", "x:3", "1:", "1:ctrl", "1:shift+", "-1:a"] {
            let e = parse_press(bad).unwrap_err().to_string();
            assert!(e.contains("--press"), "{bad:?}: {e}");
        }
        assert_eq!(parse_resize("20:320x240").unwrap(), (20, 320, 240));
        for bad in ["20:320", "320x240", "a:1x1", "1:0x5", "1:99999x5"] {
            assert!(parse_resize(bad).is_err(), "{bad:?}");
        }
    }

    #[test]
    fn the_readme_lists_every_control() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md");
        let readme = std::fs::read_to_string(path).unwrap();
        for (keys, what) in CONTROLS {
            let row = format!("| `{keys}` | {what} |");
            assert!(readme.contains(&row), "README.md lacks the row {row}");
        }
    }

    #[test]
    fn the_main_light_turns_about_the_scene_centre() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.gltf");
        let mut scene = crate::scene::load(&path).unwrap();
        scene.lights[0].position = scene.bounds.center() + Vec3::new(1.0, 0.5, 0.0);
        let turned = turned_lights(&scene, 90.0);
        let c = scene.bounds.center();
        let p = turned[0].position - c;
        assert!(p.distance(Vec3::new(0.0, 0.5, -1.0)) < 1e-5, "{p:?}");
        assert_eq!(turned.len(), scene.lights.len());
    }
}
