//! `voxgi soak` (a long run's memory watch) on a short run: the bundled box with a node and its
//! light moving every frame, under validation. The 10,000-frame run and its figures are in
//! docs/robustness.md.

mod common;

#[test]
fn a_short_soak_is_flat_clean_and_writes_its_samples() {
    let dir = common::temp_dir("soak");
    let csv = dir.join("soak.csv");
    let (ok, stdout, stderr) = common::voxgi(&[
        "soak",
        "--frames",
        "40",
        "--sample-every",
        "10",
        "--width",
        "16",
        "--height",
        "16",
        "--voxels",
        "16",
        "--shadow-res",
        "128",
        "--validate",
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    assert!(
        stdout.contains("GPU memory change 0 bytes") && stdout.contains("0 validation message(s)"),
        "{stdout}"
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<Vec<u64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(
        rows.iter().map(|r| r[0]).collect::<Vec<_>>(),
        [10, 20, 30, 40]
    );
    for r in &rows {
        assert!(r[1] > 1 << 20 && r[2] > 0, "{r:?}");
        // --timings is off: only the frame times are kept.
        assert_eq!(r[3], r[0], "{r:?}");
    }
}

#[test]
fn a_bad_max_growth_is_a_clear_error() {
    for (arg, shown) in [
        ("--max-growth=-1", "--max-growth -1"),
        ("--max-growth=nan", "NaN"),
    ] {
        let (ok, _, stderr) = common::voxgi(&["soak", "--frames", "1", arg]);
        assert!(!ok);
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        assert!(stderr.contains(shown), "{stderr}");
    }
}

#[test]
fn the_validation_sweep_covers_every_mode_and_both_columns() {
    // Two small shared models (the 10,000-frame soak and the full sweep over every shared
    // scene are in docs/robustness.md): every mode, default and --paper, a node and the sun
    // moving, under validation.
    let dir = common::temp_dir("sweep");
    let table = dir.join("sweep.md");
    let s = common::scenes_dir();
    let (ok, stdout, stderr) = common::voxgi(&[
        "validation-sweep",
        s.join("Box/Box.gltf").to_str().unwrap(),
        s.join("BoxTextured/BoxTextured.gltf").to_str().unwrap(),
        "--frames",
        "3",
        "--size",
        "16",
        "--voxels",
        "16",
        "--out",
        table.to_str().unwrap(),
    ]);
    assert!(ok, "{stdout}\n{stderr}");
    let text = std::fs::read_to_string(&table).unwrap();
    let rows: Vec<&str> = text.lines().skip(2).collect();
    assert_eq!(rows.len(), 2 * 8, "{text}");
    for mode in voxgi::render::Mode::NAMES.split(", ") {
        assert_eq!(
            rows.iter()
                .filter(|r| r.contains(&format!("| {mode} |")))
                .count(),
            2,
            "{mode}: {text}"
        );
    }
    for r in &rows {
        assert!(r.contains("| 0 / 0 | 0 / 0 | 0 / 0 |"), "{r}");
    }
}

#[test]
fn a_sweep_of_a_missing_scene_is_a_clear_error() {
    let (ok, _, stderr) = common::voxgi(&["validation-sweep", "no/such/scene.gltf"]);
    assert!(!ok);
    assert!(stderr.contains("no/such/scene.gltf"), "{stderr}");
}
