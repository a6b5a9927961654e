//! Recordings to DoAs: reading and picking channels, one localizer per sample rate,
//! the files localised in parallel, warnings on what the recordings showed, DoA tables.

use super::*;

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
        .map(|r| crate::dataset::file_name(&r.file))
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
