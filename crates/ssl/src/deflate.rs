//! Deflation: a weak DoA refined on what the recording holds once the stronger DoAs of its
//! row are projected out ([`crate::SslConfig::deflate`], off by default).
//!
//! Why. A compact array's main lobe is wide (the ReSpeaker 4-mic, 6.4 cm across, spans
//! tens of degrees at speech frequencies), and where two sources sound at once the weaker
//! one's peak sits on the stronger one's slope: it is found, but displaced towards it or
//! away along the slope. With two steady plane waves 60-120 degrees apart, the second 2-4
//! dB down, GCC-PHAT's second peak lies 3-10 degrees off (`tests/doa_sim.rs`), and in a
//! simulated room two talkers heard by that array are mapped 7-11 times worse than by the
//! paper's array. The maximum-likelihood estimator of several plane waves in white noise
//! has an alternating-projection step for this (Ziskind & Wax, 1988): with the other
//! sources' steering vectors `A` fixed, the likelihood of one more direction `θ` is the
//! power that the covariance holds along `a(θ)` once the span of `A` is projected out,
//! `a_pᴴ R a_p / ‖a_p‖²` with `a_p = P⊥ a(θ)`, `P⊥ = I - A (AᴴA)⁻¹ Aᴴ`.
//!
//! How. Each DoA of a row but the first is refined in turn, the stronger DoAs before it
//! projected out (they stay where the spectrum put them). The projected power is computed
//! block by block (each block's covariance over the frames the pooling kept, every bin
//! weighted alike, as PHAT does), summed over the band and pooled over the blocks as the
//! spectrum was ([`crate::Pooling`], `pool_top`), so that talkers who take turns keep
//! their best block here too. From the DoA the search climbs the pooled projected power
//! (1-degree steps, then 0.25) to its local maximum, at most [`REACH_DEG`] away; the
//! elevation stays. The blocks' covariances are the recording's alone: they are computed
//! once per row ([`BlockCovariances`]) and the projection is applied to the steering
//! vector, `(P⊥ a)ᴴ R (P⊥ a)`, rather than to each block's matrix. Bins where the array does not resolve the stronger DoAs from each
//! other, and candidate directions that the projection all but removes (`‖a_p‖²` under a
//! fifth of `M`), are left out.
//!
//! When not. The step assumes the row's DoAs are the sources the recording holds, and
//! plane waves. A row cut at `N` holds fewer ([`crate::Located::cut`]) and is left alone.
//! In a crowd that the array does not resolve (ten talkers heard by the ReSpeaker, rows of
//! two or three), the residual is the other talkers' and the refined DoAs follow them; and
//! a source nearer than the array's far-field distance (2 D² / λ: 2.6 m for the paper's
//! 0.235-m array at 8 kHz) is no plane wave, so that projecting its DoA out leaves much of
//! it. Hence off by default; measured in `BENCHMARKS.md` (session 24).

use std::collections::HashMap;
use std::ops::Range;

use nalgebra::{Complex, DMatrix};

use crate::config::Pooling;
use crate::covariance::{CMatrix, angular_frequency, leads, resolved_steering};
use crate::grid::unit_vector;
use crate::stft::Spectrogram;

/// How far (degrees) the search may move a DoA: a weak DoA on a strong one's lobe lay 5-25
/// degrees off in the measurements; further lies another peak.
pub const REACH_DEG: f64 = 30.0;

/// What a deflation needs to know of the localizer.
pub(crate) struct Setup<'a> {
    /// Microphone positions (m).
    pub positions: &'a [[f64; 3]],
    /// Sample rate (Hz), STFT frame length, speed of sound (m/s).
    pub fs: f64,
    pub frame_len: usize,
    pub c: f64,
    /// How block values are pooled, and `pool_top`.
    pub pooling: Pooling,
    pub pool_top: usize,
}

impl Setup<'_> {
    /// Each microphone's lead (s) for a plane wave from (azimuth, elevation) degrees: a
    /// microphone further along the direction hears it earlier, `X = S e^(i w lead)`.
    fn lead(&self, azimuth_deg: f64, elevation_deg: f64) -> Vec<f64> {
        leads(
            self.positions,
            unit_vector(azimuth_deg, elevation_deg),
            self.c,
        )
    }

    /// The pooled value of per-block values `q` (see [`crate::SslConfig::pooling`]).
    fn pool(&self, q: &mut [f64]) -> f64 {
        match self.pooling {
            Pooling::Mean => q.iter().sum::<f64>() / q.len() as f64,
            Pooling::Max => {
                let k = self.pool_top.clamp(1, q.len());
                q.sort_unstable_by(|a, b| b.total_cmp(a));
                q[..k].iter().sum::<f64>() / k as f64
            }
        }
    }
}

/// Each kept block's spatial covariance per bin, divided by its trace (every bin weighted
/// alike, as PHAT does): the part of a deflation that depends on the recording alone,
/// computed once per row and shared by its DoAs. Only the upper triangle (`i <= j`) is
/// kept: the matrices are Hermitian.
pub(crate) struct BlockCovariances {
    /// Microphones, bins, blocks.
    m: usize,
    bins: usize,
    blocks: usize,
    /// `[block][pair][bin]`, the pairs `(i, j)`, `i <= j`, in row order; zero where a
    /// block holds no power in a bin.
    re: Vec<f64>,
    im: Vec<f64>,
}

impl BlockCovariances {
    /// The covariances of the blocks of `spec` (each a range of frames).
    pub(crate) fn of(spec: &Spectrogram, blocks: &[Range<usize>]) -> Self {
        let (m, bins) = (spec.num_channels(), spec.bins().len());
        let pairs = m * (m + 1) / 2;
        let size = blocks.len() * pairs * bins;
        let (mut re, mut im) = (vec![0.0f64; size], vec![0.0f64; size]);
        let mut trace = vec![0.0f64; bins];
        for (b, frames) in blocks.iter().enumerate() {
            let block = b * pairs * bins;
            // Frame by frame, channel pair by pair, bins innermost: the spectrogram's and
            // the sums' memory both run along the bins.
            for f in frames.clone() {
                let mut pair = 0;
                for i in 0..m {
                    let xi = spec.frame(f, i);
                    for j in i..m {
                        let xj = spec.frame(f, j);
                        let at = block + pair * bins;
                        let (r, q) = (&mut re[at..at + bins], &mut im[at..at + bins]);
                        for k in 0..bins {
                            // xi conj(xj)
                            let (a, c) = (xi[k], xj[k]);
                            let (ar, ai) = (f64::from(a.re), f64::from(a.im));
                            let (cr, ci) = (f64::from(c.re), f64::from(c.im));
                            r[k] += ar * cr + ai * ci;
                            q[k] += ai * cr - ar * ci;
                        }
                        pair += 1;
                    }
                }
            }
            trace.iter_mut().for_each(|t| *t = 0.0);
            for i in 0..m {
                let at = block + diagonal(i, m) * bins;
                trace
                    .iter_mut()
                    .zip(&re[at..at + bins])
                    .for_each(|(t, r)| *t += r);
            }
            for pair in 0..pairs {
                let at = block + pair * bins;
                let (r, q) = (&mut re[at..at + bins], &mut im[at..at + bins]);
                for ((r, q), &t) in r.iter_mut().zip(q.iter_mut()).zip(&trace) {
                    let scale = if t > 0.0 { 1.0 / t } else { 0.0 };
                    *r *= scale;
                    *q *= scale;
                }
            }
        }
        Self {
            m,
            bins,
            blocks: blocks.len(),
            re,
            im,
        }
    }
}

/// The index of the pair `(i, i)` among the upper triangle's pairs of `m` microphones in
/// row order.
fn diagonal(i: usize, m: usize) -> usize {
    // The rows before row i hold m, m - 1, ..., m - i + 1 pairs.
    i * m - i * i.saturating_sub(1) / 2
}

/// The azimuth (degrees, wrapped) of the DoA at `weak` (azimuth, elevation) refined with
/// the DoAs at `strong` projected out of the blocks whose covariances are `cov`; `weak`'s
/// own azimuth when there is nothing to refine against (no stronger DoA, more than
/// `M - 2` of them, no block).
pub(crate) fn deflated_azimuth(
    setup: &Setup<'_>,
    spec: &Spectrogram,
    cov: &BlockCovariances,
    strong: &[(f64, f64)],
    weak: (f64, f64),
) -> f64 {
    let (m, nb) = (cov.m, cov.bins);
    let s = strong.len();
    if s == 0 || s + 2 > m || cov.blocks == 0 {
        return weak.0;
    }
    let omega: Vec<f64> = spec
        .bins()
        .map(|b| angular_frequency(b, setup.frame_len, setup.fs))
        .collect();
    // Per bin, the projector away from the stronger DoAs; none where the array does not
    // resolve them from each other (the smallest eigenvalue of AᴴA, per microphone, below
    // 1 - `MAX_STEERING_OVERLAP`, as the coherence statistic requires).
    let leads: Vec<Vec<f64>> = strong.iter().map(|&(a, e)| setup.lead(a, e)).collect();
    let projectors: Vec<Option<CMatrix>> = omega
        .iter()
        .map(|&w| {
            let (a, gi) = resolved_steering(m, w, &leads)?;
            Some(DMatrix::identity(m, m) - &a * gi * a.adjoint())
        })
        .collect();
    let pairs = m * (m + 1) / 2;
    let mut per_block = vec![0.0f64; cov.blocks];
    let mut a = vec![Complex::new(0.0, 0.0); m];
    let mut b = vec![Complex::new(0.0, 0.0); m];
    // Per pair and bin, the weight of the covariance's entry in the projected power
    // (zero in the bins left out).
    let (mut u_re, mut u_im) = (vec![0.0f64; pairs * nb], vec![0.0f64; pairs * nb]);
    let mut power = |azimuth_deg: f64| -> f64 {
        let lead = setup.lead(azimuth_deg, weak.1);
        u_re.iter_mut().for_each(|u| *u = 0.0);
        u_im.iter_mut().for_each(|u| *u = 0.0);
        for (k, p) in projectors.iter().enumerate() {
            let Some(p) = p else { continue };
            for (ai, l) in a.iter_mut().zip(&lead) {
                *ai = Complex::from_polar(1.0, omega[k] * l);
            }
            // The projected steering vector P⊥ a; its power aᴴ P⊥ a = ‖P⊥ a‖² (P⊥ is a
            // Hermitian projector), and aᴴ P⊥ R P⊥ a = (P⊥ a)ᴴ R (P⊥ a).
            for (i, bi) in b.iter_mut().enumerate() {
                *bi = (0..m).map(|j| p[(i, j)] * a[j]).sum();
            }
            let n2: f64 = b.iter().map(|x| x.norm_sqr()).sum();
            if n2 < 0.2 * m as f64 {
                continue;
            }
            // bᴴ R b / n2 = Σ_i R_ii |b_i|² / n2 + 2 Re Σ_{i<j} R_ij conj(b_i) b_j / n2.
            let mut pair = 0;
            for i in 0..m {
                for j in i..m {
                    let w = b[i].conj() * b[j] * if i == j { 1.0 } else { 2.0 } / n2;
                    (u_re[pair * nb + k], u_im[pair * nb + k]) = (w.re, w.im);
                    pair += 1;
                }
            }
        }
        for (block, q) in per_block.iter_mut().enumerate() {
            let at = block * pairs * nb;
            let (re, im) = (&cov.re[at..at + pairs * nb], &cov.im[at..at + pairs * nb]);
            // Re(R w) summed: R.re w.re - R.im w.im.
            *q = re
                .iter()
                .zip(im)
                .zip(u_re.iter().zip(&u_im))
                .map(|((r, i), (x, y))| r * x - i * y)
                .sum::<f64>();
        }
        setup.pool(&mut per_block)
    };
    // The climb comes back to directions it has weighed (each step's neighbour behind
    // it): each is computed once, keyed by its offset from the start in quarter degrees.
    let mut seen: HashMap<i64, f64> = HashMap::new();
    let start = weak.0;
    let mut weigh = |azimuth_deg: f64| {
        let key = ((azimuth_deg - start) * 4.0).round() as i64;
        *seen.entry(key).or_insert_with(|| power(azimuth_deg))
    };
    let mut at = start;
    let mut here = weigh(at);
    for step in [1.0, 0.25] {
        loop {
            let (lower, upper) = (weigh(at - step), weigh(at + step));
            let next = if lower > here && lower >= upper {
                (at - step, lower)
            } else if upper > here {
                (at + step, upper)
            } else {
                break;
            };
            if (next.0 - start).abs() > REACH_DEG {
                break;
            }
            (at, here) = next;
        }
    }
    crate::wrap_deg(at)
}

#[cfg(test)]
mod tests {
    use super::*;
    use realfft::num_complex::Complex32;

    #[test]
    fn diagonal_indexes_the_upper_triangle_row_by_row() {
        for m in 1..9 {
            let pairs: Vec<(usize, usize)> =
                (0..m).flat_map(|i| (i..m).map(move |j| (i, j))).collect();
            for i in 0..m {
                assert_eq!(pairs[diagonal(i, m)], (i, i), "m = {m}, i = {i}");
            }
        }
    }

    /// Each stored entry is the block's sum over its frames of `x_i conj(x_j)`, divided by
    /// the sum of the diagonal's, computed here directly from the frames.
    #[test]
    fn block_covariances_are_the_frames_outer_products_over_their_trace() {
        let (frames, m, bins) = (6, 4, 5);
        let data: Vec<Complex32> = (0..frames * m * bins)
            .map(|n| {
                let x = n as f32;
                Complex32::new((0.7 * x).sin(), (1.3 * x + 0.4).cos())
            })
            .collect();
        let spec = Spectrogram::from_parts(frames, m, 10..10 + bins, data);
        let blocks = [0..2, 2..6];
        let cov = BlockCovariances::of(&spec, &blocks);
        let pairs = m * (m + 1) / 2;
        for (b, range) in blocks.iter().enumerate() {
            for k in 0..bins {
                let entry = |i: usize, j: usize| {
                    range.clone().fold(Complex::new(0.0f64, 0.0), |sum, f| {
                        let (x, y) = (spec.frame(f, i)[k], spec.frame(f, j)[k]);
                        let (x, y) = (
                            Complex::new(f64::from(x.re), f64::from(x.im)),
                            Complex::new(f64::from(y.re), f64::from(y.im)),
                        );
                        sum + x * y.conj()
                    })
                };
                let trace: f64 = (0..m).map(|i| entry(i, i).re).sum();
                let mut pair = 0;
                for i in 0..m {
                    for j in i..m {
                        let want = entry(i, j) / trace;
                        let at = (b * pairs + pair) * bins + k;
                        assert!(
                            (cov.re[at] - want.re).abs() < 1e-12,
                            "block {b} bin {k} ({i}, {j})"
                        );
                        assert!(
                            (cov.im[at] - want.im).abs() < 1e-12,
                            "block {b} bin {k} ({i}, {j})"
                        );
                        pair += 1;
                    }
                }
            }
        }
    }
}
