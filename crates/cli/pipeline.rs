//! The one place where recordings become DoAs and DoAs become a map.
//!
//! Every command that goes from recordings to a map goes through here, so that a setting
//! means the same thing in `map`, `eval`, `regress` and `demo`:
//!
//! ```text
//!  SurveyInputs ──► Survey::load ──► Survey { map, poses, doas_deg, truth } ──► Survey::map
//!  (files)          (localise_files                                              evaluate
//!                    when no DoA table)
//!  Simulated (a rendered scene) ──► Simulated::survey ──► the same Survey
//! ```
//!
//! A [`Survey`] is what one robot run gives the mapper: the occupancy map, a pose per stop,
//! the DoAs heard at each stop (a table in degrees, array frame, strongest first, as the
//! published tables and `iasm ssl` write it), and the true sources when known. The DoA
//! source (a table or the SSL) does not matter past this point.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use anyhow::{Context, Result, bail, ensure};
use asm::MapRng;
use asm::map::OccupancyMap;
use asm::ospa::{Ospa, ospa};
use asm::{IasmConfig, MapResult, Mapper, Pose, Variant};
use rand::SeedableRng;
use rayon::prelude::*;
use serde::Serialize;

use crate::explain::MissedTally;
use sim::scene::PreparedScene;
use ssl::{Audio, Doa, Localizer, Located, MicArray, Scratch, SslConfig};

use crate::dataset::read_timed_poses;
use crate::dataset::{Dataset, Table, first_with_ext, list_files, load_map, read_poses};
use crate::dataset::{read_sources, read_table};
pub use crate::robot_noise::RobotNoise;
use crate::score::{DoaScore, score_doas};
use crate::settings::Settings;

/// The DoAs of one recording.
#[derive(Clone, Debug, Serialize)]
pub struct FileDoas {
    /// The WAV file.
    pub file: PathBuf,
    /// Strongest first.
    pub doas: Vec<Doa>,
    /// Whether N cut the row: a further peak passed the thresholds ([`ssl::Located::cut`]).
    /// Not serialised: the DoA output is the DoAs.
    #[serde(skip)]
    pub cut: bool,
    /// In a cut row, the directions beyond N that the band's octaves heard
    /// ([`ssl::Located::extra`]): the mapper takes them after the DoAs.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub extra: Vec<Doa>,
    /// How its blocks were pooled ([`ssl::Located::pooling`]: with the default
    /// [`ssl::Pooling::Auto`], the mean for a steady, noise-like recording, else max).
    pub pooling: ssl::Pooling,
    /// The channels found not to hear the room ([`ssl::Located::faulty_channels`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub faulty_channels: Vec<FaultyChannel>,
    /// The time it took to read and localise it on one thread (s). Not serialised: the
    /// DoA output stays the same from run to run.
    #[serde(skip)]
    pub seconds: f64,
    /// Its sample rate (Hz). Not serialised.
    #[serde(skip)]
    pub sample_rate: u32,
    /// Whether every sample of its channels is zero: a recorder that wrote no sound (a
    /// quiet room still gives the microphones' own noise). Such a recording has no DoAs.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub silent: bool,
}

/// A channel of a recording that does not hear the room ([`ssl::channels`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FaultyChannel {
    /// The channel, counted from 1 as in the file.
    pub channel: usize,
    /// Whether the recording was localised without it ([`ssl::Located::microphones`]).
    pub left_out: bool,
    /// Why it was found faulty.
    #[serde(flatten)]
    pub fault: ssl::channels::Fault,
}

impl FaultyChannel {
    /// The faulty channels of a row localised with an array of `microphones`.
    pub fn of(row: &Located, microphones: usize) -> Vec<Self> {
        row.faulty_channels
            .iter()
            .map(|&(c, fault)| Self {
                channel: c + 1,
                left_out: row.microphones < microphones,
                fault,
            })
            .collect()
    }
}

/// One warning line per faulty channel of `rows` (the recordings `names`, in order),
/// grouped by channel and kind of fault: how many recordings, which, why (the first
/// one's figures) and whether they were localised without it.
pub fn faulty_channel_warnings<'a>(
    rows: impl IntoIterator<Item = (&'a str, &'a [FaultyChannel])>,
) -> Vec<String> {
    /// The recordings in which one channel had one kind of fault.
    struct Group<'a> {
        channel: usize,
        silent: bool,
        /// The first recording's fault (its figures are quoted).
        first: FaultyChannel,
        /// Whether every one of them was localised without the channel.
        left_out: bool,
        names: Vec<&'a str>,
    }
    let mut total = 0usize;
    let mut groups: Vec<Group<'a>> = Vec::new();
    for (name, faults) in rows {
        total += 1;
        for f in faults {
            let silent = matches!(f.fault, ssl::channels::Fault::Silent { .. });
            match groups
                .iter_mut()
                .find(|g| g.channel == f.channel && g.silent == silent)
            {
                Some(g) => {
                    g.left_out &= f.left_out;
                    g.names.push(name);
                }
                None => groups.push(Group {
                    channel: f.channel,
                    silent,
                    first: *f,
                    left_out: f.left_out,
                    names: vec![name],
                }),
            }
        }
    }
    groups.sort_by_key(|g| (g.channel, g.silent));
    groups
        .into_iter()
        .map(|g| {
            let Group {
                channel,
                first,
                left_out,
                names,
                ..
            } = g;
            format!(
                "warning: channel {channel} in {} of {total} recordings ({}): {}; {}",
                names.len(),
                listed(&names),
                first.fault,
                if left_out {
                    "localised without it (a microphone that does not hear the room; \
                     `screen_channels = false` under [ssl] keeps it)"
                } else {
                    "localised with it all the same (the microphones left would not \
                     localise by themselves; see ssl::Located::microphones)"
                }
            )
        })
        .collect()
}

/// The warnings about a set of recordings as a whole (`rows`, with their `names`): those
/// that hold no sound at all, and recordings at more than one sample rate (each is
/// localised at its own, which is right only if the files say their rates truly: a survey
/// is recorded at one).
pub fn recording_warnings(names: &[&str], rows: &[FileDoas]) -> Vec<String> {
    let mut out = Vec::new();
    let silent: Vec<&str> = names
        .iter()
        .zip(rows)
        .filter(|(_, r)| r.silent)
        .map(|(n, _)| *n)
        .collect();
    if !silent.is_empty() {
        out.push(format!(
            "warning: no sound at all in {} of {} recordings, every sample zero ({}): a \
             recorder that wrote none (even a quiet room gives the microphones' own noise); \
             no DoAs from them, as from stops that heard nothing",
            silent.len(),
            rows.len(),
            listed(&silent)
        ));
    }
    let mut rates: Vec<(u32, Vec<&str>)> = Vec::new();
    for (n, r) in names.iter().zip(rows) {
        match rates.iter_mut().find(|(fs, _)| *fs == r.sample_rate) {
            Some((_, v)) => v.push(n),
            None => rates.push((r.sample_rate, vec![n])),
        }
    }
    if rates.len() > 1 {
        rates.sort_by_key(|(fs, v)| (std::cmp::Reverse(v.len()), *fs));
        let each: Vec<String> = rates
            .iter()
            .map(|(fs, v)| format!("{} at {fs} Hz ({})", v.len(), listed(v)))
            .collect();
        out.push(format!(
            "warning: the recordings are sampled at {} rates: {}; each is localised at its \
             own rate, which is right only if its file gives the rate it was recorded at",
            rates.len(),
            each.join("; ")
        ));
    }
    out
}

/// The first three of `names` and how many more: `a, b, c and 4 more`.
fn listed(names: &[&str]) -> String {
    let shown = names.iter().take(3).copied().collect::<Vec<_>>().join(", ");
    match names.len().saturating_sub(3) {
        0 => shown,
        n => format!("{shown} and {n} more"),
    }
}

/// Prints the warnings about `rows` to standard error: [`faulty_channel_warnings`] and
/// [`recording_warnings`].
pub fn warn_recordings(rows: &[FileDoas]) {
    let names: Vec<String> = rows
        .iter()
        .map(|r| {
            r.file.file_name().map_or_else(
                || r.file.display().to_string(),
                |n| n.to_string_lossy().into(),
            )
        })
        .collect();
    for w in faulty_channel_warnings(
        names
            .iter()
            .zip(rows)
            .map(|(n, r)| (n.as_str(), &r.faulty_channels[..])),
    ) {
        eprintln!("{w}");
    }
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    for w in recording_warnings(&names, rows) {
        eprintln!("{w}");
    }
}

/// Reads the WAV at `path`, keeping its channels `channels` (counted from 1, in that
/// order: [`Settings::channels`]) when given.
///
/// # Errors
/// An unreadable file, or a channel it does not have; named.
pub fn read_recording(path: &Path, channels: Option<&[usize]>) -> Result<Audio> {
    let audio = ssl::read_wav(path)?;
    match channels {
        None => Ok(audio),
        Some(c) => pick_channels(&audio, c).with_context(|| path.display().to_string()),
    }
}

/// The channels `channels` of `audio` (counted from 1, in that order:
/// [`Settings::channels`]).
///
/// # Errors
/// A channel `audio` does not have.
pub fn pick_channels(audio: &Audio, channels: &[usize]) -> Result<Audio> {
    let from0: Vec<usize> = channels.iter().map(|&c| c.saturating_sub(1)).collect();
    audio
        .select(&from0)
        .with_context(|| format!("the channels {channels:?}"))
}

/// `e`, with a hint when the file holds more channels than the array has microphones and
/// no channels were picked (`--channels`).
pub(crate) fn with_channel_hint(e: ssl::Error, channels: Option<&[usize]>) -> anyhow::Error {
    match e {
        ssl::Error::ChannelMismatch { expected, got } if got > expected && channels.is_none() => {
            anyhow::anyhow!(
                "{e}; if the file holds other channels too, `--channels` (or `channels` in \
                 the settings file) picks the microphones' channels, counted from 1, in the \
                 array's order (a ReSpeaker 4-mic's 6-channel firmware records them on \
                 channels 2-5)"
            )
        }
        e => e.into(),
    }
}

/// The localizer of `array` at `fs` Hz with `config`, subtracting the robot's `noise` when
/// given.
///
/// # Errors
/// Settings the SSL refuses, or a noise recording of another sample rate, channel count
/// or too short; named.
pub fn localizer(
    array: &MicArray,
    fs: u32,
    config: &SslConfig,
    noise: Option<&RobotNoise>,
) -> Result<Localizer> {
    let l =
        Localizer::new(array, fs, config).with_context(|| format!("[ssl] settings at {fs} Hz"))?;
    let Some(n) = noise else {
        return Ok(l);
    };
    let got = n.audio.sample_rate();
    ensure!(
        got == fs,
        "the recording of the robot alone {} is sampled at {got} Hz, the recordings at {fs} Hz",
        n.path.display()
    );
    l.with_noise(&n.audio)
        .with_context(|| format!("the recording of the robot alone {}", n.path.display()))
}

/// Localises every file with one localizer per sample rate, in parallel, keeping order;
/// the robot's `noise` subtracted when given.
///
/// # Errors
/// The first file that cannot be read or localised, named.
pub fn localise_files(
    files: &[PathBuf],
    array: &MicArray,
    channels: Option<&[usize]>,
    config: &SslConfig,
    noise: Option<&RobotNoise>,
) -> Result<Vec<FileDoas>> {
    let bar = crate::progress(files.len() as u64, "localising");
    let cache: Mutex<Vec<Arc<Localizer>>> = Mutex::default();
    let out = files
        .par_iter()
        .map_init(Scratch::default, |scratch, f| {
            let t0 = std::time::Instant::now();
            let audio = read_recording(f, channels)?;
            let silent = audio.channels().iter().flatten().all(|&v| v == 0.0);
            let loc = {
                let mut c = cache.lock().expect("no panics while locked");
                match c.iter().find(|l| l.sample_rate() == audio.sample_rate()) {
                    Some(l) => l.clone(),
                    None => {
                        let l = localizer(array, audio.sample_rate(), config, noise)
                            .with_context(|| format!("localising {}", f.display()))?;
                        let l = Arc::new(l);
                        c.push(l.clone());
                        l
                    }
                }
            };
            let row = loc
                .locate_row_with_scratch(&audio, scratch)
                .map_err(|e| with_channel_hint(e, channels))
                .with_context(|| format!("localising {}", f.display()))?;
            let faulty_channels = FaultyChannel::of(&row, array.len());
            let Located {
                doas,
                cut,
                extra,
                pooling,
                ..
            } = row;
            bar.inc(1);
            Ok(FileDoas {
                file: f.clone(),
                doas,
                cut,
                extra,
                pooling,
                faulty_channels,
                seconds: t0.elapsed().as_secs_f64(),
                sample_rate: audio.sample_rate(),
                silent,
            })
        })
        .collect::<Result<Vec<_>>>();
    bar.finish_and_clear();
    out
}

/// One window of `window_s` seconds of `audio` from each time in `times` (s from its
/// start), for a continuous recording with a pose per time; a window that runs past the
/// end is cut short there.
///
/// # Errors
/// A window that starts at or beyond the end, or is shorter than 0.1 s; named by its
/// pose's number.
pub fn cut_windows(audio: &Audio, times: &[f64], window_s: f64) -> Result<Vec<Audio>> {
    ensure!(
        window_s.is_finite() && window_s > 0.0,
        "the window must be a positive duration (got {window_s} s)"
    );
    let fs = f64::from(audio.sample_rate());
    let n = audio.num_samples();
    times
        .iter()
        .enumerate()
        .map(|(k, &t)| {
            ensure!(
                t.is_finite() && t >= 0.0,
                "pose {}: time {t} s is not a time in the recording",
                k + 1
            );
            let a = (t * fs).round() as usize;
            let b = ((t + window_s) * fs).round().min(n as f64) as usize;
            ensure!(
                a < n && (b - a) as f64 >= 0.1 * fs,
                "pose {}: the window at {t} s holds {:.3} s of the {:.3}-s recording",
                k + 1,
                b.saturating_sub(a) as f64 / fs,
                n as f64 / fs
            );
            Ok(Audio::new(
                audio.sample_rate(),
                audio.channels().iter().map(|c| c[a..b].to_vec()).collect(),
            )?)
        })
        .collect()
}

/// The DoAs of each of `windows` (in order, in parallel), with one localizer (the robot's
/// `noise` subtracted when given); `channels`
/// are the ones picked from the recording (`None`: every channel), for the hint that a
/// channel count the array does not match gets, as in [`localise_files`].
///
/// # Errors
/// A window the array or the SSL settings cannot take.
pub fn localise_audio(
    windows: &[Audio],
    array: &MicArray,
    channels: Option<&[usize]>,
    config: &SslConfig,
    noise: Option<&RobotNoise>,
) -> Result<Vec<Located>> {
    let Some(first) = windows.first() else {
        return Ok(Vec::new());
    };
    let loc = localizer(array, first.sample_rate(), config, noise)?;
    windows
        .par_iter()
        .enumerate()
        .map_init(Scratch::default, |scratch, (k, w)| {
            loc.locate_row_with_scratch(w, scratch)
                .map_err(|e| with_channel_hint(e, channels))
                .with_context(|| format!("window {}", k + 1))
        })
        .collect()
}

/// A DoA table from ranked DoAs per recording: azimuths (degrees), `n` columns, `None`
/// where fewer were found.
pub fn doa_table<'a>(rows: impl IntoIterator<Item = &'a [Doa]>, n: usize) -> Table {
    rows.into_iter()
        .map(|r| (0..n).map(|i| r.get(i).map(|d| d.azimuth_deg)).collect())
        .collect()
}

/// The table the mapper takes from the SSL's rows: each row's `N` DoAs (empty cells where
/// it has fewer), then its extra ones ([`ssl::Located::extra`]), the extra columns as many
/// as the most any row has (none when no row has any: then it is [`doa_table`]'s).
pub fn mapped_table<'a>(rows: impl IntoIterator<Item = (&'a [Doa], &'a [Doa])>, n: usize) -> Table {
    let rows: Vec<_> = rows.into_iter().collect();
    let width = rows.iter().map(|(_, e)| e.len()).max().unwrap_or(0);
    rows.into_iter()
        .map(|(d, e)| {
            let cells = (0..n).map(|i| d.get(i)).chain((0..width).map(|i| e.get(i)));
            cells.map(|c| c.map(|d| d.azimuth_deg)).collect()
        })
        .collect()
}

/// Where a survey's parts come from: a data set folder, and files that override its parts.
#[derive(Clone, Debug, Default)]
pub struct SurveyInputs {
    /// A data set folder in the published layout.
    pub dataset: Option<PathBuf>,
    /// A ROS occupancy map YAML.
    pub map: Option<PathBuf>,
    /// A pose table (x, y, theta per stop).
    pub poses: Option<PathBuf>,
    /// Whether the pose table's theta is in radians (else degrees).
    pub theta_in_radians: bool,
    /// A DoA table (degrees, array frame); when absent the recordings are localised.
    pub doas: Option<PathBuf>,
    /// A folder of recordings, one per stop (default: the data set's `audio/`).
    pub audio: Option<PathBuf>,
    /// Ground-truth source positions.
    pub truth: Option<PathBuf>,
    /// One continuous recording instead of one per stop: cut into a window of `window_s`
    /// seconds from each pose's time stamp (the pose table then has t, x, y, theta).
    pub recording: Option<PathBuf>,
    /// The window per pose of a continuous recording (s).
    pub window_s: f64,
    /// Without an occupancy map (no `map` and no data set with a `map/` folder): the
    /// sources are searched within this many metres of a stop (default
    /// [`OPEN_MARGIN_M`]; see [`asm::map::OccupancyMap::open_around`]).
    pub open_margin_m: Option<f64>,
}

/// How far from the stops a survey without an occupancy map searches for sources (m): a
/// room's half-width, where a robot driving through a room hears the sources in it.
pub const OPEN_MARGIN_M: f64 = 3.0;

/// The grid of an open region (m): as fine as the ROS maps robots build.
pub const OPEN_RESOLUTION_M: f64 = 0.05;

/// What one robot run gives the mapper.
#[derive(Clone, Debug)]
pub struct Survey {
    /// The occupancy map.
    pub map: OccupancyMap,
    /// `Some(margin)` when no occupancy map was given and [`Survey::map`] is the region
    /// within `margin` metres of the stops ([`asm::map::OccupancyMap::open_around`]).
    pub open_margin_m: Option<f64>,
    /// One pose per stop.
    pub poses: Vec<Pose>,
    /// The DoAs heard at each stop: azimuths in degrees, array frame, strongest first;
    /// `None` for an empty cell.
    pub doas_deg: Table,
    /// Per stop, whether the SSL cut its row at N (a further peak passed its thresholds;
    /// [`ssl::Located::cut`]); `None` for a DoA table, whose rows do not say (the mapper
    /// then takes a full row as cut; see [`asm::Mapper::run_rows`]).
    pub cut: Option<Vec<bool>>,
    /// The true source positions (m), when known.
    pub truth: Option<Vec<[f64; 2]>>,
    /// Where the DoAs came from: a table's path, or `ssl:<method>`.
    pub doa_source: String,
    /// For a linear array, the azimuth of its line (degrees, array frame;
    /// [`ssl::MicArray::mirror_axis_deg`]): the mapper takes each DoA and its mirror image
    /// (see [`Survey::mapper_config`]). A DoA table is taken to be in the frame of the
    /// settings' array.
    pub mirror_axis_deg: Option<f64>,
}

/// What a user of a linear array must know, or `None` for any other array.
pub fn linear_array_note(array: &MicArray) -> Option<String> {
    array.mirror_axis_deg().map(|axis| {
        format!(
            "note: the array {} is linear (its line at {axis:.1} deg): it cannot tell a source at azimuth a from one at {:.1} - a, its mirror image; DoAs are reported between {axis:.1} and {:.1} deg, and the mapper weighs both sides (only a robot that turns tells them apart; a source it cannot place is marked with its mirror position)",
            array.name(),
            2.0 * axis,
            axis + 180.0
        )
    })
}

impl Survey {
    /// Reads and checks a survey: the map, the poses, the truth, and the DoAs from a table
    /// or, when none is given, by localising the recordings with `settings`.
    ///
    /// # Errors
    /// Missing or unreadable inputs, or tables that do not match one to one, named.
    pub fn load(inputs: &SurveyInputs, settings: &Settings) -> Result<Self> {
        Self::load_with_doas(inputs, settings, None)
    }

    /// [`Survey::load`] with the DoAs given (a table and where it came from) instead of
    /// read or localised: several DoA sources on one survey.
    ///
    /// # Errors
    /// As [`Survey::load`].
    pub fn load_with_doas(
        inputs: &SurveyInputs,
        settings: &Settings,
        doas: Option<(Table, String)>,
    ) -> Result<Self> {
        let ds = inputs.dataset.as_deref().map(Dataset::open).transpose()?;
        let map_path = match (&inputs.map, &ds) {
            (Some(p), _) => Some(p.clone()),
            (None, Some(d)) if d.root.join("map").is_dir() => {
                Some(first_with_ext(&d.root.join("map"), "yaml")?)
            }
            (None, _) => None,
        };
        let map = map_path.as_deref().map(load_map).transpose()?;
        let pose_path = match (&inputs.poses, &ds) {
            (Some(p), _) => p.clone(),
            (None, Some(d)) => d
                .poses
                .clone()
                .with_context(|| format!("{}: no pose table in pose/", d.root.display()))?,
            (None, None) => bail!("give --dataset DIR or --poses FILE"),
        };
        let timed = match &inputs.recording {
            Some(_) => Some(read_timed_poses(&pose_path, inputs.theta_in_radians)?),
            None => None,
        };
        let poses = match &timed {
            Some(t) => t.iter().map(|p| p.1).collect(),
            None => read_poses(&pose_path, inputs.theta_in_radians)?,
        };
        let truth_path = inputs
            .truth
            .clone()
            .or_else(|| ds.as_ref().and_then(|d| d.sources.clone()));
        let truth = truth_path.as_deref().map(read_sources).transpose()?;
        let mut cut = None;
        let (doas_deg, doa_source) = if let Some(given) = doas {
            given
        } else if let (Some(rec), Some(timed)) = (&inputs.recording, &timed) {
            let audio = read_recording(rec, settings.channels.as_deref())?;
            let array = settings.mic_array()?;
            let times: Vec<f64> = timed.iter().map(|p| p.0).collect();
            let windows = cut_windows(&audio, &times, inputs.window_s).with_context(|| {
                format!(
                    "cutting {} at the times of {}",
                    rec.display(),
                    pose_path.display()
                )
            })?;
            let rows = localise_audio(
                &windows,
                &array,
                settings.channels.as_deref(),
                &settings.ssl,
                RobotNoise::of(settings)?.as_ref(),
            )
            .with_context(|| format!("localising {}", rec.display()))?;
            let names: Vec<String> = (1..=rows.len()).map(|k| format!("window {k}")).collect();
            let faults: Vec<Vec<FaultyChannel>> = rows
                .iter()
                .map(|r| FaultyChannel::of(r, array.len()))
                .collect();
            for w in faulty_channel_warnings(
                names.iter().zip(&faults).map(|(n, f)| (n.as_str(), &f[..])),
            ) {
                eprintln!("{}: {w}", rec.display());
            }
            cut = Some(rows.iter().map(|r| r.cut).collect());
            (
                mapped_table(
                    rows.iter().map(|r| (&r.doas[..], &r.extra[..])),
                    settings.ssl.num_peaks,
                ),
                format!("ssl:{}", settings.ssl.method),
            )
        } else if let Some(t) = &inputs.doas {
            (
                first_columns(read_table(t)?, settings.iasm.num_doas, t),
                t.display().to_string(),
            )
        } else {
            let (files, folder) = match (&inputs.audio, &ds) {
                (Some(dir), _) => (list_files(dir, "wav")?, dir.clone()),
                (None, Some(d)) => (d.audio.clone(), d.root.join("audio")),
                (None, None) => bail!("give --doas TABLE, --audio DIR or --dataset DIR"),
            };
            ensure!(
                !files.is_empty(),
                "{}: no WAV file to localise",
                folder.display()
            );
            ensure!(
                files.len() == poses.len(),
                "{} recordings but {} poses in {}: they must match one to one",
                files.len(),
                poses.len(),
                pose_path.display()
            );
            let rows = localise_files(
                &files,
                &settings.mic_array()?,
                settings.channels.as_deref(),
                &settings.ssl,
                RobotNoise::of(settings)?.as_ref(),
            )?;
            warn_recordings(&rows);
            cut = Some(rows.iter().map(|r| r.cut).collect());
            (
                mapped_table(
                    rows.iter().map(|r| (&r.doas[..], &r.extra[..])),
                    settings.ssl.num_peaks,
                ),
                format!("ssl:{}", settings.ssl.method),
            )
        };
        let (map, open_margin_m) = match map {
            Some(map) => (map, None),
            None => {
                let margin = inputs.open_margin_m.unwrap_or(OPEN_MARGIN_M);
                let stops: Vec<[f64; 2]> = poses.iter().map(|p| [p.x, p.y]).collect();
                let map = OccupancyMap::open_around(&stops, margin, OPEN_RESOLUTION_M)
                    .with_context(|| format!("poses from {}", pose_path.display()))?;
                (map, Some(margin))
            }
        };
        let survey = Self {
            map,
            open_margin_m,
            poses,
            doas_deg: Table::new(),
            cut: None,
            truth,
            doa_source: String::new(),
            mirror_axis_deg: settings.mic_array()?.mirror_axis_deg(),
        }
        .with_doas(doas_deg, doa_source, cut)
        .with_context(|| format!("poses from {}", pose_path.display()))?;
        Ok(survey)
    }

    /// What a user should know about the map when no occupancy map was given: where the
    /// sources were searched for, and how to change it.
    pub fn map_note(&self) -> Option<String> {
        self.open_margin_m.map(|m| {
            format!(
                "note: no occupancy map given: the sources are searched within {m} m of the stops (--open-margin M to change it; a map in map/ or --map bounds the search by the room)"
            )
        })
    }

    /// The same survey heard through other DoAs (a table, where it came from, and per
    /// stop whether the SSL cut its row, when it says; see [`Survey::cut`]): several DoA
    /// sources compared on one map, poses and truth, read once.
    ///
    /// # Errors
    /// If the table or the flags have not one row per pose.
    pub fn with_doas(
        self,
        doas_deg: Table,
        doa_source: String,
        cut: Option<Vec<bool>>,
    ) -> Result<Self> {
        ensure!(
            doas_deg.len() == self.poses.len(),
            "{} rows of DoAs ({doa_source}) but {} poses: they must match one to one",
            doas_deg.len(),
            self.poses.len()
        );
        if let Some(cut) = &cut {
            ensure!(
                cut.len() == self.poses.len(),
                "{} row-cut flags ({doa_source}) but {} poses: they must match one to one",
                cut.len(),
                self.poses.len()
            );
        }
        Ok(Self {
            doas_deg,
            cut,
            doa_source,
            ..self
        })
    }

    /// The DoAs as the mapper takes them: radians, empty cells dropped.
    pub fn doas_rad(&self) -> Vec<Vec<f64>> {
        self.doas_deg
            .iter()
            .map(|row| row.iter().flatten().map(|a| a.to_radians()).collect())
            .collect()
    }

    /// `config` as the mapper takes it for this survey: with the linear array's mirror axis
    /// ([`Survey::mirror_axis_deg`]) unless `config` sets one.
    pub fn mapper_config(&self, config: &IasmConfig) -> IasmConfig {
        IasmConfig {
            mirror_axis_deg: config.mirror_axis_deg.or(self.mirror_axis_deg),
            ..config.clone()
        }
    }

    /// One I-ASM map with `config` (see [`Survey::mapper_config`]), seeded by `seed`.
    ///
    /// # Errors
    /// As [`Mapper::new`] and [`Mapper::run`].
    pub fn map(&self, config: &IasmConfig, seed: u64) -> Result<MapResult> {
        let mapper = Mapper::new(&self.map, &self.mapper_config(config))?;
        Ok(mapper.run_rows(
            &self.poses,
            &self.doas_rad(),
            self.cut.as_deref(),
            &mut MapRng::seed_from_u64(seed),
        )?)
    }

    /// The OSPA of `result` against the truth (cutoff `c` m, order `p`), when it is known.
    pub fn ospa(&self, result: &MapResult, c: f64, p: f64) -> Option<Ospa> {
        self.truth
            .as_ref()
            .map(|t| ospa(&result.positions(), t, c, p))
    }
}

/// The first `n` columns of a DoA table (ranked tables list the strongest first, and are
/// often wider than the N a user maps with), saying once on stderr when it cuts.
pub fn first_columns(mut table: Table, n: usize, path: &std::path::Path) -> Table {
    let widest = table.iter().map(Vec::len).max().unwrap_or(0);
    if widest > n {
        eprintln!(
            "note: {} has up to {widest} DoAs per stop; mapping the first {n} (N = {n}, strongest first)",
            path.display()
        );
        table.iter_mut().for_each(|row| row.truncate(n));
    }
    table
}

/// One variant's Monte Carlo summary.
#[derive(Clone, Debug, Serialize)]
pub struct VariantStats {
    /// The variant.
    pub variant: Variant,
    /// Mean OSPA (m).
    pub mean: f64,
    /// Median OSPA (m).
    pub median: f64,
    /// Mean localisation part (m).
    pub mean_localization: f64,
    /// Mean cardinality part (m).
    pub mean_cardinality: f64,
    /// Mean number of sources found.
    pub mean_sources: f64,
    /// The share of runs that found exactly as many sources as the truth holds.
    pub right_count: f64,
    /// The worst run's OSPA (m).
    pub worst: f64,
    /// The seed of the worst run.
    pub worst_seed: u64,
    /// Every run's OSPA (m), by seed.
    pub runs: Vec<f64>,
    /// Every run's number of sources, by seed.
    pub sources: Vec<usize>,
    /// The mean distance of matched sources from the truth, before and after each run's
    /// best similarity transform of the map onto the truth, and the transforms' mean scale
    /// and rotation (degrees): a diagnostic of the data's frames (`asm::align`). `None`
    /// when no run matched three sources.
    pub aligned: Option<AlignedStats>,
    /// True sources missed per run, and of those how many the mapper made and refused, by
    /// rule (the mean of each run's [`MissedTally`]): a source lost to the mapper's rules
    /// rather than to the DoAs.
    pub missed: MissedTally,
}

/// The runs' [`asm::align::Alignment`]s, averaged.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct AlignedStats {
    /// Runs with a transform (three matched sources or more).
    pub runs: usize,
    /// Mean distance of matched sources from the truth (m).
    pub mean_before_m: f64,
    /// The same after each run's transform (m).
    pub mean_after_m: f64,
    /// Mean scale of the transforms.
    pub scale: f64,
    /// Mean rotation of the transforms (degrees).
    pub rotation_deg: f64,
}

/// The paper's Monte Carlo evaluation: `runs` seeded maps (seeds `seed0..seed0 + runs`) of
/// each variant, in parallel, scored with OSPA (cutoff `c` m, order `p`).
///
/// # Errors
/// A survey without truth, or as [`Mapper::new`] and [`Mapper::run`].
pub fn evaluate(
    survey: &Survey,
    base: &IasmConfig,
    variants: &[Variant],
    runs: usize,
    seed0: u64,
    c: f64,
    p: f64,
) -> Result<Vec<VariantStats>> {
    let truth = survey
        .truth
        .as_ref()
        .context("the evaluation needs ground truth (src_gt* or --truth)")?;
    let doas_rad = survey.doas_rad();
    let bar = crate::progress((variants.len() * runs) as u64, "mapping");
    let out = variants
        .iter()
        .map(|&v| {
            let config = IasmConfig {
                variant: v,
                ..survey.mapper_config(base)
            };
            let mapper = Mapper::new(&survey.map, &config)?;
            let res: Vec<Run> = (0..runs as u64)
                .into_par_iter()
                .map(|s| {
                    let mut rng = MapRng::seed_from_u64(seed0 + s);
                    let r = mapper.run_rows(
                        &survey.poses,
                        &doas_rad,
                        survey.cut.as_deref(),
                        &mut rng,
                    )?;
                    bar.inc(1);
                    let found = r.positions();
                    Ok((
                        ospa(&found, truth, c, p),
                        r.sources.len(),
                        asm::align::align(&found, truth, c),
                        MissedTally::of(&r, truth, c),
                    ))
                })
                .collect::<Result<_>>()?;
            Ok(summarise(v, &res, truth.len(), seed0))
        })
        .collect::<Result<Vec<_>>>();
    bar.finish_and_clear();
    out
}

/// One run's OSPA, source count, alignment, and how its missed sources were lost.
type Run = (Ospa, usize, Option<asm::align::Alignment>, MissedTally);

fn summarise(variant: Variant, res: &[Run], truth: usize, seed0: u64) -> VariantStats {
    let n = res.len() as f64;
    let fits: Vec<_> = res.iter().filter_map(|r| r.2).collect();
    let k = fits.len() as f64;
    let aligned = (!fits.is_empty()).then(|| AlignedStats {
        runs: fits.len(),
        mean_before_m: fits.iter().map(|f| f.mean_before_m).sum::<f64>() / k,
        mean_after_m: fits.iter().map(|f| f.mean_after_m).sum::<f64>() / k,
        scale: fits.iter().map(|f| f.scale).sum::<f64>() / k,
        rotation_deg: fits
            .iter()
            .map(|f| f.rotation_rad.to_degrees())
            .sum::<f64>()
            / k,
    });
    let runs: Vec<f64> = res.iter().map(|r| r.0.total).collect();
    let mut sorted = runs.clone();
    sorted.sort_by(f64::total_cmp);
    let mid = sorted.len() / 2;
    let median = if sorted.len() % 2 == 1 {
        sorted[mid]
    } else {
        0.5 * (sorted[mid - 1] + sorted[mid])
    };
    VariantStats {
        variant,
        mean: sorted.iter().sum::<f64>() / n,
        median,
        mean_localization: res.iter().map(|r| r.0.localization).sum::<f64>() / n,
        mean_cardinality: res.iter().map(|r| r.0.cardinality).sum::<f64>() / n,
        mean_sources: res.iter().map(|r| r.1 as f64).sum::<f64>() / n,
        right_count: res.iter().filter(|r| r.1 == truth).count() as f64 / n,
        worst: sorted.last().copied().unwrap_or(f64::NAN),
        worst_seed: seed0
            + runs
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1))
                .map_or(0, |(i, _)| i as u64),
        runs,
        sources: res.iter().map(|r| r.1).collect(),
        aligned,
        missed: MissedTally::mean(res.iter().map(|r| r.3)),
    }
}

/// A scene rendered at every stop: recordings with known truth, ready for the pipeline.
pub struct Simulated {
    /// The scene's name (or its file's stem).
    pub name: String,
    /// The checked scene.
    pub scene: PreparedScene,
    /// What the array heard at each stop.
    pub audio: Vec<Audio>,
    /// The scene's array.
    pub array: MicArray,
    /// True source positions (m).
    pub truth: Vec<[f64; 2]>,
    /// The scene's occupancy map.
    pub map: OccupancyMap,
    /// For a scene with sources on the robot: the robot alone, rendered at the first stop
    /// ([`sim::scene::PreparedScene::render_robot_alone`]), which the SSL subtracts as a user's
    /// recording of their robot.
    pub noise: Option<RobotNoise>,
}

/// One run of the pipeline on a [`Simulated`] scene.
pub struct SceneRun {
    /// The DoAs, with the scene's poses, map and truth.
    pub survey: Survey,
    /// The DoA score of the first N DoAs per stop (hit within 5 degrees).
    pub score: DoaScore,
    /// The I-ASM map.
    pub map: MapResult,
    /// Its OSPA (p = 1, c = 1 m).
    pub ospa: Ospa,
}

impl Simulated {
    /// Renders a checked scene (`fallback_name` when it has none), every stop in parallel.
    ///
    /// # Errors
    /// If the scene's array cannot be built.
    pub fn render(scene: PreparedScene, fallback_name: String) -> Result<Self> {
        let name = if scene.scene.name.is_empty() {
            fallback_name
        } else {
            scene.scene.name.clone()
        };
        let fs = scene.scene.fs;
        let audio: Vec<Audio> = (0..scene.stops.len())
            .into_par_iter()
            .map(|k| {
                let ch = scene
                    .render_stop(k)
                    .into_iter()
                    .map(|c| c.into_iter().map(|v| v as f32).collect())
                    .collect();
                Audio::new(fs, ch).map_err(anyhow::Error::from)
            })
            .collect::<Result<_>>()?;
        let array = MicArray::new(name.clone(), scene.mics.clone())?;
        let truth = scene.room_sources().map(|s| [s.pos[0], s.pos[1]]).collect();
        let map = crate::scenes::scene_map(&scene);
        let noise = scene
            .render_robot_alone(0)
            .map(|ch| -> Result<RobotNoise> {
                let ch = ch
                    .into_iter()
                    .map(|c| c.into_iter().map(|v| v as f32).collect())
                    .collect();
                Ok(RobotNoise {
                    path: PathBuf::from(format!("{name} (the robot alone, rendered)")),
                    audio: Audio::new(fs, ch)?,
                })
            })
            .transpose()?;
        Ok(Self {
            name,
            scene,
            audio,
            array,
            truth,
            map,
            noise,
        })
    }

    /// The robot's stops.
    pub fn poses(&self) -> &[Pose] {
        &self.scene.stops
    }

    /// Localises every stop with `ssl` (the scene's own array, whatever `ssl` says; the
    /// robot's noise subtracted when the scene has some).
    ///
    /// # Errors
    /// Settings refused for this array and rate.
    pub fn survey(&self, ssl: &SslConfig) -> Result<Survey> {
        let loc = localizer(&self.array, self.scene.scene.fs, ssl, self.noise.as_ref())
            .with_context(|| format!("scene {}", self.name))?;
        let rows: Vec<Located> = self
            .audio
            .par_iter()
            .map_init(Scratch::default, |scratch, a| {
                loc.locate_row_with_scratch(a, scratch)
            })
            .collect::<Result<_, _>>()
            .with_context(|| format!("localising scene {}", self.name))?;
        Ok(Survey {
            map: self.map.clone(),
            open_margin_m: None,
            poses: self.scene.stops.clone(),
            doas_deg: mapped_table(
                rows.iter().map(|r| (&r.doas[..], &r.extra[..])),
                ssl.num_peaks,
            ),
            cut: Some(rows.iter().map(|r| r.cut).collect()),
            truth: Some(self.truth.clone()),
            doa_source: format!("ssl:{}", ssl.method),
            mirror_axis_deg: self.array.mirror_axis_deg(),
        })
    }

    /// The whole pipeline with `settings`: localise, score, map with `seed`, OSPA (p = 1,
    /// c = 1 m). The score counts the first `min(N, sources)` DoAs of each stop (hit within
    /// 5 degrees): N is an upper bound a user guesses, and a stop cannot hear more sources
    /// than there are, so DoAs beyond the true count are neither rewarded nor punished.
    ///
    /// # Errors
    /// Settings refused.
    pub fn run(&self, settings: &Settings, seed: u64) -> Result<SceneRun> {
        let survey = self.survey(&settings.ssl)?;
        let score = score_doas(
            &survey.doas_deg,
            &survey.poses,
            &self.truth,
            settings.ssl.num_peaks.min(self.truth.len()),
            5.0,
            survey.mirror_axis_deg,
        )?;
        let map = survey.map(&settings.iasm, seed)?;
        let ospa = ospa(&map.positions(), &self.truth, 1.0, 1.0);
        Ok(SceneRun {
            survey,
            score,
            map,
            ospa,
        })
    }
}

/// The settings the suite and the demo run a scene with: `base`, with `method` and N.
pub fn scene_settings(base: &Settings, method: ssl::Method, n: usize) -> Settings {
    let mut s = base.clone();
    s.ssl.method = method;
    s.set_num(n);
    s
}
