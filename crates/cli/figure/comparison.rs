//! The method comparison's three figures: OSPA per method as box plots (which DoA source
//! gives the best maps, and how the seeds spread), DoA error against the source's distance
//! (where in range a method fails), and the maps side by side (what its errors look like).

use std::path::Path;

use anyhow::Result;
use plotters::prelude::*;

use super::{colour, fail, legend, write_svg};
use crate::compare::Report;

/// Writes all three figures of `report` into `dir`: `ospa.svg`, `error_by_distance.svg`,
/// `maps.svg`.
///
/// # Errors
/// A figure that cannot be drawn or written, named.
pub fn comparison(report: &Report, dir: &Path) -> Result<()> {
    ospa_boxes(report, &dir.join("ospa.svg"))?;
    error_by_distance(report, &dir.join("error_by_distance.svg"))?;
    maps(report, &dir.join("maps.svg"))
}

/// OSPA of every row's runs as a box plot (quartiles and whiskers).
///
/// # Errors
/// As [`comparison`].
pub fn ospa_boxes(report: &Report, path: &Path) -> Result<()> {
    let names: Vec<String> = report.rows.iter().map(|r| r.name.clone()).collect();
    let top = report
        .rows
        .iter()
        .flat_map(|r| r.ospa.runs.iter().copied())
        .fold(0.1f64, f64::max) as f32
        * 1.1;
    let width = (160 * names.len() as u32).max(480);
    write_svg(path, (width, 420), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(
                format!("Map OSPA per DoA source ({} runs, CA)", report.runs),
                ("sans-serif", 20),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(names[..].into_segmented(), 0f32..top)
            .map_err(fail)?;
        chart
            .configure_mesh()
            .x_desc("DoA source")
            .y_desc("OSPA (m)")
            .disable_x_mesh()
            .draw()
            .map_err(fail)?;
        for (i, r) in report.rows.iter().enumerate() {
            let q = Quartiles::new(&r.ospa.runs);
            let c = colour(i);
            chart
                .draw_series(std::iter::once(
                    Boxplot::new_vertical(SegmentValue::CenterOf(&names[i]), &q)
                        .width(30)
                        .style(c),
                ))
                .map_err(fail)?
                .label(format!("{} (mean {:.3} m)", r.name, r.ospa.mean))
                .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 15, y + 5)], c.filled()));
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight, 12)
    })
}

/// Mean absolute DoA error (degrees) by the source's distance from the robot, one line per
/// row.
///
/// # Errors
/// As [`comparison`].
pub fn error_by_distance(report: &Report, path: &Path) -> Result<()> {
    let bands: Vec<String> = report
        .rows
        .first()
        .map(|r| r.diagnostics.bands.iter().map(|b| b.band.clone()).collect())
        .unwrap_or_default();
    let top = report
        .rows
        .iter()
        .flat_map(|r| r.diagnostics.bands.iter().map(|b| b.mean_abs_err_deg))
        .filter(|v| v.is_finite())
        .fold(1.0f64, f64::max)
        * 1.15;
    write_svg(path, (640, 420), |root| {
        let last = bands.len().saturating_sub(1) as f64;
        let mut chart = ChartBuilder::on(root)
            .caption(
                format!(
                    "DoA error by source distance (DoAs within {} deg)",
                    crate::compare::MATCH_DEG
                ),
                ("sans-serif", 20),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(-0.3f64..last + 0.3, 0f64..top)
            .map_err(fail)?;
        let band_label = |x: &f64| {
            let i = x.round();
            if (x - i).abs() < 1e-6 && i >= 0.0 {
                bands.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        };
        chart
            .configure_mesh()
            .x_desc("distance from the robot to the source")
            .y_desc("mean |error| (deg)")
            .x_labels(bands.len().max(2))
            .x_label_formatter(&band_label)
            .draw()
            .map_err(fail)?;
        for (i, r) in report.rows.iter().enumerate() {
            let c = colour(i);
            let pts: Vec<(f64, f64)> = r
                .diagnostics
                .bands
                .iter()
                .enumerate()
                .filter(|(_, b)| b.mean_abs_err_deg.is_finite())
                .map(|(k, b)| (k as f64, b.mean_abs_err_deg))
                .collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))
                .map_err(fail)?
                .label(r.name.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2))
                });
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 3, c.filled())))
                .map_err(fail)?;
        }
        legend(&mut chart, SeriesLabelPosition::UpperRight, 12)
    })
}

/// Every row's first-seed map beside the others: true sources, the stops, the sources
/// found; axes in metres at one scale for all panels.
///
/// # Errors
/// As [`comparison`].
pub fn maps(report: &Report, path: &Path) -> Result<()> {
    let k = report.rows.len().max(1);
    let cols = k.min(3);
    let rows = k.div_ceil(cols);
    let pts = report
        .truth
        .iter()
        .chain(&report.path)
        .chain(report.rows.iter().flat_map(|r| r.map_seed0.iter()));
    let (x0, x1, y0, y1) = super::bounds(pts.copied(), 0.5).unwrap_or((-1.5, 1.5, -1.5, 1.5));
    // Equal scale in x and y: panels take the data's aspect.
    let panel_w = 420u32;
    let panel_h =
        ((f64::from(panel_w) - 70.0) * (y1 - y0) / (x1 - x0) + 90.0).clamp(200.0, 900.0) as u32;
    let size = (panel_w * cols as u32, panel_h * rows as u32 + 40);
    write_svg(path, size, |root| {
        let (title, body) = root.split_vertically(40);
        title
            .titled(
                &format!(
                    "Maps of the first seed (seed {}), one per DoA source",
                    report.seed0
                ),
                ("sans-serif", 20),
            )
            .map_err(fail)?;
        let panels = body.split_evenly((rows, cols));
        for (i, (r, area)) in report.rows.iter().zip(panels.iter()).enumerate() {
            let c = colour(i);
            let mut chart = ChartBuilder::on(area)
                .caption(
                    format!(
                        "{}: {} found, OSPA {:.3} m",
                        r.name,
                        r.map_seed0.len(),
                        r.ospa.runs.first().copied().unwrap_or(f64::NAN)
                    ),
                    ("sans-serif", 14),
                )
                .margin(8)
                .x_label_area_size(30)
                .y_label_area_size(40)
                .build_cartesian_2d(x0..x1, y0..y1)
                .map_err(fail)?;
            chart
                .configure_mesh()
                .x_desc("x (m)")
                .y_desc("y (m)")
                .light_line_style(WHITE)
                .draw()
                .map_err(fail)?;
            let grey = RGBColor(150, 150, 150);
            chart
                .draw_series(LineSeries::new(
                    report.path.iter().map(|p| (p[0], p[1])),
                    grey,
                ))
                .map_err(fail)?
                .label("robot stops")
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 15, y)], grey));
            chart
                .draw_series(
                    report
                        .path
                        .iter()
                        .map(|p| Circle::new((p[0], p[1]), 2, grey.filled())),
                )
                .map_err(fail)?;
            chart
                .draw_series(
                    report
                        .truth
                        .iter()
                        .map(|p| Cross::new((p[0], p[1]), 6, BLACK.stroke_width(2))),
                )
                .map_err(fail)?
                .label("true source")
                .legend(|(x, y)| Cross::new((x + 7, y), 5, BLACK.stroke_width(2)));
            chart
                .draw_series(
                    r.map_seed0
                        .iter()
                        .map(|p| Circle::new((p[0], p[1]), 6, c.stroke_width(2))),
                )
                .map_err(fail)?
                .label("source found")
                .legend(move |(x, y)| Circle::new((x + 7, y), 5, c.stroke_width(2)));
            legend(&mut chart, SeriesLabelPosition::LowerRight, 11)?;
        }
        Ok(())
    })
}
