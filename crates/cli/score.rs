//! The DoA score of a table against known sources: the share of the first N DoAs of each
//! recording whose world bearing lies within a tolerance of the bearing of a true source.
//!
//! A DoA `phi` (array frame) at pose `(x, y, theta)` has world bearing
//! `wrap(phi + theta)`; it is a hit when some source `s` has
//! `|wrap(bearing - atan2(s_y - y, s_x - x))| <= tol`. A missing DoA is a miss. The score is
//! hits / (N x recordings): 1 is perfect; a table of random bearings scores about the share
//! of the circle that the sources' tolerance windows cover.
//!
//! For a linear array (`mirror_axis_deg`: its line's azimuth, [`ssl::MicArray::mirror_axis_deg`])
//! a DoA and its mirror image in the line are one: both the DoA and the truth are folded to
//! one side of the line ([`ssl::fold_azimuth`]) before they are compared.

use anyhow::{Result, ensure};
use asm::Pose;
use serde::Serialize;
use ssl::{fold_azimuth, wrap_deg};

use crate::dataset::Table;

/// The score of one DoA table.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DoaScore {
    /// DoAs within tolerance of a source.
    pub hits: usize,
    /// N x recordings.
    pub total: usize,
    /// hits / total.
    pub score: f64,
    /// Mean absolute bearing error of the hits (degrees).
    pub mean_hit_error_deg: f64,
}

fn same_length(doas: &Table, poses: &[Pose]) -> Result<()> {
    ensure!(
        doas.len() == poses.len(),
        "the DoA table has {} rows but there are {} poses",
        doas.len(),
        poses.len()
    );
    Ok(())
}

/// Scores the first `n` DoAs of every row of `doas` (degrees, array frame) heard at
/// `poses`, against `sources` (m); for a linear array at `mirror_axis_deg`, folded (see
/// the module docs).
///
/// # Errors
/// If the table and the poses differ in length, or nothing is to be scored.
pub fn score_doas(
    doas: &Table,
    poses: &[Pose],
    sources: &[[f64; 2]],
    n: usize,
    tol_deg: f64,
    mirror_axis_deg: Option<f64>,
) -> Result<DoaScore> {
    same_length(doas, poses)?;
    ensure!(
        n > 0 && !poses.is_empty() && !sources.is_empty(),
        "nothing to score"
    );
    let (mut hits, mut err_sum) = (0usize, 0.0);
    for (row, pose) in doas.iter().zip(poses) {
        for &az in row.iter().take(n).flatten() {
            let az = fold_azimuth(az, mirror_axis_deg);
            let best = sources
                .iter()
                .map(|s| {
                    let truth = pose.bearing_to(*s).to_degrees() - pose.theta_deg();
                    wrap_deg(az - fold_azimuth(truth, mirror_axis_deg)).abs()
                })
                .fold(f64::INFINITY, f64::min);
            if best <= tol_deg {
                hits += 1;
                err_sum += best;
            }
        }
    }
    let total = n * poses.len();
    Ok(DoaScore {
        hits,
        total,
        score: hits as f64 / total as f64,
        mean_hit_error_deg: if hits > 0 {
            err_sum / hits as f64
        } else {
            f64::NAN
        },
    })
}

/// Upper edges (m) of the distance bands of [`diagnose`]; the last band is open.
pub const BAND_EDGES_M: [f64; 4] = [1.0, 1.5, 2.5, 4.0];

/// The errors of the DoAs attributed to sources in one band of distance from the robot.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BandStats {
    /// The band, in words (`"1-1.5 m"`).
    pub band: String,
    /// DoAs attributed to a source at this distance.
    pub doas: usize,
    /// Their mean absolute error (degrees).
    pub mean_abs_err_deg: f64,
    /// Their median absolute error (degrees).
    pub median_abs_err_deg: f64,
    /// Their mean signed error towards the array's x axis (degrees): positive when the DoA
    /// lies closer to the heading axis (0 or 180 degrees) than the true bearing, the way a
    /// source's elevation bends the azimuth of a search in the plane.
    pub axis_bias_deg: f64,
}

/// Where DoAs fail: errors by the source's distance, and recall of near sources.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Diagnostics {
    /// A DoA is attributed to the source whose bearing is nearest, if within this.
    pub match_deg: f64,
    /// Errors by distance band, nearest first.
    pub bands: Vec<BandStats>,
    /// (stop, source within 3 m) pairs.
    pub near_pairs: usize,
    /// The share of those pairs in which some DoA of the stop lies within `tol_deg` of the
    /// source's bearing.
    pub recall_3m: f64,
}

/// Diagnoses the first `n` DoAs of every row of `doas` (degrees, array frame) heard at
/// `poses` against `sources` (m): each DoA is attributed to the source of nearest bearing
/// if within `match_deg`, and its error filed under that source's distance; recall counts
/// sources within 3 m found within `tol_deg`; for a linear array at `mirror_axis_deg`,
/// folded (see the module docs).
///
/// # Errors
/// As [`score_doas`].
pub fn diagnose(
    doas: &Table,
    poses: &[Pose],
    sources: &[[f64; 2]],
    n: usize,
    match_deg: f64,
    tol_deg: f64,
    mirror_axis_deg: Option<f64>,
) -> Result<Diagnostics> {
    same_length(doas, poses)?;
    let axis_dist = |a: f64| {
        let a = wrap_deg(a).abs();
        a.min(180.0 - a)
    };
    let mut errs: Vec<Vec<(f64, f64)>> = vec![Vec::new(); BAND_EDGES_M.len() + 1];
    let (mut near, mut found) = (0usize, 0usize);
    for (row, pose) in doas.iter().zip(poses) {
        let truth: Vec<(f64, f64)> = sources
            .iter()
            .map(|s| {
                let world = pose.bearing_to(*s).to_degrees();
                let dist = (s[0] - pose.x).hypot(s[1] - pose.y);
                let az = fold_azimuth(world - pose.theta_deg(), mirror_axis_deg);
                (wrap_deg(az), dist)
            })
            .collect();
        let azs: Vec<f64> = row
            .iter()
            .take(n)
            .flatten()
            .map(|&az| fold_azimuth(az, mirror_axis_deg))
            .collect();
        for &az in &azs {
            let Some(&(t, dist)) = truth.iter().min_by(|a, b| {
                wrap_deg(az - a.0)
                    .abs()
                    .total_cmp(&wrap_deg(az - b.0).abs())
            }) else {
                continue;
            };
            let e = wrap_deg(az - t);
            if e.abs() <= match_deg {
                let band = BAND_EDGES_M
                    .iter()
                    .take_while(|&&edge| dist >= edge)
                    .count();
                errs[band].push((e.abs(), axis_dist(t) - axis_dist(az)));
            }
        }
        for &(t, dist) in &truth {
            if dist < 3.0 {
                near += 1;
                found += usize::from(azs.iter().any(|&az| wrap_deg(az - t).abs() <= tol_deg));
            }
        }
    }
    let bands = errs
        .into_iter()
        .enumerate()
        .map(|(i, mut v)| {
            let lo = if i == 0 { 0.0 } else { BAND_EDGES_M[i - 1] };
            let band = match BAND_EDGES_M.get(i) {
                Some(hi) => format!("{lo}-{hi} m"),
                None => format!(">= {lo} m"),
            };
            let k = v.len();
            v.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mean = |f: fn(&(f64, f64)) -> f64| {
                if k == 0 {
                    f64::NAN
                } else {
                    v.iter().map(f).sum::<f64>() / k as f64
                }
            };
            BandStats {
                band,
                doas: k,
                mean_abs_err_deg: mean(|e| e.0),
                median_abs_err_deg: if k == 0 { f64::NAN } else { v[k / 2].0 },
                axis_bias_deg: mean(|e| e.1),
            }
        })
        .collect();
    Ok(Diagnostics {
        match_deg,
        bands,
        near_pairs: near,
        recall_3m: if near > 0 {
            found as f64 / near as f64
        } else {
            f64::NAN
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hand_worked_score() {
        // Robot at the origin facing +y (theta 90). A source at (0, 5) is dead ahead:
        // azimuth 0 in the array frame. One at (-5, 0) is at azimuth +90.
        let poses = [Pose::from_degrees(0.0, 0.0, 90.0)];
        let sources = [[0.0, 5.0], [-5.0, 0.0]];
        let doas = vec![vec![Some(3.0), Some(84.0), None, Some(-170.0)]];
        let s = score_doas(&doas, &poses, &sources, 4, 5.0, None).unwrap();
        // 3 -> hit (3 deg off); 84 -> miss (6 off); missing -> miss; -170 -> miss.
        assert_eq!((s.hits, s.total), (1, 4));
        assert!((s.score - 0.25).abs() < 1e-12);
        assert!((s.mean_hit_error_deg - 3.0).abs() < 1e-9);
        // Only the first N count.
        assert_eq!(
            score_doas(&doas, &poses, &sources, 1, 5.0, None)
                .unwrap()
                .hits,
            1
        );
        assert_eq!(
            score_doas(&doas, &poses, &sources, 2, 6.5, None)
                .unwrap()
                .hits,
            2
        );
    }

    #[test]
    fn a_linear_arrays_doa_hits_a_source_on_either_side_of_its_line() {
        // Facing +x, a line along the heading (axis 0): a source at (3, -3) (azimuth -45)
        // is heard at +45, its mirror image. Folded, it is a hit; without the axis, a miss.
        let poses = [Pose::from_degrees(0.0, 0.0, 0.0)];
        let doas = vec![vec![Some(45.0)]];
        let sources = [[3.0, -3.0]];
        assert_eq!(
            score_doas(&doas, &poses, &sources, 1, 5.0, Some(0.0))
                .unwrap()
                .hits,
            1
        );
        assert_eq!(
            score_doas(&doas, &poses, &sources, 1, 5.0, None)
                .unwrap()
                .hits,
            0
        );
        let d = diagnose(&doas, &poses, &sources, 1, 10.0, 5.0, Some(0.0)).unwrap();
        // 4.24 m away: the last band, and no pair within 3 m.
        assert_eq!((d.bands[4].doas, d.near_pairs), (1, 0));
        assert!(d.bands[4].mean_abs_err_deg < 1e-9);
    }

    #[test]
    fn bearings_wrap_across_180() {
        // Facing -x (theta 180); a source behind-left at (-5, -0.1): world bearing ~ -178.9.
        let poses = [Pose::from_degrees(0.0, 0.0, 180.0)];
        let doas = vec![vec![Some(2.0)]]; // world bearing 182 = -178
        let s = score_doas(&doas, &poses, &[[-5.0, -0.1]], 1, 5.0, None).unwrap();
        assert_eq!(s.hits, 1);
    }

    #[test]
    fn diagnostics_file_errors_by_distance_and_count_near_recall() {
        // Robot at the origin facing +x. A source at (0.8, 0.8) (1.13 m, bearing 45) and
        // one at (-3, 0) (3 m, bearing 180). DoAs: 48 (3 off the near one and 3 further
        // from the heading axis: axis bias -3), -178 (2 off the far one, 2 further from the
        // axis: -2), and -90 (no source within 10 degrees: not attributed).
        let poses = [Pose::from_degrees(0.0, 0.0, 0.0)];
        let sources = [[0.8, 0.8], [-3.0, 0.0]];
        let doas = vec![vec![Some(48.0), Some(-178.0), Some(-90.0)]];
        let d = diagnose(&doas, &poses, &sources, 3, 10.0, 5.0, None).unwrap();
        let b: Vec<(usize, f64, f64)> = d
            .bands
            .iter()
            .map(|b| (b.doas, b.mean_abs_err_deg, b.axis_bias_deg))
            .collect();
        assert_eq!(b[0].0, 0);
        assert_eq!(b[1].0, 1); // 1-1.5 m
        assert!(
            (b[1].1 - 3.0).abs() < 1e-9 && (b[1].2 + 3.0).abs() < 1e-9,
            "{b:?}"
        );
        assert_eq!(b[3].0, 1); // 2.5-4 m
        assert!(
            (b[3].1 - 2.0).abs() < 1e-9 && (b[3].2 + 2.0).abs() < 1e-9,
            "{b:?}"
        );
        // Only the near source is within 3 m (the far one is at exactly 3 m), and a DoA
        // 3 degrees off finds it.
        assert_eq!((d.near_pairs, d.recall_3m), (1, 1.0));
        let d = diagnose(&doas, &poses, &sources, 3, 10.0, 2.0, None).unwrap();
        assert_eq!(d.recall_3m, 0.0);
    }

    #[test]
    fn lengths_must_match() {
        let poses = [Pose::from_degrees(0.0, 0.0, 0.0)];
        assert!(score_doas(&vec![], &poses, &[[1.0, 0.0]], 4, 5.0, None).is_err());
    }
}
