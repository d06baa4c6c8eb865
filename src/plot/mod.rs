//! Plots of a problem and of a fit, as PNG or SVG.
//!
//! - [`draw_rays`]: the ray diagram of a problem (side view of every pair's ray
//!   beside the refractivity profile δ(y)).
//! - [`draw_convergence`]: how a fit's objective and parameters moved.
//! - [`draw_tradeoff`]: the speed/accuracy trade of the integrators.
//!
//! Text is drawn with an embedded DejaVu Sans ([`ensure_font`]), so plotting
//! needs no system font library; raster text is placed glyph by glyph (see
//! `text.rs`) because plotters' own placement spaces letters unevenly. Every
//! figure is rendered in memory and written with [`crate::io::write_atomic`]: a
//! failed plot never leaves a partial file.

mod convergence;
mod rays;
mod text;
mod tradeoff;

pub use convergence::draw_convergence;
pub use rays::draw_rays;
pub use tradeoff::draw_tradeoff;

use crate::error::{Error, Result};
use plotters::coord::Shift;
use plotters::coord::ranged1d::{BoldPoints, Ranged};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::FontStyle;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;
use text::{TextMode, draw_label};

/// DejaVu Sans (see `src/plot/fonts/LICENSE-DejaVu.txt`).
static FONT_BYTES: &[u8] = include_bytes!("fonts/DejaVuSans.ttf");

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
    /// Draws the whole figure on `root` (already filled white), with text drawn
    /// the way `mode` says.
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        mode: TextMode,
    ) -> DrawResult<DB>;
}

fn draw_failed(e: impl std::fmt::Display) -> Error {
    Error::encode("the plot", e)
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
                figure
                    .draw(&root, TextMode::PerGlyph)
                    .map_err(draw_failed)?;
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
            .map_err(|e| Error::encode("the PNG", e))?;
            Ok(bytes)
        }
        ImageFormat::Svg => {
            let mut text = String::new();
            {
                let root = SVGBackend::with_string(&mut text, (w, h)).into_drawing_area();
                root.fill(&WHITE).map_err(draw_failed)?;
                figure.draw(&root, TextMode::Whole).map_err(draw_failed)?;
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

// Text sizes are even: plotters places a glyph at trunc(size/2 + top), which
// for odd sizes rounds tall and short glyphs differently and lifts the
// decimal point a pixel above the digits.
const TITLE_SIZE: f64 = 26.0;
const SUBTITLE_SIZE: f64 = 16.0;
const PANEL_TITLE_SIZE: f64 = 18.0;
const AXIS_LABEL_SIZE: f64 = 16.0;
const TICK_SIZE: f64 = 14.0;
const LEGEND_SIZE: f64 = 14.0;

fn text(size: f64, color: RGBColor) -> TextStyle<'static> {
    (FAMILY, size).into_font().color(&color)
}

fn anchored(style: TextStyle<'static>, h: HPos, v: VPos) -> TextStyle<'static> {
    style.pos(Pos::new(h, v))
}

/// Draws the title and a subtitle line centred at the top of `header`.
fn draw_header<DB: DrawingBackend>(
    header: &DrawingArea<DB, Shift>,
    title: &str,
    subtitle: &str,
    mode: TextMode,
) -> DrawResult<DB> {
    let (w, _) = header.dim_in_pixel();
    let centre = (w / 2) as i32;
    let style = anchored(text(TITLE_SIZE, INK), HPos::Center, VPos::Top);
    draw_label(header, title, (centre, 12), &style, mode)?;
    let style = anchored(text(SUBTITLE_SIZE, MUTED), HPos::Center, VPos::Top);
    draw_label(header, subtitle, (centre, 46), &style, mode)
}

/// Draws a message in the middle of an area that has no data to show.
fn draw_placeholder<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    message: &str,
    mode: TextMode,
) -> DrawResult<DB> {
    let (w, h) = area.dim_in_pixel();
    let style = anchored(text(AXIS_LABEL_SIZE, MUTED), HPos::Center, VPos::Center);
    draw_label(
        area,
        message,
        ((w / 2) as i32, (h / 2) as i32),
        &style,
        mode,
    )
}

// ------------------------------------------------------------------- axes --

/// A chart with linear f64 axes (log axes are drawn as linear axes of log10).
type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Height reserved above a plotting area for the panel caption.
const CAPTION_SPACE: u32 = 34;
/// Height reserved below a plotting area for tick labels and the axis label.
const X_LABEL_AREA: u32 = 56;

/// The text around one chart; plotters draws the grid, axes and ticks, and
/// [`draw_axes`] the rest, so every string goes through [`draw_label`].
struct Axes<'a> {
    caption: &'a str,
    x_desc: &'a str,
    y_desc: &'a str,
    /// Most tick labels per axis.
    x_ticks: usize,
    y_ticks: usize,
    x_format: &'a dyn Fn(f64) -> String,
    y_format: &'a dyn Fn(f64) -> String,
}

/// Builds a chart on `area` with room for a caption above and tick labels and
/// axis labels below and to the left (`y_label_area` pixels wide).
fn build_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    x: (f64, f64),
    y: (f64, f64),
    y_label_area: u32,
) -> std::result::Result<Chart<'a, DB>, DrawingAreaErrorKind<DB::ErrorType>> {
    ChartBuilder::on(area)
        .margin_top(CAPTION_SPACE)
        .margin_left(6)
        .margin_right(26)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(y_label_area)
        .build_cartesian_2d(x.0..x.1, y.0..y.1)
}

/// Draws the grid, axes and ticks of `chart`, then its caption, tick labels and
/// axis labels on `area` (the area the chart was built on).
fn draw_axes<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    chart: &mut Chart<'_, DB>,
    axes: &Axes,
    mode: TextMode,
) -> DrawResult<DB> {
    let hidden = text(TICK_SIZE, INK).color(&TRANSPARENT);
    chart
        .configure_mesh()
        .x_labels(axes.x_ticks)
        .y_labels(axes.y_ticks)
        .label_style(hidden)
        .bold_line_style(GRID)
        .light_line_style(TRANSPARENT)
        .axis_style(MUTED)
        .draw()?;

    let base = area.get_base_pixel();
    let (xr, yr) = chart.plotting_area().get_pixel_range();
    let (left, right) = (xr.start - base.0, xr.end - base.0);
    let (top, bottom) = (yr.start - base.1, yr.end - base.1);
    let px = |x: f64, y: f64| {
        let (a, b) = chart.backend_coord(&(x, y));
        (a - base.0, b - base.1)
    };
    let (y_lo, x_lo) = (chart.y_range().start, chart.x_range().start);

    let caption = anchored(text(PANEL_TITLE_SIZE, INK), HPos::Center, VPos::Top);
    draw_label(area, axes.caption, ((left + right) / 2, 8), &caption, mode)?;

    // Ticks are multiples of a step computed in floating point, so zero can
    // come out as 5.55e-17; anything that small next to the range is zero.
    let snap = |v: f64, r: std::ops::Range<f64>| {
        if v.abs() < 1e-9 * (r.end - r.start).abs() {
            0.0
        } else {
            v
        }
    };
    let tick = anchored(text(TICK_SIZE, INK), HPos::Center, VPos::Top);
    for v in chart
        .as_coord_spec()
        .x_spec()
        .key_points(BoldPoints(axes.x_ticks))
    {
        let (x, _) = px(v, y_lo);
        let label = minus((axes.x_format)(snap(v, chart.x_range())));
        draw_label(area, &label, (x, bottom + 9), &tick, mode)?;
    }
    let tick = anchored(text(TICK_SIZE, INK), HPos::Right, VPos::Center);
    let mut widest = 0;
    for v in chart
        .as_coord_spec()
        .y_spec()
        .key_points(BoldPoints(axes.y_ticks))
    {
        let (_, y) = px(x_lo, v);
        let label = minus((axes.y_format)(snap(v, chart.y_range())));
        widest = widest.max(text_width(&label, TICK_SIZE));
        draw_label(area, &label, (left - 9, y), &tick, mode)?;
    }

    let desc = anchored(text(AXIS_LABEL_SIZE, INK), HPos::Center, VPos::Top);
    draw_label(
        area,
        axes.x_desc,
        ((left + right) / 2, bottom + 32),
        &desc,
        mode,
    )?;
    let desc = TextStyle::from(
        (FAMILY, AXIS_LABEL_SIZE)
            .into_font()
            .transform(FontTransform::Rotate270),
    )
    .color(&INK)
    .pos(Pos::new(HPos::Center, VPos::Center));
    let x = (left - 9 - widest - 16).max(10);
    draw_label(area, axes.y_desc, (x, (top + bottom) / 2), &desc, mode)
}

/// A number label with true minus signs (a hyphen reads as a dash next to
/// tick marks).
fn minus(label: String) -> String {
    label.replace('-', "−")
}

/// Width in pixels of `label` at `size`.
fn text_width(label: &str, size: f64) -> i32 {
    match (FAMILY, size).into_font().box_size(label) {
        Ok((w, _)) => w as i32,
        // No font: a rough width still keeps things apart.
        Err(_) => (label.chars().count() as f64 * size * 0.6) as i32,
    }
}

/// Maps chart coordinates to pixels of the chart's plotting area, for shapes
/// drawn in pixels (markers, dashes) on [`Chart::plotting_area`]`.strip_coord_spec()`.
fn pixel_mapper<'c, DB: DrawingBackend>(
    chart: &'c Chart<'_, DB>,
) -> impl Fn((f64, f64)) -> (i32, i32) + 'c {
    let base = chart.plotting_area().get_base_pixel();
    move |p| {
        let (a, b) = chart.backend_coord(&p);
        (a - base.0, b - base.1)
    }
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

/// A logarithmic range in whole decades, as exponents `(a, b)` (the axis runs
/// from 10^a to 10^b), at least two decades wide so the ticks fall on powers of
/// ten, covering the positive finite values included.
///
/// Log axes are drawn as linear axes of log10(v) with [`log_label`] ticks:
/// plotters' own log scale drops every tick below 2.2·10⁻¹⁶ and loops for
/// ranges whose ratio overflows, and objectives routinely go there.
fn decade_range(span: Span) -> (f64, f64) {
    if span.is_empty() || span.lo <= 0.0 {
        return (-3.0, 1.0);
    }
    let mut a = span.lo.log10().floor();
    let mut b = span.hi.log10().ceil();
    if b - a < 2.0 {
        let extra = 2.0 - (b - a);
        b += (extra / 2.0).ceil();
        a -= (extra / 2.0).floor();
    }
    // Wide ranges are labelled every few decades; ending the axis on a label
    // (the step plotters will pick, see `decade_ticks`) keeps both ends named.
    for step in [1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0] {
        let (lo, hi) = ((a / step).floor() * step, (b / step).ceil() * step);
        if (hi - lo) / step + 1.0 <= LOG_TICKS as f64 {
            return (lo, hi);
        }
    }
    (a, b)
}

/// Most labels on a log axis.
const LOG_TICKS: usize = 9;

/// How many tick labels to ask plotters for on a log axis from
/// [`decade_range`]: one per decade at most, so labels land on powers of ten.
fn decade_ticks((a, b): (f64, f64)) -> usize {
    ((b - a).clamp(0.0, LOG_TICKS as f64) as usize + 1).min(LOG_TICKS)
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
        let s = format!("{:.*e}", digits.saturating_sub(1), v);
        // 1.0e-9 → 1e-9: the digits that carry no information go.
        return match s.split_once('e') {
            Some((m, e)) if m.contains('.') => {
                format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.'))
            }
            _ => s,
        };
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
    /// Nothing: a note such as "… and 12 more".
    Blank,
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
    text_width(label, LEGEND_SIZE)
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

/// `entries` cut to at most `max`, the last slot saying how many were left
/// out: a legend must never crowd out the plot it explains.
fn truncate_legend(mut entries: Vec<LegendEntry>, max: usize, what: &str) -> Vec<LegendEntry> {
    if entries.len() > max {
        let kept = max.saturating_sub(1);
        let left_out = entries.len() - kept;
        entries.truncate(kept);
        entries.push(LegendEntry::new(
            Swatch::Blank,
            format!("… and {left_out} more {what}"),
        ));
    }
    entries
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
    mode: TextMode,
) -> DrawResult<DB> {
    let (w, _) = area.dim_in_pixel();
    let width = (w as i32 - left - 8).max(50);
    let at: Vec<(i32, i32)> = legend_layout(entries, width)
        .into_iter()
        .map(|(x, y)| (x + left, y))
        .collect();
    draw_legend_at(area, entries, &at, mode)
}

/// Draws the entries one per row, from `top` pixels down.
fn draw_legend_column<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
    top: i32,
    mode: TextMode,
) -> DrawResult<DB> {
    let at: Vec<(i32, i32)> = (0..entries.len() as i32)
        .map(|k| (0, top + k * (LEGEND_ROW + 2)))
        .collect();
    draw_legend_at(area, entries, &at, mode)
}

/// Draws each entry with its row's top-left corner at the given position.
fn draw_legend_at<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
    at: &[(i32, i32)],
    mode: TextMode,
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
            Swatch::Blank => {}
        }
        let style = anchored(text(LEGEND_SIZE, INK), HPos::Left, VPos::Center);
        draw_label(area, &e.label, (x + SWATCH_W + 6, cy), &style, mode)?;
    }
    Ok(())
}

/// A corner of a plotting area.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Corner {
    UpperLeft,
    UpperRight,
}

/// Draws `entries` one per row in a framed white box in a corner of `plot`
/// (a plotting area in pixel coordinates).
fn draw_legend_box<DB: DrawingBackend>(
    plot: &DrawingArea<DB, Shift>,
    entries: &[LegendEntry],
    corner: Corner,
    mode: TextMode,
) -> DrawResult<DB> {
    if entries.is_empty() {
        return Ok(());
    }
    let pad = 8;
    let text_w = entries
        .iter()
        .map(|e| legend_text_width(&e.label))
        .max()
        .unwrap_or(0);
    let w = SWATCH_W + 6 + text_w + 2 * pad;
    let h = entries.len() as i32 * (LEGEND_ROW + 2) + 2 * pad - 2;
    let (pw, _) = plot.dim_in_pixel();
    let x0 = match corner {
        Corner::UpperLeft => 12,
        Corner::UpperRight => pw as i32 - 12 - w,
    };
    let y0 = 12;
    plot.draw(&Rectangle::new(
        [(x0, y0), (x0 + w, y0 + h)],
        WHITE.filled(),
    ))?;
    plot.draw(&Rectangle::new(
        [(x0, y0), (x0 + w, y0 + h)],
        GRID.stroke_width(1),
    ))?;
    let at: Vec<(i32, i32)> = (0..entries.len() as i32)
        .map(|k| (x0 + pad, y0 + pad - 4 + k * (LEGEND_ROW + 2)))
        .collect();
    draw_legend_at(plot, entries, &at, mode)
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
        assert_eq!(format_sig(1e-9, 2), "1e-9");
        assert_eq!(format_sig(3.52e-12, 3), "3.52e-12");
        assert_eq!(format_sig(0.126, 2), "0.13");
        assert_eq!(format_sig(1234.6, 4), "1235");
    }

    #[test]
    fn spans_are_drawable() {
        let mut s = Span::EMPTY;
        assert_eq!(s.padded(0.1, (0.0, 1.0)), (0.0, 1.0));
        s.include(f64::NAN);
        s.include(3.0);
        let (lo, hi) = s.padded(0.0, (0.0, 1.0));
        assert!(lo < 3.0 && hi > 3.0);
        let (a, b) = decade_range(Span { lo: 3e-7, hi: 4e-7 });
        assert!(a <= -7.0 && b >= -6.0 && b - a >= 2.0);
        assert_eq!(
            decade_range(Span {
                lo: 1e-310,
                hi: 1e300
            }),
            (-400.0, 300.0)
        );
        // Thirty decades: labels every five, and both ends on a label.
        let r = decade_range(Span {
            lo: 3e-28,
            hi: 0.02,
        });
        assert_eq!(r, (-30.0, 0.0));
        assert_eq!(decade_ticks(r), 9);
    }
}
