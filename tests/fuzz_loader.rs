//! The loader under the mutation fuzzer (src/scene/fuzz.rs), a fixed budget: the bundled
//! Cornell box as .gltf and .glb and small shared models, damaged 10,000 ways. Every case must
//! load into a well-formed scene or fail with a one-line error that names the file: no panic,
//! no case over 10 s. (A million cases ran once: docs/robustness.md.) Alone in its binary: the
//! fuzzer silences the panic hook while it runs.

use std::path::Path;
use std::time::Duration;
use voxgi::scene::fuzz::{self, FuzzSettings, Seed};

#[test]
fn ten_thousand_damaged_scenes_load_or_fail_clearly() {
    let mut seeds = Seed::builtin();
    let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes");
    for s in [
        "Box/Box.gltf",
        "BoxTextured/BoxTextured.gltf",
        "CornellBox-Original/CornellBox-Original.gltf",
        "NegativeScaleTest/NegativeScaleTest.gltf",
    ] {
        seeds.push(Seed::from_file(&shared.join(s)).expect("a shared scene"));
    }
    let scratch = Path::new(env!("CARGO_TARGET_TMPDIR")).join("voxgi-fuzz-loader");
    let _ = std::fs::remove_dir_all(&scratch);
    let settings = FuzzSettings {
        cases: 10_000,
        seed: 2026,
        time_limit: Duration::from_secs(10),
        scratch: scratch.clone(),
        threads: 2,
    };
    std::panic::set_hook(Box::new(|_| {}));
    let report = fuzz::run(&seeds, &settings).expect("scratch files");
    let _ = std::panic::take_hook();
    eprintln!(
        "{} cases: {} loaded, {} rejected; slowest {:?}",
        report.cases, report.loaded, report.rejected, report.slowest
    );
    for f in &report.findings {
        eprintln!("{f:?}");
    }
    assert!(
        report.findings.is_empty(),
        "{} findings",
        report.findings.len()
    );
    assert_eq!(report.cases, 10_000);
    // Both outcomes are reached: damage the loader accepts and damage it refuses.
    assert!(report.loaded > 500 && report.rejected > 5000, "{report:?}");
    let _ = std::fs::remove_dir_all(&scratch);
}
