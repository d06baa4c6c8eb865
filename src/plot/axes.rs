//! Charts and their axes: building a chart with room for its text, drawing
//! the axis text, the spans of data, decades and tick labels.

use super::style::{
    AXIS_LABEL_SIZE, DrawResult, FAMILY, GRID, INK, MUTED, PANEL_TITLE_SIZE, TICK_SIZE, anchored,
    text,
};
use super::text::{TextMode, draw_label};
use plotters::coord::Shift;
use plotters::coord::ranged1d::{BoldPoints, Ranged};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

// ------------------------------------------------------------------- axes --

/// A chart with linear f64 axes (log axes are drawn as linear axes of log10).
pub(super) type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Height reserved above a plotting area for the panel caption.
pub(super) const CAPTION_SPACE: u32 = 34;
/// Height reserved below a plotting area for tick labels and the axis label.
pub(super) const X_LABEL_AREA: u32 = 56;

/// The text around one chart; plotters draws the grid, axes and ticks, and
/// [`draw_axes`] the rest, so every string goes through [`draw_label`].
pub(super) struct Axes<'a> {
    pub(super) caption: &'a str,
    pub(super) x_desc: &'a str,
    pub(super) y_desc: &'a str,
    /// Most tick labels per axis.
    pub(super) x_ticks: usize,
    pub(super) y_ticks: usize,
    pub(super) x_format: &'a dyn Fn(f64) -> String,
    pub(super) y_format: &'a dyn Fn(f64) -> String,
}

/// Builds a chart on `area` with room for a caption above and tick labels and
/// axis labels below and to the left (`y_label_area` pixels wide).
pub(super) fn build_chart<'a, DB: DrawingBackend>(
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
pub(super) fn draw_axes<DB: DrawingBackend>(
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
pub(super) fn minus(label: String) -> String {
    label.replace('-', "−")
}

/// Width in pixels of `label` at `size`.
pub(super) fn text_width(label: &str, size: f64) -> i32 {
    match (FAMILY, size).into_font().box_size(label) {
        Ok((w, _)) => w as i32,
        // No font: a rough width still keeps things apart.
        Err(_) => (label.chars().count() as f64 * size * 0.6) as i32,
    }
}

/// Maps chart coordinates to pixels of the chart's plotting area, for shapes
/// drawn in pixels (markers, dashes) on [`Chart::plotting_area`]`.strip_coord_spec()`.
pub(super) fn pixel_mapper<'c, DB: DrawingBackend>(
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
pub(super) struct Span {
    pub(super) lo: f64,
    pub(super) hi: f64,
}

impl Span {
    pub(super) const EMPTY: Span = Span {
        lo: f64::INFINITY,
        hi: f64::NEG_INFINITY,
    };

    pub(super) fn include(&mut self, v: f64) {
        if v.is_finite() {
            self.lo = self.lo.min(v);
            self.hi = self.hi.max(v);
        }
    }

    pub(super) fn is_empty(&self) -> bool {
        self.lo > self.hi
    }

    pub(super) fn width(&self) -> f64 {
        self.hi - self.lo
    }

    /// A drawable range: `fallback` when empty, widened when degenerate, and
    /// `pad` (a fraction of the width) added on both sides. Plotters needs
    /// lo < hi, both finite, and a width that is not lost in rounding.
    pub(super) fn padded(self, pad: f64, fallback: (f64, f64)) -> (f64, f64) {
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
pub(super) fn decade_range(span: Span) -> (f64, f64) {
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
pub(super) const LOG_TICKS: usize = 9;

/// How many tick labels to ask plotters for on a log axis from
/// [`decade_range`]: one per decade at most, so labels land on powers of ten.
pub(super) fn decade_ticks((a, b): (f64, f64)) -> usize {
    ((b - a).clamp(0.0, LOG_TICKS as f64) as usize + 1).min(LOG_TICKS)
}

/// Tick label of a log axis: `10⁻⁵` for powers of ten, `2·10⁻⁵` otherwise.
pub(super) fn log_label(v: f64) -> String {
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
pub(super) fn format_sig(v: f64, digits: usize) -> String {
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
