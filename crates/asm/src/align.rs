//! How far a map lies from the truth once their frames agree: the least-squares similarity
//! transform (scale, rotation, shift) of the estimates onto the true positions they match.
//!
//! A map is built in the frame of the robot's poses and scored against positions surveyed
//! in another. Where the two frames disagree (a localisation map a few percent off scale, a
//! rotated survey, an offset origin), every source moves by the same transform, and the
//! OSPA counts that as localisation error that no front end or mapper can remove. Fitting
//! the four parameters of a similarity to the matched pairs and measuring what is left
//! separates the two: on the authors' arrangement II recordings the maps from our DoAs and
//! from the authors' own tables all need the same transform (scale 1.05, rotation -1.5 to
//! -2.3 degrees, shift about 0.12 m) and agree with the truth to 0.03-0.05 m after it,
//! against 0.155-0.21 before. It is a diagnostic of the data, never a
//! correction of the map: the transform is fitted to the truth.
//!
//! In 2-D the fit has a closed form: with the centred estimates `a_i` and true positions
//! `b_i` written as complex numbers, `z = sum conj(a_i) b_i / sum |a_i|^2` is the scale
//! times the rotation (Umeyama 1991, specialised to the plane).

use serde::Serialize;

/// A similarity transform of a map onto the truth and what it leaves.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Alignment {
    /// Scale factor applied to the map.
    pub scale: f64,
    /// Rotation applied to the map (rad, counter-clockwise).
    pub rotation_rad: f64,
    /// Shift applied after scaling and rotating (m).
    pub shift: [f64; 2],
    /// Matched pairs the transform was fitted to.
    pub pairs: usize,
    /// Mean distance between the matched pairs before the transform (m).
    pub mean_before_m: f64,
    /// Mean distance between the matched pairs after it (m).
    pub mean_after_m: f64,
}

impl Alignment {
    /// Where the inverse transform takes a true position: the truth in the map's frame.
    pub fn invert(&self, q: [f64; 2]) -> [f64; 2] {
        let (s, c) = self.rotation_rad.sin_cos();
        let (x, y) = (q[0] - self.shift[0], q[1] - self.shift[1]);
        [(c * x + s * y) / self.scale, (-s * x + c * y) / self.scale]
    }

    /// Where the transform takes a map position.
    pub fn apply(&self, p: [f64; 2]) -> [f64; 2] {
        let (s, c) = self.rotation_rad.sin_cos();
        let k = self.scale;
        [
            k * (c * p[0] - s * p[1]) + self.shift[0],
            k * (s * p[0] + c * p[1]) + self.shift[1],
        ]
    }
}

/// The least-squares similarity of `est` onto `truth`, fitted to the pairs of OSPA's
/// optimal assignment that lie within `c` (m) of each other; `None` with fewer than three
/// such pairs (two pairs fix a similarity exactly and would always leave nothing).
///
/// # Panics
/// If `c` is not positive.
pub fn align(est: &[[f64; 2]], truth: &[[f64; 2]], c: f64) -> Option<Alignment> {
    assert!(c > 0.0, "the matching cutoff must be positive");
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let pairs: Vec<([f64; 2], [f64; 2])> = crate::ospa::pairs(est, truth, c)
        .into_iter()
        .map(|(i, j)| (est[i], truth[j]))
        .collect();
    if pairs.len() < 3 {
        return None;
    }
    let n = pairs.len() as f64;
    let (me, mt) = pairs
        .iter()
        .fold(([0.0, 0.0], [0.0, 0.0]), |(a, b), (e, t)| {
            (
                [a[0] + e[0] / n, a[1] + e[1] / n],
                [b[0] + t[0] / n, b[1] + t[1] / n],
            )
        });
    // z = sum conj(a) b / sum |a|^2, a and b centred.
    let (mut re, mut im, mut norm) = (0.0, 0.0, 0.0);
    for (e, t) in &pairs {
        let a = [e[0] - me[0], e[1] - me[1]];
        let b = [t[0] - mt[0], t[1] - mt[1]];
        re += a[0] * b[0] + a[1] * b[1];
        im += a[0] * b[1] - a[1] * b[0];
        norm += a[0] * a[0] + a[1] * a[1];
    }
    if norm <= 0.0 {
        return None;
    }
    let (zr, zi) = (re / norm, im / norm);
    let mut fit = Alignment {
        scale: zr.hypot(zi),
        rotation_rad: zi.atan2(zr),
        shift: [0.0, 0.0],
        pairs: pairs.len(),
        mean_before_m: pairs.iter().map(|&(e, t)| dist(e, t)).sum::<f64>() / n,
        mean_after_m: 0.0,
    };
    let moved = fit.apply(me);
    fit.shift = [mt[0] - moved[0], mt[1] - moved[1]];
    fit.mean_after_m = pairs
        .iter()
        .map(|&(e, t)| dist(fit.apply(e), t))
        .sum::<f64>()
        / n;
    Some(fit)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;

    const TRUTH: [[f64; 2]; 6] = [
        [1.25, 0.6],
        [1.25, -0.6],
        [2.5, 0.6],
        [3.74, -0.6],
        [4.99, 0.6],
        [6.23, -0.6],
    ];

    #[test]
    fn a_map_in_a_scaled_rotated_shifted_frame_is_brought_back_exactly() {
        // The truth seen through a frame 5 % small, turned 2 degrees, shifted: the fit
        // recovers the inverse transform and leaves nothing.
        let (k, r, t) = (0.95f64, 2f64.to_radians(), [-0.05, 0.11]);
        let est: Vec<[f64; 2]> = TRUTH
            .iter()
            .map(|p| {
                let (s, c) = r.sin_cos();
                [
                    k * (c * p[0] - s * p[1]) + t[0],
                    k * (s * p[0] + c * p[1]) + t[1],
                ]
            })
            .collect();
        let fit = align(&est, &TRUTH, 1.0).unwrap();
        assert_abs_diff_eq!(fit.scale, 1.0 / k, epsilon = 1e-12);
        assert_abs_diff_eq!(fit.rotation_rad, -r, epsilon = 1e-12);
        assert_eq!(fit.pairs, 6);
        assert!(fit.mean_before_m > 0.1, "{fit:?}");
        assert_abs_diff_eq!(fit.mean_after_m, 0.0, epsilon = 1e-12);
        for (e, p) in est.iter().zip(&TRUTH) {
            let (q, back) = (fit.apply(*e), fit.invert(*p));
            assert_abs_diff_eq!(q[0], p[0], epsilon = 1e-12);
            assert_abs_diff_eq!(q[1], p[1], epsilon = 1e-12);
            assert_abs_diff_eq!(back[0], e[0], epsilon = 1e-12);
            assert_abs_diff_eq!(back[1], e[1], epsilon = 1e-12);
        }
    }

    #[test]
    fn a_ghost_and_a_missed_source_do_not_enter_the_fit() {
        // Estimates at the truth but one missing and a ghost 3 m from everything: the
        // identity, fitted to the five matched pairs.
        let mut est: Vec<[f64; 2]> = TRUTH[1..].to_vec();
        est.push([3.0, 4.0]);
        let fit = align(&est, &TRUTH, 1.0).unwrap();
        assert_eq!(fit.pairs, 5);
        assert_abs_diff_eq!(fit.scale, 1.0, epsilon = 1e-12);
        assert_abs_diff_eq!(fit.mean_after_m, 0.0, epsilon = 1e-12);
    }

    #[test]
    fn two_pairs_prove_nothing() {
        assert!(align(&TRUTH[..2], &TRUTH[..2], 1.0).is_none());
        assert!(align(&[], &TRUTH, 1.0).is_none());
    }
}
