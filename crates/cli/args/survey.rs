//! The arguments of the commands that localise and map a survey: `ssl`, `map`, `eval`
//! and `compare`, and how they report and draw.

use std::path::PathBuf;

use asm::Variant;
use clap::Args;

use super::inputs::{InputArgs, SettingsArgs};

/// `iasm compare`.
#[derive(Debug, Clone, Args)]
pub struct CompareArgs {
    /// A data set folder in the published layout, with ground truth (src_gt*).
    #[arg(long, value_name = "DIR")]
    pub dataset: PathBuf,
    /// The methods: all, or a comma-separated list (gcc-phat, mvdr, srp-phat, music,
    /// normmusic, tops, cssm, waves).
    #[arg(long, default_value = "all")]
    pub methods: String,
    /// Maps per method (seeds seed..seed + runs).
    #[arg(long, default_value_t = 20)]
    pub runs: usize,
    /// The first seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Write report.json, report.csv and the figures (ospa.svg, error_by_distance.svg,
    /// maps.svg) into this folder (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Without an occupancy map in the data set: how far from the stops to search for
    /// sources (m; default 3), as for `map`.
    #[arg(long, value_name = "M")]
    pub open_margin: Option<f64>,
    /// Also say, per method, why the sources within 3 m that no DoA found were missed (no
    /// peak there, N, the thresholds) and what N raised to 4N would add, as `iasm ssl
    /// --score --rules` does: six more localisations per recording and method.
    #[arg(long)]
    pub rules: bool,
    /// A DoA table of another tool on the same recordings (one row per recording in the
    /// audio's order, N azimuths in degrees in the array frame, strongest first; CSV or
    /// .xlsx, as `iasm ssl --out` writes and `scripts/pra_doa_tables.py` writes for
    /// pyroomacoustics' methods): a row beside ours, scored and mapped the same way.
    /// Repeatable; the row is named after the file.
    #[arg(long = "table", value_name = "FILE")]
    pub tables: Vec<PathBuf>,
    /// The settings (the method is each row's own).
    #[command(flatten)]
    pub settings: SettingsArgs,
    /// Output and metric.
    #[command(flatten)]
    pub report: ReportArgs,
}

/// How `map` and `eval` report: the format and the OSPA metric's parameters.
#[derive(Debug, Clone, Args)]
pub struct ReportArgs {
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// OSPA order p.
    #[arg(long, default_value_t = 1.0, value_parser = super::inputs::parse_ospa_p)]
    pub ospa_p: f64,
    /// OSPA cutoff c (m).
    #[arg(long, default_value_t = 1.0, value_parser = super::inputs::parse_ospa_c)]
    pub ospa_c: f64,
}

/// `iasm map`.
#[derive(Debug, Clone, Args)]
pub struct MapArgs {
    /// The inputs.
    #[command(flatten)]
    pub input: InputArgs,
    /// Variant: ca (full I-ASM), ws (weighted sum) or wdp (no distance penalty)
    /// [default: ca, or the settings file's].
    #[arg(long)]
    pub variant: Option<Variant>,
    /// Seed of the particle filter.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Write the map as JSON here.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Write the sources as CSV here.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Write the map as ROS 2 messages to this MCAP file (frame `map`): source markers with
    /// their 2-sigma ellipses and labels, each stop's DoA rays, the trajectory, the occupancy
    /// map and the sources as poses; Foxglove opens it, `ros2 bag play` sends it to RViz.
    #[arg(long, value_name = "FILE")]
    pub mcap: Option<PathBuf>,
    /// Draw the map here: PNG or SVG by the file's extension (axes in metres, legend, title).
    #[arg(long, value_name = "FILE", visible_alias = "figure")]
    pub png: Option<PathBuf>,
    /// Write the truth moved into the map's frame here (the inverse of the best similarity
    /// transform of the map onto the truth; the src_gt text format), to score DoAs against
    /// with `iasm ssl --score --truth FILE`: where the poses' and the truth's frames
    /// disagree, the DoAs are then judged in the frame they were heard in. Fit it to a map
    /// from other DoAs than those you score (e.g. a published table), or the score is
    /// partly of the fit.
    #[arg(long, value_name = "FILE")]
    pub write_aligned_truth: Option<PathBuf>,
    /// Also say why the map holds what it holds: the DoAs each source explains (stop,
    /// azimuth, miss), the DoAs no source explains, and, with ground truth, where the DoAs
    /// of each true source the map missed went (unheard, taken by another source, or
    /// left unexplained). In JSON: the `explain` object
    #[arg(long)]
    pub explain: bool,
    /// Also say what each source sounds like, from the recordings of the stops that heard
    /// it (the array steered at its map position): its spectrum, level (dB relative to the
    /// loudest source), steadiness, dominant band and a kind (speech, tonal or broadband).
    /// Needs one recording per stop (a data set's audio/ or --audio). In JSON: each
    /// source's `signature`; in the table, the figure's legend and the MCAP's labels: its
    /// kind
    #[arg(long)]
    pub signatures: bool,
    /// How the map is drawn.
    #[command(flatten)]
    pub figure: FigureArgs,
    /// Output and metric.
    #[command(flatten)]
    pub report: ReportArgs,
}

/// How a map figure is drawn.
#[derive(Debug, Clone, Copy, Args)]
pub struct FigureArgs {
    /// Draw the whole occupancy map [default: crop to the trajectory and the sources, with a
    /// margin].
    #[arg(long)]
    pub full_map: bool,
    /// Width of the figure in pixels (the height follows the region's aspect; text scales
    /// with it: 2000 for print at 200 dpi and 10 inches).
    #[arg(long, value_name = "PX", default_value_t = 1000,
          value_parser = clap::value_parser!(u32).range(200..=8000))]
    pub figure_width: u32,
}

/// `iasm eval`.
#[derive(Debug, Clone, Args)]
pub struct EvalArgs {
    /// The inputs.
    #[command(flatten)]
    pub input: InputArgs,
    /// Runs per variant (seeds seed..seed+runs).
    #[arg(long, default_value_t = 50)]
    pub runs: usize,
    /// First seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output and metric.
    #[command(flatten)]
    pub report: ReportArgs,
    /// Exit with status 1 if CA's mean OSPA is above this (m).
    #[arg(long, value_name = "M")]
    pub max_mean_ospa: Option<f64>,
    /// Exit with status 1 if CA's matched sources lie further than this (m, mean over the
    /// runs) from the truth after each map's best similarity transform onto it, or if no
    /// run matched three sources: the map's own accuracy, whatever the poses' and the
    /// truth's frames.
    #[arg(long, value_name = "M")]
    pub max_aligned: Option<f64>,
    /// Exit with status 1 unless WS and WDP both have a higher mean OSPA than CA.
    #[arg(long)]
    pub expect_ablation: bool,
    /// Worker threads (default: all cores).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
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
    /// The settings.
    #[command(flatten)]
    pub settings: SettingsArgs,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// With --dataset: write the DoA table (one row per recording, N azimuths in degrees,
    /// array frame, empty cells where fewer peaks were found) to this CSV file.
    #[arg(
        long,
        value_name = "FILE",
        requires = "dataset",
        conflicts_with = "files"
    )]
    pub out: Option<PathBuf>,
    /// With --out: write a header line first.
    #[arg(long, requires = "out", conflicts_with = "files")]
    pub header: bool,
    /// With --dataset: score the DoAs against the data set's poses and ground truth (and
    /// score the published tables in `azimuth/` beside them).
    #[arg(long, requires = "dataset", conflicts_with = "files")]
    pub score: bool,
    /// With --score: a DoA within this many degrees of a true source's bearing is a hit.
    #[arg(long, default_value_t = 5.0, value_name = "DEG")]
    pub tol_deg: f64,
    /// With --score: also print where the DoAs fail, for ours and the published tables:
    /// errors by the source's distance from the robot, bias towards the heading axis, and
    /// the recall of sources within 3 m.
    #[arg(long, requires = "score")]
    pub by_distance: bool,
    /// With --score: also print which of the SSL's rules left out each source within 3 m
    /// that no DoA found (no peak there at all, N, height, coherence, prominence,
    /// sidelobe, significance), and which let in each DoA that found no source (height,
    /// block votes, incoherence), and what N raised to 4N would add. With --json, every
    /// missed pair is listed with its stop, source, distance and reason. Localises every
    /// recording six times, each time with one rule off (see `iasm::rules`).
    #[arg(long, requires = "score")]
    pub rules: bool,
    /// With --score: ground-truth source positions to score against instead of the data
    /// set's src_gt* (e.g. the truth moved into the poses' frame by `iasm map
    /// --write-aligned-truth`).
    #[arg(long, value_name = "FILE", requires = "score")]
    pub truth: Option<PathBuf>,
    /// With --score: exit with status 1 if the score is below this.
    #[arg(long, value_name = "SCORE", requires = "score")]
    pub min_score: Option<f64>,
    /// With --score: exit with status 1 if the score is below that of the published table
    /// of the same method (`azimuth/*<METHOD>*`).
    #[arg(long, requires = "score")]
    pub beat_published: bool,
    /// Worker threads for --dataset (default: all cores).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
}
