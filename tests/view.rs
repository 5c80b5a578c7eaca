//! `voxgi view` in a window under Xvfb (lavapipe presents to X11), with the Khronos validation
//! layer: scenes that move, windows that resize, keys that change the settings; each
//! screenshot must show the scene and match `voxgi render` of the same camera and settings.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::Mutex;

mod common;

/// xvfb-run -a races when two start at once: one window at a time.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

fn voxgi() -> Command {
    Command::new(env!("CARGO_BIN_EXE_voxgi"))
}

fn shared(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../shared/scenes/{name}/{name}.gltf"))
}

fn out_dir(test: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("voxgi-view-{test}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn show(o: &Output) -> String {
    format!(
        "status {:?}\nstdout:\n{}\nstderr:\n{}",
        o.status,
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// `voxgi view ARGS` in a virtual X screen.
fn view(args: &[&str]) -> Output {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let mut cmd = Command::new("xvfb-run");
    cmd.args([
        "-a",
        "-s",
        "-screen 0 1024x768x24",
        env!("CARGO_BIN_EXE_voxgi"),
        "view",
    ])
    .args(args);
    match cmd.output() {
        Ok(o) => o,
        Err(e) => panic!(
            "cannot run xvfb-run ({e}): the window tests need Xvfb (bash .ci/install-deps \
             installs it)"
        ),
    }
}

fn render(args: &[&str]) -> Output {
    voxgi().arg("render").args(args).output().unwrap()
}

fn png(path: &Path) -> image::RgbImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8()
}

/// Not blank: the picture has light and structure (not one flat colour).
fn assert_shows_something(img: &image::RgbImage, what: &str) {
    let n = (img.width() * img.height() * 3) as f64;
    let mean = img.as_raw().iter().map(|&v| v as f64).sum::<f64>() / n;
    let var = img
        .as_raw()
        .iter()
        .map(|&v| (v as f64 - mean).powi(2))
        .sum::<f64>()
        / n;
    assert!(
        mean > 10.0 && var.sqrt() > 10.0,
        "{what}: looks blank (mean {mean:.1}, deviation {:.1} of 255)",
        var.sqrt()
    );
}

/// Channels that differ by more than 8 of 255 between two images of one size.
fn changed_channels(a: &image::RgbImage, b: &image::RgbImage) -> usize {
    a.as_raw()
        .iter()
        .zip(b.as_raw())
        .filter(|(x, y)| x.abs_diff(**y) > 8)
        .count()
}

/// Runs the window and `voxgi render` with the same settings (`common`), the window's
/// extra arguments `window`, and the render's `still` (the pose of its last frame); returns
/// the FLIP error between the screenshot and the render, the screenshot, and what the
/// window printed.
fn window_against_render(
    test: &str,
    common: &[&str],
    window: &[&str],
    still: &[&str],
) -> (f64, image::RgbImage, String) {
    let dir = out_dir(test);
    let shot = dir.join("window.png");
    let still_png = dir.join("render.png");
    let shot_s = shot.to_str().unwrap();
    let mut args: Vec<&str> = common.to_vec();
    args.extend(window);
    args.extend(["--screenshot", shot_s, "--validate"]);
    let o = view(&args);
    assert!(o.status.success(), "voxgi view failed:\n{}", show(&o));
    let printed = String::from_utf8_lossy(&o.stdout).into_owned();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !err.contains("VUID") && !err.to_lowercase().contains("validation"),
        "validation messages:\n{err}"
    );
    let mut args: Vec<&str> = common.to_vec();
    args.extend(still);
    args.extend(["--out", still_png.to_str().unwrap(), "--validate"]);
    let o = render(&args);
    assert!(o.status.success(), "voxgi render failed:\n{}", show(&o));

    let (a, b) = (png(&shot), png(&still_png));
    assert_eq!(a.dimensions(), b.dimensions(), "window and render sizes");
    let flip = voxgi::metrics::flip_display(&a, &b);
    eprintln!("{test}: FLIP {flip:.5} between the window and voxgi render");
    let _ = std::fs::remove_dir_all(&dir);
    (flip, a, printed)
}

#[test]
fn cornell_box_original_spins_resizes_and_matches_render() {
    let scene = shared("CornellBox-Original");
    let scene = scene.to_str().unwrap();
    // Its one node (the whole box) turns a full turn over the 60 frames (1 s), voxelized
    // every frame; the window is resized twice on the way.
    let common = [
        scene,
        // A moving scene: the window shows one sample per pixel, render the mean.
        "--accumulate",
        "1",
        "--width",
        "128",
        "--height",
        "128",
        "--voxels",
        "32",
        "--exposure",
        "3",
        "--spin",
        "CornellBox-Original",
        "--spin-speed",
        "360",
    ];
    let (flip, shot, _) = window_against_render(
        "cornell",
        &common,
        &[
            "--frames",
            "60",
            "--resize",
            "20:96x72",
            "--resize",
            "40:128x128",
        ],
        &["--time", "1"],
    );
    assert_shows_something(&shot, "screenshot");
    assert!(flip < 0.005, "FLIP {flip}");
}

fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for i in 0..4 {
            if i <= c.len() {
                out.push(A[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// Sponza as it is (its file, buffer and textures read where they lie in ../shared) plus a
/// red cube 1.5 m wide, node "spinner", standing in the atrium: Sponza is one node, and
/// turning all of it would voxelize its 262k triangles every frame.
fn sponza_with_a_spinner(dir: &Path) -> PathBuf {
    use serde_json::{json, Value};
    let sponza_dir = shared("Sponza").parent().unwrap().canonicalize().unwrap();
    let text = std::fs::read_to_string(shared("Sponza")).unwrap();
    let mut g: Value = serde_json::from_str(&text).unwrap();
    let absolute = |uri: &Value| {
        Value::String(
            sponza_dir
                .join(uri.as_str().unwrap())
                .to_str()
                .unwrap()
                .into(),
        )
    };
    for b in g["buffers"].as_array_mut().unwrap() {
        b["uri"] = absolute(&b["uri"]);
    }
    for i in g["images"].as_array_mut().unwrap() {
        i["uri"] = absolute(&i["uri"]);
    }
    // A unit cube as 12 triangles, unindexed.
    let corner = |i: usize| {
        [
            (i & 1) as f32 - 0.5,
            ((i >> 1) & 1) as f32 - 0.5,
            ((i >> 2) & 1) as f32 - 0.5,
        ]
    };
    let faces = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let mut bytes = Vec::new();
    for f in faces {
        for k in [0, 1, 2, 0, 2, 3] {
            for v in corner(f[k]) {
                bytes.extend(v.to_le_bytes());
            }
        }
    }
    let buffers = g["buffers"].as_array().unwrap().len();
    let views = g["bufferViews"].as_array().unwrap().len();
    let accessors = g["accessors"].as_array().unwrap().len();
    let materials = g["materials"].as_array().unwrap().len();
    let meshes = g["meshes"].as_array().unwrap().len();
    let nodes = g["nodes"].as_array().unwrap().len();
    let push = |g: &mut Value, key: &str, v: Value| g[key].as_array_mut().unwrap().push(v);
    push(
        &mut g,
        "buffers",
        json!({"uri": format!("data:application/octet-stream;base64,{}", base64(&bytes)), "byteLength": bytes.len()}),
    );
    push(
        &mut g,
        "bufferViews",
        json!({"buffer": buffers, "byteLength": bytes.len()}),
    );
    push(
        &mut g,
        "accessors",
        json!({"bufferView": views, "componentType": 5126, "count": 36, "type": "VEC3", "min": [-0.5, -0.5, -0.5], "max": [0.5, 0.5, 0.5]}),
    );
    push(
        &mut g,
        "materials",
        json!({"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.15, 0.1, 1.0], "metallicFactor": 0.0}}),
    );
    push(
        &mut g,
        "meshes",
        json!({"name": "cube", "primitives": [{"attributes": {"POSITION": accessors}, "material": materials}]}),
    );
    push(
        &mut g,
        "nodes",
        json!({"name": "spinner", "mesh": meshes, "translation": [0.0, 1.5, 0.0], "rotation": [0.0, 0.2588, 0.0, 0.9659], "scale": [1.5, 1.5, 1.5]}),
    );
    g["scenes"][0]["nodes"]
        .as_array_mut()
        .unwrap()
        .push(json!(nodes));
    let path = dir.join("sponza-spinner.gltf");
    std::fs::write(&path, serde_json::to_string(&g).unwrap()).unwrap();
    path
}

#[test]
fn sponza_with_a_spinning_cube_resizes_and_matches_render() {
    let dir = out_dir("sponza-scene");
    let scene = sponza_with_a_spinner(&dir);
    let scene = scene.to_str().unwrap();
    let common = [
        scene,
        // A moving scene: the window shows one sample per pixel, render the mean.
        "--accumulate",
        "1",
        "--width",
        "128",
        "--height",
        "96",
        "--voxels",
        "32",
        "--sun",
        "70,30,6",
        "--shadow-res",
        "512",
        "--spin",
        "spinner",
    ];
    let (flip, shot, _) = window_against_render(
        "sponza",
        &common,
        &[
            "--frames",
            "60",
            "--resize",
            "20:80x64",
            "--resize",
            "40:128x96",
        ],
        &["--time", "1"],
    );
    let _ = std::fs::remove_dir_all(&dir);
    assert_shows_something(&shot, "screenshot");
    assert!(flip < 0.005, "FLIP {flip}");
}

#[test]
fn a_still_window_shows_renders_antialiasing_mean() {
    // Nothing moves: after the 8 frames of the mean the window holds it, which is what
    // `render` writes by default (its 8 frames).
    let common = ["--width", "96", "--height", "96", "--shadow-res", "256"];
    let (flip, shot, _) = window_against_render("still-mean", &common, &["--frames", "12"], &[]);
    assert_shows_something(&shot, "screenshot");
    // The same mean, encoded to 8 bits on the GPU (the window) and on the CPU (render): a
    // value within a float's step of a rounding boundary may fall either way. Measured: 0 (the
    // same bytes), then 2.5e-5 once cones skipped empty space (one pixel of 9216 one step
    // apart); one sample per pixel (below) gives 0.058.
    assert!(flip < 1e-4, "FLIP {flip}");
    // One sample per pixel differs from it (the edges): the comparison can tell.
    let (one, _, _) = window_against_render(
        "still-one",
        &common,
        &["--frames", "12", "--accumulate", "1"],
        &[],
    );
    assert!(
        one > flip,
        "FLIP with one sample {one}, with the mean {flip}"
    );
}

#[test]
fn keys_change_mode_bounces_and_voxels_as_the_command_line_would() {
    // The bundled Cornell box: 3 is the indirect mode, B three bounces, Shift+V halves the
    // voxels (64 -> 32); the tall box turns meanwhile (a quarter turn per second).
    let common = [
        // A moving scene: the window shows one sample per pixel, render the mean.
        "--accumulate",
        "1",
        "--width",
        "96",
        "--height",
        "96",
        "--spin",
        "tall box",
        "--shadow-res",
        "256",
    ];
    let (flip, shot, printed) = window_against_render(
        "keys",
        &common,
        &[
            "--timings",
            "--frames",
            "12",
            "--press",
            "2:3",
            "--press",
            "4:b",
            "--press",
            "6:shift+v",
        ],
        &[
            "--time",
            "0.2",
            "--mode",
            "indirect",
            "--bounces",
            "3",
            "--voxels",
            "32",
        ],
    );
    assert_shows_something(&shot, "screenshot");
    assert!(flip < 0.005, "FLIP {flip}");
    // The title bar showed the settings the keys chose and each pass's time, and --timings
    // printed the medians.
    let title = printed
        .lines()
        .find(|l| l.starts_with("title: "))
        .unwrap_or_else(|| panic!("no title printed:\n{printed}"));
    for want in [
        "indirect",
        "3 bounces",
        "32^3",
        "ms",
        "trace ",
        "voxelize dynamic ",
    ] {
        assert!(title.contains(want), "title lacks {want:?}: {title}");
    }
    assert!(printed.contains("pass timings, median over"), "{printed}");
}

#[test]
fn animations_play_in_the_window_as_render_poses_them() {
    // tests/common's animated scene: a parent node sliding 0 -> (2,0,0) -> (2,1,0) over 2 s,
    // its child triangle turning a quarter turn; under a sun, seen from the default camera.
    let dir = common::temp_dir("view-anim");
    let scene = common::animated_scene(&dir);
    let scene = scene.to_str().unwrap();
    let common = [
        scene,
        // A moving scene: the window shows one sample per pixel, render the mean.
        "--accumulate",
        "1",
        "--width",
        "64",
        "--height",
        "48",
        "--voxels",
        "16",
        "--sun",
        "60,20,6",
        "--shadow-res",
        "128",
    ];
    let mut shots = Vec::new();
    for (frames, time) in [("30", "0.5"), ("90", "1.5")] {
        let (flip, shot, _) =
            window_against_render("anim", &common, &["--frames", frames], &["--time", time]);
        assert!(flip < 0.005, "{frames} frames: FLIP {flip}");
        shots.push(shot);
    }
    // The animation moved something between 0.5 s and 1.5 s.
    let changed = changed_channels(&shots[0], &shots[1]);
    assert!(
        changed > 20,
        "only {changed} channels changed between 0.5 s and 1.5 s"
    );
}

#[test]
fn the_light_key_turns_the_sun() {
    // L held for 60 frames (pressed anew each frame) turns the sun 45 degrees about the
    // vertical: the triangles, facing +Z, darken against the same run without (n.l from 0.81
    // to 0.37).
    let dir = common::temp_dir("view-light");
    let scene = common::animated_scene(&dir);
    let mut shots = Vec::new();
    for held in [false, true] {
        let shot = dir.join(format!("light-{held}.png"));
        let mut args: Vec<String> = [
            scene.to_str().unwrap(),
            "--width",
            "64",
            "--height",
            "48",
            "--voxels",
            "16",
            "--sun",
            "30,20,6",
            "--shadow-res",
            "128",
            "--frames",
            "61",
            "--validate",
            "--screenshot",
            shot.to_str().unwrap(),
        ]
        .iter()
        .map(|a| a.to_string())
        .collect();
        if held {
            for f in 1..=60 {
                args.extend(["--press".to_string(), format!("{f}:l")]);
            }
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = view(&args);
        assert!(o.status.success(), "voxgi view failed:\n{}", show(&o));
        shots.push(png(&shot));
    }
    let changed = changed_channels(&shots[0], &shots[1]);
    assert!(
        changed > 20,
        "turning the sun changed only {changed} channels"
    );
}

#[test]
fn a_window_hidden_shown_again_screenshot_and_closed_by_keys() {
    // Minimizing a window on X11 unmaps it: xdotool unmaps the running window and maps it
    // again, then presses F12 (a screenshot into the working directory) and Esc (quit) as
    // real key events. The run must not end while hidden, nor hang, nor report anything.
    let dir = common::temp_dir("view-unmap");
    let script = format!(
        "{exe} view --width 96 --height 96 --voxels 16 --shadow-res 256 --validate & pid=$!; \
         for i in $(seq 100); do wid=$(xdotool search --name voxgi | head -1); \
         [ -n \"$wid\" ] && break; sleep 0.2; done; \
         [ -n \"$wid\" ] || {{ echo no window; exit 3; }}; \
         sleep 1; xdotool windowunmap $wid; sleep 2; \
         kill -0 $pid || {{ echo ended while hidden; exit 4; }}; \
         xdotool windowmap $wid; sleep 1; xdotool windowfocus $wid; sleep 0.5; \
         xdotool key F12; \
         for i in $(seq 300); do [ -f voxgi-view-1.png ] && break; sleep 0.2; done; \
         xdotool key Escape; wait $pid",
        exe = env!("CARGO_BIN_EXE_voxgi"),
    );
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    // A key that never arrives would leave the window open: give up after two minutes.
    let o = Command::new("timeout")
        .args([
            "120",
            "xvfb-run",
            "-a",
            "-s",
            "-screen 0 1024x768x24",
            "sh",
            "-c",
            &script,
        ])
        .current_dir(&dir)
        .output()
        .expect("xvfb-run (bash .ci/install-deps installs it, and xdotool)");
    assert!(o.status.success(), "{}", show(&o));
    assert_shows_something(&png(&dir.join("voxgi-view-1.png")), "F12's screenshot");
}

#[test]
fn bad_view_arguments_fail_clearly_before_opening_a_window() {
    for (args, want) in [
        (vec!["--screenshot", "x.jpg", "--frames", "1"], "x.jpg"),
        (vec!["--screenshot", "x.png"], "--frames"),
        (vec!["--frames", "0"], "--frames"),
        (vec!["--resize", "5:0x3"], "--resize"),
        (vec!["--press", "5:ctrl"], "--press"),
        (vec!["--spin", "no such node"], "no such node"),
        (vec!["--spin-speed", "10"], "--spin"),
        (vec!["--time", "1"], "--time"),
    ] {
        let o = voxgi()
            .arg("view")
            .args(&args)
            .env_remove("DISPLAY")
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert!(err.contains(want), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
    // Without a display the error says what to do.
    let o = voxgi()
        .args(["view", "--frames", "1"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(err.contains("xvfb-run"), "{err}");
}

#[test]
fn the_camera_key_prints_options_that_render_the_window_s_view() {
    // Fly forward, to the side and up, then K: the printed options given to `voxgi render`
    // make the window's still image. The window's temporal trace carried its history through
    // the moves; once still, it traces every block afresh and ends where a fresh start does
    // (before that it settled 0.062 FLIP away here).
    let dir = out_dir("camera-key");
    let shot = dir.join("window.png");
    let common = ["--width", "96", "--height", "96", "--shadow-res", "256"];
    let mut args: Vec<&str> = common.to_vec();
    args.extend([
        "--frames",
        "30",
        "--press",
        "1:w",
        "--press",
        "3:d",
        "--press",
        "5:e",
        "--press",
        "11:k",
        "--screenshot",
    ]);
    args.push(shot.to_str().unwrap());
    let o = view(&args);
    assert!(o.status.success(), "voxgi view failed:\n{}", show(&o));
    let printed = String::from_utf8_lossy(&o.stdout).into_owned();
    let line = printed
        .lines()
        .find(|l| l.starts_with("--eye "))
        .unwrap_or_else(|| panic!("K printed no camera:\n{printed}"));
    let still = dir.join("render.png");
    let mut args: Vec<&str> = common.to_vec();
    args.extend(line.split_whitespace());
    args.extend(["--out", still.to_str().unwrap()]);
    let o = render(&args);
    assert!(o.status.success(), "voxgi render {line}:\n{}", show(&o));
    // The camera moved: not the scene's own view.
    let first = dir.join("first.png");
    let mut args: Vec<&str> = common.to_vec();
    args.extend(["--out", first.to_str().unwrap()]);
    assert!(render(&args).status.success());
    let (a, b, c) = (png(&shot), png(&still), png(&first));
    let flip = voxgi::metrics::flip_display(&a, &b);
    let moved = voxgi::metrics::flip_display(&a, &c);
    eprintln!("camera key: FLIP {flip:.5} against the printed options, {moved:.5} unmoved");
    assert!(moved > 0.01, "the window did not move ({moved})");
    assert!(flip < 1e-3, "FLIP {flip} ({line})");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_y_key_steps_the_environments_strength_as_env_strength_would() {
    // The bundled Cornell box, open at the front, under a uniform sky: Y at frame 2 doubles
    // its strength, as --env-strength 2 does for render.
    let common = [
        "--accumulate",
        "1",
        "--width",
        "64",
        "--height",
        "64",
        "--env",
        "0.5,0.6,0.8",
        "--shadow-res",
        "256",
    ];
    let (flip, shot, printed) = window_against_render(
        "env-key",
        &common,
        &["--frames", "6", "--press", "2:y"],
        &["--env-strength", "2"],
    );
    assert_shows_something(&shot, "screenshot");
    assert!(flip < 0.005, "FLIP {flip}");
    assert!(
        printed.contains("sky x2"),
        "the key's setting was not printed:\n{printed}"
    );
}
