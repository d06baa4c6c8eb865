//! Text drawing with even letter spacing in raster plots.
//!
//! plotters 0.3.7 rasterises text with ab_glyph but puts each glyph's bitmap at
//! the pen position, dropping the glyph's left side bearing (ab_glyph's
//! `px_bounds().min.x`), so letters sit a pixel or two off: "ob jective",
//! "vie w". [`draw_label`] therefore draws raster text one glyph at a time,
//! each shifted by its bearing as read from the embedded font's own tables.
//! Vector output keeps whole strings (the SVG viewer lays them out itself).

use super::style::{DrawResult, FONT_BYTES};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::sync::OnceLock;

/// What the correction needs from a TrueType font: the character map, each
/// glyph's left edge (`xMin`, font units) and the font height that ab_glyph
/// scales to the pixel size.
struct FontMetrics {
    data: &'static [u8],
    /// Offset of the format 4 (BMP) character map subtable.
    cmap4: usize,
    /// `loca` offset and whether its entries are 32-bit.
    loca: (usize, bool),
    glyf: usize,
    num_glyphs: u16,
    /// Ascender − descender (font units): ab_glyph's `height_unscaled`.
    height: f64,
}

fn u16_at(d: &[u8], o: usize) -> Option<u16> {
    Some(u16::from_be_bytes([*d.get(o)?, *d.get(o + 1)?]))
}
fn i16_at(d: &[u8], o: usize) -> Option<i16> {
    u16_at(d, o).map(|v| v as i16)
}
fn u32_at(d: &[u8], o: usize) -> Option<u32> {
    Some(u32::from_be_bytes([
        *d.get(o)?,
        *d.get(o + 1)?,
        *d.get(o + 2)?,
        *d.get(o + 3)?,
    ]))
}

impl FontMetrics {
    fn parse(data: &'static [u8]) -> Option<FontMetrics> {
        let num_tables = u16_at(data, 4)? as usize;
        let table = |tag: &[u8; 4]| -> Option<usize> {
            (0..num_tables).find_map(|i| {
                let rec = 12 + 16 * i;
                (data.get(rec..rec + 4)? == tag)
                    .then(|| u32_at(data, rec + 8).map(|o| o as usize))?
            })
        };
        let head = table(b"head")?;
        let hhea = table(b"hhea")?;
        let cmap = table(b"cmap")?;
        let loca = table(b"loca")?;
        let glyf = table(b"glyf")?;
        let maxp = table(b"maxp")?;

        // ttf-parser (under ab_glyph) takes the OS/2 typographic metrics when
        // the font asks for them (fsSelection bit 7), else hhea's.
        let (mut ascender, mut descender) = (i16_at(data, hhea + 4)?, i16_at(data, hhea + 6)?);
        if let Some(os2) = table(b"OS/2") {
            if u16_at(data, os2 + 62).is_some_and(|f| f & (1 << 7) != 0) {
                ascender = i16_at(data, os2 + 68)?;
                descender = i16_at(data, os2 + 70)?;
            }
        }

        let cmap4 = (0..u16_at(data, cmap + 2)? as usize).find_map(|i| {
            let rec = cmap + 4 + 8 * i;
            let (platform, encoding) = (u16_at(data, rec)?, u16_at(data, rec + 2)?);
            let sub = cmap + u32_at(data, rec + 4)? as usize;
            let unicode = (platform == 3 && encoding == 1) || platform == 0;
            (unicode && u16_at(data, sub)? == 4).then_some(sub)
        })?;

        Some(FontMetrics {
            data,
            cmap4,
            loca: (loca, i16_at(data, head + 50)? != 0),
            glyf,
            num_glyphs: u16_at(data, maxp + 4)?,
            height: f64::from(ascender) - f64::from(descender),
        })
    }

    /// Glyph index of `c` (0, the missing-glyph box, when the font lacks it).
    fn glyph_id(&self, c: char) -> Option<u16> {
        let d = self.data;
        let code = u16::try_from(u32::from(c)).ok()?;
        let seg_count = u16_at(d, self.cmap4 + 6)? as usize / 2;
        let ends = self.cmap4 + 14;
        let starts = ends + 2 * seg_count + 2;
        let deltas = starts + 2 * seg_count;
        let range_offsets = deltas + 2 * seg_count;
        for s in 0..seg_count {
            if u16_at(d, ends + 2 * s)? < code {
                continue;
            }
            let start = u16_at(d, starts + 2 * s)?;
            if start > code {
                return Some(0);
            }
            let delta = u16_at(d, deltas + 2 * s)?;
            let at = range_offsets + 2 * s;
            let range_offset = u16_at(d, at)? as usize;
            if range_offset == 0 {
                return Some(code.wrapping_add(delta));
            }
            let g = u16_at(d, at + range_offset + 2 * (code - start) as usize)?;
            return Some(if g == 0 { 0 } else { g.wrapping_add(delta) });
        }
        Some(0)
    }

    /// Left edge of glyph `id` in font units; `None` for glyphs without an
    /// outline (spaces), which draw nothing.
    fn x_min(&self, id: u16) -> Option<i16> {
        if id >= self.num_glyphs {
            return None;
        }
        let d = self.data;
        let (loca, long) = self.loca;
        let i = id as usize;
        let (from, to) = if long {
            (
                u32_at(d, loca + 4 * i)? as usize,
                u32_at(d, loca + 4 * i + 4)? as usize,
            )
        } else {
            (
                2 * u16_at(d, loca + 2 * i)? as usize,
                2 * u16_at(d, loca + 2 * i + 2)? as usize,
            )
        };
        if to <= from {
            return None;
        }
        i16_at(d, self.glyf + from + 2)
    }

    /// Where ab_glyph puts the left edge of `c`'s bitmap relative to the pen, at
    /// `size` pixels (`floor(xMin · size / height)`, as its `px_bounds`).
    fn left_px(&self, c: char, size: f64) -> Option<i32> {
        let x_min = self.x_min(self.glyph_id(c)?)?;
        if self.height <= 0.0 {
            return None;
        }
        Some((f64::from(x_min) * size / self.height).floor() as i32)
    }
}

fn metrics() -> Option<&'static FontMetrics> {
    static METRICS: OnceLock<Option<FontMetrics>> = OnceLock::new();
    METRICS
        .get_or_init(|| FontMetrics::parse(FONT_BYTES))
        .as_ref()
}

/// Pen positions are measured at this multiple of the text size, where
/// plotters' whole-pixel widths are fine enough to give sub-pixel positions.
const MEASURE_SCALE: f64 = 64.0;

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
    let Some(metrics) = metrics().filter(|_| mode == TextMode::PerGlyph) else {
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
    let size = style.font.get_size();
    // Measured unrotated: a rotated font reports its box turned, width as height.
    let big = style
        .font
        .resize(size * MEASURE_SCALE)
        .transform(FontTransform::None);
    let measure = |s: &str| -> f64 {
        big.box_size(s)
            .map(|(w, _)| f64::from(w) / MEASURE_SCALE)
            .unwrap_or(0.0)
    };
    let mut buf = [0u8; 4];
    for (i, c) in text.char_indices() {
        let glyph: &str = c.encode_utf8(&mut buf);
        let Some(left) = metrics.left_px(c, size) else {
            continue;
        };
        // The pen for `c` is where the text up to and including `c` ends, less
        // `c`'s own advance: that keeps the kerning before `c`.
        let pen = (measure(&text[..i + c.len_utf8()]) - measure(glyph)).round() as i32;
        let (ox, oy) = transform.transform(pen + left + dx - min_x, dy - min_y);
        area.draw(&Text::new(
            glyph.to_string(),
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
        let m = metrics().expect("DejaVu Sans parses");
        assert!(m.height > 0.0);
        let id = |c| m.glyph_id(c).unwrap();
        assert_ne!(id('a'), 0);
        assert_ne!(id('δ'), 0);
        assert_ne!(id('⁻'), 0);
        // A space has no outline; `j` hangs left of its pen, `H` starts right of it.
        assert_eq!(m.x_min(id(' ')), None);
        assert!(m.x_min(id('j')).unwrap() < 0);
        assert!(m.x_min(id('H')).unwrap() > 0);
        assert!(m.left_px('j', 15.0).unwrap() < 0);
        assert_eq!(m.glyph_id('\u{1F600}'), None);
    }
}
