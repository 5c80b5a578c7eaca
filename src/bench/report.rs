//! The benchmark's files: results.csv, results.json, results.md and pareto.png, written all
//! together (temporary names first, renamed once every one of them is complete).

use super::{chart, BenchError, BenchResults, Row};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Pass names over all rows, in the order they first ran.
fn pass_names(rows: &[Row]) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for r in rows {
        for (n, _) in &r.passes {
            if !names.contains(n) {
                names.push(n.clone());
            }
        }
    }
    names
}

/// `mip base (bounce)` -> `mip_base_bounce`, for column names.
fn slug(name: &str) -> String {
    let mut s = String::new();
    for c in name.chars() {
        if c.is_ascii_alphanumeric() {
            s.push(c.to_ascii_lowercase());
        } else if !s.is_empty() && !s.ends_with('_') {
            s.push('_');
        }
    }
    s.trim_end_matches('_').to_string()
}

/// A number for CSV and JSON: shortest round-trip form; non-finite is empty / null.
fn num(v: f64, null: &str) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        null.to_string()
    }
}

/// About four significant digits, for people.
fn sig(v: f64) -> String {
    if !v.is_finite() {
        return "-".into();
    }
    if v == 0.0 {
        return "0".into();
    }
    let mag = v.abs().log10().floor() as i32;
    if (-3..5).contains(&mag) {
        let digits = (3 - mag).max(0) as usize;
        format!("{v:.digits$}")
    } else {
        format!("{v:.3e}")
    }
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

fn json_string(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// The GiSettings fields as (column name, value) pairs, shared by CSV and JSON.
fn gi_fields(r: &Row) -> Vec<(&'static str, String)> {
    crate::gi::FIELDS
        .iter()
        .map(|f| (f.column, (f.get)(&r.gi).column()))
        .collect()
}

/// The path tracer's time to the row's relMSE (NaN when it did not get there).
fn pt_ms(r: &Row) -> f64 {
    r.pt_ms.unwrap_or(f64::NAN)
}

/// How many times faster than the path tracer the still frame is, at equal relMSE.
fn speedup(r: &Row) -> f64 {
    pt_ms(r) / r.still.median
}

/// One line per setting, in sweep order; a pass a setting did not run is an empty cell.
pub fn csv(res: &BenchResults) -> String {
    let passes = pass_names(&res.rows);
    let mut head: Vec<String> = vec!["index".into(), "label".into()];
    if let Some(r) = res.rows.first() {
        head.extend(gi_fields(r).iter().map(|(n, _)| n.to_string()));
    }
    head.extend(
        [
            "still_wall_median_ms",
            "still_wall_min_ms",
            "still_wall_max_ms",
            "moving_wall_median_ms",
            "frame_wall_median_ms",
            "frame_wall_min_ms",
            "frame_wall_max_ms",
        ]
        .map(String::from),
    );
    for p in &passes {
        let s = slug(p);
        head.extend([
            format!("{s}_median_ms"),
            format!("{s}_min_ms"),
            format!("{s}_max_ms"),
        ]);
    }
    head.extend(
        [
            "relMSE",
            "MAE",
            "RMSE",
            "FLIP",
            "moving_relMSE",
            "relit_relMSE",
            "relit_FLIP",
            "pt_equal_error_ms",
            "speedup_vs_pt",
            "pareto",
        ]
        .map(String::from),
    );
    let mut out = head.join(",");
    out.push('\n');
    for r in &res.rows {
        let mut f: Vec<String> = vec![r.index.to_string(), csv_field(&r.label)];
        f.extend(gi_fields(r).into_iter().map(|(_, v)| v));
        f.extend([r.still.median, r.still.min, r.still.max, r.moving.median].map(|v| num(v, "")));
        f.extend([r.frame.median, r.frame.min, r.frame.max].map(|v| num(v, "")));
        for p in &passes {
            match r.passes.iter().find(|(n, _)| n == p) {
                Some((_, s)) => f.extend([s.median, s.min, s.max].map(|v| num(v, ""))),
                None => f.extend([String::new(), String::new(), String::new()]),
            }
        }
        let m = &r.metrics;
        f.extend([m.rel_mse, m.mae, m.rmse, m.flip].map(|v| num(v, "")));
        let rm = &r.relit_metrics;
        f.extend([r.moving_metrics.rel_mse, rm.rel_mse, rm.flip].map(|v| num(v, "")));
        f.extend([pt_ms(r), speedup(r)].map(|v| num(v, "")));
        f.push(r.pareto.to_string());
        out.push_str(&f.join(","));
        out.push('\n');
    }
    out
}

/// `{"scene": .., .., "settings": [one object per setting]}`.
pub fn json(res: &BenchResults) -> String {
    let o = &res.options;
    let mut out = String::from("{\n");
    let _ = writeln!(
        out,
        "  \"scene\": {},",
        json_string(&o.scene.display().to_string())
    );
    let _ = writeln!(out, "  \"command\": {},", json_string(&o.command_line));
    let _ = writeln!(out, "  \"device\": {},", json_string(&res.device));
    let _ = writeln!(
        out,
        "  \"width\": {}, \"height\": {}, \"frames\": {}, \"warmup\": {}, \"exposure\": {}, \
         \"accumulate\": {},",
        o.width, o.height, o.frames, o.warmup, o.exposure, o.accumulate
    );
    let _ = writeln!(
        out,
        "  \"reference\": {{\"path\": {}, \"spp\": {}, \"cached\": {}, \"noise_relMSE\": {}}},",
        json_string(&res.reference_path.display().to_string()),
        o.ref_spp,
        res.reference_cached,
        res.reference_noise
            .map_or("null".into(), |v| num(v, "null"))
    );
    let curve: Vec<String> = res
        .pt_curve
        .iter()
        .map(|p| {
            format!(
                "{{\"spp\": {}, \"ms\": {}, \"relMSE\": {}}}",
                p.spp,
                num(p.ms, "null"),
                num(p.rel_mse, "null")
            )
        })
        .collect();
    let _ = writeln!(out, "  \"path_tracer\": [{}],", curve.join(", "));
    out.push_str("  \"settings\": [");
    for (i, r) in res.rows.iter().enumerate() {
        out.push_str(if i == 0 { "\n" } else { ",\n" });
        let mut f: Vec<String> = vec![
            format!("\"index\": {}", r.index),
            format!("\"label\": {}", json_string(&r.label)),
        ];
        f.extend(
            gi_fields(r)
                .into_iter()
                .map(|(n, v)| format!("\"{n}\": {v}")),
        );
        let spread = |s: &super::Spread| {
            format!(
                "{{\"median_ms\": {}, \"min_ms\": {}, \"max_ms\": {}}}",
                num(s.median, "null"),
                num(s.min, "null"),
                num(s.max, "null")
            )
        };
        f.push(format!("\"still_wall\": {}", spread(&r.still)));
        f.push(format!("\"moving_wall\": {}", spread(&r.moving)));
        f.push(format!("\"frame_wall\": {}", spread(&r.frame)));
        let passes: Vec<String> = r
            .passes
            .iter()
            .map(|(n, s)| format!("{}: {}", json_string(n), spread(s)))
            .collect();
        f.push(format!("\"passes\": {{{}}}", passes.join(", ")));
        let m = &r.metrics;
        for (n, v) in [
            ("relMSE", m.rel_mse),
            ("MAE", m.mae),
            ("RMSE", m.rmse),
            ("FLIP", m.flip),
            ("moving_relMSE", r.moving_metrics.rel_mse),
            ("relit_relMSE", r.relit_metrics.rel_mse),
            ("relit_FLIP", r.relit_metrics.flip),
            ("pt_equal_error_ms", pt_ms(r)),
            ("speedup_vs_pt", speedup(r)),
        ] {
            f.push(format!("\"{n}\": {}", num(v, "null")));
        }
        f.push(format!("\"pareto\": {}", r.pareto));
        let _ = write!(out, "    {{{}}}", f.join(", "));
    }
    out.push_str("\n  ]\n}\n");
    out
}

/// A table sorted by frame time with the Pareto settings in bold, and the per-pass times.
pub fn markdown(res: &BenchResults) -> String {
    let o = &res.options;
    let mut out = String::new();
    let name = o.scene.file_name().map_or_else(
        || o.scene.display().to_string(),
        |n| n.to_string_lossy().into(),
    );
    let _ = writeln!(out, "# voxgi bench: {name}\n");
    let _ = writeln!(out, "```\n{}\n```\n", o.command_line);
    let _ = writeln!(
        out,
        "- scene `{}`, {}x{}, full mode; device: {}",
        o.scene.display(),
        o.width,
        o.height,
        res.device
    );
    let _ = writeln!(
        out,
        "- time: median (min to max) over {} frame{} after {} warm-up frame{}, submission to \
         fence (wall clock). still: a still frame (G-buffer, direct light, trace; a \
         temporal trace keeps its blocks' cones), its error once the antialiasing mean of \
         its frames is complete ({} frames; 1: one sample per pixel); relit: a frame after the lights moved (shadow maps, voxel \
         lighting and bounces run; a temporal trace traces every block's cones again; one \
         sample per pixel); moving: the camera swung about the scene's vertical axis by up \
         to {} degrees and back over {} frames, its error at the last (the start again, one \
         sample per pixel). GPU \
         passes: timestamps of the relit frames (on lavapipe they can miss \
         compute work: trust the wall time there)",
        o.frames,
        if o.frames == 1 { "" } else { "s" },
        o.warmup,
        if o.warmup == 1 { "" } else { "s" },
        o.accumulate,
        o.orbit_deg,
        super::ORBIT_FRAMES
    );
    let noise = res.reference_noise.map_or(String::new(), |v| {
        format!("; its noise alone adds about {} to relMSE", sig(v))
    });
    let _ = writeln!(
        out,
        "- reference: `{}` ({} spp, {}){noise}",
        res.reference_path.display(),
        o.ref_spp,
        if res.reference_cached {
            "from the cache"
        } else {
            "rendered now"
        }
    );
    let _ = writeln!(
        out,
        "- error against it: relMSE, MAE, RMSE on linear radiance; FLIP on the display images \
         at exposure {}",
        o.exposure
    );
    let curve: Vec<String> = res
        .pt_curve
        .iter()
        .map(|p| format!("{} spp {} ms {}", p.spp, sig(p.ms), sig(p.rel_mse)))
        .collect();
    let _ = writeln!(
        out,
        "- path tracer (`voxgi reference`, another seed, without its BVH build): {}. PT ms: \
         its time to the still frame's relMSE (log-log between those; past the last, along \
         error = a / spp + b through the last two), speed-up: that over the still frame's",
        curve.join(", ")
    );
    let _ = writeln!(
        out,
        "- **bold**: on the Pareto front of still frames (no other setting is both faster and \
         more accurate); `#` is the point's number in pareto.png\n"
    );
    let mut sorted: Vec<&Row> = res.rows.iter().collect();
    sorted.sort_by(|a, b| a.still.median.total_cmp(&b.still.median));
    out.push_str(
        "| # | setting | still ms | moving ms | relit ms | GPU passes ms | relMSE | FLIP | moving relMSE | relit relMSE | PT ms | speed-up | Pareto |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|:---:|\n",
    );
    for r in &sorted {
        let label = if r.pareto {
            format!("**{}**", r.label)
        } else {
            r.label.clone()
        };
        let gpu: f64 = r.passes.iter().map(|(_, s)| s.median).sum();
        let m = &r.metrics;
        let _ = writeln!(
            out,
            "| {} | {label} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.index,
            sig(r.still.median),
            sig(r.moving.median),
            sig(r.frame.median),
            if r.passes.is_empty() {
                "-".into()
            } else {
                sig(gpu)
            },
            sig(m.rel_mse),
            sig(m.flip),
            sig(r.moving_metrics.rel_mse),
            sig(r.relit_metrics.rel_mse),
            sig(pt_ms(r)),
            sig(speedup(r)),
            if r.pareto { "yes" } else { "" }
        );
    }
    let passes = pass_names(&res.rows);
    if !passes.is_empty() {
        let _ = writeln!(out, "\nGPU time per pass, median ms:\n");
        let _ = writeln!(out, "| # | setting | {} |", passes.join(" | "));
        let _ = writeln!(out, "|---|---|{}", "---:|".repeat(passes.len()));
        for r in &sorted {
            let cells: Vec<String> = passes
                .iter()
                .map(|p| {
                    r.passes
                        .iter()
                        .find(|(n, _)| n == p)
                        .map_or("-".into(), |(_, s)| sig(s.median))
                })
                .collect();
            let _ = writeln!(out, "| {} | {} | {} |", r.index, r.label, cells.join(" | "));
        }
    }
    out
}

/// pareto.png, encoded.
pub fn chart_png(res: &BenchResults) -> Result<Vec<u8>, String> {
    let points: Vec<chart::Point> = res
        .rows
        .iter()
        .map(|r| chart::Point {
            index: r.index,
            label: r.label.clone(),
            time: r.still.median,
            error: r.metrics.rel_mse,
            paper: r.gi.paper,
            pareto: r.pareto,
        })
        .collect();
    let o = &res.options;
    let name = o
        .scene
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    let img = chart::draw(&points, &format!("{name} {}x{}", o.width, o.height));
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .map_err(|e| e.to_string())?;
    Ok(png)
}

/// Writes the four files into `dir`: each to a temporary name, then all renamed.
pub fn write_all(res: &BenchResults, dir: &Path) -> Result<(), BenchError> {
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| BenchError::Io { path, source }
    };
    let png = chart_png(res).map_err(|reason| BenchError::Io {
        path: dir.join("pareto.png"),
        source: std::io::Error::other(reason),
    })?;
    let files: Vec<(&str, Vec<u8>)> = vec![
        ("results.csv", csv(res).into_bytes()),
        ("results.json", json(res).into_bytes()),
        ("results.md", markdown(res).into_bytes()),
        ("pareto.png", png),
    ];
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let temp = |name: &str| dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let mut written: Vec<(PathBuf, PathBuf)> = Vec::new();
    let mut result = Ok(());
    for (name, bytes) in &files {
        let t = temp(name);
        if let Err(e) = std::fs::write(&t, bytes) {
            result = Err(io(&t)(e));
            let _ = std::fs::remove_file(&t);
            break;
        }
        written.push((t, dir.join(name)));
    }
    if result.is_ok() {
        for (t, path) in &written {
            if let Err(e) = std::fs::rename(t, path) {
                result = Err(io(path)(e));
                break;
            }
        }
    }
    if result.is_err() {
        for (t, _) in &written {
            let _ = std::fs::remove_file(t);
        }
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::{BenchOptions, Spread};
    use crate::gi::GiSettings;
    use crate::metrics::Metrics;

    fn results() -> BenchResults {
        let row = |index: usize, gi: GiSettings, t: f64, e: f64, pareto: bool| Row {
            index,
            label: super::super::sweep::label(&gi),
            gi,
            passes: vec![(
                "mip base (bounce)".into(),
                Spread {
                    median: t / 2.0,
                    min: t / 3.0,
                    max: t,
                },
            )],
            frame: Spread {
                median: 2.0 * t,
                min: 2.0 * t,
                max: 2.0 * t,
            },
            still: Spread {
                median: t,
                min: t,
                max: t,
            },
            moving: Spread {
                median: 1.5 * t,
                min: t,
                max: 2.0 * t,
            },
            moving_metrics: Metrics {
                rel_mse: 1.5 * e,
                mae: e,
                rmse: e,
                flip: e,
            },
            metrics: Metrics {
                rel_mse: e,
                mae: e,
                rmse: e,
                flip: e,
            },
            relit_metrics: Metrics {
                rel_mse: 2.0 * e,
                mae: e,
                rmse: e,
                flip: e,
            },
            pt_ms: Some(10.0 * t),
            pareto,
        };
        BenchResults {
            options: BenchOptions {
                scene: "a \"b\".gltf".into(),
                command_line: "voxgi bench a.gltf".into(),
                ..Default::default()
            },
            device: "dev".into(),
            reference_path: "cache/r.exr".into(),
            reference_cached: false,
            reference_noise: Some(1e-4),
            pt_curve: vec![crate::bench::PtPoint {
                spp: 1,
                ms: 5.0,
                rel_mse: 0.5,
            }],
            rows: vec![
                row(1, GiSettings::default(), 20.0, 0.1, true),
                row(2, GiSettings::paper(128), 10.0, f64::NAN, false),
            ],
        }
    }

    #[test]
    fn csv_has_a_header_and_a_line_per_setting() {
        let c = csv(&results());
        let lines: Vec<&str> = c.lines().collect();
        assert_eq!(lines.len(), 3);
        let head: Vec<&str> = lines[0].split(',').collect();
        assert!(head.contains(&"mip_base_bounce_median_ms"), "{head:?}");
        assert!(head.contains(&"cone_aperture_deg"));
        for l in &lines[1..] {
            assert_eq!(l.split(',').count(), head.len(), "{l}");
        }
        assert!(lines[2].contains("128^3 paper"));
    }

    #[test]
    fn markdown_sorts_by_time_and_marks_the_front() {
        let md = markdown(&results());
        let paper = md.find("| 2 | 128^3 paper |").unwrap();
        let default = md.find("| 1 | **64^3** |").unwrap();
        assert!(paper < default, "{md}");
        assert!(md.contains("voxgi bench a.gltf"));
        // still 20 ms, relit 40, path tracer 200 ms: 10 times faster.
        assert!(
            md.contains("| 1 | **64^3** | 20.00 | 30.00 | 40.00 |"),
            "{md}"
        );
        assert!(md.contains("| 200.0 | 10.00 | yes |"), "{md}");
    }

    #[test]
    fn json_escapes_and_nulls() {
        let j = json(&results());
        assert!(j.contains(r#""scene": "a \"b\".gltf""#), "{j}");
        assert!(j.contains(r#""relMSE": null"#));
        assert!(j.contains(r#""mip base (bounce)": {"median_ms": 10"#));
    }
}
