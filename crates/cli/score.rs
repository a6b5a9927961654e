//! The DoA score of a table against known sources: the share of the first N DoAs of each
//! recording whose world bearing lies within a tolerance of the bearing of a true source.
//!
//! A DoA `phi` (array frame) at pose `(x, y, theta)` has world bearing
//! `wrap(phi + theta)`; it is a hit when some source `s` has
//! `|wrap(bearing - atan2(s_y - y, s_x - x))| <= tol`. A missing DoA is a miss. The score is
//! hits / (N x recordings): 1 is perfect; a table of random bearings scores about the share
//! of the circle that the sources' tolerance windows cover.

use anyhow::{Result, ensure};
use asm::Pose;
use serde::Serialize;
use ssl::wrap_deg;

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

/// Scores the first `n` DoAs of every row of `doas` (degrees, array frame) heard at
/// `poses`, against `sources` (m).
///
/// # Errors
/// If the table and the poses differ in length, or nothing is to be scored.
pub fn score_doas(
    doas: &Table,
    poses: &[Pose],
    sources: &[[f64; 2]],
    n: usize,
    tol_deg: f64,
) -> Result<DoaScore> {
    ensure!(
        doas.len() == poses.len(),
        "the DoA table has {} rows but there are {} poses",
        doas.len(),
        poses.len()
    );
    ensure!(
        n > 0 && !poses.is_empty() && !sources.is_empty(),
        "nothing to score"
    );
    let (mut hits, mut err_sum) = (0usize, 0.0);
    for (row, pose) in doas.iter().zip(poses) {
        for az in row.iter().take(n).flatten() {
            let bearing = wrap_deg(az + pose.theta_deg());
            let best = sources
                .iter()
                .map(|s| {
                    let truth = (s[1] - pose.y).atan2(s[0] - pose.x).to_degrees();
                    wrap_deg(bearing - truth).abs()
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
        let s = score_doas(&doas, &poses, &sources, 4, 5.0).unwrap();
        // 3 -> hit (3 deg off); 84 -> miss (6 off); missing -> miss; -170 -> miss.
        assert_eq!((s.hits, s.total), (1, 4));
        assert!((s.score - 0.25).abs() < 1e-12);
        assert!((s.mean_hit_error_deg - 3.0).abs() < 1e-9);
        // Only the first N count.
        assert_eq!(score_doas(&doas, &poses, &sources, 1, 5.0).unwrap().hits, 1);
        assert_eq!(score_doas(&doas, &poses, &sources, 2, 6.5).unwrap().hits, 2);
    }

    #[test]
    fn bearings_wrap_across_180() {
        // Facing -x (theta 180); a source behind-left at (-5, -0.1): world bearing ~ -178.9.
        let poses = [Pose::from_degrees(0.0, 0.0, 180.0)];
        let doas = vec![vec![Some(2.0)]]; // world bearing 182 = -178
        let s = score_doas(&doas, &poses, &[[-5.0, -0.1]], 1, 5.0).unwrap();
        assert_eq!(s.hits, 1);
    }

    #[test]
    fn lengths_must_match() {
        let poses = [Pose::from_degrees(0.0, 0.0, 0.0)];
        assert!(score_doas(&vec![], &poses, &[[1.0, 0.0]], 4, 5.0).is_err());
    }
}
