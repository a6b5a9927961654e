//! Every figure iasm draws, with plotters: axes in units, a title and a legend on each.
//!
//! | figure | drawn by | what it is for |
//! |---|---|---|
//! | [`map()`] | `iasm map --png`, `iasm demo` | the paper's Fig. 7/8: where the sources are, read off metric axes |
//! | [`comparison()`]: `ospa.svg` | `iasm compare --out` | which DoA source gives the best maps, and how the seeds spread |
//! | [`comparison()`]: `error_by_distance.svg` | `iasm compare --out` | at what range a method's DoAs fail |
//! | [`comparison()`]: `maps.svg` | `iasm compare --out` | what each method's errors look like on the map |
//! | [`diff()`] | `iasm diff --png` | what changed between two maps of one building |
//! | [`curve()`] | `iasm watch --replay --curve` | how fast the map converges as the robot moves |
//!
//! A figure goes to SVG or PNG by its file's extension. SVG keeps text as text (a reader or
//! a test finds every label); PNG rasterises it with an embedded DejaVu Sans through
//! plotters' pure-Rust `ab_glyph` back end, so the picture is the same on every machine and
//! no system font or C library is needed. Files are written whole (a temporary name, then a
//! rename).

mod comparison;
mod curve;
mod diff;
mod map;

use std::path::Path;
use std::sync::Once;

use anyhow::{Context, Result, bail};
use plotters::coord::Shift;
use plotters::prelude::*;

pub use comparison::comparison;
pub use curve::{Curve, curve};
pub use diff::{DiffFigure, diff};
pub use map::{MapFigure, map};

/// Colours of successive rows or sources (colour-blind-safe, Okabe & Ito).
const PALETTE: [RGBColor; 8] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
    RGBColor(240, 228, 66),
];

fn colour(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// The colour of each kind of change between two maps, in `iasm diff`'s figure and on the
/// live node's `/iasm/changes`: the palette's blue, orange, vermillion and green.
pub(crate) fn change_colour(k: asm::diff::ChangeKind) -> RGBColor {
    use asm::diff::ChangeKind;
    PALETTE[match k {
        ChangeKind::Kept => 0,
        ChangeKind::Moved => 4,
        ChangeKind::Removed => 1,
        ChangeKind::Added => 2,
    }]
}

/// The bounding box `(x0, x1, y0, y1)` of the finite points among `pts`, widened by
/// `margin` on every side; `None` when there is none.
fn bounds(pts: impl IntoIterator<Item = [f64; 2]>, margin: f64) -> Option<(f64, f64, f64, f64)> {
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in pts
        .into_iter()
        .filter(|p| p[0].is_finite() && p[1].is_finite())
    {
        x0 = x0.min(p[0]);
        x1 = x1.max(p[0]);
        y0 = y0.min(p[1]);
        y1 = y1.max(p[1]);
    }
    x0.is_finite()
        .then_some((x0 - margin, x1 + margin, y0 - margin, y1 + margin))
}

/// A plotters error as ours (its drawing errors are `Debug` only).
fn fail<E: std::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow::anyhow!("drawing failed: {e:?}")
}

/// Hands plotters the one font every figure uses, as "sans-serif" (its text layout needs
/// glyph metrics on both back ends).
fn register_font() {
    static FONT: Once = Once::new();
    FONT.call_once(|| {
        // The bytes are a valid TrueType file shipped by the `dejavu` crate.
        if plotters::style::register_font("sans-serif", FontStyle::Normal, dejavu::sans::regular())
            .is_err()
        {
            eprintln!("warning: the embedded font could not be loaded; figure text may be missing");
        }
    });
}

/// A figure that can be drawn on any plotters back end.
pub trait Draw {
    /// Size in pixels.
    fn size(&self) -> (u32, u32);
    /// Draws the figure on `root`, already filled white.
    ///
    /// # Errors
    /// A drawing error.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>;
}

/// The image format a figure file's extension asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// `.svg`
    Svg,
    /// `.png`
    Png,
}

impl Format {
    /// The format of `path` by its extension (case-insensitive).
    ///
    /// # Errors
    /// Any other extension, named with the file.
    pub fn of(path: &Path) -> Result<Self> {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("svg") => Ok(Self::Svg),
            Some("png") => Ok(Self::Png),
            _ => bail!(
                "{}: a figure is written as .png or .svg (chosen by the file's extension)",
                path.display()
            ),
        }
    }
}

/// Draws `fig` and writes it to `path` whole, as SVG or PNG by the extension.
///
/// # Errors
/// An unknown extension, a drawing error, or a file that cannot be written; named.
pub fn write(path: &Path, fig: &impl Draw) -> Result<()> {
    register_font();
    let (w, h) = fig.size();
    let bytes = match Format::of(path)? {
        Format::Svg => {
            let mut svg = String::new();
            {
                let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
                root.fill(&WHITE).map_err(fail)?;
                fig.draw(&root)?;
                root.present().map_err(fail)?;
            }
            svg.into_bytes()
        }
        Format::Png => {
            let mut rgb = vec![0u8; 3 * w as usize * h as usize];
            {
                let root = BitMapBackend::with_buffer(&mut rgb, (w, h)).into_drawing_area();
                root.fill(&WHITE).map_err(fail)?;
                fig.draw(&root)?;
                root.present().map_err(fail)?;
            }
            encode_png(&rgb, w, h).with_context(|| format!("encoding {}", path.display()))?
        }
    };
    crate::output::write_atomic(path, &bytes).with_context(|| format!("figure {}", path.display()))
}

/// An RGB buffer as PNG bytes.
fn encode_png(rgb: &[u8], w: u32, h: u32) -> Result<Vec<u8>> {
    let mut bytes = Vec::new();
    let mut enc = png::Encoder::new(&mut bytes, w, h);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut wr = enc.write_header()?;
    wr.write_image_data(rgb)?;
    wr.finish()?;
    Ok(bytes)
}

/// Draws a `size`-pixel SVG figure on a white ground with `draw` and writes it to `path`
/// whole.
fn write_svg(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&DrawingArea<SVGBackend<'_>, Shift>) -> Result<()>,
) -> Result<()> {
    register_font();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        root.fill(&WHITE).map_err(fail)?;
        draw(&root)?;
        root.present().map_err(fail)?;
    }
    crate::output::write_atomic(path, svg.as_bytes())
        .with_context(|| format!("figure {}", path.display()))
}

/// Draws the legend of `chart`'s labelled series at `pos` in a `font_px` font, on a light,
/// framed box.
fn legend<'a, DB, CT>(
    chart: &mut ChartContext<'a, DB, CT>,
    pos: SeriesLabelPosition,
    font_px: u32,
) -> Result<()>
where
    DB: DrawingBackend + 'a,
    CT: CoordTranslate,
{
    chart
        .configure_series_labels()
        .position(pos)
        .label_font(("sans-serif", font_px))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(fail)
}
