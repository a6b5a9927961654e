use std::collections::HashMap;

use super::Label;

/// Labels `points` with DBSCAN(`eps`, `min_pts`); see the module docs for the method.
///
/// # Panics
/// If `eps` is not positive (use [`super::DbscanParams::check`] to validate first).
pub fn dbscan(points: &[[f64; 2]], eps: f64, min_pts: usize) -> Vec<Label> {
    assert!(eps > 0.0, "eps must be positive");
    let n = points.len();
    let side = eps / std::f64::consts::SQRT_2;
    let key = |p: &[f64; 2]| ((p[0] / side).floor() as i64, (p[1] / side).floor() as i64);
    let mut cells: HashMap<(i64, i64), Vec<u32>> = HashMap::new();
    for (i, p) in points.iter().enumerate() {
        cells.entry(key(p)).or_default().push(i as u32);
    }
    let eps2 = eps * eps;
    let near = |a: usize, b: usize| {
        let (p, q) = (points[a], points[b]);
        (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) <= eps2
    };
    let around =
        |k: (i64, i64)| (-2..=2).flat_map(move |dx| (-2..=2).map(move |dy| (k.0 + dx, k.1 + dy)));

    // 1. Core points.
    let mut core = vec![false; n];
    for (&k, members) in &cells {
        if members.len() >= min_pts {
            members.iter().for_each(|&i| core[i as usize] = true);
            continue;
        }
        for &i in members {
            let mut count = members.len();
            'search: for other in around(k).filter(|&o| o != k) {
                if let Some(ms) = cells.get(&other) {
                    for &j in ms {
                        if near(i as usize, j as usize) {
                            count += 1;
                            if count >= min_pts {
                                break 'search;
                            }
                        }
                    }
                }
            }
            core[i as usize] = count >= min_pts;
        }
    }

    // 2. Union cells' core points.
    let keys: Vec<(i64, i64)> = cells.keys().copied().collect();
    let index: HashMap<(i64, i64), usize> = keys.iter().enumerate().map(|(i, &k)| (k, i)).collect();
    let mut parent: Vec<usize> = (0..keys.len()).collect();
    fn find(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    let core_of = |k: &(i64, i64)| -> Vec<u32> {
        cells[k]
            .iter()
            .copied()
            .filter(|&i| core[i as usize])
            .collect()
    };
    let cores: Vec<Vec<u32>> = keys.iter().map(core_of).collect();
    for (a, k) in keys.iter().enumerate() {
        if cores[a].is_empty() {
            continue;
        }
        for other in around(*k) {
            let Some(&b) = index.get(&other) else {
                continue;
            };
            if b <= a || cores[b].is_empty() || find(&mut parent, a) == find(&mut parent, b) {
                continue;
            }
            let linked = cores[a]
                .iter()
                .any(|&i| cores[b].iter().any(|&j| near(i as usize, j as usize)));
            if linked {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                parent[ra] = rb;
            }
        }
    }

    // 3. Labels, numbered in order of first appearance; border points join a core neighbour.
    let mut names: HashMap<usize, u32> = HashMap::new();
    let mut labels = vec![Label::Noise; n];
    let mut name = |root: usize| -> u32 {
        let next = names.len() as u32;
        *names.entry(root).or_insert(next)
    };
    for i in 0..n {
        let k = key(&points[i]);
        let root = if core[i] {
            Some(find(&mut parent, index[&k]))
        } else {
            // Own cell first (every point there is within eps), then the ring around it.
            let own = &cores[index[&k]];
            if !own.is_empty() {
                Some(find(&mut parent, index[&k]))
            } else {
                around(k)
                    .filter_map(|o| index.get(&o).copied())
                    .find(|&b| cores[b].iter().any(|&j| near(i, j as usize)))
                    .map(|b| find(&mut parent, b))
            }
        };
        if let Some(r) = root {
            labels[i] = Label::Cluster(name(r));
        }
    }
    labels
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::collections::HashMap;

    /// The textbook O(n^2) DBSCAN: the oracle.
    fn naive(points: &[[f64; 2]], eps: f64, min_pts: usize) -> (Vec<bool>, Vec<Option<usize>>) {
        let n = points.len();
        let nb = |i: usize| -> Vec<usize> {
            (0..n)
                .filter(|&j| {
                    (points[i][0] - points[j][0]).powi(2) + (points[i][1] - points[j][1]).powi(2)
                        <= eps * eps
                })
                .collect()
        };
        let core: Vec<bool> = (0..n).map(|i| nb(i).len() >= min_pts).collect();
        let mut label: Vec<Option<usize>> = vec![None; n];
        let mut c = 0;
        for i in 0..n {
            if !core[i] || label[i].is_some() {
                continue;
            }
            let mut stack = vec![i];
            label[i] = Some(c);
            while let Some(p) = stack.pop() {
                for q in nb(p) {
                    if label[q].is_none() {
                        label[q] = Some(c);
                        if core[q] {
                            stack.push(q);
                        }
                    }
                }
            }
            c += 1;
        }
        (core, label)
    }

    fn check_against_naive(points: &[[f64; 2]], eps: f64, min_pts: usize) -> Result<(), String> {
        let got = dbscan(points, eps, min_pts);
        let (core, want) = naive(points, eps, min_pts);
        let mut map: HashMap<usize, u32> = HashMap::new();
        let mut back: HashMap<u32, usize> = HashMap::new();
        for i in 0..points.len() {
            match (want[i], got[i]) {
                (None, Label::Noise) => {}
                (Some(w), Label::Cluster(g)) if core[i] => {
                    // Core points: the same partition up to renaming.
                    if *map.entry(w).or_insert(g) != g || *back.entry(g).or_insert(w) != w {
                        return Err(format!("core point {i}: cluster {g} vs oracle {w}"));
                    }
                }
                (Some(_), Label::Cluster(g)) => {
                    // Border points may be reachable from two clusters; the one given must
                    // hold a core point within eps.
                    let ok = (0..points.len()).any(|j| {
                        core[j]
                            && got[j] == Label::Cluster(g)
                            && (points[i][0] - points[j][0]).powi(2)
                                + (points[i][1] - points[j][1]).powi(2)
                                <= eps * eps
                    });
                    if !ok {
                        return Err(format!(
                            "border point {i} joined cluster {g} with no core point in reach"
                        ));
                    }
                }
                (w, g) => return Err(format!("point {i}: {g:?} vs oracle {w:?}")),
            }
        }
        Ok(())
    }

    #[test]
    fn two_blobs_and_an_outlier() {
        let mut pts = Vec::new();
        for k in 0..20 {
            let a = k as f64 * 0.3;
            pts.push([0.02 * a.cos(), 0.02 * a.sin()]);
            pts.push([1.0 + 0.02 * a.cos(), 0.02 * a.sin()]);
        }
        pts.push([5.0, 5.0]);
        let labels = dbscan(&pts, 0.1, 5);
        assert_eq!(labels[0], Label::Cluster(0));
        assert_eq!(labels[1], Label::Cluster(1));
        assert_eq!(labels[40], Label::Noise);
        check_against_naive(&pts, 0.1, 5).unwrap();
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn labels_match_the_naive_oracle(
            pts in prop::collection::vec((-1.0f64..1.0, -1.0f64..1.0).prop_map(|(x, y)| [x, y]), 0..300),
            eps in 0.02f64..0.3,
            min_pts in 1usize..12,
        ) {
            prop_assert_eq!(check_against_naive(&pts, eps, min_pts), Ok(()));
        }

        #[test]
        fn shuffling_points_only_renames_clusters(
            pts in prop::collection::vec((-1.0f64..1.0, -1.0f64..1.0).prop_map(|(x, y)| [x, y]), 1..200),
            rot in 1usize..200,
        ) {
            let a = dbscan(&pts, 0.15, 4);
            let r = rot % pts.len();
            let mut shifted = pts.clone();
            shifted.rotate_left(r);
            let b = dbscan(&shifted, 0.15, 4);
            let noise_a: Vec<bool> = a.iter().map(|l| *l == Label::Noise).collect();
            let mut noise_b: Vec<bool> = b.iter().map(|l| *l == Label::Noise).collect();
            noise_b.rotate_right(r);
            prop_assert_eq!(noise_a, noise_b);
        }
    }
}
