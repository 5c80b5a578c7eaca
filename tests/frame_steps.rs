//! The frame as data: recording and `Renderer::passes` (what `voxgi info` lists) walk the same
//! list of steps, so the passes a frame records (their debug labels), their names in
//! `--timings` and `info` agree, in every mode, with `--paper`, with more bounces and with a
//! moving node; a still frame records only what its steps say.

mod gpu;
use gpu::context;
use voxgi::gi::GiSettings;
use voxgi::render::{Mode, RenderSettings, Renderer};

const MODES: [Mode; 8] = Mode::ALL;

/// Consecutive passes of one name (a pass per mip level) read as one.
fn merged(names: &[String]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for n in names {
        if out.last() != Some(n) {
            out.push(n.clone());
        }
    }
    out
}

fn check(label: &str, settings: RenderSettings, moving: bool) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.gltf");
    let scene = voxgi::scene::load(&path).unwrap();
    let ctx = context();
    let stats = ctx.stats.clone();
    {
        let mut settings = settings;
        settings.timings = true;
        if moving {
            // The tall box moves: voxelized every frame, apart from the static geometry.
            let node = scene
                .nodes
                .iter()
                .position(|n| n.name.as_deref() == Some("tall box"));
            settings.dynamic_nodes = vec![node.expect("the box has a tall box")];
        }
        let mut r = Renderer::new(&ctx, &scene, settings).unwrap();
        let passes = r.passes();
        assert_eq!(r.steps(true).len(), passes.len(), "{label}");
        r.render(true).unwrap();
        assert_eq!(
            merged(&r.recorded),
            passes,
            "{label}: the first frame's passes against info's"
        );
        let timed: Vec<String> = r
            .timer
            .as_ref()
            .expect("lavapipe has timestamps")
            .samples
            .iter()
            .map(|(n, _)| n.clone())
            .collect();
        assert_eq!(timed, passes, "{label}: --timings against info's passes");

        // A still frame (or one where only the moving node moved) records its own steps.
        if moving {
            let world = glam::Mat4::from_translation(glam::Vec3::new(0.01, 0.0, 0.0));
            let node = r.settings.dynamic_nodes[0];
            r.set_node_transform(node, world);
        }
        let expected: Vec<String> = r.steps(false).iter().map(|s| s.name()).collect();
        r.render(false).unwrap();
        assert_eq!(merged(&r.recorded), expected, "{label}: the second frame");
        assert!(expected.len() < passes.len(), "{label}: {expected:?}");
    }
    drop(ctx);
    assert_eq!(stats.count(), 0, "{label}: {:#?}", stats.messages());
}

fn small(mode: Mode, gi: GiSettings) -> RenderSettings {
    RenderSettings {
        width: 16,
        height: 16,
        mode,
        shadow_resolution: 64,
        gi: GiSettings { voxels: 8, ..gi },
        ..Default::default()
    }
}

#[test]
fn every_mode_records_the_passes_info_lists() {
    for mode in MODES {
        check(
            &format!("{mode:?}"),
            small(mode, GiSettings::default()),
            false,
        );
    }
}

#[test]
fn paper_records_the_passes_info_lists() {
    for mode in MODES {
        check(
            &format!("{mode:?} --paper"),
            small(mode, GiSettings::paper(8)),
            false,
        );
    }
}

#[test]
fn more_bounces_and_a_moving_node_record_the_passes_info_lists() {
    let three = GiSettings {
        bounces: 3,
        ..Default::default()
    };
    check("3 bounces", small(Mode::Full, three.clone()), false);
    check("3 bounces, moving", small(Mode::Full, three), true);
    let paper = GiSettings {
        bounces: 3,
        ..GiSettings::paper(8)
    };
    check("--paper, 3 bounces, moving", small(Mode::Full, paper), true);
    check(
        "1 bounce, moving",
        small(
            Mode::Indirect,
            GiSettings {
                bounces: 1,
                ..Default::default()
            },
        ),
        true,
    );
}
