//! The refraction plot of `mirage refraction`: refraction (arcminutes)
//! against apparent elevation (degrees), mirage's traced rows as points
//! joined by a line, Bennett's formula beside them (dashed, 200 points from
//! 0° to the highest elevation, with the observer's pressure and
//! temperature), the rows whose rays meet the ground as crosses on the axis,
//! and the dip of the apparent horizon as a vertical line at −dip.

use super::axes::{Axes, Span, build_chart, draw_axes, format_sig, pixel_mapper};
use super::figure::{Figure, draw_header, save};
use super::legend::{Corner, LegendEntry, Swatch, draw_legend_box};
use super::marker::{Marker, draw_dashed, draw_marker};
use super::style::{DrawResult, MUTED, TICK_SIZE, series_color, text};
use super::text::{TextMode, draw_label};
use crate::error::Result;
use crate::refraction::{Refraction, bennett_arcmin};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

/// Draws `report` (titled `name`) to `output` (`.png` or `.svg`), atomically.
pub fn draw_refraction(name: &str, report: &Refraction, output: &Path) -> Result<()> {
    super::figure::ImageFormat::from_path(output)?;
    save(&RefractionFigure { name, report }, output)
}

struct RefractionFigure<'a> {
    name: &'a str,
    report: &'a Refraction,
}

impl RefractionFigure<'_> {
    /// Bennett's curve from 0° to `top` degrees, if the air's pressure and
    /// temperature are known.
    fn bennett(&self, top: f64) -> Vec<(f64, f64)> {
        let r = self.report;
        match (r.pressure_pa, r.temperature_c) {
            (Some(p), Some(t)) if top > 0.0 => (0..=200)
                .map(|i| {
                    let e = top * f64::from(i) / 200.0;
                    (e, bennett_arcmin(e, p, t))
                })
                .collect(),
            _ => Vec::new(),
        }
    }
}

impl Figure for RefractionFigure<'_> {
    fn size(&self) -> (u32, u32) {
        (1100, 720)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        mode: TextMode,
    ) -> DrawResult<DB> {
        let r = self.report;
        let (header, body) = root.split_vertically(74);
        let traced: Vec<(f64, f64)> = r
            .rows
            .iter()
            .filter_map(|row| Some((row.elevation_deg, row.refraction_arcmin?)))
            .collect();
        let ground: Vec<f64> = r
            .rows
            .iter()
            .filter(|row| row.hits_ground)
            .map(|row| row.elevation_deg)
            .collect();
        let dip_deg = r.dip_arcmin.map(|d| -d / 60.0);
        let mut xs = Span::EMPTY;
        let mut ys = Span::EMPTY;
        ys.include(0.0);
        for row in &r.rows {
            xs.include(row.elevation_deg);
        }
        for q in &traced {
            ys.include(q.1);
        }
        if let Some(d) = dip_deg {
            xs.include(d);
        }
        let bennett = self.bennett(xs.padded(0.0, (0.0, 1.0)).1);
        for q in &bennett {
            ys.include(q.1);
        }
        let x = xs.padded(0.04, (-1.0, 1.0));
        let y = ys.padded(0.06, (0.0, 1.0));
        let mut chart = build_chart(&body, x, y, 84)?;
        draw_axes(
            &body,
            &mut chart,
            &Axes {
                caption: "astronomical refraction (apparent − true elevation)",
                x_desc: "apparent elevation (°)",
                y_desc: "refraction (′)",
                x_ticks: 10,
                y_ticks: 8,
                x_format: &|v| format_sig(v, 4),
                y_format: &|v| format_sig(v, 4),
            },
            mode,
        )?;
        let px = pixel_mapper(&chart);
        let plot = chart.plotting_area();
        let pixels = plot.strip_coord_spec();
        let mut legend = Vec::new();
        if let Some(d) = dip_deg {
            let line = [px((d, y.0)), px((d, y.1))];
            draw_dashed(&pixels, &line, MUTED.stroke_width(2), 6.0, 5.0)?;
            let (lx, ly) = px((d, y.1));
            let label = format!("dip {}′", format_sig(-d * 60.0, 4));
            let style = text(TICK_SIZE, MUTED).pos(Pos::new(HPos::Left, VPos::Top));
            draw_label(&pixels, &label, (lx + 5, ly + 6), &style, mode)?;
            legend.push(LegendEntry::new(
                Swatch::Dashed(MUTED),
                "dip of the apparent horizon",
            ));
        }
        if !bennett.is_empty() {
            let line: Vec<(i32, i32)> = bennett.iter().map(|&q| px(q)).collect();
            draw_dashed(&pixels, &line, series_color(1).stroke_width(2), 9.0, 6.0)?;
            legend.push(LegendEntry::new(
                Swatch::Dashed(series_color(1)),
                "Bennett (1982), the observer's P and T",
            ));
        }
        let color = series_color(0);
        if !traced.is_empty() {
            plot.draw(&PathElement::new(traced.clone(), color.stroke_width(2)))?;
            for &q in &traced {
                draw_marker(&pixels, px(q), Marker::Circle, color)?;
            }
            legend.push(LegendEntry::new(
                Swatch::Marker(Marker::Circle, color),
                "mirage: traced through the air",
            ));
        }
        if !ground.is_empty() {
            for &e in &ground {
                draw_marker(&pixels, px((e, 0.0)), Marker::Cross, MUTED)?;
            }
            legend.push(LegendEntry::new(
                Swatch::Marker(Marker::Cross, MUTED),
                "the ray meets the ground",
            ));
        }
        draw_legend_box(&pixels, &legend, Corner::UpperRight, mode)?;
        let subtitle = format!(
            "observer {} m up, earth radius {} m, air to {} m   ·   k = {}",
            format_sig(r.height, 6),
            format_sig(r.earth_radius, 7),
            format_sig(r.top, 6),
            format_sig(r.k, 4)
        );
        draw_header(
            &header,
            &format!("{}: refraction near the horizon", self.name),
            &subtitle,
            mode,
        )
    }
}
