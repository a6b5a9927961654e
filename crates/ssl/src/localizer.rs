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
use crate::grid::{DirectionGrid, ElevationRange, PairScratch, unit_vector};
use crate::method::music::SubspaceScratch;
use crate::noise::NoiseField;
use crate::spectrum::{AngularSpectrum, Doa, wrap_deg};
use crate::stft::{Spectrogram, Stft};

/// A block more than this many dB below the recording's loudest casts no dominance vote
/// (see [`SslConfig::dominance_blocks`]): in a pause or a silence the strongest direction
/// of a block is a random one of the sensor noise or the room's decay. Its own floor, not
/// [`SslConfig::decay_gate_db`], so that turning the decay gate off (0, as MBSS Locate
/// pools) leaves the vote as it is; with the default gate the two are equal.
const VOTE_QUIET_DB: f64 = 10.0;

/// An angular-spectrum method: writes the spectrum of a block of STFT frames.
pub trait SpectrumEstimator: Send + Sync {
    /// Stable short name used in reports (`"gcc-phat"`, `"mvdr"`).
    fn name(&self) -> &'static str;

    /// Writes the angular spectrum of frames `frames` of `stft` into `out`, one value per
    /// direction of the grid the estimator was built for. `scratch` is working memory that
    /// the caller keeps between calls (RustFFT's `process_with_scratch`): the estimators
    /// run once per block of frames, dozens of times per recording, and allocate nothing
    /// once it has grown to size. Its contents on entry do not matter.
    ///
    /// # Panics
    /// If `out` does not hold one value per direction, `frames` is out of range, or `stft`
    /// was not made with the band and channel count the estimator was built for.
    fn estimate_into(
        &self,
        stft: &Spectrogram,
        frames: Range<usize>,
        out: &mut [f32],
        scratch: &mut Scratch,
    );

    /// The spectra of several blocks: `sink(i, spectrum)` for each of `blocks` (frame
    /// ranges of `stft`), in order, each spectrum being what
    /// [`SpectrumEstimator::estimate_into`] writes for it (to within rounding: an override
    /// may sum in another order). `block` is a buffer of one
    /// value per direction. The default runs `estimate_into` block by block; an estimator
    /// whose work can be shared between blocks overrides it (the subspace methods form
    /// each direction's steering terms once per recording instead of once per block; the
    /// pairwise methods read their lag functions off at the directions a tile of blocks at
    /// a time).
    ///
    /// # Panics
    /// As [`SpectrumEstimator::estimate_into`].
    fn estimate_blocks(
        &self,
        stft: &Spectrogram,
        blocks: &[Range<usize>],
        block: &mut [f32],
        scratch: &mut Scratch,
        sink: &mut dyn FnMut(usize, &[f32]),
    ) {
        each_block(self, stft, blocks, block, scratch, sink);
    }

    /// Whether [`SpectrumEstimator::estimate_blocks_parts`] gives the spectra of parts of
    /// the band in the same pass as the band's. Default: no.
    fn estimates_parts(&self) -> bool {
        false
    }

    /// [`SpectrumEstimator::estimate_blocks`], and in the same pass what each of `parts`
    /// (bin ranges relative to the band; a bin in two counts in the first) contributes,
    /// kept in `scratch` for
    /// [`SpectrumEstimator::part_spectra`]. Returns whether it kept them; the default does
    /// not, and an estimator that shares no work between the band and its parts should
    /// not either (a localizer of each part is then as fast).
    ///
    /// # Panics
    /// As [`SpectrumEstimator::estimate_into`].
    fn estimate_blocks_parts(
        &self,
        stft: &Spectrogram,
        blocks: &[Range<usize>],
        parts: &[Range<usize>],
        block: &mut [f32],
        scratch: &mut Scratch,
        sink: &mut dyn FnMut(usize, &[f32]),
    ) -> bool {
        let _ = parts;
        self.estimate_blocks(stft, blocks, block, scratch, sink);
        false
    }

    /// After [`SpectrumEstimator::estimate_blocks_parts`] kept them (and before the next
    /// call of it), each block's spectrum of part `part` at the grid directions `dirs`,
    /// into `out` (block-major, one value per direction of `dirs`): to within a constant
    /// factor, what an estimator of that part alone would write there (the estimator says
    /// how its part's plan differs). The band's other estimates in between
    /// ([`SpectrumEstimator::estimate_blocks`], [`SpectrumEstimator::estimate_into`]) leave
    /// them as they are.
    ///
    /// # Panics
    /// If the parts were not kept; the default always panics.
    fn part_spectra(&self, part: usize, dirs: &[usize], scratch: &mut Scratch, out: &mut Vec<f32>) {
        let _ = (part, dirs, scratch, out);
        unreachable!("part_spectra without estimate_blocks_parts keeping the parts")
    }
}

/// [`SpectrumEstimator::estimate_blocks`] block by block, through `estimate_into`: the
/// default, and the fallback of an override for the cases it does not batch.
pub(crate) fn each_block<E: SpectrumEstimator + ?Sized>(
    estimator: &E,
    stft: &Spectrogram,
    blocks: &[Range<usize>],
    block: &mut [f32],
    scratch: &mut Scratch,
    sink: &mut dyn FnMut(usize, &[f32]),
) {
    for (i, frames) in blocks.iter().enumerate() {
        estimator.estimate_into(stft, frames.clone(), block, scratch);
        sink(i, block);
    }
}

/// Working memory of the spectrum estimators, grown on first use and reused after: one
/// per thread, passed to [`SpectrumEstimator::estimate_into`] or
/// [`Localizer::locate_with_scratch`]. Any estimator may use any scratch.
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    /// Per frame and channel, each bin's unit phasor (GCC-PHAT).
    pub(crate) unit: Vec<Complex32>,
    /// Per channel, bin powers summed over the block, then smoothed (MVDR).
    pub(crate) power: Vec<f32>,
    /// One channel's unsmoothed powers (MVDR).
    pub(crate) power_sum: Vec<f32>,
    /// One pair's cross-spectrum, summed then smoothed (MVDR).
    pub(crate) cross: Vec<Complex32>,
    pub(crate) cross_smooth: Vec<Complex32>,
    /// Prefix sums of the box smoother (MVDR).
    pub(crate) prefix_real: Vec<f32>,
    pub(crate) prefix_complex: Vec<Complex32>,
    /// The pairwise lag-function machinery ([`crate::grid`]).
    pub(crate) pairs: PairScratch,
    /// The full-array estimators' buffers ([`crate::music`]).
    pub(crate) subspace: SubspaceScratch,
    /// One block's spectrum (the localizer).
    pub(crate) block: Vec<f32>,
    /// The recording's STFT (the localizer), its memory kept from one recording to the next.
    pub(crate) spec: Spectrogram,
    /// A tile of blocks' lag functions and spectra (the pairwise methods).
    pub(crate) lag_tile: crate::grid::LagTile,
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

/// Whether this CPU can run the AVX2+FMA builds of the hot kernels (the lag sums, the
/// subspace steering), which are compiled beside the portable ones and chosen at run time.
#[cfg(target_arch = "x86_64")]
pub(crate) fn avx2_fma() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

/// Zero-filled `v` of length `n`, reusing its memory.
pub(crate) fn zeroed<T: Copy + Default>(v: &mut Vec<T>, n: usize) -> &mut [T] {
    v.clear();
    v.resize(n, T::default());
    v
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
/// times as wide, and reflections pull it differently), as measured in session 15.
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

    /// The pooled spectrum of the STFT in `scratch.spec` ([`Localizer::analyse`]), the
    /// block spectra taken from `blocks`.
    fn pooled(&self, scratch: &mut Scratch, blocks: Blocks<'_>) -> AngularSpectrum {
        let spec = std::mem::take(&mut scratch.spec);
        let pooling = self.pooling_of(&spec);
        let pooled = self.pool(&spec, scratch, blocks, pooling);
        scratch.spec = spec;
        pooled
    }

    /// How the blocks of `spec` are pooled: as set, or for [`Pooling::Auto`], the mean
    /// where the recording is steady and noise-like in each octave of the band
    /// ([`crate::steady`]), else max.
    fn pooling_of(&self, spec: &Spectrogram) -> Pooling {
        if self.config.pooling != Pooling::Auto {
            return self.config.pooling;
        }
        let (n_blocks, frames) = self.blocks(spec.num_frames());
        if crate::steady::Octaves::of(spec, n_blocks, &frames).is_steady() {
            Pooling::Mean
        } else {
            Pooling::Max
        }
    }

    /// The pooled spectrum of the blocks of `spec` (this localizer's band, or a wider one
    /// of the same STFT: see [`Spectrogram::band_into`]), its dominance votes with it;
    /// the block spectra from `source`. Stored spectra pool only the blocks they hold.
    fn pool(
        &self,
        spec: &Spectrogram,
        scratch: &mut Scratch,
        source: Blocks<'_>,
        pooling: Pooling,
    ) -> AngularSpectrum {
        let nf = spec.num_frames();
        let (n_blocks, frames) = self.blocks(nf);
        let dominance = self.config.dominance_blocks > 0;
        let energy = if dominance || self.config.decay_gate_db > 0.0 {
            block_energies(spec, n_blocks, &frames)
        } else {
            Vec::new()
        };
        let mut keep = self.gate(&energy, n_blocks, nf);
        if let Blocks::Stored { blocks, .. } = source {
            for (b, k) in keep.iter_mut().enumerate() {
                *k = *k && blocks.binary_search(&b).is_ok();
            }
        }
        let kept = keep.iter().filter(|&&k| k).count();
        // Per azimuth cell, the blocks whose strongest direction lies there (see
        // `SslConfig::dominance_blocks`). A block holding half the energy of the one before
        // or less is the room's decay, and one more than `VOTE_QUIET_DB` below the
        // recording's loudest is a pause or silence: neither votes.
        let n_az = self.grid.num_azimuths();
        let mut votes = vec![0u32; if dominance { n_az } else { 0 }];
        let loudest = energy.iter().copied().fold(0.0, f64::max);
        let quiet = loudest * 10f64.powf(-VOTE_QUIET_DB / 10.0);
        let votes_in = |b: usize| {
            dominance && energy[b] >= quiet && (b == 0 || energy[b] >= 0.5 * energy[b - 1])
        };
        let mut pooled = vec![0.0f32; self.grid.len()];
        let mut block = std::mem::take(&mut scratch.block);
        block.resize(self.grid.len(), 0.0);
        // Max pooling keeps each direction's `k` largest block values, largest first (k = 1:
        // the plain maximum), and pools their mean.
        let k = self.config.pool_top.min(kept).max(1);
        let max = pooling != Pooling::Mean;
        let mut top = if max {
            vec![f32::NEG_INFINITY; pooled.len() * k]
        } else {
            Vec::new()
        };
        // Each block's azimuth profile, for placing the DoAs (`SslConfig::placement_share`;
        // the octaves' localizers have it off: their DoAs are block maxima).
        let place = max && self.config.placement_share > 0.0;
        let mut profiles: Vec<f32> = Vec::with_capacity(if place { kept * n_az } else { 0 });
        let kept_blocks: Vec<usize> = (0..n_blocks).filter(|&b| keep[b]).collect();
        let ranges: Vec<Range<usize>> = kept_blocks.iter().map(|&b| frames(b)).collect();
        let mut sink = |i: usize, block: &[f32]| {
            let b = kept_blocks[i];
            if votes_in(b) {
                let (mut best, mut at) = (f32::NEG_INFINITY, 0);
                for (d, &v) in block.iter().enumerate() {
                    if v > best {
                        (best, at) = (v, d);
                    }
                }
                votes[at % n_az] += 1;
            }
            if place {
                let at = profiles.len();
                profiles.extend_from_slice(&block[..n_az]);
                for row in block.chunks_exact(n_az).skip(1) {
                    profiles[at..]
                        .iter_mut()
                        .zip(row)
                        .for_each(|(p, &v)| *p = p.max(v));
                }
            }
            match (max, k) {
                // The plain maximum as one vectorisable pass.
                (true, 1) => top.iter_mut().zip(block).for_each(|(t, &v)| *t = t.max(v)),
                (true, _) => {
                    for (t, &v) in top.chunks_exact_mut(k).zip(block) {
                        if v > t[k - 1] {
                            let mut i = k - 1;
                            while i > 0 && t[i - 1] < v {
                                t[i] = t[i - 1];
                                i -= 1;
                            }
                            t[i] = v;
                        }
                    }
                }
                (false, _) => pooled
                    .iter_mut()
                    .zip(block)
                    .for_each(|(p, &v)| *p += v / kept as f32),
            }
        };
        match source {
            Blocks::Estimate => self
                .estimator
                .estimate_blocks(spec, &ranges, &mut block, scratch, &mut sink),
            Blocks::EstimateWithOctaves => {
                let mut parts = std::mem::take(&mut scratch.parts);
                let octaves: Vec<Range<usize>> = self
                    .subbands
                    .iter()
                    .map(|s| s.bins.start - self.bins.start..s.bins.end - self.bins.start)
                    .collect();
                parts.valid = self
                    .estimator
                    .estimate_blocks_parts(spec, &ranges, &octaves, &mut block, scratch, &mut sink);
                parts.blocks.clone_from(&kept_blocks);
                scratch.parts = parts;
            }
            Blocks::Stored { spectra, blocks } => {
                let nd = self.grid.len();
                for (i, b) in kept_blocks.iter().enumerate() {
                    let at = blocks
                        .binary_search(b)
                        .expect("only stored blocks are kept");
                    sink(i, &spectra[at * nd..(at + 1) * nd]);
                }
            }
        }
        if max {
            for (p, t) in pooled.iter_mut().zip(top.chunks_exact(k)) {
                *p = t.iter().sum::<f32>() / k as f32;
            }
        }
        scratch.block = block;
        AngularSpectrum::new(self.grid.clone(), pooled)
            .with_pooling(if max { Pooling::Max } else { Pooling::Mean })
            .with_votes(votes)
            .with_mirror_axis(self.mirror_axis_deg)
            .with_block_profiles(profiles)
    }

    /// How `nf` frames split into blocks: their number, and each block's frames. Blocks
    /// split the frames as evenly as possible and cover all of them.
    fn blocks(&self, nf: usize) -> (usize, impl Fn(usize) -> Range<usize> + Copy) {
        let n_blocks = (nf / self.config.block_frames).max(1);
        (n_blocks, move |b: usize| {
            b * nf / n_blocks..(b + 1) * nf / n_blocks
        })
    }

    /// The frames of the blocks of `spec` that the pooling keeps ([`Localizer::gate`]).
    fn kept_frames(&self, spec: &Spectrogram) -> Vec<Range<usize>> {
        let nf = spec.num_frames();
        let (n_blocks, frames) = self.blocks(nf);
        let energy = if self.config.decay_gate_db > 0.0 {
            block_energies(spec, n_blocks, &frames)
        } else {
            Vec::new()
        };
        let keep = self.gate(&energy, n_blocks, nf);
        (0..n_blocks).filter(|&b| keep[b]).map(frames).collect()
    }

    /// [`Localizer::gate`] on the blocks of `spec` (the tests' entry).
    #[cfg(test)]
    fn decay_gate(
        &self,
        spec: &Spectrogram,
        n_blocks: usize,
        frames: &dyn Fn(usize) -> Range<usize>,
    ) -> Vec<bool> {
        let energy = block_energies(spec, n_blocks, frames);
        self.gate(&energy, n_blocks, spec.num_frames())
    }

    /// Which of `n_blocks` blocks (of `nf` frames in all) the pooling keeps, given their
    /// energies ([`block_energies`]): all when the gate is off; else those whose energy is
    /// within `decay_gate_db` of the loudest block of the preceding `decay_window_s` (see
    /// [`SslConfig::decay_gate_db`]). The loudest block of a recording is always kept.
    fn gate(&self, energy: &[f64], n_blocks: usize, nf: usize) -> Vec<bool> {
        let gate = self.config.decay_gate_db;
        if gate <= 0.0 || n_blocks < 2 {
            return vec![true; n_blocks];
        }
        // Blocks per window: the window's length over one block's hop in time.
        let frames_per_block = nf as f64 / n_blocks as f64;
        let block_s = self.stft.hop() as f64 * frames_per_block / f64::from(self.sample_rate);
        let window = ((self.config.decay_window_s / block_s).round() as usize).max(1);
        let floor = 10f64.powf(-gate / 10.0);
        (0..n_blocks)
            .map(|b| {
                let recent = energy[b.saturating_sub(window)..b]
                    .iter()
                    .copied()
                    .fold(0.0, f64::max);
                energy[b] >= floor * recent
            })
            .collect()
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

    /// The row of the recording whose STFT is in `scratch.spec` ([`Localizer::analyse`]),
    /// localised with every channel.
    fn located(&self, scratch: &mut Scratch) -> Result<Located> {
        let n = self.config.num_peaks;
        // The N strongest resolved peaks, and the next one: the row is cut when that one
        // passes the thresholds too (the peaks are taken strongest first, so the first N
        // are those of a search for N).
        let source = if self.shared_octaves() {
            Blocks::EstimateWithOctaves
        } else {
            Blocks::Estimate
        };
        let spectrum = self.pooled(scratch, source);
        let mut peaks =
            spectrum.resolved_peaks(n + 1, self.config.min_sep_deg, self.config.min_prominence);
        let next = (peaks.len() > n).then(|| peaks.remove(n));
        let stands_out = |d: &Doa| {
            let dominant = self.config.dominance_blocks;
            d.relative >= self.config.min_relative
                || (dominant > 0 && d.dominant_blocks as usize >= dominant)
        };
        let (mut doas, mut next) = if self.config.incoherent_relative > 0.0 {
            self.by_coherence(peaks, next, &scratch.spec, stands_out)
        } else {
            (
                peaks.into_iter().filter(stands_out).collect(),
                next.filter(stands_out),
            )
        };
        if self.config.sidelobe_ratio > 0.0 && doas.len() + usize::from(next.is_some()) > 1 {
            (doas, next) = self.drop_sidelobes(doas, next.take())?;
        }
        let checked = doas.len();
        doas.extend(next);
        // Every DoA's significance (cheap beside the spectrum: one pass over the frames,
        // then a few thousand terms per DoA); those below the floor are noise. The pass
        // over the frames is made once, for the row and its extra DoAs alike.
        let mut coherence = None;
        let mut significant = |doas: Vec<Doa>, spec: &Spectrogram| {
            let z = if doas.is_empty() {
                Vec::new()
            } else {
                let g = coherence.get_or_insert_with(|| self.coherence(spec));
                self.significance(g, &doas)
            };
            let floor = self.config.min_significance;
            doas.into_iter()
                .zip(z)
                .map(|(d, significance)| Doa { significance, ..d })
                .map(move |d| (floor <= 0.0 || d.significance >= floor).then_some(d))
                .collect::<Vec<_>>()
        };
        let mut row = significant(doas, &scratch.spec).into_iter();
        let doas: Vec<Doa> = row.by_ref().take(checked).flatten().collect();
        let cut = row.next().flatten().is_some();
        let extra = if cut && !self.subbands.is_empty() {
            let extra = self.octave_doas(&spectrum, &doas, scratch);
            significant(extra, &scratch.spec)
                .into_iter()
                .flatten()
                .collect()
        } else {
            Vec::new()
        };
        // Where each DoA lies: from its own best blocks (`SslConfig::placement_share`).
        let sep = self.config.min_sep_deg;
        let doas = spectrum.placed(doas, self.config.placement_share, 0.5 * sep, sep);
        let pooling = spectrum.pooling();
        let doas = if self.deflate && !cut && doas.len() >= 2 {
            self.deflated(doas, &scratch.spec, pooling)
        } else {
            doas
        };
        Ok(Located {
            doas,
            cut,
            extra,
            pooling,
            faulty_channels: Vec::new(),
            microphones: self.array.len(),
        })
    }

    /// `doas` (a row, strongest first) with each DoA but the first refined with the
    /// stronger ones projected out ([`SslConfig::deflate`], [`crate::deflate`]), on the
    /// blocks of `spec` that the pooling keeps.
    fn deflated(&self, doas: Vec<Doa>, spec: &Spectrogram, pooling: Pooling) -> Vec<Doa> {
        if spec.num_channels() < 3 {
            // One stronger DoA projected out leaves too few dimensions to search in.
            return doas;
        }
        let gate = self.config.deflate_max_residual;
        if gate > 0.0 && !crate::deflate::testable(doas.len(), spec.num_channels()) {
            // The gate cannot test the row: leave it before computing its covariances.
            return doas;
        }
        let blocks = self.kept_frames(spec);
        let cov = crate::deflate::BlockCovariances::of(spec, &blocks);
        let setup = crate::deflate::Setup {
            positions: self.array.positions(),
            fs: f64::from(self.sample_rate),
            frame_len: self.stft.frame_len(),
            c: self.config.speed_of_sound,
            pooling,
            pool_top: self.config.pool_top,
        };
        let at = |d: &Doa| (d.azimuth_deg, d.elevation_deg);
        let strong: Vec<(f64, f64)> = doas.iter().map(at).collect();
        if gate > 0.0
            && !crate::deflate::residual_share(&setup, spec, &cov, &strong)
                .is_some_and(|r| r < gate)
        {
            return doas;
        }
        doas.iter()
            .enumerate()
            .map(|(k, d)| Doa {
                azimuth_deg: crate::deflate::deflated_azimuth(
                    &setup,
                    spec,
                    &cov,
                    &strong[..k],
                    at(d),
                ),
                ..*d
            })
            .collect()
    }

    /// The extra DoAs of a cut row ([`Located::extra`]) before the significance floor:
    /// each octave of the band pooled on its own (the STFT in `scratch`), its resolved
    /// peaks with their block votes, merged across octaves within
    /// [`SUBBAND_MERGE_DEG`]; those with [`SslConfig::subband_votes`] votes or more and no
    /// DoA of `row` within [`SslConfig::min_sep_deg`], at most `N` of them, most votes
    /// first, read off the full band's pooled `spectrum`.
    fn octave_doas(
        &self,
        spectrum: &AngularSpectrum,
        row: &[Doa],
        scratch: &mut Scratch,
    ) -> Vec<Doa> {
        let c = &self.config;
        let spec = std::mem::take(&mut scratch.spec);
        let mut octave = std::mem::take(&mut scratch.octave);
        let parts = std::mem::take(&mut scratch.parts);
        let mut spectra = std::mem::take(&mut scratch.part_spectra);
        // (azimuth, votes) of every octave's peaks that dominated a block.
        let mut peaks: Vec<(f64, u32)> = Vec::new();
        for (o, sub) in self.subbands.iter().enumerate() {
            spec.band_into(sub.bins.clone(), &mut octave);
            let source = if self.shared_octaves() && parts.valid {
                self.estimator
                    .part_spectra(o, &self.octave_dirs, scratch, &mut spectra);
                Blocks::Stored {
                    spectra: &spectra,
                    blocks: &parts.blocks,
                }
            } else {
                Blocks::Estimate
            };
            let pooled = sub.pool(&octave, scratch, source, spectrum.pooling());
            peaks.extend(
                pooled
                    .resolved_peaks(2 * c.num_peaks, c.min_sep_deg, c.min_prominence)
                    .into_iter()
                    .filter(|p| p.dominant_blocks > 0)
                    .map(|p| (p.azimuth_deg, p.dominant_blocks)),
            );
        }
        scratch.spec = spec;
        scratch.octave = octave;
        scratch.parts = parts;
        scratch.part_spectra = spectra;
        // Greedily, the peak with the most votes takes every peak within the merge
        // distance: their votes summed, their azimuths averaged by votes.
        peaks.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.total_cmp(&b.0)));
        let mut merged: Vec<(f64, u32)> = Vec::new();
        while let Some(&(at, _)) = peaks.first() {
            let (near, rest): (Vec<_>, Vec<_>) = peaks
                .into_iter()
                .partition(|p| wrap_deg(p.0 - at).abs() <= SUBBAND_MERGE_DEG);
            let votes: u32 = near.iter().map(|p| p.1).sum();
            let offset: f64 = near
                .iter()
                .map(|p| wrap_deg(p.0 - at) * f64::from(p.1))
                .sum::<f64>()
                / f64::from(votes);
            merged.push((wrap_deg(at + offset), votes));
            peaks = rest;
        }
        merged.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.total_cmp(&b.0)));
        // Each direction is read off the full band's spectrum: at its strongest local
        // maximum within the merge distance (the octaves' coarser grid and their scatter
        // place it a few degrees off), else at its own cell.
        let maxima = spectrum.peaks(self.grid.num_azimuths(), 0.0);
        let (profile, el_at) = spectrum.azimuth_profile();
        let median = f64::from(crate::spectrum::median(&profile));
        let span = maxima.first().map_or(0.0, |d| d.strength - median);
        let mut extra: Vec<Doa> = Vec::new();
        for (azimuth_deg, votes) in merged {
            if (votes as usize) < c.subband_votes || extra.len() == c.num_peaks {
                break;
            }
            let near = |d: &&Doa| wrap_deg(d.azimuth_deg - azimuth_deg).abs() <= SUBBAND_MERGE_DEG;
            let doa = match maxima.iter().find(near) {
                Some(d) => Doa {
                    dominant_blocks: votes,
                    ..*d
                },
                None => {
                    let cell = self.grid.azimuth_cell(azimuth_deg);
                    let strength = f64::from(profile[cell]);
                    Doa {
                        azimuth_deg,
                        elevation_deg: self.grid.elevations()[el_at[cell]],
                        strength,
                        relative: if span > 0.0 {
                            (strength - median) / span
                        } else {
                            0.0
                        },
                        dominant_blocks: votes,
                        prominence: 0.0,
                        significance: 0.0,
                    }
                }
            };
            let apart = |d: &Doa| wrap_deg(d.azimuth_deg - doa.azimuth_deg).abs() > c.min_sep_deg;
            if row.iter().all(apart) && extra.iter().all(apart) {
                extra.push(doa);
            }
        }
        extra
    }

    /// The peaks (strongest first, and the next one beyond `N`) that [`SslConfig`]'s
    /// height rules (`stands_out`) keep, and those they do not that stand at least
    /// [`SslConfig::incoherent_relative`] high and are incoherent with every stronger peak
    /// ([`SslConfig::max_incoherence`]). Stronger peaks are all of them, reported or not:
    /// a peak that copies a reflection the height rules left out copies its source too.
    /// The recording's covariance (`spec`, the blocks the pooling kept) is computed once,
    /// when a peak first needs it.
    fn by_coherence(
        &self,
        peaks: Vec<Doa>,
        next: Option<Doa>,
        spec: &Spectrogram,
        stands_out: impl Fn(&Doa) -> bool,
    ) -> (Vec<Doa>, Option<Doa>) {
        let c = &self.config;
        let has_next = next.is_some();
        let all: Vec<Doa> = peaks.into_iter().chain(next).collect();
        let n = all.len() - usize::from(has_next);
        let mut cov = None;
        let mut kept: Vec<Doa> = Vec::new();
        let mut last = None;
        for (i, p) in all.iter().enumerate() {
            let keep = stands_out(p)
                || (i > 0 && p.relative >= c.incoherent_relative && {
                    let cov = cov.get_or_insert_with(|| {
                        SpatialCovariance::of(spec, self.kept_frames(spec).into_iter().flatten())
                    });
                    all[..i].iter().all(|s| {
                        self.source_coherence(cov, s, p)
                            .is_some_and(|g| g < c.max_incoherence)
                    })
                });
            if keep {
                if i == n {
                    last = Some(*p);
                } else {
                    kept.push(*p);
                }
            }
        }
        (kept, last)
    }

    /// The source coherence of two DoAs in the recording whose covariance is `cov`
    /// ([`SpatialCovariance::source_coherence`]).
    fn source_coherence(&self, cov: &SpatialCovariance, a: &Doa, b: &Doa) -> Option<f64> {
        let unit = |d: &Doa| unit_vector(d.azimuth_deg, d.elevation_deg);
        cov.source_coherence(
            self.array.positions(),
            f64::from(self.sample_rate),
            self.stft.frame_len(),
            self.config.speed_of_sound,
            unit(a),
            unit(b),
        )
    }

    /// `doas` and `next` (strongest first) without the peaks that do not stand more than
    /// [`SslConfig::sidelobe_ratio`] times above the sidelobes of the stronger peaks kept,
    /// unless they were the strongest direction of a block ([`Doa::dominant_blocks`]). As
    /// with the other thresholds, a peak dropped leaves its place empty.
    fn drop_sidelobes(&self, doas: Vec<Doa>, next: Option<Doa>) -> Result<(Vec<Doa>, Option<Doa>)> {
        let n = doas.len();
        let ratio = self.config.sidelobe_ratio;
        let mut scratch = Scratch::default();
        // The kept peaks, each with its plane wave's profile once a weaker peak needs it.
        let mut kept: Vec<(Doa, Option<Vec<f32>>)> = Vec::new();
        let mut last = None;
        for (i, p) in doas.into_iter().chain(next).enumerate() {
            // A peak that was the strongest direction of a block is not a sidelobe: in a
            // block where a source sounds, its main lobe stands above its sidelobes.
            if !kept.is_empty() && p.dominant_blocks == 0 {
                let at = self.grid.azimuth_cell(p.azimuth_deg);
                let mut sidelobe = 0.0f64;
                for (k, profile) in &mut kept {
                    if profile.is_none() {
                        *profile = Some(self.plane_wave_profile(
                            k.azimuth_deg,
                            k.elevation_deg,
                            &mut scratch,
                        )?);
                    }
                    let profile = profile.as_deref().unwrap_or_default();
                    // Within 2 degrees: the sidelobe may stand a cell or two aside.
                    let here = self
                        .grid
                        .azimuth_window(at, 2.0)
                        .map(|j| profile[j])
                        .fold(0.0f32, f32::max);
                    sidelobe = sidelobe.max(k.relative * f64::from(here));
                }
                if p.relative <= ratio * sidelobe {
                    continue;
                }
            }
            if i == n {
                last = Some(p);
            } else {
                kept.push((p, None));
            }
        }
        Ok((kept.into_iter().map(|(d, _)| d).collect(), last))
    }

    /// The method's pooled azimuth profile of an ideal plane wave from `azimuth_deg`,
    /// `elevation_deg` (array frame) through this localizer's array, band, grid and
    /// settings, as heights above its median relative to its top (1 at the wave's
    /// direction; its sidelobes where they stand): one block of a periodic noise with a
    /// flat spectrum, delayed exactly at every microphone.
    ///
    /// # Errors
    /// None in practice (the synthetic recording fits the localizer by construction).
    pub fn plane_wave_profile(
        &self,
        azimuth_deg: f64,
        elevation_deg: f64,
        scratch: &mut Scratch,
    ) -> Result<Vec<f32>> {
        let len = self.wave_fft.len();
        let nbins = len / 2 + 1;
        let phases = &self.wave_phases;
        let u = unit_vector(azimuth_deg, elevation_deg);
        let fs = f64::from(self.sample_rate);
        let c = self.config.speed_of_sound;
        let channels = self
            .array
            .positions()
            .iter()
            .map(|p| {
                // A microphone further along `u` hears the wave earlier by `lead` seconds:
                // x(t) = s(t + lead), X = S e^(i w lead).
                let lead = (p[0] * u[0] + p[1] * u[1] + p[2] * u[2]) / c;
                let mut spec: Vec<Complex32> = (0..nbins)
                    .map(|k| {
                        if k == 0 || (len % 2 == 0 && k == nbins - 1) {
                            return Complex32::default();
                        }
                        let w = std::f64::consts::TAU * k as f64 / len as f64 * fs;
                        let (im, re) = (phases[k] + w * lead).sin_cos();
                        Complex32::new(re as f32, im as f32)
                    })
                    .collect();
                let mut x = vec![0.0f32; len];
                self.wave_fft
                    .process(&mut spec, &mut x)
                    .expect("a spectrum of the planned length, real at DC and Nyquist");
                x
            })
            .collect();
        let audio = Audio::new(self.sample_rate, channels)?;
        self.analyse(&audio, scratch)?;
        // The method's own response to the wave: the robot's noise is no part of it.
        scratch.spec.noise = None;
        let (profile, _) = self.pooled(scratch, Blocks::Estimate).azimuth_profile();
        let median = crate::spectrum::median(&profile);
        let top = profile.iter().copied().fold(f32::MIN, f32::max);
        let span = (top - median).max(f32::MIN_POSITIVE);
        Ok(profile.iter().map(|v| (v - median) / span).collect())
    }

    /// The PHAT coherence of `spec` that [`Localizer::significance`] steers: with `u`
    /// each channel's unit phasors, `G_ij(b) = sum_f u_i u_j^*` over all frames, for every
    /// pair `i < j` and bin `b`.
    fn coherence(&self, spec: &Spectrogram) -> Coherence {
        let m = self.array.len();
        let nf = spec.num_frames();
        let bins = spec.bins();
        let nb = bins.len();
        let pairs: Vec<(usize, usize)> = (0..m)
            .flat_map(|i| (i + 1..m).map(move |j| (i, j)))
            .collect();
        let np = pairs.len();
        // G_p(b) = sum over frames of u_i u_j^*, u the unit phasors; real and imaginary
        // parts apart, bins contiguous, so that the sums vectorise.
        let (mut gr, mut gi) = (vec![0.0f32; np * nb], vec![0.0f32; np * nb]);
        let (mut ur, mut ui) = (vec![0.0f32; m * nb], vec![0.0f32; m * nb]);
        // With the robot's noise ([`crate::noise`]): per pair and bin, its coherence
        // `N_ij / sqrt(N_ii N_jj)` and `sqrt(N_ii N_jj)`; per channel and bin, `1 / |x|`.
        let noise: Option<(Vec<Complex32>, Vec<f32>)> = spec.noise().map(|field| {
            let mut gamma = Vec::with_capacity(np * nb);
            let mut own = Vec::with_capacity(np * nb);
            for &(i, j) in &pairs {
                for b in bins.clone() {
                    let o = (field.power(b, i) * field.power(b, j)).sqrt();
                    own.push(o);
                    gamma.push(if o > f32::MIN_POSITIVE {
                        field.cross(b, i, j) / o
                    } else {
                        Complex32::default()
                    });
                }
            }
            (gamma, own)
        });
        let mut inv_mag = vec![0.0f32; if noise.is_some() { m * nb } else { 0 }];
        for f in 0..nf {
            for i in 0..m {
                let x = spec.frame(f, i);
                let r = ur[i * nb..(i + 1) * nb].iter_mut();
                let im = ui[i * nb..(i + 1) * nb].iter_mut();
                for (k, ((v, r), im)) in x.iter().zip(r).zip(im).enumerate() {
                    let n2 = v.re * v.re + v.im * v.im;
                    let inv = if n2 > 0.0 { n2.sqrt().recip() } else { 0.0 };
                    *r = v.re * inv;
                    *im = v.im * inv;
                    if let Some(w) = inv_mag.get_mut(i * nb + k) {
                        *w = inv;
                    }
                }
            }
            for (p, &(i, j)) in pairs.iter().enumerate() {
                let (ar, ai) = (&ur[i * nb..(i + 1) * nb], &ui[i * nb..(i + 1) * nb]);
                let (br, bi) = (&ur[j * nb..(j + 1) * nb], &ui[j * nb..(j + 1) * nb]);
                let sums = gr[p * nb..(p + 1) * nb]
                    .iter_mut()
                    .zip(&mut gi[p * nb..(p + 1) * nb]);
                for ((((sr, si), ar), ai), (br, bi)) in sums.zip(ar).zip(ai).zip(br.iter().zip(bi))
                {
                    *sr += ar * br + ai * bi;
                    *si += ai * br - ar * bi;
                }
            }
            if let Some((gamma, own)) = &noise {
                // Less the robot's noise: its coherence, in proportion to its share of the
                // frame's `|x_i| |x_j|` (at most all of it). Each term stays a phasor's
                // size, so the statistic's spread under independent noise stays what the
                // test assumes.
                for (p, &(i, j)) in pairs.iter().enumerate() {
                    let (wi, wj) = (
                        &inv_mag[i * nb..(i + 1) * nb],
                        &inv_mag[j * nb..(j + 1) * nb],
                    );
                    let at = p * nb..(p + 1) * nb;
                    let terms = gamma[at.clone()]
                        .iter()
                        .zip(&own[at])
                        .zip(wi.iter().zip(wj));
                    for (k, ((g, o), (a, b))) in terms.enumerate() {
                        let share = (o * a * b).min(1.0);
                        gr[p * nb + k] -= g.re * share;
                        gi[p * nb + k] -= g.im * share;
                    }
                }
            }
        }
        Coherence {
            frames: nf,
            bins,
            pairs,
            re: gr,
            im: gi,
        }
    }

    /// Each DoA's [`Doa::significance`] in the recording whose [`Coherence`] is `g`: the
    /// statistic `sum_(i<j) sum_b Re(G_ij(b) e^(-i w_b tau_ij)) / (F B P)` at the pairs'
    /// delays `tau_ij` of the direction, divided by its standard deviation under
    /// independent noise, `1 / sqrt(2 F B P)` (each term then has mean 0 and variance 1/2).
    fn significance(&self, g: &Coherence, doas: &[Doa]) -> Vec<f64> {
        let pos = self.array.positions();
        let fs = f64::from(self.sample_rate);
        let c = self.config.speed_of_sound;
        let frame_len = self.stft.frame_len() as f64;
        let Coherence {
            frames: nf,
            bins,
            pairs,
            re: gr,
            im: gi,
        } = g;
        let (nf, nb, np) = (*nf, bins.len(), pairs.len());
        let sigma0 = (1.0 / (2.0 * nf as f64 * nb as f64 * np as f64)).sqrt();
        doas.iter()
            .map(|d| {
                let u = unit_vector(d.azimuth_deg, d.elevation_deg);
                let lead: Vec<f64> = pos
                    .iter()
                    .map(|q| (q[0] * u[0] + q[1] * u[1] + q[2] * u[2]) / c * fs)
                    .collect();
                let mut total = 0.0f64;
                for (p, &(i, j)) in pairs.iter().enumerate() {
                    // e^(-i w_b tau) over the band's bins, a geometric progression in b.
                    let step = -std::f64::consts::TAU / frame_len * (lead[i] - lead[j]);
                    let (mut re, mut im) = (step * bins.start as f64).sin_cos();
                    (re, im) = (im, re);
                    let (sr, si) = (step.cos(), step.sin());
                    let (g_re, g_im) = (&gr[p * nb..(p + 1) * nb], &gi[p * nb..(p + 1) * nb]);
                    for (a, b) in g_re.iter().zip(g_im) {
                        // Re(G e^(-i w tau)), with e^(-i w tau) = re + i im.
                        total += f64::from(*a) * re - f64::from(*b) * im;
                        (re, im) = (re * sr - im * si, re * si + im * sr);
                    }
                }
                total / (nf as f64 * nb as f64 * np as f64) / sigma0
            })
            .collect()
    }
}

/// A recording's PHAT coherence per microphone pair and bin ([`Localizer::coherence`]).
struct Coherence {
    /// Frames summed.
    frames: usize,
    /// The FFT bins, as the spectrogram kept them.
    bins: Range<usize>,
    /// The pairs `(i, j)`, `i < j`.
    pairs: Vec<(usize, usize)>,
    /// Real and imaginary parts of `G`, per pair then bin.
    re: Vec<f32>,
    im: Vec<f32>,
}

/// Each block's energy: all channels, the band's bins.
fn block_energies(
    spec: &Spectrogram,
    n_blocks: usize,
    frames: &dyn Fn(usize) -> Range<usize>,
) -> Vec<f64> {
    // Less the robot's own noise ([`crate::noise`]), kept at least a share of what was
    // heard: the gates compare the sources' levels.
    let noise = spec.noise().map_or(0.0, |n| n.frame_energy(spec.bins()));
    (0..n_blocks)
        .map(|b| {
            let heard: f64 = frames(b)
                .flat_map(|f| (0..spec.num_channels()).map(move |c| (f, c)))
                .map(|(f, c)| {
                    spec.frame(f, c)
                        .iter()
                        .map(|x| f64::from(x.norm_sqr()))
                        .sum::<f64>()
                })
                .sum();
            let floor = f64::from(crate::noise::RESIDUAL_FLOOR) * heard;
            (heard - noise * frames(b).len() as f64).max(floor)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn localizer_is_send_and_sync() {
        fn check<T: Send + Sync>() {}
        check::<Localizer>();
    }

    #[test]
    fn the_decay_gate_drops_the_decay_and_keeps_a_new_onset() {
        // 16 kHz: noise for 0.5 s, then a decay at RT60 0.5 s (-60 dB in 0.5 s) for 0.5 s,
        // then noise again. Blocks are 4 hops of 256 samples (16 ms): 64 ms, and a frame
        // reaches 32 ms beyond its start.
        let fs = 16_000;
        let n = 3 * fs as usize / 2;
        let mut state = 1u64;
        let mut noise = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 33) as f64 / (1u64 << 31) as f64 - 1.0) as f32
        };
        let ch: Vec<Vec<f32>> = (0..6)
            .map(|_| {
                (0..n)
                    .map(|i| {
                        let t = i as f64 / f64::from(fs);
                        let g = if (0.5..1.0).contains(&t) {
                            10f64.powf(-3.0 * (t - 0.5) / 0.5) // -60 dB in 0.5 s
                        } else {
                            1.0
                        };
                        (g as f32) * noise()
                    })
                    .collect()
            })
            .collect();
        let audio = Audio::new(fs, ch).unwrap();
        let loc = Localizer::new(&MicArray::default(), fs, &SslConfig::default()).unwrap();
        let spec = loc.stft.analyze(&audio, loc.bins.clone()).unwrap();
        let nf = spec.num_frames();
        let nb = nf / loc.config.block_frames;
        let frames = |b: usize| b * nf / nb..(b + 1) * nf / nb;
        let keep = loc.decay_gate(&spec, nb, &frames);
        let hop = loc.stft.hop();
        let block_s = |b: usize| (frames(b).start * hop) as f64 / f64::from(fs);
        for b in 0..nb {
            let (t0, t1) = (block_s(b), block_s(b) + 0.064 + 0.032);
            if t1 < 0.5 || t0 > 1.0 {
                assert!(
                    keep[b],
                    "block {b} at {t0:.2} s (sound) was dropped: {keep:?}"
                );
            } else if t0 > 0.65 && t1 <= 1.0 {
                // More than 0.15 s (18 dB) into the decay.
                assert!(
                    !keep[b],
                    "block {b} at {t0:.2} s (decay) was kept: {keep:?}"
                );
            }
        }
        // With the gate off, every block is pooled.
        let off = Localizer::new(
            &MicArray::default(),
            fs,
            &SslConfig {
                decay_gate_db: 0.0,
                ..SslConfig::default()
            },
        )
        .unwrap();
        assert!(off.decay_gate(&spec, nb, &frames).iter().all(|&k| k));
    }

    #[test]
    fn a_band_above_nyquist_is_refused() {
        let c = SslConfig {
            fmin_hz: 8500.0,
            fmax_hz: 9000.0,
            ..SslConfig::default()
        };
        let e = Localizer::new(&MicArray::default(), 16_000, &c).unwrap_err();
        assert!(matches!(e, ConfigError::Band { .. }), "{e}");
    }

    #[test]
    fn wrong_channel_count_is_refused() {
        let loc = Localizer::new(&MicArray::default(), 16_000, &SslConfig::default()).unwrap();
        let audio = Audio::new(16_000, vec![vec![0.0; 4000]; 4]).unwrap();
        let e = loc.locate(&audio).unwrap_err();
        assert!(
            matches!(
                e,
                Error::ChannelMismatch {
                    expected: 6,
                    got: 4
                }
            ),
            "{e}"
        );
    }
}
