//! The robot's own noise: a recording of the robot alone, subtracted from what every
//! statistic of the SSL measures.
//!
//! A robot carries its noise with it: the fans of its computer and motor drivers, a pump,
//! a hard disk. That noise reaches the array from the same place in the array frame at
//! every stop, louder than most sources because it is a few tens of centimetres away (a
//! fan of 50 dB SPL at 1 m, 0.36 m from the array, is 59 dB there; a talker of 65 dB at 2
//! m is 59 dB). Measured on our simulator: with such a fan
//! behind the array, two talkers who take turns are found in no map by GCC-PHAT (DoA
//! score 0.86 -> 0.06: the fan fills every pause and every block the max pooling keeps),
//! and three talkers in a third of the maps.
//!
//! Its spatial statistics are steady: the same fans at the same places. So a recording of
//! the robot standing alone in a quiet room with its fans running (a few seconds: `iasm
//! --noise robot.wav`) gives, per frequency bin, the noise's spatial covariance per frame,
//! `N(k) = E[n(t, k) n(t, k)ᴴ]`, and with the noise independent of the sources, a block of
//! `T` frames of a recording has `E[Σ_t x xᴴ] = Σ_t s sᴴ + T N`: every statistic below
//! subtracts `T N` (or `N` per frame) from what it sums, so that what it measures is the
//! sources' (the HARK toolkit's GEVD/GSVD-MUSIC whitens by the same matrix; pairwise
//! methods cannot whiten, they subtract):
//!
//! - MVDR, SRP-PHAT, MUSIC (block sums): `Σ x_i x_j^* - T N_ij`, and the powers alike,
//!   each power kept at least [`RESIDUAL_FLOOR`] of what was heard (a block of noise alone
//!   leaves a residual of its own fluctuations, not a negative power).
//! - GCC-PHAT, which averages per-frame phasors: PHAT of the block's cross-spectrum less
//!   `T N_ij` instead. A mean cannot be taken out of a frame's phasor: each frame's
//!   `(x_i x_j^* - N_ij) / (|x_i| |x_j|)` subtracts several times the noise's mean phasor,
//!   since `1 / |x|` of a Gaussian bin has a heavy tail (measured, [`crate::gcc_phat`]).
//! - The source coherence ([`crate::SpatialCovariance`]) and the blocks' levels (gates,
//!   pooling choice): the same subtraction from their sums, powers floored alike.
//! - The significance of a peak, a sum of per-frame phasor products: from each, the
//!   noise's coherence `N_ij / sqrt(N_ii N_jj)` in proportion to its share of
//!   `|x_i| |x_j|` (at most all of it), so that each term stays a phasor's size.
//!
//! The subtraction assumes the noise as loud and as placed as when it was recorded: a fan
//! that speeds up leaves part of itself, and a noise recorded in another room carries that
//! room's reverberation (its direct path, the loudest part at 0.3 m, is the robot's own).

use std::ops::Range;

use realfft::num_complex::Complex32;

use crate::error::{Error, Result};
use crate::stft::Spectrogram;

/// The fewest STFT frames a noise recording may hold: its covariance is a mean over them,
/// and with fewer than a few dozen its own fluctuations are what is subtracted.
pub const MIN_NOISE_FRAMES: usize = 32;

/// A power left after the subtraction is kept at least this share of the power heard.
pub const RESIDUAL_FLOOR: f32 = 0.05;

/// The robot's noise per frequency bin: its spatial covariance per STFT frame, `N(k)`
/// (microphones x microphones, Hermitian), from a recording of the robot alone.
#[derive(Clone, Debug, PartialEq)]
pub struct NoiseField {
    m: usize,
    bins: Range<usize>,
    frames: usize,
    /// Per microphone pair `(i, j)` (row-major), the bins in order: a pair's row over a
    /// band is one slice.
    cov: Vec<Complex32>,
}

impl NoiseField {
    /// The noise field of the STFT `spec` of a recording of the robot alone: the mean of
    /// `x xᴴ` over its frames.
    ///
    /// # Errors
    /// [`Error::NoiseTooShort`] for fewer than [`MIN_NOISE_FRAMES`] frames.
    pub fn of(spec: &Spectrogram) -> Result<Self> {
        let (m, nf) = (spec.num_channels(), spec.num_frames());
        if nf < MIN_NOISE_FRAMES {
            return Err(Error::NoiseTooShort {
                frames: nf,
                min: MIN_NOISE_FRAMES,
            });
        }
        let bins = spec.bins();
        let nb = bins.len();
        let mut acc = vec![[0.0f64; 2]; m * m * nb];
        for f in 0..nf {
            for i in 0..m {
                let xi = spec.frame(f, i);
                for j in i..m {
                    let xj = spec.frame(f, j);
                    let row = &mut acc[(i * m + j) * nb..(i * m + j + 1) * nb];
                    for (s, (a, b)) in row.iter_mut().zip(xi.iter().zip(xj)) {
                        s[0] += f64::from(a.re * b.re + a.im * b.im);
                        s[1] += f64::from(a.im * b.re - a.re * b.im);
                    }
                }
            }
        }
        let mut cov = vec![Complex32::default(); m * m * nb];
        let scale = 1.0 / nf as f64;
        for i in 0..m {
            for j in i..m {
                for k in 0..nb {
                    let [re, im] = acc[(i * m + j) * nb + k];
                    let v = Complex32::new((re * scale) as f32, (im * scale) as f32);
                    cov[(i * m + j) * nb + k] = v;
                    cov[(j * m + i) * nb + k] = v.conj();
                }
            }
        }
        Ok(Self {
            m,
            bins,
            frames: nf,
            cov,
        })
    }

    /// Microphones.
    pub fn num_channels(&self) -> usize {
        self.m
    }

    /// The frames of the recording it was estimated from.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// The FFT bins it holds.
    pub fn bins(&self) -> Range<usize> {
        self.bins.clone()
    }

    /// `N_ij` at FFT bin `bin` (an absolute index, within [`NoiseField::bins`]).
    #[inline]
    pub fn cross(&self, bin: usize, i: usize, j: usize) -> Complex32 {
        let nb = self.bins.len();
        self.cov[(i * self.m + j) * nb + bin - self.bins.start]
    }

    /// `N_ii` at FFT bin `bin`: microphone `i`'s noise power per frame.
    #[inline]
    pub fn power(&self, bin: usize, i: usize) -> f32 {
        self.cross(bin, i, i).re
    }

    /// `N_ij` at each of `bins` (absolute indices, within [`NoiseField::bins`]).
    #[inline]
    pub fn row(&self, bins: Range<usize>, (i, j): (usize, usize)) -> &[Complex32] {
        let nb = self.bins.len();
        let at = (i * self.m + j) * nb - self.bins.start;
        &self.cov[at + bins.start..at + bins.end]
    }

    /// The field of microphones `keep` (in that order).
    pub fn subset(&self, keep: &[usize]) -> Self {
        let n = keep.len();
        let mut cov = Vec::with_capacity(n * n * self.bins.len());
        for &i in keep {
            for &j in keep {
                cov.extend_from_slice(self.row(self.bins.clone(), (i, j)));
            }
        }
        Self {
            m: n,
            bins: self.bins.clone(),
            frames: self.frames,
            cov,
        }
    }

    /// The noise's energy in `bins` summed over microphones, per frame (the subtrahend of
    /// a frame's energy).
    pub(crate) fn frame_energy(&self, bins: Range<usize>) -> f64 {
        bins.map(|b| {
            (0..self.m)
                .map(|i| f64::from(self.power(b, i)))
                .sum::<f64>()
        })
        .sum()
    }
}

/// `heard - frames * noise`, kept at least [`RESIDUAL_FLOOR`] of `heard`.
#[inline]
pub(crate) fn residual_power(heard: f32, noise: f32, frames: f32) -> f32 {
    (heard - frames * noise).max(RESIDUAL_FLOOR * heard)
}
