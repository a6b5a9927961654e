//! What every command reads the same way: the settings (one file, then the flags given),
//! where a survey's inputs come from, and the `--channels` list.

use std::path::PathBuf;

use anyhow::{Context, Result};
use asm::Profile;
use clap::{Args, ValueEnum};
use ssl::{Method, Pooling};

use crate::pipeline::SurveyInputs;
use crate::settings::Settings;

/// The settings every command reads the same way: one file, then the flags that were given.
#[derive(Debug, Clone, Default, Args)]
pub struct SettingsArgs {
    /// A settings file (TOML): `[ssl]` (the `ssl::SslConfig` fields), `[iasm]` (the
    /// `asm::IasmConfig` fields), `array`, `channels` and `noise`. Flags given here
    /// override it.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Microphone array: a preset (iasm6, respeaker4, respeaker6, uma8) or a TOML/JSON
    /// file [default: iasm6, or the settings file's].
    #[arg(long)]
    pub array: Option<String>,
    /// Which channels of each WAV are the array's microphones, in the array's order,
    /// counted from 1: a list and ranges, `2-5` or `2,3,4,5` (a ReSpeaker 4-mic's
    /// 6-channel firmware records its microphones on channels 2-5) [default: every
    /// channel, or the settings file's `channels`].
    #[arg(long, value_name = "LIST", value_parser = parse_channels)]
    pub channels: Option<ChannelList>,
    /// A recording of the robot alone (WAV: its fans running, no other source, a few
    /// seconds, the same microphones and channels as the recordings): the robot's own
    /// noise is subtracted from every statistic of the SSL (see `ssl::noise`) [default:
    /// the settings file's `noise`, or the one WAV in the data set's noise/ folder].
    #[arg(long, value_name = "WAV")]
    pub noise: Option<PathBuf>,
    /// Angular-spectrum method: gcc-phat, mvdr, srp-phat, music, normmusic, tops, cssm or waves [default:
    /// mvdr, or the settings file's].
    #[arg(long)]
    pub method: Option<Method>,
    /// N, the DoAs per stop, strongest first, for the SSL and the mapper alike
    /// [default: 4, or the settings file's].
    #[arg(long, value_name = "N")]
    pub num: Option<usize>,
    /// Lower edge of the analysis band (Hz).
    #[arg(long)]
    pub fmin: Option<f64>,
    /// Upper edge of the analysis band (Hz).
    #[arg(long)]
    pub fmax: Option<f64>,
    /// Frames per pooling block.
    #[arg(long)]
    pub block_frames: Option<usize>,
    /// Block pooling: auto (the default: the mean for a recording whose sound is steady and
    /// noise-like in every octave, max for any other; see `ssl::steady`), max or mean.
    #[arg(long)]
    pub pooling: Option<Pooling>,
    /// With max pooling: keep the mean of each direction's K largest block values
    /// (1, the default, is the plain maximum; see `ssl::SslConfig::pool_top`).
    #[arg(long, value_name = "K")]
    pub pool_top: Option<usize>,
    /// With max pooling: place each DoA that was the strongest direction of a block at the
    /// peak of the mean of its best SHARE of the blocks, within half the minimum
    /// separation (0 keeps the pooled peak's azimuth; default 0.25; see
    /// `ssl::SslConfig::placement_share`).
    #[arg(long, value_name = "SHARE")]
    pub placement_share: Option<f64>,
    /// Refine each weaker DoA of a row with the stronger ones projected out (deflation),
    /// whatever the array [default: on for a compact array, whose far-field distance at
    /// the band's top is under 1 m, such as a ReSpeaker; see `ssl::SslConfig::deflate`]
    #[arg(long, conflicts_with = "no_deflate")]
    pub deflate: bool,
    /// Never deflate, not even for a compact array (see --deflate).
    #[arg(long)]
    pub no_deflate: bool,
    /// I-ASM profile: paper (the paper's algorithm exactly, Table I) or robust (bearing
    /// refinement, three observing stops per source, a vote for missed sources, no source
    /// on the robot's path, contradicted by stops that heard nothing, outside the room,
    /// heard through a wall as another's image, or made of another's reflections in the
    /// map's walls) [default: robust, or the settings file's].
    #[arg(long)]
    pub profile: Option<Profile>,
}

impl SettingsArgs {
    /// The settings file (or the defaults) with the given flags applied, validated.
    ///
    /// # Errors
    /// An unreadable or refused file, or a refused value.
    pub fn settings(&self) -> Result<Settings> {
        let mut s = Settings::load_with(self.config.as_deref(), self.profile)?;
        if let Some(a) = &self.array {
            s.array = Some(a.clone());
        }
        if let Some(ChannelList(c)) = &self.channels {
            s.channels = Some(c.clone());
        }
        if let Some(n) = &self.noise {
            s.noise = Some(n.clone());
        }
        if let Some(m) = self.method {
            s.ssl.method = m;
        }
        if let Some(n) = self.num {
            s.set_num(n);
        }
        if let Some(v) = self.fmin {
            s.ssl.fmin_hz = v;
        }
        if let Some(v) = self.fmax {
            s.ssl.fmax_hz = v;
        }
        if let Some(v) = self.block_frames {
            s.ssl.block_frames = v;
        }
        if let Some(v) = self.pooling {
            s.ssl.pooling = v;
        }
        if let Some(v) = self.pool_top {
            s.ssl.pool_top = v;
        }
        if let Some(v) = self.placement_share {
            s.ssl.placement_share = v;
        }
        if self.deflate {
            s.ssl.deflate = Some(true);
        }
        if self.no_deflate {
            s.ssl.deflate = Some(false);
        }
        s.validate().with_context(|| match &self.config {
            Some(p) => format!("settings {} with the command's flags", p.display()),
            None => "the command's flags".to_owned(),
        })?;
        Ok(s)
    }
}

/// The unit of theta in a pose table.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, ValueEnum)]
pub enum AngleUnit {
    /// Degrees.
    #[default]
    #[value(alias = "degrees")]
    Deg,
    /// Radians.
    #[value(alias = "radians")]
    Rad,
}

/// Where the mapping inputs come from (shared by `map` and `eval`).
#[derive(Debug, Clone, Args)]
pub struct InputArgs {
    /// A data set folder in the published layout (map/, pose/, audio/, azimuth/, src_gt*).
    /// Repeat it for several runs of one building (several robots, or one robot's runs,
    /// their poses in the building's map frame): their stops are mapped as one survey,
    /// each run localised with its own array and noise.
    #[arg(long, value_name = "DIR")]
    pub dataset: Vec<PathBuf>,
    /// ROS occupancy map YAML (overrides the data set's). Without one (and without a
    /// map/ folder in the data set) the sources are searched within --open-margin of the
    /// stops.
    #[arg(long, value_name = "YAML")]
    pub map: Option<PathBuf>,
    /// Without an occupancy map: how far from the stops to search for sources (m; default
    /// 3, a room's half-width). The particles per round grow with the region's area.
    #[arg(long, value_name = "M")]
    pub open_margin: Option<f64>,
    /// Pose table, one row per stop, CSV or .xlsx (overrides the data set's): plain x, y,
    /// theta columns, or a CSV whose header names them as ROS exports do: x and y (or
    /// `*position.x`, `*position.y`), and yaw or theta_rad (radians), theta_deg (degrees),
    /// theta (--theta-unit), or a quaternion qx, qy, qz, qw (or `*orientation.x..w`);
    /// other columns are ignored.
    #[arg(long, value_name = "FILE")]
    pub poses: Option<PathBuf>,
    /// Unit of theta in the pose table.
    #[arg(long, value_enum, default_value_t = AngleUnit::Deg)]
    pub theta_unit: AngleUnit,
    /// DoA table: azimuths per stop (degrees, array frame, strongest first), CSV or .xlsx;
    /// a wider table than N maps its first N columns.
    #[arg(long, value_name = "TABLE", conflicts_with = "audio")]
    pub doas: Option<PathBuf>,
    /// Folder of WAV recordings, one per stop, localised with the SSL settings (default:
    /// the data set's audio/ when no --doas is given).
    #[arg(long, value_name = "DIR")]
    pub audio: Option<PathBuf>,
    /// Ground-truth source positions (overrides the data set's src_gt*).
    #[arg(long, value_name = "FILE")]
    pub truth: Option<PathBuf>,
    /// One continuous multichannel WAV instead of one per stop: a window of --window
    /// seconds is cut from each pose's time, and the pose table has a time per row (plain
    /// t, x, y, theta columns, or a header naming t/time/stamp/%time beside the pose
    /// columns above).
    #[arg(long, value_name = "WAV", conflicts_with_all = ["doas", "audio"])]
    pub recording: Option<PathBuf>,
    /// Seconds of a continuous recording used from each pose's time.
    #[arg(long, value_name = "S", default_value_t = 3.0, requires = "recording")]
    pub window: f64,
    /// Refine each source by bearing least squares over the DoAs it explains (not in the
    /// paper; see `asm::IasmConfig::refine`).
    #[arg(long)]
    pub refine: bool,
    /// The settings.
    #[command(flatten)]
    pub settings: SettingsArgs,
}

impl InputArgs {
    /// The settings, with `--refine` when given.
    ///
    /// # Errors
    /// As [`SettingsArgs::settings`].
    pub fn settings(&self) -> Result<Settings> {
        self.settings_of(self.dataset.first().map(PathBuf::as_path))
    }

    /// The settings for the data set `dataset` (its array and robot noise).
    fn settings_of(&self, dataset: Option<&std::path::Path>) -> Result<Settings> {
        let mut s = self
            .settings
            .settings()?
            .with_dataset_array(dataset)
            .with_dataset_noise(dataset)?;
        s.iasm.refine |= self.refine;
        Ok(s)
    }

    /// Where the survey comes from (the first data set's).
    pub fn survey_inputs(&self) -> SurveyInputs {
        SurveyInputs {
            dataset: self.dataset.first().cloned(),
            map: self.map.clone(),
            poses: self.poses.clone(),
            theta_in_radians: self.theta_unit == AngleUnit::Rad,
            doas: self.doas.clone(),
            audio: self.audio.clone(),
            truth: self.truth.clone(),
            recording: self.recording.clone(),
            window_s: self.window,
            open_margin_m: self.open_margin,
        }
    }

    /// Each run to map (a name, where its survey comes from, its settings): one per
    /// `--dataset`, or the one the files give.
    ///
    /// # Errors
    /// Settings refused; a file of one run's own (`--poses`, `--doas`, `--audio`,
    /// `--recording`) given with several data sets.
    pub fn runs(&self) -> Result<Vec<(String, SurveyInputs, Settings)>> {
        if self.dataset.len() <= 1 {
            let name = self
                .dataset
                .first()
                .or(self.poses.as_ref())
                .map_or_else(|| "survey".to_owned(), |p| crate::dataset::file_name(p));
            return Ok(vec![(name, self.survey_inputs(), self.settings()?)]);
        }
        for (flag, given) in [
            ("--poses", self.poses.is_some()),
            ("--doas", self.doas.is_some()),
            ("--audio", self.audio.is_some()),
            ("--recording", self.recording.is_some()),
        ] {
            anyhow::ensure!(
                !given,
                "{flag} with {} data sets: each run's own {} are its data set's (map one run with {flag}, or give each run's files in its folder)",
                self.dataset.len(),
                &flag[2..]
            );
        }
        self.dataset
            .iter()
            .map(|d| {
                let inputs = SurveyInputs {
                    dataset: Some(d.clone()),
                    ..self.survey_inputs()
                };
                Ok((d.display().to_string(), inputs, self.settings_of(Some(d))?))
            })
            .collect()
    }
}

/// The channels of `--channels`, counted from 1.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ChannelList(pub Vec<usize>);

/// A `--channels` list: channels counted from 1, single or as ranges (`2-5`, `1,3-4`).
pub(super) fn parse_channels(text: &str) -> Result<ChannelList, String> {
    let number = |t: &str| {
        t.trim()
            .parse::<usize>()
            .ok()
            .filter(|&c| c >= 1)
            .ok_or_else(|| format!("`{t}` is not a channel number (counted from 1)"))
    };
    let mut out = Vec::new();
    for part in text.split(',') {
        match part.split_once('-') {
            Some((a, b)) => {
                let (a, b) = (number(a)?, number(b)?);
                if a > b {
                    return Err(format!("`{part}` is an empty range"));
                }
                out.extend(a..=b);
            }
            None => out.push(number(part)?),
        }
    }
    Ok(ChannelList(out))
}

/// `--ospa-c`: a finite cutoff above 0 (m), as [`asm::ospa::check_params`] asks.
pub(super) fn parse_ospa_c(s: &str) -> Result<f64, String> {
    let c: f64 = s.parse().map_err(|e| format!("{e}"))?;
    asm::ospa::check_params(c, 1.0).map(|()| c)
}

/// `--ospa-p`: a finite order of at least 1, as [`asm::ospa::check_params`] asks.
pub(super) fn parse_ospa_p(s: &str) -> Result<f64, String> {
    let p: f64 = s.parse().map_err(|e| format!("{e}"))?;
    asm::ospa::check_params(1.0, p).map(|()| p)
}

#[cfg(test)]
mod channel_list_tests {
    use super::*;

    #[test]
    fn channel_lists_take_numbers_and_ranges_from_1() {
        assert_eq!(parse_channels("2-5"), Ok(ChannelList(vec![2, 3, 4, 5])));
        assert_eq!(
            parse_channels("1, 3-4,6"),
            Ok(ChannelList(vec![1, 3, 4, 6]))
        );
        assert!(parse_channels("0-3").unwrap_err().contains("`0`"));
        assert!(parse_channels("5-2").unwrap_err().contains("empty range"));
        assert!(parse_channels("a").is_err());
    }
}
