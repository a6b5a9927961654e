//! Angular spectra and their peaks: the ranked directions of arrival.

use serde::{Deserialize, Serialize};

use crate::config::Pooling;
use crate::grid::DirectionGrid;

/// One direction of arrival: azimuth and elevation (degrees, array frame) and the
/// spectrum's value there.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Doa {
    /// Azimuth (degrees, counter-clockwise from the array's x axis, in `[-180, 180)`).
    pub azimuth_deg: f64,
    /// Elevation (degrees above the array's xy plane) at which the peak is strongest.
    pub elevation_deg: f64,
    /// The pooled spectrum's value at the peak (method-specific scale; larger is stronger).
    pub strength: f64,
    /// How the peak stands out, on a scale every method shares: its height above the
    /// spectrum's median over azimuths, as a fraction of the strongest peak's height above
    /// it (1 for the strongest peak; near 0 for a ripple of the background).
    pub relative: f64,
    /// How many blocks of the recording had their strongest direction within 2 degrees
    /// of this azimuth (blocks in a decay not counted; see
    /// [`crate::SslConfig::dominance_blocks`]); 0 when not counted.
    #[serde(default)]
    pub dominant_blocks: u32,
    /// How far the azimuth profile dips between this peak and the nearest higher one (on
    /// the lower side of the two), as a fraction of the peak's height above the median:
    /// 1 for the strongest peak or one with the background between; near 0 for a ripple
    /// on another peak's flank (see [`crate::SslConfig::min_prominence`]).
    #[serde(default)]
    pub prominence: f64,
    /// How surely the array heard something coherent from this direction: the PHAT
    /// coherence of the whole recording towards it (every microphone pair's unit-magnitude
    /// cross-spectrum, summed over frames and band bins, steered to the direction), in
    /// standard deviations of its value when every channel holds independent noise (see
    /// [`crate::SslConfig::min_significance`]). 0 when not computed.
    #[serde(default)]
    pub significance: f64,
}

/// An angular spectrum over a [`DirectionGrid`]: `values[e * num_azimuths + a]`.
#[derive(Clone, Debug, PartialEq)]
pub struct AngularSpectrum {
    grid: DirectionGrid,
    values: Vec<f32>,
    /// Per azimuth cell, the blocks whose strongest direction lay there (empty: not
    /// counted).
    votes: Vec<u32>,
    /// For a linear array, the azimuth of its line (degrees): peaks are searched on its
    /// counter-clockwise side only ([`AngularSpectrum::with_mirror_axis`]).
    mirror_axis_deg: Option<f64>,
    /// Every pooled block's azimuth profile (the largest value over elevations), one block
    /// after the other; empty when not kept ([`AngularSpectrum::with_block_profiles`]).
    profiles: Vec<f32>,
    /// How the blocks were pooled into these values.
    pooling: Pooling,
}

/// The median of `values` (the upper one of an even count): the background that
/// [`Doa::relative`] heights are measured from.
pub(crate) fn median(values: &[f32]) -> f32 {
    let mut s = values.to_vec();
    let mid = s.len() / 2;
    *s.select_nth_unstable_by(mid, f32::total_cmp).1
}

/// Wraps an angle in degrees to `[-180, 180)`.
pub fn wrap_deg(a: f64) -> f64 {
    let w = (a + 180.0).rem_euclid(360.0) - 180.0;
    // rem_euclid can round up to exactly 360 for tiny negative inputs.
    if w >= 180.0 { w - 360.0 } else { w }
}

impl AngularSpectrum {
    /// Wraps values laid out as the grid documents.
    ///
    /// # Panics
    /// If `values.len() != grid.len()`.
    pub fn new(grid: DirectionGrid, values: Vec<f32>) -> Self {
        assert_eq!(values.len(), grid.len(), "one value per direction");
        Self {
            grid,
            values,
            votes: Vec::new(),
            mirror_axis_deg: None,
            profiles: Vec::new(),
            pooling: Pooling::Max,
        }
    }

    /// The same spectrum, marked as pooled by `pooling`.
    #[must_use]
    pub fn with_pooling(self, pooling: Pooling) -> Self {
        Self { pooling, ..self }
    }

    /// How the blocks were pooled into this spectrum: [`Pooling::Max`] (also the mark of a
    /// spectrum built from values alone) or [`Pooling::Mean`]; for a localizer set to
    /// [`Pooling::Auto`], the one it chose for the recording.
    pub fn pooling(&self) -> Pooling {
        self.pooling
    }

    /// The same spectrum with the azimuth profiles of the blocks it pooled (one
    /// [`DirectionGrid::num_azimuths`] run per block), for [`AngularSpectrum::placed`].
    ///
    /// # Panics
    /// If `profiles` is not a whole number of azimuth profiles.
    #[must_use]
    pub fn with_block_profiles(self, profiles: Vec<f32>) -> Self {
        assert!(
            profiles.len().is_multiple_of(self.grid.num_azimuths()),
            "whole azimuth profiles"
        );
        Self { profiles, ..self }
    }

    /// `doas` (strongest first), each that was the strongest direction of a block
    /// ([`Doa::dominant_blocks`] at least 1) moved to the highest local maximum within
    /// `window_deg` of it of the mean azimuth profile of the `share` of the pooled blocks
    /// (at least one) in which its direction stood highest, unless that would bring it
    /// nearer than `min_sep_deg` to a DoA before it (see [`crate::SslConfig::placement_share`]).
    /// Each azimuth is refined between cells as [`AngularSpectrum::peaks`] refines it; the
    /// other fields stay the pooled peak's. Without block profiles, or with `share` 0, the
    /// DoAs are returned as they are.
    pub fn placed(
        &self,
        doas: Vec<Doa>,
        share: f64,
        window_deg: f64,
        min_sep_deg: f64,
    ) -> Vec<Doa> {
        let n = self.grid.num_azimuths();
        let blocks = self.profiles.len() / n;
        if blocks == 0 || share <= 0.0 || window_deg <= 0.0 {
            return doas;
        }
        let take = ((share * blocks as f64).ceil() as usize).clamp(1, blocks);
        let step = self.grid.az_step_deg();
        let reach = (window_deg / step).ceil() as usize;
        let mut order: Vec<usize> = (0..blocks).collect();
        let mut mean = vec![0.0f32; n];
        let mut out: Vec<Doa> = Vec::with_capacity(doas.len());
        for d in doas {
            if d.dominant_blocks == 0 {
                out.push(d);
                continue;
            }
            let cell = self.grid.azimuth_cell(d.azimuth_deg);
            let at = |b: usize| self.profiles[b * n + cell];
            order.sort_unstable_by(|&a, &b| at(b).total_cmp(&at(a)));
            mean.fill(0.0);
            for &b in &order[..take] {
                let row = &self.profiles[b * n..(b + 1) * n];
                mean.iter_mut().zip(row).for_each(|(m, &v)| *m += v);
            }
            // The highest local maximum within the window.
            let mut best: Option<(f64, f64)> = None; // (azimuth, height)
            for o in 0..=2 * reach {
                let i = (cell + n + o - reach) % n;
                if let Some((az, height)) = self.local_max(&mean, i)
                    && wrap_deg(az - d.azimuth_deg).abs() <= window_deg
                    && best.is_none_or(|b| height > b.1)
                {
                    best = Some((az, height));
                }
            }
            let placed = best.map(|(az, _)| az).filter(|&az| {
                out.iter()
                    .all(|e: &Doa| wrap_deg(e.azimuth_deg - az).abs() >= min_sep_deg)
            });
            out.push(match placed {
                Some(azimuth_deg) => Doa { azimuth_deg, ..d },
                None => d,
            });
        }
        out
    }

    /// The same spectrum heard by a linear array whose line lies at `axis_deg` (array
    /// frame; see `MicArray::mirror_axis_deg`), or by any array when `None`.
    ///
    /// Why: a linear array hears only the angle to its line, so its spectrum is symmetric
    /// about the line and every source stands there twice, at `a` and `2 axis - a`, equally
    /// high. Its peaks are searched on the line's counter-clockwise side only (azimuths
    /// from `axis` to `axis + 180`, as [`crate::fold_azimuth`] folds them), so that a source
    /// is one DoA, not two that take two of the `N` places; a block that voted for the
    /// other side's cell voted for this one (which of the two a block's maximum falls on is
    /// the noise's choice).
    #[must_use]
    pub fn with_mirror_axis(mut self, axis_deg: Option<f64>) -> Self {
        if let Some(axis) = axis_deg
            && !self.votes.is_empty()
        {
            let n = self.grid.num_azimuths();
            let mut folded = vec![0u32; n];
            for (i, &v) in self.votes.iter().enumerate() {
                let az = crate::fold_azimuth(self.grid.azimuths()[i], Some(axis));
                folded[self.grid.azimuth_cell(az)] += v;
            }
            self.votes = folded;
        }
        Self {
            mirror_axis_deg: axis_deg,
            ..self
        }
    }

    /// Whether the azimuth cell at `azimuth_deg` lies on the searched side of a linear
    /// array's line (always, for other arrays), within half a cell.
    fn searched(&self, azimuth_deg: f64) -> bool {
        self.mirror_axis_deg.is_none_or(|axis| {
            let half = 0.5 * self.grid.az_step_deg();
            let from = wrap_deg(azimuth_deg - axis);
            (from >= -half && from <= 180.0 + half) || from <= -180.0 + half
        })
    }

    /// The same spectrum with, per azimuth cell of the grid, the number of pooled blocks
    /// whose strongest direction lay at that azimuth: the peaks then report them as
    /// [`Doa::dominant_blocks`].
    ///
    /// # Panics
    /// If `votes` is neither empty nor one count per azimuth.
    #[must_use]
    pub fn with_votes(self, votes: Vec<u32>) -> Self {
        assert!(
            votes.is_empty() || votes.len() == self.grid.num_azimuths(),
            "one count per azimuth"
        );
        Self { votes, ..self }
    }

    /// The grid.
    pub fn grid(&self) -> &DirectionGrid {
        &self.grid
    }

    /// Values, elevation-major.
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// For each azimuth, the largest value over elevations, and the elevation index of it.
    pub fn azimuth_profile(&self) -> (Vec<f32>, Vec<usize>) {
        let n = self.grid.num_azimuths();
        let mut best = self.values[..n].to_vec();
        let mut at = vec![0usize; n];
        for (e, row) in self.values.chunks_exact(n).enumerate().skip(1) {
            for a in 0..n {
                if row[a] > best[a] {
                    best[a] = row[a];
                    at[a] = e;
                }
            }
        }
        (best, at)
    }

    /// Whether cell `i` of the azimuth profile `v` is a local maximum (`>=` on one side
    /// only: a two-cell plateau yields one, not two), and if so its azimuth refined between
    /// cells by a parabola through the cell and its two neighbours, and the parabola's
    /// height there.
    fn local_max(&self, v: &[f32], i: usize) -> Option<(f64, f64)> {
        let n = v.len();
        let (l, c, r) = (v[(i + n - 1) % n], v[i], v[(i + 1) % n]);
        if !(c >= l && c > r) {
            return None;
        }
        let (l, c, r) = (f64::from(l), f64::from(c), f64::from(r));
        let den = l - 2.0 * c + r;
        let delta = if den < 0.0 {
            (0.5 * (l - r) / den).clamp(-0.5, 0.5)
        } else {
            0.0
        };
        let az = wrap_deg(self.grid.azimuths()[i] + delta * self.grid.az_step_deg());
        // On a linear array's line a peak is its own mirror image: refined a fraction of a
        // cell across, it is folded back (see `with_mirror_axis`).
        let az = crate::fold_azimuth(az, self.mirror_axis_deg);
        Some((az, c - 0.25 * (l - r) * delta))
    }

    /// The strongest local maxima of the azimuth profile, at least `min_sep_deg` apart
    /// (circularly), strongest first, at most `max_peaks`.
    ///
    /// Each peak's azimuth is refined between grid cells by fitting a parabola through the
    /// peak cell and its two neighbours, so the estimate is not quantised to the grid.
    pub fn peaks(&self, max_peaks: usize, min_sep_deg: f64) -> Vec<Doa> {
        self.resolved_peaks(max_peaks, min_sep_deg, 0.0)
    }

    /// [`AngularSpectrum::peaks`] without the peaks (but the strongest) whose
    /// [`Doa::prominence`] is below `min_prominence`: what the spectrum does not resolve
    /// from a higher peak is not reported, and takes no place among the `max_peaks`.
    pub fn resolved_peaks(
        &self,
        max_peaks: usize,
        min_sep_deg: f64,
        min_prominence: f64,
    ) -> Vec<Doa> {
        let (v, el_at) = self.azimuth_profile();
        let n = v.len();
        let mut cands: Vec<(usize, f64, f64)> = Vec::new(); // (cell, refined az, value)
        for i in 0..n {
            if self.searched(self.grid.azimuths()[i])
                && let Some((az, height)) = self.local_max(&v, i)
            {
                cands.push((i, az, height));
            }
        }
        cands.sort_by(|a, b| b.2.total_cmp(&a.2));
        let median = f64::from(median(&v));
        let top = cands.first().map_or(median, |c| c.2);
        let span = top - median;
        // Votes within 2 degrees (at least one cell) either side of the peak cell.
        let dominant = |i: usize| -> u32 {
            if self.votes.is_empty() {
                return 0;
            }
            self.grid
                .azimuth_window(i, 2.0)
                .map(|j| self.votes[j])
                .sum()
        };
        // The dip to the nearest higher cell on each side (circularly), the higher of the
        // two lowest points on the way, as a fraction of the cell's height above the
        // median; 1 at most (the background between counts as a full dip).
        let prominence = |i: usize| -> f64 {
            let c = v[i];
            let lowest_towards = |step: usize| -> Option<f32> {
                let (mut lo, mut j) = (c, i);
                for _ in 1..n {
                    j = (j + step) % n;
                    if v[j] > c {
                        return Some(lo);
                    }
                    lo = lo.min(v[j]);
                }
                None // no higher cell: the strongest
            };
            // Each walk passes every other cell: both find a higher one, or neither.
            let (Some(l), Some(r)) = (lowest_towards(n - 1), lowest_towards(1)) else {
                return 1.0;
            };
            let height = f64::from(c) - median;
            if height > 0.0 {
                ((f64::from(c) - f64::from(l.max(r))) / height).min(1.0)
            } else {
                0.0
            }
        };
        let mut out: Vec<Doa> = Vec::with_capacity(max_peaks);
        for (i, az, val) in cands {
            if out.len() == max_peaks {
                break;
            }
            let prominence = prominence(i);
            if !out.is_empty() && prominence < min_prominence {
                continue;
            }
            if out
                .iter()
                .all(|d| wrap_deg(d.azimuth_deg - az).abs() >= min_sep_deg)
            {
                out.push(Doa {
                    azimuth_deg: az,
                    elevation_deg: self.grid.elevations()[el_at[i]],
                    strength: val,
                    relative: if span > 0.0 {
                        (val - median) / span
                    } else {
                        1.0
                    },
                    dominant_blocks: dominant(i),
                    prominence,
                    significance: 0.0,
                });
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::ElevationRange;

    fn spectrum_with_bumps(bumps: &[(f64, f32)]) -> AngularSpectrum {
        let g = DirectionGrid::new(1.0, ElevationRange::default()).unwrap();
        let values = g
            .azimuths()
            .iter()
            .map(|&a| {
                bumps
                    .iter()
                    .map(|&(c, h)| h * (-(wrap_deg(a - c) / 4.0).powi(2) as f32).exp())
                    .sum()
            })
            .collect();
        AngularSpectrum::new(g, values)
    }

    #[test]
    fn wrap_keeps_angles_in_range() {
        for (a, w) in [
            (180.0, -180.0),
            (-180.0, -180.0),
            (190.0, -170.0),
            (-190.0, 170.0),
        ] {
            assert_eq!(wrap_deg(a), w);
        }
        assert!(wrap_deg(-1e-15) < 180.0);
    }

    #[test]
    fn relative_heights_are_measured_from_the_median() {
        // Narrow bumps on a flat floor of 0.1: the median is the floor, so a bump of height
        // h over it stands h / 2 as high as the strongest (2).
        let g = DirectionGrid::new(1.0, ElevationRange::default()).unwrap();
        let values = g
            .azimuths()
            .iter()
            .map(|&a| {
                0.1 + [(0.0, 2.0f32), (90.0, 1.0), (-90.0, 0.4)]
                    .iter()
                    .map(|&(c, h)| h * (-(wrap_deg(a - c) / 3.0).powi(2) as f32).exp())
                    .sum::<f32>()
            })
            .collect();
        let p = AngularSpectrum::new(g, values).peaks(4, 10.0);
        let rel: Vec<f64> = p.iter().map(|d| d.relative).collect();
        assert_eq!(rel.len(), 3);
        for (got, want) in rel.iter().zip([1.0, 0.5, 0.2]) {
            assert!((got - want).abs() < 1e-3, "{rel:?}");
        }
    }

    #[test]
    fn a_ripple_on_a_peaks_flank_is_not_resolved_a_separate_peak_is() {
        // A broad peak (1 at 0 degrees, Gaussian of width 12) with a ripple on its flank
        // (0.2 at 20 degrees, width 4: a local maximum at 19) and a separate bump (0.5 at
        // 90), on a zero floor: the median is 0.
        let f = |a: f64| -> f64 {
            (-(a / 12.0).powi(2)).exp()
                + 0.2 * (-((a - 20.0) / 4.0).powi(2)).exp()
                + 0.5 * (-((a - 90.0) / 4.0).powi(2)).exp()
        };
        let g = DirectionGrid::new(1.0, ElevationRange::default()).unwrap();
        let values = g.azimuths().iter().map(|&a| f(a) as f32).collect();
        let s = AngularSpectrum::new(g, values);
        // The ripple's prominence from the definition: its height above the lowest point
        // between it and the higher peak, as a fraction of its height (about 0.10).
        let want = (f(19.0)
            - (1..19)
                .map(|a| f(f64::from(a)))
                .fold(f64::INFINITY, f64::min))
            / f(19.0);
        assert!(want > 0.05 && want < 0.2, "the test's ripple dips {want}");
        let all = s.peaks(4, 10.0);
        assert_eq!(all.len(), 3, "{all:?}");
        let ripple = all
            .iter()
            .find(|d| (d.azimuth_deg - 19.0).abs() < 1.0)
            .unwrap();
        assert!(
            (ripple.prominence - want).abs() < 1e-5,
            "{ripple:?} against {want}"
        );
        // The separate bump has the floor between it and the higher one: a full dip.
        let apart = all
            .iter()
            .find(|d| (d.azimuth_deg - 90.0).abs() < 1.0)
            .unwrap();
        assert!((apart.prominence - 1.0).abs() < 1e-6, "{apart:?}");
        assert_eq!(all[0].prominence, 1.0, "{all:?}");
        // Resolved peaks drop the ripple and keep the separate one.
        let resolved = s.resolved_peaks(4, 10.0, 0.2);
        let az: Vec<f64> = resolved.iter().map(|d| d.azimuth_deg.round()).collect();
        assert_eq!(az, [0.0, 90.0]);
    }

    #[test]
    fn peaks_come_strongest_first_with_subcell_azimuth() {
        let s = spectrum_with_bumps(&[(30.3, 1.0), (-120.6, 2.0), (179.8, 0.5)]);
        let p = s.peaks(4, 10.0);
        assert_eq!(p.len(), 3);
        let az: Vec<f64> = p.iter().map(|d| d.azimuth_deg).collect();
        assert!((az[0] + 120.6).abs() < 0.1, "{az:?}");
        assert!((az[1] - 30.3).abs() < 0.1, "{az:?}");
        assert!(wrap_deg(az[2] - 179.8).abs() < 0.1, "{az:?}");
    }

    #[test]
    fn peaks_closer_than_min_sep_keep_the_stronger() {
        let s = spectrum_with_bumps(&[(0.0, 1.0), (14.0, 0.8), (60.0, 0.5)]);
        let p = s.peaks(4, 20.0);
        let az: Vec<i64> = p.iter().map(|d| d.azimuth_deg.round() as i64).collect();
        assert_eq!(az, vec![0, 60]);
        assert_eq!(s.peaks(1, 20.0).len(), 1);
    }

    /// Azimuth profiles of blocks, each a sum of Gaussian bumps (centre, height), as
    /// `spectrum_with_bumps` draws them, one block after the other.
    fn block_profiles(g: &DirectionGrid, blocks: &[Vec<(f64, f32)>]) -> Vec<f32> {
        blocks
            .iter()
            .flat_map(|bumps| {
                g.azimuths().iter().map(move |&a| {
                    bumps
                        .iter()
                        .map(|&(c, h)| h * (-(wrap_deg(a - c) / 4.0).powi(2) as f32).exp())
                        .sum::<f32>()
                })
            })
            .collect()
    }

    fn doa_at(azimuth_deg: f64) -> Doa {
        Doa {
            azimuth_deg,
            elevation_deg: 0.0,
            strength: 1.0,
            relative: 1.0,
            dominant_blocks: 1,
            prominence: 1.0,
            significance: 0.0,
        }
    }

    #[test]
    fn a_doa_is_placed_where_its_own_best_blocks_peak_together() {
        // A source at 33 degrees sounds in blocks 0-2; block 3 holds a fluke 3 degrees
        // off it, higher than any of them, where max pooling puts the peak; blocks 4-7
        // hold another source at -90 only.
        let g = DirectionGrid::new(1.0, ElevationRange::default()).unwrap();
        let mut blocks = vec![vec![(33.0, 1.0)]; 3];
        blocks.push(vec![(30.0, 1.2)]);
        blocks.extend(vec![vec![(-90.0, 1.0)]; 4]);
        let profiles = block_profiles(&g, &blocks);
        let n = g.num_azimuths();
        let pooled: Vec<f32> = (0..n)
            .map(|a| {
                (0..blocks.len())
                    .map(|b| profiles[b * n + a])
                    .fold(0.0, f32::max)
            })
            .collect();
        let mut values = pooled.clone();
        for _ in 1..g.elevations().len() {
            values.extend_from_slice(&pooled);
        }
        // Each source was the strongest direction of a block.
        let mut votes = vec![0u32; n];
        votes[g.azimuth_cell(30.0)] = 1;
        votes[g.azimuth_cell(-90.0)] = 4;
        let s = AngularSpectrum::new(g.clone(), values)
            .with_votes(votes)
            .with_block_profiles(profiles);
        let peaks = s.peaks(2, 10.0);
        assert!((peaks[0].azimuth_deg - 30.0).abs() < 0.3, "{peaks:?}");
        // Half the blocks: the four highest at 30 degrees are blocks 0-3, and their mean
        // peaks where a fine search of the bumps' mean puts it.
        let mean = |a: f64| {
            (3.0 * (-((a - 33.0) / 4.0).powi(2)).exp() + 1.2 * (-((a - 30.0) / 4.0).powi(2)).exp())
                / 4.0
        };
        let want = (0..=1000)
            .map(|k| 28.0 + 0.007 * f64::from(k))
            .max_by(|a, b| mean(*a).total_cmp(&mean(*b)))
            .unwrap();
        let placed = s.placed(peaks.clone(), 0.5, 5.0, 10.0);
        assert!(
            (placed[0].azimuth_deg - want).abs() < 0.2,
            "{placed:?}, want {want:.2}"
        );
        assert!((placed[1].azimuth_deg + 90.0).abs() < 0.2, "{placed:?}");
        // Only the azimuth moves; a share of 0 or no block profiles moves nothing.
        assert_eq!(placed[0].strength, peaks[0].strength);
        assert_eq!(s.placed(peaks.clone(), 0.0, 5.0, 10.0), peaks);
        let bare = AngularSpectrum::new(g, s.values().to_vec());
        assert_eq!(bare.placed(peaks.clone(), 0.5, 5.0, 10.0), peaks);
        // A DoA that was never the strongest direction of a block has no blocks of its
        // own: it stays where the pooling put it.
        let unvoted: Vec<Doa> = peaks
            .iter()
            .map(|d| Doa {
                dominant_blocks: 0,
                ..*d
            })
            .collect();
        assert_eq!(s.placed(unvoted.clone(), 0.5, 5.0, 10.0), unvoted);
    }

    #[test]
    fn a_doa_stays_where_its_window_holds_no_maximum_or_the_place_is_taken() {
        let g = DirectionGrid::new(1.0, ElevationRange::default()).unwrap();
        // The blocks peak 10 degrees from the DoA: beyond a 5-degree window, whose cells
        // lie on the bump's flank.
        let profiles = block_profiles(&g, &[vec![(40.0, 1.0)], vec![(40.0, 0.9)]]);
        let s = AngularSpectrum::new(g.clone(), vec![0.0; g.len()]).with_block_profiles(profiles);
        let placed = s.placed(vec![doa_at(30.0)], 1.0, 5.0, 10.0);
        assert_eq!(placed[0].azimuth_deg, 30.0);
        // A weaker DoA at 12 degrees whose blocks peak at 8 would come within 10 degrees
        // of the stronger one at 0: it stays.
        let profiles = block_profiles(&g, &[vec![(0.0, 1.0), (8.0, 0.6)]]);
        let s = AngularSpectrum::new(g.clone(), vec![0.0; g.len()]).with_block_profiles(profiles);
        let placed = s.placed(vec![doa_at(0.0), doa_at(12.0)], 1.0, 5.0, 10.0);
        assert!(placed[0].azimuth_deg.abs() < 0.2, "{placed:?}");
        assert_eq!(placed[1].azimuth_deg, 12.0);
        // With a separation of 5 degrees it moves.
        let placed = s.placed(vec![doa_at(0.0), doa_at(12.0)], 1.0, 5.0, 5.0);
        assert!((placed[1].azimuth_deg - 8.0).abs() < 0.5, "{placed:?}");
    }
}
