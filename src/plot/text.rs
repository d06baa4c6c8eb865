//! Text drawing with even letter spacing in raster plots.
//!
//! plotters 0.3.7 rasterises text with ab_glyph but puts each glyph's bitmap at
//! the pen position, dropping the glyph's left side bearing (ab_glyph's
//! `px_bounds().min.x`), so letters sit a pixel or two off: "ob jective",
//! "vie w". [`draw_label`] therefore draws raster text one glyph at a time,
//! each shifted by that bearing, with pens and bearings from ab_glyph itself
//! at the scale plotters uses (the font's height is the pixel size).
//! Vector output keeps whole strings (the SVG viewer lays them out itself).

use super::style::{DrawResult, FONT_BYTES};
use ab_glyph::{Font, FontRef, GlyphId, PxScaleFont, ScaleFont};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::sync::OnceLock;

/// The embedded font as ab_glyph reads it: the same bytes plotters draws with.
fn font() -> Option<&'static FontRef<'static>> {
    static FONT: OnceLock<Option<FontRef<'static>>> = OnceLock::new();
    FONT.get_or_init(|| FontRef::try_from_slice(FONT_BYTES).ok())
        .as_ref()
}

/// Where ab_glyph puts the left edge of glyph `id`'s bitmap relative to the pen
/// (plotters drops exactly this); `None` for glyphs without an outline
/// (spaces), which draw nothing.
fn left_px(font: &PxScaleFont<&FontRef<'static>>, id: GlyphId) -> Option<i32> {
    let outlined = font.outline_glyph(id.with_scale(font.scale()))?;
    Some(outlined.px_bounds().min.x as i32)
}

/// How text reaches the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum TextMode {
    /// One text element per string (SVG: the viewer lays the string out).
    Whole,
    /// One glyph at a time at its true position (raster output).
    PerGlyph,
}

/// Draws `text` at `pos` (pixels in `area`) with `style`, anchored as its
/// `pos` says and rotated as its font's transform says, exactly where plotters
/// would put it, but with correct glyph spacing in [`TextMode::PerGlyph`].
pub(super) fn draw_label<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    text: &str,
    pos: (i32, i32),
    style: &TextStyle,
    mode: TextMode,
) -> DrawResult<DB> {
    let whole = || area.draw(&Text::new(text.to_string(), pos, style.clone()));
    let Some(font) = font().filter(|_| mode == TextMode::PerGlyph) else {
        return whole();
    };
    let Ok(((min_x, min_y), (max_x, max_y))) = style.font.layout_box(text) else {
        return whole();
    };
    // The anchoring of plotters' own text drawing, applied to the whole string.
    let (width, height) = (max_x - min_x, max_y - min_y);
    let dx = match style.pos.h_pos {
        HPos::Left => 0,
        HPos::Right => -width,
        HPos::Center => -width / 2,
    };
    let dy = match style.pos.v_pos {
        VPos::Top => 0,
        VPos::Center => -height / 2,
        VPos::Bottom => -height,
    };
    let transform = style.font.get_transform();
    let glyph_style = style.clone().pos(Pos::new(HPos::Left, VPos::Top));
    // plotters scales the font so its height is the text size, as here.
    let scaled = font.as_scaled(style.font.get_size() as f32);
    // The pen advances and kerns as in plotters' own layout of the string.
    let mut pen = 0f32;
    let mut prev = None;
    let mut buf = [0u8; 4];
    for c in text.chars() {
        let id = scaled.glyph_id(c);
        if let Some(p) = prev {
            pen += scaled.kern(p, id);
        }
        prev = Some(id);
        let at = pen.round() as i32;
        pen += scaled.h_advance(id);
        let Some(left) = left_px(&scaled, id) else {
            continue;
        };
        let (ox, oy) = transform.transform(at + left + dx - min_x, dy - min_y);
        area.draw(&Text::new(
            c.encode_utf8(&mut buf).to_string(),
            (pos.0 + ox, pos.1 + oy),
            glyph_style.clone(),
        ))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_embedded_font() {
        let font = font().expect("DejaVu Sans parses");
        let scaled = font.as_scaled(15.0);
        let id = |c| font.glyph_id(c);
        assert_ne!(id('a').0, 0);
        assert_ne!(id('δ').0, 0);
        assert_ne!(id('⁻').0, 0);
        // A space has no outline; `j` hangs left of its pen, `H` starts right of it.
        assert_eq!(left_px(&scaled, id(' ')), None);
        assert!(left_px(&scaled, id('j')).unwrap() < 0);
        assert!(left_px(&scaled, id('H')).unwrap() >= 0);
        assert!(font.outline(id('H')).unwrap().bounds.min.x > 0.0);
        // Beyond the BMP (the font's format 12 map) and missing (glyph 0, the box).
        assert_ne!(id('\u{1F600}').0, 0);
        assert_eq!(id('\u{10FFFD}').0, 0);
    }
}
