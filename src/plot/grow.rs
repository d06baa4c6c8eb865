//! The plot of a grown fit (`mirage fit --grow --plot`): the usual convergence
//! figure of the final fit, and beside it the criterion after each step of
//! the growth (the terms added and dropped, and the model each step left).

use super::axes::{Axes, Span, build_chart, decade_range, decade_ticks, draw_axes, log_label};
use super::convergence::ConvergenceFigure;
use super::figure::{Figure, draw_header, save};
use super::style::{DrawResult, INK, MUTED, TICK_SIZE, series_color, text};
use super::text::{TextMode, draw_label};
use crate::error::Result;
use crate::fit::History;
use crate::fit::grow::GrowReport;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// Width of the growth panel beside the convergence figure.
const PANEL_W: u32 = 760;

/// Draws the convergence plots of the final fit (as
/// [`super::draw_convergence`]) with, beside them, the criterion after each
/// step of the growth, each point labelled with the step's action. Format by
/// the extension of `output`, written atomically.
pub fn draw_grow(history: &History, grow: &GrowReport, output: &Path) -> Result<()> {
    super::figure::ImageFormat::from_path(output)?;
    let figure = GrowFigure {
        convergence: ConvergenceFigure::new(history),
        grow: grow.clone(),
    };
    save(&figure, output)
}

struct GrowFigure {
    convergence: ConvergenceFigure,
    grow: GrowReport,
}

impl Figure for GrowFigure {
    fn size(&self) -> (u32, u32) {
        let (w, h) = self.convergence.size();
        (w + PANEL_W, h)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        mode: TextMode,
    ) -> DrawResult<DB> {
        let (w, _) = self.convergence.size();
        let (left, right) = root.split_horizontally(w);
        self.convergence.draw(&left, mode)?;
        self.draw_steps(&right, mode)
    }
}

impl GrowFigure {
    fn draw_steps<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        mode: TextMode,
    ) -> DrawResult<DB> {
        let (header, body) = area.split_vertically(74);
        draw_header(
            &header,
            "Growing the model",
            &format!("stopped: {}", self.grow.stop_reason),
            mode,
        )?;
        let steps = &self.grow.steps;
        let values: Vec<f64> = steps.iter().map(|s| s.criterion).collect();
        // Criteria with σ known are positive and span decades: a log axis;
        // with σ estimated they may be negative: a linear one.
        let log = values.iter().all(|v| *v > 0.0 && v.is_finite());
        let mut span = Span::EMPTY;
        for v in &values {
            span.include(*v);
        }
        let y = if log {
            decade_range(span)
        } else {
            span.padded(0.08, (-1.0, 1.0))
        };
        let to_y = |v: f64| if log { v.log10() } else { v };
        let x = (-0.5, steps.len().max(1) as f64 - 0.5);
        let mut chart = build_chart(&body, x, y, 84)?;
        let log_fmt = |v: f64| log_label(10f64.powf(v));
        let lin_fmt = |v: f64| format!("{v:.0}");
        draw_axes(
            &body,
            &mut chart,
            &Axes {
                caption: "criterion after each step (lower is better)",
                x_desc: "step",
                y_desc: "criterion (BIC)",
                x_ticks: steps.len().clamp(2, 12),
                y_ticks: if log { decade_ticks(y) } else { 8 },
                x_format: &|v| format!("{v:.0}"),
                y_format: if log { &log_fmt } else { &lin_fmt },
            },
            mode,
        )?;
        let pts: Vec<(f64, f64)> = values
            .iter()
            .enumerate()
            .map(|(i, v)| (i as f64, to_y(*v)))
            .collect();
        let plot = chart.plotting_area();
        let color = series_color(0);
        if pts.len() >= 2 {
            plot.draw(&PathElement::new(pts.clone(), color.stroke_width(2)))?;
        }
        let px = super::axes::pixel_mapper(&chart);
        let pixels = plot.strip_coord_spec();
        for (s, p) in steps.iter().zip(&pts) {
            plot.draw(&Circle::new(*p, 5, color.filled()))?;
            let (cx, cy) = px(*p);
            let style = text(TICK_SIZE, INK).pos(Pos::new(HPos::Left, VPos::Bottom));
            draw_label(&pixels, &s.action, (cx + 8, cy - 6), &style, mode)?;
            let chi2 = s.chi2.map(|c| format!("χ² = {c:.1}, ")).unwrap_or_default();
            let detail = format!("{chi2}{} free", s.free.len());
            let style = text(TICK_SIZE, MUTED).pos(Pos::new(HPos::Left, VPos::Top));
            draw_label(&pixels, &detail, (cx + 8, cy + 6), &style, mode)?;
        }
        Ok(())
    }
}
