//! The bands of `mirage ensemble --plot`: temperature and n − 1 against
//! height, the members' 95 % (2.5–97.5 %) and 68 % (16–84 %) envelopes as
//! filled bands, the median dashed, the best fit, and the truth when given.

use super::axes::{Axes, Span, build_chart, draw_axes, format_sig, pixel_mapper};
use super::figure::{Figure, draw_header, save};
use super::legend::{LegendEntry, Swatch, draw_legend};
use super::marker::draw_dashed;
use super::style::{DrawResult, INK, series_color};
use super::text::TextMode;
use crate::error::Result;
use crate::fit::ensemble::{EnsembleReport, Envelope};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

const SIZE: (u32, u32) = (1200, 720);
const HEADER: u32 = 74;
const LEGEND: u32 = 40;
const Y_LABEL_AREA: u32 = 74;

/// Draws `report`'s bands to `output` (`.png` or `.svg`), atomically.
pub fn draw_ensemble(report: &EnsembleReport, output: &Path) -> Result<()> {
    super::figure::ImageFormat::from_path(output)?;
    save(&EnsembleFigure { report }, output)
}

struct EnsembleFigure<'a> {
    report: &'a EnsembleReport,
}

/// A light version of `c` (mixed with white by `f`).
fn light(c: RGBColor, f: f64) -> RGBColor {
    let m = |v: u8| (v as f64 + (255.0 - v as f64) * f).round() as u8;
    RGBColor(m(c.0), m(c.1), m(c.2))
}

impl Figure for EnsembleFigure<'_> {
    fn size(&self) -> (u32, u32) {
        SIZE
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        mode: TextMode,
    ) -> DrawResult<DB> {
        let r = self.report;
        let p = &r.profiles;
        let (header, rest) = root.split_vertically(HEADER);
        let (legend, body) = rest.split_vertically(LEGEND);
        let panels = body.split_evenly((1, 2));
        let color = series_color(0);
        let t_caption = if p.implied {
            "implied temperature"
        } else {
            "temperature"
        };
        let series: [(&str, &str, &Envelope, f64); 2] = [
            (t_caption, "T (°C)", &p.temperature, 1.0),
            ("refractivity", "(n − 1) × 10⁶", &p.delta, 1e6),
        ];
        let top = p.heights.last().copied().unwrap_or(1.0).max(1e-3);
        for (area, (caption, desc, env, scale)) in panels.iter().zip(series) {
            let mut xs = Span::EMPTY;
            for v in env.percentiles.iter().flatten().chain(&env.best) {
                xs.include(v * scale);
            }
            for v in env.truth.iter().flatten() {
                xs.include(v * scale);
            }
            let x = xs.padded(0.06, (-1.0, 1.0));
            let mut chart = build_chart(area, x, (0.0, top), Y_LABEL_AREA)?;
            draw_axes(
                area,
                &mut chart,
                &Axes {
                    caption,
                    x_desc: desc,
                    y_desc: "height (m)",
                    x_ticks: 5,
                    y_ticks: 8,
                    x_format: &|v| format_sig(v, 4),
                    y_format: &|v| format_sig(v, 4),
                },
                mode,
            )?;
            let band = |lo: &[f64], hi: &[f64]| -> Vec<(f64, f64)> {
                let mut pts: Vec<(f64, f64)> = lo
                    .iter()
                    .zip(&p.heights)
                    .map(|(v, h)| (v * scale, *h))
                    .collect();
                pts.extend(
                    hi.iter()
                        .zip(&p.heights)
                        .rev()
                        .map(|(v, h)| (v * scale, *h)),
                );
                pts.retain(|q| q.0.is_finite());
                pts
            };
            let q = &env.percentiles;
            chart.plotting_area().draw(&Polygon::new(
                band(&q[0], &q[4]),
                light(color, 0.8).filled(),
            ))?;
            chart.plotting_area().draw(&Polygon::new(
                band(&q[1], &q[3]),
                light(color, 0.55).filled(),
            ))?;
            let line = |v: &[f64]| -> Vec<(f64, f64)> {
                v.iter()
                    .zip(&p.heights)
                    .map(|(v, h)| (v * scale, *h))
                    .filter(|q| q.0.is_finite())
                    .collect()
            };
            let px = pixel_mapper(&chart);
            let median: Vec<(i32, i32)> = line(&q[2]).into_iter().map(&px).collect();
            let plot = chart.plotting_area().strip_coord_spec();
            draw_dashed(&plot, &median, color.stroke_width(2), 8.0, 5.0)?;
            chart
                .plotting_area()
                .draw(&PathElement::new(line(&env.best), color.stroke_width(3)))?;
            if let Some(t) = &env.truth {
                chart
                    .plotting_area()
                    .draw(&PathElement::new(line(t), INK.stroke_width(2)))?;
            }
        }
        let mut entries = vec![
            LegendEntry::new(Swatch::Band(light(color, 0.8)), "95 % of members"),
            LegendEntry::new(Swatch::Band(light(color, 0.55)), "68 % of members"),
            LegendEntry::new(Swatch::Dashed(color), "median"),
            LegendEntry::new(Swatch::Line(color, 3), "best fit"),
        ];
        if p.temperature.truth.is_some() {
            entries.push(LegendEntry::new(Swatch::Line(INK, 2), "truth"));
        }
        draw_legend(&legend, &entries, Y_LABEL_AREA as i32, mode)?;
        let how = match (r.resampling.kind, r.resampling.noise) {
            ("parametric", Some(s)) => format!("parametric resampling, σ = {}", format_sig(s, 3)),
            _ => "bootstrap resampling".to_string(),
        };
        let subtitle = format!(
            "{} members, {how}, seed {}   ·   at x = {} m, z = {} m",
            r.members.len(),
            r.resampling.seed,
            format_sig(p.at[0], 4),
            format_sig(p.at[1], 4)
        );
        draw_header(
            &header,
            &format!("{}: ensemble of fits", r.problem),
            &subtitle,
            mode,
        )
    }
}
