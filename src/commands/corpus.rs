//! `voxgi corpus`: generate a scene corpus, path-trace its references, run the renderer on it.

use crate::{check_validation, context, DeviceOpts, GiOpts};
use anyhow::{bail, Result};
use clap::{Args, Subcommand};
use std::path::PathBuf;
use voxgi::corpus::{self, reference::ReferenceOptions, run::RunOptions, Class, Split};

#[derive(Args)]
pub struct CorpusCmd {
    #[command(subcommand)]
    command: CorpusCommand,
}

#[derive(Subcommand)]
enum CorpusCommand {
    /// Write N scenes drawn from the classes (openings, emitters, materials, objects, scale)
    ///
    /// Each scene is DIR/NAME.glb (camera and lights in the file) and DIR/NAME.json (class,
    /// seed, split, sky, what was drawn). The same seed writes the same bytes. A class's
    /// even-numbered scenes are its tune split, its odd-numbered ones are held out.
    Generate(GenerateCmd),
    /// Path-trace the references of a corpus (resumable: each is kept when done)
    ///
    /// Each scene is traced in two independent halves, doubled until they agree (relMSE of one
    /// against the other, over 4, under --noise) or --spp-max is reached; the mean of both is
    /// kept in the cache by the hash of the scene's bytes, its sky and these settings.
    Reference(ReferenceCmd),
    /// Render every scene and measure it against its reference, per class
    ///
    /// Prints the table (median, 90th percentile and worst relMSE and FLIP, the image's mean
    /// against the reference's, the still and first frame times) and writes OUT/results.md,
    /// OUT/results.json and the worst scenes beside their references (OUT/worst-NAME.png).
    /// Missing references are path-traced first.
    Run(Box<RunCmd>),
    /// Two runs side by side: per class before -> after, and the scenes that moved
    ///
    /// BEFORE and AFTER are the results.json of two `corpus run`s (or their folders). Prints a
    /// row per class (relMSE median, 90th percentile and worst, FLIP median and 90th
    /// percentile, the image means' 90th percentile, how many scenes got better and worse),
    /// then each scene whose relMSE moved by more than --moved.
    Compare(CompareCmd),
}

#[derive(Args)]
struct CompareCmd {
    /// The earlier run's results.json, or its folder
    before: PathBuf,
    /// The later run's results.json, or its folder
    after: PathBuf,
    /// A scene counts as moved (better or worse) past this change of its relMSE
    #[arg(long, default_value_t = corpus::compare::MOVED)]
    moved: f64,
}

fn split(s: &str) -> Result<Split, String> {
    match s {
        "tune" => Ok(Split::Tune),
        "held-out" => Ok(Split::HeldOut),
        _ => Err("expected tune or held-out".into()),
    }
}

fn class(s: &str) -> Result<Class, String> {
    Class::from_name(s).ok_or_else(|| {
        let names: Vec<&str> = Class::ALL.iter().map(|c| c.name()).collect();
        format!("expected one of {}", names.join(", "))
    })
}

#[derive(Args)]
struct GenerateCmd {
    /// The corpus's folder (made if missing)
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Scenes in all, the classes in turn
    #[arg(long, default_value_t = 100, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    count: u32,
    /// The corpus's seed
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Only these classes (repeat the option; default all)
    #[arg(long = "class", value_name = "CLASS", value_parser = class)]
    classes: Vec<Class>,
}

/// Which scenes, and how their references are made.
#[derive(Args)]
struct Selection {
    /// The corpus's folder
    dir: PathBuf,
    /// Only this split: tune or held-out
    #[arg(long, value_parser = split)]
    split: Option<Split>,
    /// Only these classes (repeat the option)
    #[arg(long = "class", value_name = "CLASS", value_parser = class)]
    classes: Vec<Class>,
    /// At most K scenes of each class (the first by number)
    #[arg(long, value_name = "K")]
    per_class: Option<usize>,
    /// Where references are kept (default DIR/references)
    #[arg(long, value_name = "DIR")]
    cache: Option<PathBuf>,
    /// Image side in pixels (references and renders)
    #[arg(long, default_value_t = ReferenceOptions::default().width, value_parser = clap::value_parser!(u32).range(8..=4096))]
    size: u32,
    /// The references' own error (relMSE against converged, estimated) that ends their rounds
    #[arg(long, default_value_t = ReferenceOptions::default().noise_target)]
    noise: f64,
    /// Samples per pixel of a reference's first round, in each half
    #[arg(long, default_value_t = ReferenceOptions::default().spp_start,
          value_parser = clap::value_parser!(u32).range(1..=1 << 20))]
    spp_start: u32,
    /// The most samples per pixel of a reference
    #[arg(long, default_value_t = ReferenceOptions::default().spp_max,
          value_parser = clap::value_parser!(u32).range(1..=1 << 24))]
    spp_max: u32,
}

impl Selection {
    fn references(&self) -> Result<ReferenceOptions> {
        if !(self.noise.is_finite() && self.noise > 0.0) {
            bail!("--noise {} must be a positive number", self.noise);
        }
        Ok(ReferenceOptions {
            width: self.size,
            height: self.size,
            spp_start: self.spp_start,
            spp_max: self.spp_max,
            noise_target: self.noise,
        })
    }

    fn run_options(&self) -> Result<RunOptions> {
        Ok(RunOptions {
            dir: self.dir.clone(),
            cache: self
                .cache
                .clone()
                .unwrap_or_else(|| self.dir.join("references")),
            references: self.references()?,
            split: self.split,
            classes: self.classes.clone(),
            per_class: self.per_class,
            gi: voxgi::gi::GiSettings::default(),
            accumulate: 8,
            shadow_resolution: 2048,
            area_shadow_resolution: 512,
            out: self
                .dir
                .join(format!("report-{}", self.split.map_or("all", |s| s.name()))),
            worst: 2,
            save_images: false,
            command_line: voxgi::bench::shell_words(
                &std::iter::once("voxgi".to_string())
                    .chain(std::env::args().skip(1))
                    .collect::<Vec<_>>(),
            ),
        })
    }
}

#[derive(Args)]
struct ReferenceCmd {
    #[command(flatten)]
    selection: Selection,
}

#[derive(Args)]
struct RunCmd {
    #[command(flatten)]
    selection: Selection,
    #[command(flatten)]
    gi: GiOpts,
    /// Frames in the antialiasing mean (see render --accumulate)
    #[arg(long, value_name = "N", default_value_t = 8,
          value_parser = clap::value_parser!(u32).range(1..=1024))]
    accumulate: u32,
    /// Shadow-map texels per side (punctual lights)
    #[arg(long, default_value_t = 2048, value_parser = clap::value_parser!(u32).range(16..=16384))]
    shadow_res: u32,
    /// Shadow-map texels per side of the area lights
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(16..=16384))]
    area_shadow_res: u32,
    /// The report's folder (default DIR/report-SPLIT)
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// The worst scenes of each class shown beside their references
    #[arg(long, value_name = "K", default_value_t = 2)]
    worst: usize,
    /// Also write every scene's image (OUT/NAME.exr)
    #[arg(long)]
    save_images: bool,
    /// Fail when a class's 90th-percentile relMSE grows past this earlier run's (its
    /// results.json, or its folder) by more than the references' noise
    #[arg(long, value_name = "FILE.json")]
    baseline: Option<PathBuf>,
    #[command(flatten)]
    device: DeviceOpts,
}

pub fn corpus(c: CorpusCmd) -> Result<()> {
    match c.command {
        CorpusCommand::Generate(g) => generate(g),
        CorpusCommand::Reference(r) => reference(r),
        CorpusCommand::Run(r) => run(*r),
        CorpusCommand::Compare(c) => compare(c),
    }
}

fn compare(c: CompareCmd) -> Result<()> {
    if !(c.moved.is_finite() && c.moved >= 0.0) {
        bail!("--moved {} must be a number of 0 or more", c.moved);
    }
    let before = corpus::run::load_report(&c.before)?;
    let after = corpus::run::load_report(&c.after)?;
    print!("{}", corpus::compare::markdown(&before, &after, c.moved));
    Ok(())
}

fn generate(g: GenerateCmd) -> Result<()> {
    let classes = if g.classes.is_empty() {
        Class::ALL.to_vec()
    } else {
        g.classes
    };
    let records = corpus::generate(&g.out, g.count, g.seed, &classes)?;
    let held = records.iter().filter(|r| r.split == Split::HeldOut).count();
    log::info!(
        "wrote {} scenes to {} ({} tune, {held} held out)",
        records.len(),
        g.out.display(),
        records.len() - held
    );
    Ok(())
}

fn reference(r: ReferenceCmd) -> Result<()> {
    let opts = r.selection.run_options()?;
    let records = corpus::run::select(corpus::records(&opts.dir)?, &opts);
    let refs = corpus::run::ensure_references(&opts, &records)?;
    println!("| scene | spp | noise | at display | seconds |\n|---|---|---|---|---|");
    for r in &refs {
        println!(
            "| {} | {} | {:.5} | {:.5} | {:.1} |",
            r.info.scene, r.info.spp, r.info.noise, r.info.display_noise, r.info.seconds
        );
    }
    Ok(())
}

fn run(r: RunCmd) -> Result<()> {
    let mut opts = r.selection.run_options()?;
    opts.gi = r.gi.settings();
    opts.accumulate = r.accumulate;
    opts.shadow_resolution = r.shadow_res;
    opts.area_shadow_resolution = r.area_shadow_res;
    opts.worst = r.worst;
    opts.save_images = r.save_images;
    if let Some(out) = r.out {
        opts.out = out;
    }
    let baseline = r
        .baseline
        .as_deref()
        .map(corpus::run::load_report)
        .transpose()?;
    let ctx = context(&r.device)?;
    let stats = ctx.stats.clone();
    let validating = ctx.validating;
    let report = corpus::run::run(&ctx, &opts)?;
    drop(ctx);
    print!("{}", corpus::run::markdown(&report, opts.worst));
    log::info!("wrote {}", opts.out.join("results.md").display());
    check_validation(&stats, validating)?;
    if let Some(b) = baseline {
        let worse = corpus::run::regressions(&report, &b);
        if !worse.is_empty() {
            bail!("worse than the baseline: {}", worse.join("; "));
        }
    }
    Ok(())
}
