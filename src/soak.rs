//! Long runs (`voxgi soak`): thousands of frames with a moving node and moving lights, each
//! frame revoxelizing, relighting and bouncing, while host and GPU memory, the timing lists and
//! the validation layer are watched. A renderer that keeps something per frame shows it here as
//! a slope.

use crate::render::Renderer;
use crate::scene::{LightKind, Motion, Scene};
use crate::vk::VkResult;
use glam::{Quat, Vec3};

/// What a soak runs.
#[derive(Clone, Debug)]
pub struct SoakOptions {
    pub frames: u32,
    /// Frames between two samples of the memory and the lists.
    pub sample_every: u32,
    /// Seconds of scene time per frame (the motion's clock).
    pub frame_seconds: f32,
}

impl Default for SoakOptions {
    fn default() -> Self {
        SoakOptions {
            frames: 10_000,
            sample_every: 100,
            frame_seconds: 1.0 / 60.0,
        }
    }
}

/// One look at the process after `frame` frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SoakSample {
    pub frame: u32,
    /// Resident host memory (VmRSS). On a software device (lavapipe) this holds the device's
    /// memory as well.
    pub host_bytes: u64,
    /// Bytes the GPU allocator has handed out.
    pub gpu_bytes: u64,
    /// Entries in the renderer's frame-time list and its pass timer's lists together.
    pub timing_entries: usize,
}

/// A soak's samples and what else it counted.
#[derive(Clone, Debug, Default)]
pub struct SoakReport {
    pub samples: Vec<SoakSample>,
    /// Frames whose image held NaN or Inf pixels (each frame's image is read back).
    pub non_finite_frames: u32,
    pub seconds: f64,
}

/// Least-squares slope of y over x.
fn slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    if points.len() < 2 {
        return 0.0;
    }
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = points.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    if sxx > 0.0 {
        sxy / sxx
    } else {
        0.0
    }
}

impl SoakReport {
    /// The samples after the first tenth of the run (allocators and caches warm up).
    fn settled(&self) -> &[SoakSample] {
        let last = self.samples.last().map_or(0, |s| s.frame);
        let start = self
            .samples
            .iter()
            .position(|s| s.frame >= last / 10)
            .unwrap_or(0);
        &self.samples[start..]
    }

    /// Host memory's slope over the settled samples, bytes per frame.
    pub fn host_slope(&self) -> f64 {
        let p: Vec<(f64, f64)> = self
            .settled()
            .iter()
            .map(|s| (s.frame as f64, s.host_bytes as f64))
            .collect();
        slope(&p)
    }

    /// How much host memory grew over the settled frames, relative: the median of their last
    /// fifth against that of their first. (The allocator hands a megabyte back and takes it
    /// again now and then; a slope fitted through such steps says more about where they fell
    /// than about growth.)
    pub fn host_growth(&self) -> f64 {
        let s = self.settled();
        let fifth = (s.len() / 5).max(1);
        if s.len() < 2 {
            return 0.0;
        }
        let median = |part: &[SoakSample]| {
            let mut v: Vec<u64> = part.iter().map(|x| x.host_bytes).collect();
            v.sort_unstable();
            v[v.len() / 2] as f64
        };
        let (first, last) = (median(&s[..fifth]), median(&s[s.len() - fifth..]));
        if first > 0.0 {
            (last - first) / first
        } else {
            0.0
        }
    }

    /// The largest change of GPU memory between settled samples, bytes.
    pub fn gpu_change(&self) -> u64 {
        let s = self.settled();
        let lo = s.iter().map(|x| x.gpu_bytes).min().unwrap_or(0);
        let hi = s.iter().map(|x| x.gpu_bytes).max().unwrap_or(0);
        hi - lo
    }

    /// The timing lists' largest total length.
    pub fn max_timing_entries(&self) -> usize {
        self.samples
            .iter()
            .map(|s| s.timing_entries)
            .max()
            .unwrap_or(0)
    }

    /// What makes the run fail: host memory growing by more than `max_growth` (relative) over
    /// the settled frames, any change of GPU memory, timing lists longer than `max_entries`,
    /// non-finite images.
    pub fn problems(&self, max_growth: f64, max_entries: usize) -> Vec<String> {
        let mut out = Vec::new();
        let growth = self.host_growth();
        if growth > max_growth {
            out.push(format!(
                "host memory grew {:.2}% over the run ({:.1} bytes per frame; at most {:.2}%)",
                100.0 * growth,
                self.host_slope(),
                100.0 * max_growth
            ));
        }
        if self.gpu_change() > 0 {
            out.push(format!(
                "GPU memory changed by {} bytes after the first tenth of the run",
                self.gpu_change()
            ));
        }
        if self.max_timing_entries() > max_entries {
            out.push(format!(
                "the timing lists grew to {} entries (at most {max_entries})",
                self.max_timing_entries()
            ));
        }
        if self.non_finite_frames > 0 {
            out.push(format!(
                "{} frame(s) had NaN or Inf pixels",
                self.non_finite_frames
            ));
        }
        out
    }
}

/// Resident host memory of this process (VmRSS), 0 where /proc cannot tell.
pub fn host_resident_bytes() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("VmRSS:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        })
        .map_or(0, |kb| kb * 1024)
}

/// The scene's lights at frame `frame`: point lights and spots circle their place (a tenth of
/// the scene's size across, one turn in 240 frames), directional lights and spots swing 20
/// degrees either way about the vertical.
pub fn moved_lights(scene: &Scene, frame: u32) -> Vec<crate::scene::Light> {
    let phase = frame as f32 * std::f32::consts::TAU / 240.0;
    let radius = 0.05 * scene.bounds.extent().max_element().max(1e-3);
    let swing = Quat::from_rotation_y(20f32.to_radians() * phase.sin());
    scene
        .lights
        .iter()
        .map(|l| {
            let mut l = l.clone();
            match l.kind {
                LightKind::Point | LightKind::Spot { .. } => {
                    l.position += radius * Vec3::new(phase.cos(), 0.0, phase.sin());
                }
                LightKind::Directional => {}
            }
            if !matches!(l.kind, LightKind::Point) {
                l.direction = (swing * l.direction).normalize();
            }
            l
        })
        .collect()
}

/// Renders `opts.frames` frames, moving `motion`'s nodes and every light each frame, and
/// samples the process every `opts.sample_every` frames (and after the last). `progress` is
/// called after each sample with the frames done.
pub fn run(
    renderer: &mut Renderer,
    scene: &Scene,
    motion: &Motion,
    opts: &SoakOptions,
    mut progress: impl FnMut(&SoakSample),
) -> VkResult<SoakReport> {
    let start = std::time::Instant::now();
    let mut report = SoakReport::default();
    let every = opts.sample_every.max(1);
    let bar = crate::console::bar(opts.frames as u64, "soak, frames");
    for f in 0..opts.frames {
        bar.inc(1);
        for (node, world) in motion.pose(scene, f as f32 * opts.frame_seconds) {
            renderer.set_node_transform(node, world);
        }
        if !scene.lights.is_empty() {
            renderer.set_lights(&moved_lights(scene, f))?;
        }
        renderer.render(true)?;
        if renderer
            .radiance()
            .iter()
            .any(|p| p.iter().any(|c| !c.is_finite()))
        {
            report.non_finite_frames += 1;
        }
        let done = f + 1;
        if done % every == 0 || done == opts.frames {
            let sample = SoakSample {
                frame: done,
                host_bytes: host_resident_bytes(),
                gpu_bytes: renderer.context().allocated_bytes(),
                timing_entries: renderer.timing_entries(),
            };
            report.samples.push(sample);
            progress(&sample);
        }
    }
    report.seconds = start.elapsed().as_secs_f64();
    Ok(report)
}

/// What moves when the scene and the options move nothing: a spin of the first node with a
/// mesh (None if there is none).
pub fn moving_something(scene: &Scene, motion: Motion) -> Option<Motion> {
    if motion.moves(scene) {
        return Some(motion);
    }
    let node = scene.instances.first()?.node;
    Some(Motion {
        spin: Some(crate::scene::Spin {
            node,
            degrees_per_second: crate::scene::SPIN_DEGREES_PER_SECOND,
        }),
        ..motion
    })
}

/// One run of the validation sweep (`voxgi validation-sweep`): a scene in one mode, default or
/// `--paper`, some frames with a node and the lights moving.
#[derive(Clone, Debug)]
pub struct SweepRun {
    pub frames: u32,
    /// Validation messages during the run.
    pub messages: usize,
    pub non_finite_frames: u32,
    /// NaN or Inf voxels and texels left in the lit volumes after the last frame.
    pub non_finite_voxels: usize,
    pub seconds: f64,
}

/// Renders `frames` frames of `scene` (prepared for `motion`) as `settings` ask, moving the
/// motion's nodes and the lights, and counts what the sweep must not see.
pub fn sweep_run(
    ctx: &std::sync::Arc<crate::vk::Context>,
    scene: &Scene,
    motion: &Motion,
    settings: crate::render::RenderSettings,
    frames: u32,
) -> VkResult<SweepRun> {
    let before = ctx.stats.count();
    let start = std::time::Instant::now();
    let mut renderer = Renderer::new(ctx, scene, settings)?;
    let opts = SoakOptions {
        frames,
        sample_every: frames.max(1),
        ..Default::default()
    };
    let report = run(&mut renderer, scene, motion, &opts, |_| {})?;
    let voxels = renderer.count_non_finite()?.map_or(0, |n| n.total());
    drop(renderer);
    Ok(SweepRun {
        frames,
        messages: ctx.stats.count() - before,
        non_finite_frames: report.non_finite_frames,
        non_finite_voxels: voxels,
        seconds: start.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report(host: impl Fn(u32) -> u64, gpu: impl Fn(u32) -> u64) -> SoakReport {
        SoakReport {
            samples: (1..=100)
                .map(|i| SoakSample {
                    frame: i * 100,
                    host_bytes: host(i * 100),
                    gpu_bytes: gpu(i * 100),
                    timing_entries: 10,
                })
                .collect(),
            non_finite_frames: 0,
            seconds: 1.0,
        }
    }

    #[test]
    fn flat_memory_passes_and_growth_fails() {
        let flat = report(|f| 100_000_000 + (f % 300) as u64 * 1000, |_| 5_000_000);
        assert!(
            flat.problems(0.01, 100).is_empty(),
            "{:?}",
            flat.problems(0.01, 100)
        );
        // 200 bytes a frame: the medians of the settled run's first and last fifths (frames
        // 2,000 and 9,200) 1.44 MB apart, on about 100 MB.
        let leaking = report(|f| 100_000_000 + 200 * f as u64, |_| 5_000_000);
        assert!((leaking.host_slope() - 200.0).abs() < 1e-6);
        assert!(
            (leaking.host_growth() - 0.0144).abs() < 1e-3,
            "{}",
            leaking.host_growth()
        );
        // A megabyte taken and given back again a third of the time late in the run (as glibc
        // did in the 10,000-frame soak): flat, where the slope makes 0.46% of it.
        let toggling = report(
            |f| {
                100_000_000
                    + if f > 6000 && (f / 300) % 3 == 1 {
                        1 << 20
                    } else {
                        0
                    }
            },
            |_| 5_000_000,
        );
        assert_eq!(toggling.host_growth(), 0.0);
        let by_slope = toggling.host_slope() * 9000.0 / 1e8;
        assert!(by_slope > 0.002, "{by_slope}");
        assert_eq!(leaking.problems(0.01, 100).len(), 1);
        let gpu = report(|_| 100_000_000, |f| 5_000_000 + (f / 6000) as u64);
        assert_eq!(gpu.gpu_change(), 1);
        assert_eq!(gpu.problems(0.01, 100).len(), 1);
        // A jump in the first tenth (warm-up) does not count.
        let warm = report(|f| if f < 500 { 1 } else { 100_000_000 }, |_| 0);
        assert!(warm.problems(0.01, 100).is_empty());
        assert_eq!(warm.problems(0.01, 5).len(), 1);
    }

    #[test]
    fn the_resident_memory_is_read() {
        assert!(host_resident_bytes() > 1 << 20);
    }
}
