//! The look shared by every plot: the embedded font, the colours, the text
//! sizes and styles, and what a drawing step returns.

use plotters::prelude::*;
use plotters::style::FontStyle;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// DejaVu Sans (see `src/plot/fonts/LICENSE-DejaVu.txt`).
pub(super) static FONT_BYTES: &[u8] = include_bytes!("fonts/DejaVuSans.ttf");

/// The family every text style of the plots names; also what SVG viewers get as
/// `font-family`, so they fall back to their own sans-serif font.
pub(super) const FAMILY: &str = "sans-serif";

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

/// What a drawing step returns: plotters' error for the backend in use.
pub(super) type DrawResult<DB> =
    std::result::Result<(), DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

// ---------------------------------------------------------------- styling --

/// Colours of series (pairs, runs, parameters), in order: the Tableau 10
/// palette, chosen because its colours stay distinct for colour-blind readers
/// better than plotters' primaries.
pub(super) const PALETTE: [RGBColor; 10] = [
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
pub(super) fn series_color(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

pub(super) const INK: RGBColor = RGBColor(40, 40, 40);
pub(super) const MUTED: RGBColor = RGBColor(110, 110, 110);
pub(super) const GRID: RGBColor = RGBColor(228, 228, 228);

// Text sizes are even: plotters places a glyph at trunc(size/2 + top), which
// for odd sizes rounds tall and short glyphs differently and lifts the
// decimal point a pixel above the digits.
pub(super) const TITLE_SIZE: f64 = 26.0;
pub(super) const SUBTITLE_SIZE: f64 = 16.0;
pub(super) const PANEL_TITLE_SIZE: f64 = 18.0;
pub(super) const AXIS_LABEL_SIZE: f64 = 16.0;
pub(super) const TICK_SIZE: f64 = 14.0;
pub(super) const LEGEND_SIZE: f64 = 14.0;

pub(super) fn text(size: f64, color: RGBColor) -> TextStyle<'static> {
    (FAMILY, size).into_font().color(&color)
}

pub(super) fn anchored(style: TextStyle<'static>, h: HPos, v: VPos) -> TextStyle<'static> {
    style.pos(Pos::new(h, v))
}
