//! SRP-PHAT: the steered response power of the whole array with the phase transform
//! (DiBiase, Silverman & Brandstein 2001), as pyroomacoustics computes it.
//!
//! For each bin, the block's cross-spectral matrix `R_b = sum_f x_f x_f^H` over all
//! microphones is whitened element by element, `R_ij / |R_ij|`, and the power of the array
//! steered to direction `u` is `sum_b a_b(u)^H R_b a_b(u)`. Under PHAT the diagonal is the
//! constant `M` per bin, so the steered power is exactly `M * n_bins` plus twice the sum over
//! the `M (M - 1) / 2` pairs of `Re(R_ij/|R_ij| e^{i w_b tau_ij(u)})`: the full-array power
//! decomposes into pairs without approximation, and so it runs on the pairwise lag kernel of
//! [`crate::grid`] (the constant is dropped; peaks and their order do not change).
//!
//! It differs from [`super::gcc_phat`] only in where the whitening is applied. GCC-PHAT
//! averages the unit phasors of single frames, so a bin whose phase wanders across the
//! block (reverberation, two sources taking turns) votes with less than full weight;
//! SRP-PHAT whitens the block's averaged cross-spectrum, so every bin with any energy
//! votes with weight one, coherent or not. On a block of one frame the two are equal.

use std::ops::Range;
use std::sync::Arc;

use crate::grid::{PairLags, Pairwise, Target};
use crate::method::{MethodScratch, zeroed};
use crate::stft::Spectrogram;

/// The SRP-PHAT estimator for one array, grid, band and sample rate.
#[derive(Clone, Debug)]
pub struct SrpPhat {
    lags: Arc<PairLags>,
}

impl SrpPhat {
    pub(crate) fn new(lags: Arc<PairLags>) -> Self {
        Self { lags }
    }
}

impl Pairwise for SrpPhat {
    const NAME: &'static str = "srp-phat";

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
        let norm = 1.0 / (nb * l.pairs.len()) as f32;
        let MethodScratch {
            srp_phat: cross,
            pairs,
            ..
        } = scratch;
        let cross = zeroed(cross, nb);
        // Bins past the band stay 0 and so add nothing.
        let coefficients = |_, pair, gr: &mut [f32], gi: &mut [f32], _: &mut [f32]| {
            // Less the robot's noise when known (`crate::noise`), before the whitening.
            super::block_cross(stft, frames.clone(), pair, cross);
            for (b, c) in cross.iter().enumerate() {
                let u = super::unit_phasor(*c);
                gr[b] = u.re;
                gi[b] = u.im;
            }
        };
        l.pairwise_spectrum(target, norm, pairs, coefficients, |gr, gi, _, c, s| {
            gr * c - gi * s
        });
    }
}
