//! `voxgi bench` end to end on the bundled Cornell box: every output file is written and
//! parses, and the second run takes the reference from the cache. Bad input fails cleanly.

mod common;
use common::{temp_dir, voxgi};

use std::path::{Path, PathBuf};

fn bundled_scene() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets/cornell-box.gltf")
        .to_string_lossy()
        .into_owned()
}

#[test]
fn tiny_bench_writes_every_output_and_reuses_the_reference() {
    let dir = temp_dir("tiny").join("out");
    let out = dir.to_str().unwrap();
    let scene = bundled_scene();
    let args = [
        "bench",
        &scene,
        "--sweep",
        "tiny",
        "--out",
        out,
        "--width",
        "64",
        "--height",
        "64",
        "--frames",
        "2",
        "--warmup",
        "1",
        "--ref-spp",
        "8",
        "--validate",
    ];
    let (ok, _, err) = voxgi(&args);
    assert!(ok, "bench failed:\n{err}");
    assert!(
        err.contains("reference: path tracing 64x64 at 8 spp"),
        "{err}"
    );
    assert!(
        err.contains("[1/2] 32^3 ") && err.contains("[2/2] 32^3 paper"),
        "{err}"
    );

    // CSV: the header and one line per setting, every line as wide as the header.
    let csv = std::fs::read_to_string(dir.join("results.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 3, "{csv}");
    let head: Vec<&str> = lines[0].split(',').collect();
    for col in [
        "label",
        "voxels",
        "cone_count",
        "frame_wall_median_ms",
        "relMSE",
        "FLIP",
        "pareto",
    ] {
        assert!(head.contains(&col), "no {col} in {head:?}");
    }
    let rel = head.iter().position(|c| *c == "relMSE").unwrap();
    for l in &lines[1..] {
        let f: Vec<&str> = l.split(',').collect();
        assert_eq!(f.len(), head.len(), "{l}");
        let e: f64 = f[rel].parse().unwrap();
        assert!(e.is_finite() && e > 0.0, "relMSE {e}");
    }

    // JSON: parses, two settings with every field, at least one on the Pareto front.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("results.json")).unwrap())
            .expect("results.json parses");
    let settings = json["settings"].as_array().unwrap();
    assert_eq!(settings.len(), 2);
    assert_eq!(settings[1]["paper"], true);
    assert_eq!(settings[0]["voxels"], 32);
    for s in settings {
        assert!(s["frame_wall"]["median_ms"].as_f64().unwrap() > 0.0);
        assert!(s["MAE"].as_f64().is_some() && s["RMSE"].as_f64().is_some());
        assert!(s["passes"].as_object().is_some());
    }
    assert!(settings.iter().any(|s| s["pareto"] == true));
    assert_eq!(json["reference"]["cached"], false);

    let md = std::fs::read_to_string(dir.join("results.md")).unwrap();
    assert!(
        md.contains("| # | setting |") && md.contains("--sweep tiny"),
        "{md}"
    );
    let png = image::open(dir.join("pareto.png")).expect("pareto.png decodes");
    assert!(png.width() >= 400 && png.height() >= 300);

    // Second run: the reference comes from the cache, untouched.
    let cached: Vec<PathBuf> = std::fs::read_dir(dir.join("cache"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "exr"))
        .collect();
    assert_eq!(cached.len(), 2, "{cached:?}");
    let reference = cached
        .iter()
        .find(|p| !p.to_string_lossy().ends_with("-var.exr"))
        .unwrap();
    assert!(reference.to_string_lossy().ends_with("-64x64-8.exr"));
    let mtime = std::fs::metadata(reference).unwrap().modified().unwrap();
    let (ok, _, err) = voxgi(&args);
    assert!(ok, "second bench failed:\n{err}");
    assert!(err.contains("reference: cached"), "{err}");
    assert!(!err.contains("path tracing"), "{err}");
    assert_eq!(
        std::fs::metadata(reference).unwrap().modified().unwrap(),
        mtime
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("results.json")).unwrap()).unwrap();
    assert_eq!(json["reference"]["cached"], true);
}

#[test]
fn bad_input_fails_cleanly_and_writes_nothing() {
    let dir = temp_dir("bad");
    let out = dir.join("out");
    let o = out.to_str().unwrap();
    let scene = bundled_scene();
    let missing = dir.join("missing.gltf");
    for (args, expect) in [
        (
            vec!["bench", &scene, "--sweep", "voxels=2", "--out", o],
            "--sweep",
        ),
        (
            vec!["bench", &scene, "--sweep", "colour=1", "--out", o],
            "unknown axis",
        ),
        (
            vec!["bench", &scene, "--ref-spp", "0", "--out", o],
            "--ref-spp",
        ),
        (
            vec!["bench", &scene, "--frames", "0", "--out", o],
            "--frames",
        ),
        (
            vec!["bench", &scene, "--width", "0", "--out", o],
            "image size",
        ),
        (
            vec!["bench", missing.to_str().unwrap(), "--out", o],
            "missing.gltf",
        ),
        (vec!["bench", "--out", o], "one scene"),
    ] {
        let (ok, _, err) = voxgi(&args);
        assert!(!ok, "{args:?} succeeded");
        assert!(err.contains(expect), "{args:?}: {err}");
        assert!(!out.exists(), "{args:?} left {}", out.display());
    }
}
