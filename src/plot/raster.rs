//! A small anti-aliased rasteriser for drawing over photos: segments with
//! round ends, rings and filled rectangles blended onto an RGB image, with
//! segments clipped to the image first (so points far outside cost nothing
//! and non-finite ones are skipped), and dashed polylines.
//!
//! Pixel (x, y) has its centre at (x, y) (OpenCV's convention). A pixel is
//! covered in proportion to its centre's distance from the shape's edge, a
//! linear ramp one pixel wide centred on the edge: the half-covered contour
//! lies exactly on the edge, so shapes sit where their coordinates say to
//! well under a pixel, and a stroke w wide paints about w pixels across.

use image::RgbImage;
use plotters::style::RGBColor;

/// A position in pixels (u, v).
pub(super) type Point = [f64; 2];

/// Draws anti-aliased shapes on an RGB image, clipped to it.
pub(super) struct Canvas<'a> {
    /// The image drawn on.
    pub(super) img: &'a mut RgbImage,
}

impl Canvas<'_> {
    pub(super) fn size(&self) -> (f64, f64) {
        (f64::from(self.img.width()), f64::from(self.img.height()))
    }

    /// Blends `colour` over pixel (x, y) with opacity `alpha`.
    fn blend(&mut self, x: u32, y: u32, colour: RGBColor, alpha: f64) {
        let p = self.img.get_pixel_mut(x, y);
        for (c, v) in p.0.iter_mut().zip([colour.0, colour.1, colour.2]) {
            let mixed = f64::from(*c) + (f64::from(v) - f64::from(*c)) * alpha;
            *c = mixed.round().clamp(0.0, 255.0) as u8;
        }
    }

    /// The pixel range covering [lo, hi] in one axis of length `n`, or
    /// `None` when it misses the image.
    fn span(lo: f64, hi: f64, n: f64) -> Option<(u32, u32)> {
        let (a, b) = (lo.floor().max(0.0), hi.ceil().min(n - 1.0));
        (a <= b).then_some((a as u32, b as u32))
    }

    /// A segment `width` wide with round ends.
    pub(super) fn segment(&mut self, a: Point, b: Point, width: f64, colour: RGBColor, alpha: f64) {
        let (w, h) = self.size();
        let hw = 0.5 * width;
        let pad = hw + 2.0;
        let Some((a, b)) = clip(a, b, [-pad, -pad], [w - 1.0 + pad, h - 1.0 + pad]) else {
            return;
        };
        let ab = [b[0] - a[0], b[1] - a[1]];
        let len2 = ab[0] * ab[0] + ab[1] * ab[1];
        // Pieces of at most 64 px, so that a long diagonal visits only the
        // pixels near it; each pixel is drawn by the piece its foot falls in.
        let pieces = (len2.sqrt() / 64.0).ceil().max(1.0) as usize;
        for i in 0..pieces {
            let (t0, t1) = (i as f64 / pieces as f64, (i + 1) as f64 / pieces as f64);
            let p0 = [a[0] + ab[0] * t0, a[1] + ab[1] * t0];
            let p1 = [a[0] + ab[0] * t1, a[1] + ab[1] * t1];
            let Some((x0, x1)) =
                Self::span(p0[0].min(p1[0]) - hw - 1.0, p0[0].max(p1[0]) + hw + 1.0, w)
            else {
                continue;
            };
            let Some((y0, y1)) =
                Self::span(p0[1].min(p1[1]) - hw - 1.0, p0[1].max(p1[1]) + hw + 1.0, h)
            else {
                continue;
            };
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let p = [f64::from(x) - a[0], f64::from(y) - a[1]];
                    let t = if len2 > 0.0 {
                        ((p[0] * ab[0] + p[1] * ab[1]) / len2).clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    let mine = t >= t0 && (t < t1 || i + 1 == pieces);
                    if !mine {
                        continue;
                    }
                    let d = (p[0] - t * ab[0]).hypot(p[1] - t * ab[1]);
                    let cover = (hw + 0.5 - d).clamp(0.0, 1.0);
                    if cover > 0.0 {
                        self.blend(x, y, colour, alpha * cover);
                    }
                }
            }
        }
    }

    /// A circle of radius `r` drawn with a stroke `width` wide.
    pub(super) fn ring(&mut self, c: Point, r: f64, width: f64, colour: RGBColor, alpha: f64) {
        if !(c[0].is_finite() && c[1].is_finite()) {
            return;
        }
        let (w, h) = self.size();
        let reach = r + 0.5 * width + 1.0;
        let (Some((x0, x1)), Some((y0, y1))) = (
            Self::span(c[0] - reach, c[0] + reach, w),
            Self::span(c[1] - reach, c[1] + reach, h),
        ) else {
            return;
        };
        for y in y0..=y1 {
            for x in x0..=x1 {
                let d = (f64::from(x) - c[0]).hypot(f64::from(y) - c[1]);
                let cover = (0.5 * width + 0.5 - (d - r).abs()).clamp(0.0, 1.0);
                if cover > 0.0 {
                    self.blend(x, y, colour, alpha * cover);
                }
            }
        }
    }

    /// A filled rectangle over pixels whose centres lie in [x0, x1) × [y0, y1).
    pub(super) fn rect(&mut self, [x0, y0]: Point, [x1, y1]: Point, colour: RGBColor, alpha: f64) {
        let (w, h) = self.size();
        let (Some((a, b)), Some((c, d))) = (
            Self::span(x0.ceil(), x1.ceil() - 1.0, w),
            Self::span(y0.ceil(), y1.ceil() - 1.0, h),
        ) else {
            return;
        };
        for y in c..=d {
            for x in a..=b {
                self.blend(x, y, colour, alpha);
            }
        }
    }
}

/// The part of segment a–b inside the box [lo, hi] (Liang–Barsky), in the
/// order a → b, or `None` when it misses the box or has a non-finite end.
/// Computed with half-differences, so no finite input overflows, and with
/// the parameter counted from the end nearer the origin, so that where one
/// end is near the box and the other far beyond it (a fitted position at
/// 1e300) the clipped segment is as exact as the near end.
pub(super) fn clip(a: Point, b: Point, lo: Point, hi: Point) -> Option<(Point, Point)> {
    if !a.iter().chain(&b).all(|v| v.is_finite()) {
        return None;
    }
    let far = |p: Point| p[0].abs().max(p[1].abs());
    if far(a) > far(b) {
        return clip_from(b, a, lo, hi).map(|(p, q)| (q, p));
    }
    clip_from(a, b, lo, hi)
}

/// [`clip`] with the parameter counted from `a`.
fn clip_from(a: Point, b: Point, lo: Point, hi: Point) -> Option<(Point, Point)> {
    // The segment is a + 2·t·d for t in [0, 1].
    let d = [0.5 * b[0] - 0.5 * a[0], 0.5 * b[1] - 0.5 * a[1]];
    // The parameters where the segment enters and leaves the box, and the
    // side (axis, coordinate) it crosses there: the point on that side gets
    // the side's coordinate exactly.
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    let (mut side0, mut side1) = (None, None);
    for k in 0..2 {
        for (p, q, edge) in [
            (-d[k], 0.5 * a[k] - 0.5 * lo[k], lo[k]),
            (d[k], 0.5 * hi[k] - 0.5 * a[k], hi[k]),
        ] {
            if p == 0.0 {
                if q < 0.0 {
                    return None;
                }
                continue;
            }
            let r = q / p;
            if p < 0.0 && r > t0 {
                (t0, side0) = (r, Some((k, edge)));
            } else if p > 0.0 && r < t1 {
                (t1, side1) = (r, Some((k, edge)));
            }
        }
    }
    if t0 > t1 {
        return None;
    }
    let at = |t: f64, side: Option<(usize, f64)>| -> Point {
        let mut p = if t <= 0.5 {
            [a[0] + 2.0 * t * d[0], a[1] + 2.0 * t * d[1]]
        } else {
            [b[0] - 2.0 * (1.0 - t) * d[0], b[1] - 2.0 * (1.0 - t) * d[1]]
        };
        if let Some((k, edge)) = side {
            p[k] = edge;
        }
        [p[0].clamp(lo[0], hi[0]), p[1].clamp(lo[1], hi[1])]
    };
    Some((at(t0, side0), at(t1, side1)))
}

/// The dashes of a polyline: pieces `dash` long every `dash + gap`, the
/// pattern running on across vertices; segments are clipped to the box
/// [lo, hi] first, and one with a non-finite end breaks the line.
pub(super) fn dashes(
    line: &[Point],
    dash: f64,
    gap: f64,
    lo: Point,
    hi: Point,
) -> Vec<(Point, Point)> {
    let period = dash + gap;
    let mut out = Vec::new();
    let mut phase = 0.0;
    for pair in line.windows(2) {
        let Some((a, b)) = clip(pair[0], pair[1], lo, hi) else {
            continue;
        };
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        if len == 0.0 {
            continue;
        }
        let along = |s: f64| -> Point {
            let t = s / len;
            [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t]
        };
        // `s` runs along this segment; `phase` is where in the pattern its
        // start falls.
        let mut s = -phase;
        while s < len {
            let (from, to) = (s.max(0.0), (s + dash).min(len));
            if to > from {
                out.push((along(from), along(to)));
            }
            s += period;
        }
        phase = (phase + len) % period;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The coverage-weighted centre and the total coverage of what was
    /// painted white on black.
    fn centroid(img: &RgbImage) -> (Point, f64) {
        let (mut sum, mut su, mut sv) = (0.0, 0.0, 0.0);
        for (x, y, p) in img.enumerate_pixels() {
            let c = f64::from(p.0[0]) / 255.0;
            sum += c;
            su += c * f64::from(x);
            sv += c * f64::from(y);
        }
        ([su / sum, sv / sum], sum)
    }

    #[test]
    fn shapes_sit_where_their_coordinates_say() {
        const WHITE: RGBColor = RGBColor(255, 255, 255);
        for c in [[20.0, 15.0], [20.3, 15.7], [19.5, 16.25]] {
            let mut img = RgbImage::new(40, 32);
            Canvas { img: &mut img }.ring(c, 6.0, 2.0, WHITE, 1.0);
            let (at, area) = centroid(&img);
            assert!(
                (at[0] - c[0]).abs() < 0.05 && (at[1] - c[1]).abs() < 0.05,
                "{c:?}: {at:?}"
            );
            // An annulus 2 wide around radius 6: 2π·6·2 ≈ 75.4 px.
            assert!((area - 75.4).abs() < 1.0, "{area}");
        }
        for x in [10.0, 10.25, 10.5] {
            let mut img = RgbImage::new(20, 40);
            Canvas { img: &mut img }.segment([x, 10.0], [x, 30.0], 3.0, WHITE, 1.0);
            let (at, area) = centroid(&img);
            assert!((at[0] - x).abs() < 0.02, "{x}: {at:?}");
            assert!((at[1] - 20.0).abs() < 0.02, "{x}: {at:?}");
            // 20 long and 3 wide, with round ends: 60 + π·1.5² ≈ 67.1 px.
            assert!((area - 67.1).abs() < 1.0, "{area}");
        }
        // A rectangle covers the pixels whose centres are inside it.
        let mut img = RgbImage::new(10, 10);
        Canvas { img: &mut img }.rect([1.5, 2.0], [4.5, 3.0], WHITE, 1.0);
        let (at, area) = centroid(&img);
        assert_eq!((at, area), ([3.0, 2.0], 3.0));
    }

    #[test]
    fn clipping() {
        let (lo, hi) = ([0.0, 0.0], [10.0, 10.0]);
        assert_eq!(
            clip([-5.0, 5.0], [15.0, 5.0], lo, hi),
            Some(([0.0, 5.0], [10.0, 5.0]))
        );
        assert_eq!(
            clip([2.0, 3.0], [4.0, 5.0], lo, hi),
            Some(([2.0, 3.0], [4.0, 5.0]))
        );
        assert_eq!(clip([-5.0, -5.0], [-1.0, 20.0], lo, hi), None);
        assert_eq!(clip([f64::NAN, 0.0], [1.0, 1.0], lo, hi), None);
        // An end inside stays exact whatever the other end, and the exit
        // point is where the direction (1, 1) from it leaves the box.
        for (far, near) in [
            ([1e300, 1e300], [3.0, 4.0]),
            ([f64::MAX, f64::MAX], [3.0, 4.0]),
        ] {
            let (a, b) = clip(far, near, lo, hi).unwrap();
            assert_eq!(b, near);
            assert!((a[0] - 9.0).abs() < 1e-12 && a[1] == 10.0, "{a:?}");
            assert_eq!(clip(near, far, lo, hi), Some((b, a)));
        }
        let (a, b) = clip([f64::MAX, 5.0], [f64::MIN, 5.0], lo, hi).unwrap();
        assert_eq!((a, b), ([10.0, 5.0], [0.0, 5.0]));
        // Dashes follow a polyline and skip its broken parts.
        let d = dashes(
            &[
                [0.0, 0.0],
                [10.0, 0.0],
                [f64::NAN, 0.0],
                [0.0, 5.0],
                [10.0, 5.0],
            ],
            3.0,
            2.0,
            lo,
            hi,
        );
        let lengths: Vec<f64> = d
            .iter()
            .map(|(a, b)| (b[0] - a[0]).hypot(b[1] - a[1]))
            .collect();
        assert_eq!(lengths, vec![3.0, 3.0, 3.0, 3.0]);
    }
}
