//! A group's subspaces per block: the covariance of its bins over the block's frames,
//! its eigen-decomposition, the signal-subspace dimension (fixed or estimated), the
//! vectors the steering kernel projects on, and the least value its pseudo-spectrum's
//! denominator may take.

use std::ops::Range;

use nalgebra::{Complex, DMatrix, SymmetricEigen};
use realfft::num_complex::Complex32;

use super::{EIG_RATIO, FLOOR, FLOOR_RATIO, Music, SubspaceScratch, covariance};
use crate::method::zeroed;
use crate::stft::Spectrogram;

impl Music {
    /// A group's signal-subspace dimension for its eigenvalues `vals` taken in `order`
    /// (descending) from `snapshots` snapshots: fixed; or, estimated, those within
    /// [`EIG_RATIO`] of the largest, up to the cap, and for MUSIC also [`FLOOR_RATIO`]
    /// above the least eigenvalue the snapshots resolve (possibly none).
    fn signal_dimension(&self, vals: &[f32], order: &[usize], snapshots: usize) -> usize {
        if !self.estimate {
            return self.sources;
        }
        let v = |i: usize| vals[order[i]];
        let top = v(0);
        if self.normalise {
            return 1
                + (1..self.sources)
                    .take_while(|&i| v(i) >= EIG_RATIO * top)
                    .count();
        }
        // The eigenvalues the group's snapshots resolve; the least is the floor.
        let rank = snapshots.clamp(2, order.len());
        let floor = v(rank - 1).max(0.0);
        (0..self.sources.min(rank - 1))
            .take_while(|&i| v(i) >= EIG_RATIO * top && v(i) >= FLOOR_RATIO * floor)
            .count()
    }

    /// The least `|E_n^H a|^2 / |a|^2` a group's pseudo-spectrum takes, for its eigenvalues
    /// `vals` taken in `order` (descending) from `snapshots` snapshots with a signal
    /// subspace of `k` vectors: for MUSIC, the residual a source's own steering vector is
    /// expected to leave in the estimated noise subspace, `(M - K) / S * r / (r - 1)^2`
    /// with `r = lambda_K / sigma^2` (`S` snapshots, `lambda_K` the least signal
    /// eigenvalue, `sigma^2` the mean of the noise eigenvalues the snapshots resolve), or
    /// [`FLOOR`] where that is smaller or unknown; for NormMUSIC, [`FLOOR`].
    ///
    /// Why: the sample noise subspace misses a source's steering vector by about that
    /// much (the first-order perturbation of the subspaces; Stoica & Nehorai 1989), so
    /// a pseudo-spectrum value above its inverse is sharper than the snapshots resolve.
    /// From the 4 snapshots of a block, a bin where the signal barely stands above the
    /// noise can still leave a noise subspace that nearly contains some other steering
    /// vector, by chance, and its peak there can stand higher than a true source's in a
    /// good bin; summed unnormalised, such bins decided the spectrum. In the suite's
    /// `one_source` (a voiced talker at 130 Hz, RT60 0.3 s), the first stop's MUSIC peaks
    /// stood 50 degrees below the array, 8 degrees either side of the talker, made by the
    /// bins of 7-7.5 kHz where the voice is weak (the band below 7 kHz alone found the
    /// talker). Floored where the estimate's own accuracy ends, a bin counts by how well
    /// it resolves, as MUSIC's peaks should, and not by chance. NormMUSIC divides each
    /// group by its largest value, so no group outweighs another anyway.
    pub(super) fn resolution(
        &self,
        vals: &[f32],
        order: &[usize],
        k: usize,
        snapshots: usize,
    ) -> f32 {
        let rank = snapshots.clamp(2, order.len());
        if self.normalise || k == 0 || k >= rank {
            return FLOOR;
        }
        let v = |i: usize| vals[order[i]].max(0.0);
        let noise = (k..rank).map(v).sum::<f32>() / (rank - k) as f32;
        if noise <= f32::MIN_POSITIVE {
            return FLOOR;
        }
        let ratio = v(k - 1) / noise;
        if ratio <= 1.0 {
            return 1.0;
        }
        let residual = (self.mics - k) as f32 / snapshots as f32 * ratio / (ratio - 1.0).powi(2);
        residual.clamp(FLOOR, 1.0)
    }

    /// Fills `s.vec_re`/`s.vec_im` with each group's projected-on eigenvectors, and
    /// `s.used`/`s.signal` with how many each group uses and which subspace they span;
    /// returns the slots per group.
    ///
    /// `|E_n^H a|^2 = |a|^2 - |E_s^H a|^2`, so each group projects on whichever of its
    /// subspaces is smaller: `min(K, M - K)` vectors (at most `M / 2`), the cost of the
    /// steering kernel being proportional to it.
    pub(super) fn subspaces(
        &self,
        stft: &Spectrogram,
        frames: Range<usize>,
        s: &mut SubspaceScratch,
    ) -> usize {
        let m = self.mics;
        let dim = if self.estimate {
            // The largest min(K, M - K) for K up to the cap.
            (1..=self.sources).map(|k| k.min(m - k)).max().unwrap_or(1)
        } else {
            self.sources.min(m - self.sources)
        };
        let ng = self.centres.len();
        let n = ng * dim * m;
        let (vr, vi) = (zeroed(&mut s.vec_re, n), zeroed(&mut s.vec_im, n));
        s.used.clear();
        s.used.resize(ng, 0);
        s.signal.clear();
        s.signal.resize(ng, true);
        s.floor.clear();
        s.floor.resize(ng, FLOOR);
        let mut cov = DMatrix::<Complex<f32>>::zeros(m, m);
        for (k, &c) in self.centres.iter().enumerate() {
            let band = c.saturating_sub(self.smoothing)..(c + self.smoothing + 1).min(self.n_bins);
            let snapshots = frames.len() * band.len();
            covariance(stft, frames.clone(), band, &mut cov);
            // Scale to unit trace (the decomposition does not care, f32 does), then mirror.
            let tr: f32 = (0..m).map(|i| cov[(i, i)].re).sum();
            if tr <= f32::MIN_POSITIVE {
                // No energy: no vector (an empty signal subspace), and the group adds the
                // same to every direction.
                continue;
            }
            for i in 0..m {
                for j in i..m {
                    let v = cov[(i, j)] / tr;
                    cov[(i, j)] = v;
                    cov[(j, i)] = v.conj();
                }
            }
            let eig = SymmetricEigen::new(cov.clone());
            let mut order: Vec<usize> = (0..m).collect();
            order.sort_by(|&x, &y| eig.eigenvalues[y].total_cmp(&eig.eigenvalues[x]));
            let k_sig = self.signal_dimension(eig.eigenvalues.as_slice(), &order, snapshots);
            if k_sig == 0 {
                // No source in the group: an empty signal subspace, as for no energy.
                continue;
            }
            let signal = k_sig <= m - k_sig;
            let keep = if signal {
                &order[..k_sig]
            } else {
                &order[k_sig..]
            };
            s.used[k] = keep.len();
            s.signal[k] = signal;
            s.floor[k] = self.resolution(eig.eigenvalues.as_slice(), &order, k_sig, snapshots);
            for (v, &e) in keep.iter().enumerate() {
                for mic in 0..m {
                    let z: Complex32 = eig.eigenvectors[(mic, e)];
                    vr[(k * dim + v) * m + mic] = z.re;
                    vi[(k * dim + v) * m + mic] = z.im;
                }
            }
        }
        dim
    }
}
