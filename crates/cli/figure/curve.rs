//! The online mapping curve, like the authors' `online_ospa_*.xlsx`: the map's OSPA (and
//! its localisation and cardinality parts) after every stop, so that one sees how fast the
//! map converges as the robot moves; the sources found when no truth is known.

use anyhow::Result;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::{Draw, colour, fail, legend};
use crate::online::StopRecord;

/// The curve of a run.
pub struct Curve<'a> {
    /// The title.
    pub title: String,
    /// One record per stop.
    pub records: &'a [StopRecord],
}

impl Draw for Curve<'_> {
    fn size(&self) -> (u32, u32) {
        (800, 440)
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let n = self.records.len().max(1) as f64;
        let with_truth = self.records.iter().any(|r| r.ospa.is_some());
        let series: Vec<(&str, Vec<(f64, f64)>)> = if with_truth {
            let pts = |f: fn(&asm::ospa::Ospa) -> f64| {
                self.records
                    .iter()
                    .filter_map(|r| r.ospa.as_ref().map(|o| (r.stop as f64, f(o))))
                    .collect()
            };
            vec![
                ("OSPA", pts(|o| o.total)),
                ("localisation part", pts(|o| o.localization)),
                ("cardinality part", pts(|o| o.cardinality)),
            ]
        } else {
            vec![(
                "sources found",
                self.records
                    .iter()
                    .map(|r| (r.stop as f64, r.sources as f64))
                    .collect(),
            )]
        };
        let top = series
            .iter()
            .flat_map(|(_, v)| v.iter().map(|p| p.1))
            .fold(0.1f64, f64::max)
            * 1.1;
        let mut chart = ChartBuilder::on(root)
            .caption(&self.title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.5f64..n + 0.5, 0f64..top)
            .map_err(fail)?;
        chart
            .configure_mesh()
            .x_desc("stop")
            .x_label_formatter(&|x| format!("{x:.0}"))
            .y_desc(if with_truth { "OSPA (m)" } else { "sources" })
            .draw()
            .map_err(fail)?;
        for (i, (name, pts)) in series.iter().enumerate() {
            let c = colour(i);
            let w = if i == 0 { 2 } else { 1 };
            chart
                .draw_series(LineSeries::new(pts.iter().copied(), c.stroke_width(w)))
                .map_err(fail)?
                .label(*name)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(w))
                });
        }
        // The stops that took in a full map (the one after each stop that started one).
        let full: Vec<(f64, f64)> = self
            .records
            .iter()
            .filter(|r| r.full_map_ms.is_some())
            .filter_map(|r| series[0].1.iter().find(|p| p.0 == r.stop as f64).copied())
            .collect();
        let c = colour(0);
        chart
            .draw_series(full.iter().map(|&p| Circle::new(p, 4, c.filled())))
            .map_err(fail)?
            .label("a full map taken in")
            .legend(move |(x, y)| Circle::new((x + 7, y), 4, c.filled()));
        legend(&mut chart, SeriesLabelPosition::UpperRight, 12)
    }
}

/// Draws `curve` to `path` (PNG or SVG by the extension), whole.
///
/// # Errors
/// As [`super::write`].
pub fn curve(path: &std::path::Path, curve: &Curve<'_>) -> Result<()> {
    super::write(path, curve)
}
