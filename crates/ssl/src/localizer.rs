//! The localizer: from multichannel audio to a pooled angular spectrum and ranked DoAs.

use std::ops::Range;
use std::sync::Arc;

use realfft::num_complex::Complex32;

use crate::array::MicArray;
use crate::audio::Audio;
use crate::config::{Method, Pooling, SslConfig};
use crate::error::{ConfigError, Error, Result};
use crate::gcc_phat::GccPhat;
use crate::grid::{DirectionGrid, PairLags, PairScratch};
use crate::mvdr::Mvdr;
use crate::spectrum::{AngularSpectrum, Doa};
use crate::stft::{Spectrogram, Stft};

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
    /// One block's spectrum (the localizer).
    pub(crate) block: Vec<f32>,
}

/// Zero-filled `v` of length `n`, reusing its memory.
pub(crate) fn zeroed<T: Copy + Default>(v: &mut Vec<T>, n: usize) -> &mut [T] {
    v.clear();
    v.resize(n, T::default());
    v
}

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
        let fmax = config.fmax_hz.min(nyquist);
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
        let lags = Arc::new(PairLags::new(
            array,
            &grid,
            fs,
            config.speed_of_sound,
            bins.clone(),
            frame_len,
        ));
        let estimator: Box<dyn SpectrumEstimator> = match config.method {
            Method::GccPhat => Box::new(GccPhat::new(lags)),
            Method::Mvdr => Box::new(Mvdr::new(
                lags,
                config.mvdr_loading,
                config.mvdr_freq_smoothing,
            )),
        };
        Ok(Self {
            array: array.clone(),
            sample_rate,
            config: config.clone(),
            stft,
            bins,
            grid,
            estimator,
        })
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

    /// The pooled angular spectrum of `audio`.
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
        let spec = self.stft.analyze(audio, self.bins.clone())?;
        let nf = spec.num_frames();
        let n_blocks = (nf / self.config.block_frames).max(1);
        let mut pooled = vec![0.0f32; self.grid.len()];
        let mut block = std::mem::take(&mut scratch.block);
        block.resize(self.grid.len(), 0.0);
        for b in 0..n_blocks {
            // Blocks split the frames as evenly as possible and cover all of them.
            let frames = b * nf / n_blocks..(b + 1) * nf / n_blocks;
            self.estimator
                .estimate_into(&spec, frames, &mut block, scratch);
            match self.config.pooling {
                Pooling::Max if b == 0 => pooled.copy_from_slice(&block),
                Pooling::Max => pooled
                    .iter_mut()
                    .zip(&block)
                    .for_each(|(p, &v)| *p = p.max(v)),
                Pooling::Mean => pooled
                    .iter_mut()
                    .zip(&block)
                    .for_each(|(p, &v)| *p += v / n_blocks as f32),
            }
        }
        scratch.block = block;
        Ok(AngularSpectrum::new(self.grid.clone(), pooled))
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
        Ok(self
            .spectrum_with_scratch(audio, scratch)?
            .peaks(self.config.num_peaks, self.config.min_sep_deg)
            .into_iter()
            .filter(|d| d.relative >= self.config.min_relative)
            .collect())
    }
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
    fn a_band_above_nyquist_is_refused() {
        let c = SslConfig {
            fmin_hz: 9000.0,
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
