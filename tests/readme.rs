//! The README's commands, run as written (in a scratch directory, `../shared/` resolved beside
//! the repository, `view` in a virtual X screen for two frames), so that they cannot rot.

use std::path::{Path, PathBuf};
use std::process::Command;

/// The `voxgi ...` lines of the README's ```sh blocks, split into words (double quotes group).
fn readme_commands() -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md"))
        .expect("README.md");
    let mut commands = Vec::new();
    let mut in_sh = false;
    for line in text.lines() {
        let line = line.trim();
        if line.starts_with("```") {
            in_sh = !in_sh && line == "```sh";
            continue;
        }
        if in_sh && line.starts_with("voxgi ") {
            commands.push(words(line));
        }
    }
    commands
}

fn words(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut word = String::new();
    let mut quoted = false;
    for c in line.chars() {
        match c {
            '"' => quoted = !quoted,
            ' ' if !quoted => {
                if !word.is_empty() {
                    out.push(std::mem::take(&mut word));
                }
            }
            c => word.push(c),
        }
    }
    assert!(!quoted, "an unclosed quote in the README: {line}");
    if !word.is_empty() {
        out.push(word);
    }
    out
}

/// `../shared/...` as the repository's neighbour and `assets/...` as the repository's, so the
/// command runs from anywhere.
fn resolve(arg: &str) -> String {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    if let Some(rest) = arg.strip_prefix("../shared/") {
        return root.join("../shared").join(rest).display().to_string();
    }
    if let Some(rest) = arg.strip_prefix("assets/") {
        return root.join("assets").join(rest).display().to_string();
    }
    arg.to_string()
}

#[test]
fn the_readmes_commands_run_as_written() {
    let commands = readme_commands();
    let named: Vec<&str> = commands.iter().map(|c| c[1].as_str()).collect();
    for needed in ["render", "view", "reference", "compare", "bench"] {
        assert!(
            named.contains(&needed),
            "the README's quick start has no `voxgi {needed}`: {named:?}"
        );
    }
    let dir: PathBuf =
        Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("voxgi-readme-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for command in &commands {
        let args: Vec<String> = command[1..].iter().map(|a| resolve(a)).collect();
        let mut cmd = if args[0] == "view" {
            // Two frames in a virtual screen, then exit.
            let mut cmd = Command::new("xvfb-run");
            cmd.args([
                "-a",
                "-s",
                "-screen 0 1024x768x24",
                env!("CARGO_BIN_EXE_voxgi"),
            ])
            .args(&args)
            .args(["--frames", "2"]);
            cmd
        } else {
            let mut cmd = Command::new(env!("CARGO_BIN_EXE_voxgi"));
            cmd.args(&args);
            cmd
        };
        let out = cmd
            .current_dir(&dir)
            .env_remove("RUST_LOG")
            .output()
            .unwrap_or_else(|e| panic!("cannot run {}: {e}", command.join(" ")));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            out.status.success() && !stderr.contains("panicked"),
            "the README's `{}` failed:\n{stderr}",
            command.join(" ")
        );
        // What it says it writes is there.
        if let Some(k) = args.iter().position(|a| a == "--out") {
            let written = dir.join(&args[k + 1]);
            assert!(
                written.exists(),
                "`{}` wrote no {}",
                command.join(" "),
                written.display()
            );
        }
    }
}
