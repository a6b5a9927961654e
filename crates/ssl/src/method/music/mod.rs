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
//!    per group, sum `x x^H` over the block's frames and the group's bins (a row of up to
//!    eight microphones at a time, real and imaginary parts apart, so that the sums
//!    vectorise: half the time of the entry-by-entry complex sums, the same values).
//! 2. Eigen-decompose it; the signal subspace is the `K` largest eigenvectors: `K` fixed by
//!    [`crate::SslConfig::music_sources`], or estimated per group as the eigenvalues within
//!    10 dB of the largest, up to N. `|E_n^H a|^2 = |a|^2 - |E_s^H a|^2`, so each group
//!    projects on whichever subspace is smaller, `min(K, M - K)` vectors: with six
//!    microphones and N = 4, the groups that hold four sources project on two noise
//!    vectors, not four signal ones (measured: 1.2-1.3x faster per recording on the
//!    authors' recordings, DoAs within 0.005 degrees of the signal-subspace sums).
//! 3. For every direction, steer to the group's centre frequency (the phasors advance from
//!    group to group by one complex multiplication per microphone) and evaluate `P_b`;
//!    sum over groups (NormMUSIC: each group divided by its largest value first). MUSIC's
//!    `|E_n^H a|^2` is floored at the residual the group's snapshots leave a true source's
//!    steering vector (`Music::resolution`): no peak is sharper than its data resolve.
//!
//! A recording's blocks are evaluated together ([`SpectrumEstimator::estimate_blocks`]):
//! each block's projected-on vectors become the projector `Q = sum_v conj(e_v) e_v^T`, and
//! `sum_v |e_v^H a|^2 = tr Q + 2 Re sum_(i<j) Q_ij a_i conj(a_j)` for unit phasors. The
//! pair phasors `a_i conj(a_j)` depend on the direction and the group only, so they are
//! formed once per recording and each block costs `M (M - 1)` multiply-adds per direction
//! and group (30 for six microphones), where steering block by block cost `4 M` per
//! vector plus the phasor step. Measured on the authors' recordings (one thread, file read
//! included): NormMUSIC 45-52 -> 26-27 ms, MUSIC 42-46 -> 26 ms per recording; DoAs within
//! 0.004 degrees. When the grid holds every direction's antipode (an even number of
//! azimuths, elevations symmetric about 0: the default 3-D grid and the horizontal plane),
//! only half of it is steered: `-u` has the conjugate phasors of `u`, so the kernel's
//! real-part and imaginary-part sums give `u`'s value as their sum and `-u`'s as their
//! difference (measured, medians of 11 interleaved runs on the authors' recordings:
//! NormMUSIC 28.5 -> 22.5 ms, MUSIC 23.9 -> 18.8 ms per recording; DoAs within 0.0001
//! degrees). The coarse-to-fine search
//! ([`crate::SslConfig::music_coarse`]) still steers block by block.
//!
//! The octaves of [`crate::SslConfig::subband_votes`] are the band's own groups summed
//! apart ([`SpectrumEstimator::estimate_blocks_parts`]): each group's pseudo-spectrum is
//! added to its octave's sum instead of the band's, the band's is their total, and each
//! octave is read at its coarser grid's directions. An octave localizer of its own
//! decomposed the same covariances a second time: NormMUSIC and MUSIC took 22.5-23.3 and
//! 22.2-22.3 ms per recording of the authors' with the octaves, 18 without. The octaves'
//! groups are the band's, not a grid of their own from the octave's edge, and each weighs
//! its share of the band's groups (the votes and peaks are the same under a constant
//! factor).

use std::ops::Range;

use nalgebra::{Complex, DMatrix};
use realfft::num_complex::Complex32;

use crate::array::MicArray;
use crate::grid::DirectionGrid;
use crate::method::{MethodScratch, SpectrumEstimator, each_block, zeroed};
use crate::stft::Spectrogram;

mod coarse;
mod kernel;
mod subspace;
#[cfg(test)]
mod tests;

use coarse::Coarse;
pub(crate) use kernel::covariance;
use kernel::*;

/// The smallest value of `|E_n^H a|^2 / |a|^2` used: it bounds one bin's peak at `1e5`
/// times its floor, far above the precision of `f32` sums of a few terms, so that a
/// noise-free bin cannot make an infinite peak. MUSIC floors each group higher, where its
/// snapshots resolve less ([`Music::resolution`]).
const FLOOR: f32 = 1e-5;

/// With the subspace dimension estimated, a group's signal subspace holds the eigenvectors
/// whose eigenvalue is at least this fraction of the largest (up to the cap): a source up to
/// 10 dB weaker than the group's strongest still counts as one.
const EIG_RATIO: f32 = 0.1;

/// MUSIC (unnormalised) with the subspace dimension estimated: a signal eigenvalue must
/// also stand this far above the group's noise floor, the smallest eigenvalue its
/// snapshots can resolve; a group with none holds no source and adds the same to every
/// direction. 10 dB, as [`EIG_RATIO`].
///
/// Why for MUSIC: its groups are summed unnormalised, and in a group that holds only noise
/// the eigenvalues lie close together, so [`EIG_RATIO`] alone takes N of them for signal
/// and leaves a noise subspace whose pseudo-spectrum spikes at random directions as high
/// as a source's; those groups decide the sum. NormMUSIC, each group scaled to a peak of
/// one, shrugs them off.
const FLOOR_RATIO: f32 = 10.0;

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
    /// The coarse-to-fine plan, when the grid is searched so (see [`Music::coarse_search`]).
    coarse: Option<Coarse>,
    /// Half the grid, when the grid holds every direction's antipode ([`Antipodes`]).
    antipodes: Option<Antipodes>,
}

/// Half of a grid whose every direction's antipode is also in it, and the steering tables
/// of that half ([`Tables`]' layout).
///
/// The antipode `-u` of a direction `u` has the conjugate steering phasors at every
/// frequency, so its pair phasors are `conj(a_i conj(a_j))` and its pair sum is
/// `tr Q + 2 Re(Q) Re(g) + 2 Im(Q) Im(g)` where `u`'s is `tr Q + 2 Re(Q) Re(g) - 2 Im(Q)
/// Im(g)`: the pair kernel's two sums give both directions ([`Music::all_blocks`]). A grid
/// is symmetric so when its azimuth count is even and its elevations are symmetric about 0
/// (the default `-60..60`, and the horizontal plane).
#[derive(Clone, Debug)]
struct Antipodes {
    /// The grid direction of each output slot: the steered half, then their antipodes in
    /// the same order.
    order: Vec<usize>,
    /// Its inverse: the output slot of each grid direction.
    slot_of: Vec<usize>,
    start_re: Vec<f32>,
    start_im: Vec<f32>,
    step_re: Vec<f32>,
    step_im: Vec<f32>,
}

/// Working memory of the subspace estimators (part of [`crate::method::MethodScratch`]).
#[derive(Clone, Debug, Default)]
pub(crate) struct SubspaceScratch {
    /// One chunk's steering phasors being advanced, per microphone and lane.
    a_re: Vec<f32>,
    a_im: Vec<f32>,
    /// Per group and direction, `|E^H a|^2`, then the group's pseudo-spectrum.
    proj: Vec<f32>,
    /// The same for the directions refined by the coarse-to-fine search.
    proj_fine: Vec<f32>,
    /// Those directions, a mark per grid direction, and their steering tables.
    fine_dirs: Vec<usize>,
    fine_mark: Vec<bool>,
    fine_tables: [Vec<f32>; 4],
    /// Per coarse direction, the summed spectrum; per refined direction, the same.
    coarse_sum: Vec<f32>,
    fine_sum: Vec<f32>,
    /// The coarse spectrum interpolated along azimuth, per coarse elevation.
    rows: Vec<f32>,
    /// The coarse spectrum's local maxima: value, coarse elevation, coarse azimuth.
    peaks: Vec<(f32, usize, usize)>,
    /// The projected-on eigenvectors of every group: group-major, then vector, then mic.
    vec_re: Vec<f32>,
    vec_im: Vec<f32>,
    /// Per group: how many of its vector slots are used, and whether they span the signal
    /// subspace (else the noise subspace).
    used: Vec<usize>,
    signal: Vec<bool>,
    /// Per group, the least `|E_n^H a|^2 / |a|^2` its pseudo-spectrum takes
    /// ([`Music::resolution`]).
    floor: Vec<f32>,
    /// The blocks of a recording at once ([`Music::all_blocks`]): per group and block, the
    /// projector's trace and pair terms, and how its projections become the group's
    /// pseudo-spectrum.
    terms: Vec<f32>,
    pseudo: Vec<Pseudo>,
    /// Per direction chunk and microphone, the steering phasors at the current group.
    cur_re: Vec<f32>,
    cur_im: Vec<f32>,
    /// One chunk's pair phasors `a_i conj(a_j)`, per pair and lane.
    g_re: Vec<f32>,
    g_im: Vec<f32>,
    /// Per block, the spectrum being summed over groups.
    outs: Vec<f32>,
    /// The same for each part of the band ([`Music::estimate_blocks_parts`]), part-major,
    /// and how many blocks and parts they hold.
    part_sums: Vec<f32>,
    part_blocks: usize,
    part_count: usize,
}

/// MUSIC's own settings: the signal subspace's dimension (`sources`; `None`: estimated
/// per group of bins, at most `max_sources`), the bins each side of a group's centre whose
/// covariances are pooled (`smoothing`), and whether each group's pseudo-spectrum is
/// normalised to a peak of one (NormMUSIC).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Subspace {
    pub sources: Option<usize>,
    pub max_sources: usize,
    pub smoothing: usize,
    pub normalise: bool,
}

impl Music {
    /// Plans the estimator. `bins` are the band's bins of a `frame_len`-point FFT at `fs`.
    pub(crate) fn new(
        array: &MicArray,
        grid: &DirectionGrid,
        fs: f64,
        c: f64,
        bins: Range<usize>,
        frame_len: usize,
        subspace: Subspace,
    ) -> Self {
        let Subspace {
            sources,
            max_sources,
            smoothing,
            normalise,
        } = subspace;
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
        let leads = super::steering_leads(array, grid, c, fs);
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
            for (m, &lead) in leads[d * mics..(d + 1) * mics].iter().enumerate() {
                let i = ((d / W) * mics + m) * W + d % W;
                (start_re[i], start_im[i]) = ((w0 * lead).cos() as f32, (w0 * lead).sin() as f32);
                (step_re[i], step_im[i]) = ((dw * lead).cos() as f32, (dw * lead).sin() as f32);
            }
        }
        let mut music = Self {
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
            coarse: None,
            antipodes: None,
        };
        music.antipodes = music.antipodes(grid);
        music
    }

    /// The steered half of `grid` and the antipodes of its directions, if the grid holds
    /// them ([`DirectionGrid::antipodal_half`]).
    fn antipodes(&self, grid: &DirectionGrid) -> Option<Antipodes> {
        let (half, anti) = grid.antipodal_half()?;
        let mut tables: [Vec<f32>; 4] = Default::default();
        self.gather_into(&half, &mut tables);
        let [start_re, start_im, step_re, step_im] = tables;
        let order: Vec<usize> = half.into_iter().chain(anti).collect();
        let mut slot_of = vec![0; order.len()];
        for (slot, &d) in order.iter().enumerate() {
            slot_of[d] = slot;
        }
        Some(Antipodes {
            order,
            slot_of,
            start_re,
            start_im,
            step_re,
            step_im,
        })
    }

    /// The steering tables of directions `dirs` (in that order), chunk-major, into `out`.
    fn gather_into(&self, dirs: &[usize], out: &mut [Vec<f32>; 4]) {
        let m = self.mics;
        let len = dirs.len().div_ceil(W) * W * m;
        let src = [&self.start_re, &self.start_im, &self.step_re, &self.step_im];
        for (o, t) in out.iter_mut().zip(src) {
            let o = zeroed(o, len);
            for (j, &d) in dirs.iter().enumerate() {
                for mic in 0..m {
                    o[((j / W) * m + mic) * W + j % W] = t[((d / W) * m + mic) * W + d % W];
                }
            }
        }
    }

    /// The signal-subspace dimension in use: fixed, or `None` when estimated per group
    /// (up to [`crate::SslConfig::num_peaks`]).
    pub fn sources(&self) -> Option<usize> {
        (!self.estimate).then_some(self.sources)
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
        scratch: &mut MethodScratch,
    ) {
        self.check_plan(stft);
        assert_eq!(out.len(), self.n_dirs, "one value per direction");
        let s = &mut scratch.subspace;
        let dim = self.subspaces(stft, frames, s);
        match &self.coarse {
            None => self.exhaustive(dim, out, s),
            Some(c) => self.coarse_to_fine(c, dim, out, s),
        }
    }

    fn estimate_blocks(
        &self,
        stft: &Spectrogram,
        blocks: &[Range<usize>],
        block: &mut [f32],
        scratch: &mut MethodScratch,
        sink: &mut dyn FnMut(usize, &[f32]),
    ) {
        if self.coarse.is_some() || blocks.len() < 2 {
            return each_block(self, stft, blocks, block, scratch, sink);
        }
        self.check_plan(stft);
        self.all_blocks(stft, blocks, block, &mut scratch.subspace, sink, None);
    }

    fn estimates_parts(&self) -> bool {
        self.coarse.is_none()
    }

    /// Each part holds the band's groups whose centre bin lies in it, each weighted as in
    /// the band's sum: a part's spectrum is what a plan of those groups alone gives, times
    /// their share of the band's groups. The groups' decompositions and steering are the
    /// band's own: each group's pseudo-spectrum is summed into its part's sum instead of
    /// the band's, and the band's is their total.
    fn estimate_blocks_parts(
        &self,
        stft: &Spectrogram,
        blocks: &[Range<usize>],
        parts: &[Range<usize>],
        block: &mut [f32],
        scratch: &mut MethodScratch,
        sink: &mut dyn FnMut(usize, &[f32]),
    ) -> bool {
        if !self.estimates_parts() {
            self.estimate_blocks(stft, blocks, block, scratch, sink);
            return false;
        }
        self.check_plan(stft);
        let part_of: Vec<usize> = self
            .centres
            .iter()
            .map(|c| parts.iter().position(|r| r.contains(c)).unwrap_or(NO_PART))
            .collect();
        let split = Split {
            part_of: &part_of,
            parts: parts.len(),
        };
        self.all_blocks(
            stft,
            blocks,
            block,
            &mut scratch.subspace,
            sink,
            Some(split),
        );
        true
    }

    fn part_spectra(
        &self,
        part: usize,
        dirs: &[usize],
        scratch: &mut MethodScratch,
        out: &mut Vec<f32>,
    ) {
        let s = &scratch.subspace;
        let (nd, nb) = (self.n_dirs, s.part_blocks);
        assert!(part < s.part_count, "part {part} was not kept");
        // The sums are in the steered order ([`Antipodes`]).
        let slot = |d: usize| self.antipodes.as_ref().map_or(d, |h| h.slot_of[d]);
        let sums = &s.part_sums[part * nb * nd..(part + 1) * nb * nd];
        let out = zeroed(out, nb * dirs.len());
        for (row, out) in sums.chunks_exact(nd).zip(out.chunks_exact_mut(dirs.len())) {
            for (o, &d) in out.iter_mut().zip(dirs) {
                *o = row[slot(d)];
            }
        }
    }
}

/// A group in no part ([`Split`]).
const NO_PART: usize = usize::MAX;

/// The parts of the band [`Music::all_blocks`] also sums apart
/// ([`SpectrumEstimator::estimate_blocks_parts`]).
struct Split<'a> {
    /// Per group, its part, or [`NO_PART`].
    part_of: &'a [usize],
    parts: usize,
}

/// The directions [`Music::all_blocks`] steers: the steering tables (start and step,
/// real and imaginary), the order of the grid's directions in a row of its output when
/// only half the grid is steered (the steered half, then their antipodes), the padded
/// length of the steered directions, the ranges of a row that hold values, and a row's
/// length.
struct Steered<'a> {
    tables: [&'a Vec<f32>; 4],
    order: Option<&'a Vec<usize>>,
    n_pad: usize,
    segs: [Range<usize>; 2],
    row: usize,
}

impl Music {
    /// Each block's projector `Q = sum_v conj(e_v) e_v^T` on each group's projected-on
    /// vectors, as the pair kernel takes it: into `s.terms` (group-major, then block) its
    /// trace and, per microphone pair `i < j`, `2 Re Q_ij` and `-2 Im Q_ij`; into
    /// `s.pseudo` how each becomes the group's pseudo-spectrum. Returns the terms per
    /// projector, `1 + M (M - 1)`.
    fn projectors(
        &self,
        stft: &Spectrogram,
        blocks: &[Range<usize>],
        s: &mut SubspaceScratch,
    ) -> usize {
        let (m, ng, nb) = (self.mics, self.centres.len(), blocks.len());
        let stride = 1 + m * (m - 1);
        zeroed(&mut s.terms, ng * nb * stride);
        s.pseudo.clear();
        s.pseudo.resize(ng * nb, Pseudo::FLAT);
        for (b, frames) in blocks.iter().enumerate() {
            let dim = self.subspaces(stft, frames.clone(), s);
            for k in 0..ng {
                let t = &mut s.terms[(k * nb + b) * stride..(k * nb + b + 1) * stride];
                for v in 0..s.used[k] {
                    let e = (k * dim + v) * m;
                    let (er, ei) = (&s.vec_re[e..e + m], &s.vec_im[e..e + m]);
                    t[0] += (0..m).map(|i| er[i] * er[i] + ei[i] * ei[i]).sum::<f32>();
                    let mut p = 0;
                    for i in 0..m {
                        for j in i + 1..m {
                            // Q_ij = conj(e_i) e_j; its pair term 2 Re(Q_ij g) with
                            // g = a_i conj(a_j) is 2 Re(Q) Re(g) - 2 Im(Q) Im(g).
                            t[1 + 2 * p] += 2.0 * (er[i] * er[j] + ei[i] * ei[j]);
                            t[2 + 2 * p] -= 2.0 * (er[i] * ei[j] - ei[i] * er[j]);
                            p += 1;
                        }
                    }
                }
                s.pseudo[k * nb + b] = Pseudo::new(s.signal[k], m, s.floor[k]);
            }
        }
        stride
    }

    /// Which directions [`Music::all_blocks`] steers, and where their values lie.
    fn steered(&self) -> Steered<'_> {
        let nd = self.n_dirs;
        match &self.antipodes {
            // Half the directions, each row of `xs` holding the steered half and (from
            // `n_pad` on) their antipodes.
            Some(h) => {
                let n_steer = nd / 2;
                let n_pad = n_steer.div_ceil(W) * W;
                Steered {
                    tables: [&h.start_re, &h.start_im, &h.step_re, &h.step_im],
                    order: Some(&h.order),
                    n_pad,
                    segs: [0..n_steer, n_pad..n_pad + n_steer],
                    row: 2 * n_pad,
                }
            }
            None => {
                let n_pad = nd.div_ceil(W) * W;
                Steered {
                    tables: [&self.start_re, &self.start_im, &self.step_re, &self.step_im],
                    order: None,
                    n_pad,
                    segs: [0..nd, 0..0],
                    row: n_pad,
                }
            }
        }
    }

    /// Every block's spectrum of the full search at once: per block and group, the
    /// projector `Q = sum_v conj(e_v) e_v^T` of the projected-on vectors, so that
    /// `sum_v |e_v^H a|^2 = a^T Q conj(a) = tr Q + 2 Re sum_(i<j) Q_ij a_i conj(a_j)` (unit
    /// phasors); then, per group and chunk of directions, the pair phasors
    /// `a_i conj(a_j)` are formed once and serve every block. Per direction, group and
    /// block that is `M (M - 1)` multiply-adds against the `4 M` per vector of
    /// [`steer_all`] plus its phasor step: the step and the pair products are paid once
    /// per recording, not once per block.
    fn all_blocks(
        &self,
        stft: &Spectrogram,
        blocks: &[Range<usize>],
        block: &mut [f32],
        s: &mut SubspaceScratch,
        sink: &mut dyn FnMut(usize, &[f32]),
        split: Option<Split<'_>>,
    ) {
        let (m, ng, nb, nd) = (self.mics, self.centres.len(), blocks.len(), self.n_dirs);
        let np = m * (m - 1) / 2;
        let stride = self.projectors(stft, blocks, s);
        let SubspaceScratch {
            terms,
            pseudo,
            cur_re,
            cur_im,
            g_re,
            g_im,
            outs,
            proj,
            part_sums,
            part_blocks,
            part_count,
            ..
        } = s;
        let Steered {
            tables,
            order,
            n_pad,
            segs,
            row,
        } = self.steered();
        cur_re.clear();
        cur_re.extend_from_slice(tables[0]);
        cur_im.clear();
        cur_im.extend_from_slice(tables[1]);
        let g_re = zeroed(g_re, np * W);
        let g_im = zeroed(g_im, np * W);
        let xs = zeroed(proj, nb * row);
        let outs = zeroed(outs, nb * nd);
        // The parts' sums, in the steered order as `outs`, each group's in its part's (a
        // pass without parts leaves the last ones as they are).
        let n_parts = split.as_ref().map_or(0, |p| p.parts);
        if split.is_some() {
            zeroed(part_sums, n_parts * nb * nd);
            (*part_blocks, *part_count) = (nb, n_parts);
        }
        for k in 0..ng {
            let kernel = PairKernel {
                terms: &terms[k * nb * stride..(k + 1) * nb * stride],
                mics: m,
                blocks: nb,
                step: (k + 1 < ng).then_some((&tables[2][..], &tables[3][..])),
                antipodes: order.is_some().then_some(n_pad),
            };
            kernel.run(cur_re, cur_im, g_re, g_im, xs);
            let scale = |top: f32| self.group_scale(top);
            let target = match &split {
                Some(p) if p.part_of[k] != NO_PART => {
                    let at = p.part_of[k] * nb * nd;
                    &mut part_sums[at..at + nb * nd]
                }
                _ => &mut *outs,
            };
            accumulate(xs, &segs, target, &pseudo[k * nb..(k + 1) * nb], &scale);
        }
        if split.is_some() {
            // The band's sum is its parts' and the rest's.
            for part in part_sums.chunks_exact(nb * nd) {
                outs.iter_mut().zip(part).for_each(|(o, v)| *o += v);
            }
        }
        deliver(outs, nd, order, block, sink);
    }
}

/// Hands each block's spectrum in `outs` (`nd` values per block, in the steered `order`
/// when only half the grid was steered) to `sink` in the grid's order, through `block`.
fn deliver(
    outs: &[f32],
    nd: usize,
    order: Option<&Vec<usize>>,
    block: &mut [f32],
    sink: &mut dyn FnMut(usize, &[f32]),
) {
    for (b, o) in outs.chunks_exact(nd).enumerate() {
        match order {
            Some(order) => {
                for (&d, &v) in order.iter().zip(o) {
                    block[d] = v;
                }
                sink(b, block);
            }
            None => sink(b, o),
        }
    }
}

impl Music {
    /// Every group's pseudo-spectrum `1 / |E_n^H a|^2` (floored) on the `n` directions of
    /// `tables`, into `proj` (group-major, each group padded to whole chunks), from the
    /// groups' vectors of [`Music::subspaces`].
    fn pseudo(
        &self,
        tables: &Tables,
        n: usize,
        sub: &Subspaces,
        a: (&mut Vec<f32>, &mut Vec<f32>),
        proj: &mut Vec<f32>,
    ) -> usize {
        let (m, ng) = (self.mics, self.centres.len());
        let n_pad = n.div_ceil(W) * W;
        let a_re = zeroed(a.0, m * W);
        let a_im = zeroed(a.1, m * W);
        let proj = zeroed(proj, ng * n_pad);
        steer_all(tables, sub, m, ng, a_re, a_im, proj);
        // Branch-free within a group, so that the loop runs on whole vectors.
        for ((p, &signal), &floor) in proj.chunks_exact_mut(n_pad).zip(sub.signal).zip(sub.floor) {
            let Pseudo { a0, a1, floor } = Pseudo::new(signal, m, floor);
            for v in p.iter_mut() {
                *v = 1.0 / (a0 + a1 * *v).max(floor);
            }
        }
        n_pad
    }

    /// `out` = the sum over groups of the first `n` values of each group's pseudo-spectrum
    /// in `proj` (groups `n_pad` apart), each scaled by [`Music::group_scale`] of its own
    /// largest.
    fn sum_groups(&self, proj: &[f32], n_pad: usize, n: usize, out: &mut [f32]) {
        out.fill(0.0);
        for p in proj.chunks_exact(n_pad) {
            let p = &p[..n];
            let scale = self.group_scale(p.iter().copied().fold(0.0, f32::max));
            for (o, v) in out.iter_mut().zip(p) {
                *o += v * scale;
            }
        }
    }

    /// Panics unless `stft` has the band and the channel count the plan was made for.
    fn check_plan(&self, stft: &Spectrogram) {
        assert_eq!(
            stft.bins().len(),
            self.n_bins,
            "spectrogram band differs from the plan"
        );
        assert_eq!(stft.num_channels(), self.mics, "one channel per microphone");
    }

    /// A group's weight in the sum: NormMUSIC divides by its largest value (`max`).
    fn group_scale(&self, max: f32) -> f32 {
        let norm = 1.0 / self.centres.len() as f32;
        if self.normalise {
            norm / max.max(f32::MIN_POSITIVE)
        } else {
            norm * FLOOR
        }
    }

    /// Every direction of the grid steered.
    fn exhaustive(&self, dim: usize, out: &mut [f32], s: &mut SubspaceScratch) {
        let nd = self.n_dirs;
        let tables = Tables {
            start_re: &self.start_re,
            start_im: &self.start_im,
            step_re: &self.step_re,
            step_im: &self.step_im,
        };
        let SubspaceScratch {
            a_re,
            a_im,
            proj,
            vec_re,
            vec_im,
            used,
            signal,
            floor,
            ..
        } = s;
        let sub = Subspaces {
            re: vec_re,
            im: vec_im,
            stride: dim,
            used,
            signal,
            floor,
        };
        let nd_pad = self.pseudo(&tables, nd, &sub, (a_re, a_im), proj);
        self.sum_groups(proj, nd_pad, nd, out);
    }
}
