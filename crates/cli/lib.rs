//! The `iasm` application: the pipeline that joins the libraries, and the commands behind
//! the binary, callable from tests.
//!
//! The library modules a researcher calls from Rust, which the commands use and never the
//! other way round:
//!
//! - [`pipeline`]: the one place where recordings become DoAs and DoAs become a map
//!   ([`pipeline::Survey`], [`pipeline::Simulated`], [`pipeline::evaluate`]).
//! - [`settings`]: one [`settings::Settings`] (SSL, I-ASM, array) from one TOML file.
//! - [`dataset`]: the published data-set layout, tables, poses, maps, natural file order.
//! - [`scenes`]: scene files (with the suite's `[expect]`), and writing a rendered scene.
//! - [`suite`]: the synthetic-room regression suite.
//! - [`generated`]: the benchmark of scenes drawn at random, beside true bearings.
//! - [`score`]: the DoA score against known sources.
//! - [`rules`]: which SSL rule left each missed near source out, and let each false DoA in.
//! - [`explain`]: which DoAs each source of a map explains, which none does, and where a
//!   missed true source's DoAs went.
//! - [`live`]: the live mapper behind `iasm ros2`, a robot's messages in, a map out.
//! - [`mapfile`]: a map's JSON read back (positions, covariances, states), for `iasm
//!   diff` and the live node's prior.
//! - [`merge`]: the merging mapper behind `iasm ros2-merge`, several robots' stops in, one
//!   building's map out.
//!
//! Inside, for the commands only: `compare` (every SSL method side by side), `figure`
//! (PNG and SVG), `online` (mapping while the robot records: a session, a folder
//! follower), `robot_noise` (the recording of the robot alone), `rosmap` (a map as ROS 2
//! messages), `bagset` (a bag as a data set), `output` (files written whole: a temporary
//! name, then a rename), `args` (the command line), and `cmd`, the commands, one module
//! each (`ssl`, `map`, `diff`, `eval`, `compare`, `simulate`, `regress`, `demo`, `watch`, `bag`,
//! `ros2`); none imports another. [`main`] runs the command line.
//!
//! Where these docs say why a default is what it is, they state the measurement that chose
//! it; `docs/decisions/` holds the decisions, `BENCHMARKS.md` today's figures and git the
//! history (the development journal: `git show 7ee1616:BENCHMARKS.md`).
//!
//! The pipeline from Rust, end to end: a scene rendered by the image-source method (one
//! talker at (3.5, 3.2) m, a robot passing it), every stop localised with MVDR and the stops
//! mapped by I-ASM, as `iasm simulate` and then `iasm map` do.
//!
//! ```
//! use iasm::pipeline::{Simulated, scene_settings};
//! use iasm::scenes::{parse_scene, prepare};
//! use iasm::settings::Settings;
//!
//! # fn main() -> anyhow::Result<()> {
//! let (scene, _) = parse_scene(include_str!("../../fixtures/rooms/one_source.toml"))?;
//! let simulated = Simulated::render(prepare(scene)?, "one source".into())?;
//! let settings = scene_settings(&Settings::default(), ssl::Method::Mvdr, 3);
//! let run = simulated.run(&settings, 1)?;
//! assert_eq!(run.map.sources.len(), 1);
//! let s = &run.map.sources[0];
//! assert!((s.x - 3.5).hypot(s.y - 3.2) < 0.05, "{s:?}");
//! # Ok(())
//! # }
//! ```

pub(crate) mod args;
pub(crate) mod bagset;
pub mod changes;
pub(crate) mod cmd;
pub(crate) mod compare;
pub mod dataset;
pub mod explain;
pub(crate) mod figure;
pub mod generated;
pub mod live;
pub mod mapfile;
pub mod merge;
pub(crate) mod online;
pub(crate) mod output;
pub mod pipeline;
pub(crate) mod robot_noise;
pub(crate) mod rosmap;
pub mod rules;
pub mod scenes;
pub mod score;
pub mod settings;
pub mod suite;

/// How a command ended when it did not fail outright.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Outcome {
    /// Everything ran and every threshold held: exit 0.
    Success,
    /// Everything ran but a threshold was not met: exit 1.
    ThresholdFailed,
}

/// The `iasm` command line: parses the process's arguments, runs the command and reports
/// the outcome as an exit status (0 success, 1 a threshold failed, 2 an error, its file
/// and problem on stderr).
pub fn main() -> std::process::ExitCode {
    #[cfg(feature = "ros2")]
    let cli = args::parse_from(std::env::args_os().collect()).unwrap_or_else(|e| e.exit());
    #[cfg(not(feature = "ros2"))]
    let cli = <args::Cli as clap::Parser>::parse();
    match run(&cli) {
        Ok(Outcome::Success) => std::process::ExitCode::SUCCESS,
        Ok(Outcome::ThresholdFailed) => std::process::ExitCode::from(1),
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::from(2)
        }
    }
}

/// Runs a parsed command line.
///
/// # Errors
/// Any failure, with the file and the problem in its context chain (exit 2).
fn run(cli: &args::Cli) -> anyhow::Result<Outcome> {
    match &cli.command {
        args::Command::Ssl(a) => {
            set_threads(a.threads);
            cmd::ssl::run(a)
        }
        args::Command::Demo {
            seed,
            png,
            mcap,
            figure,
        } => cmd::demo::run(*seed, png, mcap.as_deref(), figure),
        args::Command::Map(a) => cmd::map::run(a),
        args::Command::Diff(a) => cmd::diff::run(a),
        #[cfg(feature = "ros2")]
        args::Command::Ros2(a) => cmd::ros2::run(a),
        #[cfg(feature = "ros2")]
        args::Command::Ros2Play(a) => cmd::ros2::play(a),
        #[cfg(feature = "ros2")]
        args::Command::Ros2Call(a) => cmd::ros2::call_node(a),
        #[cfg(feature = "ros2")]
        args::Command::Ros2Merge(a) => cmd::ros2::merge(a),
        args::Command::Simulate {
            scene,
            out,
            threads,
            force,
        } => {
            set_threads(*threads);
            cmd::simulate::run(scene, out, *force)
        }
        args::Command::Regress {
            dir,
            config,
            num,
            json,
            generated,
        } => {
            let settings = settings::Settings::load(config.as_deref())?;
            anyhow::Context::with_context(settings.validate(), || match config {
                Some(p) => format!("settings {}", p.display()),
                None => "the default settings".to_owned(),
            })?;
            if generated.generated {
                anyhow::ensure!(num.is_none(), "--num: a drawn scene's N is drawn with it");
                cmd::regress::run_generated(generated, &settings, *json)
            } else {
                cmd::regress::run(dir, &settings, *num, *json)
            }
        }
        args::Command::Scenes {
            command: args::ScenesCommand::Generate { draw, out },
        } => cmd::scenes::generate(&draw_options(draw, 1, 1, false)?, out),
        args::Command::Eval(a) => {
            set_threads(a.threads);
            cmd::eval::run(a)
        }
        args::Command::Compare(a) => {
            set_threads(a.threads);
            cmd::compare::run(a)
        }
        args::Command::Watch(a) => cmd::watch::run(a),
        args::Command::Bag(a) => cmd::bag::run(a),
    }
}

/// The draw of `iasm regress --generated` and `iasm scenes generate`.
fn draw_options(
    a: &args::DrawArgs,
    renderings: usize,
    map_seeds: usize,
    floor_only: bool,
) -> anyhow::Result<generated::DrawOptions> {
    let end = a.seed.checked_add(a.count).ok_or_else(|| {
        anyhow::anyhow!("--seed {} --count {}: beyond the seeds", a.seed, a.count)
    })?;
    anyhow::ensure!(a.count >= 1, "--count: at least one scene");
    Ok(generated::DrawOptions {
        seeds: a.seed..end,
        renderings,
        map_seeds,
        talkers: cmd::scenes::talkers(a.talkers.as_deref())?,
        floor_only,
        changes: a.changes,
    })
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
pub(crate) fn progress(len: u64, what: &str) -> indicatif::ProgressBar {
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
