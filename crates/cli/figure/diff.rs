//! The comparison of two maps (`iasm diff --png`): both maps' sources with their 2-sigma
//! ellipses, the earlier as rings and the later as dots, coloured by what happened to each
//! (kept, moved with an arrow from its old place to its new one, removed, added), over the
//! occupancy map when one is given; world axes in metres at one scale.

use anyhow::Result;
use asm::diff::{Change, ChangeKind, Placed};
use asm::map::OccupancyMap;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::map::{
    Chart, Glyph, OCCUPIED, Region, decoration, draw_grid, ellipse, extent, font, legend_panel,
    legend_width, metric_chart, metric_size,
};
use super::{Draw, change_colour, fail};

/// What the comparison's figure shows.
pub struct DiffFigure<'a> {
    /// The title: the two maps and the counts.
    pub title: String,
    /// The occupancy map to draw under the sources, if any.
    pub map: Option<&'a OccupancyMap>,
    /// The earlier map's sources.
    pub before: &'a [Placed],
    /// The later map's sources.
    pub after: &'a [Placed],
    /// What happened to each (`asm::diff::diff` of the two).
    pub changes: &'a [Change],
    /// Width (px).
    pub width: u32,
}

/// Margin around the sources (m).
const MARGIN_M: f64 = 1.0;

impl DiffFigure<'_> {
    fn font(&self, base: u32) -> u32 {
        font(self.width, base)
    }

    fn region(&self) -> Region {
        let pts = self.before.iter().chain(self.after).map(|p| [p.x, p.y]);
        super::bounds(pts, MARGIN_M)
            .unwrap_or_else(|| self.map.map_or((-1.0, 1.0, -1.0, 1.0), extent))
    }

    fn draw_sources<DB: DrawingBackend>(&self, chart: &mut Chart<'_, DB>) -> Result<()> {
        for c in self.changes {
            let col = change_colour(c.kind);
            let old = c.before.map(|i| &self.before[i]);
            let new = c.after.map(|j| &self.after[j]);
            for p in old.iter().chain(new.iter()) {
                chart
                    .draw_series(LineSeries::new(
                        ellipse([p.x, p.y], p.covariance),
                        col.mix(0.6).stroke_width(1),
                    ))
                    .map_err(fail)?;
            }
            if let (ChangeKind::Moved, Some(a), Some(b)) = (c.kind, old, new) {
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![(a.x, a.y), (b.x, b.y)],
                        col.stroke_width(2),
                    )))
                    .map_err(fail)?;
                // The arrow's head: two strokes back from the new place.
                let (dx, dy) = (b.x - a.x, b.y - a.y);
                let len = dx.hypot(dy).max(1e-9);
                let (ux, uy) = (dx / len, dy / len);
                let h = 0.15_f64.min(0.4 * len);
                for s in [1.0, -1.0] {
                    let (hx, hy) = (
                        b.x - h * (ux * 0.87 - s * uy * 0.5),
                        b.y - h * (uy * 0.87 + s * ux * 0.5),
                    );
                    chart
                        .draw_series(std::iter::once(PathElement::new(
                            vec![(b.x, b.y), (hx, hy)],
                            col.stroke_width(2),
                        )))
                        .map_err(fail)?;
                }
            }
            if let Some(a) = old {
                chart
                    .draw_series(std::iter::once(Circle::new(
                        (a.x, a.y),
                        7,
                        col.stroke_width(2),
                    )))
                    .map_err(fail)?;
                if c.kind == ChangeKind::Removed {
                    chart
                        .draw_series(std::iter::once(Cross::new(
                            (a.x, a.y),
                            6,
                            col.stroke_width(2),
                        )))
                        .map_err(fail)?;
                }
            }
            if let Some(b) = new {
                chart
                    .draw_series(std::iter::once(Circle::new((b.x, b.y), 4, col.filled())))
                    .map_err(fail)?;
            }
        }
        Ok(())
    }
}

impl Draw for DiffFigure<'_> {
    fn size(&self) -> (u32, u32) {
        metric_size(self.width, self.region(), decoration(self.width))
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let region = self.region();
        let (l, _, _, b) = decoration(self.width);
        let small = self.font(13);
        let (plot, side) =
            root.split_horizontally(root.dim_in_pixel().0 - legend_width(self.width));
        let mut chart = metric_chart(&plot, &self.title, region, (l, b), |f| self.font(f))?;
        if let Some(map) = self.map {
            draw_grid(&mut chart, map, region)?;
        }
        self.draw_sources(&mut chart)?;
        let mut entries = Vec::new();
        if self.map.is_some() {
            entries.push((Glyph::Box(OCCUPIED), "occupied"));
        }
        entries.extend([
            (Glyph::Ring(BLACK, 2), "earlier map"),
            (Glyph::Dot(BLACK), "later map"),
            (Glyph::Ring(change_colour(ChangeKind::Kept), 1), "kept"),
            (
                Glyph::Line(change_colour(ChangeKind::Moved)),
                "moved (to the dot)",
            ),
            (Glyph::Cross(change_colour(ChangeKind::Removed)), "removed"),
            (Glyph::Dot(change_colour(ChangeKind::Added)), "added"),
            (Glyph::None, "ellipses: 2 sigma"),
        ]);
        legend_panel(&side, &entries, small)
    }
}

/// Draws `fig` to `path` (PNG or SVG by the extension), whole.
///
/// # Errors
/// As [`super::write`].
pub fn diff(path: &std::path::Path, fig: &DiffFigure<'_>) -> Result<()> {
    super::write(path, fig)
}
