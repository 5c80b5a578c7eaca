//! examples/render_and_move.rs runs: two EXRs, finite, the second showing the node moved.
//! (`cargo test` builds the examples; the binary lies beside the test's own directory.)

mod common;

#[test]
fn the_library_example_renders_moves_a_node_and_renders_again() {
    let exe = std::env::current_exe().unwrap();
    let examples = exe.parent().unwrap().parent().unwrap().join("examples");
    let bin = examples.join(format!("render_and_move{}", std::env::consts::EXE_SUFFIX));
    assert!(bin.exists(), "{} not built", bin.display());
    let dir = common::temp_dir("example");
    let o = std::process::Command::new(&bin)
        .current_dir(&dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let before = voxgi::output::load_exr(&dir.join("before.exr")).unwrap();
    let after = voxgi::output::load_exr(&dir.join("after.exr")).unwrap();
    assert_eq!((before.width, before.height), (256, 256));
    assert!(!before.has_non_finite() && !after.has_non_finite());
    let changed = before
        .pixels
        .iter()
        .zip(&after.pixels)
        .filter(|(a, b)| (0..3).any(|k| (a[k] - b[k]).abs() > 0.01 * (b[k].abs() + 0.01)))
        .count();
    // The tall box turned 22.5 degrees: its silhouette and shading change, the room does not.
    assert!(
        changed > 500 && changed < 256 * 256 / 2,
        "{changed} pixels changed"
    );
}
