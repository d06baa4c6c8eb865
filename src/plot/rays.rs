//! The ray diagram of a problem: every pair's traced ray in side view, beside
//! the refractivity profile δ(y) that bends it, and for real air beside the
//! temperature T(h) that makes that δ (a panel of its own, on the same heights).
//!
//! Over the round earth (`earth` in the problem) the side view keeps the
//! frame's y and draws the ground as the sphere's profile in pair 0's vertical
//! plane, y = √(R² − ρ²) − R at horizontal distance ρ from the sphere's axis,
//! so that a ray's height above the ground is its distance above that curve
//! (the profile panels, δ and T against the height, are unchanged: above pair
//! 0's origin height and y agree to its drop, ρ²/2R).

use super::axes::{Axes, Span, build_chart, draw_axes, format_sig, pixel_mapper};
use super::figure::{Figure, draw_header, draw_placeholder, save};
use super::legend::{LegendEntry, Swatch, draw_legend, legend_height, truncate_legend};
use super::marker::{Marker, draw_dashed, draw_marker};
use super::style::{DrawResult, INK, MUTED, series_color};
use super::text::TextMode;
use crate::error::Result;
use crate::evaluate::pair_report;
use crate::math::V3;
use crate::medium::air::KELVIN;
use crate::medium::{Field, IndexField, Medium};
use crate::problem::Problem;
use crate::trace::{Earth, RayState};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

const SIZE: (u32, u32) = (1400, 700);
/// Share of the width given to the side view; the profile gets the rest.
const SIDE_SHARE: f64 = 0.72;
/// The same with a temperature panel beside the δ panel (real air).
const SIDE_SHARE_AIR: f64 = 0.56;
/// Heights sampled for the profile curves.
const PROFILE_SAMPLES: usize = 400;
/// Points of the round earth's profile across the side view.
const GROUND_SAMPLES: usize = 400;

const GROUND_FILL: RGBColor = RGBColor(238, 229, 212);
const GROUND_LINE: RGBColor = RGBColor(140, 110, 70);
const SIGHT: RGBColor = RGBColor(150, 150, 150);
/// Colours of the hot spots (their profile curves and ground bands), kept apart
/// from the pair palette so a hot spot is never mistaken for a ray.
const HOT_COLORS: [RGBColor; 4] = [
    RGBColor(178, 24, 43),
    RGBColor(118, 42, 131),
    RGBColor(1, 102, 94),
    RGBColor(140, 81, 10),
];

fn hot_color(j: usize) -> RGBColor {
    HOT_COLORS[j % HOT_COLORS.len()]
}

/// `c` mixed with white (`t` = 0: `c`, 1: white): opaque stand-in for
/// transparency, which renders the same in PNG and SVG.
fn tint(c: RGBColor, t: f64) -> RGBColor {
    let m = |v: u8| (v as f64 + (255.0 - v as f64) * t).round() as u8;
    RGBColor(m(c.0), m(c.1), m(c.2))
}

/// Draws the ray diagram of `problem` with `medium`: a side view of every pair's
/// traced ray (with its line of sight, origin, `through`, target and endpoint)
/// and, beside it on the same heights, δ(y) above the first pair's origin and
/// over each hot spot centre. The format follows the extension of `output`
/// (`.png` or `.svg`); the file is written atomically.
pub fn draw_rays(problem: &Problem, medium: &Medium, output: &Path) -> Result<()> {
    // Refuse a bad extension before spending time on tracing.
    super::figure::ImageFormat::from_path(output)?;
    let figure = RayFigure::new(problem, medium);
    save(&figure, output)
}

/// One pair in side-view coordinates: (distance along the view, height).
struct PairView {
    label: String,
    color: RGBColor,
    ray: Vec<(f64, f64)>,
    origin: (f64, f64),
    through: (f64, f64),
    target: (f64, f64),
    endpoint: (f64, f64),
    sight: [(f64, f64); 2],
}

/// A δ(y) curve of the profile panel: (δ·10⁶, y).
struct Profile {
    label: String,
    color: RGBColor,
    dashed: bool,
    points: Vec<(f64, f64)>,
}

/// Where pair 0's view passes over a hot spot, as a range of view distance.
struct HotBand {
    label: String,
    color: RGBColor,
    from: f64,
    to: f64,
}

struct RayFigure {
    title: String,
    method: String,
    pairs: Vec<PairView>,
    bands: Vec<HotBand>,
    profiles: Vec<Profile>,
    /// T(h) curves (°C, y) on the same columns as `profiles`; real air only.
    temperatures: Vec<Profile>,
    x: (f64, f64),
    y: (f64, f64),
    delta: (f64, f64),
    /// The range of `temperatures` (°C).
    temperature: (f64, f64),
    /// Over the round earth, the ground's profile under pair 0's view: (view
    /// distance, y) across the x range; empty over the flat ground.
    ground: Vec<(f64, f64)>,
}

/// Unit horizontal direction from `origin` toward `target` (the target plane's
/// normal), and the view distance of a point along it.
struct ViewFrame {
    origin: V3,
    along: V3,
}

impl ViewFrame {
    fn distance(&self, p: V3) -> f64 {
        (p.x - self.origin.x) * self.along.x + (p.z - self.origin.z) * self.along.z
    }
    fn project(&self, p: V3) -> (f64, f64) {
        (self.distance(p), p.y)
    }
}

/// The traced path as a polyline to draw. An adaptive step can span tens of
/// metres, far more than a pixel, so each step is filled in along the cubic
/// Hermite curve through its end states (positions and unit tangents against
/// arc length). A ray that reached its target plane is cut at its endpoint: the
/// last step ends beyond the plane.
fn ray_polyline(
    path: &[RayState],
    frame: &ViewFrame,
    target: V3,
    report: &crate::evaluate::PairReport,
) -> Vec<V3> {
    let plane = frame.distance(target);
    let endpoint = V3::from(report.endpoint);
    let reached = !report.unreachable;
    let gap = plane.abs().max(1.0) / 400.0;
    let mut out = Vec::with_capacity(path.len());
    let Some(first) = path.first() else {
        return out;
    };
    out.push(first.x);
    for w in path.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        let ds = b.s - a.s;
        let pieces = if ds.is_finite() && ds > gap {
            (ds / gap).ceil().min(64.0) as usize
        } else {
            1
        };
        let (t0, t1) = (a.v.normalized() * ds, b.v.normalized() * ds);
        for k in 1..=pieces {
            let u = k as f64 / pieces as f64;
            let p = if pieces == 1 {
                b.x
            } else {
                let (u2, u3) = (u * u, u * u * u);
                a.x * (2.0 * u3 - 3.0 * u2 + 1.0)
                    + t0 * (u3 - 2.0 * u2 + u)
                    + b.x * (3.0 * u2 - 2.0 * u3)
                    + t1 * (u3 - u2)
            };
            if reached && frame.distance(p) >= plane {
                out.push(endpoint);
                return out;
            }
            out.push(p);
        }
    }
    if reached {
        out.push(endpoint);
    }
    out
}

fn describe_method(problem: &Problem) -> String {
    let spec = &problem.trace_spec;
    let mut s = match (spec.method.as_str(), spec.step, spec.tolerance) {
        ("rk4", Some(step), _) => format!("traced with RK4, step {} m", format_sig(step, 3)),
        ("dopri5", _, Some(tol)) => format!(
            "traced with Dormand–Prince 5(4), tolerance {}",
            format_sig(tol, 2)
        ),
        (m, _, _) => format!("traced with {m}"),
    };
    if let Some(l) = spec.max_length {
        s.push_str(&format!(", max length {} m", format_sig(l, 3)));
    }
    s
}

impl RayFigure {
    fn new(problem: &Problem, medium: &Medium) -> RayFigure {
        use rayon::prelude::*;
        let fields = crate::evaluate::pair_fields(problem, medium);
        // The profiles show the medium as given (its own wavelength).
        let field = &fields.fields()[0];
        let traced: Vec<_> = problem
            .pairs
            .par_iter()
            .enumerate()
            .map(|(i, pair)| {
                let mut path: Vec<RayState> = Vec::new();
                let report = pair_report(pair, fields.of(i), &problem.trace, Some(&mut path));
                (report, path)
            })
            .collect();

        let mut pairs = Vec::with_capacity(traced.len());
        let mut objective = 0.0;
        for (i, (pair, (report, path))) in problem.pairs.iter().zip(traced).enumerate() {
            objective += 0.5 * report.residual.iter().map(|r| r * r).sum::<f64>();
            let frame = ViewFrame {
                origin: pair.origin(),
                along: pair.plane().normal,
            };
            let origin = frame.project(pair.origin());
            let target = frame.project(pair.target());
            let through = frame.project(V3::from(pair.through));
            // The line of sight runs straight to the target plane; a sight that
            // does not approach the plane is drawn only to `through`.
            let run = through.0 - origin.0;
            let sight_end = if run > 0.0 {
                let y = origin.1 + (through.1 - origin.1) * (target.0 - origin.0) / run;
                (target.0, y)
            } else {
                through
            };
            let mut flags = Vec::new();
            if report.occluded {
                flags.push("occluded");
            }
            if report.unreachable {
                flags.push("unreachable");
            }
            let mut label = format!("pair {i}: misses by {} m", format_sig(report.distance, 2));
            if !flags.is_empty() {
                label.push_str(&format!(" ({})", flags.join(", ")));
            }
            pairs.push(PairView {
                label,
                color: series_color(i),
                ray: ray_polyline(&path, &frame, pair.target(), &report)
                    .into_iter()
                    .map(|x| frame.project(x))
                    .filter(|p| p.0.is_finite() && p.1.is_finite())
                    .collect(),
                origin,
                through,
                target,
                endpoint: frame.project(V3::from(report.endpoint)),
                sight: [origin, sight_end],
            });
        }

        // The x range comes from where rays go and what they must hit; `through`
        // can lie far beyond and is drawn only when it falls inside.
        let mut xs = Span::EMPTY;
        xs.include(0.0);
        for p in &pairs {
            for q in p.ray.iter().chain([&p.origin, &p.target, &p.endpoint]) {
                xs.include(q.0);
            }
        }
        let x = xs.padded(0.03, (0.0, 100.0));

        // Heights from the data alone: mirage bends are metres over kilometres,
        // so tying the y range to the x range would flatten every ray.
        let mut ys = Span::EMPTY;
        for p in &pairs {
            for q in p.ray.iter().chain([&p.origin, &p.target, &p.endpoint]) {
                ys.include(q.1);
            }
            for q in p.sight {
                ys.include(q.1);
            }
            if (x.0..=x.1).contains(&p.through.0) {
                ys.include(p.through.1);
            }
        }
        // Show the ground when the scene is near it (within its own height).
        if !ys.is_empty() && ys.lo > 0.0 && ys.lo <= ys.width().max(1.0) {
            ys.include(0.0);
        }
        // The sphere's profile under pair 0's view, sampled across the range.
        let ground_at = |d: f64| -> Option<f64> {
            let (Earth::Round { radius }, Some(pair)) =
                (problem.trace.earth, problem.pairs.first())
            else {
                return None;
            };
            let o = pair.origin();
            let u = pair.plane().normal;
            let (gx, gz) = (o.x + d * u.x, o.z + d * u.z);
            let rho2 = gx * gx + gz * gz;
            // √(R² − ρ²) − R without cancellation.
            (rho2 < radius * radius).then(|| -rho2 / ((radius * radius - rho2).sqrt() + radius))
        };
        let mut ground = Vec::new();
        if !ys.is_empty() {
            for k in 0..=GROUND_SAMPLES {
                let d = x.0 + (x.1 - x.0) * k as f64 / GROUND_SAMPLES as f64;
                if let Some(g) = ground_at(d) {
                    ground.push((d, g));
                }
            }
            // The ground within the scene's own height shows; a ground
            // far below it is left out, as over the flat ground.
            let width = ys.width().max(1.0);
            for &(_, g) in &ground {
                if g >= ys.lo - width {
                    ys.include(g);
                }
            }
        }
        let fallback_y = (-1.0, 10.0);
        let y = ys.padded(0.08, fallback_y);

        // Hot spot extent under pair 0's view: solve |o + s·u − c| = R.
        let mut bands = Vec::new();
        if let Some(pair) = problem.pairs.first() {
            let o = pair.origin();
            let u = pair.plane().normal;
            for (j, h) in medium.envelope().patches.iter().enumerate() {
                let (dx, dz) = (o.x - h.x, o.z - h.z);
                let b = dx * u.x + dz * u.z;
                let c = dx * dx + dz * dz - h.radius * h.radius;
                let disc = b * b - c;
                if disc > 0.0 {
                    let r = disc.sqrt();
                    let (from, to) = ((-b - r).max(x.0), (-b + r).min(x.1));
                    if from < to {
                        bands.push(HotBand {
                            label: format!("hotspots[{j}] under pair 0's view"),
                            color: tint(hot_color(j), 0.55),
                            from,
                            to,
                        });
                    }
                }
            }
        }

        // δ(y) columns: above pair 0's origin (what its ray starts in), and over
        // each hot spot centre (where the mirage is made).
        let (px, pz, where_) = match problem.pairs.first() {
            Some(p) => (
                p.origin[0],
                p.origin[2],
                "above pair 0's origin".to_string(),
            ),
            None => (0.0, 0.0, "at x = 0, z = 0".to_string()),
        };
        let heights: Vec<f64> = (0..=PROFILE_SAMPLES)
            .map(|k| y.0 + (y.1 - y.0) * k as f64 / PROFILE_SAMPLES as f64)
            .collect();
        let column = |cx: f64, cz: f64| -> Vec<(f64, f64)> {
            heights
                .iter()
                .map(|&h| (field.delta(V3::new(cx, h, cz)) * 1e6, h))
                .filter(|p| p.0.is_finite())
                .collect()
        };
        let air = match &field {
            Field::Air(f) => Some(f),
            _ => None,
        };
        let quantity = if air.is_some() { "δ and T" } else { "δ" };
        let mut profiles = vec![Profile {
            label: format!("{quantity} {where_}"),
            color: INK,
            dashed: false,
            points: column(px, pz),
        }];
        for (j, h) in medium.envelope().patches.iter().enumerate() {
            profiles.push(Profile {
                label: format!("{quantity} over hotspots[{j}]"),
                color: hot_color(j),
                dashed: true,
                points: column(h.x, h.z),
            });
        }
        let mut ds = Span::EMPTY;
        for p in &profiles {
            for q in &p.points {
                ds.include(q.0);
            }
        }
        if !ds.is_empty() && ds.lo > 0.0 && ds.lo < 0.25 * ds.hi {
            // A profile that starts near zero reads better against zero.
            ds.include(0.0);
        }
        let delta = ds.padded(0.06, (-1.0, 1.0));

        // T(h) on the same columns, for real air.
        let mut temperatures = Vec::new();
        if let Some(f) = air {
            let mut columns = vec![(px, pz)];
            columns.extend(medium.envelope().patches.iter().map(|h| (h.x, h.z)));
            for (p, (cx, cz)) in profiles.iter().zip(columns) {
                temperatures.push(Profile {
                    label: p.label.clone(),
                    color: p.color,
                    dashed: p.dashed,
                    points: heights
                        .iter()
                        .map(|&h| (f.kelvin(V3::new(cx, h, cz)).0 - KELVIN, h))
                        .filter(|q| q.0.is_finite())
                        .collect(),
                });
            }
        }
        let mut ts = Span::EMPTY;
        for p in &temperatures {
            for q in &p.points {
                ts.include(q.0);
            }
        }
        let temperature = ts.padded(0.06, (0.0, 30.0));

        let mut method = describe_method(problem);
        if !pairs.is_empty() {
            method.push_str(&format!(
                "   ·   F = ½ Σ |r|² = {} m²",
                format_sig(objective, 3)
            ));
        }
        RayFigure {
            title: problem.name.clone(),
            method,
            pairs,
            bands,
            profiles,
            temperatures,
            x,
            y,
            delta,
            temperature,
            ground,
        }
    }

    fn side_legend(&self) -> Vec<LegendEntry> {
        let pairs: Vec<LegendEntry> = self
            .pairs
            .iter()
            .map(|p| LegendEntry::new(Swatch::Line(p.color, 3), p.label.clone()))
            .collect();
        let mut out = truncate_legend(pairs, MAX_PAIR_ENTRIES, "pairs");
        if !self.pairs.is_empty() {
            out.push(LegendEntry::new(
                Swatch::Dashed(SIGHT),
                "straight line of sight",
            ));
            out.push(LegendEntry::new(
                Swatch::Marker(Marker::Circle, INK),
                "origin",
            ));
            out.push(LegendEntry::new(
                Swatch::Marker(Marker::Triangle, INK),
                "through",
            ));
            out.push(LegendEntry::new(
                Swatch::Marker(Marker::Star, MUTED),
                "target",
            ));
            out.push(LegendEntry::new(
                Swatch::Marker(Marker::Cross, INK),
                "endpoint",
            ));
        }
        for b in &self.bands {
            out.push(LegendEntry::new(Swatch::Band(b.color), b.label.clone()));
        }
        out
    }

    fn profile_legend(&self) -> Vec<LegendEntry> {
        self.profiles
            .iter()
            .map(|p| {
                let swatch = if p.dashed {
                    Swatch::Dashed(p.color)
                } else {
                    Swatch::Line(p.color, 2)
                };
                LegendEntry::new(swatch, p.label.clone())
            })
            .collect()
    }
}

/// Width of the tick label column left of each panel; the panels share
/// everything vertical, so their height axes line up pixel for pixel.
const SIDE_Y_LABEL_AREA: u32 = 84;
const PROFILE_Y_LABEL_AREA: u32 = 74;
const HEADER: u32 = 74;
/// Most pairs named in the legend (four rows of the side view's legend).
const MAX_PAIR_ENTRIES: usize = 16;

impl Figure for RayFigure {
    fn size(&self) -> (u32, u32) {
        SIZE
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        mode: TextMode,
    ) -> DrawResult<DB> {
        let (header, body) = root.split_vertically(HEADER);
        let (w, body_h) = body.dim_in_pixel();
        let share = if self.temperatures.is_empty() {
            SIDE_SHARE
        } else {
            SIDE_SHARE_AIR
        };
        let side_w = (w as f64 * share).round() as u32;
        let side_legend = self.side_legend();
        let profile_legend = self.profile_legend();
        // Legends go in a strip under the panels, where they cannot hide data.
        let legend_h = legend_height(&side_legend, (side_w - SIDE_Y_LABEL_AREA - 20) as i32)
            .max(legend_height(
                &profile_legend,
                (w - side_w - PROFILE_Y_LABEL_AREA - 20) as i32,
            ))
            .max(30);
        let (charts, legends) = body.split_vertically(body_h.saturating_sub(legend_h as u32));
        let (side_area, profile_area) = charts.split_horizontally(side_w);
        let (side_legend_area, profile_legend_area) = legends.split_horizontally(side_w);

        let scale_note = self.draw_side(&side_area, mode)?;
        if self.temperatures.is_empty() {
            self.draw_profile(&profile_area, mode)?;
        } else {
            let (pw, _) = profile_area.dim_in_pixel();
            let (delta_area, t_area) = profile_area.split_horizontally(pw / 2);
            self.draw_profile(&delta_area, mode)?;
            self.draw_curves(
                &t_area,
                &self.temperatures,
                self.temperature,
                ("temperature", "T (°C)"),
                mode,
            )?;
        }
        let indent = |label_area: u32| (label_area + 6) as i32;
        draw_legend(
            &side_legend_area,
            &side_legend,
            indent(SIDE_Y_LABEL_AREA),
            mode,
        )?;
        draw_legend(
            &profile_legend_area,
            &profile_legend,
            indent(PROFILE_Y_LABEL_AREA),
            mode,
        )?;

        let mut subtitle = self.method.clone();
        if let Some(note) = scale_note {
            subtitle.push_str(&format!("   ·   {note}"));
        }
        draw_header(&header, &self.title, &subtitle, mode)
    }
}

/// Tick label of a length axis.
fn metres(v: f64) -> String {
    format_sig(v, 4)
}

impl RayFigure {
    /// Draws the side view; returns a note on the vertical scale when heights
    /// are drawn at a different scale from distances.
    fn draw_side<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        mode: TextMode,
    ) -> std::result::Result<Option<String>, DrawingAreaErrorKind<DB::ErrorType>> {
        let (x, y) = (self.x, self.y);
        let mut chart = build_chart(area, x, y, SIDE_Y_LABEL_AREA)?;

        // Pixels per metre vertically over pixels per metre horizontally.
        let (pw, ph) = chart.plotting_area().dim_in_pixel();
        let ratio = (f64::from(ph) / (y.1 - y.0)) / (f64::from(pw) / (x.1 - x.0));
        let (y_desc, note) = if ratio > 2.0 {
            (
                "height (m, exaggerated)",
                Some(format!("heights exaggerated {}×", format_sig(ratio, 2))),
            )
        } else if ratio < 0.5 {
            (
                "height (m, compressed)",
                Some(format!(
                    "heights compressed {}×",
                    format_sig(1.0 / ratio, 2)
                )),
            )
        } else {
            ("height (m)", None)
        };
        // Over the round earth the vertical is the frame's y; heights are
        // measured from the curved ground.
        let y_desc = if self.ground.is_empty() {
            y_desc.to_string()
        } else {
            y_desc.replacen("height", "y", 1)
        };
        let caption = if self.ground.is_empty() {
            "side view along each pair's line of sight"
        } else {
            "side view along each pair's line of sight, over the round earth"
        };
        draw_axes(
            area,
            &mut chart,
            &Axes {
                caption,
                x_desc: "distance along the view (m)",
                y_desc: &y_desc,
                x_ticks: 10,
                y_ticks: 8,
                x_format: &metres,
                y_format: &metres,
            },
            mode,
        )?;

        let plot = chart.plotting_area();
        if !self.ground.is_empty() {
            // The round earth: filled below the sphere's profile, hot spots
            // marked on it, then its line.
            let mut fill = self.ground.clone();
            fill.push((x.1, y.0));
            fill.push((x.0, y.0));
            plot.draw(&Polygon::new(fill, GROUND_FILL.filled()))?;
            let depth = 0.02 * (y.1 - y.0);
            for b in &self.bands {
                let under: Vec<(f64, f64)> = self
                    .ground
                    .iter()
                    .copied()
                    .filter(|q| b.from <= q.0 && q.0 <= b.to)
                    .collect();
                let mut band = under.clone();
                band.extend(under.iter().rev().map(|&(d, g)| (d, g - depth)));
                if band.len() >= 3 {
                    plot.draw(&Polygon::new(band, b.color.filled()))?;
                }
            }
            plot.draw(&PathElement::new(
                self.ground.clone(),
                GROUND_LINE.stroke_width(2),
            ))?;
        } else if y.0 < 0.0 {
            // Ground: filled below y = 0, hot spots marked on it, then its line.
            plot.draw(&Rectangle::new(
                [(x.0, y.0), (x.1, 0.0_f64.min(y.1))],
                GROUND_FILL.filled(),
            ))?;
            let depth = (0.35 * -y.0).min(0.05 * (y.1 - y.0));
            for b in &self.bands {
                plot.draw(&Rectangle::new(
                    [(b.from, -depth), (b.to, 0.0)],
                    b.color.filled(),
                ))?;
            }
        }
        if self.ground.is_empty() && y.0 <= 0.0 && 0.0 <= y.1 {
            plot.draw(&PathElement::new(
                vec![(x.0, 0.0), (x.1, 0.0)],
                GROUND_LINE.stroke_width(2),
            ))?;
        }

        let px = pixel_mapper(&chart);
        let pixels = plot.strip_coord_spec();
        if self.pairs.is_empty() {
            draw_placeholder(&pixels, "no point pairs in this problem", mode)?;
            return Ok(note);
        }
        for p in &self.pairs {
            draw_dashed(
                &pixels,
                &[px(p.sight[0]), px(p.sight[1])],
                SIGHT.stroke_width(1),
                7.0,
                5.0,
            )?;
        }
        for p in &self.pairs {
            plot.draw(&PathElement::new(p.ray.clone(), p.color.stroke_width(2)))?;
        }
        let inside = |q: (f64, f64)| x.0 <= q.0 && q.0 <= x.1 && y.0 <= q.1 && q.1 <= y.1;
        for p in &self.pairs {
            draw_marker(&pixels, px(p.origin), Marker::Circle, p.color)?;
            if inside(p.through) {
                draw_marker(&pixels, px(p.through), Marker::Triangle, p.color)?;
            }
            draw_marker(&pixels, px(p.target), Marker::Star, p.color)?;
            draw_marker(&pixels, px(p.endpoint), Marker::Cross, INK)?;
        }
        Ok(note)
    }

    fn draw_profile<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        mode: TextMode,
    ) -> DrawResult<DB> {
        self.draw_curves(
            area,
            &self.profiles,
            self.delta,
            ("refractivity profile", "δ × 10⁶"),
            mode,
        )
    }

    /// Draws height profiles (`curves`, x in `d`) against the side view's
    /// heights, with a `(caption, x axis label)`.
    fn draw_curves<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        curves: &[Profile],
        d: (f64, f64),
        (caption, x_desc): (&str, &str),
        mode: TextMode,
    ) -> DrawResult<DB> {
        let y = self.y;
        let mut chart = build_chart(area, d, y, PROFILE_Y_LABEL_AREA)?;
        draw_axes(
            area,
            &mut chart,
            &Axes {
                caption,
                x_desc,
                y_desc: "height (m)",
                x_ticks: 5,
                y_ticks: 8,
                x_format: &|v| format_sig(v, 3),
                y_format: &metres,
            },
            mode,
        )?;

        let plot = chart.plotting_area();
        if y.0 < 0.0 {
            plot.draw(&Rectangle::new(
                [(d.0, y.0), (d.1, 0.0_f64.min(y.1))],
                GROUND_FILL.filled(),
            ))?;
        }
        if y.0 <= 0.0 && 0.0 <= y.1 {
            plot.draw(&PathElement::new(
                vec![(d.0, 0.0), (d.1, 0.0)],
                GROUND_LINE.stroke_width(2),
            ))?;
        }
        if d.0 < 0.0 && 0.0 < d.1 {
            plot.draw(&PathElement::new(
                vec![(0.0, y.0), (0.0, y.1)],
                MUTED.stroke_width(1),
            ))?;
        }

        let px = pixel_mapper(&chart);
        let pixels = plot.strip_coord_spec();
        // Hot spot curves on top of the origin curve would hide it where they
        // coincide (high above the ground), so the dashed ones go first.
        for p in curves.iter().rev() {
            if p.dashed {
                let pts: Vec<(i32, i32)> = p.points.iter().map(|&q| px(q)).collect();
                draw_dashed(&pixels, &pts, p.color.stroke_width(2), 9.0, 6.0)?;
            } else {
                plot.draw(&PathElement::new(p.points.clone(), p.color.stroke_width(2)))?;
            }
        }
        Ok(())
    }
}
