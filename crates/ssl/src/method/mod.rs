//! The angular-spectrum methods, in two families.
//!
//! - **Pairwise** ([`gcc_phat`], [`mvdr`], [`srp_phat`]): each microphone pair's per-bin
//!   statistic is turned into a function of the pair's lag, and a direction reads each
//!   pair's value at its delay ([`crate::grid`]). A method only says what its bins hold and
//!   how a bin votes at a lag; the cost grows with pairs x lags, not with directions.
//! - **Full-array** ([`music`], [`coherent`]): the `M x M` covariance per bin is decomposed
//!   as a whole and every direction is steered to it; the cost grows with directions x
//!   bins. MUSIC and NormMUSIC add the bins' pseudo-spectra; TOPS, CSSM and WAVES combine
//!   the bins coherently, one spectrum per recording.
//!
//! [`crate::Localizer::new`] builds the one a [`crate::SslConfig`] names.

pub mod coherent;
mod estimator;
pub mod gcc_phat;
pub mod music;
pub mod mvdr;
pub mod srp_phat;

#[cfg(target_arch = "x86_64")]
pub(crate) use estimator::avx2_fma;
pub(crate) use estimator::{GccPhatScratch, MvdrScratch, each_block, zeroed};
pub use estimator::{MethodScratch, SpectrumEstimator};

use std::ops::Range;
use std::sync::Arc;

use realfft::num_complex::Complex32;

use crate::array::MicArray;
use crate::config::{Method, SslConfig};
use crate::grid::{DirectionGrid, PairLags};
use crate::stft::Spectrogram;

/// Writes the cross-spectrum of channels `i` and `j` summed over `frames`,
/// `out[b] = sum_f X_i(f, b) X_j(f, b)^*` (MVDR before its smoothing, SRP-PHAT before its
/// whitening, GCC-PHAT with the robot's noise before its), less `T N_ij(b)` over the `T`
/// frames when the spectrogram carries the robot's noise ([`crate::noise`]).
pub(crate) fn block_cross(
    stft: &Spectrogram,
    frames: Range<usize>,
    (i, j): (usize, usize),
    out: &mut [Complex32],
) {
    out.fill(Complex32::default());
    let t = frames.len() as f32;
    for f in frames {
        let (xi, xj) = (stft.frame(f, i), stft.frame(f, j));
        for ((c, a), b) in out.iter_mut().zip(xi).zip(xj) {
            *c += a * b.conj();
        }
    }
    if let Some(field) = stft.noise() {
        for (c, n) in out.iter_mut().zip(field.row(stft.bins(), (i, j))) {
            *c -= n * t;
        }
    }
}

/// Per direction of `grid` and microphone of `array` (direction-major), the microphone's
/// lead over the array's centroid in samples at `fs`, speed of sound `c`:
/// `(p - centroid) . u / c * fs`. A microphone further along `u` hears the wave earlier:
/// its STFT is the reference's times `exp(+i w lead)` at `w` rad per sample. Delays
/// relative to the centroid keep the phases small. The full-array methods steer with it.
pub(crate) fn steering_leads(array: &MicArray, grid: &DirectionGrid, c: f64, fs: f64) -> Vec<f64> {
    let pos = array.positions();
    let n = pos.len() as f64;
    let centroid: [f64; 3] = std::array::from_fn(|a| pos.iter().map(|p| p[a]).sum::<f64>() / n);
    (0..grid.len())
        .flat_map(|d| {
            let u = grid.unit(d);
            pos.iter()
                .map(move |p| (0..3).map(|a| (p[a] - centroid[a]) * u[a]).sum::<f64>() / c * fs)
        })
        .collect()
}

/// `x / |x|`, or 0 for a bin with no energy (it carries no phase and votes for nothing):
/// PHAT's whitening. `|x|` is the square root of the sum of squares rather than libm's
/// `hypot`, whose care against overflow cost 4.5 % of a GCC-PHAT run (`perf`) for values
/// that cannot overflow here: an STFT of samples in `[-1, 1]`, or a block's sum of their
/// products, lies many orders of magnitude below `f32::MAX`'s square root.
#[inline]
pub(crate) fn unit_phasor(x: Complex32) -> Complex32 {
    let p = x.re * x.re + x.im * x.im;
    if p > f32::MIN_POSITIVE {
        x * (1.0 / p.sqrt())
    } else {
        Complex32::default()
    }
}

/// The estimator of `config.method` for `array`, `grid`, the band's `bins` of a
/// `frame_len`-point FFT at `fs` (Hz).
pub(crate) fn estimator(
    config: &SslConfig,
    array: &MicArray,
    grid: &DirectionGrid,
    fs: f64,
    bins: Range<usize>,
    frame_len: usize,
) -> Box<dyn SpectrumEstimator> {
    let c = config.speed_of_sound;
    let lags = || Arc::new(PairLags::new(array, grid, fs, c, bins.clone(), frame_len));
    let music = |normalise| {
        Box::new(
            music::Music::new(
                array,
                grid,
                fs,
                c,
                bins.clone(),
                frame_len,
                music::Subspace {
                    sources: config.music_sources,
                    max_sources: config.num_peaks,
                    smoothing: config.music_smoothing(),
                    normalise,
                },
            )
            .coarse_search(grid, config.music_coarse),
        )
    };
    let plan = || {
        coherent::Plan::new(
            array,
            grid,
            coherent::Band {
                fs,
                c,
                bins: (bins.start, bins.end),
                frame_len,
                sources: config.music_sources,
                max_sources: config.num_peaks,
                min_sep_deg: config.min_sep_deg,
            },
        )
    };
    match config.method {
        Method::GccPhat => Box::new(gcc_phat::GccPhat::new(lags())),
        Method::Mvdr => Box::new(mvdr::Mvdr::new(
            lags(),
            config.mvdr_loading,
            config.mvdr_freq_smoothing,
        )),
        Method::SrpPhat => Box::new(srp_phat::SrpPhat::new(lags())),
        Method::Music => music(false),
        Method::NormMusic => music(true),
        Method::Tops => Box::new(coherent::Tops::new(plan(), grid)),
        Method::Cssm => Box::new(coherent::Focused::new(
            plan(),
            lags(),
            false,
            config.block_frames,
        )),
        Method::Waves => Box::new(coherent::Focused::new(
            plan(),
            lags(),
            true,
            config.block_frames,
        )),
    }
}

/// Uniform numbers in `[-0.5, 0.5)` from a linear congruential generator (24-bit
/// values, exact in `f32`): the methods' tests' random spectrograms and matrices.
#[cfg(test)]
pub(crate) fn lcg(mut state: u64) -> impl FnMut() -> f64 {
    move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 40) as f64 / (1u64 << 24) as f64 - 0.5
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::ElevationRange;

    /// The pairwise methods spectra of a recording's blocks at once (a tile of blocks'
    /// lag functions read off together) are bit for bit their block-by-block spectra, over
    /// whole tiles and a partial one, on the 3-D grid and in the plane.
    #[test]
    fn all_blocks_at_once_are_the_blocks_one_by_one() {
        let array = MicArray::default();
        let (fs, frame_len, bins) = (16_000.0, 512, 8..200);
        let m = array.len();
        let (frames, nb) = (3 * crate::grid::TILE + 5, bins.len());
        let mut state = 7u64;
        let data: Vec<Complex32> = (0..frames * m * nb)
            .map(|_| {
                let mut r = || {
                    state = state
                        .wrapping_mul(6_364_136_223_846_793_005)
                        .wrapping_add(1);
                    (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
                };
                Complex32::new(r(), r())
            })
            .collect();
        let spec = Spectrogram::from_parts(frames, m, bins.clone(), data);
        let blocks: Vec<Range<usize>> = (0..frames).map(|f| f..f + 1).collect();
        for elevation in [ElevationRange::ROBOT, ElevationRange::PLANE] {
            let grid = DirectionGrid::new(2.0, elevation).unwrap();
            for method in [Method::GccPhat, Method::Mvdr, Method::SrpPhat] {
                let config = SslConfig {
                    method,
                    ..SslConfig::default()
                };
                let est = estimator(&config, &array, &grid, fs, bins.clone(), frame_len);
                let mut scratch = MethodScratch::default();
                let mut one = vec![0.0f32; grid.len()];
                let mut got: Vec<Vec<f32>> = Vec::new();
                let mut buf = vec![0.0f32; grid.len()];
                est.estimate_blocks(&spec, &blocks, &mut buf, &mut scratch, &mut |i, v| {
                    assert_eq!(i, got.len(), "blocks in order");
                    got.push(v.to_vec());
                });
                assert_eq!(got.len(), blocks.len());
                for (b, frames) in blocks.iter().enumerate() {
                    est.estimate_into(&spec, frames.clone(), &mut one, &mut scratch);
                    assert!(
                        one.iter()
                            .zip(&got[b])
                            .all(|(x, y)| x.to_bits() == y.to_bits()),
                        "{method:?}, {elevation:?}, block {b}"
                    );
                }
            }
        }
    }
}
