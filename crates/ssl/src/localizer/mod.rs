//! The localizer: from multichannel audio to a pooled angular spectrum and ranked DoAs.

use std::ops::Range;
use std::sync::{Arc, Mutex};

use realfft::num_complex::Complex32;

use crate::array::MicArray;
use crate::audio::Audio;
use crate::channels::{ChannelStats, Fault};
use crate::config::{Pooling, SslConfig};
use crate::covariance::SpatialCovariance;
use crate::error::{ConfigError, Error, Result};
use crate::grid::{DirectionGrid, ElevationRange, unit_vector};
use crate::method::{MethodScratch, SpectrumEstimator};
use crate::noise::NoiseField;
use crate::spectrum::{AngularSpectrum, Doa, wrap_deg};
use crate::stft::{Spectrogram, Stft};

mod pool;
mod rules;
#[cfg(test)]
mod tests;

/// A block more than this many dB below the recording's loudest casts no dominance vote
/// (see [`SslConfig::dominance_blocks`]): in a pause or a silence the strongest direction
/// of a block is a random one of the sensor noise or the room's decay. Its own floor, not
/// [`SslConfig::decay_gate_db`], so that turning the decay gate off (0, as MBSS Locate
/// pools) leaves the vote as it is; with the default gate the two are equal.
const VOTE_QUIET_DB: f64 = 10.0;

/// Working memory of a [`Localizer`], grown on first use and reused after: one per
/// thread, passed to [`Localizer::locate_with_scratch`]. It holds the recording's STFT and
/// the pooling's buffers, and the estimators' own working memory ([`MethodScratch`]).
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    /// The spectrum estimator's working memory.
    pub(crate) method: MethodScratch,
    /// One block's spectrum.
    pub(crate) block: Vec<f32>,
    /// The recording's STFT, its memory kept from one recording to the next.
    pub(crate) spec: Spectrogram,
    /// One octave of the recording's STFT ([`SslConfig::subband_votes`]).
    pub(crate) octave: Spectrogram,
    /// The octaves' blocks of the last recording, when its estimator kept the octaves'
    /// contributions in the band's own pass ([`SpectrumEstimator::estimate_blocks_parts`]).
    pub(crate) parts: OctaveParts,
    /// One octave's block spectra.
    pub(crate) part_spectra: Vec<f32>,
}

/// The octaves' blocks that the band's pass kept the contributions of ([`Scratch::parts`]).
#[derive(Clone, Debug, Default)]
pub(crate) struct OctaveParts {
    /// The blocks estimated (those the band's pooling kept), ascending.
    blocks: Vec<usize>,
    /// Whether the estimator kept this recording's octaves.
    valid: bool,
}

/// Where [`Localizer::pool`] takes its block spectra from.
#[derive(Clone, Copy)]
enum Blocks<'a> {
    /// The localizer's estimator.
    Estimate,
    /// The estimator, keeping the octaves' contributions in the same pass
    /// ([`Scratch::parts`]).
    EstimateWithOctaves,
    /// The spectra of `blocks` (ascending), one after the other: an octave's, read from
    /// the band's pass ([`SpectrumEstimator::part_spectra`]).
    Stored {
        spectra: &'a [f32],
        blocks: &'a [usize],
    },
}

/// The DoAs of one recording ([`Localizer::locate_row_with_scratch`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Located {
    /// At most [`SslConfig::num_peaks`], strongest first.
    pub doas: Vec<Doa>,
    /// Whether `num_peaks` cut the row: a further peak passed every threshold. A row that
    /// is not cut holds every peak the thresholds let through, so a full row is then as
    /// telling as a shorter one (what it does not hold was not heard); a cut one holds the
    /// strongest `N` of more.
    pub cut: bool,
    /// In a cut row, the directions beyond `N` that the band's octaves heard as the
    /// strongest of enough blocks ([`SslConfig::subband_votes`]), most votes first, none
    /// within [`SslConfig::min_sep_deg`] of a DoA of the row: sources the `N` strongest
    /// pooled peaks left out. Each has the full band's pooled values at its direction, and
    /// its octaves' votes as [`Doa::dominant_blocks`]. Empty in a row that was not cut.
    pub extra: Vec<Doa>,
    /// How this recording's blocks were pooled: [`Pooling::Max`] or [`Pooling::Mean`],
    /// the one [`Pooling::Auto`] chose (see [`crate::steady`]) or the one set.
    pub pooling: Pooling,
    /// The channels found not to hear the room, ascending, each with why
    /// ([`SslConfig::screen_channels`], [`crate::channels`]); empty for a recording of
    /// working microphones, or with the screen off.
    pub faulty_channels: Vec<(usize, Fault)>,
    /// The microphones the row was localised with: the array's, or fewer when faulty
    /// channels were left out. They are left out when at least two others remain, the
    /// array of those is no line unless the whole array is one (its DoAs would be folded
    /// onto one side of the line, the mapper's rows not), and the settings hold for it;
    /// otherwise the row is localised with every channel, or (a single working
    /// microphone) holds no DoA.
    pub microphones: usize,
}

impl Located {
    /// The row's DoAs and then its extra ones.
    pub fn all(&self) -> impl Iterator<Item = &Doa> {
        self.doas.iter().chain(&self.extra)
    }
}

/// The lower edges of the octaves whose block maxima vote for the extra DoAs of a cut row
/// ([`SslConfig::subband_votes`]); the band's top closes the last.
const SUBBAND_EDGES_HZ: [f64; 3] = [700.0, 1500.0, 3000.0];

/// The octaves' grid ([`SslConfig::subband_votes`]) is no finer than this in azimuth and
/// elevation (degrees).
const SUBBAND_AZ_STEP_DEG: f64 = 2.0;
const SUBBAND_EL_STEP_DEG: f64 = 20.0;

/// Peaks of different octaves within this many degrees are one direction: an octave's
/// peak of one source scatters by a few degrees from another's (its beam is up to four
/// times as wide, and reflections pull it differently), as measured.
const SUBBAND_MERGE_DEG: f64 = 6.0;

/// Frames of the synthetic plane wave of [`Localizer::plane_wave_profile`] at most.
const WAVE_MAX_FRAMES: usize = 8;

/// A localizer of some of an array's microphones (the channels it keeps, ascending), or
/// `None` where they cannot localise by themselves ([`Located::microphones`]).
type Subset = (Vec<usize>, Option<Arc<Localizer>>);

/// A validated, precomputed SSL front end for one array and sample rate.
///
/// Building it plans the FFT, the window, the direction grid and every pair's delay
/// tables; [`Localizer::locate`] then only transforms and sums.
pub struct Localizer {
    array: MicArray,
    sample_rate: u32,
    config: SslConfig,
    stft: Stft,
    bins: Range<usize>,
    grid: DirectionGrid,
    estimator: Box<dyn SpectrumEstimator>,
    /// The synthetic plane wave of [`Localizer::plane_wave_profile`]: its inverse FFT and
    /// its fixed phases, one per bin.
    wave_fft: std::sync::Arc<dyn realfft::ComplexToReal<f32>>,
    wave_phases: Vec<f64>,
    /// One localizer per octave of [`SslConfig::subband_votes`] (none when it is 0), each
    /// pooling its own bins of this localizer's STFT.
    subbands: Vec<Localizer>,
    /// The band's grid direction nearest each of the octaves' (all the octaves' grids are
    /// one).
    octave_dirs: Vec<usize>,
    /// For a linear array, the azimuth of its line ([`Localizer::mirror_axis_deg`]).
    mirror_axis_deg: Option<f64>,
    /// Whether rows are deflated ([`SslConfig::deflates`]).
    deflate: bool,
    /// Localizers of this one's array without some of its microphones, keyed by the
    /// channels they keep (ascending), built when a recording first needs one
    /// ([`SslConfig::screen_channels`]); `None` where those channels cannot localise by
    /// themselves (see [`Located::microphones`]).
    subsets: Mutex<Vec<Subset>>,
    /// The robot's own noise, subtracted from every statistic ([`Localizer::with_noise`]).
    noise: Option<Arc<NoiseField>>,
}

impl std::fmt::Debug for Localizer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Localizer")
            .field("array", &self.array.name())
            .field("sample_rate", &self.sample_rate)
            .field("method", &self.estimator.name())
            .field("stft", &self.stft)
            .field("bins", &self.bins)
            .finish()
    }
}

impl Localizer {
    /// Validates `config` for `array` at `sample_rate` and precomputes the tables.
    ///
    /// # Errors
    /// The first [`ConfigError`] found, including a band with no bin at this rate.
    pub fn new(
        array: &MicArray,
        sample_rate: u32,
        config: &SslConfig,
    ) -> Result<Self, ConfigError> {
        config.validate()?;
        if sample_rate == 0 {
            return Err(ConfigError::SampleRate);
        }
        let fs = f64::from(sample_rate);
        let frame_len = config.frame_len_at(sample_rate);
        let stft = Stft::new(frame_len, config.hop.unwrap_or(frame_len / 2))?;
        let nyquist = fs / 2.0;
        let fmax = config.band_top_hz(sample_rate);
        if !(config.fmin_hz >= 0.0 && config.fmin_hz < fmax) {
            return Err(ConfigError::Band {
                fmin: config.fmin_hz,
                fmax: config.fmax_hz,
                nyquist,
            });
        }
        let spacing = fs / frame_len as f64;
        // The DC bin carries no phase, hence no delay: it is never used.
        let lo = ((config.fmin_hz / spacing).ceil() as usize).max(1);
        let hi = (fmax / spacing).floor() as usize;
        if lo > hi {
            return Err(ConfigError::BandHasNoBin {
                fmin: config.fmin_hz,
                fmax,
                spacing,
            });
        }
        let bins = lo..hi + 1;
        let elevation = config
            .elevation
            .unwrap_or_else(|| crate::ElevationRange::auto(array));
        let grid = DirectionGrid::new(config.az_step_deg, elevation)?;
        let estimator = crate::method::estimator(config, array, &grid, fs, bins.clone(), frame_len);
        // One block of the wave, but no more than `WAVE_MAX_FRAMES` frames: a block longer
        // than the wave is the whole wave (one block, as for a recording shorter than a
        // block), and the profile of a stationary periodic noise does not change with its
        // length. Without the cap, `block_frames` set to pool one spectrum per recording
        // (pyroomacoustics' use) planned an FFT of 50 million samples.
        let wave_frames = config.block_frames.min(WAVE_MAX_FRAMES);
        let wave_len = frame_len + (wave_frames - 1) * stft.hop();
        let wave_fft = realfft::RealFftPlanner::<f32>::new().plan_fft_inverse(wave_len);
        // A fixed sequence of phases (xorshift64): every call hears the same wave.
        let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
        let wave_phases = (0..wave_len / 2 + 1)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 11) as f64 / (1u64 << 53) as f64 * std::f64::consts::TAU
            })
            .collect();
        let mut subbands = Vec::new();
        if config.subband_votes > 0 {
            let tops = SUBBAND_EDGES_HZ.iter().skip(1).copied().chain([fmax]);
            for (lo, hi) in SUBBAND_EDGES_HZ.iter().zip(tops) {
                let (lo, hi) = (lo.max(config.fmin_hz), hi.min(fmax));
                // An octave the band does not reach, or holds no bin of, casts no vote.
                if lo >= hi || (lo / spacing).ceil() > (hi / spacing).floor() {
                    continue;
                }
                // A coarser grid than the full band's: an octave's block maximum only
                // votes, within `SUBBAND_MERGE_DEG`, and costs a third as much to find.
                // Whole multiples of the band's steps, so that when the band's pass gives
                // the octaves' spectra its directions are among the band's.
                let coarser = |step: f64, at_least: f64| step * (at_least / step).round().max(1.0);
                let octave = SslConfig {
                    fmin_hz: lo,
                    fmax_hz: hi,
                    subband_votes: 0,
                    // An octave's DoAs are its block maxima, not placed peaks.
                    placement_share: 0.0,
                    az_step_deg: coarser(grid.az_step_deg(), SUBBAND_AZ_STEP_DEG),
                    elevation: Some(ElevationRange {
                        step_deg: coarser(elevation.step_deg, SUBBAND_EL_STEP_DEG),
                        ..elevation
                    }),
                    ..config.clone()
                };
                subbands.push(Self::new(array, sample_rate, &octave)?);
            }
        }
        let octave_dirs = subbands
            .first()
            .map_or_else(Vec::new, |s: &Localizer| grid.nearest_of(&s.grid));
        Ok(Self {
            array: array.clone(),
            sample_rate,
            config: config.clone(),
            stft,
            bins,
            grid,
            estimator,
            wave_fft,
            wave_phases,
            octave_dirs,
            subbands,
            mirror_axis_deg: array.mirror_axis_deg(),
            deflate: config.deflates(array, sample_rate),
            subsets: Mutex::default(),
            noise: None,
        })
    }

    /// This localizer, subtracting the robot's own noise as heard in `noise`, a recording
    /// of the robot alone (its fans running, no other source; a few seconds), from every
    /// statistic it measures ([`crate::noise`]).
    ///
    /// # Errors
    /// A recording of another channel count or sample rate than this localizer's, or
    /// shorter than [`crate::noise::MIN_NOISE_FRAMES`] STFT frames.
    pub fn with_noise(self, noise: &Audio) -> Result<Self> {
        let mut scratch = Scratch::default();
        self.analyse(noise, &mut scratch)?;
        let field = NoiseField::of(&scratch.spec)?;
        Ok(self.with_noise_field(Arc::new(field)))
    }

    /// This localizer with `field` as the robot's noise ([`Localizer::with_noise`]).
    ///
    /// # Panics
    /// If `field` was estimated with another channel count or band.
    pub fn with_noise_field(mut self, field: Arc<NoiseField>) -> Self {
        assert_eq!(
            field.num_channels(),
            self.array.len(),
            "one channel per microphone"
        );
        assert!(
            field.bins().start <= self.bins.start && self.bins.end <= field.bins().end,
            "the noise field holds the band"
        );
        self.subsets = Mutex::default();
        self.noise = Some(field);
        self
    }

    /// The robot's noise this localizer subtracts, if any.
    pub fn noise(&self) -> Option<&NoiseField> {
        self.noise.as_deref()
    }

    /// The localizer of this one's microphones `keep` (ascending, fewer than all), built
    /// on first use and kept; `None` when they cannot localise by themselves (see
    /// [`Located::microphones`]). Its settings are this one's, deflating as this one
    /// does and without a screen of its own.
    fn subset(&self, keep: &[usize]) -> Option<Arc<Localizer>> {
        let mut subsets = self.subsets.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, l)) = subsets.iter().find(|(k, _)| k == keep) {
            return l.clone();
        }
        let positions = keep.iter().map(|&i| self.array.positions()[i]).collect();
        let without: Vec<String> = (0..self.array.len())
            .filter(|i| !keep.contains(i))
            .map(|i| (i + 1).to_string())
            .collect();
        let name = format!(
            "{} without channel {}",
            self.array.name(),
            without.join(", ")
        );
        let config = SslConfig {
            deflate: Some(self.deflate),
            screen_channels: false,
            ..self.config.clone()
        };
        let l = MicArray::new(name, positions)
            .ok()
            .filter(|a| a.linear_axis().is_none() || self.array.linear_axis().is_some())
            .and_then(|a| Localizer::new(&a, self.sample_rate, &config).ok())
            .map(|l| match &self.noise {
                Some(n) => l.with_noise_field(Arc::new(n.subset(keep))),
                None => l,
            })
            .map(Arc::new);
        subsets.push((keep.to_vec(), l.clone()));
        l
    }

    /// For a linear array ([`MicArray::linear_axis`]), the azimuth of its line (degrees,
    /// array frame, in `[0, 180)`); `None` for any other array.
    ///
    /// A linear array cannot tell a source at azimuth `a` from its mirror image at
    /// `2 axis - a`: this localizer reports each source once, on the line's
    /// counter-clockwise side (`axis` to `axis + 180`, as [`crate::fold_azimuth`] folds
    /// a bearing; see [`AngularSpectrum::with_mirror_axis`]), and leaves the choice between
    /// the two to a robot that turns (`asm::IasmConfig::mirror_axis_deg`).
    pub fn mirror_axis_deg(&self) -> Option<f64> {
        self.mirror_axis_deg
    }

    /// Whether the octaves' block spectra come from the band's own pass
    /// ([`SpectrumEstimator::estimate_blocks_parts`]) rather than from the octave
    /// localizers.
    fn shared_octaves(&self) -> bool {
        !self.subbands.is_empty() && self.estimator.estimates_parts()
    }

    /// The array.
    pub fn array(&self) -> &MicArray {
        &self.array
    }

    /// The sample rate (Hz) the tables were built for.
    pub fn sample_rate(&self) -> u32 {
        self.sample_rate
    }

    /// The settings.
    pub fn config(&self) -> &SslConfig {
        &self.config
    }

    /// The direction grid.
    pub fn grid(&self) -> &DirectionGrid {
        &self.grid
    }

    /// The planned STFT.
    pub fn stft(&self) -> &Stft {
        &self.stft
    }

    /// The estimator in use.
    pub fn estimator(&self) -> &dyn SpectrumEstimator {
        &*self.estimator
    }

    /// The pooled angular spectrum of `audio`, from every channel: the screen of faulty
    /// channels ([`SslConfig::screen_channels`]) is [`Localizer::locate`]'s; a caller can
    /// run [`crate::channels::faults`] on the STFT and [`Audio::select`] the others.
    ///
    /// # Errors
    /// [`Error::ChannelMismatch`], [`Error::SampleRateMismatch`] or [`Error::TooShort`].
    pub fn spectrum(&self, audio: &Audio) -> Result<AngularSpectrum> {
        self.spectrum_with_scratch(audio, &mut Scratch::default())
    }

    /// [`Localizer::spectrum`] with working memory the caller keeps between recordings.
    ///
    /// # Errors
    /// As [`Localizer::spectrum`].
    pub fn spectrum_with_scratch(
        &self,
        audio: &Audio,
        scratch: &mut Scratch,
    ) -> Result<AngularSpectrum> {
        self.spectrum_from(audio, scratch, Blocks::Estimate)
    }

    /// [`Localizer::spectrum_with_scratch`], the block spectra taken from `blocks`.
    fn spectrum_from(
        &self,
        audio: &Audio,
        scratch: &mut Scratch,
        blocks: Blocks<'_>,
    ) -> Result<AngularSpectrum> {
        self.analyse(audio, scratch)?;
        Ok(self.pooled(scratch, blocks))
    }

    /// Checks that `audio` fits this localizer and writes its STFT (the band's bins) into
    /// `scratch.spec`.
    fn analyse(&self, audio: &Audio, scratch: &mut Scratch) -> Result<()> {
        if audio.num_channels() != self.array.len() {
            return Err(Error::ChannelMismatch {
                expected: self.array.len(),
                got: audio.num_channels(),
            });
        }
        if audio.sample_rate() != self.sample_rate {
            return Err(Error::SampleRateMismatch {
                expected: self.sample_rate,
                got: audio.sample_rate(),
            });
        }
        self.stft
            .analyze_into(audio, self.bins.clone(), &mut scratch.spec)?;
        scratch.spec.noise = self.noise.clone();
        Ok(())
    }

    /// [`Localizer::locate_row_with_scratch`] on an STFT computed elsewhere
    /// ([`Spectrogram::from_frames`], of this localizer's `frame_len`), whose bins must
    /// hold the localizer's band: its channels are taken as they are (no screen of faulty
    /// channels: that needs the recording), the robot's noise subtracted when known.
    /// Returns the row and the pooled spectrum whose peaks its DoAs are.
    ///
    /// # Errors
    /// [`Error::ChannelMismatch`], or [`Error::BandNotInSpectrogram`] when the band's bins
    /// are not all in `spec`.
    pub fn locate_spectrogram(
        &self,
        spec: &Spectrogram,
        scratch: &mut Scratch,
    ) -> Result<(Located, AngularSpectrum)> {
        self.take_spectrogram(spec, scratch)?;
        self.located_with_spectrum(scratch)
    }

    /// Writes the localizer's band of `spec` into `scratch.spec`.
    fn take_spectrogram(&self, spec: &Spectrogram, scratch: &mut Scratch) -> Result<()> {
        if spec.num_channels() != self.array.len() {
            return Err(Error::ChannelMismatch {
                expected: self.array.len(),
                got: spec.num_channels(),
            });
        }
        let have = spec.bins();
        if !(have.start <= self.bins.start && self.bins.end <= have.end) || spec.num_frames() == 0 {
            return Err(Error::BandNotInSpectrogram {
                band: (self.bins.start, self.bins.end),
                have: (have.start, have.end),
                frames: spec.num_frames(),
            });
        }
        spec.band_into(self.bins.clone(), &mut scratch.spec);
        scratch.spec.noise = self.noise.clone();
        Ok(())
    }

    /// The ranked DoAs of `audio`: at most `num_peaks`, strongest first.
    ///
    /// # Errors
    /// As [`Localizer::spectrum`].
    pub fn locate(&self, audio: &Audio) -> Result<Vec<Doa>> {
        self.locate_with_scratch(audio, &mut Scratch::default())
    }

    /// [`Localizer::locate`] with working memory the caller keeps between recordings.
    ///
    /// # Errors
    /// As [`Localizer::spectrum`].
    pub fn locate_with_scratch(&self, audio: &Audio, scratch: &mut Scratch) -> Result<Vec<Doa>> {
        Ok(self.locate_row_with_scratch(audio, scratch)?.doas)
    }

    /// [`Localizer::locate_with_scratch`], and whether `num_peaks` cut the row: a further
    /// peak passed every threshold (see [`Located::cut`]).
    ///
    /// # Errors
    /// As [`Localizer::spectrum`].
    pub fn locate_row_with_scratch(&self, audio: &Audio, scratch: &mut Scratch) -> Result<Located> {
        self.analyse(audio, scratch)?;
        if !self.config.screen_channels {
            return self.located(scratch);
        }
        let faulty = crate::channels::faults(&ChannelStats::of(&scratch.spec));
        if !faulty.is_empty() {
            let keep: Vec<usize> = (0..self.array.len())
                .filter(|i| faulty.iter().all(|(f, _)| f != i))
                .collect();
            if keep.len() < 2 {
                // One microphone hears no direction.
                return Ok(Located {
                    doas: Vec::new(),
                    cut: false,
                    extra: Vec::new(),
                    pooling: match self.config.pooling {
                        Pooling::Auto => Pooling::Max,
                        p => p,
                    },
                    faulty_channels: faulty,
                    microphones: keep.len(),
                });
            }
            if let Some(sub) = self.subset(&keep) {
                let part = Audio::new(
                    audio.sample_rate(),
                    keep.iter().map(|&i| audio.channels()[i].clone()).collect(),
                )?;
                let row = sub.locate_row_with_scratch(&part, scratch)?;
                return Ok(Located {
                    faulty_channels: faulty,
                    ..row
                });
            }
        }
        Ok(Located {
            faulty_channels: faulty,
            ..self.located(scratch)?
        })
    }
}
