//! Hard cases: generated scenes where voxel GI is known to break (light leaks, density,
//! precision, degenerate input, extreme lights and emission, cones at the edges), each with one
//! measured property and a goal, run with the project's defaults and with `--paper`.
//!
//! Every run also checks what no case may do: non-finite pixels or voxels (read back from the
//! volumes) and validation messages. `voxgi hard-cases` writes the table of docs/hard-cases.md;
//! tests/hard_cases.rs asserts the goals at the default settings.

mod cases;
pub mod scenes;

pub use cases::CASES;

use crate::gi::GiSettings;
use crate::output::RadianceImage;
use crate::reference::{self, ReferenceSettings};
use crate::render::{Mode, RenderSettings, Renderer};
use crate::scene::builder::SceneBuilder;
use crate::scene::{Camera, Scene};
use crate::vk::Context;
use anyhow::{Context as _, Result};
use glam::Mat4;
use std::path::PathBuf;
use std::sync::Arc;

/// What a case's value must satisfy.
#[derive(Clone, Copy, Debug)]
pub enum Goal {
    AtMost(f64),
}

impl Goal {
    pub fn met(self, value: f64) -> bool {
        match self {
            Goal::AtMost(g) => value <= g,
        }
    }
}

impl std::fmt::Display for Goal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Goal::AtMost(g) => write!(f, "<= {g}"),
        }
    }
}

/// One hard case.
pub struct Case {
    pub name: &'static str,
    pub group: &'static str,
    /// What the scene holds and what is measured.
    pub what: &'static str,
    /// The measured quantity, e.g. "leak ratio".
    pub metric: &'static str,
    pub goal: Goal,
    pub run: fn(&mut Env, &GiSettings) -> Result<f64>,
}

/// Where the cases run: a context, image and grid sizes, the reference's sample count.
pub struct Env {
    pub ctx: Arc<Context>,
    pub size: u32,
    pub voxels: u32,
    pub ref_spp: u32,
    /// Light bounces of the default column (the defaults' own unless `--bounces` says).
    pub bounces: u32,
    /// Whether the default column adds the bounces not traced (`GiSettings::tail`; off with
    /// `--no-tail`).
    pub tail: bool,
    /// Also measure, for the cases measured against the reference, the reference limited to
    /// the settings' bounces in place of the real-time image (`voxgi hard-cases --ideal`).
    pub ideal: bool,
    /// That measure for the current case.
    ideal_value: Option<f64>,
    /// And the real-time image's relMSE against that reference, for the current case.
    cones_value: Option<f64>,
    scratch: PathBuf,
    /// Non-finite pixels or voxels met by the current case.
    non_finite: Vec<String>,
    /// Loader warnings met by the current case.
    pub warnings: Vec<String>,
    dumped: usize,
}

/// The outcome of one case at one setting.
#[derive(Clone, Debug)]
pub struct Outcome {
    pub value: f64,
    /// Non-finite values found (pixels or voxels), described.
    pub non_finite: Vec<String>,
    pub validation_messages: usize,
    /// An error instead of a value (e.g. a grid too large for the device).
    pub error: Option<String>,
    /// With [`Env::ideal`]: what the reference path tracer limited to the same bounces scores.
    pub ideal: Option<f64>,
    /// With [`Env::ideal`]: relMSE of the real-time image without the tail (the bounces after
    /// the last, `GiSettings::tail`) against that path tracer's, the error the bounces it
    /// traces leave (the cones' own, not the missing bounces').
    pub cones: Option<f64>,
}

impl Outcome {
    pub fn passed(&self, goal: Goal) -> bool {
        self.error.is_none()
            && self.non_finite.is_empty()
            && self.validation_messages == 0
            && goal.met(self.value)
    }
}

impl Env {
    pub fn new(ctx: Arc<Context>, size: u32, voxels: u32, ref_spp: u32) -> Result<Env> {
        let scratch = std::env::temp_dir().join(format!("voxgi-hard-{}", std::process::id()));
        std::fs::create_dir_all(&scratch)
            .with_context(|| format!("creating {}", scratch.display()))?;
        Ok(Env {
            ctx,
            size,
            voxels,
            ref_spp,
            bounces: GiSettings::default().bounces,
            tail: GiSettings::default().tail,
            ideal: false,
            ideal_value: None,
            cones_value: None,
            scratch,
            non_finite: Vec::new(),
            warnings: Vec::new(),
            dumped: 0,
        })
    }

    /// The settings a case runs at: the defaults or the paper's, at the environment's grid.
    pub fn settings(&self, paper: bool) -> GiSettings {
        if paper {
            GiSettings::paper(self.voxels)
        } else {
            GiSettings {
                voxels: self.voxels,
                bounces: self.bounces,
                tail: self.tail,
                ..GiSettings::default()
            }
        }
    }

    /// Runs one case; errors become part of the outcome.
    pub fn run(&mut self, case: &Case, gi: &GiSettings) -> Outcome {
        self.non_finite.clear();
        self.warnings.clear();
        self.ideal_value = None;
        self.cones_value = None;
        let before = self.ctx.stats.count();
        let result = (case.run)(self, gi);
        let validation_messages = self.ctx.stats.count() - before;
        let (value, error) = match result {
            Ok(v) => (v, None),
            Err(e) => (f64::NAN, Some(format!("{e:#}"))),
        };
        Outcome {
            value,
            non_finite: std::mem::take(&mut self.non_finite),
            validation_messages,
            error,
            ideal: self.ideal_value.take(),
            cones: self.cones_value.take(),
        }
    }

    /// Writes `b` as a .glb and loads it back, as a user's file would be; the .glb is also kept
    /// in [`dump_dir`] when set.
    pub fn load(&mut self, name: &str, b: &SceneBuilder) -> Result<Scene> {
        let path = self.scratch.join(format!("{name}.glb"));
        std::fs::write(&path, b.to_glb()).with_context(|| format!("writing {}", path.display()))?;
        // Kept for `voxgi render` to look into.
        if let Some(dir) = dump_dir() {
            let keep = dir.join(format!("{name}.glb"));
            if let Err(e) = std::fs::copy(&path, &keep) {
                log::warn!("VOXGI_HARD_DUMP: {}: {e}", keep.display());
            }
        }
        let scene = crate::scene::load(&path)?;
        self.warnings.extend(scene.warnings.iter().cloned());
        Ok(scene)
    }

    /// Every image a case makes, saved to [`dump_dir`] (.exr and .png), in order.
    fn dump(&mut self, what: &str, img: &RadianceImage) {
        if let Some(dir) = dump_dir() {
            self.dumped += 1;
            let path = dir.join(format!("{:03}-{what}.exr", self.dumped));
            for p in [path.clone(), path.with_extension("png")] {
                if let Err(e) = crate::output::save(img, &p, 0.0) {
                    log::warn!("VOXGI_HARD_DUMP: {e}");
                }
            }
        }
    }

    fn check_image(&mut self, what: &str, img: &RadianceImage) {
        self.dump(what, img);
        let bad = img
            .pixels
            .iter()
            .filter(|p| p.iter().any(|c| !c.is_finite()))
            .count();
        if bad > 0 {
            self.non_finite
                .push(format!("{what}: {bad} non-finite pixels"));
        }
    }

    /// Renders `scene` from `camera` and checks the image and the volumes for non-finite values.
    pub fn render(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        gi: &GiSettings,
    ) -> Result<RadianceImage> {
        self.render_with(scene, camera, gi, Mode::Full, |_| Ok(()))
    }

    /// [`Env::render`], with `before` run on the renderer after a first frame (then a second
    /// frame is rendered), and a render mode.
    pub fn render_with(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        gi: &GiSettings,
        mode: Mode,
        before: impl FnOnce(&mut Renderer) -> Result<()>,
    ) -> Result<RadianceImage> {
        self.render_dynamic(scene, camera, gi, mode, Vec::new(), before)
    }

    pub fn render_dynamic(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        gi: &GiSettings,
        mode: Mode,
        dynamic_nodes: Vec<usize>,
        before: impl FnOnce(&mut Renderer) -> Result<()>,
    ) -> Result<RadianceImage> {
        let settings = RenderSettings {
            width: self.size,
            height: self.size,
            mode,
            shadow_resolution: 512,
            gi: gi.clone(),
            dynamic_nodes,
            // The second frame is the one shown: one sample per pixel, as the first.
            accumulate: 1,
            ..RenderSettings::default()
        };
        let mut r = Renderer::new(&self.ctx, scene, settings)?;
        r.camera = camera.clone();
        r.render(false)?;
        before(&mut r)?;
        r.render(true)?;
        let img = RadianceImage {
            width: self.size,
            height: self.size,
            pixels: r.radiance(),
        };
        self.check_image("image", &img);
        // One level at a time: a 512^3 grid's volumes, decoded at once, would not fit in memory.
        if let Some(bad) = r.count_non_finite()? {
            for (what, count) in [
                ("voxels", bad.radiance),
                ("directional volume texels", bad.directional),
                ("small emitters' voxels", bad.small_emission),
                ("backs' voxels", bad.back_radiance),
                ("glossy lobes' voxels", bad.glossy_radiance),
            ] {
                if count > 0 {
                    self.non_finite
                        .push(format!("volumes: {count} non-finite {what}"));
                }
            }
        }
        Ok(img)
    }

    /// The reference path tracer's image of `scene` from `camera`: all the light, or only
    /// what a tracer with `bounces` models.
    pub fn reference(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        bounces: Option<u32>,
    ) -> RadianceImage {
        let mut s = scene.clone();
        s.camera = camera.clone();
        let img = reference::render(
            &s,
            &ReferenceSettings {
                width: self.size,
                height: self.size,
                spp: self.ref_spp,
                bounces,
                // Noise of its own, not the full reference's.
                seed: u64::from(bounces.is_some()),
                ..Default::default()
            },
        );
        self.check_image(
            if bounces.is_some() {
                "ideal"
            } else {
                "reference"
            },
            &img,
        );
        img
    }

    /// `run` with references of `factor` times the samples per pixel: for scenes lit mostly
    /// by light that bounced, on which the path tracer converges slowly.
    pub fn with_more_samples<T>(&mut self, factor: u32, run: impl FnOnce(&mut Env) -> T) -> T {
        let spp = self.ref_spp;
        self.ref_spp = spp.saturating_mul(factor);
        let out = run(self);
        self.ref_spp = spp;
        out
    }

    /// relMSE of the real-time image of `scene` against the reference.
    pub fn error_vs_reference(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        gi: &GiSettings,
    ) -> Result<f64> {
        let img = self.render(scene, camera, gi)?;
        let reference = self.reference(scene, camera, None);
        self.measure_ideal(scene, camera, gi, &img, |ideal| {
            crate::metrics::compare(ideal, &reference).rel_mse
        })?;
        Ok(crate::metrics::compare(&img, &reference).rel_mse)
    }

    /// With [`Env::ideal`] (and not `--paper`): `measure` of the reference limited to `gi`'s
    /// bounces, kept as the case's [`Outcome::ideal`], and the relMSE of `img`, the real-time
    /// image, against it ([`Outcome::cones`]); with the tail, of the image rendered again
    /// without it, which traces only those bounces.
    pub fn measure_ideal(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        gi: &GiSettings,
        img: &RadianceImage,
        measure: impl FnOnce(&RadianceImage) -> f64,
    ) -> Result<()> {
        if self.ideal && !gi.paper {
            let ideal = self.reference(scene, camera, Some(gi.bounces));
            self.ideal_value = Some(measure(&ideal));
            let untailed;
            let traced = if gi.tail && gi.bounces >= 2 {
                let no_tail = GiSettings {
                    tail: false,
                    ..gi.clone()
                };
                untailed = self.render(scene, camera, &no_tail)?;
                &untailed
            } else {
                img
            };
            self.cones_value = Some(crate::metrics::compare(traced, &ideal).rel_mse);
        }
        Ok(())
    }
}

impl Drop for Env {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.scratch);
    }
}

/// Mean of the three channels over all pixels.
pub fn mean(img: &RadianceImage) -> f64 {
    let sum: f64 = img
        .pixels
        .iter()
        .map(|p| (p[0] as f64 + p[1] as f64 + p[2] as f64) / 3.0)
        .sum();
    sum / img.pixels.len().max(1) as f64
}

/// The largest channel value of any pixel.
pub fn max(img: &RadianceImage) -> f64 {
    img.pixels
        .iter()
        .flat_map(|p| p.iter())
        .fold(0.0f64, |m, &c| m.max(c as f64))
}

/// relMSE of `a` against `b` (per CONVENTIONS.md).
pub fn rel_mse(a: &RadianceImage, b: &RadianceImage) -> f64 {
    crate::metrics::compare(a, b).rel_mse
}

/// `img` times `k`.
pub fn scaled(img: &RadianceImage, k: f32) -> RadianceImage {
    RadianceImage {
        pixels: img.pixels.iter().map(|p| p.map(|c| c * k)).collect(),
        ..img.clone()
    }
}

/// A node's world transform, for moving it.
pub fn node_of(scene: &Scene, name: &str) -> Result<(usize, Mat4)> {
    scene
        .instances
        .iter()
        .find(|i| i.node_name.as_deref() == Some(name))
        .map(|i| (i.node, i.world))
        .with_context(|| format!("no node {name:?}"))
}

/// One row of the report.
pub struct Row {
    pub case: &'static Case,
    pub paper: Outcome,
    pub default: Outcome,
}

fn cell(o: &Outcome, goal: Goal) -> String {
    let mut s = if let Some(e) = &o.error {
        format!("error: {}", e.replace('|', "/").replace('\n', " "))
    } else {
        format!("{:.4}", o.value)
    };
    if !o.non_finite.is_empty() {
        s.push_str(&format!(" ({})", o.non_finite.join("; ")));
    }
    if o.validation_messages > 0 {
        s.push_str(&format!(" ({} validation messages)", o.validation_messages));
    }
    let mark = if o.passed(goal) { "pass" } else { "**fail**" };
    format!("{s} {mark}")
}

/// The markdown table of docs/hard-cases.md; `default` heads the defaults' column, `ideal`
/// adds the columns of [`Outcome::cones`] and [`Outcome::ideal`].
pub fn table(rows: &[Row], default: &str, ideal: bool) -> String {
    let (extra, rule) = if ideal {
        (
            " default without the tail against the path tracer, same bounces | path tracer, same bounces |",
            "---|---|",
        )
    } else {
        ("", "")
    };
    let mut s = format!(
        "| case | group | scene and measure | metric | goal | --paper | {default} |{extra}\n\
         |---|---|---|---|---|---|---|{rule}\n",
    );
    for r in rows {
        let c = r.case;
        let value = |v: Option<f64>| v.map_or(" - |".to_string(), |v| format!(" {v:.4} |"));
        let ideal_cell = match ideal {
            false => String::new(),
            true => value(r.default.cones) + &value(r.default.ideal),
        };
        s.push_str(&format!(
            "| `{}` | {} | {} | {} | {} | {} | {} |{}\n",
            c.name,
            c.group,
            c.what,
            c.metric,
            c.goal,
            cell(&r.paper, c.goal),
            cell(&r.default, c.goal),
            ideal_cell
        ));
    }
    s
}

/// VOXGI_HARD_DUMP=DIR: where the cases' images and scenes are kept, if anywhere.
fn dump_dir() -> Option<PathBuf> {
    std::env::var_os("VOXGI_HARD_DUMP").map(PathBuf::from)
}
