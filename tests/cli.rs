//! The command line: renders the bundled scene, and bad input gives a clear error that names
//! the file, a non-zero exit, no panic and no output file.

mod common;
use common::{temp_dir, voxgi};

#[test]
fn renders_the_bundled_scene_to_exr_and_png() {
    let dir = temp_dir("ok");
    let exr = dir.join("box.exr");
    let png = dir.join("box.png");
    for out in [&exr, &png] {
        let (ok, _, err) = voxgi(&[
            "render",
            "--out",
            out.to_str().unwrap(),
            "--width",
            "64",
            "--height",
            "48",
            "--voxels",
            "32",
            "--validate",
        ]);
        assert!(ok, "render failed:\n{err}");
    }
    let img = voxgi::output::load_exr(&exr).unwrap();
    assert_eq!((img.width, img.height), (64, 48));
    assert!(!img.has_non_finite());
    assert!(
        img.pixels.iter().any(|p| p[0] > 0.0),
        "the bundled scene rendered black"
    );
    let png = image::open(&png).unwrap();
    assert_eq!((png.width(), png.height()), (64, 48));
}

#[test]
fn bad_input_is_a_clear_error_with_no_output() {
    let dir = temp_dir("bad");
    let truncated = dir.join("truncated.gltf");
    std::fs::write(&truncated, r#"{"asset": {"version": "2.0"}, "meshes": [{"#).unwrap();
    let missing = dir.join("missing.gltf");
    let out = dir.join("never.png");
    let o = out.to_str().unwrap();
    for (args, needle) in [
        (
            vec!["render", truncated.to_str().unwrap(), "--out", o],
            "truncated.gltf",
        ),
        (
            vec!["render", missing.to_str().unwrap(), "--out", o],
            "missing.gltf",
        ),
        (vec!["info", missing.to_str().unwrap()], "missing.gltf"),
        (vec!["render", "--out", "image.tiff"], "image.tiff"),
        (vec!["render", "--width", "abc", "--out", o], "--width"),
        (vec!["render", "--mode", "sideways", "--out", o], "sideways"),
        (vec!["render", "--bogus"], "--bogus"),
        (vec!["render", "--paper-slips", "--out", o], "--paper"),
        (vec!["render", "--bounces", "9", "--out", o], "--bounces"),
        (vec!["hard-cases", "--bounces", "0"], "--bounces"),
    ] {
        let (ok, _, err) = voxgi(&args);
        assert!(!ok, "{args:?} succeeded");
        assert!(
            err.contains(needle),
            "{args:?}: the error does not name {needle}:\n{err}"
        );
        assert!(err.contains("error"), "{args:?}: no error line:\n{err}");
    }
    assert!(!out.exists(), "a failed run left {}", out.display());
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp-"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
}

#[test]
fn help_after_a_command_prints_usage_and_runs_nothing() {
    let dir = temp_dir("help");
    for flag in ["--help", "-h"] {
        let (ok, out, err) = common::voxgi_in(&dir, &["render", flag]);
        assert!(ok, "render {flag} failed:\n{err}");
        assert!(
            out.contains("voxgi render"),
            "render {flag} printed:\n{out}"
        );
    }
    let left: Vec<_> = std::fs::read_dir(&dir).unwrap().collect();
    assert!(left.is_empty(), "render --help wrote {left:?}");
}

#[test]
fn help_per_command_suggestions_and_one_error_line_with_status_1() {
    let (ok, out, err) = voxgi(&["help", "render"]);
    assert!(ok, "{err}");
    assert!(
        out.contains("voxgi render") && out.contains("--voxels") && out.contains("--no-tail"),
        "{out}"
    );
    for (args, want) in [
        (vec!["render", "--voxel", "32"], "--voxels"),
        (vec!["rendr"], "'render'"),
        (vec!["render", "--voxels", "2"], "4..=1024"),
        (vec!["render", "--mode", "sideways"], "the modes are"),
        (vec!["view", "--spin-speed", "10"], "--spin"),
    ] {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_voxgi"))
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(o.stdout.is_empty(), "{args:?} printed to stdout");
        assert_eq!(err.lines().count(), 1, "{args:?}: not one line:\n{err}");
        assert!(
            err.starts_with("voxgi: error: ") && err.contains(want),
            "{args:?}: {err}"
        );
    }
}

#[test]
fn validation_asked_for_without_its_layer_is_a_clear_error() {
    // The loader told to hide every layer (VK_LOADER_LAYERS_DISABLE): `--validate` cannot be
    // honoured, and the render stops before it writes anything.
    let dir = temp_dir("no-layer");
    let out = dir.join("x.exr");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_voxgi"))
        .args([
            "render",
            "--width",
            "32",
            "--height",
            "32",
            "--validate",
            "--out",
        ])
        .arg(&out)
        .env("VK_LOADER_LAYERS_DISABLE", "*")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "not one line:\n{err}");
    assert!(
        err.starts_with("voxgi: error: ") && err.contains("VK_LAYER_KHRONOS_validation"),
        "{err}"
    );
    assert!(!out.exists(), "an image was written");
}

/// Runs `voxgi render` at 32x32 under validation with `args` and `env`; returns the exit
/// status, stderr and whether an image was written.
fn render_failing(name: &str, args: &[&str], env: &[(&str, &str)]) -> (Option<i32>, String, bool) {
    let dir = temp_dir(name);
    let out = dir.join("x.exr");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_voxgi"))
        .args(["render", "--width", "32", "--height", "32", "--validate"])
        .args(args)
        .arg("--out")
        .arg(&out)
        .envs(env.iter().copied())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    (o.status.code(), err, out.exists())
}

#[test]
fn running_out_of_device_memory_is_a_clear_error_that_frees_everything() {
    // A budget that the shadow maps and images fit in and the 160^3 grid's volumes do not:
    // the allocation that fails names itself, the memory in use and the budget.
    let (code, err, wrote) =
        render_failing("oom", &["--voxels", "160", "--memory-budget", "250"], &[]);
    assert_eq!(code, Some(1), "{err}");
    let last = err.lines().last().unwrap();
    assert!(
        last.starts_with("voxgi: error: GPU memory allocation \"")
            && last.contains("voxel")
            && last.contains("of the --memory-budget 250.0 MiB: out of device memory"),
        "{err}"
    );
    // The device line, then the error: no validation message and no leak report.
    assert_eq!(err.lines().count(), 2, "{err}");
    assert!(!wrote, "an image was written");
}

#[test]
fn a_lost_device_is_a_clear_error_that_frees_everything() {
    // lavapipe cannot lose its device: a test hook fails a submission as a lost device's
    // would: the first (the scene's upload), the third, and the sixth (the second frame of the
    // antialiasing mean, after the renderer has made and used everything).
    for after in ["0", "2", "5"] {
        let (code, err, wrote) =
            render_failing("lost", &[], &[("VOXGI_TEST_LOSE_DEVICE_AFTER", after)]);
        assert_eq!(code, Some(1), "{err}");
        assert_eq!(err.lines().count(), 2, "{err}");
        assert!(
            err.lines()
                .last()
                .unwrap()
                .starts_with("voxgi: error: the Vulkan device was lost (vkQueueSubmit2"),
            "{err}"
        );
        assert!(!wrote, "an image was written");
    }
}

#[test]
fn completions_generate_for_each_shell_from_the_command_line() {
    for shell in ["bash", "zsh", "fish"] {
        let (ok, script, err) = voxgi(&["completions", shell]);
        assert!(ok, "{shell}: {err}");
        for word in [
            "render",
            "validation-sweep",
            "eye",
            "memory-budget",
            "spin-speed",
        ] {
            assert!(script.contains(word), "{shell}: no {word}");
        }
    }
    // The bash script parses and registers the completion.
    let (_, script, _) = voxgi(&["completions", "bash"]);
    let dir = temp_dir("completions");
    let path = dir.join("voxgi.bash");
    std::fs::write(&path, script).unwrap();
    let o = std::process::Command::new("bash")
        .arg("-c")
        .arg(format!("source {} && complete -p voxgi", path.display()))
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success() && out.contains("voxgi"), "{out}");
    let (ok, _, err) = voxgi(&["completions", "powershell"]);
    assert!(!ok && err.contains("powershell"), "{err}");
}

/// `voxgi` with extra environment variables. Returns (success, stderr).
fn voxgi_env(args: &[&str], env: &[(&str, &str)]) -> (bool, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_voxgi"))
        .args(args)
        .env_remove("RUST_LOG")
        .envs(env.iter().copied())
        .output()
        .expect("run voxgi");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "voxgi panicked:\n{stderr}");
    (out.status.success(), stderr)
}

#[test]
fn log_lines_follow_the_flags_and_rust_log_and_warnings_stay_warnings() {
    let dir = temp_dir("log");
    let unlit = common::animated_scene(&dir);
    let out = dir.join("out.png");
    let render = |scene: &std::path::Path, extra: &[&str], env: &[(&str, &str)]| {
        let mut args = vec![
            "render",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--width",
            "16",
            "--height",
            "16",
            "--voxels",
            "16",
            "--frames",
            "2",
        ];
        args.extend_from_slice(extra);
        let (ok, err) = voxgi_env(&args, env);
        assert!(ok, "voxgi {args:?} failed:\n{err}");
        err
    };
    let bundled = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/cornell-box.gltf");

    let plain = render(&bundled, &[], &[]);
    assert!(
        plain.contains("wrote ") && plain.contains("device: "),
        "{plain}"
    );
    assert!(
        !plain.contains("debug "),
        "debug lines without -v:\n{plain}"
    );

    let verbose = render(&bundled, &["-v"], &[]);
    assert!(
        verbose.contains("debug voxgi::scene::load: loaded ") && verbose.contains("wrote "),
        "-v shows no details:\n{verbose}"
    );
    assert!(!verbose.contains("trace "), "trace lines at -v:\n{verbose}");

    let traced = render(&bundled, &[], &[("RUST_LOG", "voxgi=trace")]);
    assert!(
        traced.contains("trace voxgi::render::renderer: frame of "),
        "RUST_LOG=voxgi=trace shows no frames:\n{traced}"
    );

    let quiet = render(&bundled, &["-q"], &[]);
    assert!(quiet.is_empty(), "-q printed more than warnings:\n{quiet}");

    // The scene has no light: a warning, printed as one, even under -q.
    for extra in [&[][..], &["-q"][..]] {
        let warned = render(&unlit, extra, &[]);
        assert!(
            warned
                .lines()
                .any(|l| l.starts_with("warning: ") && l.contains("no lights")),
            "no warning with {extra:?}:\n{warned}"
        );
    }
}

#[test]
fn progress_bars_are_drawn_on_a_terminal_only() {
    let dir = temp_dir("progress");
    let out = dir.join("out.png");
    let cmd = format!(
        "{} render --out {} --width 32 --height 32 --voxels 16 --frames 40",
        env!("CARGO_BIN_EXE_voxgi"),
        out.display()
    );
    // util-linux's `script` runs the command on a pseudo-terminal (Debian's essential bsdutils).
    let on_terminal = |extra: &str| {
        let out = std::process::Command::new("script")
            .args(["-qec", &format!("{cmd} {extra}"), "/dev/null"])
            .env_remove("RUST_LOG")
            .output()
            .expect("run util-linux's script (package bsdutils)");
        let text = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(out.status.success(), "{cmd} {extra} failed:\n{text}");
        text
    };
    let shown = on_terminal("");
    assert!(
        shown.contains("rendering, frames [") && shown.contains("/40"),
        "no progress bar on a terminal:\n{shown}"
    );
    let quiet = on_terminal("-q");
    assert!(
        !quiet.contains("rendering, frames"),
        "a bar under -q:\n{quiet}"
    );
    let args: Vec<&str> = cmd.split(' ').skip(1).collect();
    let (ok, piped) = voxgi_env(&args, &[]);
    assert!(ok, "{piped}");
    assert!(
        !piped.contains("rendering, frames") && piped.contains("wrote "),
        "a bar on a pipe:\n{piped}"
    );
}

/// `bench --help` names every axis a sweep can vary (each field of `GiSettings`).
#[test]
fn bench_help_names_every_sweep_axis() {
    let (ok, out, err) = voxgi(&["bench", "--help"]);
    assert!(ok, "bench --help failed:\n{err}");
    // The axes' list, its lines joined.
    let text = out.split_whitespace().collect::<Vec<_>>().join(" ");
    for f in voxgi::gi::FIELDS {
        assert!(
            text.contains(&format!(" {},", f.axis)) || text.contains(&format!(" {} ", f.axis)),
            "bench --help does not name the axis {}",
            f.axis
        );
    }
}

/// Output into a pipe nobody reads (`voxgi render --help | head -1` once head has gone) ends
/// the program quietly, as other tools do: no panic. The pipe's reading end is closed before
/// voxgi starts, so its first write fails.
#[test]
#[cfg(unix)]
fn output_into_a_closed_pipe_ends_quietly() {
    use std::os::unix::process::ExitStatusExt;
    for args in [&["render", "--help"][..], &["info", "--help"]] {
        let (reader, writer) = std::io::pipe().expect("pipe");
        drop(reader);
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_voxgi"))
            .args(args)
            .stdout(writer)
            .stderr(std::process::Stdio::piped())
            .output()
            .expect("run voxgi");
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert!(!stderr.contains("panicked"), "{args:?} panicked:\n{stderr}");
        assert_eq!(
            o.status.signal(),
            Some(libc::SIGPIPE),
            "{args:?}: ended by SIGPIPE"
        );
    }
}
