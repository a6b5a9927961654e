//! The OSPA metric (Schuhmacher, Vo & Vo, 2008) between two finite sets of points.
//!
//! With cutoff `c` and order `p`, for sets `X` (`m` points) and `Y` (`n` points),
//! `m <= n` (else swap them):
//!
//! `d(X, Y) = ( (1/n) (min_pi sum_i min(c, |x_i - y_pi(i)|)^p + c^p (n - m)) )^(1/p)`.
//!
//! It splits into a localisation part (the assignment term) and a cardinality part (the
//! `c^p (n - m)` term); for `p = 1` they add up to the total. The optimal assignment is
//! found with the Hungarian algorithm, `O(n^2 m)`.
//!
//! The powers are taken of the distances relative to `c` (each in `[0, 1]`), and the
//! result is scaled by `c` at the end: `d = c ((1/n) (sum (d_c / c)^p + (n - m)))^(1/p)`,
//! the same figure, but one that cannot overflow whatever `c` and `p` are (`c^p` itself
//! overflows a double for `c = 10, p = 400`, and the assignment then never settles).

use serde::Serialize;

/// An OSPA distance and its parts (m).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Ospa {
    /// The OSPA distance.
    pub total: f64,
    /// `((1/n) min sum d_c^p)^(1/p)`: how far matched points are.
    pub localization: f64,
    /// `(c^p (n - m) / n)^(1/p)`: how many points are missing or extra.
    pub cardinality: f64,
}

/// Checks OSPA's parameters: a finite cutoff `c > 0` (m) and a finite order `p >= 1` (below
/// 1 the distance is not a metric). The commands and the Python bindings ask this before
/// [`ospa`].
///
/// # Errors
/// The refusal, naming both values.
pub fn check_params(c: f64, p: f64) -> Result<(), String> {
    if c.is_finite() && c > 0.0 && p.is_finite() && p >= 1.0 {
        Ok(())
    } else {
        Err(format!(
            "OSPA needs a finite cutoff c > 0 and a finite order p >= 1 (got c = {c}, p = {p})"
        ))
    }
}

/// OSPA between `est` and `truth` (either order gives the same), cutoff `c` (m), order `p`.
/// A coordinate that is not finite counts as a distance of `c`.
///
/// # Panics
/// If `c` or `p` is not finite and positive (a caller's bug: [`check_params`] says so
/// first).
pub fn ospa(est: &[[f64; 2]], truth: &[[f64; 2]], c: f64, p: f64) -> Ospa {
    assert!(
        c.is_finite() && c > 0.0 && p.is_finite() && p > 0.0,
        "OSPA needs finite c > 0 and p > 0"
    );
    let (x, y) = if est.len() <= truth.len() {
        (est, truth)
    } else {
        (truth, est)
    };
    let (m, n) = (x.len(), y.len());
    if n == 0 {
        return Ospa {
            total: 0.0,
            localization: 0.0,
            cardinality: 0.0,
        };
    }
    let cost: Vec<Vec<f64>> = x
        .iter()
        .map(|a| {
            y.iter()
                .map(|b| {
                    let d = (a[0] - b[0]).hypot(a[1] - b[1]);
                    // NaN (a coordinate that is not a number) is as far as anything can be.
                    let d = if d.is_nan() { c } else { d.min(c) };
                    (d / c).powf(p)
                })
                .collect()
        })
        .collect();
    let assigned = if m == 0 { 0.0 } else { min_assignment(&cost) };
    let card = (n - m) as f64;
    let nf = n as f64;
    Ospa {
        total: c * ((assigned + card) / nf).powf(1.0 / p),
        localization: c * (assigned / nf).powf(1.0 / p),
        cardinality: c * (card / nf).powf(1.0 / p),
    }
}

/// The pairs `(i, j)` of `est[i]` and `truth[j]` that OSPA's optimal assignment (each
/// distance capped at `c`, m) matches within `c` of each other: what a map found of the
/// truth, each at most once.
pub fn pairs(est: &[[f64; 2]], truth: &[[f64; 2]], c: f64) -> Vec<(usize, usize)> {
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    if est.is_empty() || truth.is_empty() {
        return Vec::new();
    }
    // Rows must not outnumber columns.
    let swapped = est.len() > truth.len();
    let (rows, cols) = if swapped { (truth, est) } else { (est, truth) };
    let cost: Vec<Vec<f64>> = rows
        .iter()
        .map(|&a| cols.iter().map(|&b| dist(a, b).min(c)).collect())
        .collect();
    assignment(&cost)
        .into_iter()
        .enumerate()
        .map(|(r, k)| if swapped { (k, r) } else { (r, k) })
        .filter(|&(i, j)| dist(est[i], truth[j]) < c)
        .collect()
}

/// The least total cost of assigning each row to a distinct column (`rows <= cols`):
/// the Hungarian algorithm with potentials.
pub fn min_assignment(cost: &[Vec<f64>]) -> f64 {
    assignment(cost)
        .iter()
        .enumerate()
        .map(|(i, &j)| cost[i][j])
        .sum()
}

/// The column assigned to each row by [`min_assignment`]'s optimal assignment.
pub fn assignment(cost: &[Vec<f64>]) -> Vec<usize> {
    let n = cost.len();
    let m = cost.first().map_or(0, Vec::len);
    assert!(n <= m, "rows must not outnumber columns");
    // 1-based arrays as in the classic formulation; p[j] = row matched to column j.
    let (mut u, mut v) = (vec![0.0; n + 1], vec![0.0; m + 1]);
    let (mut p, mut way) = (vec![0usize; m + 1], vec![0usize; m + 1]);
    for i in 1..=n {
        p[0] = i;
        let mut j0 = 0;
        let mut minv = vec![f64::INFINITY; m + 1];
        let mut used = vec![false; m + 1];
        loop {
            used[j0] = true;
            let i0 = p[j0];
            let mut delta = f64::INFINITY;
            let mut j1 = 0;
            for j in 1..=m {
                if !used[j] {
                    let cur = cost[i0 - 1][j - 1] - u[i0] - v[j];
                    if cur < minv[j] {
                        minv[j] = cur;
                        way[j] = j0;
                    }
                    if minv[j] < delta {
                        delta = minv[j];
                        j1 = j;
                    }
                }
            }
            for j in 0..=m {
                if used[j] {
                    u[p[j]] += delta;
                    v[j] -= delta;
                } else {
                    minv[j] -= delta;
                }
            }
            j0 = j1;
            if p[j0] == 0 {
                break;
            }
        }
        loop {
            let j1 = way[j0];
            p[j0] = p[j1];
            j0 = j1;
            if j0 == 0 {
                break;
            }
        }
    }
    let mut column = vec![0; n];
    for j in (1..=m).filter(|&j| p[j] != 0) {
        column[p[j] - 1] = j - 1;
    }
    column
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;
    use proptest::prelude::*;

    fn brute_force(cost: &[Vec<f64>]) -> f64 {
        fn go(cost: &[Vec<f64>], row: usize, used: &mut Vec<bool>) -> f64 {
            if row == cost.len() {
                return 0.0;
            }
            let mut best = f64::INFINITY;
            for j in 0..used.len() {
                if !used[j] {
                    used[j] = true;
                    best = best.min(cost[row][j] + go(cost, row + 1, used));
                    used[j] = false;
                }
            }
            best
        }
        go(cost, 0, &mut vec![false; cost[0].len()])
    }

    #[test]
    fn pairs_match_each_estimate_to_its_own_source_within_the_cutoff() {
        let truth = [[0.0, 0.0], [4.0, 0.0], [0.0, 4.0]];
        // One estimate near each of the first two sources (the second 0.5 m off), one far
        // from every source, and none for the third.
        let est = [[4.5, 0.0], [9.0, 9.0], [0.1, 0.0]];
        assert_eq!(pairs(&est, &truth, 1.0), [(0, 1), (2, 0)]);
        // Beyond a cutoff of 0.4 m the 0.5-m pair is no match; either order agrees.
        assert_eq!(pairs(&est, &truth, 0.4), [(2, 0)]);
        let mut back: Vec<(usize, usize)> = pairs(&truth, &est, 1.0)
            .into_iter()
            .map(|(j, i)| (i, j))
            .collect();
        back.sort_unstable();
        assert_eq!(back, [(0, 1), (2, 0)]);
        assert!(pairs(&[], &truth, 1.0).is_empty());
    }

    #[test]
    fn equal_sets_are_at_zero() {
        let s = [[1.0, 2.0], [3.0, -1.0], [0.0, 0.0]];
        let mut shuffled = s;
        shuffled.reverse();
        assert_eq!(ospa(&s, &shuffled, 1.0, 1.0).total, 0.0);
    }

    #[test]
    fn against_an_empty_set_it_is_c() {
        let s = [[1.0, 2.0], [3.0, -1.0]];
        let o = ospa(&[], &s, 1.0, 1.0);
        assert_eq!((o.total, o.localization, o.cardinality), (1.0, 0.0, 1.0));
        assert_eq!(ospa(&s, &[], 2.5, 2.0).total, 2.5);
        assert_eq!(ospa(&[], &[], 1.0, 1.0).total, 0.0);
    }

    #[test]
    fn hand_worked_example() {
        // Truth: (0,0), (4,0). Estimates: (0.3,0.4) [0.5 from the first], (4,0.2) [0.2],
        // (9,9) [extra]. p = 1, c = 1: (0.5 + 0.2 + 1 * 1) / 3 = 0.5667.
        let truth = [[0.0, 0.0], [4.0, 0.0]];
        let est = [[0.3, 0.4], [4.0, 0.2], [9.0, 9.0]];
        let o = ospa(&est, &truth, 1.0, 1.0);
        assert_abs_diff_eq!(o.total, 1.7 / 3.0, epsilon = 1e-12);
        assert_abs_diff_eq!(o.localization, 0.7 / 3.0, epsilon = 1e-12);
        assert_abs_diff_eq!(o.cardinality, 1.0 / 3.0, epsilon = 1e-12);
        // p = 2: sqrt((0.25 + 0.04 + 1) / 3).
        assert_abs_diff_eq!(
            ospa(&est, &truth, 1.0, 2.0).total,
            (1.29f64 / 3.0).sqrt(),
            epsilon = 1e-12
        );
        // A far miss costs at most c.
        let o = ospa(&[[50.0, 0.0]], &[[0.0, 0.0]], 1.0, 1.0);
        assert_eq!(o.total, 1.0);
    }

    /// Parameters whose `c^p` overflows a double give the figure the definition gives,
    /// in finite time: one miss of 50 m at c = 100, p = 200 is 50 m; equal sets at c = 10,
    /// p = 400 are at 0; a miss as large as c (1e160) at p = 2 is c.
    #[test]
    fn powers_beyond_a_double_do_not_overflow() {
        assert_abs_diff_eq!(
            ospa(&[[50.0, 0.0]], &[[0.0, 0.0]], 100.0, 200.0).total,
            50.0,
            epsilon = 1e-9
        );
        assert_eq!(ospa(&[[0.0, 0.0]], &[[0.0, 0.0]], 10.0, 400.0).total, 0.0);
        let o = ospa(&[[1e160, 0.0]], &[[0.0, 0.0]], 1e160, 2.0);
        assert_abs_diff_eq!(o.total / 1e160, 1.0, epsilon = 1e-12);
        // Two misses of 3 and 4 m and a missing point, c = 10, p = 300: the largest term
        // is the cardinality's, (1/3)^(1/300) c.
        let o = ospa(&[[3.0, 0.0], [0.0, 4.0]], &[[0.0, 0.0]; 3], 10.0, 300.0);
        assert!(
            o.total.is_finite() && o.total > 9.9 && o.total <= 10.0,
            "{o:?}"
        );
        assert!(check_params(10.0, 400.0).is_ok());
        for (c, p) in [
            (f64::NAN, 1.0),
            (f64::INFINITY, 1.0),
            (0.0, 1.0),
            (1.0, 0.5),
            (1.0, f64::INFINITY),
        ] {
            assert!(check_params(c, p).is_err(), "c = {c}, p = {p}");
        }
    }

    #[test]
    fn a_greedy_match_is_not_optimal_but_hungarian_is() {
        // Greedy takes (0,0)-(0,0) then pays 0.9; optimal pays 0.5 + 0.5.
        let cost = vec![vec![0.0, 0.5], vec![0.5, 0.9]];
        assert_abs_diff_eq!(min_assignment(&cost), 0.9, epsilon = 1e-12);
        let cost = vec![vec![0.1, 0.5], vec![0.2, 0.9]];
        assert_abs_diff_eq!(min_assignment(&cost), 0.7, epsilon = 1e-12);
    }

    fn points(n: usize) -> impl Strategy<Value = Vec<[f64; 2]>> {
        prop::collection::vec((-3.0f64..3.0, -3.0f64..3.0).prop_map(|(x, y)| [x, y]), 0..n)
    }

    proptest! {
        #[test]
        fn hungarian_matches_brute_force(rows in 1usize..6, extra in 0usize..3, seed in prop::collection::vec(0.0f64..2.0, 48)) {
            let cols = rows + extra;
            let cost: Vec<Vec<f64>> = (0..rows).map(|i| (0..cols).map(|j| seed[(i * cols + j) % 48]).collect()).collect();
            prop_assert!((min_assignment(&cost) - brute_force(&cost)).abs() < 1e-9);
        }

        #[test]
        fn ospa_is_a_metric_bounded_by_c(a in points(6), b in points(6), z in points(6)) {
            let d = |x: &[[f64; 2]], y: &[[f64; 2]]| ospa(x, y, 1.0, 1.0).total;
            prop_assert!((d(&a, &b) - d(&b, &a)).abs() < 1e-12);
            prop_assert!((0.0..=1.0 + 1e-12).contains(&d(&a, &b)));
            prop_assert!(d(&a, &z) <= d(&a, &b) + d(&b, &z) + 1e-9);
        }
    }
}
