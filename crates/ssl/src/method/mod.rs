//! The angular-spectrum methods, in two families.
//!
//! - **Pairwise** ([`gcc_phat`], [`mvdr`], [`srp_phat`]): each microphone pair's per-bin
//!   statistic is turned into a function of the pair's lag, and a direction reads each
//!   pair's value at its delay ([`crate::grid`]). A method only says what its bins hold and
//!   how a bin votes at a lag; the cost grows with pairs x lags, not with directions.
//! - **Full-array** ([`music`]): the `M x M` covariance per bin is decomposed as a whole and
//!   every direction is steered to it; the cost grows with directions x bins.
//!
//! [`crate::Localizer::new`] builds the one a [`crate::SslConfig`] names.

pub mod gcc_phat;
pub mod music;
pub mod mvdr;
pub mod srp_phat;

use std::ops::Range;
use std::sync::Arc;

use realfft::num_complex::Complex32;

use crate::array::MicArray;
use crate::config::{Method, SslConfig};
use crate::grid::{DirectionGrid, PairLags};
use crate::localizer::SpectrumEstimator;
use crate::stft::Spectrogram;

/// Writes the cross-spectrum of channels `i` and `j` summed over `frames`,
/// `out[b] = sum_f X_i(f, b) X_j(f, b)^*` (MVDR before its smoothing, SRP-PHAT before its
/// whitening).
pub(crate) fn block_cross(
    stft: &Spectrogram,
    frames: Range<usize>,
    (i, j): (usize, usize),
    out: &mut [Complex32],
) {
    out.fill(Complex32::default());
    for f in frames {
        let (xi, xj) = (stft.frame(f, i), stft.frame(f, j));
        for ((c, a), b) in out.iter_mut().zip(xi).zip(xj) {
            *c += a * b.conj();
        }
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
                config.music_sources,
                config.num_peaks,
                config.music_freq_smoothing,
                normalise,
            )
            .coarse_search(grid, config.music_coarse),
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
    }
}
