//! TOPS, CSSM and WAVES: wideband subspace methods that combine the band's bins coherently.
//!
//! MUSIC and NormMUSIC ([`super::music`]) decompose each bin's covariance apart and add the
//! bins' pseudo-spectra: *incoherently*. A bin's covariance needs well over `M` snapshots
//! before its noise subspace means anything, and a reverberant room gives few independent
//! ones. The three methods of this module carry what every bin knows to one reference
//! bin first, so that the whole band's snapshots build one estimate:
//!
//! - **CSSM** (coherent signal-subspace method; Wang & Kaveh 1985) *focuses* each bin's
//!   covariance `R_b` onto the reference bin `b0` by a matrix `T_b` that maps the steering
//!   vectors of preliminary directions at `b` onto theirs at `b0`, sums `T_b R_b T_b^H`,
//!   and runs MUSIC on the sum at `b0` (pyroomacoustics then takes its peaks as the next
//!   preliminary directions; here it is done once, see below).
//! - **WAVES** (weighted average of signal subspaces; di Claudio & Parisi 2001) focuses each
//!   bin's signal subspace instead, each eigenvector weighted by its eigenvalue's excess
//!   over the noise, `(lambda - sigma^2) / sqrt(lambda sigma^2)`, so that a bin counts by
//!   its signal-to-noise ratio rather than its power; MUSIC then runs on the weighted
//!   vectors' span (the left singular vectors of `Z = [T_b E_b P_b]`, the eigenvectors of
//!   `Z Z^H`).
//! - **TOPS** (test of orthogonality of projected subspaces; Yoon, Kaplan & McClellan
//!   2006) needs no preliminary directions: the reference bin's signal subspace `F_0`,
//!   carried to bin `b` along a direction `u` (`Phi_b(u) = diag(a_b(u) / a_0(u))`; the
//!   paper also projects it off `a_b(u)`, left out here, see below), holds one and the
//!   same combination orthogonal to every bin's noise subspace `W_b` only when `u` is a
//!   source's direction (it is then `a_b(u)`); the spectrum is `1 / sigma_min(D(u))`, `D`
//!   the `K x B (M - K)` matrix of every bin's `U_b^H W_b`, which then loses rank.
//!
//! **TOPS's cost.** Written out, `D(u)` holds `B (M - K)` columns of `K` entries, each `M`
//! multiply-adds, per direction. Since every steering entry has unit modulus,
//! `U_b^H W_b = C(u)^H diag(conj a_b(u)) W_b` with `C(u) = diag(conj a_0(u)) F_0` the same
//! for every bin, so `D D^H = C^H S C` with `S_ij(u) = sum_b Pi_b,ij conj(a_b,i(u))
//! a_b,j(u)`, `Pi_b = W_b W_b^H`: per direction and bin one complex multiply-add per
//! microphone pair (the pair-phasor sum of MUSIC's kernel), and one `K x K` eigenvalue,
//! `sigma_min(D)^2`, per direction; and since the antipode `-u` has the conjugate
//! phasors, the same sums give both where the grid holds every antipode. The test
//! `tops_is_its_definition_written_out` checks the two against each other.
//!
//! **One spectrum per recording.** Each is defined on sample covariances over every
//! snapshot (as pyroomacoustics computes them), and a 4-frame block would leave a bin's
//! covariance of rank 4 on six microphones, its "noise" subspace partly the snapshots
//! missing. The localizer makes one block of the recording for them
//! ([`crate::SpectrumEstimator::whole_recording`]), whatever
//! [`crate::SslConfig::block_frames`] says.
//!
//! **The subspace dimension** `K` is [`crate::SslConfig::music_sources`] when set, else
//! [`crate::SslConfig::num_peaks`] (at most one less than the microphones), as
//! pyroomacoustics' `num_src`: one spectrum of a whole recording holds every source that
//! sounded in it, not the one or two of a short block that MUSIC's per-group estimate
//! looks for. Measured on arrangement II (first 4 DoAs within 5 degrees, poses' frame):
//! TOPS 0.475 with MUSIC's 10-dB estimate, 0.537 with K = 4.
//!
//! Where each departs from the papers' letter, and why (arrangement II, same score):
//!
//! - **TOPS's reference bin** is the band's loudest (largest covariance trace), as Yoon et
//!   al. advise (the highest signal-to-noise ratio) and pyroomacoustics does. TOPS's
//!   `D(u)` is tested **without the projection** `P_b(u) = I - a_b a_b^H / M`, as
//!   pyroomacoustics tests it: with it 0.237, without 0.525 (pyroomacoustics 0.500).
//!   Both vanish at a source's direction; but the loudest bin of speech lies low, where
//!   every direction's steering vector lies nearly in the signal subspace, and the
//!   projection then removes most of what tells directions apart.
//! - **CSSM's and WAVES's reference bin** is where the focused covariance is searched, by
//!   MUSIC at that one frequency: the highest at which the array samples every direction
//!   without spatial aliasing, `c / (2 d)` for its closest pair `d` apart (1.42 kHz for
//!   the paper's array). Lower, the single-frequency peaks are broad; higher, they have
//!   grating lobes. The loudest bin (pyroomacoustics) gave 0.175 / 0.194 there, `c / 2d`
//!   0.319 / 0.419.
//! - **Their focusing** is unitary (the rotational signal subspace of Hung & Kaveh 1988,
//!   the orthogonal Procrustes solution), not Wang & Kaveh's first `[A_0 B][A_b B]^-1`:
//!   the latter amplifies every bin's noise where its directions' first rows are nearly
//!   singular (at the same reference, five iterations: 0.206 / 0.200 against 0.287 /
//!   0.250).
//! - **Their preliminary directions** are the `K` strongest peaks of SRP-PHAT
//!   ([`super::srp_phat`], the whitened beamformer over the whole band) over the
//!   recording's blocks of [`crate::SslConfig::block_frames`], max-pooled: each talker's
//!   best moment, as the blockwise methods pool. pyroomacoustics takes each bin's
//!   beamformer peaks instead. And the focusing is done **once**: iterating on the focused
//!   spectrum's own peaks (pyroomacoustics: five times) replaces those directions by a
//!   single frequency's, and the score falls (one pass 0.319 / 0.419, two 0.256 / 0.312,
//!   five 0.231 / 0.300).

use std::ops::Range;
use std::sync::Arc;

use nalgebra::{Complex, DMatrix, SymmetricEigen};
use realfft::num_complex::Complex32;

use crate::array::MicArray;
use crate::grid::{DirectionGrid, PairLags};
use crate::method::srp_phat::SrpPhat;
use crate::method::{MethodScratch, SpectrumEstimator};
use crate::stft::Spectrogram;

#[cfg(test)]
mod tests;
mod tops;

pub use tops::Tops;

pub(crate) type C64 = Complex<f64>;
pub(crate) type Mat = DMatrix<C64>;

/// The least value of MUSIC's `a^H Pi a / M` used at the reference bin: it bounds a peak
/// at `1e6` times the floor, so that a noise-free recording makes no infinite peak.
const FLOOR: f64 = 1e-6;

/// What the three methods share: the steering of every direction at every band bin, the
/// grid's shape, the subspace dimension.
#[derive(Clone, Debug)]
pub(crate) struct Plan {
    mics: usize,
    /// Per direction and microphone, its lead over the array's centroid (samples): at bin
    /// `k` of the FFT the steering entry is `exp(i 2 pi k lead / frame_len)`.
    leads: Vec<f64>,
    n_az: usize,
    n_el: usize,
    /// The band's first FFT bin, its bin count, and the FFT length.
    bin0: usize,
    n_bins: usize,
    frame_len: usize,
    /// The signal subspace's dimension `K`.
    k: usize,
    /// CSSM's and WAVES's reference bin (band-relative): the one nearest `c / 2d`.
    focus_bin: usize,
    /// Peaks closer than this are one (degrees).
    min_sep_deg: f64,
}

/// The settings [`Plan::new`] takes beside the array and grid.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Band {
    pub fs: f64,
    pub c: f64,
    pub bins: (usize, usize),
    pub frame_len: usize,
    pub sources: Option<usize>,
    pub max_sources: usize,
    pub min_sep_deg: f64,
}

impl Plan {
    pub(crate) fn new(array: &MicArray, grid: &DirectionGrid, band: Band) -> Self {
        let mics = array.len();
        let pos = array.positions();
        let leads = super::steering_leads(array, grid, band.c, band.fs);
        let k = band
            .sources
            .unwrap_or(band.max_sources)
            .clamp(1, mics.saturating_sub(1).max(1));
        // The closest pair's spacing, and the band bin nearest c / 2d.
        let d_min = (0..mics)
            .flat_map(|i| (i + 1..mics).map(move |j| (i, j)))
            .map(|(i, j)| {
                (0..3)
                    .map(|a| (pos[i][a] - pos[j][a]).powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .fold(f64::INFINITY, f64::min);
        let n_bins = band.bins.1 - band.bins.0;
        let alias_bin = band.c / (2.0 * d_min) / band.fs * band.frame_len as f64;
        let focus_bin = (alias_bin.round().max(0.0) as usize)
            .saturating_sub(band.bins.0)
            .min(n_bins.saturating_sub(1));
        Self {
            mics,
            leads,
            n_az: grid.num_azimuths(),
            n_el: grid.elevations().len(),
            bin0: band.bins.0,
            n_bins,
            frame_len: band.frame_len,
            k,
            focus_bin,
            min_sep_deg: band.min_sep_deg,
        }
    }

    fn n_dirs(&self) -> usize {
        self.leads.len() / self.mics
    }

    /// Radians per sample of band bin `b`.
    fn omega(&self, b: usize) -> f64 {
        std::f64::consts::TAU * (self.bin0 + b) as f64 / self.frame_len as f64
    }

    /// Direction `d`'s steering vector at band bin `b`, into `out` (one entry per mic).
    fn steer(&self, d: usize, b: usize, out: &mut [C64]) {
        let w = self.omega(b);
        let leads = &self.leads[d * self.mics..(d + 1) * self.mics];
        for (o, &l) in out.iter_mut().zip(leads) {
            *o = C64::from_polar(1.0, w * l);
        }
    }

    /// Panics unless `stft` and `out` fit the plan.
    fn check(&self, stft: &Spectrogram, out: &[f32]) {
        assert_eq!(stft.bins().len(), self.n_bins, "spectrogram band differs");
        assert_eq!(stft.num_channels(), self.mics, "one channel per microphone");
        assert_eq!(out.len(), self.n_dirs(), "one value per direction");
    }

    /// Every band bin's sample covariance over `frames` (full Hermitian, `1 / T` of the sum
    /// of `x x^H`, less the robot's noise when known).
    fn covariances(&self, stft: &Spectrogram, frames: Range<usize>) -> Vec<Mat> {
        let m = self.mics;
        let t = frames.len().max(1) as f64;
        let mut cov = DMatrix::<Complex32>::zeros(m, m);
        (0..self.n_bins)
            .map(|b| {
                crate::method::music::covariance(stft, frames.clone(), b..b + 1, &mut cov);
                Mat::from_fn(m, m, |i, j| {
                    let v = if i <= j {
                        cov[(i, j)]
                    } else {
                        cov[(j, i)].conj()
                    };
                    C64::new(f64::from(v.re), f64::from(v.im)) / t
                })
            })
            .collect()
    }

    /// The loudest bin: the largest covariance trace.
    fn reference(covs: &[Mat]) -> usize {
        let power = |r: &Mat| r.diagonal().iter().map(|v| v.re).sum::<f64>();
        (0..covs.len())
            .max_by(|&a, &b| power(&covs[a]).total_cmp(&power(&covs[b])))
            .unwrap_or(0)
    }

    /// MUSIC at band bin `b` on every direction: `1 / max(a^H Pi a / M, FLOOR)`, `Pi` the
    /// noise subspace's projector.
    fn music(&self, pi: &Mat, b: usize, out: &mut [f32]) {
        let m = self.mics;
        let mut a = vec![C64::default(); m];
        for (d, o) in out.iter_mut().enumerate() {
            self.steer(d, b, &mut a);
            let mut q = 0.0;
            for i in 0..m {
                let row: C64 = (0..m).map(|j| pi[(i, j)] * a[j]).sum();
                q += (a[i].conj() * row).re;
            }
            *o = (1.0 / (q / m as f64).max(FLOOR)) as f32;
        }
    }

    /// The `k` strongest peaks of `values`' azimuth profile (each azimuth's largest value
    /// over elevations; local maxima, azimuth wrapping), at least [`Plan::min_sep_deg`]
    /// apart in azimuth, strongest first, each at its best elevation: how the localizer
    /// reads DoAs off a spectrum. A planar-ish array resolves elevation poorly, and peaks
    /// of the full grid would take one source at two elevations for two.
    fn peaks(&self, values: &[f32], k: usize) -> Vec<usize> {
        let na = self.n_az;
        let best: Vec<usize> = (0..na)
            .map(|a| {
                (0..self.n_el)
                    .map(|e| e * na + a)
                    .max_by(|&x, &y| values[x].total_cmp(&values[y]))
                    .expect("a grid has an elevation")
            })
            .collect();
        let v = |a: usize| values[best[a]];
        let mut cands: Vec<usize> = (0..na)
            .filter(|&a| v(a) >= v((a + na - 1) % na) && v(a) >= v((a + 1) % na))
            .collect();
        cands.sort_by(|&x, &y| v(y).total_cmp(&v(x)));
        let step = 360.0 / na as f64;
        let mut picked: Vec<usize> = Vec::with_capacity(k);
        for a in cands {
            if picked.len() == k {
                break;
            }
            let apart = picked.iter().all(|&p| {
                let d = (a as f64 - p as f64).abs() * step;
                d.min(360.0 - d) >= self.min_sep_deg
            });
            if apart {
                picked.push(a);
            }
        }
        picked.into_iter().map(|a| best[a]).collect()
    }
}

/// `r`'s eigenvalues, descending, and their eigenvectors as the columns in that order.
pub(crate) fn eigh_desc(r: &Mat) -> (Vec<f64>, Mat) {
    let eig = SymmetricEigen::new(r.clone());
    let mut order: Vec<usize> = (0..r.nrows()).collect();
    order.sort_by(|&x, &y| eig.eigenvalues[y].total_cmp(&eig.eigenvalues[x]));
    let vals = order.iter().map(|&i| eig.eigenvalues[i]).collect();
    let vecs = Mat::from_fn(r.nrows(), r.nrows(), |i, j| eig.eigenvectors[(i, order[j])]);
    (vals, vecs)
}

/// The projector onto the span of `vecs`' columns `from..`.
fn projector(vecs: &Mat, from: usize) -> Mat {
    let e = vecs.columns(from, vecs.ncols() - from);
    e * e.adjoint()
}

/// CSSM or WAVES for one array, grid, band and sample rate.
#[derive(Clone, Debug)]
pub struct Focused {
    plan: Plan,
    waves: bool,
    prelim: SrpPhat,
    block_frames: usize,
}

impl Focused {
    /// CSSM, or WAVES when `waves`; `lags` serve the preliminary SRP-PHAT spectrum, of
    /// blocks of `block_frames`.
    pub(crate) fn new(plan: Plan, lags: Arc<PairLags>, waves: bool, block_frames: usize) -> Self {
        Self {
            plan,
            waves,
            prelim: SrpPhat::new(lags),
            block_frames,
        }
    }

    /// The focusing matrix of band bin `b` onto `b0` for directions `beta`: the unitary
    /// `T` nearest to mapping each direction's steering vector at `b` onto its own at
    /// `b0` (the rotational signal subspace focusing of Hung & Kaveh 1988: `T = V U^H`
    /// for `A_b A_0^H = U S V^H`, the orthogonal Procrustes solution). Unitary, it keeps
    /// white noise white, so no bin's noise is amplified into the sum; the
    /// `[A_0 B] [A_b B]^-1` of Wang & Kaveh's first paper (and pyroomacoustics) is exact on
    /// the directions but amplifies whatever lies off them where `A_b`'s first rows are
    /// nearly singular. `None` without directions (the identity).
    pub(crate) fn focusing(&self, beta: &[usize], b: usize, b0: usize) -> Option<Mat> {
        if beta.is_empty() {
            return None;
        }
        let m = self.plan.mics;
        let (mut a0, mut ab) = (Mat::zeros(m, beta.len()), Mat::zeros(m, beta.len()));
        let mut col = vec![C64::default(); m];
        for (j, &d) in beta.iter().enumerate() {
            self.plan.steer(d, b0, &mut col);
            a0.column_mut(j).copy_from_slice(&col);
            self.plan.steer(d, b, &mut col);
            ab.column_mut(j).copy_from_slice(&col);
        }
        // T = V U^H for X = A_b A_0^H = U S V^H, from the eigenvectors of X^H X (V, S^2)
        // and of X X^H (U's columns beyond X's rank): nalgebra's complex SVD does not
        // always converge to a true decomposition (dimforge/nalgebra#1172), its Hermitian
        // eigensolver does.
        let x = &ab * a0.adjoint();
        let (s2, v) = eigh_desc(&(x.adjoint() * &x));
        let (_, u) = eigh_desc(&(&x * x.adjoint()));
        // Singular values below 1e-4 of the largest are taken for 0: their left vectors,
        // X v / s, would lose their orthogonality to rounding.
        let rank = s2.iter().take_while(|&&e| e > 1e-8 * s2[0]).count();
        let mut t = Mat::zeros(m, m);
        for (i, &e) in s2.iter().enumerate() {
            let ui = if i < rank {
                &x * v.column(i) / C64::new(e.sqrt(), 0.0)
            } else {
                u.column(i).into_owned()
            };
            t += v.column(i) * ui.adjoint();
        }
        Some(t)
    }

    /// CSSM's `sum_b T_b R_b T_b^H`, or WAVES's `Z Z^H = sum_b T_b E_b P_b^2 E_b^H T_b^H`.
    pub(crate) fn focused(&self, covs: &[Mat], beta: &[usize], b0: usize) -> Mat {
        let m = self.plan.mics;
        let mut sum = Mat::zeros(m, m);
        for (b, r) in covs.iter().enumerate() {
            let t = self
                .focusing(beta, b, b0)
                .unwrap_or_else(|| Mat::identity(m, m));
            if self.waves {
                let (vals, vecs) = eigh_desc(r);
                let k = self.plan.k;
                // The noise power: the mean of the noise eigenvalues.
                let sigma2 = (vals[k..].iter().sum::<f64>() / (m - k) as f64)
                    .max(1e-12 * vals[0].max(f64::MIN_POSITIVE));
                for (s, &lambda) in vals[..k].iter().enumerate() {
                    if lambda <= sigma2 {
                        continue;
                    }
                    let w = (lambda - sigma2).powi(2) / (lambda * sigma2);
                    let y = &t * vecs.column(s);
                    sum += (&y * y.adjoint()) * C64::new(w, 0.0);
                }
            } else {
                sum += &t * r * t.adjoint();
            }
        }
        sum
    }
}

impl SpectrumEstimator for Focused {
    fn name(&self) -> &'static str {
        if self.waves { "waves" } else { "cssm" }
    }

    fn whole_recording(&self) -> bool {
        true
    }

    fn estimate_into(
        &self,
        stft: &Spectrogram,
        frames: Range<usize>,
        out: &mut [f32],
        scratch: &mut MethodScratch,
    ) {
        let p = &self.plan;
        p.check(stft, out);
        let covs = p.covariances(stft, frames.clone());
        // The preliminary directions: SRP-PHAT's blocks, max-pooled.
        let per = self.block_frames.max(1);
        let blocks: Vec<Range<usize>> = frames
            .clone()
            .step_by(per)
            .map(|f| f..(f + per).min(frames.end))
            .collect();
        let mut block = vec![0.0f32; out.len()];
        out.fill(f32::MIN);
        self.prelim
            .estimate_blocks(stft, &blocks, &mut block, scratch, &mut |_, v| {
                out.iter_mut().zip(v).for_each(|(o, &x)| *o = o.max(x))
            });
        let beta = p.peaks(out, p.k);
        let r = self.focused(&covs, &beta, p.focus_bin);
        let (vals, vecs) = eigh_desc(&r);
        if vals[0] <= f64::MIN_POSITIVE {
            // Nothing heard: every direction alike.
            out.fill(1.0);
            return;
        }
        p.music(&projector(&vecs, p.k), p.focus_bin, out);
    }
}
