//! The scene corpus (docs/corpus.md): the generator is deterministic and its scenes load; every
//! class renders validation-clean and finite; the held-out slice that CI runs stays at or below
//! its recorded table.

mod common;

use common::{temp_dir, voxgi};
use std::path::Path;
use voxgi::corpus::{self, run::Report, Class, Split};

fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read(&p).unwrap(),
            )
        })
        .collect();
    out.sort();
    out
}

fn generate(dir: &Path, count: u32, seed: u64) {
    let (ok, _, err) = voxgi(&[
        "corpus",
        "generate",
        "--out",
        dir.to_str().unwrap(),
        "--count",
        &count.to_string(),
        "--seed",
        &seed.to_string(),
    ]);
    assert!(ok, "{err}");
}

#[test]
fn the_generator_writes_the_same_bytes_from_a_seed_and_every_scene_loads() {
    let dir = temp_dir("corpus-generate");
    let (a, b, c) = (dir.join("a"), dir.join("b"), dir.join("c"));
    generate(&a, 15, 3);
    generate(&b, 15, 3);
    generate(&c, 15, 4);
    let (fa, fb, fc) = (files(&a), files(&b), files(&c));
    assert_eq!(fa.len(), 30, "a .glb and a .json per scene");
    assert!(fa == fb, "the same seed wrote other bytes");
    let differing = fa.iter().zip(&fc).filter(|(x, y)| x.1 != y.1).count();
    assert!(
        differing >= 15,
        "another seed changed only {differing} files"
    );

    let records = corpus::records(&a).unwrap();
    for class in Class::ALL {
        let of: Vec<_> = records.iter().filter(|r| r.class == class.name()).collect();
        assert_eq!(of.len(), 3, "{class:?}");
        let held = of.iter().filter(|r| r.split == Split::HeldOut).count();
        assert_eq!(held, 1, "{class:?}: numbers 0 and 2 tune, 1 is held out");
    }
    for r in &records {
        let s = r.load(&a).unwrap_or_else(|e| panic!("{e}"));
        common::assert_well_formed(&s);
        assert!(!s.camera.is_default, "{}: the file has its camera", r.name);
        let lit = !s.lights.is_empty()
            || s.environment.is_some()
            || s.materials.iter().any(|m| m.is_emissive());
        assert!(lit, "{}: nothing lights it", r.name);
        assert!(s.triangle_count() > 0, "{}", r.name);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn every_class_renders_validation_clean_and_finite() {
    let dir = temp_dir("corpus-render");
    generate(&dir, 10, 5);
    let out = dir.join("report");
    let (ok, stdout, err) = voxgi(&[
        "corpus",
        "run",
        dir.to_str().unwrap(),
        "--validate",
        "--size",
        "32",
        "--voxels",
        "32",
        "--spp-start",
        "4",
        "--spp-max",
        "8",
        "--accumulate",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(stdout.contains("| openings | 2 |"), "{stdout}");
    let report = corpus::run::load_report(&out.join("results.json")).unwrap();
    assert_eq!(report.scenes.len(), 10);
    for s in &report.scenes {
        assert_eq!(s.validation_messages, 0, "{}", s.name);
        assert!(
            s.rel_mse.is_finite() && s.flip.is_finite() && s.mean_ratio.is_finite(),
            "{}: {s:?}",
            s.name
        );
    }
    assert_eq!(report.classes.len(), 5);
    assert!(out.join("results.md").exists());
    let worst = &report.classes[0].rel_mse.worst_scene;
    assert!(out.join(format!("worst-{worst}.png")).exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_corpus_folders_get_one_clear_error() {
    let dir = temp_dir("corpus-errors");
    let missing = dir.join("missing");
    let (ok, _, err) = voxgi(&["corpus", "run", missing.to_str().unwrap()]);
    assert!(!ok);
    assert!(err.contains("missing") && err.lines().count() == 1, "{err}");

    std::fs::write(dir.join("broken.json"), "{\"name\": 3}").unwrap();
    let (ok, _, err) = voxgi(&["corpus", "reference", dir.to_str().unwrap()]);
    assert!(!ok);
    assert!(
        err.contains("broken.json") && err.contains("not a scene record"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The held-out slice CI runs: the first held-out scene of each class of the corpus of seed 1
/// (the same scenes as the full corpus's `CLASS-001`), 48x48, its references to 2048 samples.
/// The recorded table is tests/corpus/held-out-slice.json, made by this same command; a class
/// whose 90th percentile grows past it by more than the references' noise fails.
#[test]
fn the_held_out_slice_is_no_worse_than_recorded() {
    let dir = temp_dir("corpus-slice");
    generate(&dir, 10, 1);
    let baseline = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus/held-out-slice.json");
    let out = dir.join("report");
    let (ok, stdout, err) = voxgi(&[
        "corpus",
        "run",
        dir.to_str().unwrap(),
        "--split",
        "held-out",
        "--validate",
        "--size",
        "48",
        "--spp-max",
        "2048",
        "--out",
        out.to_str().unwrap(),
        "--baseline",
        baseline.to_str().unwrap(),
    ]);
    assert!(ok, "{err}\n{stdout}");
    let report: Report = corpus::run::load_report(&out.join("results.json")).unwrap();
    assert_eq!(report.scenes.len(), 5);
    assert!(report.scenes.iter().all(|s| s.split == Split::HeldOut));

    // The run beside the recorded one: a row per class and all, by the run's folder.
    let (ok, table, err) = voxgi(&[
        "corpus",
        "compare",
        baseline.to_str().unwrap(),
        out.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    for class in [
        "openings",
        "emitters",
        "materials",
        "objects",
        "scale",
        "all",
    ] {
        assert!(
            table.contains(&format!("| {class} | ")),
            "{class}:\n{table}"
        );
    }
    let missing = dir.join("no-such-run");
    let (ok, _, err) = voxgi(&[
        "corpus",
        "compare",
        baseline.to_str().unwrap(),
        missing.to_str().unwrap(),
    ]);
    assert!(!ok);
    assert!(
        err.contains("no-such-run") && err.lines().count() == 1,
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
