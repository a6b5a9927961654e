//! The arguments of the generated benchmark (`iasm regress --generated`) and of
//! `iasm scenes generate`.

use std::path::PathBuf;

use clap::{Args, Subcommand};

/// The draw: which seeds, how many renderings and maps, which talkers.
#[derive(Debug, Args)]
pub struct DrawArgs {
    /// How many scenes: seeds SEED, SEED + 1, ...
    #[arg(long, default_value_t = 100)]
    pub count: u64,
    /// The first seed. Choose defaults on seeds 0-99 (the tuning draw) and report them on
    /// 1000-1099 (the judging draw), never the other way round.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// A folder of talkers' recordings (mono WAV at 16 kHz). Default: fixtures/audio when
    /// it is there, else speech-shaped noise.
    #[arg(long, value_name = "DIR")]
    pub talkers: Option<PathBuf>,
    /// Draw changes too: in three scenes of four one source falls silent, one starts, or
    /// a talker walks 2-3 m to another place, in the middle third of the run (the scenes
    /// are otherwise those of the same seeds without it).
    #[arg(long)]
    pub changes: bool,
}

/// `iasm regress --generated` and its options.
#[derive(Debug, Args)]
pub struct GeneratedArgs {
    /// Run scenes drawn at random instead of a folder's.
    #[arg(long)]
    pub generated: bool,
    /// The draw.
    #[command(flatten)]
    pub draw: DrawArgs,
    /// Renderings of each scene (other signals, sensor noise and late tail).
    #[arg(long, default_value_t = 2, requires = "generated")]
    pub renderings: usize,
    /// Maps of each rendering per method (other particle draws).
    #[arg(long, default_value_t = 3, requires = "generated")]
    pub map_seeds: usize,
    /// Map from true bearings only, rendering nothing: the mapper's own loss over many
    /// scenes in seconds.
    #[arg(long, requires = "generated")]
    pub floor_only: bool,
    /// Also print every scene's row, worst first.
    #[arg(long, requires = "generated")]
    pub scenes: bool,
    /// Fail (exit 1) when a method's mean OSPA over the draw exceeds this (m).
    #[arg(long, value_name = "M", requires = "generated")]
    pub max_mean_ospa: Option<f64>,
    /// Fail when a method's 90th percentile of OSPA exceeds this (m).
    #[arg(long, value_name = "M", requires = "generated")]
    pub max_p90_ospa: Option<f64>,
    /// Fail when a method's share of maps with the right count is below this (0-1).
    #[arg(long, value_name = "SHARE", requires = "generated")]
    pub min_right_count: Option<f64>,
    /// Fail when a method maps more than this many sources outside the walls, in all.
    #[arg(long, value_name = "K", requires = "generated")]
    pub max_outside: Option<usize>,
}

/// `iasm scenes ...`.
#[derive(Debug, Subcommand)]
pub enum ScenesCommand {
    /// Write drawn scenes as scene files (with `[expect] num`, the N drawn), which `iasm
    /// simulate` renders and `iasm regress DIR` runs; the talkers' recordings are copied
    /// beside them.
    Generate {
        /// The draw.
        #[command(flatten)]
        draw: DrawArgs,
        /// The folder to write (created; existing scene files of the same names are
        /// replaced).
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
    },
}
