use std::path::{Path, PathBuf};

use super::format::{check_size, parse_pgm, pgm_header, read_meta, resolve_image};
use crate::error::MapError;

/// The state of one grid cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Cell {
    /// Known to be free.
    Free,
    /// Known to be occupied (walls, furniture).
    Occupied,
    /// Never observed.
    Unknown,
}

/// The coarsest resolution accepted (m per cell): occupancy maps are centimetres to a metre.
pub const MAX_RESOLUTION_M: f64 = 10.0;
/// The finest resolution accepted (m per cell): a millimetre, finer than any range sensor
/// maps. A grid finer than that is a unit mistake (a resolution given in kilometres).
pub const MIN_RESOLUTION_M: f64 = 1e-3;
/// The largest extent a map may span, and the farthest its origin may lie (m): a robot's
/// building, campus or yard, with room to spare. Bounds every size computed from a map.
pub const MAX_EXTENT_M: f64 = 10_000.0;
/// The most cells a map may have: a 250-m square at 5 cm, or 2.5 km at 0.5 m. Bounds the
/// memory of a map and of its known cells (16 bytes each) to well under a gigabyte.
pub const MAX_CELLS: usize = 25_000_000;

/// Checks a grid's geometry before any cell of it is built: its resolution within
/// [[`MIN_RESOLUTION_M`], [`MAX_RESOLUTION_M`]], its origin finite and within
/// [`MAX_EXTENT_M`] of the world's, its span within [`MAX_EXTENT_M`] and its cells at most
/// [`MAX_CELLS`]. Every door asks this one function: a map file, a grid from Python, a
/// ROS `/map` message.
///
/// # Errors
/// [`MapError::TooLarge`] for a grid of more cells than a map may have (its cells would not
/// fit in memory); [`MapError::Grid`] for the rest.
pub fn check_grid(
    width: usize,
    height: usize,
    resolution: f64,
    origin: [f64; 2],
) -> Result<(), MapError> {
    let grid = |message| Err(MapError::Grid { message });
    if let Err(message) = check_resolution(resolution) {
        return grid(message);
    }
    if let Err(message) = check_origin(origin) {
        return grid(message);
    }
    if width == 0 || height == 0 {
        return grid(format!("a {width} x {height} grid has no cell"));
    }
    if width.checked_mul(height).is_none_or(|n| n > MAX_CELLS) {
        return Err(MapError::TooLarge {
            message: format!(
                "{width} x {height} cells are more than a map may have ({MAX_CELLS}): crop it \
                 to the surveyed area or give it at a coarser resolution"
            ),
        });
    }
    let extent = (width.max(height) as f64) * resolution;
    if extent > MAX_EXTENT_M {
        return grid(format!(
            "resolution {resolution} m x {width} x {height} cells spans {extent:.0} m, more than the {MAX_EXTENT_M} m a map may span"
        ));
    }
    Ok(())
}

/// A resolution within [[`MIN_RESOLUTION_M`], [`MAX_RESOLUTION_M`]] m per cell.
pub(super) fn check_resolution(resolution: f64) -> Result<(), String> {
    if !(resolution.is_finite() && resolution > 0.0) {
        return Err(format!(
            "resolution {resolution} must be a positive number of metres"
        ));
    }
    if !(MIN_RESOLUTION_M..=MAX_RESOLUTION_M).contains(&resolution) {
        return Err(format!(
            "resolution {resolution} m per cell is beyond any occupancy map ({MIN_RESOLUTION_M} to {MAX_RESOLUTION_M})"
        ));
    }
    Ok(())
}

/// An origin that is finite and within [`MAX_EXTENT_M`] of the world frame's.
pub(super) fn check_origin(origin: [f64; 2]) -> Result<(), String> {
    if origin.iter().any(|v| !v.is_finite()) {
        return Err(format!("origin {origin:?} has a non-finite value"));
    }
    if origin.iter().any(|v| v.abs() > MAX_EXTENT_M) {
        return Err(format!(
            "origin {origin:?} lies more than {MAX_EXTENT_M} m from the world frame's origin"
        ));
    }
    Ok(())
}

/// An occupancy grid: `width x height` cells of `resolution` metres, row 0 at the top
/// (image order), lower-left cell at `origin`.
#[derive(Clone, Debug, PartialEq)]
pub struct OccupancyMap {
    width: usize,
    height: usize,
    resolution: f64,
    origin: [f64; 2],
    cells: Vec<Cell>,
}

impl OccupancyMap {
    /// A map from cells in image order (row 0 at the top).
    ///
    /// # Panics
    /// If `cells.len() != width * height`, or `resolution` is not positive.
    pub fn new(
        width: usize,
        height: usize,
        resolution: f64,
        origin: [f64; 2],
        cells: Vec<Cell>,
    ) -> Self {
        assert_eq!(cells.len(), width * height, "one cell per pixel");
        assert!(resolution > 0.0, "positive resolution");
        Self {
            width,
            height,
            resolution,
            origin,
            cells,
        }
    }

    /// A map for a survey that has none: every cell within `margin_m` of one of `points`
    /// (the robot's stops) free, the rest unknown, on a grid of `resolution` metres.
    ///
    /// I-ASM spreads its particles over the known cells, so the map bounds where a source
    /// can be found. Without a surveyed map, the stops themselves say where the robot was,
    /// and a source it mapped lies within hearing of them; how far is the caller's choice
    /// (the CLI's `--open-margin`, 3 m by default: a room's half-width). No walls are
    /// known, so nothing is removed as a mirror image beyond them except beyond the
    /// region's edge ([`crate::IasmConfig::beyond_map_m`]). The particles per round grow
    /// with the region's area (one per [`crate::IasmConfig::density_d`] cells).
    ///
    /// # Errors
    /// [`MapError::Open`] if `points` is empty or holds a non-finite coordinate,
    /// `margin_m` or `resolution` is not positive and finite, `resolution` exceeds
    /// the coarsest resolution a map may have (10 m), or the region spans more than a map
    /// may (10 km).
    pub fn open_around(
        points: &[[f64; 2]],
        margin_m: f64,
        resolution: f64,
    ) -> Result<Self, MapError> {
        let fail = |message: String| Err(MapError::Open { message });
        if points.is_empty() {
            return fail("no stop to build it around".into());
        }
        if let Some(p) = points
            .iter()
            .find(|p| !(p[0].is_finite() && p[1].is_finite()))
        {
            return fail(format!("a stop at ({}, {}) is not finite", p[0], p[1]));
        }
        if !(margin_m.is_finite() && margin_m > 0.0) {
            return fail(format!("the margin must be positive (got {margin_m} m)"));
        }
        if !(resolution.is_finite() && resolution > 0.0 && resolution <= MAX_RESOLUTION_M) {
            return fail(format!(
                "the resolution must lie in (0, {MAX_RESOLUTION_M}] m (got {resolution})"
            ));
        }
        let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
        for p in points {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k] - margin_m);
                hi[k] = hi[k].max(p[k] + margin_m);
            }
        }
        let span = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let far = lo.iter().chain(&hi).fold(0.0f64, |m, v| m.max(v.abs()));
        if span > MAX_EXTENT_M || far > MAX_EXTENT_M {
            return fail(format!(
                "the stops and margin span {span:.0} m, beyond {MAX_EXTENT_M} m"
            ));
        }
        let width = ((hi[0] - lo[0]) / resolution).ceil() as usize;
        let height = ((hi[1] - lo[1]) / resolution).ceil() as usize;
        if width.saturating_mul(height) > MAX_CELLS {
            return fail(format!(
                "the stops and a margin of {margin_m} m make a {width} x {height} grid of \
                 {resolution} m cells, more than a map may have ({MAX_CELLS}); give a smaller \
                 margin"
            ));
        }
        let mut map = Self::new(
            width,
            height,
            resolution,
            lo,
            vec![Cell::Unknown; width * height],
        );
        let r2 = margin_m * margin_m;
        for j in 0..height {
            for i in 0..width {
                let c = map.cell_center(i, j);
                if points
                    .iter()
                    .any(|p| (c[0] - p[0]).powi(2) + (c[1] - p[1]).powi(2) <= r2)
                {
                    map.cells[j * width + i] = Cell::Free;
                }
            }
        }
        Ok(map)
    }

    /// Reads a ROS map: the YAML at `yaml` and the image it names (relative to the YAML's
    /// folder).
    ///
    /// # Errors
    /// [`MapError`] if either file cannot be read or is malformed, the origin has a yaw,
    /// or no cell is known.
    pub fn load(yaml: &Path) -> Result<Self, MapError> {
        Self::load_with_image(yaml, None)
    }

    /// As [`OccupancyMap::load`], but reads `image` instead of the image the YAML names
    /// when given (for published maps whose YAML names a file that is not there).
    ///
    /// # Errors
    /// As [`OccupancyMap::load`].
    pub fn load_with_image(yaml: &Path, image: Option<&Path>) -> Result<Self, MapError> {
        let meta = read_meta(yaml)?;
        let img_path = image.map_or_else(|| resolve_image(yaml, &meta.image), Path::to_owned);
        let io_error = |source| match image {
            Some(_) => MapError::Io {
                path: img_path.clone(),
                source,
            },
            None => MapError::Image {
                yaml: yaml.to_owned(),
                image: img_path.clone(),
                source,
            },
        };
        // The header first: an image too large to be a map is refused before it is read.
        let mut file = std::fs::File::open(&img_path).map_err(io_error)?;
        let mut bytes = Vec::new();
        std::io::Read::read_to_end(&mut std::io::Read::take(&mut file, 4096), &mut bytes)
            .map_err(io_error)?;
        // (A header cut by the 4 KiB, past long comments, can only read smaller numbers.)
        if let Ok((_, w, h, ..)) = pgm_header(&bytes) {
            check_size(w, h).map_err(|message| MapError::Pgm {
                path: img_path.clone(),
                message,
            })?;
        }
        std::io::Read::read_to_end(&mut file, &mut bytes).map_err(io_error)?;
        let (w, h, maxval, pixels) = parse_pgm(&bytes).map_err(|message| MapError::Pgm {
            path: img_path.clone(),
            message,
        })?;
        let cells = pixels
            .iter()
            .map(|&v| {
                let v = f64::from(v) / f64::from(maxval);
                let p = if meta.negate { v } else { 1.0 - v };
                if p > meta.occupied_thresh {
                    Cell::Occupied
                } else if p < meta.free_thresh {
                    Cell::Free
                } else {
                    Cell::Unknown
                }
            })
            .collect();
        let _ = (&meta.image, &meta.mode);
        check_grid(w, h, meta.resolution, [meta.origin[0], meta.origin[1]]).map_err(|e| {
            MapError::Yaml {
                path: yaml.to_owned(),
                message: e.to_string(),
            }
        })?;
        let map = Self::new(
            w,
            h,
            meta.resolution,
            [meta.origin[0], meta.origin[1]],
            cells,
        );
        if map.known_cells().next().is_none() {
            return Err(MapError::NoKnownCell {
                path: yaml.to_owned(),
            });
        }
        Ok(map)
    }

    /// The image a map YAML names, resolved against the YAML's folder.
    ///
    /// # Errors
    /// [`MapError::Io`] if the YAML cannot be read, [`MapError::Yaml`] if it is malformed.
    pub fn image_path(yaml: &Path) -> Result<PathBuf, MapError> {
        Ok(resolve_image(yaml, &read_meta(yaml)?.image))
    }

    /// Width (cells).
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height (cells).
    pub fn height(&self) -> usize {
        self.height
    }

    /// Cell size (m).
    pub fn resolution(&self) -> f64 {
        self.resolution
    }

    /// World position of the lower-left corner of the lower-left cell (m).
    pub fn origin(&self) -> [f64; 2] {
        self.origin
    }

    /// The cell at column `i`, row `j` (row 0 at the top).
    pub fn cell(&self, i: usize, j: usize) -> Cell {
        self.cells[j * self.width + i]
    }

    /// World centre (m) of the cell at column `i`, row `j`.
    pub fn cell_center(&self, i: usize, j: usize) -> [f64; 2] {
        [
            self.origin[0] + (i as f64 + 0.5) * self.resolution,
            self.origin[1] + ((self.height - 1 - j) as f64 + 0.5) * self.resolution,
        ]
    }

    /// The cell (column, row) holding world point `p`, if inside the map.
    pub fn world_to_cell(&self, p: [f64; 2]) -> Option<(usize, usize)> {
        let fi = ((p[0] - self.origin[0]) / self.resolution).floor();
        let fr = ((p[1] - self.origin[1]) / self.resolution).floor();
        if fi < 0.0 || fr < 0.0 || fi >= self.width as f64 || fr >= self.height as f64 {
            return None;
        }
        Some((fi as usize, self.height - 1 - fr as usize))
    }

    /// The cell holding world point `p`, if inside the map.
    pub fn cell_at(&self, p: [f64; 2]) -> Option<Cell> {
        self.world_to_cell(p).map(|(i, j)| self.cell(i, j))
    }

    /// The centre (world, m) of the first occupied cell that the segment from `a` to `b`
    /// passes through, if any: every cell it touches is visited in order from `a` (the grid
    /// traversal of Amanatides and Woo, 1987), so that a wall a cell thick drawn on the
    /// diagonal stops it too, and a segment through a corner shared by four cells tries the
    /// one beside it first. Cells beyond the map hold nothing; a non-finite end passes
    /// nothing.
    pub fn first_occupied(&self, a: [f64; 2], b: [f64; 2]) -> Option<[f64; 2]> {
        if !a.iter().chain(&b).all(|v| v.is_finite()) {
            return None;
        }
        let grid = |p: [f64; 2]| {
            [
                (p[0] - self.origin[0]) / self.resolution,
                (p[1] - self.origin[1]) / self.resolution,
            ]
        };
        let (ga, gb) = (grid(a), grid(b));
        // Clip to the map (Liang and Barsky): beyond it nothing is occupied, and the
        // traversal's length stays bounded by the map's.
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for (k, size) in [(0, self.width as f64), (1, self.height as f64)] {
            let d = gb[k] - ga[k];
            if d == 0.0 {
                if !(0.0..=size).contains(&ga[k]) {
                    return None;
                }
                continue;
            }
            let (ta, tb) = ((0.0 - ga[k]) / d, (size - ga[k]) / d);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
        }
        if t0 > t1 {
            return None;
        }
        let at = |t: f64| [ga[0] + t * (gb[0] - ga[0]), ga[1] + t * (gb[1] - ga[1])];
        let (ga, gb) = (at(t0), at(t1));
        let mut cell = [ga[0].floor(), ga[1].floor()];
        let steps = (gb[0].floor() - cell[0]).abs() + (gb[1].floor() - cell[1]).abs();
        // Per axis: the step's sign, the segment's parameter at the next cell edge, and the
        // parameter one cell spans.
        let (mut step, mut next, mut span) = ([0.0; 2], [f64::INFINITY; 2], [f64::INFINITY; 2]);
        for k in 0..2 {
            let d = gb[k] - ga[k];
            if d > 0.0 {
                (step[k], next[k], span[k]) = (1.0, (cell[k] + 1.0 - ga[k]) / d, 1.0 / d);
            } else if d < 0.0 {
                (step[k], next[k], span[k]) = (-1.0, (ga[k] - cell[k]) / -d, -1.0 / d);
            }
        }
        for _ in 0..=steps as usize {
            if self.occupied_grid(cell) {
                return Some([
                    self.origin[0] + (cell[0] + 0.5) * self.resolution,
                    self.origin[1] + (cell[1] + 0.5) * self.resolution,
                ]);
            }
            let k = usize::from(next[1] < next[0]);
            cell[k] += step[k];
            next[k] += span[k];
        }
        None
    }

    /// Whether the cell at grid coordinates `(column, row from the bottom)` is occupied
    /// (`false` beyond the map).
    fn occupied_grid(&self, cell: [f64; 2]) -> bool {
        let (w, h) = (self.width as f64, self.height as f64);
        (0.0..w).contains(&cell[0])
            && (0.0..h).contains(&cell[1])
            && self.cell(cell[0] as usize, self.height - 1 - cell[1] as usize) == Cell::Occupied
    }

    /// Whether any cell is occupied: a surveyed map has walls; an open region around the
    /// stops ([`OccupancyMap::open_around`]) has none.
    pub fn has_occupied(&self) -> bool {
        self.cells.contains(&Cell::Occupied)
    }

    /// Centres of the free cells whose centres lie within `radius` (m) of `p`, nearest
    /// first.
    pub fn free_within(&self, p: [f64; 2], radius: f64) -> Vec<[f64; 2]> {
        self.cells_within(p, radius, Cell::Free)
    }

    /// Centres of the occupied cells whose centres lie within `radius` (m) of `p`,
    /// nearest first: the stretch of wall around a point on it.
    pub fn occupied_within(&self, p: [f64; 2], radius: f64) -> Vec<[f64; 2]> {
        self.cells_within(p, radius, Cell::Occupied)
    }

    /// Centres of the cells of `kind` whose centres lie within `radius` (m) of `p`,
    /// nearest first.
    fn cells_within(&self, p: [f64; 2], radius: f64, kind: Cell) -> Vec<[f64; 2]> {
        if !(p[0].is_finite() && p[1].is_finite() && radius.is_finite() && radius >= 0.0) {
            return Vec::new();
        }
        let r = self.resolution;
        let span = |v: f64, o: f64, n: usize| {
            let lo = ((v - radius - o) / r).floor().max(0.0);
            let hi = ((v + radius - o) / r).ceil().min(n as f64 - 1.0);
            (lo, hi)
        };
        let (i0, i1) = span(p[0], self.origin[0], self.width);
        let (f0, f1) = span(p[1], self.origin[1], self.height);
        if i0 > i1 || f0 > f1 {
            return Vec::new();
        }
        let mut out: Vec<(f64, [f64; 2])> = Vec::new();
        for fr in f0 as usize..=f1 as usize {
            let j = self.height - 1 - fr;
            for i in i0 as usize..=i1 as usize {
                if self.cell(i, j) != kind {
                    continue;
                }
                let c = self.cell_center(i, j);
                let d = (c[0] - p[0]).hypot(c[1] - p[1]);
                if d <= radius {
                    out.push((d, c));
                }
            }
        }
        out.sort_by(|a, b| a.0.total_cmp(&b.0));
        out.into_iter().map(|(_, c)| c).collect()
    }

    /// Centres of every known (free or occupied) cell, in image order.
    pub fn known_cells(&self) -> impl Iterator<Item = [f64; 2]> + '_ {
        (0..self.height).flat_map(move |j| {
            (0..self.width)
                .filter(move |&i| self.cell(i, j) != Cell::Unknown)
                .map(move |i| self.cell_center(i, j))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write_map(dir: &Path, yaml: &str, pgm: &[u8]) -> PathBuf {
        std::fs::write(dir.join("m.pgm"), pgm).unwrap();
        let y = dir.join("m.yaml");
        std::fs::write(&y, yaml).unwrap();
        y
    }

    const YAML: &str = "image: m.pgm\nresolution: 0.5\norigin: [-1.0, 2.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";

    /// A 2 x 2 m map of 0.1 m cells, free but for `wall` (columns i, rows j from the top).
    fn walled(wall: impl Fn(usize, usize) -> bool) -> OccupancyMap {
        let cells = (0..20)
            .flat_map(|j| (0..20).map(move |i| (i, j)))
            .map(|(i, j)| {
                if wall(i, j) {
                    Cell::Occupied
                } else {
                    Cell::Free
                }
            })
            .collect();
        OccupancyMap::new(20, 20, 0.1, [0.0, 0.0], cells)
    }

    #[test]
    fn a_segment_is_stopped_by_the_occupied_cells_it_crosses_and_no_others() {
        // A wall along y in [1.0, 1.1): the cells of image row 9.
        let m = walled(|_, j| j == 9);
        let hit = m.first_occupied([0.55, 0.5], [0.55, 1.5]).unwrap();
        assert!((hit[0] - 0.55).abs() < 1e-9 && (hit[1] - 1.05).abs() < 1e-9);
        assert!(m.first_occupied([0.2, 0.3], [1.9, 1.7]).is_some());
        // Short of it, along it below, or beyond the map's edge: nothing.
        assert!(m.first_occupied([0.55, 0.5], [0.55, 0.95]).is_none());
        assert!(m.first_occupied([0.05, 0.95], [1.95, 0.95]).is_none());
        assert!(m.first_occupied([-1.0, 0.5], [-0.5, 1.5]).is_none());
        assert!(m.first_occupied([0.5, f64::NAN], [0.5, 1.5]).is_none());
        // From beyond the map, through it: the wall's cells are met after clipping.
        assert!(m.first_occupied([1.0, -3.0], [1.0, 5.0]).is_some());
        // A door at x in [0.8, 1.2): through it, free; beside it, stopped.
        let door = walled(|i, j| j == 9 && !(8..12).contains(&i));
        assert!(door.first_occupied([1.0, 0.2], [1.05, 1.8]).is_none());
        assert!(door.first_occupied([0.5, 0.2], [1.05, 1.8]).is_some());
        assert_eq!(door.cell_at([1.0, 1.05]), Some(Cell::Free));
        assert_eq!(door.cell_at([0.5, 1.05]), Some(Cell::Occupied));
        assert_eq!(door.cell_at([2.5, 1.05]), None);
    }

    #[test]
    fn a_diagonal_wall_one_cell_thick_stops_every_segment_across_it() {
        // Cells (i, i) from the bottom: a staircase along y = x, touching only at corners.
        use rand::{Rng, SeedableRng};
        let m = walled(|i, j| i == 19 - j);
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let mut crossing = 0;
        for _ in 0..2000 {
            let a = [rng.random_range(0.0..2.0), rng.random_range(0.0..2.0)];
            let b = [rng.random_range(0.0..2.0), rng.random_range(0.0..2.0)];
            if (a[1] - a[0]) * (b[1] - b[0]) < 0.0 {
                crossing += 1;
                assert!(m.first_occupied(a, b).is_some(), "{a:?} -> {b:?}");
            }
        }
        assert!(crossing > 500);
        // Through the corner the staircase's cells (4, 4) and (5, 5) share.
        assert!(m.first_occupied([0.7, 0.3], [0.3, 0.7]).is_some());
    }

    #[test]
    fn ros_convention_puts_the_lower_left_pixel_at_the_origin() {
        // 3 x 2 image, top row: free, occupied, unknown; bottom row: free, free, occupied.
        let dir = tempfile::tempdir().unwrap();
        let mut pgm = b"P5\n# comment\n3 2\n255\n".to_vec();
        pgm.extend([254u8, 0, 205, 254, 254, 0]);
        let m = OccupancyMap::load(&write_map(dir.path(), YAML, &pgm)).unwrap();
        assert_eq!((m.width(), m.height()), (3, 2));
        assert_eq!(m.cell(1, 0), Cell::Occupied);
        assert_eq!(m.cell(2, 0), Cell::Unknown);
        assert_eq!(m.cell(0, 1), Cell::Free);
        // Bottom-left pixel (0, 1): centre at origin + half a cell.
        assert_eq!(m.cell_center(0, 1), [-0.75, 2.25]);
        // Top-right pixel (2, 0): x = -1 + 2.5 * 0.5, y = 2 + 1.5 * 0.5.
        assert_eq!(m.cell_center(2, 0), [0.25, 2.75]);
        assert_eq!(m.known_cells().count(), 5);
    }

    #[test]
    fn an_open_region_is_the_disc_around_each_stop() {
        // One stop: the free cells cover pi r^2 to within the cells cut by the circle.
        let (r, res) = (3.0, 0.05);
        let m = OccupancyMap::open_around(&[[1.0, -2.0]], r, res).unwrap();
        let area = m.known_cells().count() as f64 * res * res;
        let disc = std::f64::consts::PI * r * r;
        assert!(
            (area - disc).abs() < 2.0 * std::f64::consts::PI * r * res,
            "{area} vs {disc}"
        );
        assert!(m.known_cells().all(|c| (c[0] - 1.0).hypot(c[1] + 2.0) <= r));
        // Two stops 4 m apart: 2.9 m beside the midpoint lies sqrt(2^2 + 2.9^2) = 3.52 m
        // from each, so it is unknown; 2.9 m beside a stop is free; 3.1 m beyond the far
        // one is not.
        let m = OccupancyMap::open_around(&[[0.0, 0.0], [4.0, 0.0]], r, res).unwrap();
        let at = |p: [f64; 2]| m.world_to_cell(p).map(|(i, j)| m.cell(i, j));
        assert_eq!(at([2.0, 2.9]), Some(Cell::Unknown));
        assert_eq!(at([4.0, 2.9]), Some(Cell::Free));
        assert_eq!(at([2.0, 0.0]), Some(Cell::Free));
        assert_ne!(at([7.1, 0.0]), Some(Cell::Free));
        assert_eq!(m.origin(), [-3.0, -3.0]);
    }

    #[test]
    fn an_open_region_refuses_what_it_cannot_build() {
        let e = |pts: &[[f64; 2]], m: f64, r: f64| {
            OccupancyMap::open_around(pts, m, r)
                .unwrap_err()
                .to_string()
        };
        assert!(e(&[], 3.0, 0.05).contains("no stop"));
        assert!(e(&[[f64::NAN, 0.0]], 3.0, 0.05).contains("not finite"));
        assert!(e(&[[0.0, 0.0]], 0.0, 0.05).contains("margin"));
        assert!(e(&[[0.0, 0.0]], 3.0, -1.0).contains("resolution"));
        assert!(e(&[[0.0, 0.0], [2e4, 0.0]], 3.0, 0.05).contains("span"));
        // A 2-km square of 5-cm cells is 40000 x 40000 = 1.6e9 cells: refused before a
        // cell is made (the CLI's `--open-margin 1000`).
        let big = e(&[[0.0, 0.0]], 1000.0, 0.05);
        assert!(big.contains("more than a map may have (25000000)"), "{big}");
    }

    #[test]
    fn an_image_of_more_cells_than_a_map_may_have_is_refused_from_its_header() {
        // 5000 x 5000 (a 250-m square at 5 cm) is the most; one row more is refused.
        assert!(check_size(5000, 5000).is_ok());
        assert!(check_size(5000, 5001).is_err());
        assert!(check_size(usize::MAX, 2).is_err());
        // A 20000 x 20000 image (400 MB of pixels) is refused from its first bytes: the
        // file here holds 8 KiB of them, and the message is not the short file's.
        let dir = tempfile::tempdir().unwrap();
        let mut pgm = b"P5\n20000 20000\n255\n".to_vec();
        pgm.extend([254u8; 8192]);
        let e = OccupancyMap::load(&write_map(dir.path(), YAML, &pgm))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("m.pgm") && e.contains("a 20000 x 20000 image is more cells"),
            "{e}"
        );
    }

    #[test]
    fn pixel_to_world_round_trips() {
        let m = OccupancyMap::new(7, 5, 0.05, [-4.0, -5.0], vec![Cell::Free; 35]);
        for j in 0..5 {
            for i in 0..7 {
                assert_eq!(m.world_to_cell(m.cell_center(i, j)), Some((i, j)));
            }
        }
        assert_eq!(m.world_to_cell([-4.01, -4.99]), None);
    }

    #[test]
    fn plain_pgm_reads_like_binary() {
        let dir = tempfile::tempdir().unwrap();
        let y = write_map(dir.path(), YAML, b"P2\n3 2\n255\n254 0 205\n254 254 0\n");
        let m = OccupancyMap::load(&y).unwrap();
        assert_eq!(m.cell(1, 0), Cell::Occupied);
        assert_eq!(m.cell(0, 1), Cell::Free);
    }

    #[test]
    fn a_yawed_origin_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let y = write_map(
            dir.path(),
            &YAML.replace("0.0]", "0.3]"),
            b"P2\n1 1\n255\n254\n",
        );
        let e = OccupancyMap::load(&y).unwrap_err().to_string();
        assert!(e.contains("yaw") && e.contains("m.yaml"), "{e}");
    }

    #[test]
    fn malformed_yaml_and_pgm_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let y = write_map(
            dir.path(),
            "image: m.pgm\nresolution: fine\n",
            b"P2\n1 1\n255\n254\n",
        );
        assert!(
            OccupancyMap::load(&y)
                .unwrap_err()
                .to_string()
                .contains("resolution")
        );
        let y = write_map(
            dir.path(),
            "image: m.pgm\norigin: [0, 0, 0]\n",
            b"P2\n1 1\n255\n254\n",
        );
        assert!(
            OccupancyMap::load(&y)
                .unwrap_err()
                .to_string()
                .contains("missing key `resolution`")
        );
        let y = write_map(dir.path(), YAML, b"P5\n4 4\n255\nabc");
        let e = OccupancyMap::load(&y).unwrap_err().to_string();
        assert!(e.contains("m.pgm") && e.contains("16 bytes"), "{e}");
        let y = write_map(dir.path(), YAML, b"GIF89a");
        assert!(
            OccupancyMap::load(&y)
                .unwrap_err()
                .to_string()
                .contains("not a PGM")
        );
    }

    #[test]
    fn yaml_as_yaml_writes_it() {
        // A quoted path with a `#` (no comment), a block-style origin, quoted numbers, and
        // a trailing comment.
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("room#2.pgm"), b"P2\n1 1\n255\n254\n").unwrap();
        let y = dir.path().join("m.yaml");
        std::fs::write(
            &y,
            "image: \"room#2.pgm\"  # the image\nresolution: '0.5'\norigin:\n  - -1.0\n  - 2.0\n  - 0.0\nnegate: 0\n",
        )
        .unwrap();
        let m = OccupancyMap::load(&y).unwrap();
        assert_eq!(m.cell_center(0, 0), [-0.75, 2.25]);
        assert_eq!(
            OccupancyMap::image_path(&y).unwrap(),
            dir.path().join("room#2.pgm")
        );
        // Not a mapping, or an origin of two values: refused, named.
        std::fs::write(&y, "- 1\n- 2\n").unwrap();
        assert!(
            OccupancyMap::load(&y)
                .unwrap_err()
                .to_string()
                .contains("m.yaml")
        );
        std::fs::write(&y, YAML.replace("[-1.0, 2.0, 0.0]", "[-1.0, 2.0]")).unwrap();
        let e = OccupancyMap::load(&y).unwrap_err().to_string();
        assert!(e.contains("origin") && e.contains("2 values"), "{e}");
    }

    #[test]
    fn a_map_with_no_known_cell_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let y = write_map(dir.path(), YAML, b"P2\n2 1\n255\n205 205\n");
        assert!(matches!(
            OccupancyMap::load(&y),
            Err(MapError::NoKnownCell { .. })
        ));
    }

    #[test]
    fn a_missing_image_is_refused_with_its_path() {
        let dir = tempfile::tempdir().unwrap();
        let y = dir.path().join("m.yaml");
        std::fs::write(&y, YAML.replace("m.pgm", "gone.pgm")).unwrap();
        let e = OccupancyMap::load(&y).unwrap_err().to_string();
        assert!(e.contains("gone.pgm"), "{e}");
    }
}
