//! Whether two directions hear one signal or two: the source coherence of a pair of DoAs.
//!
//! An angular spectrum has peaks where sources are, and also where copies of a source
//! arrive: its reflections off walls (image sources), and its sidelobes through the
//! array. Heights alone do not tell them apart: a far talker beside a near one stands as
//! low as the near one's reflections (0.15-0.3 of its peak in the regression suite's rooms).
//! What does tell them apart is the signal: a reflection or a sidelobe carries the *same*
//! signal as the direct path it copies, an independent source does not.
//!
//! [`SpatialCovariance::source_coherence`] measures that. For each frequency bin it fits
//! the recording's spatial covariance `R` (all microphones, summed over the frames that
//! carry sound) with plane waves from the two directions, `a` and `b`, and white sensor
//! noise, by least squares: `S = A⁺ (R - σ² I) A⁺ᴴ` with `A = [a b]`, the 2 x 2 covariance
//! of the two waves' signals, and `σ²` the power per dimension that the two waves leave
//! of `R` (the model's maximum-likelihood noise power). Their coherence
//! `|S_ab| / sqrt(S_aa S_bb)` is 1 when they carry one signal (one rank-one term: a source
//! and its copy) and near 0 when they carry independent ones. The statistic averages it
//! over the band, each bin weighted by the power the fit gives the second direction
//! `S_bb`, so that the bins where that direction is heard decide.
//! [`SpatialCovariance::multiple_coherence`] fits more directions at once.
//!
//! Why the noise term: without it, sensor noise counts as signal of either wave,
//! independent of the other, and at low SNR every low peak looks like a source of its own
//! (measured: a two-talker room at SNR 5 dB gained ghosts).
//!
//! It is not 0 for an independent source in a room: the reverberation of both sources
//! leaks into both fitted waves alike, and a recording has finitely many frames. Measured
//! on the regression suite's and held-out scenes, a
//! second talker's low peaks mostly lie at 0.3-0.55, the reflections and sidelobes of the
//! scenes' talkers mostly at 0.5-1 (0.95 for a single white-noise source).
//!
//! Limits. A third source that the two-wave fit leaves out leaks into both waves, and
//! through it they look coherent: a quiet source lower than a loud one's sidelobe is
//! taken for a copy of that sidelobe (`tests/coherence.rs`). Fitting every stronger peak
//! at once ([`SpatialCovariance::multiple_coherence`]) removes that, but with five waves
//! on six microphones the fit explains much of any signal, and it reported fewer of the
//! quiet talkers of the ten-talker scenes (measured): the localizer tests
//! pair by pair.
//!
//! A source whose pitch never moves (a hum: a fan, a motor; the simulator's `voiced`
//! signal) is one sinusoid per bin, and a sinusoid's reflections are the same sinusoid
//! however late they arrive: in its bins its whole reverberant field is one signal, part
//! of which the fit gives to any other direction, and the two look coherent through it.
//! Broadband sources' late reflections are decorrelated within a frame and do not do this.
//! Measured: the steady 180-Hz talker of `three_sources`
//! against a louder talker 0.69-0.72 at 2.1-2.3 m, in the range of that row's reflections
//! (0.61-0.79), so its low peaks are taken for copies.
//!
//! With the robot's noise known ([`crate::noise`]), the covariance is the recording's less
//! the noise's over as many frames (and the frames' energies, which choose them, less the
//! noise's): the two waves are fitted to the sources' field.
//!
//! Bins where the steering vectors are nearly parallel (the array does not resolve the
//! directions there: low frequencies, small arrays, close directions) give an
//! ill-conditioned fit and are left out; with none left the statistic is undefined.

use std::ops::Range;

use nalgebra::{Complex, DMatrix, SymmetricEigen};

use crate::stft::Spectrogram;

/// Bins whose two steering vectors have a normalised inner product `|aᴴb| / M` at or above
/// this are left out of [`SpatialCovariance::source_coherence`]: the fit's `(AᴴA)⁻¹` then
/// amplifies noise by `1 / (1 - 0.8²) ≈ 2.8` or more.
const MAX_STEERING_OVERLAP: f64 = 0.8;

/// Frames more than this many dB below the recording's loudest carry no sound worth
/// fitting (pauses, silence): left out of the covariance.
const FRAME_FLOOR_DB: f64 = 20.0;

/// A recording's spatial covariance per frequency bin: `R(k) = Σ_t x(t, k) x(t, k)ᴴ` over
/// the frames within 20 dB of the loudest, all microphones.
#[derive(Clone, Debug)]
pub struct SpatialCovariance {
    /// Microphones.
    m: usize,
    /// The FFT bins, as the spectrogram kept them.
    bins: Range<usize>,
    /// Real and imaginary parts per bin, `m x m` row-major each.
    re: Vec<f64>,
    im: Vec<f64>,
}

impl SpatialCovariance {
    /// The covariance of `spec`'s frames that carry sound, among `frames` (e.g. those
    /// of the blocks the pooling kept, which leaves the room's decay out).
    pub fn of(spec: &Spectrogram, frames: impl IntoIterator<Item = usize>) -> Self {
        let m = spec.num_channels();
        let bins = spec.bins();
        let nb = bins.len();
        let nf = spec.num_frames();
        // What the robot's own noise adds to each frame's energy ([`crate::noise`]).
        let noise_energy = spec.noise().map_or(0.0, |n| n.frame_energy(bins.clone()));
        let energy: Vec<f64> = (0..nf)
            .map(|f| {
                let e: f64 = (0..m)
                    .flat_map(|c| spec.frame(f, c))
                    .map(|x| f64::from(x.norm_sqr()))
                    .sum();
                (e - noise_energy).max(0.0)
            })
            .collect();
        let loudest = energy.iter().copied().fold(0.0, f64::max);
        let floor = loudest * 10f64.powf(-FRAME_FLOOR_DB / 10.0);
        // Per pair (i <= j), bins contiguous, so that the sums vectorise; f32 products
        // summed in f32 per frame would lose little, but the frames are few and f64 is safe.
        let pairs: Vec<(usize, usize)> = (0..m).flat_map(|i| (i..m).map(move |j| (i, j))).collect();
        let (mut pr, mut pi) = (
            vec![0.0f64; pairs.len() * nb],
            vec![0.0f64; pairs.len() * nb],
        );
        let frames: Vec<usize> = frames
            .into_iter()
            .filter(|&f| f < nf && energy[f] > 0.0 && energy[f] >= floor)
            .collect();
        let kept = frames.len() as f64;
        for f in frames {
            for (p, &(i, j)) in pairs.iter().enumerate() {
                let (xi, xj) = (spec.frame(f, i), spec.frame(f, j));
                let sums = pr[p * nb..(p + 1) * nb]
                    .iter_mut()
                    .zip(&mut pi[p * nb..(p + 1) * nb]);
                for ((sr, si), (a, b)) in sums.zip(xi.iter().zip(xj)) {
                    // x_i x_j^*
                    *sr += f64::from(a.re * b.re + a.im * b.im);
                    *si += f64::from(a.im * b.re - a.re * b.im);
                }
            }
        }
        if let Some(field) = spec.noise() {
            // Less the robot's noise over the frames summed; a power kept at least a share
            // of what was heard, as the spectra keep it.
            let floor = f64::from(crate::noise::RESIDUAL_FLOOR);
            for (p, &(i, j)) in pairs.iter().enumerate() {
                for (k, b) in bins.clone().enumerate() {
                    let n = field.cross(b, i, j);
                    let at = p * nb + k;
                    if i == j {
                        pr[at] = (pr[at] - kept * f64::from(n.re)).max(floor * pr[at]);
                    } else {
                        pr[at] -= kept * f64::from(n.re);
                        pi[at] -= kept * f64::from(n.im);
                    }
                }
            }
        }
        let (mut re, mut im) = (vec![0.0f64; nb * m * m], vec![0.0f64; nb * m * m]);
        for (p, &(i, j)) in pairs.iter().enumerate() {
            for k in 0..nb {
                let (r, s) = (pr[p * nb + k], pi[p * nb + k]);
                re[k * m * m + i * m + j] = r;
                im[k * m * m + i * m + j] = s;
                re[k * m * m + j * m + i] = r;
                im[k * m * m + j * m + i] = -s;
            }
        }
        Self { m, bins, re, im }
    }

    /// The source coherence of directions `a` and `b` (unit vectors in the array frame):
    /// in `[0, 1]`, 1 when the recording's sound from the two is one signal, near 0 when
    /// they are independent (see the module docs). `positions` are the microphones (m),
    /// `fs` the sample rate, `frame_len` the STFT's, `c` the speed of sound. `None` when
    /// no bin of the band resolves the two directions or `b` is not heard in any.
    pub fn source_coherence(
        &self,
        positions: &[[f64; 3]],
        fs: f64,
        frame_len: usize,
        c: f64,
        a: [f64; 3],
        b: [f64; 3],
    ) -> Option<f64> {
        // The two-wave case of `multiple_coherence`, written out: 2 x 2 inverses in closed
        // form, no allocation per bin (it runs for every pair of a low peak and a stronger
        // one, in every row that has such a peak).
        let m = self.m;
        debug_assert_eq!(positions.len(), m);
        if m < 3 {
            return None;
        }
        let (la, lb) = (leads(positions, a, c), leads(positions, b, c));
        let mf = m as f64;
        let (mut num, mut den) = (0.0f64, 0.0f64);
        let mut va = vec![(0.0f64, 0.0f64); m];
        let mut vb = vec![(0.0f64, 0.0f64); m];
        let (mut ra, mut rb) = (vec![(0.0f64, 0.0f64); m], vec![(0.0f64, 0.0f64); m]);
        let dot = |u: &[(f64, f64)], v: &[(f64, f64)]| {
            // uᴴ v
            u.iter().zip(v).fold((0.0, 0.0), |(sr, si), (x, y)| {
                (sr + x.0 * y.0 + x.1 * y.1, si + x.0 * y.1 - x.1 * y.0)
            })
        };
        for (k, bin) in self.bins.clone().enumerate() {
            let w = angular_frequency(bin, frame_len, fs);
            // Steering vectors: a microphone further along `u` hears the wave earlier,
            // X = S e^(i w lead).
            for i in 0..m {
                let (s, co) = (w * la[i]).sin_cos();
                va[i] = (co, s);
                let (s, co) = (w * lb[i]).sin_cos();
                vb[i] = (co, s);
            }
            let g = dot(&va, &vb);
            let g2 = g.0 * g.0 + g.1 * g.1;
            if g2.sqrt() / mf >= MAX_STEERING_OVERLAP {
                continue;
            }
            // R a and R b.
            let cov = k * m * m;
            for i in 0..m {
                let (re, im) = (&self.re[cov + i * m..][..m], &self.im[cov + i * m..][..m]);
                let (mut xa, mut xb) = ((0.0, 0.0), (0.0, 0.0));
                for j in 0..m {
                    xa.0 += re[j] * va[j].0 - im[j] * va[j].1;
                    xa.1 += re[j] * va[j].1 + im[j] * va[j].0;
                    xb.0 += re[j] * vb[j].0 - im[j] * vb[j].1;
                    xb.1 += re[j] * vb[j].1 + im[j] * vb[j].0;
                }
                ra[i] = xa;
                rb[i] = xb;
            }
            // Y = Aᴴ R A, G = Aᴴ A = [[M, g], [g*, M]], G⁻¹ = [[M, -g], [-g*, M]] / det.
            let (yaa, ybb, yab) = (dot(&va, &ra).0, dot(&vb, &rb).0, dot(&va, &rb));
            let det = mf * mf - g2;
            // The noise power per dimension the fit leaves (see `multiple_coherence`).
            let trace: f64 = (0..m).map(|i| self.re[cov + i * m + i]).sum();
            let fitted = (mf * (yaa + ybb) - 2.0 * (g.0 * yab.0 + g.1 * yab.1)) / det;
            let noise = ((trace - fitted) / (mf - 2.0)).max(0.0);
            // S = G⁻¹ Y G⁻¹ - σ² G⁻¹, with H = det G⁻¹: S = (H Y H) / det² - σ² H / det.
            let h = [[(mf, 0.0), (-g.0, -g.1)], [(-g.0, g.1), (mf, 0.0)]];
            let y = [[(yaa, 0.0), yab], [(yab.0, -yab.1), (ybb, 0.0)]];
            let mul = |x: (f64, f64), z: (f64, f64)| (x.0 * z.0 - x.1 * z.1, x.0 * z.1 + x.1 * z.0);
            let hy = |i: usize, j: usize| {
                let (p, q) = (mul(h[i][0], y[0][j]), mul(h[i][1], y[1][j]));
                (p.0 + q.0, p.1 + q.1)
            };
            let s = |i: usize, j: usize| {
                let (p, q) = (mul(hy(i, 0), h[0][j]), mul(hy(i, 1), h[1][j]));
                (
                    (p.0 + q.0) / (det * det) - noise * h[i][j].0 / det,
                    (p.1 + q.1) / (det * det) - noise * h[i][j].1 / det,
                )
            };
            let (saa, sbb, sab) = (s(0, 0).0, s(1, 1).0, s(0, 1));
            // A bin where either wave has no power of its own says nothing of the two.
            if saa <= 0.0 || sbb <= 0.0 {
                continue;
            }
            let gamma = ((sab.0 * sab.0 + sab.1 * sab.1) / (saa * sbb))
                .sqrt()
                .min(1.0);
            num += sbb * gamma;
            den += sbb;
        }
        (den > 0.0).then(|| num / den)
    }

    /// The multiple source coherence of direction `b` with the directions `others`, all
    /// fitted at once: how much of the signal heard from `b` the signals heard from the
    /// others explain (in `[0, 1]`; the square root of the share of `b`'s fitted power
    /// that a linear combination of theirs accounts for, per bin, averaged over the band
    /// weighted by that power). Fitting them together keeps a third source's leakage out
    /// of the pair's: with two waves alone, each takes part of an unmodelled source and
    /// they look coherent through it. `None` as for
    /// [`SpatialCovariance::source_coherence`], or when the waves are as many as the
    /// microphones less one (the fit would leave no dimension to measure the noise in).
    pub fn multiple_coherence(
        &self,
        positions: &[[f64; 3]],
        fs: f64,
        frame_len: usize,
        c: f64,
        others: &[[f64; 3]],
        b: [f64; 3],
    ) -> Option<f64> {
        let m = self.m;
        debug_assert_eq!(positions.len(), m);
        let k = others.len() + 1;
        if others.is_empty() || k + 1 > m {
            return None;
        }
        let waves: Vec<Vec<f64>> = others
            .iter()
            .chain(std::iter::once(&b))
            .map(|&u| leads(positions, u, c))
            .collect();
        let (mut num, mut den) = (0.0f64, 0.0f64);
        let mf = m as f64;
        for (kb, bin) in self.bins.clone().enumerate() {
            let w = angular_frequency(bin, frame_len, fs);
            let Some((steer, gi)) = resolved_steering(m, w, &waves) else {
                continue;
            };
            let r = DMatrix::from_fn(m, m, |i, j| {
                let at = kb * m * m + i * m + j;
                Complex::new(self.re[at], self.im[at])
            });
            let y = steer.adjoint() * &r * &steer;
            // The model's maximum-likelihood noise power: what the fit leaves of R, per
            // dimension left, `tr(P⊥ R) / (M - K)` with `tr(P R) = tr(G⁻¹ Y)`; the fitted
            // covariance without it, `S = G⁻¹ Y G⁻¹ - σ² G⁻¹` (white sensor noise would
            // otherwise count as signal of every wave, independent of the others).
            let fitted = (&gi * &y).trace().re;
            let noise = ((r.trace().re - fitted) / (mf - k as f64)).max(0.0);
            let sc = &gi * &y * &gi - &gi * Complex::new(noise, 0.0);
            let pb = sc[(k - 1, k - 1)].re;
            if pb <= 0.0 {
                continue;
            }
            // The share of b's power that the others' signals explain:
            // S_bO S_OO⁻¹ S_Ob / S_bb, S_OO inverted over its positive eigenvalues (a
            // wave the fit gives no power explains nothing).
            let soo = sc.view((0, 0), (k - 1, k - 1)).into_owned();
            let sob = sc.view((0, k - 1), (k - 1, 1)).into_owned();
            let eig = SymmetricEigen::new(soo);
            let scale = eig.eigenvalues.iter().copied().fold(0.0, f64::max);
            let explained: f64 = eig
                .eigenvalues
                .iter()
                .zip(eig.eigenvectors.column_iter())
                .filter(|(l, _)| **l > 1e-9 * scale)
                .map(|(l, u)| (u.adjoint() * &sob)[(0, 0)].norm_sqr() / l)
                .sum();
            if scale <= 0.0 {
                continue;
            }
            num += pb * (explained / pb).sqrt().min(1.0);
            den += pb;
        }
        (den > 0.0).then(|| num / den)
    }
}

/// A complex matrix.
pub(crate) type CMatrix = DMatrix<Complex<f64>>;

/// The steering matrix `A` (`m x K`, one column per wave) of waves whose microphone leads
/// (s) are `leads`, at angular frequency `w`, with the inverse of its Gram matrix `AᴴA`;
/// `None` where the array does not resolve the waves from each other: the Gram matrix's
/// smallest eigenvalue, per microphone, below `1 - MAX_STEERING_OVERLAP` (for two waves,
/// `|aᴴb| / M` above `MAX_STEERING_OVERLAP`). A microphone further along a wave's
/// direction hears it earlier: `X = S e^(i w lead)`.
pub(crate) fn resolved_steering(
    m: usize,
    w: f64,
    leads: &[Vec<f64>],
) -> Option<(CMatrix, CMatrix)> {
    let steer = DMatrix::from_fn(m, leads.len(), |i, j| {
        Complex::from_polar(1.0, w * leads[j][i])
    });
    let gram = steer.adjoint() * &steer;
    let lowest = SymmetricEigen::new(gram.clone())
        .eigenvalues
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    if lowest / (m as f64) < 1.0 - MAX_STEERING_OVERLAP {
        return None;
    }
    let gi = gram.try_inverse()?;
    Some((steer, gi))
}

/// Each microphone's lead (s) for a plane wave from direction `u` (a unit vector in the
/// array frame), microphones at `positions` (m), sound at `c` (m/s): a microphone further
/// along `u` hears the wave earlier, `X = S e^(i w lead)`.
pub(crate) fn leads(positions: &[[f64; 3]], u: [f64; 3], c: f64) -> Vec<f64> {
    positions
        .iter()
        .map(|p| (p[0] * u[0] + p[1] * u[1] + p[2] * u[2]) / c)
        .collect()
}

/// The angular frequency (rad/s) of FFT bin `bin` of a `frame_len`-sample frame at `fs` Hz.
pub(crate) fn angular_frequency(bin: usize, frame_len: usize, fs: f64) -> f64 {
    std::f64::consts::TAU * bin as f64 / frame_len as f64 * fs
}
