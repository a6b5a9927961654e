//! GCC-PHAT: generalised cross-correlation with phase transform (Knapp & Carter, 1976).
//!
//! For each microphone pair `(i, j)` and each bin `b` of a block of frames, the PHAT
//! weighting keeps only the phase of the cross-spectrum, `X_i X_j^* / |X_i X_j^*|`, so
//! every bin votes alike however loud it is; the block average `g_b` of those unit phasors
//! is a coherence-like statistic whose phase is the pair's inter-channel delay. The pair's
//! correlation at lag `tau` is `sum_b Re(g_b e^{i w_b tau})`: the inverse Fourier transform
//! of the weighted cross-spectrum, evaluated directly at the pair's lags (see
//! [`crate::grid`]). The direction spectrum is the mean over pairs of each pair's
//! correlation at that direction's delay (the SRP-PHAT functional).
//!
//! ## Algorithm
//! 1. Normalise every channel's bins to unit magnitude; for each pair, average the
//!    product of the two channels' unit phasors (the PHAT-weighted cross-spectrum) over
//!    the block's frames.
//! 2. Evaluate its correlation at the pair's lag grid, normalised by bins.
//! 3. Add each pair's correlation, interpolated at each direction's delay; divide by pairs.
//!
//! ## With the robot's noise ([`crate::noise`])
//! Step 1 becomes PHAT of the block's cross-spectrum less the noise's,
//! `T (Σ_t X_i X_j^* - T N_ij) / |Σ_t X_i X_j^* - T N_ij|` (the same scale as `T` unit
//! phasors): the noise's mean can be taken out of a sum, not out of a frame's phasor. Tried
//! and not kept: each frame's `X_i X_j^* - N_ij` over
//! `|X_i| |X_j|` subtracts many times the noise's mean phasor, since `1 / |X|` of a
//! Gaussian bin has a heavy tail (a fan's two talkers 0.26-0.71 m against 0.02-0.04); the
//! noise's coherence subtracted from each phasor in proportion to its share of the frame,
//! 0.07-0.41 m; spectral-subtraction gains on each phasor, which silence the bins where the
//! fan is heard with the sources, lost them (0.08-1.0 m).

use std::ops::Range;
use std::sync::Arc;

use crate::grid::{PairLags, Pairwise, Target};
use crate::method::{GccPhatScratch, MethodScratch, zeroed};
use crate::stft::Spectrogram;

/// The GCC-PHAT estimator for one array, grid, band and sample rate.
#[derive(Clone, Debug)]
pub struct GccPhat {
    lags: Arc<PairLags>,
}

impl GccPhat {
    pub(crate) fn new(lags: Arc<PairLags>) -> Self {
        Self { lags }
    }
}

impl GccPhat {
    /// [`Pairwise::spectrum`] of a spectrogram that carries the robot's noise: subtracted
    /// from each pair's block cross-spectrum before its PHAT weighting (see the module
    /// docs).
    fn less_noise(
        &self,
        stft: &Spectrogram,
        frames: Range<usize>,
        target: Target<'_>,
        scratch: &mut MethodScratch,
        norm: f32,
    ) {
        let l = &*self.lags;
        let nb = l.band_of(stft);
        let t = frames.len() as f32;
        let MethodScratch {
            gcc_phat: GccPhatScratch { cross, .. },
            pairs,
            ..
        } = scratch;
        let cross = zeroed(cross, nb);
        let coefficients = |_, pair, gr: &mut [f32], gi: &mut [f32], _: &mut [f32]| {
            // The block's cross-spectrum less the noise's (`block_cross` subtracts it).
            super::block_cross(stft, frames.clone(), pair, cross);
            for (b, c) in cross.iter().enumerate() {
                let u = super::unit_phasor(*c) * t;
                gr[b] = u.re;
                gi[b] = u.im;
            }
        };
        l.pairwise_spectrum(target, norm, pairs, coefficients, |gr, gi, _, c, s| {
            gr * c - gi * s
        });
    }
}

impl Pairwise for GccPhat {
    const NAME: &'static str = "gcc-phat";

    fn lags(&self) -> &PairLags {
        &self.lags
    }

    fn spectrum(
        &self,
        stft: &Spectrogram,
        frames: Range<usize>,
        target: Target<'_>,
        scratch: &mut MethodScratch,
    ) {
        let l = &*self.lags;
        let nb = l.band_of(stft);
        let norm = 1.0 / (frames.len() * nb * l.pairs.len()) as f32;
        // PHAT factorises: X_i X_j^* / |X_i X_j^*| = (X_i / |X_i|) (X_j / |X_j|)^*, so each
        // channel's bins are normalised once per frame instead of once per pair.
        let n_ch = stft.num_channels();
        if stft.noise().is_some() {
            return self.less_noise(stft, frames, target, scratch, norm);
        }
        let MethodScratch {
            gcc_phat: GccPhatScratch { unit, .. },
            pairs,
            ..
        } = scratch;
        let unit = zeroed(unit, frames.len() * n_ch * nb);
        for (k, f) in frames.clone().enumerate() {
            for c in 0..n_ch {
                let dst = &mut unit[(k * n_ch + c) * nb..(k * n_ch + c + 1) * nb];
                for (u, x) in dst.iter_mut().zip(stft.frame(f, c)) {
                    *u = super::unit_phasor(*x);
                }
            }
        }
        // Bins past the band stay 0 and so add nothing.
        let coefficients = |_, (i, j), gr: &mut [f32], gi: &mut [f32], _: &mut [f32]| {
            gr.fill(0.0);
            gi.fill(0.0);
            for k in 0..frames.len() {
                let ui = &unit[(k * n_ch + i) * nb..(k * n_ch + i + 1) * nb];
                let uj = &unit[(k * n_ch + j) * nb..(k * n_ch + j + 1) * nb];
                for (b, (a, c)) in ui.iter().zip(uj).enumerate() {
                    let x = a * c.conj();
                    gr[b] += x.re;
                    gi[b] += x.im;
                }
            }
        };
        l.pairwise_spectrum(target, norm, pairs, coefficients, |gr, gi, _, c, s| {
            gr * c - gi * s
        });
    }
}
