//! The air profile of `mirage air`: four panels against height on the
//! vertical axis, T (°C), P (Pa), n − 1 (× 10⁶) and dn/dh (× 10⁶ per m), from
//! the rows of [`crate::profile::air_profile`]. For implied air the T panel
//! also draws the standard atmosphere (dashed) the excess is taken against.

use super::axes::{Axes, Span, build_chart, draw_axes, format_sig, pixel_mapper};
use super::figure::{Figure, draw_header, save};
use super::marker::draw_dashed;
use super::style::{DrawResult, MUTED, series_color};
use super::text::TextMode;
use crate::error::Result;
use crate::profile::AirProfile;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

const SIZE: (u32, u32) = (1600, 640);

/// A panel: caption, x axis label, (x, h) points.
type Panel<'a> = (&'a str, &'a str, Vec<(f64, f64)>);
const HEADER: u32 = 74;
const Y_LABEL_AREA: u32 = 74;

/// Draws `profile` (titled `name`) to `output` (`.png` or `.svg`), atomically.
pub fn draw_air(name: &str, profile: &AirProfile, output: &Path) -> Result<()> {
    super::figure::ImageFormat::from_path(output)?;
    save(&AirFigure { name, profile }, output)
}

struct AirFigure<'a> {
    name: &'a str,
    profile: &'a AirProfile,
}

impl Figure for AirFigure<'_> {
    fn size(&self) -> (u32, u32) {
        SIZE
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        mode: TextMode,
    ) -> DrawResult<DB> {
        let p = self.profile;
        let (header, body) = root.split_vertically(HEADER);
        let panels = body.split_evenly((1, 4));
        let rows = &p.rows;
        let t_caption = if p.implied {
            "implied temperature (dashed: standard)"
        } else {
            "temperature"
        };
        let series: [Panel; 4] = [
            (
                t_caption,
                "T (°C)",
                rows.iter().map(|r| (r.temperature_c, r.h)).collect(),
            ),
            (
                if p.implied {
                    "pressure (standard)"
                } else {
                    "pressure"
                },
                "P (Pa)",
                rows.iter().map(|r| (r.pressure_pa, r.h)).collect(),
            ),
            (
                "refractivity",
                "(n − 1) × 10⁶",
                rows.iter().map(|r| (r.delta * 1e6, r.h)).collect(),
            ),
            (
                "vertical gradient",
                "dn/dh × 10⁶ (per m)",
                rows.iter().map(|r| (r.dn_dh * 1e6, r.h)).collect(),
            ),
        ];
        let standard: Vec<(f64, f64)> = rows
            .iter()
            .filter_map(|r| Some((r.temperature_c - r.excess_k?, r.h)))
            .collect();
        let top = rows.last().map_or(1.0, |r| r.h.max(1e-3));
        for (k, (area, (caption, desc, points))) in panels.iter().zip(series).enumerate() {
            let mut xs = Span::EMPTY;
            for q in &points {
                xs.include(q.0);
            }
            if k == 0 {
                for q in &standard {
                    xs.include(q.0);
                }
            }
            let x = xs.padded(0.06, (-1.0, 1.0));
            let y = (0.0, top);
            let mut chart = build_chart(area, x, y, Y_LABEL_AREA)?;
            draw_axes(
                area,
                &mut chart,
                &Axes {
                    caption,
                    x_desc: desc,
                    y_desc: "height (m)",
                    x_ticks: 4,
                    y_ticks: 8,
                    x_format: &|v| format_sig(v, 4),
                    y_format: &|v| format_sig(v, 4),
                },
                mode,
            )?;
            let pts: Vec<(f64, f64)> = points
                .into_iter()
                .filter(|q| q.0.is_finite() && q.1.is_finite())
                .collect();
            if k == 0 && !standard.is_empty() {
                let px = pixel_mapper(&chart);
                let pixels: Vec<(i32, i32)> = standard.iter().map(|&q| px(q)).collect();
                let plot = chart.plotting_area().strip_coord_spec();
                draw_dashed(&plot, &pixels, MUTED.stroke_width(2), 9.0, 6.0)?;
            }
            chart
                .plotting_area()
                .draw(&PathElement::new(pts, series_color(k).stroke_width(2)))?;
        }
        let mut subtitle = format!(
            "{} medium at x = {} m, z = {} m, 0 to {} m",
            p.medium_kind,
            format_sig(p.at[0], 4),
            format_sig(p.at[1], 4),
            format_sig(top, 4)
        );
        if p.implied {
            subtitle.push_str("   ·   implied air: the standard atmosphere carrying this δ(h)");
        }
        if !p.warnings.is_empty() {
            subtitle.push_str(&format!("   ·   {} warning(s)", p.warnings.len()));
        }
        draw_header(
            &header,
            &format!("{}: air profile", self.name),
            &subtitle,
            mode,
        )
    }
}
