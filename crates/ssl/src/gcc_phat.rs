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
//! 1. For each pair, average the PHAT-weighted cross-spectrum over the block's frames.
//! 2. Evaluate its correlation at the pair's lag grid, normalised by bins.
//! 3. Add each pair's correlation, interpolated at each direction's delay; divide by pairs.

use std::ops::Range;
use std::sync::Arc;

use crate::SpectrumEstimator;
use crate::grid::{PairLags, lag_sums};
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

impl SpectrumEstimator for GccPhat {
    fn name(&self) -> &'static str {
        "gcc-phat"
    }

    fn estimate_into(&self, stft: &Spectrogram, frames: Range<usize>, out: &mut [f32]) {
        let l = &*self.lags;
        let nb = l.n_bins;
        assert_eq!(stft.bins().len(), nb, "spectrogram band differs from the plan");
        out.fill(0.0);
        let mut gr = vec![0.0f32; nb];
        let mut gi = vec![0.0f32; nb];
        let mut lagfn = Vec::new();
        let norm = 1.0 / (frames.len() * nb * l.pairs.len()) as f32;
        for (p, &(i, j)) in l.pairs.iter().enumerate() {
            gr.fill(0.0);
            gi.fill(0.0);
            for f in frames.clone() {
                let (xi, xj) = (stft.frame(f, i), stft.frame(f, j));
                for b in 0..nb {
                    let c = xi[b] * xj[b].conj();
                    let m = c.norm();
                    // A bin with no energy in either channel carries no phase: skip it.
                    if m > f32::MIN_POSITIVE {
                        gr[b] += c.re / m;
                        gi[b] += c.im / m;
                    }
                }
            }
            let (cos, sin) = l.rows(p);
            lagfn.resize(2 * l.half[p] + 1, 0.0);
            lag_sums(nb, cos, sin, &mut lagfn, |b, c, s| gr[b] * c - gi[b] * s);
            lagfn.iter_mut().for_each(|v| *v *= norm);
            l.accumulate(p, &lagfn, out);
        }
    }
}
