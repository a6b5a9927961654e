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
//! elevation stays. Bins where the array does not resolve the stronger DoAs from each
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

/// The azimuth (degrees, wrapped) of the DoA at `weak` (azimuth, elevation) refined with
/// the DoAs at `strong` projected out of the blocks of `spec` (each a range of frames);
/// `weak`'s own azimuth when there is nothing to refine against (no stronger DoA, more
/// than `M - 2` of them, no block).
pub(crate) fn deflated_azimuth(
    setup: &Setup<'_>,
    spec: &Spectrogram,
    blocks: &[Range<usize>],
    strong: &[(f64, f64)],
    weak: (f64, f64),
) -> f64 {
    let m = spec.num_channels();
    let s = strong.len();
    if s == 0 || s + 2 > m || blocks.is_empty() {
        return weak.0;
    }
    let omega: Vec<f64> = spec
        .bins()
        .map(|b| angular_frequency(b, setup.frame_len, setup.fs))
        .collect();
    let nb = omega.len();
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
    // Per block and bin, P⊥ R P⊥ / tr R (real and imaginary parts, row-major).
    let mm = m * m;
    let (mut q_re, mut q_im) = (
        vec![0.0f64; blocks.len() * nb * mm],
        vec![0.0; blocks.len() * nb * mm],
    );
    let mut r = CMatrix::zeros(m, m);
    for (bi, frames) in blocks.iter().enumerate() {
        for (k, p) in projectors.iter().enumerate() {
            let Some(p) = p else { continue };
            r.fill(Complex::new(0.0, 0.0));
            for f in frames.clone() {
                for i in 0..m {
                    let xi = spec.frame(f, i)[k];
                    let xi = Complex::new(f64::from(xi.re), f64::from(xi.im));
                    for j in 0..m {
                        let xj = spec.frame(f, j)[k];
                        r[(i, j)] += xi * Complex::new(f64::from(xj.re), -f64::from(xj.im));
                    }
                }
            }
            let tr = r.trace().re;
            if tr <= 0.0 {
                continue;
            }
            let q = p * &r * p / Complex::new(tr, 0.0);
            let at = (bi * nb + k) * mm;
            for (t, v) in q.transpose().iter().enumerate() {
                // `transpose` so that the column-major iteration runs row by row.
                q_re[at + t] = v.re;
                q_im[at + t] = v.im;
            }
        }
    }
    let mut per_block = vec![0.0f64; blocks.len()];
    let mut a = vec![Complex::new(0.0, 0.0); m];
    let (mut ph_re, mut ph_im) = (vec![0.0f64; mm], vec![0.0f64; mm]);
    let mut power = |azimuth_deg: f64| -> f64 {
        let lead = setup.lead(azimuth_deg, weak.1);
        per_block.iter_mut().for_each(|q| *q = 0.0);
        for (k, p) in projectors.iter().enumerate() {
            let Some(p) = p else { continue };
            for (ai, l) in a.iter_mut().zip(&lead) {
                *ai = Complex::from_polar(1.0, omega[k] * l);
            }
            // ‖P⊥ a‖² = aᴴ P⊥ a.
            let mut n2 = 0.0;
            for i in 0..m {
                for j in 0..m {
                    n2 += (a[i].conj() * p[(i, j)] * a[j]).re;
                }
            }
            if n2 < 0.2 * m as f64 {
                continue;
            }
            for i in 0..m {
                for j in 0..m {
                    let z = a[i].conj() * a[j] / n2;
                    (ph_re[i * m + j], ph_im[i * m + j]) = (z.re, z.im);
                }
            }
            for (bi, q) in per_block.iter_mut().enumerate() {
                let at = (bi * nb + k) * mm;
                let (re, im) = (&q_re[at..at + mm], &q_im[at..at + mm]);
                *q += re
                    .iter()
                    .zip(im)
                    .zip(ph_re.iter().zip(&ph_im))
                    .map(|((x, y), (u, v))| x * u - y * v)
                    .sum::<f64>();
            }
        }
        setup.pool(&mut per_block)
    };
    let start = weak.0;
    let mut at = start;
    let mut here = power(at);
    for step in [1.0, 0.25] {
        loop {
            let (lower, upper) = (power(at - step), power(at + step));
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
