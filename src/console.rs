//! What voxgi writes to the terminal besides a command's output: log lines (the `log` crate,
//! printed by env_logger) and progress bars (indicatif). Both go to stderr through one
//! `MultiProgress`, so that a log line printed while a bar is drawn does not tear it.
//!
//! Levels: errors and warnings always (`warning: ...`), what a command did at info (`wrote
//! out.exr`, `device: ...`), details at debug (`-v`) and trace (`-vv`); `-q` keeps warnings and
//! errors only. `RUST_LOG` overrides the flags (env_logger's syntax, e.g. `RUST_LOG=voxgi=debug`).
//! Bars are drawn only when stderr is a terminal and info is shown.

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressFinish, ProgressStyle};
use std::io::{IsTerminal, Write};
use std::sync::OnceLock;
use std::time::Duration;

fn multi() -> &'static MultiProgress {
    static MULTI: OnceLock<MultiProgress> = OnceLock::new();
    MULTI.get_or_init(|| MultiProgress::with_draw_target(ProgressDrawTarget::stderr()))
}

/// The filter for a verbosity: `-q` is -1, nothing 0, `-v` 1, `-vv` 2. Other crates log
/// warnings only, unless traced.
pub fn filter_for(verbosity: i8) -> &'static str {
    match verbosity {
        i8::MIN..=-1 => "warn",
        0 => "warn,voxgi=info",
        1 => "warn,voxgi=debug",
        _ => "trace",
    }
}

/// Installs the logger; call once, first thing in `main`. A second call does nothing.
pub fn init_logging(verbosity: i8) {
    let env = env_logger::Env::default().default_filter_or(filter_for(verbosity));
    let inner = env_logger::Builder::from_env(env)
        .format(|buf, record| {
            let args = record.args();
            match record.level() {
                log::Level::Error => writeln!(buf, "error: {args}"),
                log::Level::Warn => writeln!(buf, "warning: {args}"),
                log::Level::Info => writeln!(buf, "{args}"),
                level => writeln!(
                    buf,
                    "{} {}: {args}",
                    level.as_str().to_lowercase(),
                    record.target()
                ),
            }
        })
        .build();
    let max = inner.filter();
    if log::set_boxed_logger(Box::new(BesideBars { inner })).is_ok() {
        log::set_max_level(max);
    }
}

/// env_logger's output, printed with the bars lifted off the terminal.
struct BesideBars {
    inner: env_logger::Logger,
}

impl log::Log for BesideBars {
    fn enabled(&self, metadata: &log::Metadata) -> bool {
        self.inner.enabled(metadata)
    }

    fn log(&self, record: &log::Record) {
        if self.inner.matches(record) {
            multi().suspend(|| self.inner.log(record));
        }
    }

    fn flush(&self) {
        self.inner.flush();
    }
}

/// Whether a bar would be drawn: stderr is a terminal and voxgi's info lines are shown.
pub fn bars_shown() -> bool {
    log::log_enabled!(target: "voxgi", log::Level::Info) && std::io::stderr().is_terminal()
}

/// A progress bar of `len` steps labelled `what`, hidden where bars are not shown. It draws
/// the steps done, the elapsed time and an estimate of the time left, until dropped.
pub fn bar(len: u64, what: &str) -> ProgressBar {
    if !bars_shown() {
        return ProgressBar::hidden();
    }
    // Cleared when dropped: what stays on the terminal is the log lines.
    let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::hidden())
        .with_finish(ProgressFinish::AndClear);
    bar.set_style(
        ProgressStyle::with_template("{msg} [{bar:32}] {pos}/{len} {elapsed}, {eta} left")
            .expect("a valid progress template")
            .progress_chars("#>."),
    );
    bar.set_message(what.to_string());
    let bar = multi().add(bar);
    bar.enable_steady_tick(Duration::from_millis(250));
    bar
}
