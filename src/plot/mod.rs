//! Plots of a problem and of a fit, as PNG or SVG.
//!
//! - [`draw_rays`]: the ray diagram of a problem (side view of every pair's ray
//!   beside the refractivity profile δ(y)).
//! - [`draw_convergence`]: how a fit's objective and parameters moved.
//!
//! Text is drawn with an embedded DejaVu Sans ([`ensure_font`]), so plotting
//! needs no system font library. Every figure is rendered in memory and written
//! with [`crate::io::write_atomic`]: a failed plot never leaves a partial file.

mod convergence;
mod rays;

pub use convergence::draw_convergence;
pub use rays::draw_rays;

use crate::error::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// DejaVu Sans (see `assets/fonts/LICENSE-DejaVu.txt`).
static FONT_BYTES: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// The family every text style of the plots names; also what SVG viewers get as
/// `font-family`, so they fall back to their own sans-serif font.
const FAMILY: &str = "sans-serif";

/// Registers the embedded font with plotters (once per process).
///
/// plotters' `ab_glyph` text backend knows no font until one is registered, and
/// drawing text before that fails; every plotting function calls this first.
pub fn ensure_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // Only a corrupt embedded file can fail here, which the tests would
        // catch (no text would render); plotting then reports a font error
        // instead of panicking.
        let _ = plotters::style::register_font(FAMILY, FontStyle::Normal, FONT_BYTES);
    });
}

/// The image formats plots are written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// Portable Network Graphics (raster).
    Png,
    /// Scalable Vector Graphics (text stays text).
    Svg,
}

impl ImageFormat {
    /// The format named by the extension of `path` (`.png` or `.svg`, any
    /// case); anything else is an input error.
    pub fn from_path(path: &Path) -> Result<ImageFormat> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("png") => Ok(ImageFormat::Png),
            Some("svg") => Ok(ImageFormat::Svg),
            Some(other) => Err(Error::input(
                path,
                "-",
                format!("unsupported image format `.{other}`: expected .png or .svg"),
            )),
            None => Err(Error::input(
                path,
                "-",
                "the output has no file extension: expected .png or .svg",
            )),
        }
    }
}

/// What a drawing step returns: plotters' error for the backend in use.
type DrawResult<DB> =
    std::result::Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

/// A figure that can be drawn on any plotters backend, so one drawing routine
/// serves both PNG and SVG.
trait Figure {
    /// Size in pixels (width, height).
    fn size(&self) -> (u32, u32);
    /// Draws the whole figure on `root` (already filled white).
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult<DB>;
}

fn draw_failed(e: impl std::fmt::Display) -> Error {
    Error::Failed(format!("cannot draw the plot: {e}"))
}

/// Renders `figure` to the bytes of an image file.
fn render(figure: &impl Figure, format: ImageFormat) -> Result<Vec<u8>> {
    ensure_font();
    let (w, h) = figure.size();
    match format {
        ImageFormat::Png => {
            let mut pixels = vec![0u8; w as usize * h as usize * 3];
            {
                let root = BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area();
                root.fill(&WHITE).map_err(draw_failed)?;
                figure.draw(&root).map_err(draw_failed)?;
                root.present().map_err(draw_failed)?;
            }
            let mut bytes = Vec::new();
            image::ImageEncoder::write_image(
                image::codecs::png::PngEncoder::new(&mut bytes),
                &pixels,
                w,
                h,
                image::ExtendedColorType::Rgb8,
            )
            .map_err(|e| Error::Failed(format!("cannot encode the PNG: {e}")))?;
            Ok(bytes)
        }
        ImageFormat::Svg => {
            let mut text = String::new();
            {
                let root = SVGBackend::with_string(&mut text, (w, h)).into_drawing_area();
                root.fill(&WHITE).map_err(draw_failed)?;
                figure.draw(&root).map_err(draw_failed)?;
                root.present().map_err(draw_failed)?;
            }
            Ok(text.into_bytes())
        }
    }
}

/// Renders `figure` in the format `output` names and writes it atomically.
fn save(figure: &impl Figure, output: &Path) -> Result<()> {
    let format = ImageFormat::from_path(output)?;
    let bytes = render(figure, format)?;
    crate::io::write_atomic(output, &bytes)
}

// ---------------------------------------------------------------- styling --

/// Colours of series (pairs, runs, parameters), in order: the Tableau 10
/// palette, chosen because its colours stay distinct for colour-blind readers
/// better than plotters' primaries.
const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// The colour of series `i` (the palette repeats after ten).
fn series_color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

const INK: RGBColor = RGBColor(40, 40, 40);
const MUTED: RGBColor = RGBColor(110, 110, 110);
const GRID: RGBColor = RGBColor(228, 228, 228);

const TITLE_SIZE: f64 = 26.0;
const SUBTITLE_SIZE: f64 = 15.0;
const PANEL_TITLE_SIZE: f64 = 17.0;
const AXIS_LABEL_SIZE: f64 = 15.0;
const TICK_SIZE: f64 = 13.0;
const LEGEND_SIZE: f64 = 14.0;

fn text(size: f64, color: RGBColor) -> TextStyle<'static> {
    (FAMILY, size).into_font().color(&color)
}

/// Draws the title and an optional subtitle at the top of `root` and returns the
/// area below them.
fn draw_header<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    subtitle: &str,
) -> std::result::Result<DrawingArea<DB, Shift>, DrawingAreaErrorKind<DB::ErrorType>> {
    let height = if subtitle.is_empty() { 48 } else { 70 };
    let (header, rest) = root.split_vertically(height);
    let (w, _) = header.dim_in_pixel();
    let centre = (w / 2) as i32;
    header.draw(&Text::new(
        title.to_string(),
        (centre, 12),
        text(TITLE_SIZE, INK).pos(Pos::new(HPos::Center, VPos::Top)),
    ))?;
    if !subtitle.is_empty() {
        header.draw(&Text::new(
            subtitle.to_string(),
            (centre, 44),
            text(SUBTITLE_SIZE, MUTED).pos(Pos::new(HPos::Center, VPos::Top)),
        ))?;
    }
    Ok(rest)
}

/// Draws a message in the middle of an area that has no data to show.
fn draw_placeholder<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    message: &str,
) -> DrawResult<DB> {
    let (w, h) = area.dim_in_pixel();
    area.draw(&Text::new(
        message.to_string(),
        ((w / 2) as i32, (h / 2) as i32),
        text(AXIS_LABEL_SIZE, MUTED).pos(Pos::new(HPos::Center, VPos::Center)),
    ))
}

// ----------------------------------------------------------------- ranges --

/// An axis range grown from data; ignores non-finite values.
#[derive(Clone, Copy, Debug)]
struct Span {
    lo: f64,
    hi: f64,
}

impl Span {
    const EMPTY: Span = Span {
        lo: f64::INFINITY,
        hi: f64::NEG_INFINITY,
    };

    fn include(&mut self, v: f64) {
        if v.is_finite() {
            self.lo = self.lo.min(v);
            self.hi = self.hi.max(v);
        }
    }

    fn is_empty(&self) -> bool {
        self.lo > self.hi
    }

    fn width(&self) -> f64 {
        self.hi - self.lo
    }

    /// A drawable range: `fallback` when empty, widened when degenerate, and
    /// `pad` (a fraction of the width) added on both sides. Plotters needs
    /// lo < hi, both finite, and a width that is not lost in rounding.
    fn padded(self, pad: f64, fallback: (f64, f64)) -> (f64, f64) {
        if self.is_empty() {
            return fallback;
        }
        let (mut lo, mut hi) = (self.lo, self.hi);
        let magnitude = lo.abs().max(hi.abs());
        let min_width = (magnitude * 1e-9).max(1e-12);
        if hi - lo < min_width {
            let mid = 0.5 * (lo + hi);
            let half = (magnitude * 0.05).max(1.0);
            lo = mid - half;
            hi = mid + half;
        }
        let p = (hi - lo) * pad;
        let (lo, hi) = (lo - p, hi + p);
        // Half the largest f64 keeps widths and tick arithmetic finite.
        let cap = f64::MAX / 4.0;
        (lo.max(-cap), hi.min(cap))
    }
}

/// A log-axis range in whole decades, at least two wide (so the ticks are
/// powers of ten), covering the positive finite values included.
fn decade_range(span: Span) -> (f64, f64) {
    if span.is_empty() || span.lo <= 0.0 {
        return (1e-3, 1e1);
    }
    let mut a = span.lo.log10().floor();
    let mut b = span.hi.log10().ceil();
    if b - a < 2.0 {
        let extra = 2.0 - (b - a);
        b += (extra / 2.0).ceil();
        a -= (extra / 2.0).floor();
    }
    (10f64.powf(a.max(-300.0)), 10f64.powf(b.min(300.0)))
}

/// Tick label of a log axis: `10⁻⁵` for powers of ten, `2·10⁻⁵` otherwise.
fn log_label(v: f64) -> String {
    if !(v.is_finite() && v > 0.0) {
        return String::new();
    }
    let e = v.log10().floor();
    let mut m = v / 10f64.powf(e);
    let mut e = e as i32;
    if (m - 10.0).abs() < 1e-6 {
        m = 1.0;
        e += 1;
    }
    let exp: String = e
        .to_string()
        .chars()
        .map(|c| match c {
            '-' => '⁻',
            '0' => '⁰',
            '1' => '¹',
            '2' => '²',
            '3' => '³',
            '4' => '⁴',
            '5' => '⁵',
            '6' => '⁶',
            '7' => '⁷',
            '8' => '⁸',
            '9' => '⁹',
            c => c,
        })
        .collect();
    if (m - 1.0).abs() < 1e-6 {
        format!("10{exp}")
    } else {
        format!("{}·10{exp}", format_sig(m, 2))
    }
}

/// A number with about `digits` significant digits, without trailing zeros, in
/// scientific notation when very large or small.
fn format_sig(v: f64, digits: usize) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let mag = v.abs().log10().floor() as i32;
    if !(-3..6).contains(&mag) {
        return format!("{:.*e}", digits.saturating_sub(1), v);
    }
    let decimals = (digits as i32 - 1 - mag).max(0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

// ---------------------------------------------------------------- markers --

/// Point symbols, drawn in pixel coordinates so the same code serves chart
/// points and legend swatches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Marker {
    /// Filled circle with a white core (the observer).
    Circle,
    /// Open triangle (a point on the line of sight).
    Triangle,
    /// Filled star (the target).
    Star,
    /// Diagonal cross (where the ray ended).
    Cross,
}

fn draw_marker<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (x, y): (i32, i32),
    marker: Marker,
    color: RGBColor,
) -> DrawResult<DB> {
    match marker {
        Marker::Circle => {
            area.draw(&Circle::new((x, y), 6, color.filled()))?;
            area.draw(&Circle::new((x, y), 3, WHITE.filled()))
        }
        Marker::Triangle => {
            let pts = vec![(x, y - 7), (x + 7, y + 5), (x - 7, y + 5), (x, y - 7)];
            area.draw(&Polygon::new(pts.clone(), WHITE.filled()))?;
            area.draw(&PathElement::new(pts, color.stroke_width(2)))
        }
        Marker::Star => {
            let pts: Vec<(i32, i32)> = (0..10)
                .map(|k| {
                    let r = if k % 2 == 0 { 9.0 } else { 3.8 };
                    let a = std::f64::consts::PI * (k as f64 / 5.0 - 0.5);
                    (
                        x + (r * a.cos()).round() as i32,
                        y + (r * a.sin()).round() as i32,
                    )
                })
                .collect();
            area.draw(&Polygon::new(pts.clone(), color.filled()))?;
            let mut outline = pts;
            outline.push(outline[0]);
            area.draw(&PathElement::new(outline, INK.stroke_width(1)))
        }
        Marker::Cross => {
            let style = color.stroke_width(2);
            area.draw(&PathElement::new(
                vec![(x - 5, y - 5), (x + 5, y + 5)],
                style,
            ))?;
            area.draw(&PathElement::new(
                vec![(x - 5, y + 5), (x + 5, y - 5)],
                style,
            ))
        }
    }
}

// ----------------------------------------------------------------- legend --

/// What a legend entry shows before its text.
#[derive(Clone, Copy, Debug)]
enum Swatch {
    /// A line of the given colour and width.
    Line(RGBColor, u32),
    /// A dashed line.
    Dashed(RGBColor),
    /// A point symbol.
    Marker(Marker, RGBColor),
    /// A filled box (areas such as the ground).
    Band(RGBColor),
}

/// One legend entry.
#[derive(Clone, Debug)]
struct LegendEntry {
    swatch: Swatch,
    label: String,
}

impl LegendEntry {
    fn new(swatch: Swatch, label: impl Into<String>) -> Self {
        LegendEntry {
            swatch,
            label: label.into(),
        }
    }
}

const SWATCH_W: i32 = 30;
const LEGEND_ROW: i32 = 22;
const LEGEND_GAP: i32 = 22;

fn legend_text_width(label: &str) -> i32 {
    let font = (FAMILY, LEGEND_SIZE).into_font();
    match font.box_size(label) {
        Ok((w, _)) => w as i32,
        // No font: a rough width still keeps entries apart.
        Err(_) => (label.chars().count() as f64 * LEGEND_SIZE * 0.6) as i32,
    }
}

/// Positions of the entries when flowed left to right in rows of `width`
/// pixels (relative to the legend's top-left corner).
fn legend_layout(entries: &[LegendEntry], width: i32) -> Vec<(i32, i32)> {
    let mut out = Vec::with_capacity(entries.len());
    let (mut x, mut row) = (0, 0);
    for e in entries {
        let w = SWATCH_W + 6 + legend_text_width(&e.label);
        if x > 0 && x + w > width {
            x = 0;
            row += 1;
        }
        out.push((x, row * LEGEND_ROW));
        x += w + LEGEND_GAP;
    }
    out
}

/// Pixel height a legend needs in an area `width` pixels wide.
fn legend_height(entries: &[LegendEntry], width: i32) -> i32 {
    match legend_layout(entries, width).last() {
        Some(&(_, y)) => y + LEGEND_ROW + 8,
        None => 0,
    }
}

/// Draws the entries flowed in rows from the top-left of `area`, indented by
/// `left` pixels (to line up with a chart's plotting area).
fn draw_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
    left: i32,
) -> DrawResult<DB> {
    let (w, _) = area.dim_in_pixel();
    let width = (w as i32 - left - 8).max(50);
    let at: Vec<(i32, i32)> = legend_layout(entries, width)
        .into_iter()
        .map(|(x, y)| (x + left, y))
        .collect();
    draw_legend_at(area, entries, &at)
}

/// Draws the entries one per row, from `top` pixels down.
fn draw_legend_column<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
    top: i32,
) -> DrawResult<DB> {
    let at: Vec<(i32, i32)> = (0..entries.len() as i32)
        .map(|k| (0, top + k * (LEGEND_ROW + 2)))
        .collect();
    draw_legend_at(area, entries, &at)
}

/// Draws each entry with its row's top-left corner at the given position.
fn draw_legend_at<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
    at: &[(i32, i32)],
) -> DrawResult<DB> {
    for (e, &(x, y)) in entries.iter().zip(at) {
        let cy = y + LEGEND_ROW / 2 + 4;
        match e.swatch {
            Swatch::Line(c, width) => area.draw(&PathElement::new(
                vec![(x, cy), (x + SWATCH_W, cy)],
                c.stroke_width(width),
            ))?,
            Swatch::Dashed(c) => {
                for k in 0..3 {
                    let x0 = x + k * 11;
                    area.draw(&PathElement::new(
                        vec![(x0, cy), (x0 + 7, cy)],
                        c.stroke_width(2),
                    ))?;
                }
            }
            Swatch::Marker(m, c) => draw_marker(area, (x + SWATCH_W / 2, cy), m, c)?,
            Swatch::Band(c) => area.draw(&Rectangle::new(
                [(x, cy - 6), (x + SWATCH_W, cy + 6)],
                c.filled(),
            ))?,
        }
        area.draw(&Text::new(
            e.label.clone(),
            (x + SWATCH_W + 6, cy),
            text(LEGEND_SIZE, INK).pos(Pos::new(HPos::Left, VPos::Center)),
        ))?;
    }
    Ok(())
}

/// Draws a dashed polyline in pixel coordinates (plotters' own dashed series
/// restarts the pattern at every vertex, which looks ragged on dense paths).
fn draw_dashed<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    points: &[(i32, i32)],
    style: ShapeStyle,
    dash: f64,
    gap: f64,
) -> DrawResult<DB> {
    let mut on = true;
    let mut remaining = dash;
    let mut current: Vec<(f64, f64)> = Vec::new();
    for pair in points.windows(2) {
        let a = (pair[0].0 as f64, pair[0].1 as f64);
        let b = (pair[1].0 as f64, pair[1].1 as f64);
        let len = (b.0 - a.0).hypot(b.1 - a.1);
        if len == 0.0 {
            continue;
        }
        if on && current.is_empty() {
            current.push(a);
        }
        let mut t = 0.0;
        while t < len {
            let step = remaining.min(len - t);
            t += step;
            remaining -= step;
            let p = (a.0 + (b.0 - a.0) * t / len, a.1 + (b.1 - a.1) * t / len);
            if on {
                current.push(p);
            }
            if remaining <= 0.0 {
                if on {
                    flush_dash(area, &mut current, style)?;
                    remaining = gap;
                } else {
                    current.push(p);
                    remaining = dash;
                }
                on = !on;
            }
        }
    }
    flush_dash(area, &mut current, style)
}

fn flush_dash<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    current: &mut Vec<(f64, f64)>,
    style: ShapeStyle,
) -> DrawResult<DB> {
    if current.len() >= 2 {
        let pts: Vec<(i32, i32)> = current
            .iter()
            .map(|&(x, y)| (x.round() as i32, y.round() as i32))
            .collect();
        area.draw(&PathElement::new(pts, style))?;
    }
    current.clear();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_from_extension() {
        assert_eq!(
            ImageFormat::from_path(Path::new("a/b.PNG")).unwrap(),
            ImageFormat::Png
        );
        assert_eq!(
            ImageFormat::from_path(Path::new("b.svg")).unwrap(),
            ImageFormat::Svg
        );
        for bad in ["b.jpg", "b", "b.png.txt"] {
            let e = ImageFormat::from_path(Path::new(bad)).unwrap_err();
            assert_eq!(e.exit_code(), 2, "{bad}");
        }
    }

    #[test]
    fn log_labels() {
        assert_eq!(log_label(1e-5), "10⁻⁵");
        assert_eq!(log_label(1.0), "10⁰");
        assert_eq!(log_label(1e3 * (1.0 - 1e-12)), "10³");
        assert_eq!(log_label(2e-5), "2·10⁻⁵");
    }

    #[test]
    fn spans_are_drawable() {
        let mut s = Span::EMPTY;
        assert_eq!(s.padded(0.1, (0.0, 1.0)), (0.0, 1.0));
        s.include(f64::NAN);
        s.include(3.0);
        let (lo, hi) = s.padded(0.0, (0.0, 1.0));
        assert!(lo < 3.0 && hi > 3.0);
        let (lo, hi) = decade_range(Span { lo: 3e-7, hi: 4e-7 });
        assert!(lo <= 3e-7 && hi >= 4e-7 && hi / lo >= 99.0);
    }
}
