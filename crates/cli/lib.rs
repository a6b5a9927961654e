//! The `iasm` application: the commands behind the binary, callable from tests.
//!
//! - [`demo`]: `iasm demo`, the whole pipeline on a built-in simulated scene.
//! - [`ssl_cmd`]: `iasm ssl`, DoAs from WAV files or a data set, and their score.
//! - [`map_cmd`]: `iasm map` and `iasm eval`, I-ASM maps and their Monte Carlo OSPA.
//! - [`render`]: the map picture.
//! - [`simulate`]: `iasm simulate`, a scene file rendered into a data set.
//! - [`regress`]: `iasm regress`, the synthetic-room regression suite.
//! - [`dataset`]: the published data-set layout, tables and natural file order.
//! - [`score`]: the DoA score against known sources.

pub mod args;
pub mod dataset;
pub mod demo;
pub mod map_cmd;
pub mod regress;
pub mod render;
pub mod score;
pub mod simulate;
pub mod ssl_cmd;

/// How a command ended when it did not fail outright.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outcome {
    /// Everything ran and every threshold held: exit 0.
    Success,
    /// Everything ran but a threshold was not met: exit 1.
    ThresholdFailed,
}

/// Runs a parsed command line.
///
/// # Errors
/// Any failure, with the file and the problem in its context chain (exit 2).
pub fn run(cli: &args::Cli) -> anyhow::Result<Outcome> {
    match &cli.command {
        args::Command::Ssl(a) => {
            set_threads(a.threads);
            ssl_cmd::run(a)
        }
        args::Command::Demo { seed, png } => demo::run(*seed, png),
        args::Command::Map(a) => map_cmd::run_map(a),
        args::Command::Simulate {
            scene,
            out,
            threads,
        } => {
            set_threads(*threads);
            simulate::run(scene, out)
        }
        args::Command::Regress { dir, json } => regress::run(dir, *json),
        args::Command::Eval(a) => {
            set_threads(a.threads);
            map_cmd::run_eval(a)
        }
    }
}

/// Sizes the worker pool for `--threads N` (all cores when not given). Only the first call
/// in a process can size rayon's global pool; later ones keep it.
fn set_threads(threads: Option<usize>) {
    if let Some(t) = threads {
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(t)
            .build_global();
    }
}

/// A progress bar on stderr, drawn only when stderr is a terminal.
pub fn progress(len: u64, what: &str) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} {elapsed}")
            .expect("a valid template")
            .progress_chars("=> "),
    );
    bar.set_message(what.to_owned());
    bar
}
