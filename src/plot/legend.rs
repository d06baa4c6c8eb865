//! Legends: entries with a swatch and a label, flowed in rows, stacked in a
//! column or framed in a corner of a plot.

use super::axes::text_width;
use super::marker::{Marker, draw_marker};
use super::style::{DrawResult, GRID, INK, LEGEND_SIZE, anchored, text};
use super::text::{TextMode, draw_label};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};

// ----------------------------------------------------------------- legend --

/// What a legend entry shows before its text.
#[derive(Clone, Copy, Debug)]
pub(super) enum Swatch {
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
pub(super) struct LegendEntry {
    pub(super) swatch: Swatch,
    pub(super) label: String,
}

impl LegendEntry {
    pub(super) fn new(swatch: Swatch, label: impl Into<String>) -> Self {
        LegendEntry {
            swatch,
            label: label.into(),
        }
    }
}

pub(super) const SWATCH_W: i32 = 30;
pub(super) const LEGEND_ROW: i32 = 22;
pub(super) const LEGEND_GAP: i32 = 22;

pub(super) fn legend_text_width(label: &str) -> i32 {
    text_width(label, LEGEND_SIZE)
}

/// Positions of the entries when flowed left to right in rows of `width`
/// pixels (relative to the legend's top-left corner).
pub(super) fn legend_layout(entries: &[LegendEntry], width: i32) -> Vec<(i32, i32)> {
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
pub(super) fn truncate_legend(
    mut entries: Vec<LegendEntry>,
    max: usize,
    what: &str,
) -> Vec<LegendEntry> {
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
pub(super) fn legend_height(entries: &[LegendEntry], width: i32) -> i32 {
    match legend_layout(entries, width).last() {
        Some(&(_, y)) => y + LEGEND_ROW + 8,
        None => 0,
    }
}

/// Draws the entries flowed in rows from the top-left of `area`, indented by
/// `left` pixels (to line up with a chart's plotting area).
pub(super) fn draw_legend<DB: DrawingBackend>(
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
pub(super) fn draw_legend_column<DB: DrawingBackend>(
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
pub(super) fn draw_legend_at<DB: DrawingBackend>(
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
pub(super) enum Corner {
    UpperLeft,
    UpperRight,
}

/// Draws `entries` one per row in a framed white box in a corner of `plot`
/// (a plotting area in pixel coordinates).
pub(super) fn draw_legend_box<DB: DrawingBackend>(
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
