use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// The multiply-rotate hash of rustc's `FxHasher`, for the sparse index's integer cell
/// keys: the standard SipHash, built against hash flooding by untrusted keys, cost 8 % of a
/// whole map here (25 lookups per cell), and cell coordinates are not chosen by anyone.
#[derive(Default)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn write(&mut self, bytes: &[u8]) {
        bytes.iter().for_each(|&b| self.write_u64(u64::from(b)));
    }
    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(5) ^ v).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_i64(&mut self, v: i64) {
        self.write_u64(v as u64);
    }
    fn finish(&self) -> u64 {
        self.0
    }
}

type CellMap = HashMap<(i64, i64), usize, BuildHasherDefault<CellHasher>>;

use super::Label;

/// How cell coordinates map to cell indices.
enum Index {
    /// Every cell of the points' bounding box, row-major: `cy * nx + cx`.
    Dense { nx: i64, ny: i64 },
    /// Only the occupied cells, found by their coordinates (`coords[c]` are cell `c`'s):
    /// for points spread so widely that the bounding box holds far more cells than
    /// points (a dense table would then exhaust memory, or overflow its size).
    Sparse {
        cells: CellMap,
        coords: Vec<(i64, i64)>,
    },
}

/// Points binned into square cells, as compressed rows: the points of cell `c` are
/// `order[start[c]..start[c + 1]]`.
struct Grid {
    index: Index,
    /// The corner of cell `(0, 0)` and the cells' side.
    origin: [f64; 2],
    side: f64,
    start: Vec<u32>,
    order: Vec<u32>,
    cell_of: Vec<u32>,
}

impl Grid {
    fn new(points: &[[f64; 2]], side: f64) -> Self {
        let (mut x0, mut y0) = (f64::INFINITY, f64::INFINITY);
        let (mut x1, mut y1) = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        for p in points {
            x0 = x0.min(p[0]);
            y0 = y0.min(p[1]);
            x1 = x1.max(p[0]);
            y1 = y1.max(p[1]);
        }
        // Cell coordinates relative to the lower-left point (saturating far outside i64).
        let coord = |p: &[f64; 2]| {
            (
                ((p[0] - x0) / side).floor() as i64,
                ((p[1] - y0) / side).floor() as i64,
            )
        };
        let (fx, fy) = (
            ((x1 - x0) / side).floor() + 1.0,
            ((y1 - y0) / side).floor() + 1.0,
        );
        // A dense table costs a word per cell: worth it while the box holds not many more
        // cells than there are points.
        let dense = fx * fy <= (4 * points.len() + 4096) as f64;
        let (index, cell_of, n_cells) = if dense {
            let (nx, ny) = (fx as i64, fy as i64);
            let cell_of: Vec<u32> = points
                .iter()
                .map(|p| {
                    let (cx, cy) = coord(p);
                    (cy.clamp(0, ny - 1) * nx + cx.clamp(0, nx - 1)) as u32
                })
                .collect();
            (Index::Dense { nx, ny }, cell_of, (nx * ny) as usize)
        } else {
            let mut cells = CellMap::default();
            let mut coords = Vec::new();
            let cell_of: Vec<u32> = points
                .iter()
                .map(|p| {
                    let k = coord(p);
                    let next = coords.len();
                    let c = *cells.entry(k).or_insert(next);
                    if c == next {
                        coords.push(k);
                    }
                    c as u32
                })
                .collect();
            let n = coords.len();
            (Index::Sparse { cells, coords }, cell_of, n)
        };
        let mut start = vec![0u32; n_cells + 1];
        for &c in &cell_of {
            start[c as usize + 1] += 1;
        }
        for c in 0..n_cells {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut order = vec![0u32; points.len()];
        for (i, &c) in cell_of.iter().enumerate() {
            order[fill[c as usize] as usize] = i as u32;
            fill[c as usize] += 1;
        }
        Self {
            index,
            origin: [x0, y0],
            side,
            start,
            order,
            cell_of,
        }
    }

    /// Cell `c`'s coordinates.
    fn coords(&self, c: usize) -> (i64, i64) {
        match &self.index {
            Index::Dense { nx, .. } => (c as i64 % nx, c as i64 / nx),
            Index::Sparse { coords, .. } => coords[c],
        }
    }

    /// The squared distances from `p` to the nearest and to the furthest point of cell
    /// `c`'s square, widened by a relative margin so that rounding in the cell assignment
    /// cannot put a member outside it.
    fn reach2(&self, p: [f64; 2], c: usize) -> (f64, f64) {
        let (cx, cy) = self.coords(c);
        let pad = 1e-9 * self.side;
        let axis = |v: f64, o: f64, k: i64| {
            let lo = o + k as f64 * self.side - pad;
            let hi = lo + self.side + 2.0 * pad;
            let near = (lo - v).max(v - hi).max(0.0);
            let far = (v - lo).max(hi - v);
            (near, far)
        };
        let (nx, fx) = axis(p[0], self.origin[0], cx);
        let (ny, fy) = axis(p[1], self.origin[1], cy);
        (nx * nx + ny * ny, fx * fx + fy * fy)
    }

    fn members(&self, c: usize) -> &[u32] {
        &self.order[self.start[c] as usize..self.start[c + 1] as usize]
    }

    /// The cells in the 5 x 5 block around `c` (itself included) that exist.
    fn around(&self, c: usize) -> impl Iterator<Item = usize> + '_ {
        let (cx, cy) = self.coords(c);
        (-2..=2).flat_map(move |dy| {
            (-2..=2).filter_map(move |dx| {
                let (x, y) = (cx.saturating_add(dx), cy.saturating_add(dy));
                match &self.index {
                    Index::Dense { nx, ny } => {
                        (x >= 0 && y >= 0 && x < *nx && y < *ny).then_some((y * nx + x) as usize)
                    }
                    Index::Sparse { cells, .. } => cells.get(&(x, y)).copied(),
                }
            })
        })
    }
}

/// Labels `points` with DBSCAN(`eps`, `min_pts`); see the module docs for the method.
///
/// # Panics
/// If `eps` is not positive (use [`super::DbscanParams::check`] to validate first).
pub fn dbscan(points: &[[f64; 2]], eps: f64, min_pts: usize) -> Vec<Label> {
    assert!(eps > 0.0, "eps must be positive");
    let n = points.len();
    if n == 0 {
        return Vec::new();
    }
    // Side eps / sqrt(2): the diagonal of a cell is eps, so a cell's points all neighbour
    // each other, and neighbours are at most two cells away in x and in y.
    let grid = Grid::new(points, eps / std::f64::consts::SQRT_2);
    let eps2 = eps * eps;
    let near = |a: usize, b: usize| {
        let (p, q) = (points[a], points[b]);
        (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) <= eps2
    };
    let n_cells = grid.start.len() - 1;

    // 1. Core points.
    let mut core = vec![false; n];
    for c in 0..n_cells {
        let members = grid.members(c);
        if members.is_empty() {
            continue;
        }
        if members.len() >= min_pts {
            members.iter().for_each(|&i| core[i as usize] = true);
            continue;
        }
        for &i in members {
            // A cell wholly within eps counts whole, one wholly beyond it not at all (in
            // a settled cloud most are one or the other); only the cells that the eps
            // circle cuts are then counted point by point, until the count is reached.
            // The same counts as a point-by-point search: the margin of `reach2` only
            // sends a cell to the exact count.
            let p = points[i as usize];
            let mut count = members.len();
            let mut cut = [0usize; 24];
            let mut n_cut = 0;
            for other in grid.around(c).filter(|&o| o != c) {
                let (near2, far2) = grid.reach2(p, other);
                if far2 < eps2 {
                    count += grid.members(other).len();
                } else if near2 <= eps2 {
                    cut[n_cut] = other;
                    n_cut += 1;
                }
            }
            for &other in &cut[..n_cut] {
                if count >= min_pts {
                    break;
                }
                count += grid
                    .members(other)
                    .iter()
                    .filter(|&&j| near(i as usize, j as usize))
                    .count();
            }
            core[i as usize] = count >= min_pts;
        }
    }

    // 2. Union cells' core points (a cell's core points are one set).
    let cores: Vec<Vec<u32>> = (0..n_cells)
        .map(|c| {
            grid.members(c)
                .iter()
                .copied()
                .filter(|&i| core[i as usize])
                .collect()
        })
        .collect();
    let mut parent: Vec<usize> = (0..n_cells).collect();
    fn find(parent: &mut [usize], mut x: usize) -> usize {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    }
    for a in 0..n_cells {
        if cores[a].is_empty() {
            continue;
        }
        for b in grid.around(a) {
            if b <= a || cores[b].is_empty() || find(&mut parent, a) == find(&mut parent, b) {
                continue;
            }
            if cores[a]
                .iter()
                .any(|&i| cores[b].iter().any(|&j| near(i as usize, j as usize)))
            {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                parent[ra] = rb;
            }
        }
    }

    // 3. Labels, numbered in order of first appearance; border points join a core neighbour.
    // Each root cell's cluster number, u32::MAX until its first point is labelled.
    let mut names = vec![u32::MAX; n_cells];
    let mut named = 0u32;
    let mut labels = vec![Label::Noise; n];
    for i in 0..n {
        let c = grid.cell_of[i] as usize;
        let root = if core[i] || !cores[c].is_empty() {
            // Own cell first: every point there is within eps.
            Some(find(&mut parent, c))
        } else {
            grid.around(c)
                .find(|&b| cores[b].iter().any(|&j| near(i, j as usize)))
                .map(|b| find(&mut parent, b))
        };
        if let Some(r) = root {
            if names[r] == u32::MAX {
                names[r] = named;
                named += 1;
            }
            labels[i] = Label::Cluster(names[r]);
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
    fn points_spread_over_a_huge_box_use_the_sparse_grid() {
        // Two tight groups 1e12 m apart: a dense grid would need ~1e26 cells.
        let mut pts: Vec<[f64; 2]> = (0..20).map(|i| [0.01 * i as f64, 0.0]).collect();
        pts.extend((0..20).map(|i| [1e12, 1e12 + 0.01 * i as f64]));
        pts.push([5e11, -3e11]);
        check_against_naive(&pts, 0.1, 5).unwrap();
        let labels = dbscan(&pts, 0.1, 5);
        assert_eq!(labels[0], Label::Cluster(0));
        assert_eq!(labels[20], Label::Cluster(1));
        assert_eq!(labels[40], Label::Noise);
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

        /// A settled particle cloud: hundreds of points in a few cells, `MinPts` in the
        /// tens (the mapper's is 10 % of M), coordinates on a lattice so that points sit
        /// on cell edges and pairs lie exactly `eps` apart, where counting whole cells
        /// must agree with counting point by point.
        #[test]
        fn dense_lattice_clouds_match_the_naive_oracle(
            pts in prop::collection::vec((-8i32..8, -8i32..8).prop_map(|(x, y)| [f64::from(x) * 0.025, f64::from(y) * 0.025]), 0..600),
            eps_steps in 1u32..6,
            min_pts in 1usize..120,
        ) {
            let eps = f64::from(eps_steps) * 0.025;
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
