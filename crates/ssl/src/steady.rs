//! Whether a recording's sound is steady and noise-like: the test behind
//! [`crate::Pooling::Auto`], the default pooling.
//!
//! Max pooling keeps each direction's best block so that talkers who take turns each keep
//! their best moment; but for sources that never pause the best of many noisy blocks is
//! an extreme value, and at a low SNR or a long RT60 it lifts the room's ripples over the
//! thresholds and scatters the peaks, where the blocks' mean averages the noise down
//!. What tells the two apart is whether anything starts,
//! stops or takes turns, and that shows in the blocks' levels: speech moves its energy
//! between frequency bands from one syllable to the next (voiced and unvoiced sounds,
//! formants, pauses); a fan, a ventilation outlet or any continuous noise source does not,
//! and a block's level in each octave then varies by estimation noise alone.
//!
//! **Steady.** The spread of the blocks' levels, the 90th over the 10th percentile in dB,
//! in each octave of the band, averaged over the octaves, is under [`STEADY_SPREAD_DB`]
//! (a factor of two in power). Summing the whole band first would not do: the level of a
//! babble of several talkers is nearly steady, while each octave of it is not. A sum of
//! power over `B` Hz and `T` s has about `2 B T` degrees of freedom, so a steady source's
//! spread depends on the block's length and the octave's width, not on the sample rate.
//! Measured on the default 80-ms blocks, per recording: our
//! simulator's continuous sources (speech-shaped noise, a harmonic hum; one to ten at
//! once, SNR 5-30 dB, RT60 0.3-0.8 s, four arrays) 0.6-2.1 dB; pyroomacoustics' rooms
//! with two to five real talkers at once 4.4-21 dB; the paper's recordings of ten
//! loudspeakers playing voices at once 8.1-11.1 dB; one talker 14.6 dB and more.
//!
//! **Noise-like.** The spectral flatness of the recording's power spectrum (geometric over
//! arithmetic mean of the bins' powers in each octave, averaged over the octaves) is at
//! least [`MIN_FLATNESS`]. A steady hum (a motor, a transformer, a held note: a harmonic
//! series) is steady too, but its field is one deterministic interference pattern, the
//! same in every block: its reflections are as coherent as its direct path
//! ([`crate::covariance`]) and there is no noise of its own to average away, and averaged,
//! the reflections' peaks stand higher beside it (measured: a hum at 180 Hz, SNR 30 dB,
//! RT60 0.3 s, GCC-PHAT: its reflections at 0.31-0.53 of the top pooled by the mean, under
//! `min_relative` by the max, and a ghost source in 3 maps of 10 of one rendering). Its
//! flatness is 0.29-0.34, that of speech-shaped noise 0.85-0.98 and of speech 0.57-0.95
//! (31.25-Hz bins, the default frame at every rate).

use std::ops::Range;

use crate::stft::Spectrogram;

/// The spread of blocks' levels in the band's octaves (dB, [`spread_db`]) under which a
/// recording's sound is steady.
pub const STEADY_SPREAD_DB: f64 = 3.0;

/// The spectral flatness ([`flatness`]) at or above which a recording's sound is
/// noise-like; below it, tonal.
pub const MIN_FLATNESS: f64 = 0.5;

/// Fewer blocks than this cannot tell a steady recording from another: the pooling is then
/// max, as for any recording that is not shown to be steady.
pub const STEADY_MIN_BLOCKS: usize = 4;

/// The `q`-quantile (`[0, 1]`) of `sorted` (ascending, not empty), interpolated linearly
/// between order statistics.
fn quantile(sorted: &[f64], q: f64) -> f64 {
    let at = q * (sorted.len() - 1) as f64;
    let lo = at.floor() as usize;
    let hi = (lo + 1).min(sorted.len() - 1);
    let frac = at - lo as f64;
    sorted[lo] + frac * (sorted[hi] - sorted[lo])
}

/// The spread (dB) of the blocks' levels, averaged over bands: `levels` holds one slice per
/// band, each with every block's energy in that band. Per band, the 90th over the 10th
/// percentile; a band silent in its quietest tenth but not in its loudest is as unsteady as
/// can be (infinite spread); a band silent throughout says nothing and is left out.
/// `None` when fewer than [`STEADY_MIN_BLOCKS`] blocks or no band with any energy.
pub fn spread_db<'a>(levels: impl IntoIterator<Item = &'a [f64]>) -> Option<f64> {
    let (mut sum, mut bands) = (0.0, 0usize);
    let mut sorted = Vec::new();
    for band in levels {
        if band.len() < STEADY_MIN_BLOCKS {
            return None;
        }
        sorted.clear();
        sorted.extend_from_slice(band);
        sorted.sort_by(f64::total_cmp);
        let (low, high) = (quantile(&sorted, 0.1), quantile(&sorted, 0.9));
        if high <= 0.0 {
            continue;
        }
        sum += if low > 0.0 {
            10.0 * (high / low).log10()
        } else {
            f64::INFINITY
        };
        bands += 1;
    }
    (bands > 0).then(|| sum / bands as f64)
}

/// The spectral flatness of a power spectrum, averaged over bands: `powers` holds one slice
/// per band, each with its bins' powers. Per band, the geometric mean of the powers over
/// their arithmetic mean: 1 for a flat spectrum, near 0 for lines (a bin without power
/// makes it 0); a band without power is left out. `None` when no band has any.
pub fn flatness<'a>(powers: impl IntoIterator<Item = &'a [f64]>) -> Option<f64> {
    let (mut sum, mut bands) = (0.0, 0usize);
    for band in powers {
        let mean = band.iter().sum::<f64>() / band.len().max(1) as f64;
        if band.is_empty() || mean <= 0.0 {
            continue;
        }
        let log_mean = band.iter().map(|p| p.ln()).sum::<f64>() / band.len() as f64;
        sum += log_mean.exp() / mean;
        bands += 1;
    }
    (bands > 0).then(|| sum / bands as f64)
}

/// A recording's levels and spectrum in the octaves of its band, as [`Octaves::is_steady`]
/// judges them.
#[derive(Clone, Debug, PartialEq)]
pub struct Octaves {
    /// Each octave's energy in each block (all channels), octave after octave, `blocks`
    /// values each.
    pub levels: Vec<f64>,
    /// Blocks per octave in `levels`.
    pub blocks: usize,
    /// Each bin's power summed over frames and channels, bins ascending.
    pub powers: Vec<f64>,
    /// Each octave's bins, as indices into `powers`.
    pub octaves: Vec<Range<usize>>,
}

impl Octaves {
    /// The octaves of `spec`'s band, from its lowest bin (the first above DC) upwards, the
    /// last closed by the band's top, measured in `n_blocks` blocks of frames `frames(b)`.
    pub fn of(spec: &Spectrogram, n_blocks: usize, frames: &dyn Fn(usize) -> Range<usize>) -> Self {
        let bins = spec.bins();
        let mut octaves = Vec::new();
        let mut lo = bins.start.max(1);
        while lo < bins.end {
            let hi = (2 * lo).min(bins.end);
            octaves.push(lo - bins.start..hi - bins.start);
            lo = hi;
        }
        let mut levels = vec![0.0f64; octaves.len() * n_blocks];
        let mut powers = vec![0.0f64; bins.len()];
        let mut block = vec![0.0f64; bins.len()];
        // The robot's noise per frame and bin, all channels ([`crate::noise`]).
        let noise: Option<Vec<f32>> = spec.noise().map(|field| {
            bins.clone()
                .map(|k| (0..spec.num_channels()).map(|c| field.power(k, c)).sum())
                .collect()
        });
        for b in 0..n_blocks {
            block.fill(0.0);
            for f in frames(b) {
                for c in 0..spec.num_channels() {
                    for (p, x) in block.iter_mut().zip(spec.frame(f, c)) {
                        *p += f64::from(x.norm_sqr());
                    }
                }
            }
            if let Some(noise) = &noise {
                // The sources' levels: less the robot's own noise.
                let t = frames(b).len() as f32;
                for (p, &n) in block.iter_mut().zip(noise) {
                    *p = f64::from(crate::noise::residual_power(*p as f32, n, t));
                }
            }
            for (o, r) in octaves.iter().enumerate() {
                levels[o * n_blocks + b] = block[r.clone()].iter().sum();
            }
            powers.iter_mut().zip(&block).for_each(|(p, q)| *p += q);
        }
        Self {
            levels,
            blocks: n_blocks,
            powers,
            octaves,
        }
    }

    /// [`spread_db`] of the octaves' levels.
    pub fn spread_db(&self) -> Option<f64> {
        spread_db(self.levels.chunks_exact(self.blocks.max(1)))
    }

    /// [`flatness`] of the octaves' powers.
    pub fn flatness(&self) -> Option<f64> {
        flatness(self.octaves.iter().map(|r| &self.powers[r.clone()]))
    }

    /// Steady and noise-like: the spread of the blocks' levels under [`STEADY_SPREAD_DB`]
    /// and the flatness at least [`MIN_FLATNESS`].
    pub fn is_steady(&self) -> bool {
        self.spread_db().is_some_and(|s| s < STEADY_SPREAD_DB)
            && self.flatness().is_some_and(|f| f >= MIN_FLATNESS)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_spread_is_the_decibel_ratio_of_the_tenth_percentiles() {
        // Eleven blocks 1..=11: the 10th percentile is 2, the 90th 10 (order statistics
        // 1 and 9 exactly): 10 log10(5) = 6.99 dB.
        let band: Vec<f64> = (1..=11).map(f64::from).collect();
        let s = spread_db([band.as_slice()]).unwrap();
        assert!((s - 10.0 * 5f64.log10()).abs() < 1e-12, "{s}");
        // Two bands: the mean of their spreads (the second a constant, 0 dB).
        let flat = [3.0; 11];
        let s = spread_db([band.as_slice(), &flat]).unwrap();
        assert!((s - 5.0 * 5f64.log10()).abs() < 1e-12, "{s}");
    }

    #[test]
    fn silence_and_short_recordings_have_no_steady_spread() {
        // A band that falls silent for a while is not steady; one silent throughout is
        // left out of the mean.
        let pauses = [1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0];
        let zeros = [0.0; 10];
        let flat = [2.0; 10];
        assert_eq!(spread_db([&pauses[..]]), Some(f64::INFINITY));
        assert_eq!(spread_db([&zeros[..], &flat[..]]), Some(0.0));
        assert_eq!(spread_db([&zeros[..]]), None);
        // Three blocks cannot tell.
        assert_eq!(spread_db([&flat[..3]]), None);
    }

    #[test]
    fn a_flat_spectrum_has_flatness_one_and_lines_little() {
        // Flat: 1 whatever the level.
        let flat = [4.0; 16];
        assert!((flatness([&flat[..]]).unwrap() - 1.0).abs() < 1e-12);
        // One bin in four holding the power, the others 1 % of it: geometric mean
        // 0.01^(3/4), arithmetic (1 + 3 * 0.01) / 4.
        let lines: Vec<f64> = (0..16)
            .map(|i| if i % 4 == 0 { 1.0 } else { 0.01 })
            .collect();
        let want = 0.01f64.powf(0.75) / (1.03 / 4.0);
        assert!((flatness([lines.as_slice()]).unwrap() - want).abs() < 1e-12);
        // The mean over bands; a band without power left out; a bin without power gives 0.
        let mut gap = flat;
        gap[3] = 0.0;
        let zeros = [0.0; 8];
        let f = flatness([&flat[..], lines.as_slice(), &zeros[..], &gap[..]]).unwrap();
        assert!((f - (1.0 + want) / 3.0).abs() < 1e-12, "{f}");
        assert_eq!(flatness([&zeros[..]]), None);
    }
}
