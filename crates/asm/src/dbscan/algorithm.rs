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

/// The bounding box of a set of points, for bounds on the distances to its points that
/// hold exactly in floating point: the distance between two points (as `near` computes it,
/// `(p - q)^2` summed over the axes) is never below the gap nor above the span that the
/// boxes give, since rounding is monotone. A cell's box is at most its square (members
/// that rounding put just across an edge included), and in a settled cloud much smaller,
/// so that more cells are counted whole or passed over.
#[derive(Clone, Copy, Debug)]
struct BBox {
    lo: [f64; 2],
    hi: [f64; 2],
}

impl BBox {
    /// No point: every gap is infinite.
    const EMPTY: Self = Self {
        lo: [f64::INFINITY; 2],
        hi: [f64::NEG_INFINITY; 2],
    };

    fn of(points: impl IntoIterator<Item = [f64; 2]>) -> Self {
        let mut b = Self::EMPTY;
        points.into_iter().for_each(|p| b.add(p));
        b
    }

    fn add(&mut self, p: [f64; 2]) {
        for (k, v) in p.into_iter().enumerate() {
            self.lo[k] = self.lo[k].min(v);
            self.hi[k] = self.hi[k].max(v);
        }
    }

    /// The squared distances from `p` to the box's nearest and furthest points.
    fn reach2(&self, p: [f64; 2]) -> (f64, f64) {
        let (mut near, mut far) = (0.0, 0.0);
        for (k, v) in p.into_iter().enumerate() {
            let n = (self.lo[k] - v).max(v - self.hi[k]).max(0.0);
            let f = (v - self.lo[k]).max(self.hi[k] - v);
            near += n * n;
            far += f * f;
        }
        (near, far)
    }

    /// The squared smallest and largest distances between a point of `self` and one of
    /// `other`.
    fn between2(&self, other: &Self) -> (f64, f64) {
        let (mut gap, mut span) = (0.0, 0.0);
        for k in 0..2 {
            let g = (other.lo[k] - self.hi[k])
                .max(self.lo[k] - other.hi[k])
                .max(0.0);
            let s = (self.hi[k] - other.lo[k]).max(other.hi[k] - self.lo[k]);
            gap += g * g;
            span += s * s;
        }
        (gap, span)
    }
}

/// Points binned into square cells, as compressed rows: the points of cell `c` are
/// `order[start[c]..start[c + 1]]`.
struct Grid {
    index: Index,
    /// The bounding box of each cell's points (see [`BBox`]).
    boxes: Vec<BBox>,
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
        let mut boxes = vec![BBox::EMPTY; n_cells];
        for (p, &c) in points.iter().zip(&cell_of) {
            boxes[c as usize].add(*p);
        }
        Self {
            index,
            boxes,
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
    let near = |a: usize, b: usize| within(points, a, b, eps2);
    let n_cells = grid.start.len() - 1;
    let core = core_points(points, &grid, eps2, min_pts);
    let (cores, core_boxes, mut parent) = join_cells(points, &grid, &core, eps2);

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
                .filter(|&b| !cores[b].is_empty())
                .find(|&b| {
                    let (near2, far2) = core_boxes[b].reach2(points[i]);
                    near2 <= eps2 && (far2 <= eps2 || cores[b].iter().any(|&j| near(i, j as usize)))
                })
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

/// Whether points `a` and `b` lie within `eps` (`eps2` its square).
fn within(points: &[[f64; 2]], a: usize, b: usize, eps2: f64) -> bool {
    let (p, q) = (points[a], points[b]);
    (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) <= eps2
}

/// Step 1: which points are core points (at least `min_pts` within `eps`, themselves
/// included).
fn core_points(points: &[[f64; 2]], grid: &Grid, eps2: f64, min_pts: usize) -> Vec<bool> {
    let near = |a: usize, b: usize| within(points, a, b, eps2);
    let n_cells = grid.start.len() - 1;
    let mut core = vec![false; points.len()];
    let mut partial: Vec<usize> = Vec::with_capacity(24);
    let mut cut: Vec<usize> = Vec::with_capacity(24);
    for c in 0..n_cells {
        let members = grid.members(c);
        if members.is_empty() {
            continue;
        }
        // Bounds for the whole cell first: the cells within `eps` of all its points count
        // for each of them, and those beyond `eps` of all of them for none. In a settled
        // cloud they decide most cells; the rest is counted point by point below.
        let own = &grid.boxes[c];
        let mut whole = members.len();
        let mut reachable = whole;
        partial.clear();
        for other in grid.around(c).filter(|&o| o != c) {
            let k = grid.members(other).len();
            if k == 0 {
                continue;
            }
            let (gap2, span2) = own.between2(&grid.boxes[other]);
            if span2 <= eps2 {
                whole += k;
            } else if gap2 <= eps2 {
                partial.push(other);
            } else {
                continue;
            }
            reachable += k;
        }
        if whole >= min_pts {
            members.iter().for_each(|&i| core[i as usize] = true);
            continue;
        }
        if reachable < min_pts {
            continue;
        }
        for &i in members {
            // A cell wholly within eps counts whole, one wholly beyond it not at all; only
            // the cells that the eps circle cuts are then counted point by point, until
            // the count is reached. The same counts as a point-by-point search: the
            // boxes' bounds are exact (see `BBox`).
            let p = points[i as usize];
            let mut count = whole;
            cut.clear();
            for &other in &partial {
                let (near2, far2) = grid.boxes[other].reach2(p);
                if far2 <= eps2 {
                    count += grid.members(other).len();
                } else if near2 <= eps2 {
                    cut.push(other);
                }
            }
            for &other in &cut {
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
    core
}

/// The core points of each cell, their boxes, and the union-find forest over the cells.
type Joined = (Vec<Vec<u32>>, Vec<BBox>, Vec<usize>);

/// Step 2: the cells' core points joined (a cell's core points are one set; two cells'
/// sets are one where some of their core points lie within `eps`).
fn join_cells(points: &[[f64; 2]], grid: &Grid, core: &[bool], eps2: f64) -> Joined {
    let near = |a: usize, b: usize| within(points, a, b, eps2);
    let n_cells = grid.start.len() - 1;
    let cores: Vec<Vec<u32>> = (0..n_cells)
        .map(|c| {
            grid.members(c)
                .iter()
                .copied()
                .filter(|&i| core[i as usize])
                .collect()
        })
        .collect();
    let core_boxes: Vec<BBox> = cores
        .iter()
        .map(|m| BBox::of(m.iter().map(|&i| points[i as usize])))
        .collect();
    let mut parent: Vec<usize> = (0..n_cells).collect();
    for a in 0..n_cells {
        if cores[a].is_empty() {
            continue;
        }
        for b in grid.around(a) {
            if b <= a || cores[b].is_empty() || find(&mut parent, a) == find(&mut parent, b) {
                continue;
            }
            // The core points' boxes settle most pairs; otherwise only the points of `a`
            // within `eps` of `b`'s box can be near one of `b`'s.
            let (gap2, span2) = core_boxes[a].between2(&core_boxes[b]);
            if gap2 <= eps2
                && (span2 <= eps2
                    || cores[a].iter().any(|&i| {
                        core_boxes[b].reach2(points[i as usize]).0 <= eps2
                            && cores[b].iter().any(|&j| near(i as usize, j as usize))
                    }))
            {
                let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
                parent[ra] = rb;
            }
        }
    }

    (cores, core_boxes, parent)
}

/// The root of `x` in the union-find forest `parent`, halving the path on the way.
fn find(parent: &mut [usize], mut x: usize) -> usize {
    while parent[x] != x {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    x
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
