//! Implicit association (step 4 of the paper's Algorithm 1): which DoAs a new source
//! explains.
//!
//! I-ASM never labels DoAs before mapping. Once a filtering round has placed a source, the
//! paper's rule decides which DoAs it accounts for: **at every stop, the one remaining DoA
//! whose world bearing is nearest the bearing from that stop to the source is explained by
//! it, if the two differ by less than `gamma`** (three DoA standard deviations). Explained
//! DoAs are removed, so the next round's particle filter sees only what is still
//! unexplained. At most one DoA per stop is taken: an array hears a point source from one
//! direction.
//!
//! Angle differences are wrapped to `(-pi, pi]`, so a DoA at +179 degrees explains a source
//! at -179 degrees (the authors' code compares unwrapped angles and misses that case).
//!
//! DoAs of a linear array come in mirror pairs ([`associate_mirrored`]): a row holds each
//! DoA and its mirror image in the array's line, and a source that takes one takes both,
//! since they are one peak heard twice.

use crate::Pose;
use crate::wrap_rad;

/// A DoA explained by a source: where it was heard and its world bearing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// The stop (index into the poses).
    pub stop: usize,
    /// The robot's position there (m).
    pub from: [f64; 2],
    /// The DoA's world bearing (rad).
    pub bearing: f64,
    /// For a linear array's DoA, its mirror image's world bearing (rad), taken out of the
    /// row with it ([`associate_mirrored`]).
    pub twin: Option<f64>,
    /// Whether the DoA is another source's too: the vote lets a DoA that a source already
    /// explains support a second one that lies as nearly on it (see
    /// `IasmConfig::share_rate`). It stays with the first: never given back. Where the first
    /// is removed and gives it back, it is this one's own once the rules are done (no
    /// longer shared, out of the unexplained).
    pub shared: bool,
}

impl Ray {
    /// The wrapped angle (rad, `>= 0`) between this ray and the bearing from its stop to
    /// `point`.
    pub fn miss(&self, point: [f64; 2]) -> f64 {
        let to = (point[1] - self.from[1]).atan2(point[0] - self.from[0]);
        wrap_rad(to - self.bearing).abs()
    }

    /// Puts the DoA (and its mirror image, if any) back into its stop's row of `bearings`:
    /// a source that no longer holds it gives it back for the others.
    pub fn give_back(&self, bearings: &mut [Vec<f64>]) {
        if self.shared {
            return;
        }
        bearings[self.stop].push(self.bearing);
        bearings[self.stop].extend(self.twin);
    }

    /// Takes the DoA (and its mirror image, if any) out of its stop's row of `bearings`,
    /// where no source held it ([`Ray::give_back`] undone): whether it was there.
    pub fn take_from(&self, bearings: &mut [Vec<f64>]) -> bool {
        let row = &mut bearings[self.stop];
        let Some(n) = row.iter().position(|&b| b == self.bearing) else {
            return false;
        };
        row.swap_remove(n);
        if let Some(n) = self.twin.and_then(|t| row.iter().position(|&b| b == t)) {
            row.swap_remove(n);
        }
        true
    }
}

/// The world bearing of the mirror image of the DoA at world bearing `bearing`, heard at
/// `pose` by a linear array whose line lies at azimuth `axis` (rad, array frame):
/// `2 (theta + axis) - bearing`. `None` when the two coincide (a DoA along the line).
pub fn mirror_bearing(pose: &Pose, bearing: f64, axis: f64) -> Option<f64> {
    let twin = wrap_rad(2.0 * (pose.theta + axis) - bearing);
    (wrap_rad(twin - bearing).abs() > TWIN_TOL).then_some(twin)
}

/// The DoA of `row` (world bearings, rad) nearest `bearing`: its index and the wrapped
/// angle between them (rad, `>= 0`), the first of equals; `None` for an empty row.
pub(crate) fn nearest(row: &[f64], bearing: f64) -> Option<(usize, f64)> {
    row.iter()
        .enumerate()
        .map(|(n, &b)| (n, wrap_rad(bearing - b).abs()))
        .min_by(|a, b| a.1.total_cmp(&b.1))
}

/// A bearing within this (rad) of a DoA's computed mirror image is that image.
const TWIN_TOL: f64 = 1e-9;

/// Removes from `bearings` (per stop, world frame, rad) every DoA that a source at
/// `source` explains under the paper's rule (see the module docs), and returns them as
/// rays, in stop order.
///
/// # Panics
/// If `poses` and `bearings` differ in length (the mapper checks its inputs first).
pub fn associate(
    source: [f64; 2],
    poses: &[Pose],
    bearings: &mut [Vec<f64>],
    gamma: f64,
) -> Vec<Ray> {
    associate_mirrored(source, poses, bearings, gamma, None)
}

/// [`associate`] for DoAs that may come in mirror pairs: with `axis` (a linear array's line,
/// rad, array frame; see [`mirror_bearing`]), the DoA explained at a stop takes its mirror
/// image out of the row too, into [`Ray::twin`].
///
/// # Panics
/// As [`associate`].
pub fn associate_mirrored(
    source: [f64; 2],
    poses: &[Pose],
    bearings: &mut [Vec<f64>],
    gamma: f64,
    axis: Option<f64>,
) -> Vec<Ray> {
    assert_eq!(poses.len(), bearings.len(), "one row of bearings per pose");
    let mut rays = Vec::new();
    for (stop, (p, row)) in poses.iter().zip(bearings.iter_mut()).enumerate() {
        if let Some((n, d)) = nearest(row, p.bearing_to(source))
            && d < gamma
        {
            let bearing = row.remove(n);
            let twin = axis
                .and_then(|a| mirror_bearing(p, bearing, a))
                .and_then(|t| row.iter().position(|&b| wrap_rad(b - t).abs() <= TWIN_TOL))
                .map(|i| row.remove(i));
            rays.push(Ray {
                stop,
                from: p.position(),
                bearing,
                twin,
                shared: false,
            });
        }
    }
    rays
}

#[cfg(test)]
mod tests {
    use super::*;

    const GAMMA: f64 = 15.0 * std::f64::consts::PI / 180.0;

    fn deg(d: f64) -> f64 {
        d.to_radians()
    }

    #[test]
    fn the_nearest_doa_within_gamma_is_taken_at_each_stop() {
        // Source at (2, 2). From the origin its bearing is 45 deg; from (4, 0) it is 135 deg.
        let poses = [Pose::new(0.0, 0.0, 0.0), Pose::new(4.0, 0.0, 1.0)];
        let mut b = vec![
            vec![deg(-90.0), deg(50.0), deg(40.5)],
            vec![deg(140.0), deg(0.0)],
        ];
        let rays = associate([2.0, 2.0], &poses, &mut b, GAMMA);
        let got: Vec<(usize, [f64; 2], f64)> =
            rays.iter().map(|r| (r.stop, r.from, r.bearing)).collect();
        assert_eq!(
            got,
            vec![(0, [0.0, 0.0], deg(40.5)), (1, [4.0, 0.0], deg(140.0))]
        );
        // The others stay for the next round, in their order.
        assert_eq!(b, vec![vec![deg(-90.0), deg(50.0)], vec![deg(0.0)]]);
    }

    #[test]
    fn one_doa_per_stop_at_most() {
        // Two DoAs both within gamma of the source: only the nearer one is explained.
        let poses = [Pose::new(0.0, 0.0, 0.0)];
        let mut b = vec![vec![deg(3.0), deg(-1.0)]];
        let rays = associate([5.0, 0.0], &poses, &mut b, GAMMA);
        assert_eq!(rays.len(), 1);
        assert_eq!(rays[0].bearing, deg(-1.0));
        assert_eq!(b, vec![vec![deg(3.0)]]);
    }

    #[test]
    fn a_doa_at_or_beyond_gamma_is_not_explained() {
        let poses = [Pose::new(0.0, 0.0, 0.0)];
        let mut b = [vec![GAMMA], vec![]];
        assert!(associate([5.0, 0.0], &poses, &mut b[..1], GAMMA).is_empty());
        assert_eq!(b[0], vec![GAMMA]);
        // A stop with no DoA left explains nothing.
        assert!(associate([5.0, 0.0], &poses, &mut b[1..], GAMMA).is_empty());
    }

    #[test]
    fn a_linear_arrays_doa_takes_its_mirror_image_with_it() {
        // A line along the heading (axis 0), robot heading 90 degrees at the origin: a DoA
        // at world bearing 45 degrees (array frame -45) has its mirror at 2 * 90 - 45 =
        // 135 degrees. A source at (1, 1) takes the first and its mirror; the other DoA
        // (-30 degrees) and its own mirror (210 = -150 degrees) stay.
        let poses = [Pose::new(0.0, 0.0, deg(90.0))];
        let twin = |b: f64| mirror_bearing(&poses[0], deg(b), 0.0).unwrap();
        assert!((twin(45.0) - deg(135.0)).abs() < 1e-12);
        let mut b = vec![vec![deg(45.0), twin(45.0), deg(-30.0), twin(-30.0)]];
        let rays = associate_mirrored([1.0, 1.0], &poses, &mut b, GAMMA, Some(0.0));
        assert_eq!(rays.len(), 1);
        assert_eq!(
            (rays[0].bearing, rays[0].twin),
            (deg(45.0), Some(twin(45.0)))
        );
        assert_eq!(b[0], vec![deg(-30.0), twin(-30.0)]);
        // Given back, both return.
        rays[0].give_back(&mut b);
        assert_eq!(b[0].len(), 4);
        // A DoA along the line is its own mirror image.
        assert_eq!(mirror_bearing(&poses[0], deg(90.0), 0.0), None);
    }

    #[test]
    fn differences_wrap_across_180_degrees() {
        // Source behind the robot at bearing -179 deg; the DoA says +179 deg: 2 deg apart.
        let poses = [Pose::new(0.0, 0.0, 0.0)];
        let src = [(-179f64).to_radians().cos(), (-179f64).to_radians().sin()];
        let mut b = vec![vec![deg(179.0)]];
        assert_eq!(associate(src, &poses, &mut b, GAMMA).len(), 1);
    }
}
