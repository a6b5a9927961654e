//! Deflation: a weak DoA refined on what the recording holds once the stronger DoAs of its
//! row are projected out ([`crate::SslConfig::deflate`]; by default for compact arrays only).
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
//! once per row (`BlockCovariances`) and the projection is applied to the steering
//! vector, `(P⊥ a)ᴴ R (P⊥ a)`, rather than to each block's matrix. Bins where the array
//! does not resolve the stronger DoAs from each other, and candidate directions that the
//! projection all but removes (`‖a_p‖²` under a fifth of `M`), are left out.
//!
//! When not. The step assumes the row's DoAs are the sources the recording holds, and
//! plane waves. A row cut at `N` holds fewer ([`crate::Located::cut`]) and is left alone.
//! In a crowd that the array does not resolve (ten talkers heard by the ReSpeaker, rows of
//! two or three), the residual is the other talkers' and the refined DoAs follow them:
//! hence a gate (`residual_share`, [`crate::SslConfig::deflate_max_residual`]) that
//! refines a row only when its DoAs, projected out all at once, leave clearly less power
//! per dimension than noise would (a crowd, or a reverberant room, leaves nearly as
//! much; measured). And a source nearer than the array's
//! far-field distance (2 D² / λ: 2.1 m for the paper's array, 0.211 m across, at 8 kHz) is
//! no plane wave, so that projecting its DoA out leaves much of it. Hence on by default
//! only for an array whose far-field distance at the band's top is under a metre (a
//! ReSpeaker's is 0.19 m; [`crate::SslConfig::deflates`]).

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
    /// How block values are pooled ([`Pooling::Max`] or [`Pooling::Mean`]: a localizer
    /// passes the one it chose for the recording; [`Pooling::Auto`] pools as max), and
    /// `pool_top`.
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
            Pooling::Max | Pooling::Auto => {
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
            if let Some(field) = spec.noise() {
                // Less the robot's noise over the block's frames ([`crate::noise`]); the
                // powers kept at least a share of what was heard.
                let t = frames.len() as f64;
                let mut pair = 0;
                for i in 0..m {
                    for j in i..m {
                        let at = block + pair * bins;
                        for (k, b) in spec.bins().enumerate() {
                            let n = field.cross(b, i, j);
                            if i == j {
                                let heard = re[at + k];
                                let floor = f64::from(crate::noise::RESIDUAL_FLOOR) * heard;
                                re[at + k] = (heard - t * f64::from(n.re)).max(floor);
                            } else {
                                re[at + k] -= t * f64::from(n.re);
                                im[at + k] -= t * f64::from(n.im);
                            }
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

/// The projector away from the waves whose microphone leads are `leads`, at angular
/// frequency `w`, `P⊥ = I - A (AᴴA)⁻¹ Aᴴ` (`m x m`); `None` where the array does not
/// resolve them from each other ([`resolved_steering`]).
fn projector(m: usize, w: f64, leads: &[Vec<f64>]) -> Option<CMatrix> {
    let (a, gi) = resolved_steering(m, w, leads)?;
    Some(DMatrix::identity(m, m) - &a * gi * a.adjoint())
}

/// Whether `s` DoAs on `m` microphones leave the two dimensions that
/// [`residual_share`] needs to test them (one dimension is explained by any field).
pub(crate) fn testable(s: usize, m: usize) -> bool {
    s + 2 <= m
}

/// How much of the field a row's DoAs leave unexplained: the power left once all of
/// `doas` are projected out, per dimension left, as a share of the power per dimension
/// (`(tr(P⊥ R) / (M - s)) / (tr(R) / M)` for `s` DoAs and `M` microphones), averaged over
/// the blocks of `cov` and the bins where the array resolves the DoAs. About 1 for
/// spatially white noise, or for a field of many more sources than the row holds; the
/// noise's share of the power when the row's plane waves are all there is. `None` when the
/// DoAs leave fewer than two dimensions (one dimension is explained by any field) or no
/// bin resolves them ([`crate::SslConfig::deflate_max_residual`]).
pub(crate) fn residual_share(
    setup: &Setup<'_>,
    spec: &Spectrogram,
    cov: &BlockCovariances,
    doas: &[(f64, f64)],
) -> Option<f64> {
    let (m, nb) = (cov.m, cov.bins);
    let s = doas.len();
    if !testable(s, m) {
        return None;
    }
    let leads: Vec<Vec<f64>> = doas.iter().map(|&(a, e)| setup.lead(a, e)).collect();
    let pairs = m * (m + 1) / 2;
    let (mut sum, mut count) = (0.0f64, 0usize);
    for (k, bin) in spec.bins().enumerate() {
        let w = angular_frequency(bin, setup.frame_len, setup.fs);
        let Some(p) = projector(m, w, &leads) else {
            continue;
        };
        for block in 0..cov.blocks {
            let entry = |pair: usize| {
                let at = (block * pairs + pair) * nb + k;
                Complex::new(cov.re[at], cov.im[at])
            };
            // A block silent in this bin was stored as zero: it says nothing.
            let trace: f64 = (0..m).map(|i| entry(diagonal(i, m)).re).sum();
            if trace < 0.5 {
                continue;
            }
            // tr(P⊥ R) = Σ_i P_ii R_ii + 2 Re Σ_{i<j} P_ij conj(R_ij), R Hermitian.
            let mut pair = 0;
            let mut left = 0.0;
            for i in 0..m {
                for j in i..m {
                    let r = entry(pair);
                    left += if i == j {
                        p[(i, i)].re * r.re
                    } else {
                        2.0 * (p[(i, j)] * r.conj()).re
                    };
                    pair += 1;
                }
            }
            sum += left;
            count += 1;
        }
    }
    (count > 0).then(|| sum / count as f64 * m as f64 / (m - s) as f64)
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
    let projectors: Vec<Option<CMatrix>> = omega.iter().map(|&w| projector(m, w, &leads)).collect();
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

    /// Complex Gaussian deviates of unit power from a fixed seed (a 64-bit LCG and
    /// Box-Muller): the tests' noise without a generator crate.
    fn gaussians(n: usize, seed: u64) -> Vec<Complex<f64>> {
        let mut state = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
        let mut uniform = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((state >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| {
                let (r, t) = ((-uniform().ln()).sqrt(), std::f64::consts::TAU * uniform());
                Complex::from_polar(r, t)
            })
            .collect()
    }

    /// The ReSpeaker 4-mic's positions (m), 16 kHz, 512-sample frames.
    const MICS: [[f64; 3]; 4] = [
        [-0.032, 0.0, 0.0],
        [0.0, -0.032, 0.0],
        [0.032, 0.0, 0.0],
        [0.0, 0.032, 0.0],
    ];

    fn setup() -> Setup<'static> {
        Setup {
            positions: &MICS,
            fs: 16_000.0,
            frame_len: 512,
            c: 343.0,
            pooling: Pooling::Max,
            pool_top: 1,
        }
    }

    /// A spectrogram of `frames` frames over bins 20..200 (625-6250 Hz) holding plane
    /// waves from `waves` (azimuth degrees, in the plane; independent unit-power signals,
    /// amplitude each) and white sensor noise of power `noise` per microphone.
    fn field(waves: &[(f64, f64)], noise: f64, frames: usize) -> Spectrogram {
        let (m, bins) = (MICS.len(), 20..200);
        let nb = bins.len();
        let setup = setup();
        let mut data = vec![Complex32::new(0.0, 0.0); frames * m * nb];
        let sensor = gaussians(data.len(), 1);
        for (n, x) in data.iter_mut().enumerate() {
            *x = Complex32::new(
                (noise.sqrt() * sensor[n].re) as f32,
                (noise.sqrt() * sensor[n].im) as f32,
            );
        }
        for (w, &(azimuth, amplitude)) in waves.iter().enumerate() {
            let lead = setup.lead(azimuth, 0.0);
            let signal = gaussians(frames * nb, 100 + w as u64);
            for f in 0..frames {
                for (k, bin) in bins.clone().enumerate() {
                    let omega = angular_frequency(bin, setup.frame_len, setup.fs);
                    for (i, l) in lead.iter().enumerate() {
                        let x =
                            amplitude * signal[f * nb + k] * Complex::from_polar(1.0, omega * l);
                        let at = (f * m + i) * nb + k;
                        data[at] += Complex32::new(x.re as f32, x.im as f32);
                    }
                }
            }
        }
        Spectrogram::from_parts(frames, m, bins, data)
    }

    /// The residual share is about 1 for spatially white noise, whatever directions are
    /// projected out; the noise's share of the power when the row's plane waves are all
    /// the field holds; near 1 again when the row holds two of six equal sources (a crowd);
    /// and undefined when one dimension would be left.
    #[test]
    fn the_residual_share_tells_a_row_that_explains_its_field_from_a_crowd() {
        let setup = setup();
        let share = |spec: &Spectrogram, doas: &[(f64, f64)]| {
            let blocks: Vec<Range<usize>> = (0..8).map(|b| 4 * b..4 * b + 4).collect();
            residual_share(&setup, spec, &BlockCovariances::of(spec, &blocks), doas)
        };
        let row = [(90.0, 0.0), (10.0, 0.0)];
        let noise = share(&field(&[], 1.0, 32), &row).unwrap();
        assert!((noise - 1.0).abs() < 0.1, "white noise: {noise}");
        // Two waves of power 1 each and noise of 0.1 per microphone: the noise holds
        // 0.4 / (8 + 0.4) of the power.
        let two = share(&field(&[(90.0, 1.0), (10.0, 1.0)], 0.1, 32), &row).unwrap();
        assert!(two < 0.1, "two talkers, both in the row: {two}");
        let crowd: Vec<(f64, f64)> = [90.0, 10.0, -50.0, -110.0, 150.0, 40.0]
            .iter()
            .map(|&a| (a, 1.0))
            .collect();
        let many = share(&field(&crowd, 0.1, 32), &row).unwrap();
        assert!(many > 0.65, "six talkers, two in the row: {many}");
        assert_eq!(
            share(
                &field(&[], 1.0, 32),
                &[(90.0, 0.0), (10.0, 0.0), (-60.0, 0.0)]
            ),
            None
        );
    }

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
