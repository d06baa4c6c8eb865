//! Convergence plots of a fit: the objective against iterations and wall time,
//! and how each free parameter approached its final value.

use super::axes::{
    Axes, Span, build_chart, decade_range, decade_ticks, draw_axes, format_sig, log_label, minus,
    pixel_mapper,
};
use super::figure::{Figure, draw_header, draw_placeholder, save};
use super::legend::{
    LegendEntry, Swatch, draw_legend, draw_legend_column, legend_height, truncate_legend,
};
use super::marker::draw_dashed;
use super::style::{DrawResult, MUTED, TICK_SIZE, series_color, text};
use super::text::{TextMode, draw_label};
use crate::error::Result;
use crate::fit::History;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

const SIZE: (u32, u32) = (1400, 900);
/// Lowest objective a log axis shows; exact zeros are drawn just below the
/// smallest positive value instead, but never below this.
const FLOOR_MIN: f64 = 1e-32;
/// Share of the body's height given to the two objective panels.
const TOP_SHARE: f64 = 0.5;
/// Width of the parameter legend beside the parameter panel.
const PARAM_LEGEND_W: u32 = 330;

/// Draws the convergence plots of a fit: objective F (log scale) against
/// iteration and against wall time, one curve per run, and each free parameter's
/// trajectory normalised as (p − p_final) / max(|p_final|, range of p) per run
/// (the best run bold, the others faint). Any [`History`] is accepted, also an
/// empty one; the format follows the extension of `output` (`.png` or `.svg`)
/// and the file is written atomically.
pub fn draw_convergence(history: &History, output: &Path) -> Result<()> {
    super::figure::ImageFormat::from_path(output)?;
    save(&ConvergenceFigure::new(history), output)
}

/// One run, ready to draw.
struct RunView {
    label: String,
    color: RGBColor,
    /// (iteration, log10 F with F clamped to the floor).
    by_iteration: Vec<(f64, f64)>,
    /// (seconds, log10 F with F clamped to the floor).
    by_time: Vec<(f64, f64)>,
    /// Per parameter: (iteration, normalised deviation from this run's final).
    params: Vec<Vec<(f64, f64)>>,
    /// Final objective (unclamped), if the run has records.
    final_objective: Option<f64>,
}

pub(super) struct ConvergenceFigure {
    runs: Vec<RunView>,
    names: Vec<String>,
    /// Final values of the best run, for the legend.
    finals: Vec<Option<f64>>,
    best: Option<usize>,
    /// log10 of the value zeros are drawn at.
    floor: f64,
    has_zero: bool,
    iterations: (f64, f64),
    seconds: (f64, f64),
    objective: (f64, f64),
    deviation: (f64, f64),
}

impl ConvergenceFigure {
    pub(super) fn new(history: &History) -> ConvergenceFigure {
        let records = || history.runs.iter().flat_map(|r| r.records.iter());
        let min_positive = records()
            .map(|r| r.objective)
            .filter(|f| f.is_finite() && *f > 0.0)
            .fold(f64::INFINITY, f64::min);
        let floor = if min_positive.is_finite() {
            (min_positive * 1e-2).max(FLOOR_MIN)
        } else {
            FLOOR_MIN
        };
        let has_zero = records().any(|r| r.objective.is_finite() && r.objective < floor);
        // Objectives are drawn as log10(F) on a linear axis (see `decade_range`).
        let clamp = |f: f64| {
            if f.is_finite() {
                Some(f.max(floor).log10())
            } else {
                None
            }
        };

        let n_params = history
            .param_names
            .len()
            .max(records().map(|r| r.params.len()).max().unwrap_or(0));
        let names: Vec<String> = (0..n_params)
            .map(|k| {
                history
                    .param_names
                    .get(k)
                    .cloned()
                    .unwrap_or_else(|| format!("parameter {k}"))
            })
            .collect();

        let mut runs = Vec::with_capacity(history.runs.len());
        for (i, run) in history.runs.iter().enumerate() {
            let by_iteration = run
                .records
                .iter()
                .filter_map(|r| clamp(r.objective).map(|f| (r.iteration as f64, f)))
                .collect();
            let by_time = run
                .records
                .iter()
                .filter(|r| r.elapsed_s.is_finite())
                .filter_map(|r| clamp(r.objective).map(|f| (r.elapsed_s.max(0.0), f)))
                .collect();
            let params = (0..n_params)
                .map(|k| normalised_trajectory(run, k))
                .collect();
            runs.push(RunView {
                label: if run.label.is_empty() {
                    format!("run {i}")
                } else {
                    run.label.clone()
                },
                color: series_color(i),
                by_iteration,
                by_time,
                params,
                final_objective: run.records.last().map(|r| r.objective),
            });
        }

        // The best run ends lowest; NaN finals never win.
        let best = runs
            .iter()
            .enumerate()
            .filter_map(|(i, r)| r.final_objective.filter(|f| !f.is_nan()).map(|f| (i, f)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i);
        let finals = (0..n_params)
            .map(|k| {
                best.and_then(|b| history.runs[b].records.last())
                    .and_then(|r| r.params.get(k).copied())
            })
            .collect();

        let (mut its, mut secs, mut objs, mut devs) =
            (Span::EMPTY, Span::EMPTY, Span::EMPTY, Span::EMPTY);
        for r in &runs {
            for &(i, _) in &r.by_iteration {
                its.include(i);
            }
            for &(t, _) in &r.by_time {
                secs.include(t);
            }
            for traj in &r.params {
                for &(_, d) in traj {
                    devs.include(d);
                }
            }
        }
        for r in records() {
            if r.objective.is_finite() {
                objs.include(r.objective.max(floor));
            }
        }
        its.include(0.0);
        secs.include(0.0);
        devs.include(0.0);
        ConvergenceFigure {
            runs,
            names,
            finals,
            best,
            floor: floor.log10(),
            has_zero,
            iterations: its.padded(0.02, (0.0, 1.0)),
            seconds: secs.padded(0.02, (0.0, 1.0)),
            objective: decade_range(objs),
            deviation: devs.padded(0.06, (-1.0, 1.0)),
        }
    }

    fn is_empty(&self) -> bool {
        self.runs.iter().all(|r| r.by_iteration.is_empty())
    }
}

/// Parameter `k` of `run` as (iteration, (p − p_final) / max(|p_final|, range)):
/// every curve ends at 0 and stays within ±1, whatever the parameter's units,
/// so up to a handful of parameters share one readable axis.
fn normalised_trajectory(run: &crate::fit::history::RunHistory, k: usize) -> Vec<(f64, f64)> {
    let values: Vec<(f64, f64)> = run
        .records
        .iter()
        .filter_map(|r| r.params.get(k).map(|&p| (r.iteration as f64, p)))
        .filter(|(_, p)| p.is_finite())
        .collect();
    let Some(&(_, last)) = values.last() else {
        return Vec::new();
    };
    let mut span = Span::EMPTY;
    for &(_, p) in &values {
        span.include(p);
    }
    let scale = last.abs().max(span.width());
    if !(scale.is_finite() && scale > 0.0) {
        // A parameter that never moved: a flat line at zero says exactly that.
        return values.iter().map(|&(i, _)| (i, 0.0)).collect();
    }
    values
        .iter()
        .map(|&(i, p)| (i, (p - last) / scale))
        .filter(|(_, d)| d.is_finite())
        .collect()
}

/// Most runs named in the legend (three rows).
const MAX_RUN_ENTRIES: usize = 12;

/// Width of the tick label column left of each panel.
const Y_LABEL_AREA: u32 = 84;

impl Figure for ConvergenceFigure {
    fn size(&self) -> (u32, u32) {
        SIZE
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        mode: TextMode,
    ) -> DrawResult<DB> {
        let (header, body) = root.split_vertically(74);
        draw_header(&header, "Fit convergence", &self.subtitle(), mode)?;
        if self.is_empty() {
            return draw_placeholder(&body, "no iterations recorded", mode);
        }

        let (w, h) = body.dim_in_pixel();
        let top_h = (f64::from(h) * TOP_SHARE).round() as u32;
        let (top, bottom) = body.split_vertically(top_h);
        let run_legend: Vec<LegendEntry> = self
            .runs
            .iter()
            .map(|r| {
                let label = match r.final_objective {
                    Some(f) => format!("{}: final F = {} m²", r.label, format_f(f)),
                    None => format!("{} (no records)", r.label),
                };
                LegendEntry::new(Swatch::Line(r.color, 3), label)
            })
            .collect();
        let run_legend = truncate_legend(run_legend, MAX_RUN_ENTRIES, "runs");
        let indent = (Y_LABEL_AREA + 6) as i32;
        let legend_h = legend_height(&run_legend, w as i32 - indent - 20) as u32;
        let (top_charts, run_legend_area) = top.split_vertically(top_h.saturating_sub(legend_h));
        let (left, right) = top_charts.split_horizontally(w / 2);
        self.draw_objective(&left, false, mode)?;
        self.draw_objective(&right, true, mode)?;
        draw_legend(&run_legend_area, &run_legend, indent, mode)?;

        let (param_area, param_legend_area) = bottom.split_horizontally(w - PARAM_LEGEND_W);
        self.draw_params(&param_area, mode)?;
        let param_legend: Vec<LegendEntry> = self
            .names
            .iter()
            .zip(&self.finals)
            .enumerate()
            .map(|(k, (name, fin))| {
                let label = match fin {
                    Some(v) => format!("{name} → {}", minus(format_sig(*v, 4))),
                    None => name.clone(),
                };
                LegendEntry::new(Swatch::Line(series_color(k), 3), label)
            })
            .collect();
        // A column beside the panel, starting level with its plotting area,
        // as long as the panel is tall.
        let (_, column_h) = param_legend_area.dim_in_pixel();
        let rows = (column_h as usize).saturating_sub(100) / 24;
        let param_legend = truncate_legend(param_legend, rows.max(1), "parameters");
        draw_legend_column(&param_legend_area, &param_legend, 40, mode)
    }
}

/// Tick count for an iteration axis: no more than one per whole iteration, so
/// short runs are not labelled 0.5, 1.5, ….
fn iteration_ticks((lo, hi): (f64, f64)) -> usize {
    ((hi - lo).clamp(0.0, 9.0).floor() as usize + 1).max(2)
}

/// An objective value for labels (F can be exactly 0 at convergence).
fn format_f(f: f64) -> String {
    if f == 0.0 {
        "0".into()
    } else {
        format_sig(f, 3)
    }
}

impl ConvergenceFigure {
    fn subtitle(&self) -> String {
        let runs = self.runs.len();
        let mut s = format!(
            "{runs} run{} · {} free parameter{}",
            if runs == 1 { "" } else { "s" },
            self.names.len(),
            if self.names.len() == 1 { "" } else { "s" }
        );
        if let Some(b) = self.best {
            let r = &self.runs[b];
            if let Some(f) = r.final_objective {
                s.push_str(&format!(" · best: {} with F = {} m²", r.label, format_f(f)));
            }
        }
        s
    }

    fn draw_objective<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        by_time: bool,
        mode: TextMode,
    ) -> DrawResult<DB> {
        let (x, caption, x_desc) = if by_time {
            (
                self.seconds,
                "objective against wall time",
                "wall time since the start of the run (s)",
            )
        } else {
            (self.iterations, "objective against iteration", "iteration")
        };
        let y = self.objective;
        let mut chart = build_chart(area, x, y, Y_LABEL_AREA)?;
        draw_axes(
            area,
            &mut chart,
            &Axes {
                caption,
                x_desc,
                y_desc: "objective F (m²)",
                x_ticks: if by_time { 10 } else { iteration_ticks(x) },
                y_ticks: decade_ticks(y),
                x_format: &|v| format_sig(v, 4),
                y_format: &|v| log_label(10f64.powf(v)),
            },
            mode,
        )?;
        let plot = chart.plotting_area();
        let px = pixel_mapper(&chart);
        let pixels = plot.strip_coord_spec();

        if self.has_zero {
            let (a, b) = (px((x.0, self.floor)), px((x.1, self.floor)));
            draw_dashed(&pixels, &[a, b], MUTED.stroke_width(1), 6.0, 4.0)?;
            let style = text(TICK_SIZE, MUTED).pos(Pos::new(HPos::Right, VPos::Bottom));
            draw_label(
                &pixels,
                "F = 0 is drawn on this line",
                (b.0 - 6, b.1 - 4),
                &style,
                mode,
            )?;
        }

        for r in &self.runs {
            let pts = if by_time { &r.by_time } else { &r.by_iteration };
            if pts.len() >= 2 {
                plot.draw(&PathElement::new(pts.clone(), r.color.stroke_width(2)))?;
            }
            // The end of every run is marked, so a single-record run still shows.
            if let Some(&last) = pts.last() {
                plot.draw(&Circle::new(last, 4, r.color.filled()))?;
            }
        }
        Ok(())
    }

    fn draw_params<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        mode: TextMode,
    ) -> DrawResult<DB> {
        let caption = match (self.best, self.runs.len()) {
            (Some(b), n) if n > 1 => format!(
                "parameters, normalised (bold: {}; faint: other runs)",
                self.runs[b].label
            ),
            _ => "parameters, normalised".to_string(),
        };
        let (x, y) = (self.iterations, self.deviation);
        let mut chart = build_chart(area, x, y, Y_LABEL_AREA)?;
        draw_axes(
            area,
            &mut chart,
            &Axes {
                caption: &caption,
                x_desc: "iteration",
                y_desc: "(p − p_final) / max(|p_final|, range)",
                x_ticks: iteration_ticks(x),
                y_ticks: 8,
                x_format: &|v| format_sig(v, 4),
                y_format: &|v| format_sig(v, 3),
            },
            mode,
        )?;
        let plot = chart.plotting_area();
        if self.names.is_empty() {
            return draw_placeholder(&plot.strip_coord_spec(), "no free parameters", mode);
        }
        plot.draw(&PathElement::new(
            vec![(x.0, 0.0), (x.1, 0.0)],
            MUTED.stroke_width(1),
        ))?;
        // Faint runs first, so the best run is drawn over them.
        let order = (0..self.runs.len())
            .filter(|&i| Some(i) != self.best)
            .chain(self.best);
        for i in order {
            let bold = Some(i) == self.best;
            for (k, traj) in self.runs[i].params.iter().enumerate() {
                let c = series_color(k);
                let style = if bold {
                    c.stroke_width(2)
                } else {
                    c.mix(0.3).stroke_width(1)
                };
                if traj.len() >= 2 {
                    plot.draw(&PathElement::new(traj.clone(), style))?;
                } else if let Some(&p) = traj.first() {
                    plot.draw(&Circle::new(p, 3, style.filled()))?;
                }
            }
        }
        Ok(())
    }
}
