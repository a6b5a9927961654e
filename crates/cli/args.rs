//! Command-line arguments (clap derive). Turning them into validated settings happens in
//! the command modules, so that the library stays callable without a command line.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

/// iasm: from a robot's multichannel recordings to a map of the sound sources around it.
#[derive(Debug, Parser)]
#[command(name = "iasm", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands. (Parsed once per process: the size difference between variants is
/// irrelevant, so they are not boxed.)
#[derive(Debug, Subcommand)]
#[allow(clippy::large_enum_variant)]
pub enum Command {
    /// Render a built-in scene, localise it with every method, and compare with the truth.
    Demo {
        /// Seed of the scene's signals and noise.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// Directions of arrival from multichannel WAV files (or a whole data set).
    Ssl(SslArgs),
}

/// `iasm ssl`.
#[derive(Debug, Clone, Args)]
pub struct SslArgs {
    /// WAV files to localise (one recording each).
    #[arg(required_unless_present = "dataset", conflicts_with = "dataset")]
    pub files: Vec<PathBuf>,
    /// A data set folder: localises every `DIR/audio/*.wav` in natural name order.
    #[arg(long, value_name = "DIR")]
    pub dataset: Option<PathBuf>,
    /// Microphone array: a preset (iasm6, respeaker4, respeaker6, uma8) or a TOML/JSON file.
    #[arg(long, default_value = "iasm6")]
    pub array: String,
    /// Angular-spectrum method: gcc-phat or mvdr [default: mvdr, or the config file's].
    #[arg(long)]
    pub method: Option<String>,
    /// Number of DoAs per recording, strongest first [default: 4, or the config file's].
    #[arg(long, value_name = "N")]
    pub num: Option<usize>,
    /// A TOML file of SSL settings (the `ssl::SslConfig` fields); flags override it.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Lower edge of the analysis band (Hz).
    #[arg(long)]
    pub fmin: Option<f64>,
    /// Upper edge of the analysis band (Hz).
    #[arg(long)]
    pub fmax: Option<f64>,
    /// Frames per pooling block.
    #[arg(long)]
    pub block_frames: Option<usize>,
    /// Block pooling: max or mean.
    #[arg(long)]
    pub pooling: Option<String>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// With --dataset: write the DoA table (one row per recording, N azimuths in degrees,
    /// array frame, empty cells where fewer peaks were found) to this CSV file.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// With --out: write a header line first.
    #[arg(long)]
    pub header: bool,
    /// With --dataset: score the DoAs against the data set's poses and ground truth (and
    /// score the published tables in `azimuth/` beside them).
    #[arg(long)]
    pub score: bool,
    /// With --score: a DoA within this many degrees of a true source's bearing is a hit.
    #[arg(long, default_value_t = 5.0, value_name = "DEG")]
    pub tol_deg: f64,
    /// With --score: exit with status 1 if the score is below this.
    #[arg(long, value_name = "SCORE")]
    pub min_score: Option<f64>,
    /// With --score: exit with status 1 if the score is below that of the published table
    /// of the same method (`azimuth/*<METHOD>*`).
    #[arg(long)]
    pub beat_published: bool,
    /// Worker threads for --dataset (default: all cores).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
}
