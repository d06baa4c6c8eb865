//! The overlay: a photo with its marks, where the air puts them, and the
//! apparent horizon drawn on it.
//!
//! [`draw_overlay`] draws on a copy of the photo, per [`OverlayMark`]: the
//! marked pixel as a ring (its centre left clear, so the marked pixel itself
//! stays visible), the fitted position as a cross joined to the ring by a
//! thin line, the straight-ray position as a small square, and the mark's
//! name beside the ring (on the side where it covers the fewest other
//! symbols and names); target marks in yellow, horizon marks in cyan. The
//! fitted apparent horizon is a dashed pink polyline (dashed so that the
//! photo's own horizon shows through it). A panel in the corner that covers
//! the fewest marks holds the title, `RMS x.xx px` and a legend of what is
//! drawn.
//!
//! Pixels follow OpenCV's convention: the centre of the top-left pixel is
//! (0, 0), u to the right, v down; shapes are placed to sub-pixel accuracy
//! and anti-aliased (see `raster.rs`); text is placed to the pixel. Every size scales with the image's diagonal D, with minimums
//! for small images: strokes max(2, D/600) px, rings of radius max(7, D/110)
//! px, text of max(14, D/85) px, so the overlay reads the same on a 640-pixel
//! photo as on a 6000-pixel one seen at screen size. Every stroke is drawn
//! bright over a dark outline, and text over a dark halo, so that both read
//! on a pale sky and on a dark sea.
//!
//! Shapes are drawn by the anti-aliased rasteriser of `raster.rs` (segments
//! clipped to the image before they are drawn, so points far outside it cost
//! nothing and non-finite points are skipped); text goes through plotters and
//! the embedded font, glyph by glyph, like every other plot of the crate.

use super::axes::text_width;
use super::raster::{Canvas, Point, dashes};
use super::style::{anchored, ensure_font, text};
use super::text::{TextMode, draw_label};
use image::RgbImage;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};

/// One mark on the photo: where it was marked and where the air puts it, in
/// pixels (u right, v down, the top-left pixel's centre at (0, 0)).
#[derive(Clone, Debug, PartialEq)]
pub struct OverlayMark {
    /// The mark's name, drawn beside it (nothing when empty).
    pub name: String,
    /// The pixel the user marked (a ring).
    pub marked: [f64; 2],
    /// Where the (fitted) air puts the target (a cross joined to the ring).
    pub fitted: Option<[f64; 2]>,
    /// Where straight rays would put it (a square).
    pub straight: Option<[f64; 2]>,
    /// A horizon mark (drawn in the horizon marks' colour).
    pub horizon: bool,
}

/// Everything drawn over a photo.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Overlay {
    /// The marks.
    pub marks: Vec<OverlayMark>,
    /// The fitted apparent horizon as a polyline in pixels (may be empty;
    /// non-finite vertices break it).
    pub horizon: Vec<[f64; 2]>,
    /// The title at the top of the panel (nothing when empty).
    pub title: String,
    /// The RMS residual in pixels, shown under the title.
    pub rms_pixels: Option<f64>,
}

/// Target marks' colour.
const TARGET: RGBColor = RGBColor(255, 214, 0);
/// Horizon marks' colour.
const HORIZON_MARK: RGBColor = RGBColor(0, 224, 255);
/// The apparent horizon's colour.
const HORIZON_LINE: RGBColor = RGBColor(255, 96, 208);
/// Outlines under strokes, halos under text.
const DARK: RGBColor = RGBColor(12, 12, 12);
/// Opacity of outlines.
const DARK_ALPHA: f64 = 0.85;
/// The panel's background and its opacity.
const PANEL: RGBColor = RGBColor(0, 0, 0);
const PANEL_ALPHA: f64 = 0.62;
/// Text in the panel.
const PANEL_TEXT: RGBColor = RGBColor(245, 245, 245);

/// Sizes in pixels for an image, all scaled with its diagonal.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Sizes {
    /// Width of the symbols' strokes.
    stroke: f64,
    /// Width of the dark outline on each side of a stroke.
    outline: f64,
    /// Width of the line joining a ring to its cross, and of the horizon.
    thin: f64,
    /// Ring radius.
    ring: f64,
    /// Half the span of a cross.
    cross: f64,
    /// Half the side of a square.
    square: f64,
    /// Text size of labels and the legend (even, as plotters wants).
    text: f64,
    /// Text size of the title.
    title: f64,
    /// Dash and gap lengths of the horizon.
    dash: f64,
    gap: f64,
}

/// The nearest even number at least `min`.
fn even(x: f64, min: f64) -> f64 {
    (x.max(min) / 2.0).round() * 2.0
}

impl Sizes {
    fn for_image(width: u32, height: u32) -> Sizes {
        let diag = f64::from(width).hypot(f64::from(height));
        let stroke = (diag / 600.0).max(2.0);
        let ring = (diag / 110.0).max(7.0);
        let text = even(diag / 85.0, 14.0);
        Sizes {
            stroke,
            outline: (0.45 * stroke).max(1.0),
            thin: (0.6 * stroke).max(1.5),
            ring,
            cross: 0.8 * ring,
            square: 0.55 * ring,
            text,
            title: even(1.2 * text, 16.0),
            dash: 8.0 * stroke,
            gap: 5.0 * stroke,
        }
    }
}

// ---------------------------------------------------------------- symbols --

/// The segments of a cross centred at `c`.
fn cross(c: Point, half: f64) -> Vec<(Point, Point)> {
    let k = half * std::f64::consts::FRAC_1_SQRT_2;
    vec![
        ([c[0] - k, c[1] - k], [c[0] + k, c[1] + k]),
        ([c[0] - k, c[1] + k], [c[0] + k, c[1] - k]),
    ]
}

/// The segments of a square centred at `c`.
fn square(c: Point, half: f64) -> Vec<(Point, Point)> {
    let corners = [
        [c[0] - half, c[1] - half],
        [c[0] + half, c[1] - half],
        [c[0] + half, c[1] + half],
        [c[0] - half, c[1] + half],
    ];
    (0..4).map(|i| (corners[i], corners[(i + 1) % 4])).collect()
}

/// Draws `segments` as one symbol: the dark outline of all of them first,
/// then the bright strokes, so that no outline crosses the symbol's own
/// stroke.
fn stroke(
    canvas: &mut Canvas,
    segments: &[(Point, Point)],
    width: f64,
    outline: f64,
    colour: RGBColor,
) {
    for &(a, b) in segments {
        canvas.segment(a, b, width + 2.0 * outline, DARK, DARK_ALPHA);
    }
    for &(a, b) in segments {
        canvas.segment(a, b, width, colour, 1.0);
    }
}

/// A ring with its outline.
fn ring(canvas: &mut Canvas, c: Point, s: &Sizes, colour: RGBColor) {
    canvas.ring(c, s.ring, s.stroke + 2.0 * s.outline, DARK, DARK_ALPHA);
    canvas.ring(c, s.ring, s.stroke, colour, 1.0);
}

fn finite(p: Point) -> bool {
    p[0].is_finite() && p[1].is_finite()
}

/// A mark's colour.
fn colour_of(mark: &OverlayMark) -> RGBColor {
    if mark.horizon { HORIZON_MARK } else { TARGET }
}

/// Draws one mark's symbols (not its name).
fn draw_mark(canvas: &mut Canvas, mark: &OverlayMark, s: &Sizes) {
    let colour = colour_of(mark);
    let m = mark.marked;
    if let Some(q) = mark.straight.filter(|&q| finite(q)) {
        stroke(canvas, &square(q, s.square), s.stroke, s.outline, colour);
    }
    if let Some(f) = mark.fitted.filter(|&f| finite(f)) {
        // The joining line starts at the ring, not at its centre.
        let (du, dv) = (f[0] - m[0], f[1] - m[1]);
        let dist = du.hypot(dv);
        if finite(m) && dist.is_finite() && dist > s.ring + s.cross {
            let from = [m[0] + du / dist * s.ring, m[1] + dv / dist * s.ring];
            let to = [f[0] - du / dist * s.cross, f[1] - dv / dist * s.cross];
            stroke(canvas, &[(from, to)], s.thin, s.outline, colour);
        }
        stroke(canvas, &cross(f, s.cross), s.stroke, s.outline, colour);
    }
    ring(canvas, m, s, colour);
}

// ------------------------------------------------------------------- text --

/// A string to draw, with its anchor.
struct Label {
    text: String,
    at: (i32, i32),
    size: f64,
    colour: RGBColor,
    h: HPos,
    v: VPos,
    /// Radius of the dark halo drawn under it (0: none).
    halo: i32,
}

/// A pixel coordinate for plotters (which takes i32): clamped far enough
/// out that nothing is drawn from it.
fn px(x: f64) -> i32 {
    x.clamp(-1e6, 1e6).round() as i32
}

/// Draws the labels through plotters on the image's own buffer.
fn draw_labels(img: &mut RgbImage, labels: &[Label]) {
    let (w, h) = img.dimensions();
    // plotters multiplies the dimensions in u32.
    if w == 0 || h == 0 || u64::from(w) * u64::from(h) > u64::from(u32::MAX) {
        return;
    }
    let buffer: &mut [u8] = img;
    let root = BitMapBackend::with_buffer(buffer, (w, h)).into_drawing_area();
    for l in labels {
        if l.text.is_empty() {
            continue;
        }
        // A failure to draw one label (no font) leaves the rest.
        if l.halo > 0 {
            let style = anchored(text(l.size, DARK), l.h, l.v);
            let r = l.halo;
            let k = (f64::from(r) * std::f64::consts::FRAC_1_SQRT_2).round() as i32;
            for (dx, dy) in [
                (r, 0),
                (-r, 0),
                (0, r),
                (0, -r),
                (k, k),
                (k, -k),
                (-k, k),
                (-k, -k),
            ] {
                let at = (l.at.0 + dx, l.at.1 + dy);
                let _ = draw_label(&root, &l.text, at, &style, TextMode::PerGlyph);
            }
        }
        let style = anchored(text(l.size, l.colour), l.h, l.v);
        let _ = draw_label(&root, &l.text, l.at, &style, TextMode::PerGlyph);
    }
    let _ = root.present();
}

/// A box [x0, y0, x1, y1] in pixels.
type Area = [f64; 4];

fn overlaps(a: &Area, b: &Area) -> bool {
    a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3]
}

/// The marks' names, each placed beside its ring where it covers the
/// fewest other things: the first of up-right, up-left, down-right,
/// down-left, right and left of the ring that stays inside the image and
/// overlaps the fewest of the panel, the names placed before it and the
/// other marks' symbols (and its own cross and square). Marks whose ring is
/// off the image get no name.
fn name_labels(overlay: &Overlay, s: &Sizes, (w, h): (f64, f64), panel: Area) -> Vec<Label> {
    let reach = s.ring + s.stroke;
    // Symbols, each with the index of its mark and whether it is the ring.
    let mut symbols: Vec<(usize, bool, Area)> = Vec::new();
    for (i, m) in overlay.marks.iter().enumerate() {
        for (p, ring) in [
            (Some(m.marked), true),
            (m.fitted, false),
            (m.straight, false),
        ] {
            if let Some(p) = p.filter(|&p| finite(p)) {
                let area = [p[0] - reach, p[1] - reach, p[0] + reach, p[1] + reach];
                symbols.push((i, ring, area));
            }
        }
    }
    let mut placed: Vec<Area> = vec![panel];
    let mut labels = Vec::new();
    let gap = 0.3 * s.text + 0.5 * s.stroke;
    let diagonal = (s.ring + gap) * std::f64::consts::FRAC_1_SQRT_2;
    let side = s.ring + gap;
    for (i, mark) in overlay.marks.iter().enumerate() {
        let m = mark.marked;
        let inside =
            finite(m) && m[0] > -reach && m[1] > -reach && m[0] < w + reach && m[1] < h + reach;
        if mark.name.is_empty() || !inside {
            continue;
        }
        let tw = f64::from(text_width(&mark.name, s.text));
        let th = s.text;
        let candidates = [
            ([m[0] + diagonal, m[1] - diagonal], HPos::Left, VPos::Bottom),
            (
                [m[0] - diagonal, m[1] - diagonal],
                HPos::Right,
                VPos::Bottom,
            ),
            ([m[0] + diagonal, m[1] + diagonal], HPos::Left, VPos::Top),
            ([m[0] - diagonal, m[1] + diagonal], HPos::Right, VPos::Top),
            ([m[0] + side, m[1]], HPos::Left, VPos::Center),
            ([m[0] - side, m[1]], HPos::Right, VPos::Center),
        ];
        let area_of = |(at, hp, vp): &(Point, HPos, VPos)| -> Area {
            let x0 = match hp {
                HPos::Left => at[0],
                HPos::Right => at[0] - tw,
                HPos::Center => at[0] - 0.5 * tw,
            };
            let y0 = match vp {
                VPos::Top => at[1],
                VPos::Bottom => at[1] - th,
                VPos::Center => at[1] - 0.5 * th,
            };
            [x0, y0, x0 + tw, y0 + th]
        };
        let cost = |c: &(Point, HPos, VPos)| -> usize {
            let a = area_of(c);
            let outside = a[0] < 0.0 || a[1] < 0.0 || a[2] > w || a[3] > h;
            let covered = placed.iter().filter(|b| overlaps(&a, b)).count()
                + symbols
                    .iter()
                    .filter(|(j, ring, b)| !(*j == i && *ring) && overlaps(&a, b))
                    .count();
            1000 * usize::from(outside) + covered
        };
        // The first of the least costly (`min_by_key` keeps the first).
        let best = candidates
            .iter()
            .min_by_key(|c| cost(c))
            .unwrap_or(&candidates[0]);
        placed.push(area_of(best));
        let (at, hp, vp) = *best;
        labels.push(Label {
            text: mark.name.clone(),
            at: (px(at[0]), px(at[1])),
            size: s.text,
            colour: colour_of(mark),
            h: hp,
            v: vp,
            halo: (s.text / 14.0).round().max(1.0) as i32,
        });
    }
    labels
}

// ------------------------------------------------------------------ panel --

/// What a legend row shows before its text.
#[derive(Clone, Copy)]
enum Swatch {
    Ring(RGBColor),
    Cross,
    Square,
    Line,
}

/// The title, the RMS line and the legend rows, laid out in a box.
struct Panel {
    lines: Vec<(String, f64)>,
    rows: Vec<(Swatch, &'static str)>,
    pad: f64,
    row: f64,
    swatch: f64,
    width: f64,
    height: f64,
}

impl Panel {
    fn new(overlay: &Overlay, s: &Sizes) -> Panel {
        let mut lines = Vec::new();
        if !overlay.title.is_empty() {
            lines.push((overlay.title.clone(), s.title));
        }
        match overlay.rms_pixels {
            Some(r) if r.is_finite() => lines.push((format!("RMS {r:.2} px"), s.text)),
            Some(_) => lines.push(("RMS not finite".to_string(), s.text)),
            None => {}
        }
        let marks = &overlay.marks;
        let mut rows = Vec::new();
        if marks.iter().any(|m| !m.horizon) {
            rows.push((Swatch::Ring(TARGET), "marked target"));
        }
        if marks.iter().any(|m| m.horizon) {
            rows.push((Swatch::Ring(HORIZON_MARK), "marked horizon"));
        }
        if marks.iter().any(|m| m.fitted.is_some()) {
            rows.push((Swatch::Cross, "fitted air"));
        }
        if marks.iter().any(|m| m.straight.is_some()) {
            rows.push((Swatch::Square, "straight rays"));
        }
        if overlay.horizon.len() >= 2 {
            rows.push((Swatch::Line, "apparent horizon"));
        }
        let pad = 0.6 * s.text;
        let row = 1.5 * s.text;
        let swatch = 2.4 * s.text;
        let widest_line = lines
            .iter()
            .map(|(t, size)| f64::from(text_width(t, *size)))
            .fold(0.0, f64::max);
        let widest_row = rows
            .iter()
            .map(|(_, t)| swatch + 0.5 * s.text + f64::from(text_width(t, s.text)))
            .fold(0.0, f64::max);
        let height: f64 =
            lines.iter().map(|(_, size)| 1.4 * size).sum::<f64>() + rows.len() as f64 * row;
        Panel {
            lines,
            rows,
            pad,
            row,
            swatch,
            width: widest_line.max(widest_row) + 2.0 * pad,
            height: height + 2.0 * pad,
        }
    }

    /// The top-left corner of the corner box that covers the fewest marks
    /// (top left first on a tie).
    fn place(&self, overlay: &Overlay, s: &Sizes, (w, h): (f64, f64)) -> Point {
        let margin = 0.6 * s.text;
        let corners = [
            [margin, margin],
            [w - margin - self.width, margin],
            [margin, h - margin - self.height],
            [w - margin - self.width, h - margin - self.height],
        ];
        let points: Vec<Point> = overlay
            .marks
            .iter()
            .flat_map(|m| [Some(m.marked), m.fitted, m.straight])
            .flatten()
            .filter(|&p| finite(p))
            .collect();
        let reach = s.ring + s.stroke;
        let covered = |c: &Point| {
            points
                .iter()
                .filter(|p| {
                    p[0] > c[0] - reach
                        && p[0] < c[0] + self.width + reach
                        && p[1] > c[1] - reach
                        && p[1] < c[1] + self.height + reach
                })
                .count()
        };
        let mut best = corners[0];
        let mut fewest = covered(&best);
        for c in &corners[1..] {
            let n = covered(c);
            if n < fewest {
                best = *c;
                fewest = n;
            }
        }
        best
    }

    /// Draws the box and the swatches, and returns the text to draw on it.
    fn draw(&self, canvas: &mut Canvas, at: Point, s: &Sizes) -> Vec<Label> {
        canvas.rect(
            at,
            [at[0] + self.width, at[1] + self.height],
            PANEL,
            PANEL_ALPHA,
        );
        let mut labels = Vec::new();
        let x = at[0] + self.pad;
        let mut y = at[1] + self.pad;
        for (line, size) in &self.lines {
            labels.push(Label {
                text: line.clone(),
                at: (px(x), px(y + 0.7 * size)),
                size: *size,
                colour: PANEL_TEXT,
                h: HPos::Left,
                v: VPos::Center,
                halo: 0,
            });
            y += 1.4 * size;
        }
        // Swatch symbols at a size that fits a row.
        let sw = Sizes {
            ring: 0.38 * s.text,
            cross: 0.42 * s.text,
            square: 0.3 * s.text,
            ..*s
        };
        for &(swatch, name) in &self.rows {
            let cy = y + 0.5 * self.row;
            let c = [x + 0.5 * self.swatch, cy];
            match swatch {
                Swatch::Ring(colour) => ring(canvas, c, &sw, colour),
                Swatch::Cross => stroke(canvas, &cross(c, sw.cross), s.stroke, s.outline, TARGET),
                Swatch::Square => {
                    stroke(canvas, &square(c, sw.square), s.stroke, s.outline, TARGET)
                }
                Swatch::Line => {
                    let line = [[x, cy], [x + self.swatch, cy]];
                    let (w, h) = canvas.size();
                    let dash = dashes(
                        &line,
                        0.4 * self.swatch,
                        0.2 * self.swatch,
                        [0.0, 0.0],
                        [w, h],
                    );
                    stroke(canvas, &dash, s.thin, s.outline, HORIZON_LINE);
                }
            }
            labels.push(Label {
                text: name.to_string(),
                at: (px(x + self.swatch + 0.5 * s.text), px(cy)),
                size: s.text,
                colour: PANEL_TEXT,
                h: HPos::Left,
                v: VPos::Center,
                halo: 0,
            });
            y += self.row;
        }
        labels
    }
}

// ------------------------------------------------------------------- draw --

/// The photo with `overlay` drawn on it (see the module notes); the same
/// size as `photo`. Never fails: points outside the image are clipped,
/// non-finite ones skipped.
pub fn draw_overlay(photo: &RgbImage, overlay: &Overlay) -> RgbImage {
    let mut img = photo.clone();
    let (w, h) = img.dimensions();
    if w == 0 || h == 0 {
        return img;
    }
    ensure_font();
    let s = Sizes::for_image(w, h);
    let size = (f64::from(w), f64::from(h));
    let mut canvas = Canvas { img: &mut img };
    // The horizon first, under the marks that should lie on it.
    let pad = s.thin + 2.0 * s.outline;
    let line = dashes(
        &overlay.horizon,
        s.dash,
        s.gap,
        [-pad, -pad],
        [size.0 - 1.0 + pad, size.1 - 1.0 + pad],
    );
    stroke(&mut canvas, &line, s.thin, s.outline, HORIZON_LINE);
    for mark in &overlay.marks {
        draw_mark(&mut canvas, mark, &s);
    }
    let panel = Panel::new(overlay, &s);
    let at = panel.place(overlay, &s, size);
    let panel_area = [at[0], at[1], at[0] + panel.width, at[1] + panel.height];
    let mut labels = name_labels(overlay, &s, size, panel_area);
    labels.extend(panel.draw(&mut canvas, at, &s));
    draw_labels(&mut img, &labels);
    img
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Rgb;

    const GREY: Rgb<u8> = Rgb([90, 120, 150]);

    fn plain(w: u32, h: u32) -> RgbImage {
        RgbImage::from_pixel(w, h, GREY)
    }

    fn mark(
        name: &str,
        marked: Point,
        fitted: Option<Point>,
        straight: Option<Point>,
    ) -> OverlayMark {
        OverlayMark {
            name: name.to_string(),
            marked,
            fitted,
            straight,
            horizon: false,
        }
    }

    /// Pixels that differ between two images of one size.
    fn changed(a: &RgbImage, b: &RgbImage) -> Vec<(u32, u32)> {
        a.enumerate_pixels()
            .filter(|(x, y, p)| b.get_pixel(*x, *y) != *p)
            .map(|(x, y, _)| (x, y))
            .collect()
    }

    /// Marks spread over the upper half of a W × H image (in fractions of
    /// W and H, so both sizes get the same layout).
    fn scene(w: u32, h: u32) -> Overlay {
        let (w, h) = (f64::from(w), f64::from(h));
        let at = |u: f64, v: f64| [u * w, v * h];
        Overlay {
            marks: vec![
                mark(
                    "lighthouse lamp",
                    at(0.3, 0.3),
                    Some(at(0.32, 0.33)),
                    Some(at(0.3, 0.4)),
                ),
                mark("church tower", at(0.6, 0.25), Some(at(0.6, 0.25)), None),
                OverlayMark {
                    horizon: true,
                    ..mark(
                        "sea horizon, right",
                        at(0.8, 0.45),
                        Some(at(0.8, 0.46)),
                        None,
                    )
                },
            ],
            horizon: vec![],
            title: "harbour looming".to_string(),
            rms_pixels: Some(0.734),
        }
    }

    #[test]
    fn marks_are_drawn_and_far_pixels_kept() {
        for (w, h) in [(640, 480), (6000, 4000)] {
            let photo = plain(w, h);
            let overlay = scene(w, h);
            let out = draw_overlay(&photo, &overlay);
            assert_eq!(out.dimensions(), (w, h));
            let s = Sizes::for_image(w, h);
            let mut checked_clear = 0;
            for m in &overlay.marks {
                // The ring passes through the point `ring` left of the mark;
                // the marked pixel itself is left clear.
                let [u, v] = m.marked;
                let on_ring = ((u - s.ring).round() as u32, v.round() as u32);
                assert_ne!(
                    out.get_pixel(on_ring.0, on_ring.1),
                    &GREY,
                    "{} at {w}",
                    m.name
                );
                // (unless the cross or square is drawn over it).
                let clear = [m.fitted, m.straight]
                    .iter()
                    .flatten()
                    .all(|q| (q[0] - u).hypot(q[1] - v) > s.ring + s.cross);
                if clear {
                    checked_clear += 1;
                    assert_eq!(
                        out.get_pixel(u as u32, v as u32),
                        &GREY,
                        "{} centre at {w}",
                        m.name
                    );
                }
                if let Some([fu, fv]) = m.fitted {
                    // The cross's centre is painted.
                    assert_ne!(out.get_pixel(fu.round() as u32, fv.round() as u32), &GREY);
                }
                if let Some([qu, qv]) = m.straight {
                    // The square's left side.
                    let x = (qu - s.square).round() as u32;
                    assert_ne!(out.get_pixel(x, qv.round() as u32), &GREY);
                    assert_eq!(out.get_pixel(qu.round() as u32, qv.round() as u32), &GREY);
                }
            }
            assert_eq!(checked_clear, 1);
            // Target marks yellow, horizon marks cyan: the stroke's middle
            // (the top of the ring) has the mark's colour.
            for m in &overlay.marks {
                let [u, v] = m.marked;
                let p = out.get_pixel(u.round() as u32, (v - s.ring).round() as u32);
                let want = colour_of(m);
                assert_eq!(p.0, [want.0, want.1, want.2], "{} at {w}", m.name);
            }
            // Everything drawn is in the upper 60 % of the image or in the
            // panel (top left, where no mark is): the bottom third is untouched.
            let moved = changed(&photo, &out);
            assert!(
                moved
                    .iter()
                    .all(|&(_, y)| f64::from(y) < 0.6 * f64::from(h)),
                "at {w}"
            );
            assert!(!moved.is_empty());
        }
    }

    #[test]
    fn sizes_scale_with_the_image() {
        let small = Sizes::for_image(640, 480);
        let large = Sizes::for_image(6000, 4000);
        assert!(large.stroke > 4.0 * small.stroke, "{small:?} {large:?}");
        assert!(large.text > 4.0 * small.text && small.text >= 14.0);
        assert!(large.ring > 5.0 * small.ring);
        assert_eq!(large.text % 2.0, 0.0);
        // Measured on the drawing: the run of changed pixels across the
        // ring's left side, outline included, along the row of its centre.
        let width = |w: u32, h: u32| {
            let photo = plain(w, h);
            let c = [0.5 * f64::from(w), 0.5 * f64::from(h)];
            let overlay = Overlay {
                marks: vec![mark("", c, None, None)],
                ..Overlay::default()
            };
            let out = draw_overlay(&photo, &overlay);
            let y = c[1] as u32;
            let xs: Vec<u32> = (0..c[0] as u32)
                .filter(|&x| out.get_pixel(x, y) != &GREY)
                .collect();
            // One contiguous run.
            assert_eq!(xs.last().unwrap() - xs[0] + 1, xs.len() as u32);
            xs.len()
        };
        let (narrow, wide) = (width(640, 480), width(6000, 4000));
        assert!((3..=7).contains(&narrow), "{narrow}");
        assert!(wide > 3 * narrow, "{narrow} vs {wide}");
    }

    #[test]
    fn the_title_and_rms_are_drawn() {
        let photo = plain(640, 480);
        let base = Overlay {
            marks: vec![mark("a", [500.0, 400.0], None, None)],
            ..Overlay::default()
        };
        let without = draw_overlay(&photo, &base);
        let titled = draw_overlay(
            &photo,
            &Overlay {
                title: "harbour looming".into(),
                ..base.clone()
            },
        );
        let with_rms = draw_overlay(
            &photo,
            &Overlay {
                rms_pixels: Some(0.73),
                ..base.clone()
            },
        );
        // The same input draws the same pixels.
        assert_eq!(draw_overlay(&photo, &base), without);
        for other in [&titled, &with_rms] {
            let diff = changed(&without, other);
            // Text: many pixels, bright ones among them, in the top-left panel.
            assert!(diff.len() > 200, "{}", diff.len());
            assert!(diff.iter().all(|&(x, y)| x < 320 && y < 240));
            assert!(
                diff.iter()
                    .any(|&(x, y)| other.get_pixel(x, y).0.iter().all(|&c| c > 200))
            );
        }
        // Two titles differ where their letters do.
        let other_title = draw_overlay(
            &photo,
            &Overlay {
                title: "Fata Morgana".into(),
                ..base.clone()
            },
        );
        assert!(!changed(&titled, &other_title).is_empty());
    }

    #[test]
    fn names_are_drawn_beside_their_mark() {
        let photo = plain(640, 480);
        let at = [300.0, 300.0];
        let unnamed = draw_overlay(
            &photo,
            &Overlay {
                marks: vec![mark("", at, None, None)],
                ..Overlay::default()
            },
        );
        let named = draw_overlay(
            &photo,
            &Overlay {
                marks: vec![mark("lighthouse", at, None, None)],
                ..Overlay::default()
            },
        );
        let diff = changed(&unnamed, &named);
        assert!(diff.len() > 100);
        // Up and to the right of the ring, clear of it.
        let s = Sizes::for_image(640, 480);
        for &(x, y) in &diff {
            let (du, dv) = (f64::from(x) - at[0], f64::from(y) - at[1]);
            assert!(du.hypot(dv) > s.ring, "({x}, {y})");
            assert!(du > 0.0 && dv < 0.0, "({x}, {y})");
        }
        // Near the right edge the name goes to the left of the mark.
        let edge = [630.0, 300.0];
        let unnamed = draw_overlay(
            &photo,
            &Overlay {
                marks: vec![mark("", edge, None, None)],
                ..Overlay::default()
            },
        );
        let named = draw_overlay(
            &photo,
            &Overlay {
                marks: vec![mark("lighthouse", edge, None, None)],
                ..Overlay::default()
            },
        );
        let diff = changed(&unnamed, &named);
        assert!(diff.len() > 100);
        assert!(diff.iter().all(|&(x, _)| f64::from(x) < edge[0]));
    }

    #[test]
    fn the_horizon_is_dashed_across_the_image() {
        let photo = plain(640, 480);
        let line: Vec<Point> = (0..=10)
            .map(|k| [64.0 * k as f64, 300.0 + 2.0 * k as f64])
            .collect();
        let with = draw_overlay(
            &photo,
            &Overlay {
                horizon: line.clone(),
                ..Overlay::default()
            },
        );
        let without = draw_overlay(&photo, &Overlay::default());
        // Along the line: painted in the dashes, clear in the gaps.
        let on_line: Vec<bool> = (0..640)
            .map(|x| {
                let y = (300.0 + 2.0 * f64::from(x) / 64.0).round() as u32;
                with.get_pixel(x, y) != without.get_pixel(x, y)
            })
            .collect();
        let painted = on_line.iter().filter(|&&p| p).count();
        assert!(painted > 300 && painted < 600, "{painted}");
        // On the line where it passes through a pixel's centre, in a dash.
        let p = with.get_pixel(32, 301).0;
        assert_eq!(p, [HORIZON_LINE.0, HORIZON_LINE.1, HORIZON_LINE.2]);
        // Far from the line and the panel: untouched.
        assert_eq!(
            changed(&without, &with)
                .iter()
                .filter(|&&(_, y)| y < 250)
                .count(),
            {
                // The legend row "apparent horizon" is the only other change.
                changed(&without, &with)
                    .iter()
                    .filter(|&&(x, y)| y < 250 && x < 320)
                    .count()
            }
        );
        assert!(
            changed(&without, &with)
                .iter()
                .all(|&(_, y)| y < 250 || (290..=330).contains(&y))
        );
    }

    #[test]
    fn bad_coordinates_do_not_panic() {
        let bad = [
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            1e300,
            -1e300,
            f64::MAX,
            f64::MIN,
            -5.0,
            1e9,
        ];
        let mut marks = Vec::new();
        let mut horizon = Vec::new();
        for &a in &bad {
            for &b in &bad {
                marks.push(mark("x", [a, b], Some([b, a]), Some([a, 100.0])));
                horizon.push([a, b]);
                horizon.push([320.0, 240.0]);
            }
        }
        let overlay = Overlay {
            marks,
            horizon,
            title: "t".into(),
            rms_pixels: Some(f64::NAN),
        };
        for (w, h) in [(640, 480), (1, 1), (0, 0), (3, 0), (7, 2)] {
            let photo = plain(w, h);
            assert_eq!(draw_overlay(&photo, &overlay).dimensions(), (w, h));
        }
        // Marks all outside the image draw nothing inside it but the panel
        // (top left) and the lines that cross it.
        let outside = Overlay {
            marks: vec![
                mark(
                    "far",
                    [-500.0, -500.0],
                    Some([-400.0, -500.0]),
                    Some([-500.0, -600.0]),
                ),
                mark("further", [1e12, 2e12], None, None),
            ],
            ..Overlay::default()
        };
        let photo = plain(640, 480);
        let out = draw_overlay(&photo, &outside);
        assert!(
            changed(&photo, &out)
                .iter()
                .all(|&(x, y)| x < 320 && y < 240)
        );
        // A joining line from far outside into the image is drawn, and only
        // near its clipped course.
        let into = Overlay {
            marks: vec![mark("", [320.0, 240.0], Some([1e300, 240.0]), None)],
            ..Overlay::default()
        };
        let out = draw_overlay(&photo, &into);
        assert_ne!(out.get_pixel(600, 240), &GREY);
        assert_eq!(out.get_pixel(600, 200), &GREY);
    }

    /// A synthetic photo: sky graded to a pale horizon, a darker sea with
    /// ripples, a headland and a lighthouse.
    fn synthetic_photo(w: u32, h: u32) -> RgbImage {
        let horizon = 0.55 * f64::from(h);
        RgbImage::from_fn(w, h, |x, y| {
            let (u, v) = (f64::from(x), f64::from(y));
            let headland = horizon
                - 0.04 * f64::from(h) * (1.0 - ((u / f64::from(w) - 0.3) / 0.12).powi(2)).max(0.0);
            let tower = (u - 0.3 * f64::from(w)).abs() < 0.006 * f64::from(w)
                && v > horizon - 0.14 * f64::from(h);
            if tower && v < headland {
                Rgb([235, 235, 228])
            } else if v < headland.min(horizon) {
                let t = v / horizon;
                Rgb([
                    (150.0 + 90.0 * t) as u8,
                    (190.0 + 55.0 * t) as u8,
                    (235.0 + 15.0 * t) as u8,
                ])
            } else if v < horizon {
                Rgb([70, 80, 62])
            } else {
                // Ripples that shrink toward the horizon, as seen at a grazing angle.
                let depth = (v - horizon) / (f64::from(h) - horizon);
                let ripple =
                    8.0 * (u / f64::from(w) * 90.0 + (depth * 40.0).powf(1.6)).sin() * depth;
                let c = |x: f64| x.clamp(0.0, 255.0) as u8;
                Rgb([
                    c(45.0 + 0.5 * ripple),
                    c(78.0 - 25.0 * depth + 0.6 * ripple),
                    c(112.0 - 35.0 * depth + 0.8 * ripple),
                ])
            }
        })
    }

    #[test]
    fn example_pngs_for_the_eye() {
        // Written to target/ (not committed) to look at.
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target");
        std::fs::create_dir_all(&dir).unwrap();
        for (w, h) in [(640u32, 480u32), (6000, 4000)] {
            let photo = synthetic_photo(w, h);
            let (fw, fh) = (f64::from(w), f64::from(h));
            let at = |u: f64, v: f64| [u * fw, v * fh];
            let horizon: Vec<Point> = (0..=20)
                .map(|k| {
                    let u = k as f64 / 20.0;
                    at(u, 0.553 - 0.01 * u)
                })
                .collect();
            let overlay = Overlay {
                marks: vec![
                    mark(
                        "lighthouse lamp",
                        at(0.3, 0.41),
                        Some(at(0.305, 0.4)),
                        Some(at(0.3, 0.44)),
                    ),
                    mark(
                        "headland",
                        at(0.2, 0.545),
                        Some(at(0.203, 0.54)),
                        Some(at(0.2, 0.56)),
                    ),
                    OverlayMark {
                        horizon: true,
                        ..mark(
                            "sea horizon, left",
                            at(0.06, 0.552),
                            Some(at(0.06, 0.5524)),
                            None,
                        )
                    },
                    OverlayMark {
                        horizon: true,
                        ..mark(
                            "sea horizon, right",
                            at(0.9, 0.548),
                            Some(at(0.9, 0.5441)),
                            None,
                        )
                    },
                ],
                horizon,
                title: "harbour-looming: fitted air".into(),
                rms_pixels: Some(0.734),
            };
            let out = draw_overlay(&photo, &overlay);
            out.save(dir.join(format!("overlay-example-{w}.png")))
                .unwrap();
            assert_ne!(out, photo);
            if w > 1500 {
                // As seen on a screen: 1500 px wide.
                let small = image::imageops::resize(
                    &out,
                    1500,
                    1500 * h / w,
                    image::imageops::FilterType::Triangle,
                );
                small
                    .save(dir.join(format!("overlay-example-{w}-at-1500.png")))
                    .unwrap();
            }
        }
    }
}
