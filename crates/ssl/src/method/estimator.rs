//! What every angular-spectrum method is to the localizer: the [`SpectrumEstimator`]
//! trait, and the working memory the methods keep between calls ([`MethodScratch`]).
//!
//! The trait lives with the methods, not with the localizer that calls it: a method
//! depends on the STFT, the grid and its own kernels only, and the localizer (blocks,
//! pooling, peaks) depends on the methods through this trait, not the other way round.
//! Each method keeps its own working memory, a field of [`MethodScratch`] that no other
//! method touches; the pairwise kernel's ([`crate::grid`]) is shared by the three
//! pairwise methods, which run it in turn.

use std::ops::Range;

use realfft::num_complex::Complex32;

use crate::grid::{LagTile, PairScratch};
use crate::method::music::SubspaceScratch;
use crate::stft::Spectrogram;

/// An angular-spectrum method: writes the spectrum of a block of STFT frames.
pub trait SpectrumEstimator: Send + Sync {
    /// Stable short name used in reports (`"gcc-phat"`, `"mvdr"`).
    fn name(&self) -> &'static str;

    /// Writes the angular spectrum of frames `frames` of `stft` into `out`, one value per
    /// direction of the grid the estimator was built for. `scratch` is working memory that
    /// the caller keeps between calls (RustFFT's `process_with_scratch`): the estimators
    /// run once per block of frames, dozens of times per recording, and allocate nothing
    /// once it has grown to size. Its contents on entry do not matter, except that
    /// [`SpectrumEstimator::part_spectra`] reads what the last
    /// [`SpectrumEstimator::estimate_blocks_parts`] kept there.
    ///
    /// # Panics
    /// If `out` does not hold one value per direction, `frames` is out of range, or `stft`
    /// was not made with the band and channel count the estimator was built for.
    fn estimate_into(
        &self,
        stft: &Spectrogram,
        frames: Range<usize>,
        out: &mut [f32],
        scratch: &mut MethodScratch,
    );

    /// The spectra of several blocks: `sink(i, spectrum)` for each of `blocks` (frame
    /// ranges of `stft`), in order, each spectrum being what
    /// [`SpectrumEstimator::estimate_into`] writes for it (to within rounding: an override
    /// may sum in another order). `block` is a buffer of one
    /// value per direction. The default runs `estimate_into` block by block; an estimator
    /// whose work can be shared between blocks overrides it (the subspace methods form
    /// each direction's steering terms once per recording instead of once per block; the
    /// pairwise methods read their lag functions off at the directions a tile of blocks at
    /// a time).
    ///
    /// # Panics
    /// As [`SpectrumEstimator::estimate_into`].
    fn estimate_blocks(
        &self,
        stft: &Spectrogram,
        blocks: &[Range<usize>],
        block: &mut [f32],
        scratch: &mut MethodScratch,
        sink: &mut dyn FnMut(usize, &[f32]),
    ) {
        each_block(self, stft, blocks, block, scratch, sink);
    }

    /// Whether the estimator takes one spectrum of a recording's every frame instead of
    /// pooling short blocks (the coherent wideband methods, [`crate::coherent`]:
    /// their per-bin statistics need every snapshot): the localizer then makes one block
    /// of the recording, whatever [`crate::SslConfig::block_frames`] says. Default: no.
    fn whole_recording(&self) -> bool {
        false
    }

    /// Whether [`SpectrumEstimator::estimate_blocks_parts`] gives the spectra of parts of
    /// the band in the same pass as the band's. Default: no.
    fn estimates_parts(&self) -> bool {
        false
    }

    /// [`SpectrumEstimator::estimate_blocks`], and in the same pass what each of `parts`
    /// (bin ranges relative to the band; a bin in two counts in the first) contributes,
    /// kept in `scratch` for
    /// [`SpectrumEstimator::part_spectra`]. Returns whether it kept them; the default does
    /// not, and an estimator that shares no work between the band and its parts should
    /// not either (a localizer of each part is then as fast).
    ///
    /// # Panics
    /// As [`SpectrumEstimator::estimate_into`].
    fn estimate_blocks_parts(
        &self,
        stft: &Spectrogram,
        blocks: &[Range<usize>],
        parts: &[Range<usize>],
        block: &mut [f32],
        scratch: &mut MethodScratch,
        sink: &mut dyn FnMut(usize, &[f32]),
    ) -> bool {
        let _ = parts;
        self.estimate_blocks(stft, blocks, block, scratch, sink);
        false
    }

    /// After [`SpectrumEstimator::estimate_blocks_parts`] kept them (and before the next
    /// call of it), each block's spectrum of part `part` at the grid directions `dirs`,
    /// into `out` (block-major, one value per direction of `dirs`): to within a constant
    /// factor, what an estimator of that part alone would write there (the estimator says
    /// how its part's plan differs). The band's other estimates in between
    /// ([`SpectrumEstimator::estimate_blocks`], [`SpectrumEstimator::estimate_into`]) leave
    /// them as they are.
    ///
    /// # Panics
    /// If the parts were not kept; the default always panics.
    fn part_spectra(
        &self,
        part: usize,
        dirs: &[usize],
        scratch: &mut MethodScratch,
        out: &mut Vec<f32>,
    ) {
        let _ = (part, dirs, scratch, out);
        unreachable!("part_spectra without estimate_blocks_parts keeping the parts")
    }
}

/// [`SpectrumEstimator::estimate_blocks`] block by block, through `estimate_into`: the
/// default, and the fallback of an override for the cases it does not batch.
pub(crate) fn each_block<E: SpectrumEstimator + ?Sized>(
    estimator: &E,
    stft: &Spectrogram,
    blocks: &[Range<usize>],
    block: &mut [f32],
    scratch: &mut MethodScratch,
    sink: &mut dyn FnMut(usize, &[f32]),
) {
    for (i, frames) in blocks.iter().enumerate() {
        estimator.estimate_into(stft, frames.clone(), block, scratch);
        sink(i, block);
    }
}

/// Working memory of the spectrum estimators, grown on first use and reused after: one per
/// thread (a [`crate::Scratch`] holds one), passed to every [`SpectrumEstimator`] call.
/// Each field belongs to one method or one kernel, and only it reads or writes it.
#[derive(Clone, Debug, Default)]
pub struct MethodScratch {
    /// The pairwise kernel's lag functions, one pair at a time ([`crate::grid`]).
    pub(crate) pairs: PairScratch,
    /// The pairwise kernel's tile of blocks' lag functions and spectra.
    pub(crate) lag_tile: LagTile,
    /// GCC-PHAT's ([`crate::gcc_phat`]).
    pub(crate) gcc_phat: GccPhatScratch,
    /// MVDR's ([`crate::mvdr`]).
    pub(crate) mvdr: MvdrScratch,
    /// SRP-PHAT's ([`crate::srp_phat`]): one pair's cross-spectrum.
    pub(crate) srp_phat: Vec<Complex32>,
    /// MUSIC's and NormMUSIC's ([`crate::music`]). The coherent methods keep none of their
    /// own: CSSM and WAVES pass it to the SRP-PHAT that finds their preliminary directions.
    pub(crate) subspace: SubspaceScratch,
}

/// GCC-PHAT's working memory.
#[derive(Clone, Debug, Default)]
pub(crate) struct GccPhatScratch {
    /// Per frame and channel, each bin's unit phasor.
    pub unit: Vec<Complex32>,
    /// One pair's cross-spectrum, less the robot's noise.
    pub cross: Vec<Complex32>,
}

/// MVDR's working memory.
#[derive(Clone, Debug, Default)]
pub(crate) struct MvdrScratch {
    /// Per channel, bin powers summed over the block, then smoothed.
    pub power: Vec<f32>,
    /// One channel's unsmoothed powers.
    pub power_sum: Vec<f32>,
    /// One pair's cross-spectrum, summed then smoothed.
    pub cross: Vec<Complex32>,
    pub cross_smooth: Vec<Complex32>,
    /// Prefix sums of the box smoother.
    pub prefix_real: Vec<f32>,
    pub prefix_complex: Vec<Complex32>,
}

/// Whether this CPU can run the AVX2+FMA builds of the hot kernels (the lag sums, the
/// subspace steering), which are compiled beside the portable ones and chosen at run time.
#[cfg(target_arch = "x86_64")]
pub(crate) fn avx2_fma() -> bool {
    std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
}

/// Zero-filled `v` of length `n`, reusing its memory.
pub(crate) fn zeroed<T: Copy + Default>(v: &mut Vec<T>, n: usize) -> &mut [T] {
    v.clear();
    v.resize(n, T::default());
    v
}
