//! The speed/accuracy Pareto plot of `mirage tradeoff`: endpoint error against
//! trace time, and fitted objective against fit time, log-log, one curve per
//! integrator.

use super::axes::{
    Axes, Span, build_chart, decade_range, decade_ticks, draw_axes, log_label, pixel_mapper,
};
use super::figure::{Figure, draw_header, save};
use super::legend::{Corner, LegendEntry, Swatch, draw_legend_box};
use super::style::{DrawResult, TICK_SIZE, series_color, text};
use super::text::{TextMode, draw_label};
use crate::error::Result;
use crate::tradeoff::Tradeoff;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// Draws the Pareto plot of a [`Tradeoff`] to `output` (`.png` or `.svg`).
pub fn draw_tradeoff(t: &Tradeoff, output: &Path) -> Result<()> {
    super::figure::ImageFormat::from_path(output)?;
    save(&TradeoffFigure { t }, output)
}

struct TradeoffFigure<'a> {
    t: &'a Tradeoff,
}

type Curve = (String, Vec<(f64, f64, f64)>);

impl TradeoffFigure<'_> {
    /// Per method: (label, [(log10 x, log10 y, setting)]), non-positive values
    /// floored so that an exact answer (error 0) still shows.
    fn curves(
        &self,
        pick: impl Fn(&crate::tradeoff::TradeoffPoint) -> Option<(f64, f64)>,
    ) -> Vec<Curve> {
        let mut out: Vec<Curve> = Vec::new();
        for method in ["rk4", "dopri5"] {
            let pts: Vec<(f64, f64, f64)> = self
                .t
                .points
                .iter()
                .filter(|p| p.method == method)
                .filter_map(|p| {
                    pick(p).map(|(x, y)| (x.max(1e-12).log10(), y.max(1e-30).log10(), p.setting))
                })
                .collect();
            if !pts.is_empty() {
                let label = if method == "rk4" {
                    "RK4, fixed step (m)".to_string()
                } else {
                    "Dormand–Prince 5(4), tolerance".to_string()
                };
                out.push((label, pts));
            }
        }
        out
    }

    #[allow(clippy::too_many_arguments)]
    fn panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        caption: &str,
        x_desc: &str,
        y_desc: &str,
        curves: &[Curve],
        corner: Corner,
        mode: TextMode,
    ) -> DrawResult<DB> {
        let mut xs = Span::EMPTY;
        let mut ys = Span::EMPTY;
        for (_, pts) in curves {
            for p in pts {
                xs.include(10f64.powf(p.0));
                ys.include(10f64.powf(p.1));
            }
        }
        let (x0, x1) = decade_range(xs);
        let (y0, y1) = decade_range(ys);
        let mut chart = build_chart(area, (x0, x1), (y0, y1), 84)?;
        let power = |v: f64| log_label(10f64.powf(v));
        draw_axes(
            area,
            &mut chart,
            &Axes {
                caption,
                x_desc,
                y_desc,
                x_ticks: decade_ticks((x0, x1)),
                y_ticks: decade_ticks((y0, y1)),
                x_format: &power,
                y_format: &power,
            },
            mode,
        )?;
        let plot = chart.plotting_area();
        let px = pixel_mapper(&chart);
        let pixels = plot.strip_coord_spec();
        let mut legend = Vec::new();
        for (i, (label, pts)) in curves.iter().enumerate() {
            let color = series_color(i);
            plot.draw(&PathElement::new(
                pts.iter().map(|p| (p.0, p.1)).collect::<Vec<_>>(),
                color.stroke_width(2),
            ))?;
            let setting = text(TICK_SIZE - 2.0, color).pos(Pos::new(HPos::Left, VPos::Bottom));
            for p in pts {
                plot.draw(&Circle::new((p.0, p.1), 4, color.filled()))?;
                // Label each point with its setting, so a reader can pick one.
                let (x, y) = px((p.0, p.1));
                draw_label(&pixels, &log_label(p.2), (x + 4, y - 3), &setting, mode)?;
            }
            legend.push(LegendEntry::new(Swatch::Line(color, 3), label.clone()));
        }
        draw_legend_box(&pixels, &legend, corner, mode)
    }
}

impl Figure for TradeoffFigure<'_> {
    fn size(&self) -> (u32, u32) {
        (1400, 620)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        mode: TextMode,
    ) -> DrawResult<DB> {
        let subtitle = format!(
            "{} pair(s); errors against Dormand–Prince at {}; one core",
            self.t.pairs,
            log_label(self.t.reference_tolerance)
        );
        let (header, body) = root.split_vertically(74);
        draw_header(
            &header,
            &format!("{}: speed against accuracy", self.t.problem),
            &subtitle,
            mode,
        )?;
        let has_fit = self.t.points.iter().any(|p| p.fit.is_some());
        let (left, right) = if has_fit {
            let (w, _) = body.dim_in_pixel();
            let (l, r) = body.split_horizontally(w / 2);
            (l, Some(r))
        } else {
            (body, None)
        };
        let traces = self.curves(|p| Some((p.trace_time_s, p.endpoint_error)));
        self.panel(
            &left,
            "endpoint error against trace time",
            "time to trace every pair (s)",
            "largest endpoint error (m)",
            &traces,
            Corner::UpperRight,
            mode,
        )?;
        if let Some(right) = right {
            let fits = self.curves(|p| p.fit.as_ref().map(|f| (f.time_s, f.parameter_error)));
            self.panel(
                &right,
                "fitted parameters against fit time",
                "fit time (s)",
                "largest relative parameter error",
                &fits,
                Corner::UpperLeft,
                mode,
            )?;
        }
        Ok(())
    }
}
