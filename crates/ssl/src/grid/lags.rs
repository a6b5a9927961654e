//! Each microphone pair's delay at each direction of the grid, sampled on lags: the
//! kernel of the pairwise methods.

use std::ops::Range;

use crate::array::MicArray;
use crate::grid::DirectionGrid;
use crate::method::{MethodScratch, SpectrumEstimator, zeroed};
use crate::stft::Spectrogram;

/// Every pair's delay function sampled on a uniform lag grid, with the tables to evaluate
/// a per-bin statistic at those lags and to read the result off at each direction.
///
/// Sampling each pair on lags instead of on directions is what makes the spectra cheap:
/// a pair needs only as many lags as its delay range spans, however many directions
/// (and elevations) the grid holds, and every direction reads its value by linear
/// interpolation between the two nearest lags.
///
/// That reading-off is a gather (each direction's lag index is its own), one per pair,
/// direction and block. It ran scalar and took 22 % of a GCC-PHAT run. A recording's
/// blocks therefore go [`TILE`] at a time ([`Pairwise`], [`LagTile`]): each direction's
/// lag index is read once per tile, and the tile's blocks are summed side by side in SIMD
/// lanes (same sums, same order: identical values). Measured on the authors' recordings
/// (one thread, median of 9 interleaved runs): GCC-PHAT 14.4 -> 12.6 ms, MVDR 19.8 -> 17.0
/// ms per recording on a slow day; tiles of 8 blocks were slower, and tiles of 32 no faster.
#[derive(Clone, Debug)]
pub(crate) struct PairLags {
    pub pairs: Vec<(usize, usize)>,
    /// Pair `p` is sampled at lags `(k - half[p]) * step` samples, `k in 0..=2 half[p]`.
    pub half: Vec<usize>,
    hmax: usize,
    /// Bins in the band, padded to whole [`LANES`] (table columns past the band are 0).
    pub n_bins: usize,
    /// `cos(w_b tau_j)` and `sin(w_b tau_j)`, row `hmax + j` for lag index `j`.
    cos: Vec<f32>,
    sin: Vec<f32>,
    /// Per pair and direction: the lower lag index and the interpolation weight of the upper.
    lookup: Vec<(u32, f32)>,
    n_dirs: usize,
    /// Where pair `p`'s `2 half[p]` lag segments start in a [`LagTile`]; the last entry is
    /// the total.
    seg_offset: Vec<usize>,
}

/// Blocks per [`LagTile`]: two AVX2 vectors per direction.
pub(crate) const TILE: usize = 16;

/// A pairwise method: what one block's spectrum is, written into a [`Target`]. Every
/// such method is a [`SpectrumEstimator`] alike: block by block it reads each pair's lag
/// function off at every direction, and for a recording's blocks it goes [`TILE`] blocks at
/// a time through a [`LagTile`].
pub(crate) trait Pairwise: Send + Sync {
    /// The method's short name ([`SpectrumEstimator::name`]).
    const NAME: &'static str;

    /// The lag grids the method was planned with.
    fn lags(&self) -> &PairLags;

    /// One block's spectrum (frames `frames` of `stft`) into `target`.
    fn spectrum(
        &self,
        stft: &Spectrogram,
        frames: Range<usize>,
        target: Target<'_>,
        scratch: &mut MethodScratch,
    );
}

impl<T: Pairwise> SpectrumEstimator for T {
    fn name(&self) -> &'static str {
        T::NAME
    }

    fn estimate_into(
        &self,
        stft: &Spectrogram,
        frames: Range<usize>,
        out: &mut [f32],
        scratch: &mut MethodScratch,
    ) {
        self.spectrum(stft, frames, Target::Directions(out), scratch);
    }

    fn estimate_blocks(
        &self,
        stft: &Spectrogram,
        blocks: &[Range<usize>],
        block: &mut [f32],
        scratch: &mut MethodScratch,
        sink: &mut dyn FnMut(usize, &[f32]),
    ) {
        let lags = self.lags();
        let mut tile = std::mem::take(&mut scratch.lag_tile);
        for (i, chunk) in blocks.chunks(TILE).enumerate() {
            let w = chunk.len();
            tile.reset(lags, w);
            for (slot, frames) in chunk.iter().enumerate() {
                self.spectrum(stft, frames.clone(), Target::Lags(&mut tile, slot), scratch);
            }
            lags.read_off_tile(&mut tile);
            for slot in 0..w {
                for (d, b) in block.iter_mut().enumerate() {
                    *b = tile.out[d * w + slot];
                }
                sink(i * TILE + slot, block);
            }
        }
        scratch.lag_tile = tile;
    }
}

/// Where [`PairLags::pairwise_spectrum`] puts a block's spectrum.
pub(crate) enum Target<'a> {
    /// Read off at every direction, into this slice (one value per direction).
    Directions(&'a mut [f32]),
    /// Each pair's lag segments, into this slot of a tile of blocks.
    Lags(&'a mut LagTile, usize),
}

/// The lag functions of a tile of blocks ([`Target::Lags`]), and their spectra.
#[derive(Clone, Debug, Default)]
pub(crate) struct LagTile {
    /// Blocks in the tile.
    pub width: usize,
    /// Per pair segment (pairs one after the other) and block: the lag function's value at
    /// the segment's lower lag, and its rise to the upper.
    value: Vec<f32>,
    slope: Vec<f32>,
    /// Per direction and block, the spectrum ([`PairLags::read_off_tile`]).
    pub out: Vec<f32>,
}

impl LagTile {
    /// Makes room for `width` blocks of `lags`' segments.
    pub fn reset(&mut self, lags: &PairLags, width: usize) {
        self.width = width;
        let n = lags.seg_offset[lags.pairs.len()];
        zeroed(&mut self.value, n * width);
        zeroed(&mut self.slope, n * width);
    }
}

impl PairLags {
    /// Lays out the lag grids of every pair of `array` for directions `grid`, bins `bins`
    /// of a `frame_len`-point FFT at `fs`, and sound speed `c`.
    pub fn new(
        array: &MicArray,
        grid: &DirectionGrid,
        fs: f64,
        c: f64,
        bins: Range<usize>,
        frame_len: usize,
    ) -> Self {
        let pos = array.positions();
        let pairs = array.pairs();
        // Half an azimuth cell of the longest pair's delay change, at most one sample: the
        // lag grid then resolves finer than the direction grid for every pair.
        let step = (0.5 * grid.az_step_deg().to_radians() * fs * array.aperture() / c).min(1.0);
        // Each pair needs only the lags its directions reach: with an elevation-limited grid
        // a pair with a vertical baseline spans far fewer lags than its length allows.
        let n_dirs = grid.len();
        let units: Vec<[f64; 3]> = (0..n_dirs).map(|d| grid.unit(d)).collect();
        let delays: Vec<Vec<f64>> = pairs
            .iter()
            .map(|&(i, j)| {
                // tau_ij = t_i - t_j = (r_j - r_i) . u / c: the lag at which the
                // cross-correlation of channel i with channel j peaks for a plane wave
                // arriving from u (samples).
                units
                    .iter()
                    .map(|u| (0..3).map(|a| (pos[j][a] - pos[i][a]) * u[a]).sum::<f64>() / c * fs)
                    .collect()
            })
            .collect();
        let half: Vec<usize> = delays
            .iter()
            .map(|t| (t.iter().fold(0.0f64, |m, v| m.max(v.abs())) / step).ceil() as usize + 1)
            .collect();
        let hmax = half.iter().copied().max().unwrap_or(1);
        let n_bins = padded(bins.len());
        let rows = 2 * hmax + 1;
        let mut cos = vec![0.0f32; rows * n_bins];
        let mut sin = vec![0.0f32; rows * n_bins];
        for r in 0..rows {
            let tau = (r as f64 - hmax as f64) * step; // samples
            for (b, k) in bins.clone().enumerate() {
                let ph = std::f64::consts::TAU * k as f64 / frame_len as f64 * tau;
                cos[r * n_bins + b] = ph.cos() as f32;
                sin[r * n_bins + b] = ph.sin() as f32;
            }
        }
        let mut lookup = Vec::with_capacity(pairs.len() * n_dirs);
        for (p, taus) in delays.iter().enumerate() {
            let h = half[p];
            for &tau in taus {
                let x = tau / step + h as f64;
                let k0 = (x.floor().max(0.0) as usize).min(2 * h - 1);
                lookup.push((k0 as u32, (x - k0 as f64) as f32));
            }
        }
        let seg_offset = std::iter::once(0)
            .chain(half.iter().scan(0, |at, &h| {
                *at += 2 * h;
                Some(*at)
            }))
            .collect();
        Self {
            pairs,
            half,
            hmax,
            n_bins,
            cos,
            sin,
            lookup,
            n_dirs,
            seg_offset,
        }
    }

    /// The number of bins of `stft`'s band, checked against the plan.
    ///
    /// # Panics
    /// If `stft` was not made with the band the tables were built for.
    pub fn band_of(&self, stft: &crate::stft::Spectrogram) -> usize {
        let nb = stft.bins().len();
        assert_eq!(
            padded(nb),
            self.n_bins,
            "spectrogram band differs from the plan"
        );
        nb
    }

    /// The cosine and sine table rows of pair `p`'s lags.
    pub fn rows(&self, p: usize) -> (&[f32], &[f32]) {
        let h = self.half[p];
        let r = (self.hmax - h) * self.n_bins..(self.hmax + h + 1) * self.n_bins;
        (&self.cos[r.clone()], &self.sin[r])
    }

    /// Writes the direction spectrum `sum over pairs of scale * L_p(tau_p(d))` into `out`,
    /// where each pair's lag function is `L_p(tau) = sum_b kernel(x_b, y_b, z_b, cos w_b tau,
    /// sin w_b tau)` and `coefficients(pair, (i, j), x, y, z)` fills the pair's per-bin
    /// coefficients (the padded tail of `x`, `y`, `z` must make the kernel 0). This is the
    /// shape every pairwise method shares; a method only says what its bins hold and how a
    /// bin votes at a lag.
    ///
    /// With [`Target::Lags`] the lag functions are stored in a tile of blocks instead, to be
    /// read off at every direction for the whole tile at once ([`PairLags::read_off_tile`]).
    pub fn pairwise_spectrum<F, K>(
        &self,
        mut target: Target<'_>,
        scale: f32,
        scratch: &mut PairScratch,
        mut coefficients: F,
        kernel: K,
    ) where
        F: FnMut(usize, (usize, usize), &mut [f32], &mut [f32], &mut [f32]),
        K: Fn(f32, f32, f32, f32, f32) -> f32 + Copy,
    {
        if let Target::Directions(out) = &mut target {
            out.fill(0.0);
        }
        let PairScratch {
            x,
            y,
            z,
            lagfn,
            segments,
        } = scratch;
        // The padded tail must stay 0 (the kernels give 0 there): start from zeros.
        let (x, y, z) = (
            zeroed(x, self.n_bins),
            zeroed(y, self.n_bins),
            zeroed(z, self.n_bins),
        );
        for (p, &pair) in self.pairs.iter().enumerate() {
            coefficients(p, pair, x, y, z);
            let (cos, sin) = self.rows(p);
            lagfn.resize(2 * self.half[p] + 1, 0.0);
            lag_sums(x, y, z, cos, sin, lagfn, kernel);
            lagfn.iter_mut().for_each(|v| *v *= scale);
            // Each lag's value and slope, so that a direction costs one load and one
            // multiply-add.
            segments.clear();
            segments.extend(lagfn.windows(2).map(|w| [w[0], w[1] - w[0]]));
            match &mut target {
                Target::Directions(out) => self.accumulate(p, segments, out),
                Target::Lags(tile, slot) => {
                    let w = tile.width;
                    let at = self.seg_offset[p];
                    for (k, &[v, slope]) in segments.iter().enumerate() {
                        tile.value[(at + k) * w + *slot] = v;
                        tile.slope[(at + k) * w + *slot] = slope;
                    }
                }
            }
        }
    }

    /// The spectra of a tile of blocks whose lag functions [`PairLags::pairwise_spectrum`]
    /// stored: `tile.out[d * width + t]` for direction `d` and block `t`. The same sums as
    /// [`Target::Directions`], term for term and in the same order, so the values are
    /// identical; but each direction's lookup is read once per tile, and the tile's blocks
    /// are summed side by side in SIMD lanes instead of one scalar gather per block.
    pub fn read_off_tile(&self, tile: &mut LagTile) {
        #[cfg(target_arch = "x86_64")]
        if crate::method::avx2_fma() {
            // SAFETY: the CPU supports the features the function is compiled for.
            unsafe { self.read_off_tile_avx2(tile) };
            return;
        }
        self.read_off_tile_portable(tile);
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn read_off_tile_avx2(&self, tile: &mut LagTile) {
        self.read_off_tile_portable(tile);
    }

    #[inline(always)]
    fn read_off_tile_portable(&self, tile: &mut LagTile) {
        let w = tile.width;
        let LagTile {
            value, slope, out, ..
        } = tile;
        let out = zeroed(out, self.n_dirs * w);
        for p in 0..self.pairs.len() {
            let look = &self.lookup[p * self.n_dirs..(p + 1) * self.n_dirs];
            let at = self.seg_offset[p];
            for (o, &(k, f)) in out.chunks_exact_mut(w).zip(look) {
                let r = (at + k as usize) * w..(at + k as usize + 1) * w;
                for ((o, &v), &sl) in o.iter_mut().zip(&value[r.clone()]).zip(&slope[r]) {
                    *o += v + f * sl;
                }
            }
        }
    }

    /// Adds pair `p`'s lag function, given as each lag's value and slope, read off at
    /// every direction, to `out` (block by block this loop runs pairs x directions x blocks
    /// times, the most of any in the crate; see [`PairLags::read_off_tile`]).
    fn accumulate(&self, p: usize, segments: &[[f32; 2]], out: &mut [f32]) {
        let look = &self.lookup[p * self.n_dirs..(p + 1) * self.n_dirs];
        for (o, &(k, f)) in out.iter_mut().zip(look) {
            let [v, slope] = segments[k as usize];
            *o += v + f * slope;
        }
    }
}

/// Working memory of [`PairLags::pairwise_spectrum`] (part of [`crate::method::MethodScratch`]).
#[derive(Clone, Debug, Default)]
pub(crate) struct PairScratch {
    x: Vec<f32>,
    y: Vec<f32>,
    z: Vec<f32>,
    lagfn: Vec<f32>,
    segments: Vec<[f32; 2]>,
}

/// Bins are padded to a multiple of this, so the lag sums run on whole SIMD lanes.
pub(crate) const LANES: usize = 8;

/// Rounds `n` up to whole [`LANES`].
pub(crate) fn padded(n: usize) -> usize {
    n.div_ceil(LANES) * LANES
}

/// Evaluates `out[r] = sum_b kernel(x[b], y[b], z[b], cos[r][b], sin[r][b])` for every lag
/// row `r` of one pair. `x`, `y`, `z` are per-bin coefficients padded to whole lanes with
/// values for which the kernel gives 0.
///
/// Eight independent accumulators over fixed-size chunks let the compiler vectorise the
/// sum (float addition is not associative, so it will not reorder one accumulator); on
/// x86-64 processors with AVX2 and FMA the same code is compiled a second time for them
/// and chosen at run time.
fn lag_sums<K>(
    x: &[f32],
    y: &[f32],
    z: &[f32],
    cos: &[f32],
    sin: &[f32],
    out: &mut [f32],
    kernel: K,
) where
    K: Fn(f32, f32, f32, f32, f32) -> f32 + Copy,
{
    #[cfg(target_arch = "x86_64")]
    if crate::method::avx2_fma() {
        // SAFETY: the CPU supports the features the function is compiled for.
        unsafe { lag_sums_avx2(x, y, z, cos, sin, out, kernel) };
        return;
    }
    lag_sums_portable(x, y, z, cos, sin, out, kernel);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn lag_sums_avx2<K>(
    x: &[f32],
    y: &[f32],
    z: &[f32],
    cos: &[f32],
    sin: &[f32],
    out: &mut [f32],
    kernel: K,
) where
    K: Fn(f32, f32, f32, f32, f32) -> f32 + Copy,
{
    lag_sums_portable(x, y, z, cos, sin, out, kernel);
}

#[inline(always)]
fn lag_sums_portable<K>(
    x: &[f32],
    y: &[f32],
    z: &[f32],
    cos: &[f32],
    sin: &[f32],
    out: &mut [f32],
    kernel: K,
) where
    K: Fn(f32, f32, f32, f32, f32) -> f32 + Copy,
{
    let nb = x.len();
    assert!(
        nb.is_multiple_of(LANES) && y.len() == nb && z.len() == nb,
        "bins padded to lanes"
    );
    assert!(
        cos.len() >= out.len() * nb && sin.len() >= out.len() * nb,
        "one table row per lag"
    );
    // ROWS lags at a time: each bin's coefficients are loaded once for all of them, and
    // their sums are independent chains, so that the adder's latency does not bound the
    // loop. Each lag's own sum runs in the same order as one lag at a time would.
    let mut outs = out.chunks_exact_mut(ROWS);
    let mut at = 0;
    for o in outs.by_ref() {
        let mut acc = [[0.0f32; LANES]; ROWS];
        let c: [&[f32]; ROWS] = std::array::from_fn(|j| &cos[(at + j) * nb..(at + j + 1) * nb]);
        let s: [&[f32]; ROWS] = std::array::from_fn(|j| &sin[(at + j) * nb..(at + j + 1) * nb]);
        for k in (0..nb).step_by(LANES) {
            let (x8, y8, z8) = (&x[k..k + LANES], &y[k..k + LANES], &z[k..k + LANES]);
            for j in 0..ROWS {
                let (c8, s8) = (&c[j][k..k + LANES], &s[j][k..k + LANES]);
                for l in 0..LANES {
                    acc[j][l] += kernel(x8[l], y8[l], z8[l], c8[l], s8[l]);
                }
            }
        }
        for (o, a) in o.iter_mut().zip(&acc) {
            *o = a.iter().sum();
        }
        at += ROWS;
    }
    for ((o, c), s) in outs
        .into_remainder()
        .iter_mut()
        .zip(cos[at * nb..].chunks_exact(nb))
        .zip(sin[at * nb..].chunks_exact(nb))
    {
        let mut acc = [0.0f32; LANES];
        let rows = x
            .chunks_exact(LANES)
            .zip(y.chunks_exact(LANES))
            .zip(z.chunks_exact(LANES))
            .zip(c.chunks_exact(LANES).zip(s.chunks_exact(LANES)));
        for (((x8, y8), z8), (c8, s8)) in rows {
            for l in 0..LANES {
                acc[l] += kernel(x8[l], y8[l], z8[l], c8[l], s8[l]);
            }
        }
        *o = acc.iter().sum();
    }
}

/// Lags summed together by [`lag_sums`]. Measured (GCC-PHAT / MVDR on the authors'
/// recordings, median ms per recording of 15 interleaved runs): one lag at a time 12.4 /
/// 15.0, four 12.1 / 13.3; eight no faster than four, and two (21 / 31) far slower, the
/// compiler vectorising that loop another way.
const ROWS: usize = 4;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{DirectionGrid, ElevationRange};

    /// Seeded pseudo-random values in [-1, 1) (a splitmix-style hash: no RNG dependency).
    fn junk(n: usize, seed: u64) -> Vec<f32> {
        (0..n as u64)
            .map(|i| {
                let mut z = (i + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ seed;
                z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                z ^= z >> 31;
                (z >> 40) as f32 / (1u64 << 23) as f32 - 1.0
            })
            .collect()
    }

    /// The MVDR kernel, the most demanding of the two (a division per term).
    fn kernel(x: f32, y: f32, z: f32, c: f32, s: f32) -> f32 {
        z / (1.1 - (x * c - y * s))
    }

    #[test]
    fn lag_sums_match_a_naive_f64_sum() {
        let (nb, rows) = (3 * LANES, 7);
        let (x, y, z) = (junk(nb, 1), junk(nb, 2), junk(nb, 3));
        let x: Vec<f32> = x.iter().map(|v| 0.4 * v).collect();
        let (cos, sin) = (junk(rows * nb, 4), junk(rows * nb, 5));
        let mut out = vec![f32::NAN; rows]; // junk first: every value must be written
        lag_sums(&x, &y, &z, &cos, &sin, &mut out, kernel);
        for (r, &o) in out.iter().enumerate() {
            let want: f64 = (0..nb)
                .map(|b| {
                    let k = r * nb + b;
                    f64::from(z[b])
                        / (1.1
                            - (f64::from(x[b]) * f64::from(cos[k])
                                - f64::from(y[b]) * f64::from(sin[k])))
                })
                .sum();
            assert!(
                (f64::from(o) - want).abs() < 1e-5 * want.abs().max(1.0),
                "row {r}: {o} vs {want}"
            );
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[test]
    fn the_avx2_lag_sums_equal_the_portable_ones() {
        if !crate::method::avx2_fma() {
            eprintln!("no AVX2+FMA here: only the portable kernel runs");
            return;
        }
        for (nb, rows, seed) in [(LANES, 1, 10), (5 * LANES, 13, 20), (44 * LANES, 61, 30)] {
            let (x, y, z) = (junk(nb, seed), junk(nb, seed + 1), junk(nb, seed + 2));
            let x: Vec<f32> = x.iter().map(|v| 0.4 * v).collect();
            let (cos, sin) = (junk(rows * nb, seed + 3), junk(rows * nb, seed + 4));
            let mut portable = vec![f32::NAN; rows];
            let mut avx2 = vec![-f32::NAN; rows];
            lag_sums_portable(&x, &y, &z, &cos, &sin, &mut portable, kernel);
            // SAFETY: the features were detected above.
            unsafe { lag_sums_avx2(&x, &y, &z, &cos, &sin, &mut avx2, kernel) };
            // Same operations in the same order (no fused multiply-add is formed without
            // fast-math): the same bits.
            assert_eq!(
                portable.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                avx2.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                "{nb} bins, {rows} rows"
            );
        }
    }

    #[test]
    fn lookup_reproduces_the_analytic_delay() {
        // Two microphones 0.2 m apart on x; a source at azimuth a delays mic 1 against
        // mic 0 by 0.2 cos(a) / c: t_0 - t_1 = (r_1 - r_0) . u / c.
        let arr = MicArray::new("x", vec![[0.0; 3], [0.2, 0.0, 0.0]]).unwrap();
        let g = DirectionGrid::new(1.0, ElevationRange::default()).unwrap();
        let fs = 48_000.0;
        let lags = PairLags::new(&arr, &g, fs, 343.0, 1..10, 64);
        let step = 0.5 * 1f64.to_radians() * fs * 0.2 / 343.0;
        for d in [0usize, 45, 100, 180, 300] {
            let (k, f) = lags.lookup[d];
            let tau = (k as f64 + f as f64 - lags.half[0] as f64) * step;
            let want = 0.2 * g.azimuths()[d].to_radians().cos() / 343.0 * fs;
            assert!((tau - want).abs() < 1e-3, "d{d}: {tau} vs {want}");
        }
    }
}
