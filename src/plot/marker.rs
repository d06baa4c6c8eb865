//! Marks drawn in pixel coordinates: point symbols (for charts and legend
//! swatches alike) and dashed polylines.

use super::style::{DrawResult, INK};
use plotters::coord::Shift;
use plotters::prelude::*;

// ---------------------------------------------------------------- markers --

/// Point symbols, drawn in pixel coordinates so the same code serves chart
/// points and legend swatches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Marker {
    /// Filled circle with a white core (the observer).
    Circle,
    /// Open triangle (a point on the line of sight).
    Triangle,
    /// Filled star (the target).
    Star,
    /// Diagonal cross (where the ray ended).
    Cross,
}

pub(super) fn draw_marker<DB: DrawingBackend>(
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

/// Draws a dashed polyline in pixel coordinates (plotters' own dashed series
/// restarts the pattern at every vertex, which looks ragged on dense paths).
pub(super) fn draw_dashed<DB: DrawingBackend>(
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

pub(super) fn flush_dash<DB: DrawingBackend>(
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
