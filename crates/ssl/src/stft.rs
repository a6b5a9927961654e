//! Short-time Fourier transform of multichannel audio.
//!
//! Frames are windowed with a *periodic* Hann window: the periodic form (denominator `N`,
//! not `N - 1`) sums to a constant at 50 % overlap (COLA), so every sample weighs alike in
//! the pooled statistics; the symmetric form does not (dasp's warning). Only full frames
//! are taken, and only the bins of the analysis band are kept. The forward FFT is not
//! normalised (`X[k] = sum_n x[n] w[n] e^{-2 pi i k n / N}`): every statistic we take from it
//! is a ratio or is normalised per bin, so the scale cancels.

use std::ops::Range;
use std::sync::Arc;

use realfft::num_complex::Complex32;
use realfft::{RealFftPlanner, RealToComplex};

use crate::audio::Audio;
use crate::error::{ConfigError, Error, Result};

/// The periodic Hann window of length `n`: `w[i] = 0.5 - 0.5 cos(2 pi i / n)`.
pub fn hann_periodic(n: usize) -> Vec<f32> {
    (0..n)
        .map(|i| (0.5 - 0.5 * (std::f64::consts::TAU * i as f64 / n as f64).cos()) as f32)
        .collect()
}

/// A planned STFT: frame length, hop, window table and FFT plan.
#[derive(Clone)]
pub struct Stft {
    frame_len: usize,
    hop: usize,
    window: Vec<f32>,
    fft: Arc<dyn RealToComplex<f32>>,
}

impl std::fmt::Debug for Stft {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Stft")
            .field("frame_len", &self.frame_len)
            .field("hop", &self.hop)
            .finish()
    }
}

impl Stft {
    /// Plans an STFT with a periodic Hann window.
    ///
    /// # Errors
    /// [`ConfigError::FrameLen`] if `frame_len < 16`, [`ConfigError::Hop`] if `hop` is
    /// outside `1..=frame_len`.
    pub fn new(frame_len: usize, hop: usize) -> Result<Self, ConfigError> {
        if frame_len < 16 {
            return Err(ConfigError::FrameLen(frame_len));
        }
        if hop == 0 || hop > frame_len {
            return Err(ConfigError::Hop { hop, frame_len });
        }
        Ok(Self {
            frame_len,
            hop,
            window: hann_periodic(frame_len),
            fft: RealFftPlanner::<f32>::new().plan_fft_forward(frame_len),
        })
    }

    /// Frame length (samples).
    pub fn frame_len(&self) -> usize {
        self.frame_len
    }

    /// Hop (samples).
    pub fn hop(&self) -> usize {
        self.hop
    }

    /// Number of full frames in `n` samples.
    pub fn num_frames(&self, n: usize) -> usize {
        if n < self.frame_len {
            0
        } else {
            (n - self.frame_len) / self.hop + 1
        }
    }

    /// Transforms every channel, keeping the bins in `bins` (a sub-range of
    /// `0..=frame_len / 2`).
    ///
    /// # Errors
    /// [`Error::TooShort`] if the audio is shorter than one frame.
    ///
    /// # Panics
    /// If `bins` reaches past the Nyquist bin.
    pub fn analyze(&self, audio: &Audio, bins: Range<usize>) -> Result<Spectrogram> {
        let mut out = Spectrogram::default();
        self.analyze_into(audio, bins, &mut out)?;
        Ok(out)
    }

    /// [`Stft::analyze`] into `out`, whose memory is reused: a caller that analyses one
    /// recording after another (see [`crate::Scratch`]) then allocates it once, not once per
    /// recording (measured: a tenth to a quarter of a GCC-PHAT run went to the kernel mapping
    /// and zeroing fresh pages for it).
    ///
    /// # Errors
    /// As [`Stft::analyze`]; `out` is then left empty.
    ///
    /// # Panics
    /// As [`Stft::analyze`].
    pub fn analyze_into(
        &self,
        audio: &Audio,
        bins: Range<usize>,
        out: &mut Spectrogram,
    ) -> Result<()> {
        assert!(bins.end <= self.frame_len / 2 + 1, "bins past Nyquist");
        let n_frames = self.num_frames(audio.num_samples());
        out.data.clear();
        out.num_frames = 0;
        out.noise = None;
        if n_frames == 0 {
            return Err(Error::TooShort {
                samples: audio.num_samples(),
                frame_len: self.frame_len,
            });
        }
        let n_ch = audio.num_channels();
        let n_bins = bins.len();
        // Every value is written below: resizing the cleared vector only fills it.
        out.data
            .resize(n_frames * n_ch * n_bins, Complex32::default());
        let data = &mut out.data;
        let mut input = self.fft.make_input_vec();
        let mut output = self.fft.make_output_vec();
        let mut scratch = self.fft.make_scratch_vec();
        for f in 0..n_frames {
            let start = f * self.hop;
            for (c, samples) in audio.channels().iter().enumerate() {
                let frame = &samples[start..start + self.frame_len];
                for ((x, &s), &w) in input.iter_mut().zip(frame).zip(&self.window) {
                    *x = s * w;
                }
                self.fft
                    .process_with_scratch(&mut input, &mut output, &mut scratch)
                    .expect("buffer lengths come from the plan");
                let o = (f * n_ch + c) * n_bins;
                data[o..o + n_bins].copy_from_slice(&output[bins.clone()]);
            }
        }
        out.num_frames = n_frames;
        out.num_channels = n_ch;
        out.bins = bins;
        Ok(())
    }
}

/// The STFT of multichannel audio, restricted to a band of bins.
#[derive(Clone, Debug, Default)]
pub struct Spectrogram {
    num_frames: usize,
    num_channels: usize,
    bins: Range<usize>,
    data: Vec<Complex32>,
    /// The robot's noise to subtract from this recording's statistics, when known
    /// ([`crate::noise`]).
    pub(crate) noise: Option<std::sync::Arc<crate::noise::NoiseField>>,
}

impl Spectrogram {
    /// The robot's noise that the statistics of this spectrogram subtract, if any.
    pub fn noise(&self) -> Option<&crate::noise::NoiseField> {
        self.noise.as_deref()
    }

    /// Number of frames.
    pub fn num_frames(&self) -> usize {
        self.num_frames
    }

    /// Number of channels.
    pub fn num_channels(&self) -> usize {
        self.num_channels
    }

    /// The FFT bin indices kept (`k` is at `k * fs / frame_len` Hz).
    pub fn bins(&self) -> Range<usize> {
        self.bins.clone()
    }

    /// A spectrogram computed elsewhere (pyroomacoustics' `X`, say): `data` holds the
    /// bins `bins` of each channel of each frame, frame-major, then channel, then bin, from
    /// a forward FFT of the length the localizer's `frame_len` is, unnormalised or scaled
    /// alike in every bin (every statistic is normalised per bin).
    ///
    /// # Errors
    /// [`crate::Error::SpectrogramShape`] when `data` does not hold that many values, or a
    /// value is not finite.
    pub fn from_frames(
        num_frames: usize,
        num_channels: usize,
        bins: Range<usize>,
        data: Vec<Complex32>,
    ) -> crate::Result<Self> {
        let want = num_frames * num_channels * bins.len();
        if data.len() != want || data.iter().any(|c| !(c.re.is_finite() && c.im.is_finite())) {
            return Err(crate::Error::SpectrogramShape {
                frames: num_frames,
                channels: num_channels,
                bins: bins.len(),
                got: data.len(),
            });
        }
        Ok(Self {
            num_frames,
            num_channels,
            bins,
            data,
            noise: None,
        })
    }

    /// A spectrogram of the given values (frame-major, then channel, then bin), for tests
    /// of the estimators.
    #[cfg(test)]
    pub(crate) fn from_parts(
        num_frames: usize,
        num_channels: usize,
        bins: Range<usize>,
        data: Vec<Complex32>,
    ) -> Self {
        assert_eq!(data.len(), num_frames * num_channels * bins.len());
        Self {
            num_frames,
            num_channels,
            bins,
            data,
            noise: None,
        }
    }

    /// Writes into `out` the part of this spectrogram in `bins` (a sub-band: the same
    /// frames and channels), reusing `out`'s memory.
    ///
    /// # Panics
    /// If `bins` does not lie within [`Spectrogram::bins`].
    pub fn band_into(&self, bins: Range<usize>, out: &mut Spectrogram) {
        assert!(
            self.bins.start <= bins.start && bins.end <= self.bins.end,
            "a sub-band of the kept bins"
        );
        let (n, lo) = (self.bins.len(), bins.start - self.bins.start);
        out.data.clear();
        for row in self.data.chunks_exact(n.max(1)) {
            out.data.extend_from_slice(&row[lo..lo + bins.len()]);
        }
        out.num_frames = self.num_frames;
        out.num_channels = self.num_channels;
        out.bins = bins;
        out.noise = self.noise.clone();
    }

    /// The kept bins of one channel in one frame.
    ///
    /// # Panics
    /// If `frame` or `channel` is out of range.
    pub fn frame(&self, frame: usize, channel: usize) -> &[Complex32] {
        assert!(frame < self.num_frames && channel < self.num_channels);
        let n = self.bins.len();
        let o = (frame * self.num_channels + channel) * n;
        &self.data[o..o + n]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn periodic_hann_is_cola_at_half_overlap() {
        let n = 64;
        let w = hann_periodic(n);
        for i in 0..n / 2 {
            assert!((w[i] + w[i + n / 2] - 1.0).abs() < 1e-6);
        }
        assert_eq!(w[0], 0.0);
    }

    #[test]
    fn hop_cannot_exceed_frame_len() {
        assert!(matches!(
            Stft::new(64, 65),
            Err(ConfigError::Hop { hop: 65, .. })
        ));
        assert!(matches!(Stft::new(64, 0), Err(ConfigError::Hop { .. })));
        assert!(matches!(Stft::new(8, 4), Err(ConfigError::FrameLen(8))));
    }

    #[test]
    fn fft_matches_a_direct_dft() {
        // Oracle: the direct sum X[k] = sum_n x[n] w[n] e^{-2 pi i k n / N}.
        let n = 32;
        let x: Vec<f32> = (0..80)
            .map(|i| ((i * 7919) % 13) as f32 / 13.0 - 0.5)
            .collect();
        let audio = Audio::new(1000, vec![x.clone()]).unwrap();
        let stft = Stft::new(n, 12).unwrap();
        let spec = stft.analyze(&audio, 0..n / 2 + 1).unwrap();
        assert_eq!(spec.num_frames(), (80 - 32) / 12 + 1);
        let w = hann_periodic(n);
        for f in 0..spec.num_frames() {
            for k in 0..=n / 2 {
                let mut acc = (0.0f64, 0.0f64);
                for t in 0..n {
                    let v = f64::from(x[f * 12 + t] * w[t]);
                    let ph = -std::f64::consts::TAU * (k * t) as f64 / n as f64;
                    acc.0 += v * ph.cos();
                    acc.1 += v * ph.sin();
                }
                let got = spec.frame(f, 0)[k];
                assert!((f64::from(got.re) - acc.0).abs() < 1e-4, "f{f} k{k}");
                assert!((f64::from(got.im) - acc.1).abs() < 1e-4, "f{f} k{k}");
            }
        }
    }

    /// One spectrogram reused for recordings of other lengths, channel counts and bands
    /// holds what a fresh analysis gives, and nothing of the one before; after an error it is
    /// empty.
    #[test]
    fn a_reused_spectrogram_holds_only_the_last_analysis() {
        let sig = |n: usize, k: usize| -> Vec<f32> {
            (0..n)
                .map(|i| (((i + k) * 7919) % 13) as f32 / 13.0 - 0.5)
                .collect()
        };
        let long = Audio::new(1000, vec![sig(200, 0), sig(200, 1), sig(200, 2)]).unwrap();
        let short = Audio::new(1000, vec![sig(90, 3), sig(90, 4)]).unwrap();
        let stft = Stft::new(32, 16).unwrap();
        let mut reused = Spectrogram::default();
        stft.analyze_into(&long, 0..17, &mut reused).unwrap();
        assert_eq!(reused.data, stft.analyze(&long, 0..17).unwrap().data);
        for (audio, bins) in [(&short, 2..9), (&long, 5..17)] {
            stft.analyze_into(audio, bins.clone(), &mut reused).unwrap();
            let fresh = stft.analyze(audio, bins.clone()).unwrap();
            assert_eq!(reused.num_frames(), fresh.num_frames());
            assert_eq!(reused.num_channels(), fresh.num_channels());
            assert_eq!(reused.bins(), bins);
            assert_eq!(reused.data, fresh.data);
        }
        let tiny = Audio::new(1000, vec![vec![0.0; 20]]).unwrap();
        assert!(stft.analyze_into(&tiny, 0..17, &mut reused).is_err());
        assert_eq!((reused.num_frames(), reused.data.len()), (0, 0));
    }

    #[test]
    fn audio_shorter_than_a_frame_is_an_error() {
        let audio = Audio::new(1000, vec![vec![0.0; 20]]).unwrap();
        let e = Stft::new(32, 16)
            .unwrap()
            .analyze(&audio, 0..17)
            .unwrap_err();
        assert!(matches!(
            e,
            Error::TooShort {
                samples: 20,
                frame_len: 32
            }
        ));
    }
}
