//! MUSIC and NormMUSIC: subspace methods on the full spatial covariance.
//!
//! MUSIC (Schmidt 1986) splits each bin's `M x M` spatial covariance into the signal
//! subspace spanned by its `K` largest eigenvectors and the noise subspace `E_n` of the
//! others. A plane wave's steering vector `a_b(u)` lies in the signal subspace when `u` is a
//! source's direction, so the pseudo-spectrum `P_b(u) = 1 / |E_n^H a_b(u)|^2` (with `a`
//! scaled to unit norm) peaks there far more sharply than any beamformer. **MUSIC** sums
//! `P_b` over bins as it comes, so the few bins with the sharpest peaks decide; **NormMUSIC**
//! (Salvati, Drioli & Foresti 2014, and pyroomacoustics' `NormMUSIC`) divides each bin's
//! pseudo-spectrum by its largest value first, so every bin votes alike, as PHAT makes them
//! for GCC.
//!
//! Unlike the pairwise methods, the covariance couples all microphones at once, and the
//! pseudo-spectrum is a non-linear function of it per bin: it does not decompose into
//! pairs, and the pairwise lag kernel of [`crate::grid`] does not apply. This is the second
//! family of estimators: per block, one covariance and one eigen-decomposition
//! (nalgebra's, Hermitian) per group of bins, then every direction of the grid steered
//! once per group.
//!
//! ## Algorithm
//! 1. Group the band's bins in runs of `2 F + 1` ([`crate::SslConfig::music_freq_smoothing`]);
//!    per group, sum `x x^H` over the block's frames and the group's bins.
//! 2. Eigen-decompose it; keep the `K` largest eigenvectors: `K` fixed by
//!    [`crate::SslConfig::music_sources`], or estimated per group as the eigenvalues within
//!    10 dB of the largest, up to N. `|E_n^H a|^2 = |a|^2 - |E_s^H a|^2`, so with `K` fixed
//!    whichever subspace is smaller is the one projected on.
//! 3. For every direction, steer to the group's centre frequency (the phasors advance from
//!    group to group by one complex multiplication per microphone) and evaluate `P_b`;
//!    sum over groups (NormMUSIC: each group divided by its largest value first).

use std::ops::Range;

use nalgebra::{Complex, DMatrix, SymmetricEigen};
use realfft::num_complex::Complex32;

use crate::array::MicArray;
use crate::grid::DirectionGrid;
use crate::localizer::zeroed;
use crate::stft::Spectrogram;
use crate::{Scratch, SpectrumEstimator};

/// The smallest value of `|E_n^H a|^2 / |a|^2` used: it bounds one bin's peak at `1e5`
/// times its floor, far above the precision of `f32` sums of a few terms, so that a
/// noise-free bin cannot make an infinite peak.
const FLOOR: f32 = 1e-5;

/// With the subspace dimension estimated, a group's signal subspace holds the eigenvectors
/// whose eigenvalue is at least this fraction of the largest (up to the cap): a source up to
/// 10 dB weaker than the group's strongest still counts as one.
const EIG_RATIO: f32 = 0.1;

/// The MUSIC and NormMUSIC estimators for one array, grid, band and sample rate.
#[derive(Clone, Debug)]
pub struct Music {
    mics: usize,
    /// Signal-subspace dimension `K` (`1..mics`), or its cap when `estimate`.
    sources: usize,
    /// Whether each group's `K` is estimated from its eigenvalues ([`EIG_RATIO`]).
    estimate: bool,
    /// Half-width `F` of a group of bins.
    smoothing: usize,
    /// Bins in the band.
    n_bins: usize,
    /// Group centres (band-relative bin indices), `2F + 1` apart.
    centres: Vec<usize>,
    n_dirs: usize,
    /// Per direction and microphone ([`Tables`]' layout): the steering phasor at the first
    /// group's centre and its step from one group centre to the next, real and imaginary
    /// parts apart so the direction loops vectorise.
    start_re: Vec<f32>,
    start_im: Vec<f32>,
    step_re: Vec<f32>,
    step_im: Vec<f32>,
    normalise: bool,
}

/// Working memory of the subspace estimators (part of [`crate::Scratch`]).
#[derive(Clone, Debug, Default)]
pub(crate) struct SubspaceScratch {
    /// One chunk's steering phasors being advanced, per microphone and lane.
    a_re: Vec<f32>,
    a_im: Vec<f32>,
    /// Per group and direction, `|E^H a|^2`, then the group's pseudo-spectrum.
    proj: Vec<f32>,
    /// The projected-on eigenvectors of every group: group-major, then vector, then mic.
    vec_re: Vec<f32>,
    vec_im: Vec<f32>,
}

impl Music {
    /// Plans the estimator. `bins` are the band's bins of a `frame_len`-point FFT at `fs`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        array: &MicArray,
        grid: &DirectionGrid,
        fs: f64,
        c: f64,
        bins: Range<usize>,
        frame_len: usize,
        sources: Option<usize>,
        max_sources: usize,
        smoothing: usize,
        normalise: bool,
    ) -> Self {
        let estimate = sources.is_none();
        let sources = sources.unwrap_or(max_sources);
        let mics = array.len();
        let sources = sources.clamp(1, mics.saturating_sub(1).max(1));
        let n_bins = bins.len();
        let g = 2 * smoothing + 1;
        let centres: Vec<usize> = if n_bins >= g {
            (0..n_bins / g).map(|k| smoothing + k * g).collect()
        } else {
            vec![n_bins / 2]
        };
        // Delays relative to the array's centroid keep the phases small.
        let pos = array.positions();
        let centroid: [f64; 3] =
            std::array::from_fn(|a| pos.iter().map(|p| p[a]).sum::<f64>() / mics as f64);
        let n_dirs = grid.len();
        // Chunk-major, padded to whole chunks of W directions (the padding stays 0).
        let len = n_dirs.div_ceil(W) * W * mics;
        let mut start_re = vec![0.0; len];
        let mut start_im = vec![0.0; len];
        let mut step_re = vec![0.0; len];
        let mut step_im = vec![0.0; len];
        let w0 = std::f64::consts::TAU * (bins.start + centres[0]) as f64 / frame_len as f64;
        let dw = std::f64::consts::TAU * g as f64 / frame_len as f64;
        for d in 0..n_dirs {
            let u = grid.unit(d);
            for (m, p) in pos.iter().enumerate() {
                // A microphone further along u hears the wave earlier: its STFT is the
                // reference's times exp(+i w lead), lead = (p - centroid) . u / c (samples).
                let lead = (0..3).map(|a| (p[a] - centroid[a]) * u[a]).sum::<f64>() / c * fs;
                let i = ((d / W) * mics + m) * W + d % W;
                (start_re[i], start_im[i]) = ((w0 * lead).cos() as f32, (w0 * lead).sin() as f32);
                (step_re[i], step_im[i]) = ((dw * lead).cos() as f32, (dw * lead).sin() as f32);
            }
        }
        Self {
            mics,
            sources,
            estimate,
            smoothing,
            n_bins,
            centres,
            n_dirs,
            start_re,
            start_im,
            step_re,
            step_im,
            normalise,
        }
    }

    /// The signal-subspace dimension in use: fixed, or `None` when estimated per group
    /// (up to [`crate::SslConfig::num_peaks`]).
    pub fn sources(&self) -> Option<usize> {
        (!self.estimate).then_some(self.sources)
    }

    /// Fills `s.vec_re`/`s.vec_im` with each group's projected-on eigenvectors; returns how
    /// many there are per group and whether they span the signal subspace.
    fn subspaces(
        &self,
        stft: &Spectrogram,
        frames: Range<usize>,
        s: &mut SubspaceScratch,
    ) -> (usize, bool) {
        let m = self.mics;
        let signal = self.estimate || self.sources <= m - self.sources;
        let dim = if signal {
            self.sources
        } else {
            m - self.sources
        };
        let n = self.centres.len() * dim * m;
        let (vr, vi) = (zeroed(&mut s.vec_re, n), zeroed(&mut s.vec_im, n));
        let mut cov = DMatrix::<Complex<f32>>::zeros(m, m);
        for (k, &c) in self.centres.iter().enumerate() {
            cov.fill(Complex::default());
            let band = c.saturating_sub(self.smoothing)..(c + self.smoothing + 1).min(self.n_bins);
            for f in frames.clone() {
                for b in band.clone() {
                    for i in 0..m {
                        let xi = stft.frame(f, i)[b];
                        for j in i..m {
                            cov[(i, j)] += xi * stft.frame(f, j)[b].conj();
                        }
                    }
                }
            }
            // Scale to unit trace (the decomposition does not care, f32 does), then mirror.
            let tr: f32 = (0..m).map(|i| cov[(i, i)].re).sum();
            if tr <= f32::MIN_POSITIVE {
                // No energy: the vectors stay 0 and the group adds the same to every direction.
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
            let keep = if signal {
                &order[..dim]
            } else {
                &order[m - dim..]
            };
            for (v, &e) in keep.iter().enumerate() {
                if self.estimate
                    && v > 0
                    && eig.eigenvalues[e] < EIG_RATIO * eig.eigenvalues[order[0]]
                {
                    break; // the vectors past the estimate stay 0 and project nothing
                }
                for mic in 0..m {
                    let z: Complex32 = eig.eigenvectors[(mic, e)];
                    vr[(k * dim + v) * m + mic] = z.re;
                    vi[(k * dim + v) * m + mic] = z.im;
                }
            }
        }
        (dim, signal)
    }
}

impl SpectrumEstimator for Music {
    fn name(&self) -> &'static str {
        if self.normalise { "normmusic" } else { "music" }
    }

    fn estimate_into(
        &self,
        stft: &Spectrogram,
        frames: Range<usize>,
        out: &mut [f32],
        scratch: &mut Scratch,
    ) {
        assert_eq!(
            stft.bins().len(),
            self.n_bins,
            "spectrogram band differs from the plan"
        );
        assert_eq!(stft.num_channels(), self.mics, "one channel per microphone");
        assert_eq!(out.len(), self.n_dirs, "one value per direction");
        let s = &mut scratch.subspace;
        let (dim, signal) = self.subspaces(stft, frames, s);
        let (m, nd, ng) = (self.mics, self.n_dirs, self.centres.len());
        let nd_pad = nd.div_ceil(W) * W;
        let SubspaceScratch {
            a_re,
            a_im,
            proj,
            vec_re,
            vec_im,
        } = s;
        zeroed(a_re, m * W);
        zeroed(a_im, m * W);
        let proj = zeroed(proj, ng * nd_pad);
        let tables = Tables {
            start_re: &self.start_re,
            start_im: &self.start_im,
            step_re: &self.step_re,
            step_im: &self.step_im,
        };
        steer_all(&tables, vec_re, vec_im, m, dim, ng, a_re, a_im, proj);
        // |E_n^H a|^2 / |a|^2 with |a|^2 = M; the padding past nd is left out.
        out.fill(0.0);
        let inv_m = 1.0 / m as f32;
        let norm = 1.0 / ng as f32;
        for p in proj.chunks_exact_mut(nd_pad) {
            let p = &mut p[..nd];
            for v in p.iter_mut() {
                let noise = if signal { 1.0 - *v * inv_m } else { *v * inv_m };
                *v = 1.0 / noise.max(FLOOR);
            }
            let scale = if self.normalise {
                norm / p.iter().copied().fold(f32::MIN_POSITIVE, f32::max)
            } else {
                norm * FLOOR
            };
            for (o, v) in out.iter_mut().zip(p.iter()) {
                *o += v * scale;
            }
        }
    }
}

/// Directions are steered [`W`] at a time: a chunk's phasors stay in registers (or L1)
/// while every group is evaluated, so the tables are read once per block.
const W: usize = 16;

/// The steering tables, chunk-major: `[(chunk * mics + mic) * W + lane]`.
struct Tables<'a> {
    start_re: &'a [f32],
    start_im: &'a [f32],
    step_re: &'a [f32],
    step_im: &'a [f32],
}

/// `proj[k * nd_pad + d] = sum over the group's vectors e of |e^H a_k(d)|^2` for every
/// group `k` and (padded) direction `d`, with `vec_*` group-major, then vector, then mic.
#[allow(clippy::too_many_arguments)]
fn steer_all(
    t: &Tables,
    vec_re: &[f32],
    vec_im: &[f32],
    mics: usize,
    dim: usize,
    groups: usize,
    a_re: &mut [f32],
    a_im: &mut [f32],
    proj: &mut [f32],
) {
    #[cfg(target_arch = "x86_64")]
    if crate::localizer::avx2_fma() {
        // SAFETY: the CPU supports the features the function is compiled for.
        unsafe { steer_all_avx2(t, vec_re, vec_im, mics, dim, groups, a_re, a_im, proj) };
        return;
    }
    steer_all_portable(t, vec_re, vec_im, mics, dim, groups, a_re, a_im, proj);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
#[allow(clippy::too_many_arguments)]
unsafe fn steer_all_avx2(
    t: &Tables,
    vec_re: &[f32],
    vec_im: &[f32],
    mics: usize,
    dim: usize,
    groups: usize,
    a_re: &mut [f32],
    a_im: &mut [f32],
    proj: &mut [f32],
) {
    steer_all_portable(t, vec_re, vec_im, mics, dim, groups, a_re, a_im, proj);
}

#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn steer_all_portable(
    t: &Tables,
    vec_re: &[f32],
    vec_im: &[f32],
    mics: usize,
    dim: usize,
    groups: usize,
    a_re: &mut [f32],
    a_im: &mut [f32],
    proj: &mut [f32],
) {
    let nd_pad = proj.len() / groups;
    let (a_re, a_im) = (a_re.as_chunks_mut::<W>().0, a_im.as_chunks_mut::<W>().0);
    let (start_re, start_im) = (t.start_re.as_chunks::<W>().0, t.start_im.as_chunks::<W>().0);
    let (step_re, step_im) = (t.step_re.as_chunks::<W>().0, t.step_im.as_chunks::<W>().0);
    let proj = proj.as_chunks_mut::<W>().0;
    let chunks = nd_pad / W;
    for c in 0..chunks {
        let rows = c * mics..(c + 1) * mics;
        a_re.copy_from_slice(&start_re[rows.clone()]);
        a_im.copy_from_slice(&start_im[rows.clone()]);
        let (st_re, st_im) = (&step_re[rows.clone()], &step_im[rows]);
        for k in 0..groups {
            let mut p = [0.0f32; W];
            for v in 0..dim {
                let e = (k * dim + v) * mics;
                let (er, ei) = (&vec_re[e..e + mics], &vec_im[e..e + mics]);
                let (mut sr, mut si) = ([0.0f32; W], [0.0f32; W]);
                for (((x, y), &r), &i) in a_re.iter().zip(a_im.iter()).zip(er).zip(ei) {
                    // conj(e) a = (r - i j)(x + y j) = (r x + i y) + (r y - i x) j
                    for l in 0..W {
                        sr[l] += r * x[l] + i * y[l];
                        si[l] += r * y[l] - i * x[l];
                    }
                }
                for l in 0..W {
                    p[l] += sr[l] * sr[l] + si[l] * si[l];
                }
            }
            proj[k * chunks + c] = p;
            if k + 1 < groups {
                for (((x, y), r), i) in a_re.iter_mut().zip(a_im.iter_mut()).zip(st_re).zip(st_im) {
                    let (ox, oy) = (*x, *y);
                    for l in 0..W {
                        x[l] = ox[l] * r[l] - oy[l] * i[l];
                        y[l] = ox[l] * i[l] + oy[l] * r[l];
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::ElevationRange;

    /// The chunked, recurrence-stepped kernel against a direct sum in f64 with every
    /// steering phasor computed from its delay: `sum_v |e_v^H a_k(d)|^2`.
    #[test]
    fn the_steering_kernel_matches_a_direct_sum() {
        let array = MicArray::default();
        let grid = DirectionGrid::new(7.0, ElevationRange::ROBOT).unwrap();
        let (fs, c, frame_len, bins) = (48_000.0, 343.0, 1024, 5..171);
        let music = Music::new(
            &array,
            &grid,
            fs,
            c,
            bins.clone(),
            frame_len,
            Some(2),
            4,
            2,
            true,
        );
        let (m, dim, ng) = (array.len(), 2, music.centres.len());
        let mut state = 7u64;
        let mut rnd = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
        };
        let vec_re: Vec<f32> = (0..ng * dim * m).map(|_| rnd()).collect();
        let vec_im: Vec<f32> = (0..ng * dim * m).map(|_| rnd()).collect();
        let nd_pad = grid.len().div_ceil(W) * W;
        let mut proj = vec![0.0; ng * nd_pad];
        let (mut a_re, mut a_im) = (vec![0.0; m * W], vec![0.0; m * W]);
        let t = Tables {
            start_re: &music.start_re,
            start_im: &music.start_im,
            step_re: &music.step_re,
            step_im: &music.step_im,
        };
        steer_all(
            &t, &vec_re, &vec_im, m, dim, ng, &mut a_re, &mut a_im, &mut proj,
        );
        // The portable build is the same source compiled without AVX2 (no fused
        // multiply-adds are formed): the same sums, bit for bit.
        let mut portable = vec![0.0; ng * nd_pad];
        steer_all_portable(
            &t,
            &vec_re,
            &vec_im,
            m,
            dim,
            ng,
            &mut a_re,
            &mut a_im,
            &mut portable,
        );
        assert!(proj == portable, "dispatched and portable kernels differ");
        let pos = array.positions();
        let centroid: [f64; 3] =
            std::array::from_fn(|a| pos.iter().map(|p| p[a]).sum::<f64>() / m as f64);
        let mut worst = 0.0f64;
        for (k, &centre) in music.centres.iter().enumerate() {
            let w = std::f64::consts::TAU * (bins.start + centre) as f64 / frame_len as f64;
            for d in 0..grid.len() {
                let u = grid.unit(d);
                let mut want = 0.0;
                for v in 0..dim {
                    let (mut re, mut im) = (0.0, 0.0);
                    for (mic, p) in pos.iter().enumerate() {
                        let lead =
                            (0..3).map(|a| (p[a] - centroid[a]) * u[a]).sum::<f64>() / c * fs;
                        let (ar, ai) = ((w * lead).cos(), (w * lead).sin());
                        let i = (k * dim + v) * m + mic;
                        let (er, ei) = (f64::from(vec_re[i]), f64::from(vec_im[i]));
                        re += er * ar + ei * ai;
                        im += er * ai - ei * ar;
                    }
                    want += re * re + im * im;
                }
                let got = f64::from(proj[k * nd_pad + d]);
                worst = worst.max((got - want).abs());
            }
        }
        // Values are O(1); 33 f32 recurrence steps keep the phasors within 1e-5.
        assert!(worst < 1e-4, "largest difference {worst}");
    }

    #[test]
    fn the_subspace_is_capped_below_the_number_of_microphones() {
        let array = MicArray::preset("respeaker4").unwrap();
        let grid = DirectionGrid::new(10.0, ElevationRange::PLANE).unwrap();
        let m = Music::new(
            &array,
            &grid,
            16_000.0,
            343.0,
            7..256,
            512,
            Some(9),
            4,
            2,
            true,
        );
        assert_eq!(m.sources(), Some(3));
        let m = Music::new(
            &array,
            &grid,
            16_000.0,
            343.0,
            7..256,
            512,
            None,
            4,
            2,
            true,
        );
        assert_eq!(m.sources(), None);
    }
}
