//! `voxgi corpus run`: every scene of a corpus (or a split of it) rendered at the given
//! settings and measured against its reference; the table per class, the worst scenes beside
//! their references, and the check against a recorded table.

use super::reference::{self, Reference, ReferenceOptions};
use super::{io_error, Class, CorpusError, SceneRecord, Split};
use crate::gi::GiSettings;
use crate::metrics::try_compare;
use crate::output::{display, write_bytes_atomic, RadianceImage};
use crate::render::{RenderSettings, Renderer};
use crate::vk::Context;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// What a run renders and where it writes.
#[derive(Clone, Debug)]
pub struct RunOptions {
    pub dir: PathBuf,
    /// Where the references are kept.
    pub cache: PathBuf,
    pub references: ReferenceOptions,
    /// One split, or the whole corpus.
    pub split: Option<Split>,
    /// Only these classes (all when empty).
    pub classes: Vec<Class>,
    /// At most this many scenes of each class (after the split), the first by number.
    pub per_class: Option<usize>,
    pub gi: GiSettings,
    pub accumulate: u32,
    pub shadow_resolution: u32,
    pub area_shadow_resolution: u32,
    /// The report's folder: results.md, results.json and the worst scenes' images.
    pub out: PathBuf,
    /// The worst scenes of each class shown beside their references.
    pub worst: usize,
    /// Also write every scene's image (OUT/NAME.exr).
    pub save_images: bool,
    /// The command line, for the report.
    pub command_line: String,
}

/// One scene's measurement.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct SceneResult {
    pub name: String,
    pub class: String,
    pub split: Split,
    pub rel_mse: f64,
    pub flip: f64,
    /// The image's mean radiance over the reference's.
    pub mean_ratio: f64,
    /// Wall time of the first frame (the renderer made, the static geometry voxelized, lit
    /// and traced), milliseconds.
    pub first_frame_ms: f64,
    /// Median of the still frames after it (submit to fence), milliseconds.
    pub still_frame_ms: f64,
    /// The reference's own relMSE, estimated (it adds to `rel_mse`).
    pub reference_noise: f64,
    /// The same at the display exposure, as FLIP sees the images.
    #[serde(default)]
    pub reference_display_noise: f64,
    pub reference_spp: u32,
    pub validation_messages: usize,
    pub description: String,
}

/// A statistic of a class: median, 90th percentile and the worst, with the worst's name.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Spread {
    pub median: f64,
    pub p90: f64,
    pub worst: f64,
    pub worst_scene: String,
}

impl Spread {
    /// Nearest-rank percentiles of `values` (larger is worse).
    fn of(values: &[(f64, &str)]) -> Spread {
        let mut v: Vec<(f64, &str)> = values.to_vec();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        let rank = |p: f64| v[((p * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1].0;
        let (worst, name) = v[v.len() - 1];
        Spread {
            median: rank(0.5),
            p90: rank(0.9),
            worst,
            worst_scene: name.to_string(),
        }
    }
}

/// One class's row of the table (or "all").
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ClassSummary {
    pub class: String,
    pub scenes: usize,
    pub rel_mse: Spread,
    pub flip: Spread,
    /// |mean ratio - 1|: how far the image's mean is from the reference's.
    pub mean_error: Spread,
    pub still_frame_ms_median: f64,
    pub first_frame_ms_median: f64,
    /// The largest reference noise among the class's scenes.
    pub reference_noise_max: f64,
    /// The largest at the display exposure.
    #[serde(default)]
    pub reference_display_noise_max: f64,
}

/// What a run writes to results.json.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Report {
    pub command_line: String,
    pub split: Option<Split>,
    pub width: u32,
    pub height: u32,
    pub device: String,
    pub classes: Vec<ClassSummary>,
    pub all: ClassSummary,
    pub scenes: Vec<SceneResult>,
}

/// The goals of issue 52, per class.
pub const GOAL_P90_REL_MSE: f64 = 0.02;
pub const GOAL_P90_FLIP: f64 = 0.15;
pub const GOAL_WORST_REL_MSE: f64 = 0.05;
pub const GOAL_MEAN_ERROR: f64 = 0.05;

/// The scenes a run takes: the split, the classes, and at most `per_class` of each.
pub fn select(records: Vec<SceneRecord>, opts: &RunOptions) -> Vec<SceneRecord> {
    let mut taken: Vec<SceneRecord> = records
        .into_iter()
        .filter(|r| opts.split.is_none_or(|s| r.split == s))
        .filter(|r| opts.classes.is_empty() || opts.classes.iter().any(|c| c.name() == r.class))
        .collect();
    taken.sort_by(|a, b| (&a.class, a.number).cmp(&(&b.class, b.number)));
    if let Some(k) = opts.per_class {
        let mut count = std::collections::HashMap::<String, usize>::new();
        taken.retain(|r| {
            let n = count.entry(r.class.clone()).or_default();
            *n += 1;
            *n <= k
        });
    }
    taken
}

/// Makes every missing reference of `records` (resumable: each is kept when done).
pub fn ensure_references(
    opts: &RunOptions,
    records: &[SceneRecord],
) -> Result<Vec<Reference>, CorpusError> {
    let missing = records
        .iter()
        .map(|r| {
            reference::cached(&opts.dir, &opts.cache, r, &opts.references).map(|c| c.is_none())
        })
        .collect::<Result<Vec<bool>, _>>()?;
    let to_make = missing.iter().filter(|&&m| m).count();
    if to_make > 0 {
        log::info!(
            "path tracing {to_make} reference(s) of {} at {}x{} (kept in {})",
            records.len(),
            opts.references.width,
            opts.references.height,
            opts.cache.display()
        );
    }
    let bar = crate::console::bar(to_make as u64, "references");
    let mut out = Vec::new();
    for (r, &m) in records.iter().zip(&missing) {
        let reference = reference::get(&opts.dir, &opts.cache, r, &opts.references)?;
        if m {
            log::debug!(
                "{}: {} spp, noise {:.5} ({:.5} at display), {:.1} s",
                r.name,
                reference.info.spp,
                reference.info.noise,
                reference.info.display_noise,
                reference.info.seconds
            );
            bar.inc(1);
        }
        out.push(reference);
    }
    Ok(out)
}

/// Renders `record`'s scene as the corpus does: the first frame, then still frames until the
/// antialiasing mean is whole. Returns the image, the first frame's and the median still
/// frame's milliseconds.
fn render(
    ctx: &Arc<Context>,
    opts: &RunOptions,
    record: &SceneRecord,
    width: u32,
    height: u32,
) -> Result<(RadianceImage, f64, f64), CorpusError> {
    let scene = record.load(&opts.dir)?;
    let err = |e: crate::vk::VkError| CorpusError::Scene {
        path: opts.dir.join(&record.file),
        reason: format!("rendering: {e}"),
    };
    let settings = RenderSettings {
        width,
        height,
        gi: opts.gi.clone(),
        accumulate: opts.accumulate,
        shadow_resolution: opts.shadow_resolution,
        area_shadow_resolution: opts.area_shadow_resolution,
        ..Default::default()
    };
    let start = Instant::now();
    let mut r = Renderer::new(ctx, &scene, settings).map_err(err)?;
    let frames = opts.accumulate.max(2);
    r.render(frames == 1).map_err(err)?;
    let first = start.elapsed().as_secs_f64() * 1e3;
    r.frame_ms.clear();
    for f in 1..frames {
        r.render(f + 1 == frames).map_err(err)?;
    }
    let mut still = r.frame_ms.clone();
    still.sort_by(f64::total_cmp);
    let still = still.get(still.len() / 2).copied().unwrap_or(f64::NAN);
    let image = RadianceImage {
        width,
        height,
        pixels: r.radiance(),
    };
    Ok((image, first, still))
}

/// Runs the corpus: references first (made where missing), then every scene rendered and
/// measured. Writes the report's folder and returns the report.
pub fn run(ctx: &Arc<Context>, opts: &RunOptions) -> Result<Report, CorpusError> {
    let records = select(super::records(&opts.dir)?, opts);
    if records.is_empty() {
        return Err(CorpusError::Empty {
            path: opts.dir.clone(),
        });
    }
    let references = ensure_references(opts, &records)?;
    std::fs::create_dir_all(&opts.out).map_err(|e| io_error(&opts.out, e))?;
    let bar = crate::console::bar(records.len() as u64, "rendering the corpus, scenes");
    let mut results = Vec::new();
    let mut images = Vec::new();
    for (record, reference) in records.iter().zip(&references) {
        let (w, h) = (reference.image.width, reference.image.height);
        let before = ctx.stats.count();
        let (image, first, still) = render(ctx, opts, record, w, h)?;
        let validation_messages = ctx.stats.count() - before;
        let m = try_compare(&image, &reference.image, reference.info.exposure).map_err(|e| {
            CorpusError::Scene {
                path: opts.dir.join(&record.file),
                reason: e.to_string(),
            }
        })?;
        let mean = crate::hard::mean(&image);
        results.push(SceneResult {
            name: record.name.clone(),
            class: record.class.clone(),
            split: record.split,
            rel_mse: m.rel_mse,
            flip: m.flip,
            mean_ratio: mean / reference.info.mean.max(1e-12),
            first_frame_ms: first,
            still_frame_ms: still,
            reference_noise: reference.info.noise,
            reference_display_noise: reference.info.display_noise,
            reference_spp: reference.info.spp,
            validation_messages,
            description: record.description.clone(),
        });
        if opts.save_images {
            let path = opts.out.join(format!("{}.exr", record.name));
            crate::output::save(&image, &path, 0.0).map_err(|e| io_error(&path, e))?;
        }
        images.push(image);
        bar.inc(1);
    }
    drop(bar);
    let report = summarize(ctx, opts, results);
    write_worst(opts, &report, &images, &references)?;
    let md = markdown(&report, opts.worst);
    let md_path = opts.out.join("results.md");
    write_bytes_atomic(&md_path, md.as_bytes()).map_err(|e| io_error(&md_path, e))?;
    let json = serde_json::to_string_pretty(&report).expect("serializes") + "\n";
    let json_path = opts.out.join("results.json");
    write_bytes_atomic(&json_path, json.as_bytes()).map_err(|e| io_error(&json_path, e))?;
    Ok(report)
}

fn summary(class: &str, scenes: &[&SceneResult]) -> ClassSummary {
    let spread = |f: &dyn Fn(&SceneResult) -> f64| {
        Spread::of(
            &scenes
                .iter()
                .map(|s| (f(s), s.name.as_str()))
                .collect::<Vec<_>>(),
        )
    };
    let median = |f: &dyn Fn(&SceneResult) -> f64| spread(f).median;
    ClassSummary {
        class: class.to_string(),
        scenes: scenes.len(),
        rel_mse: spread(&|s| s.rel_mse),
        flip: spread(&|s| s.flip),
        mean_error: spread(&|s| (s.mean_ratio - 1.0).abs()),
        still_frame_ms_median: median(&|s| s.still_frame_ms),
        first_frame_ms_median: median(&|s| s.first_frame_ms),
        reference_noise_max: scenes.iter().map(|s| s.reference_noise).fold(0.0, f64::max),
        reference_display_noise_max: scenes
            .iter()
            .map(|s| s.reference_display_noise)
            .fold(0.0, f64::max),
    }
}

/// The rows of the table: each class the scenes hold, and all of them.
fn summaries(scenes: &[SceneResult]) -> (Vec<ClassSummary>, ClassSummary) {
    let classes = Class::ALL
        .iter()
        .filter_map(|c| {
            let of: Vec<&SceneResult> = scenes.iter().filter(|s| s.class == c.name()).collect();
            (!of.is_empty()).then(|| summary(c.name(), &of))
        })
        .collect();
    (classes, summary("all", &scenes.iter().collect::<Vec<_>>()))
}

fn summarize(ctx: &Arc<Context>, opts: &RunOptions, scenes: Vec<SceneResult>) -> Report {
    let (classes, all) = summaries(&scenes);
    Report {
        command_line: opts.command_line.clone(),
        split: opts.split,
        width: opts.references.width,
        height: opts.references.height,
        device: ctx.device_info.to_string(),
        classes,
        all,
        scenes,
    }
}

/// The worst scenes of each class by relMSE, as `worst-NAME.png`: the image, the reference
/// and (between them) nothing, at the reference's exposure.
fn write_worst(
    opts: &RunOptions,
    report: &Report,
    images: &[RadianceImage],
    references: &[Reference],
) -> Result<(), CorpusError> {
    for name in worst_names(report, opts.worst) {
        let i = report.scenes.iter().position(|s| s.name == name).unwrap();
        let exposure = references[i].info.exposure;
        let (a, b) = (
            display(&images[i], exposure),
            display(&references[i].image, exposure),
        );
        let gap = 4;
        let mut out =
            image::RgbImage::from_pixel(a.width() * 2 + gap, a.height(), image::Rgb([255; 3]));
        image::imageops::replace(&mut out, &a, 0, 0);
        image::imageops::replace(&mut out, &b, (a.width() + gap) as i64, 0);
        let path = opts.out.join(format!("worst-{name}.png"));
        let mut bytes = Vec::new();
        out.write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .map_err(|e| io_error(&path, e))?;
        write_bytes_atomic(&path, &bytes).map_err(|e| io_error(&path, e))?;
    }
    Ok(())
}

/// The `k` worst scenes of each class by relMSE, worst first.
fn worst_names(report: &Report, k: usize) -> Vec<String> {
    let mut out = Vec::new();
    for c in &report.classes {
        let mut of: Vec<&SceneResult> = report
            .scenes
            .iter()
            .filter(|s| s.class == c.class)
            .collect();
        of.sort_by(|a, b| b.rel_mse.total_cmp(&a.rel_mse));
        out.extend(of.iter().take(k).map(|s| s.name.clone()));
    }
    out
}

/// The report as Markdown: the table per class against the goals, then the worst scenes.
pub fn markdown(report: &Report, worst: usize) -> String {
    let mut s = format!(
        "Corpus run ({} split, {}x{}, {}): `{}`\n\n",
        report.split.map_or("whole", |s| s.name()),
        report.width,
        report.height,
        report.device,
        report.command_line
    );
    s.push_str(
        "| class | scenes | relMSE median | p90 | worst | FLIP median | p90 | worst | mean off by, p90 | worst | still frame | first frame | reference noise, max | at display |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let mark = |v: f64, goal: f64| {
        if v <= goal {
            format!("{v:.4}")
        } else {
            format!("**{v:.4}**")
        }
    };
    for c in report.classes.iter().chain(std::iter::once(&report.all)) {
        s.push_str(&format!(
            "| {} | {} | {:.4} | {} | {} ({}) | {:.3} | {} | {:.3} | {} | {:.1}% ({}) | {:.0} ms | {:.0} ms | {:.4} | {:.4} |\n",
            c.class,
            c.scenes,
            c.rel_mse.median,
            mark(c.rel_mse.p90, GOAL_P90_REL_MSE),
            mark(c.rel_mse.worst, GOAL_WORST_REL_MSE),
            c.rel_mse.worst_scene,
            c.flip.median,
            mark(c.flip.p90, GOAL_P90_FLIP),
            c.flip.worst,
            mark(c.mean_error.p90, GOAL_MEAN_ERROR),
            100.0 * c.mean_error.worst,
            c.mean_error.worst_scene,
            c.still_frame_ms_median,
            c.first_frame_ms_median,
            c.reference_noise_max,
            c.reference_display_noise_max,
        ));
    }
    s.push_str(&format!(
        "\nGoals: p90 relMSE <= {GOAL_P90_REL_MSE}, p90 FLIP <= {GOAL_P90_FLIP}, worst relMSE <= \
         {GOAL_WORST_REL_MSE}, every image's mean within {:.0}% of its reference's (bold: missed).\n",
        GOAL_MEAN_ERROR * 100.0
    ));
    s.push_str("\n| worst scenes | class | relMSE | FLIP | mean ratio | what it holds |\n|---|---|---|---|---|---|\n");
    for name in worst_names(report, worst) {
        let r = report.scenes.iter().find(|r| r.name == name).unwrap();
        s.push_str(&format!(
            "| {} ![](worst-{}.png) | {} | {:.4} | {:.3} | {:.2} | {} |\n",
            r.name, r.name, r.class, r.rel_mse, r.flip, r.mean_ratio, r.description
        ));
    }
    s
}

/// The classes whose 90th-percentile relMSE grew past `baseline`'s by more than the
/// references' noise, described; empty when none did.
pub fn regressions(report: &Report, baseline: &Report) -> Vec<String> {
    let mut out = Vec::new();
    for c in &report.classes {
        let Some(b) = baseline.classes.iter().find(|b| b.class == c.class) else {
            continue;
        };
        let margin = c.reference_noise_max.max(b.reference_noise_max);
        if c.rel_mse.p90 > b.rel_mse.p90 + margin {
            out.push(format!(
                "{}: p90 relMSE {:.5} against the recorded {:.5} (+ noise {:.5})",
                c.class, c.rel_mse.p90, b.rel_mse.p90, margin
            ));
        }
    }
    out
}

/// Reads a report written by an earlier run: its results.json, or the run's folder.
pub fn load_report(path: &Path) -> Result<Report, CorpusError> {
    let file = path.join("results.json");
    let path = if path.is_dir() { file.as_path() } else { path };
    let text = std::fs::read_to_string(path).map_err(|e| io_error(path, e))?;
    serde_json::from_str(&text).map_err(|e| CorpusError::Report {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A scene's result with its relMSE; the rest plain.
    pub(crate) fn scene_result(name: &str, class: &str, rel_mse: f64) -> SceneResult {
        SceneResult {
            name: name.into(),
            class: class.into(),
            split: Split::HeldOut,
            rel_mse,
            flip: 0.1,
            mean_ratio: 1.0,
            first_frame_ms: 1.0,
            still_frame_ms: 1.0,
            reference_noise: 0.001,
            reference_display_noise: 0.001,
            reference_spp: 64,
            validation_messages: 0,
            description: String::new(),
        }
    }

    /// A report of these scenes, its table made as a run makes it.
    pub(crate) fn report_of(scenes: Vec<SceneResult>) -> Report {
        let (classes, all) = summaries(&scenes);
        Report {
            command_line: String::new(),
            split: Some(Split::HeldOut),
            width: 1,
            height: 1,
            device: String::new(),
            classes,
            all,
            scenes,
        }
    }

    fn report(p90: f64, noise: f64) -> Report {
        let spread = |v: f64| Spread {
            median: v,
            p90: v,
            worst: v,
            worst_scene: "x".into(),
        };
        let class = ClassSummary {
            class: "openings".into(),
            scenes: 1,
            rel_mse: spread(p90),
            flip: spread(0.1),
            mean_error: spread(0.0),
            still_frame_ms_median: 1.0,
            first_frame_ms_median: 1.0,
            reference_noise_max: noise,
            reference_display_noise_max: noise,
        };
        Report {
            command_line: String::new(),
            split: None,
            width: 1,
            height: 1,
            device: String::new(),
            classes: vec![class.clone()],
            all: class,
            scenes: Vec::new(),
        }
    }

    #[test]
    fn a_class_worse_than_its_baseline_by_more_than_the_noise_is_named() {
        let base = report(0.05, 0.001);
        assert!(regressions(&report(0.0505, 0.001), &base).is_empty());
        assert!(regressions(&report(0.04, 0.001), &base).is_empty());
        let worse = regressions(&report(0.052, 0.001), &base);
        assert_eq!(worse.len(), 1);
        assert!(worse[0].starts_with("openings"), "{worse:?}");
    }

    #[test]
    fn percentiles_are_nearest_rank() {
        let v: Vec<(f64, &str)> = (1..=10).map(|i| (i as f64, "x")).collect();
        let s = Spread::of(&v);
        assert_eq!((s.median, s.p90, s.worst), (5.0, 9.0, 10.0));
        let one = Spread::of(&[(3.0, "a")]);
        assert_eq!((one.median, one.p90, one.worst), (3.0, 3.0, 3.0));
    }
}
