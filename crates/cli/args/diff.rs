//! `iasm diff`'s arguments.

use std::path::PathBuf;

use asm::diff::DiffConfig;
use clap::Args;

/// `iasm diff`: two maps of one building compared.
#[derive(Debug, Clone, Args)]
pub struct DiffArgs {
    /// The earlier map (JSON of `iasm map --out`, `iasm watch --out` or the live node's
    /// saved map).
    pub before: PathBuf,
    /// The later map, in the same frame.
    pub after: PathBuf,
    /// Each map's position error beyond its covariance (m, a standard deviation per axis).
    #[arg(long, value_name = "M", default_value_t = DiffConfig::default().floor_m,
          value_parser = parse_floor_m)]
    pub floor_m: f64,
    /// How sure a kept source's displacement must be to lie within the gate: two positions
    /// are one place while the chance of so large a difference is at least 1 - this.
    #[arg(long, value_name = "P", default_value_t = DiffConfig::default().same_p,
          value_parser = parse_same_p)]
    pub same_p: f64,
    /// The furthest a source is taken to have moved (m); beyond, one was removed and
    /// another added (0: never moved).
    #[arg(long, value_name = "M", default_value_t = DiffConfig::default().move_max_m,
          value_parser = parse_move_max_m)]
    pub move_max_m: f64,
    /// Write the comparison as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Draw both maps and what changed: PNG or SVG by the file's extension.
    #[arg(long, value_name = "FILE")]
    pub png: Option<PathBuf>,
    /// The occupancy map (map_server YAML) to draw under the figure.
    #[arg(long, value_name = "YAML")]
    pub map: Option<PathBuf>,
    /// Width of the figure in pixels.
    #[arg(long, value_name = "PX", default_value_t = 1000,
          value_parser = clap::value_parser!(u32).range(200..=8000))]
    pub figure_width: u32,
}

/// A value of one [`DiffConfig`] field, in the range [`DiffConfig::check`] asks: the library
/// says what is in range, and clap names the flag.
fn checked(text: &str, set: impl Fn(&mut DiffConfig, f64)) -> Result<f64, String> {
    let v: f64 = text.parse().map_err(|e| format!("{e}"))?;
    let mut c = DiffConfig::default();
    set(&mut c, v);
    c.check().map(|()| v)
}

fn parse_floor_m(text: &str) -> Result<f64, String> {
    checked(text, |c, v| c.floor_m = v)
}

fn parse_same_p(text: &str) -> Result<f64, String> {
    checked(text, |c, v| c.same_p = v)
}

fn parse_move_max_m(text: &str) -> Result<f64, String> {
    checked(text, |c, v| c.move_max_m = v)
}
