//! The map picture, like the paper's Fig. 7/8: the occupancy map, the robot's trajectory and
//! stops (with headings), each source's particle cloud, the estimates with their 2-sigma
//! ellipses, and the truth when it is known; world axes in metres (x right, y up, REP-103) at
//! one scale in x and y.
//!
//! By default the figure is cropped to the region that holds the trajectory, the sources and
//! the truth, with a margin: on a large map (arrangement II is about 15 x 12 m) the sources
//! would otherwise be a few pixels wide. [`MapFigure::full_map`] draws the whole occupancy map.

use anyhow::Result;
use asm::map::{Cell, OccupancyMap};
use asm::{MapResult, Pose};
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

use super::{Draw, colour, fail};

/// Margin around the cropped region (m): room for the ellipses and the legend.
const MARGIN_M: f64 = 0.8;
/// Particles drawn per source at most (a cloud of thousands reads the same as one of a
/// thousand, and keeps an SVG small).
const MAX_PARTICLES: usize = 1000;

/// What the map figure shows.
pub struct MapFigure<'a> {
    /// The title: data set, DoA source, variant, sources found, OSPA.
    pub title: String,
    /// The occupancy map.
    pub map: &'a OccupancyMap,
    /// The stops.
    pub poses: &'a [Pose],
    /// The mapper's answer.
    pub result: &'a MapResult,
    /// The true source positions, when known.
    pub truth: Option<&'a [[f64; 2]]>,
    /// The whole occupancy map instead of the region around the trajectory and sources.
    pub full_map: bool,
    /// Width of the figure (px); the height follows from the region's aspect.
    pub width: u32,
    /// What each source sounds like, for the legend (`iasm map --signatures`; empty
    /// otherwise).
    pub kinds: Vec<Option<String>>,
}

/// World region `(x0, x1, y0, y1)` drawn.
pub(super) type Region = (f64, f64, f64, f64);

/// The map's chart: world metres on both axes.
pub(super) type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Occupied cells.
pub(super) const OCCUPIED: RGBColor = RGBColor(60, 60, 60);
/// Unknown cells.
pub(super) const UNKNOWN: RGBColor = RGBColor(215, 215, 215);
/// The trajectory and its stops.
const ROBOT: RGBColor = RGBColor(40, 70, 200);
/// The true sources.
const TRUTH: RGBColor = RGBColor(0, 140, 60);
/// The sources found.
const FOUND: RGBColor = RGBColor(220, 20, 20);

impl MapFigure<'_> {
    /// Font size scaled with the figure's width (16 px at 1000 px).
    fn font(&self, base: u32) -> u32 {
        font(self.width, base)
    }

    fn region(&self) -> Region {
        let full = extent(self.map);
        if self.full_map {
            return full;
        }
        let pts = self
            .poses
            .iter()
            .map(|p| [p.x, p.y])
            .chain(self.truth.unwrap_or(&[]).iter().copied())
            .chain(self.result.sources.iter().map(|s| [s.x, s.y]));
        super::bounds(pts, MARGIN_M).unwrap_or(full)
    }

    /// Pixels around the plot: (left, right, top, bottom); the legend is on the right.
    fn decoration(&self) -> (u32, u32, u32, u32) {
        decoration(self.width)
    }

    fn legend_width(&self) -> u32 {
        legend_width(self.width)
    }
}

/// A figure's font size (px) for a `base` size at 1000 px wide, scaled with its `width`.
pub(super) fn font(width: u32, base: u32) -> u32 {
    (f64::from(base) * f64::from(width) / 1000.0)
        .round()
        .max(8.0) as u32
}

/// Width of a map figure's legend column (px), outside the plot so that it hides nothing.
pub(super) fn legend_width(width: u32) -> u32 {
    font(width, 13) * 13
}

/// A map figure's margins around the plot (px: left, right, top, bottom): the axes'
/// labels and the legend column.
pub(super) fn decoration(width: u32) -> (u32, u32, u32, u32) {
    let f = font(width, 16);
    (f * 4 + 10, 20 + legend_width(width), f * 3, f * 3 + 10)
}

/// The whole occupancy map's region (m).
pub(super) fn extent(m: &OccupancyMap) -> Region {
    let (ox, oy) = (m.origin()[0], m.origin()[1]);
    (
        ox,
        ox + m.width() as f64 * m.resolution(),
        oy,
        oy + m.height() as f64 * m.resolution(),
    )
}

impl Draw for MapFigure<'_> {
    fn size(&self) -> (u32, u32) {
        metric_size(self.width, self.region(), self.decoration())
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (x0, x1, y0, y1) = self.region();
        let (l, _, _, b) = self.decoration();
        let small = self.font(13);
        let (plot, side) = root.split_horizontally(root.dim_in_pixel().0 - self.legend_width());
        let mut chart = metric_chart(&plot, &self.title, (x0, x1, y0, y1), (l, b), |f| {
            self.font(f)
        })?;
        self.draw_grid(&mut chart, (x0, x1, y0, y1))?;
        self.draw_clouds(&mut chart)?;
        self.draw_robot(
            &mut chart,
            0.04 * (x1 - x0).max(y1 - y0).clamp(2.0, 20.0) / 2.0,
        )?;
        self.draw_truth(&mut chart)?;
        self.draw_estimates(&mut chart)?;
        let mut entries = vec![
            (Glyph::Box(OCCUPIED), "occupied"),
            (Glyph::Box(UNKNOWN), "unknown"),
            (Glyph::Line(ROBOT), "trajectory"),
            (Glyph::Dot(ROBOT), "stop (heading tick)"),
            (Glyph::Dot(colour(0)), "particles (colour"),
            (Glyph::None, "per source)"),
            (Glyph::Cross(FOUND), "source found"),
            (Glyph::Ring(FOUND, 1), "2-sigma ellipse"),
        ];
        if self.truth.is_some() {
            entries.push((Glyph::Ring(TRUTH, 2), "true source"));
        }
        let kinds: Vec<(usize, String)> = self
            .kinds
            .iter()
            .enumerate()
            .filter_map(|(k, s)| s.as_ref().map(|s| (k, format!("s{}: {s}", k + 1))))
            .collect();
        entries.extend(
            kinds
                .iter()
                .map(|(k, s)| (Glyph::Dot(colour(*k)), s.as_str())),
        );
        legend_panel(&side, &entries, small)
    }
}

/// The layers of the picture, each drawn on the chart in turn.
impl MapFigure<'_> {
    /// The occupancy map within `region` ([`draw_grid`]).
    fn draw_grid<DB: DrawingBackend>(
        &self,
        chart: &mut Chart<'_, DB>,
        region: Region,
    ) -> Result<()> {
        draw_grid(chart, self.map, region)
    }

    /// Each source's particle cloud, one colour per source.
    fn draw_clouds<DB: DrawingBackend>(&self, chart: &mut Chart<'_, DB>) -> Result<()> {
        for (k, s) in self.result.sources.iter().enumerate() {
            let c = colour(k);
            let step = s.cluster.len().div_ceil(MAX_PARTICLES).max(1);
            chart
                .draw_series(
                    s.cluster
                        .iter()
                        .step_by(step)
                        .map(|p| Circle::new((p[0], p[1]), 1, c.mix(0.5).filled())),
                )
                .map_err(fail)?;
        }
        Ok(())
    }

    /// The trajectory, its stops and their headings (a tick `tick` metres long).
    fn draw_robot<DB: DrawingBackend>(&self, chart: &mut Chart<'_, DB>, tick: f64) -> Result<()> {
        chart
            .draw_series(LineSeries::new(
                self.poses.iter().map(|p| (p.x, p.y)),
                ROBOT.stroke_width(2),
            ))
            .map_err(fail)?;
        chart
            .draw_series(self.poses.iter().map(|p| {
                PathElement::new(
                    vec![
                        (p.x, p.y),
                        (p.x + tick * p.theta.cos(), p.y + tick * p.theta.sin()),
                    ],
                    ROBOT.stroke_width(2),
                )
            }))
            .map_err(fail)?;
        chart
            .draw_series(
                self.poses
                    .iter()
                    .map(|p| Circle::new((p.x, p.y), 4, ROBOT.filled())),
            )
            .map_err(fail)?;
        Ok(())
    }

    /// The true sources, when known.
    fn draw_truth<DB: DrawingBackend>(&self, chart: &mut Chart<'_, DB>) -> Result<()> {
        if let Some(truth) = self.truth {
            chart
                .draw_series(
                    truth
                        .iter()
                        .map(|t| Circle::new((t[0], t[1]), 8, TRUTH.stroke_width(2))),
                )
                .map_err(fail)?;
        }
        Ok(())
    }

    /// The sources found and their 2-sigma ellipses.
    fn draw_estimates<DB: DrawingBackend>(&self, chart: &mut Chart<'_, DB>) -> Result<()> {
        for s in &self.result.sources {
            chart
                .draw_series(LineSeries::new(
                    ellipse([s.x, s.y], s.covariance),
                    FOUND.stroke_width(1),
                ))
                .map_err(fail)?;
        }
        chart
            .draw_series(
                self.result
                    .sources
                    .iter()
                    .map(|s| Cross::new((s.x, s.y), 6, FOUND.stroke_width(2))),
            )
            .map_err(fail)?;
        Ok(())
    }
}

/// The size (px) of a figure `width` wide whose plot shows `region` at one scale in x and
/// y, with `(left, right, top, bottom)` pixels around the plot.
pub(super) fn metric_size(
    width: u32,
    (x0, x1, y0, y1): Region,
    (l, r, t, b): (u32, u32, u32, u32),
) -> (u32, u32) {
    let plot_w = f64::from(width.saturating_sub(l + r).max(100));
    let plot_h = (plot_w * (y1 - y0) / (x1 - x0)).clamp(100.0, 4.0 * plot_w);
    (width, plot_h.round() as u32 + t + b)
}

/// A chart of world metres over `region` on `plot`, titled, with its axes described and a
/// light grid; `(l, b)` are the pixels left of and below the plot, `font` scales a font
/// size with the figure.
pub(super) fn metric_chart<'a, DB: DrawingBackend>(
    plot: &'a DrawingArea<DB, Shift>,
    title: &str,
    (x0, x1, y0, y1): Region,
    (l, b): (u32, u32),
    font: impl Fn(u32) -> u32,
) -> Result<Chart<'a, DB>> {
    let mut chart = ChartBuilder::on(plot)
        .caption(title, ("sans-serif", font(18)))
        .margin_right(20)
        .margin_left(10)
        .margin_top(5)
        .x_label_area_size(b - 10)
        .y_label_area_size(l - 10)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(fail)?;
    chart
        .configure_mesh()
        .x_desc("x (m)")
        .y_desc("y (m)")
        .label_style(("sans-serif", font(13)))
        .axis_desc_style(("sans-serif", font(15)))
        .light_line_style(WHITE.mix(0.0))
        .bold_line_style(BLACK.mix(0.08))
        .draw()
        .map_err(fail)?;
    Ok(chart)
}

/// The occupancy map within `region`: unknown cells grey, occupied dark, free left white;
/// one rectangle per run of equal cells in a row.
pub(super) fn draw_grid<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    map: &OccupancyMap,
    region: Region,
) -> Result<()> {
    let res = map.resolution();
    chart
        .draw_series(runs(map, region).iter().map(|&(c, xa, xb, yt)| {
            let fill = if c == Cell::Occupied {
                OCCUPIED
            } else {
                UNKNOWN
            };
            Rectangle::new([(xa, yt), (xb, yt - res)], fill.filled())
        }))
        .map_err(fail)?;
    Ok(())
}

/// The runs of equal cells, occupied or unknown, in each row of `m` within
/// `(x0, x1, y0, y1)`: their cell, their left and right edges and their row's top (m).
fn runs(m: &OccupancyMap, (x0, x1, y0, y1): Region) -> Vec<(Cell, f64, f64, f64)> {
    let res = m.resolution();
    let (ox, oy) = (m.origin()[0], m.origin()[1]);
    let col = |x: f64| ((x - ox) / res).floor().clamp(0.0, m.width() as f64) as usize;
    let (i0, i1) = (col(x0), col(x1));
    let row_of = |y: f64| {
        let fr = ((y - oy) / res).floor().clamp(0.0, m.height() as f64) as usize;
        m.height() - fr.min(m.height())
    };
    let (j0, j1) = (row_of(y1).saturating_sub(1), row_of(y0).min(m.height()));
    let mut runs = Vec::new();
    for j in j0..j1 {
        let ytop = oy + (m.height() - j) as f64 * res;
        let mut i = i0;
        while i < i1.min(m.width()) {
            let c = m.cell(i, j);
            let start = i;
            while i < i1.min(m.width()) && m.cell(i, j) == c {
                i += 1;
            }
            if c != Cell::Free {
                runs.push((c, ox + start as f64 * res, ox + i as f64 * res, ytop));
            }
        }
    }
    runs
}

/// The 2-sigma ellipse of covariance `cov` around `m`, as a closed polyline.
pub(super) fn ellipse(m: [f64; 2], cov: [[f64; 2]; 2]) -> Vec<(f64, f64)> {
    let (a, b, d) = (cov[0][0], cov[0][1], cov[1][1]);
    let l1 = asm::pf::max_eigenvalue(cov).max(0.0);
    let l2 = (a + d - l1).max(0.0);
    let ang = 0.5 * (2.0 * b).atan2(a - d);
    let (r1, r2) = (2.0 * l1.sqrt(), 2.0 * l2.sqrt());
    (0..=72)
        .map(|k| {
            let t = std::f64::consts::TAU * f64::from(k) / 72.0;
            let (x, y) = (r1 * t.cos(), r2 * t.sin());
            (
                m[0] + x * ang.cos() - y * ang.sin(),
                m[1] + x * ang.sin() + y * ang.cos(),
            )
        })
        .collect()
}

/// Draws `fig` to `path` (PNG or SVG by the extension), whole.
///
/// # Errors
/// As [`super::write`].
pub fn map(path: &std::path::Path, fig: &MapFigure<'_>) -> Result<()> {
    super::write(path, fig)
}

/// A legend entry's mark.
#[derive(Clone, Copy)]
pub(super) enum Glyph {
    Box(RGBColor),
    Line(RGBColor),
    Dot(RGBColor),
    Cross(RGBColor),
    Ring(RGBColor, u32),
    None,
}

/// The legend as a column of entries, framed, at the top of `area`.
pub(super) fn legend_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[(Glyph, &str)],
    font_px: u32,
) -> Result<()> {
    let line = (font_px * 3 / 2) as i32;
    let (x0, y0) = (6i32, 40i32);
    let w = area.dim_in_pixel().0 as i32 - 12;
    let h = line * entries.len() as i32 + line / 2;
    area.draw(&Rectangle::new([(x0, y0), (x0 + w, y0 + h)], BLACK))
        .map_err(fail)?;
    let style = ("sans-serif", font_px).into_font();
    for (k, (g, label)) in entries.iter().enumerate() {
        let y = y0 + line * k as i32 + line * 3 / 4;
        let x = x0 + 8;
        match *g {
            Glyph::Box(c) => area.draw(&Rectangle::new([(x, y - 5), (x + 14, y + 5)], c.filled())),
            Glyph::Line(c) => area.draw(&PathElement::new(
                vec![(x, y), (x + 16, y)],
                c.stroke_width(2),
            )),
            Glyph::Dot(c) => area.draw(&Circle::new((x + 7, y), 4, c.filled())),
            Glyph::Cross(c) => area.draw(&Cross::new((x + 7, y), 5, c.stroke_width(2))),
            Glyph::Ring(c, w) => area.draw(&Circle::new((x + 7, y), 6, c.stroke_width(w))),
            Glyph::None => Ok(()),
        }
        .map_err(fail)?;
        area.draw(&Text::new(
            (*label).to_owned(),
            (x + 24, y - font_px as i32 / 2),
            style.clone(),
        ))
        .map_err(fail)?;
    }
    Ok(())
}
