//! MVDR: minimum-variance distortionless response (Capon, 1969), per microphone pair.
//!
//! Like the "MVDR" of MBSS Locate (the toolbox behind the paper's DoAs), this is a pairwise
//! beamformer, not a full-array one: for each pair and bin it forms the 2 x 2 spatial
//! covariance, averaged over the block's frames and `±F` neighbouring bins, normalises it
//! to a coherence matrix `[[1, g], [g*, 1]]` (so that every bin weighs alike whatever its
//! energy, as PHAT does for GCC), loads its diagonal by `eps`, and evaluates the Capon power
//! `1 / (a^H R^-1 a)` for the steering vector `a = [1, e^{i w tau}]` at each lag `tau`:
//!
//! `P_b(tau) = ((1 + eps)^2 - |g_b|^2) / (2 (1 + eps - Re(g_b e^{i w_b tau})))`.
//!
//! A bin whose two channels are fully coherent (`|g| -> 1`, one dominant source) gives a
//! peak far sharper than GCC-PHAT's cosine; an incoherent bin gives a flat `~1/2`. The
//! loading `eps` keeps the denominator at least `eps`: without it a block of a single frame
//! (where `|g| = 1` exactly) would divide by zero, and one bin could outvote all others.
//! A full 6-channel Capon beamformer would need a 6 x 6 inverse per bin and a quadratic form
//! per direction and bin, about 25 times the work, for the same delay information.
//!
//! ## Algorithm
//! 1. Per channel and pair, sum powers and cross-spectra over the block's frames.
//! 2. Smooth them over `±F` bins; form the coherence `g_b = R_ij / sqrt(R_ii R_jj)`.
//! 3. Evaluate `sum_b P_b(tau)` on the pair's lag grid; read it off at each direction's
//!    delay and average over pairs.
//!
//! With the robot's noise known ([`crate::noise`]), step 1 subtracts `T N` from the
//! block's sums of `T` frames (each power kept at least
//! [`crate::noise::RESIDUAL_FLOOR`] of what was heard), and `|g|` is kept at most 1.

use std::ops::Range;
use std::sync::Arc;

use realfft::num_complex::Complex32;

use crate::grid::{PairLags, Pairwise, Target};
use crate::method::{MethodScratch, MvdrScratch, zeroed};
use crate::stft::Spectrogram;

/// The pairwise MVDR estimator for one array, grid, band and sample rate.
#[derive(Clone, Debug)]
pub struct Mvdr {
    lags: Arc<PairLags>,
    loading: f32,
    smoothing: usize,
}

impl Mvdr {
    pub(crate) fn new(lags: Arc<PairLags>, loading: f64, smoothing: usize) -> Self {
        Self {
            lags,
            loading: loading as f32,
            smoothing,
        }
    }
}

/// Box-sums `v` over `±w` neighbours (clipped at the edges) into `out`; `prefix` is
/// scratch.
fn box_smooth<T: Copy + Default + std::ops::AddAssign + std::ops::Sub<Output = T>>(
    v: &[T],
    w: usize,
    out: &mut [T],
    prefix: &mut Vec<T>,
) {
    // Prefix sums: out[b] = S[min(b + w + 1, n)] - S[b.saturating_sub(w)].
    let n = v.len();
    prefix.clear();
    let mut acc = T::default();
    prefix.push(acc);
    for &x in v {
        acc += x;
        prefix.push(acc);
    }
    for (b, o) in out.iter_mut().enumerate() {
        *o = prefix[(b + w + 1).min(n)] - prefix[b.saturating_sub(w)];
    }
}

impl Pairwise for Mvdr {
    const NAME: &'static str = "mvdr";

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
        let n_ch = stft.num_channels();
        let noise = stft.noise();
        let t = frames.len() as f32;
        let MethodScratch {
            mvdr:
                MvdrScratch {
                    power,
                    power_sum,
                    cross,
                    cross_smooth: smooth,
                    prefix_real,
                    prefix_complex,
                },
            pairs,
            ..
        } = scratch;
        // Channel powers, summed over frames then smoothed over bins.
        let power = zeroed(power, n_ch * nb);
        let tmp = zeroed(power_sum, nb);
        for (c, pw) in power.chunks_exact_mut(nb).enumerate() {
            for f in frames.clone() {
                for (acc, x) in tmp.iter_mut().zip(stft.frame(f, c)) {
                    *acc += x.norm_sqr();
                }
            }
            if let Some(field) = noise {
                for (acc, n) in tmp.iter_mut().zip(field.row(stft.bins(), (c, c))) {
                    *acc = crate::noise::residual_power(*acc, n.re, t);
                }
            }
            box_smooth(tmp, self.smoothing, pw, prefix_real);
            tmp.fill(0.0);
        }
        let power = &*power;
        let a = 1.0 + self.loading;
        let cross = zeroed(cross, nb);
        let smooth = zeroed(smooth, nb);
        // Bins past the band keep num = 0 and so add nothing.
        let coefficients = |_, (i, j), gr: &mut [f32], gi: &mut [f32], num: &mut [f32]| {
            // Less the robot's noise when known.
            super::block_cross(stft, frames.clone(), (i, j), cross);
            box_smooth(cross, self.smoothing, smooth, prefix_complex);
            let (pi, pj) = (&power[i * nb..(i + 1) * nb], &power[j * nb..(j + 1) * nb]);
            for b in 0..nb {
                let d = (pi[b] * pj[b]).sqrt();
                let mut g = if d > f32::MIN_POSITIVE {
                    smooth[b] / d
                } else {
                    Complex32::default()
                };
                if noise.is_some() {
                    // A residual cross-spectrum may exceed its floored powers.
                    let r = g.norm();
                    if r > 1.0 {
                        g /= r;
                    }
                }
                gr[b] = g.re;
                gi[b] = g.im;
                num[b] = 0.5 * (a * a - g.norm_sqr());
            }
        };
        let norm = 1.0 / (nb * l.pairs.len()) as f32;
        l.pairwise_spectrum(target, norm, pairs, coefficients, |gr, gi, num, c, s| {
            num / (a - (gr * c - gi * s))
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_smoothing_matches_a_direct_sum() {
        let v: Vec<f32> = (0..10).map(|i| (i * i % 7) as f32).collect();
        let mut out = vec![0.0; 10];
        box_smooth(&v, 2, &mut out, &mut Vec::new());
        for b in 0..10usize {
            let want: f32 = v[b.saturating_sub(2)..(b + 3).min(10)].iter().sum();
            assert_eq!(out[b], want, "bin {b}");
        }
    }
}
