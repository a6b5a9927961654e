//! Multichannel audio in memory, and reading it from WAV files.
//!
//! Samples are stored channel-major (`channels[mic][sample]`) as `f32` in `[-1, 1)` for
//! integer formats; float WAVs are taken as they are.

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Multichannel audio: a sample rate and one equally long sample vector per channel.
#[derive(Clone, Debug, PartialEq)]
pub struct Audio {
    sample_rate: u32,
    channels: Vec<Vec<f32>>,
}

impl Audio {
    /// Wraps channel-major samples.
    ///
    /// # Errors
    /// [`Error::RaggedAudio`] if there is no channel, a channel is empty, or the channels
    /// differ in length; [`Error::NonFiniteSample`] if a sample is NaN or infinite (the
    /// first one); [`Error::Config`] if `sample_rate` is zero.
    pub fn new(sample_rate: u32, channels: Vec<Vec<f32>>) -> Result<Self> {
        if sample_rate == 0 {
            return Err(crate::ConfigError::SampleRate.into());
        }
        let n = channels.first().map_or(0, Vec::len);
        if n == 0 || channels.iter().any(|c| c.len() != n) {
            return Err(Error::RaggedAudio);
        }
        // A NaN would make every spectrum it touches NaN and the localisation find nothing,
        // silently; the check is one vectorised pass, far below the STFT's cost.
        for (c, ch) in channels.iter().enumerate() {
            if !ch.iter().fold(true, |ok, v| ok & v.is_finite()) {
                let sample = ch.iter().position(|v| !v.is_finite()).unwrap_or(0);
                return Err(Error::NonFiniteSample {
                    channel: c + 1,
                    sample,
                    value: ch[sample],
                });
            }
        }
        Ok(Self {
            sample_rate,
            channels,
        })
    }

    /// Sample rate (Hz).
    pub fn sample_rate(&self) -> u32 {
        self.sample_rate
    }

    /// Channel-major samples.
    pub fn channels(&self) -> &[Vec<f32>] {
        &self.channels
    }

    /// Number of channels.
    pub fn num_channels(&self) -> usize {
        self.channels.len()
    }

    /// Samples per channel.
    pub fn num_samples(&self) -> usize {
        self.channels[0].len()
    }

    /// Duration (s).
    pub fn duration(&self) -> f64 {
        self.num_samples() as f64 / f64::from(self.sample_rate)
    }

    /// The channels `channels` of this audio (indices from 0), in that order: the channels
    /// of a recording that are an array's microphones, when the file holds others too (a
    /// ReSpeaker's firmware records its processed beam and the playback beside the
    /// microphones).
    ///
    /// # Errors
    /// [`Error::NoSuchChannel`] for an index beyond the audio's channels;
    /// [`Error::RaggedAudio`] for no index at all.
    pub fn select(&self, channels: &[usize]) -> Result<Audio> {
        if channels.is_empty() {
            return Err(Error::RaggedAudio);
        }
        if let Some(&c) = channels.iter().find(|&&c| c >= self.num_channels()) {
            return Err(Error::NoSuchChannel {
                channel: c + 1,
                channels: self.num_channels(),
            });
        }
        Ok(Self {
            sample_rate: self.sample_rate,
            channels: channels.iter().map(|&c| self.channels[c].clone()).collect(),
        })
    }
}

/// The most samples (all channels) a WAV may hold: 2^26, 256 MiB as `f32` (11.6 minutes
/// of six channels at 16 kHz, 3.9 at 48 kHz). I-ASM localises one recording per stop, a
/// few seconds long; a recording read whole with its STFT takes about 7 bytes a sample,
/// so a one-hour file once took 6.8 GB. A longer one is refused from its header.
pub const MAX_WAV_SAMPLES: u64 = 1 << 26;

/// Reads a WAV file: 8/16/24/32-bit integer PCM or 32-bit float, any sample rate, any
/// number of channels.
///
/// # Errors
/// [`Error::Wav`] if the file cannot be opened or is not a WAV, [`Error::EmptyWav`] if it
/// holds no samples, [`Error::TooLong`] if it holds more than [`MAX_WAV_SAMPLES`] (found
/// from its header and size, before they are read), [`Error::Truncated`] if it ends before the samples its header
/// declares.
pub fn read_wav(path: &Path) -> Result<Audio> {
    let wav_err = |message: String| Error::Wav {
        path: path.to_owned(),
        message,
    };
    let reader = open_wav(path)?;
    let spec = reader.spec();
    let n_ch = usize::from(spec.channels);
    if n_ch == 0 {
        return Err(wav_err("the header declares zero channels".into()));
    }
    let declared = u64::from(reader.len());
    if declared == 0 {
        return Err(Error::EmptyWav {
            path: path.to_owned(),
        });
    }
    let fits = samples_that_fit(path, spec, declared)?;
    let frames = usize::try_from(fits).unwrap_or(usize::MAX) / n_ch;
    let mut channels = vec![Vec::with_capacity(frames); n_ch];
    let int16 = spec.sample_format == hound::SampleFormat::Int && spec.bits_per_sample == 16;
    let float32 = spec.sample_format == hound::SampleFormat::Float && spec.bits_per_sample == 32;
    let read = if int16 || float32 {
        read_in_bulk(reader, int16, declared, fits, &mut channels)
            .map_err(|e| wav_err(e.to_string()))?
    } else {
        read_by_sample(path, reader, declared, &mut channels)?
    };
    if read < declared || declared % n_ch as u64 != 0 {
        return Err(truncated(path, declared, read));
    }
    Audio::new(spec.sample_rate, channels).map_err(|e| match e {
        Error::NonFiniteSample {
            channel,
            sample,
            value,
        } => Error::NonFiniteWav {
            path: path.to_owned(),
            channel,
            sample,
            value,
        },
        _ => Error::EmptyWav {
            path: path.to_owned(),
        },
    })
}

/// A WAV file open for reading, its header read.
type WavFile = hound::WavReader<std::io::BufReader<std::fs::File>>;

/// `path`'s WAV reader, its header read, or the reason it is no WAV we read, in words a
/// user acts on.
fn open_wav(path: &Path) -> Result<WavFile> {
    let wav_err = |message: String| Error::Wav {
        path: path.to_owned(),
        message,
    };
    hound::WavReader::open(path).map_err(|e| match e {
        hound::Error::IoError(io)
            if matches!(
                io.kind(),
                std::io::ErrorKind::NotFound
                    | std::io::ErrorKind::PermissionDenied
                    | std::io::ErrorKind::IsADirectory
            ) =>
        {
            wav_err(io.to_string())
        }
        hound::Error::IoError(_) => {
            wav_err("not a WAV file (too short for a RIFF/WAVE header)".into())
        }
        // hound refuses a float format of other than 32 bits while reading the header.
        hound::Error::FormatError("bits per sample is not 32") => wav_err(
            "float samples of other than 32 bits (e.g. 64-bit doubles) are not supported: \
             convert to 32-bit float or 16/24-bit PCM (e.g. `sox in.wav -b 32 -e floating-point out.wav`)"
                .into(),
        ),
        hound::Error::FormatError(m) => wav_err(format!("not a valid WAV file: {m}")),
        other => wav_err(format!("not a supported WAV file: {other}")),
    })
}

/// Refuses a recording of `channels` x `samples_per_channel` at `rate` Hz beyond
/// [`MAX_WAV_SAMPLES`], before it is copied: the bound of a WAV file, for recordings that
/// come from elsewhere (a numpy array, a ROS message); `what` names it in the error.
///
/// # Errors
/// [`Error::TooLong`].
pub fn check_length(
    what: &str,
    channels: usize,
    samples_per_channel: usize,
    rate: u32,
) -> Result<()> {
    let total = (channels as u64).saturating_mul(samples_per_channel as u64);
    if total > MAX_WAV_SAMPLES {
        let per_s = f64::from(rate.max(1)) * channels.max(1) as f64;
        return Err(Error::TooLong {
            path: PathBuf::from(what),
            seconds: total as f64 / per_s,
            channels: u16::try_from(channels).unwrap_or(u16::MAX),
            rate,
            limit_s: MAX_WAV_SAMPLES as f64 / per_s,
        });
    }
    Ok(())
}

/// How many of the `declared` samples the file can hold, refused beyond
/// [`MAX_WAV_SAMPLES`]. A header may declare more samples than the file holds (a recorder
/// still writing, or a damaged header declaring gigabytes): only what the file can hold is
/// reserved, and the read finds the truncation.
fn samples_that_fit(path: &Path, spec: hound::WavSpec, declared: u64) -> Result<u64> {
    let sample_bytes = u64::from(spec.bits_per_sample.div_ceil(8).max(1));
    let file_len = std::fs::metadata(path).map_or(u64::MAX, |m| m.len());
    let fits = (file_len / sample_bytes).min(declared);
    if fits > MAX_WAV_SAMPLES {
        let per_s = f64::from(spec.sample_rate) * f64::from(spec.channels);
        return Err(Error::TooLong {
            path: path.to_owned(),
            seconds: declared as f64 / per_s,
            channels: spec.channels,
            rate: spec.sample_rate,
            limit_s: MAX_WAV_SAMPLES as f64 / per_s,
        });
    }
    Ok(fits)
}

/// [`Error::Truncated`]: `path` ended after `read` of the `declared` samples.
fn truncated(path: &Path, declared: u64, read: u64) -> Error {
    Error::Truncated {
        path: path.to_owned(),
        declared,
        read,
    }
}

/// The samples of a 16-bit integer (`int16`) or 32-bit float WAV, decoded in bulk into
/// `channels`: hound's per-sample iterator costs more than all of the localisation that
/// follows. Returns how many samples the file held (of the `declared`; `fits` of them
/// reserved).
fn read_in_bulk(
    reader: WavFile,
    int16: bool,
    declared: u64,
    fits: u64,
    channels: &mut [Vec<f32>],
) -> std::io::Result<u64> {
    let width = if int16 { 2 } else { 4 };
    let mut bytes = Vec::with_capacity(usize::try_from(fits).unwrap_or(0) * width);
    let mut inner = reader.into_inner();
    std::io::Read::by_ref(&mut inner)
        .take(declared * width as u64)
        .read_to_end(&mut bytes)?;
    let read = (bytes.len() / width) as u64;
    // Channel by channel over whole frames: sequential writes, no per-sample division to
    // find the channel, no per-sample capacity check.
    let stride = width * channels.len();
    let whole = bytes.len() / stride;
    for (c, ch) in channels.iter_mut().enumerate() {
        ch.extend(bytes[..whole * stride].chunks_exact(stride).map(|f| {
            let b = &f[c * width..];
            if int16 {
                f32::from(i16::from_le_bytes([b[0], b[1]])) * (1.0 / 32768.0)
            } else {
                f32::from_le_bytes([b[0], b[1], b[2], b[3]])
            }
        }));
    }
    Ok(read)
}

/// The samples of an 8-, 24- or 32-bit integer WAV, one by one into `channels`; how many
/// it held, or [`Error::Truncated`] where one could not be read.
fn read_by_sample(
    path: &Path,
    reader: WavFile,
    declared: u64,
    channels: &mut [Vec<f32>],
) -> Result<u64> {
    let spec = reader.spec();
    if spec.sample_format == hound::SampleFormat::Float {
        return Err(Error::Wav {
            path: path.to_owned(),
            message: format!(
                "{}-bit float samples are not supported (32-bit only)",
                spec.bits_per_sample
            ),
        });
    }
    let n_ch = channels.len() as u64;
    let mut read = 0u64;
    let mut push = |i: u64, v: f32| channels[(i % n_ch) as usize].push(v);
    let scale = 1.0 / (1u64 << (spec.bits_per_sample - 1)) as f32;
    if spec.bits_per_sample <= 16 {
        for s in reader.into_samples::<i16>() {
            push(
                read,
                f32::from(s.map_err(|_| truncated(path, declared, read))?) * scale,
            );
            read += 1;
        }
    } else {
        for s in reader.into_samples::<i32>() {
            push(
                read,
                s.map_err(|_| truncated(path, declared, read))? as f32 * scale,
            );
            read += 1;
        }
    }
    Ok(read)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(path: &Path, spec: hound::WavSpec, samples: &[i32]) {
        let mut w = hound::WavWriter::create(path, spec).unwrap();
        for &s in samples {
            if spec.sample_format == hound::SampleFormat::Float {
                w.write_sample(s as f32 / 1000.0).unwrap();
            } else {
                w.write_sample(s).unwrap();
            }
        }
        w.finalize().unwrap();
    }

    fn spec(bits: u16, format: hound::SampleFormat) -> hound::WavSpec {
        hound::WavSpec {
            channels: 2,
            sample_rate: 16000,
            bits_per_sample: bits,
            sample_format: format,
        }
    }

    #[test]
    fn integer_and_float_formats_scale_to_unit_range() {
        let dir = tempfile::tempdir().unwrap();
        for (bits, fmt, full) in [
            (16, hound::SampleFormat::Int, 1 << 14),
            (24, hound::SampleFormat::Int, 1 << 22),
            (32, hound::SampleFormat::Int, 1 << 30),
            (32, hound::SampleFormat::Float, 500),
        ] {
            let p = dir.path().join(format!("{bits}{fmt:?}.wav"));
            write(&p, spec(bits, fmt), &[full, -full, 0, full]);
            let a = read_wav(&p).unwrap();
            assert_eq!((a.num_channels(), a.num_samples()), (2, 2));
            assert_eq!(a.sample_rate(), 16000);
            // Interleaved L R L R: channel 0 = [full, 0], channel 1 = [-full, full].
            assert!((a.channels()[0][0] - 0.5).abs() < 1e-6, "{bits} {fmt:?}");
            assert!((a.channels()[1][0] + 0.5).abs() < 1e-6);
            assert_eq!(a.channels()[0][1], 0.0);
        }
    }

    #[test]
    fn a_text_file_is_not_a_wav() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("notes.wav");
        std::fs::write(
            &p,
            "these are not samples, just some text that is long enough",
        )
        .unwrap();
        let e = read_wav(&p).unwrap_err().to_string();
        assert!(e.contains("notes.wav") && e.contains("not a"), "{e}");
    }

    #[test]
    fn an_empty_file_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("empty.wav");
        std::fs::write(&p, "").unwrap();
        let e = read_wav(&p).unwrap_err().to_string();
        assert!(e.contains("empty.wav"), "{e}");
        let p = dir.path().join("nosamples.wav");
        write(&p, spec(16, hound::SampleFormat::Int), &[]);
        assert!(matches!(read_wav(&p), Err(Error::EmptyWav { .. })));
    }

    #[test]
    fn a_truncated_file_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("cut.wav");
        write(&p, spec(16, hound::SampleFormat::Int), &[1; 1000]);
        let bytes = std::fs::read(&p).unwrap();
        std::fs::write(&p, &bytes[..bytes.len() - 501]).unwrap();
        let e = read_wav(&p).unwrap_err();
        assert!(matches!(e, Error::Truncated { declared: 1000, .. }), "{e}");
        assert!(e.to_string().contains("cut.wav"));
    }

    #[test]
    fn an_hour_of_six_channels_is_refused_from_its_header_before_it_is_read() {
        // A 6-channel 48-kHz 16-bit file of one hour: 2 GB of (sparse) zeros that once took
        // 6.8 GB to localise. It is refused at once, naming the file and its duration.
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("one_hour.wav");
        let s = hound::WavSpec {
            channels: 6,
            sample_rate: 48_000,
            bits_per_sample: 16,
            sample_format: hound::SampleFormat::Int,
        };
        hound::WavWriter::create(&p, s).unwrap().finalize().unwrap();
        let data: u32 = 48_000 * 3600 * 12;
        let mut bytes = std::fs::read(&p).unwrap();
        let at = bytes.windows(4).position(|w| w == b"data").unwrap() + 4;
        bytes[at..at + 4].copy_from_slice(&data.to_le_bytes());
        bytes[4..8].copy_from_slice(&(data + 36).to_le_bytes());
        std::fs::write(&p, &bytes).unwrap();
        let f = std::fs::OpenOptions::new().write(true).open(&p).unwrap();
        f.set_len(bytes.len() as u64 + u64::from(data)).unwrap();
        let e = read_wav(&p).unwrap_err();
        // 2^26 samples of 6 channels at 48 kHz: 233 s.
        assert!(matches!(e, Error::TooLong { .. }), "{e}");
        let m = e.to_string();
        assert!(
            m.contains("one_hour.wav")
                && m.contains("3600 s of 6 channels")
                && m.contains("(233 s"),
            "{m}"
        );
        // Within the bound, the same header on a short file is a truncation, as before.
        f.set_len(bytes.len() as u64 + 1200).unwrap();
        assert!(matches!(read_wav(&p).unwrap_err(), Error::Truncated { .. }));
    }

    #[test]
    fn a_header_declaring_gigabytes_is_a_truncation_not_an_allocation() {
        // Issue 13's mutation test found a data chunk size of 0xFFFF_FFF0 reserving 5 GB for
        // a 19 kB file. What is reserved is now bounded by the file's size.
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("huge.wav");
        write(&p, spec(16, hound::SampleFormat::Int), &[1; 1000]);
        let mut bytes = std::fs::read(&p).unwrap();
        let at = bytes.windows(4).position(|w| w == b"data").unwrap() + 4;
        bytes[at..at + 4].copy_from_slice(&0xFFFF_FFF0u32.to_le_bytes());
        std::fs::write(&p, &bytes).unwrap();
        let e = read_wav(&p).unwrap_err();
        assert!(
            matches!(
                e,
                Error::Truncated {
                    declared: 0x7FFF_FFF8,
                    read: 1000,
                    ..
                }
            ),
            "{e}"
        );
    }

    #[test]
    fn a_nan_or_infinite_sample_is_refused_with_its_channel_and_place() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("nan.wav");
        let mut w = hound::WavWriter::create(&p, spec(32, hound::SampleFormat::Float)).unwrap();
        // Interleaved: sample 2 of channel 2 (the sixth value) is NaN.
        for v in [0.1, 0.2, 0.1, 0.2, 0.1, f32::NAN, 0.1, 0.2] {
            w.write_sample(v).unwrap();
        }
        w.finalize().unwrap();
        let e = read_wav(&p).unwrap_err();
        assert!(
            matches!(
                e,
                Error::NonFiniteWav {
                    channel: 2,
                    sample: 2,
                    ..
                }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("nan.wav"), "{e}");
        let e = Audio::new(8000, vec![vec![0.0, f32::INFINITY], vec![0.0; 2]]).unwrap_err();
        assert!(
            matches!(
                e,
                Error::NonFiniteSample {
                    channel: 1,
                    sample: 1,
                    ..
                }
            ),
            "{e}"
        );
    }

    #[test]
    fn a_64_bit_float_wav_is_named_as_unsupported() {
        // A valid WAV (IEEE float, format 3) of 64-bit samples, written by hand: hound reads
        // 32-bit floats only, and the error says what to convert to.
        let (channels, rate, bits) = (2u16, 16_000u32, 64u16);
        let data: Vec<u8> = [0.5f64, -0.5, 0.25, 0.0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let block = channels * bits / 8;
        let mut b = Vec::new();
        b.extend_from_slice(b"RIFF");
        b.extend_from_slice(&(36 + data.len() as u32).to_le_bytes());
        b.extend_from_slice(b"WAVEfmt ");
        b.extend_from_slice(&16u32.to_le_bytes());
        b.extend_from_slice(&3u16.to_le_bytes());
        b.extend_from_slice(&channels.to_le_bytes());
        b.extend_from_slice(&rate.to_le_bytes());
        b.extend_from_slice(&(rate * u32::from(block)).to_le_bytes());
        b.extend_from_slice(&block.to_le_bytes());
        b.extend_from_slice(&bits.to_le_bytes());
        b.extend_from_slice(b"data");
        b.extend_from_slice(&(data.len() as u32).to_le_bytes());
        b.extend_from_slice(&data);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("double.wav");
        std::fs::write(&p, b).unwrap();
        let e = read_wav(&p).unwrap_err().to_string();
        assert!(
            e.contains("double.wav") && e.contains("64-bit") && e.contains("32-bit float"),
            "{e}"
        );
    }

    #[test]
    fn ragged_channels_are_refused() {
        assert!(matches!(
            Audio::new(8000, vec![vec![0.0; 3], vec![0.0; 2]]),
            Err(Error::RaggedAudio)
        ));
        assert!(matches!(Audio::new(8000, vec![]), Err(Error::RaggedAudio)));
    }

    #[test]
    fn channels_are_selected_in_the_order_asked() {
        let a = Audio::new(8000, vec![vec![1.0; 2], vec![2.0; 2], vec![3.0; 2]]).unwrap();
        let b = a.select(&[2, 0]).unwrap();
        assert_eq!(b.channels(), &[vec![3.0; 2], vec![1.0; 2]]);
        assert_eq!(b.sample_rate(), 8000);
        assert!(matches!(
            a.select(&[0, 3]),
            Err(Error::NoSuchChannel {
                channel: 4,
                channels: 3
            })
        ));
        assert!(matches!(a.select(&[]), Err(Error::RaggedAudio)));
    }
}
