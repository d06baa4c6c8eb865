//! The vertical profile of a medium at one horizontal position, as air: the
//! rows `mirage air` writes and draws (`docs/air.md`, "`mirage air`"), and the
//! implied air a fit of a logistic medium reports.
//!
//! Real air reports its own T(h) and P(h) (`AirField::kelvin`,
//! `AirField::pressure`), δ = n − 1 and ∂δ/∂h from its field.
//!
//! Any other kind (the logistic "artist's" model, whose δ is not a level of
//! air but a shape: only its variation bends rays) is answered with the air
//! that makes the same mirage: the US 1976 standard atmosphere (15 °C at the
//! ground, −6.5 K/km, hydrostatic from 101 325 Pa, dry, under the
//! Gladstone–Dale law with K = δ_Ciddor(15 °C, 101 325 Pa, 550 nm)·288.15 K)
//! carries the medium's variation of δ, pinned at the top of the profile:
//!
//! ```text
//! δ_air(h) = δ_std(h) + (δ_m(h) − δ_m(h_top))
//! T(h)     = K · (P_std(h) / 101 325) / δ_air(h)          (Gladstone–Dale inverted)
//! dT/dh    = T · (P_std'/P_std − δ_air'/δ_air)
//! ```
//!
//! The inversion ([`gladstone_dale_kelvin`]) is exact: fed δ and P of
//! Gladstone–Dale air it returns that air's T to rounding. Pinning at the top
//! means the implied air is the standard atmosphere there; the level lower
//! down depends on the top chosen, its variation (what bends rays) does not.
//! Implied air that no weather makes is flagged ([`Warning`]): colder than
//! −60 °C, hotter than +90 °C, or |dT/dh| above 2500 K/m (50 K over 2 cm,
//! asphalt in full sun).
//!
//! Rows: 241 heights evenly from 0 to the top, plus 41 evenly over three reaches
//! of every feature thinner than a twentieth of the top, so that a 5 cm hot
//! layer under a 450 m profile is resolved.

use crate::math::V3;
use crate::medium::air::{
    Air, AirField, AirMedium, Formula, Humidity, KELVIN, Lapse, Temperature,
    refractivity::AirState, refractivity::refractivity,
};
use crate::medium::{IndexField, Medium};
use serde::Serialize;

/// The standard pressure at the ground (Pa).
pub const P0: f64 = 101_325.0;
/// The standard atmosphere's ground temperature (K).
pub const T0: f64 = 288.15;
/// The coldest implied air accepted without a warning (°C).
pub const COLDEST_PLAUSIBLE: f64 = -60.0;
/// The hottest implied air accepted without a warning (°C).
pub const HOTTEST_PLAUSIBLE: f64 = 90.0;
/// The steepest implied gradient accepted without a warning (K/m).
pub const STEEPEST_PLAUSIBLE: f64 = 2500.0;
/// The lowest default top (m).
pub const MIN_TOP: f64 = 20.0;
/// The default top in reaches of the highest feature.
pub const TOP_REACHES: f64 = 3.0;

const UNIFORM_ROWS: usize = 240;
const FEATURE_ROWS: usize = 40;

/// One height of the profile.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ProfileRow {
    /// Height above the ground (m).
    pub h: f64,
    /// Temperature (°C): the air's own, or the implied air's.
    pub temperature_c: f64,
    /// Implied air only: T − T_std (K).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub excess_k: Option<f64>,
    /// Pressure (Pa): the air's own, or the standard atmosphere's.
    pub pressure_pa: f64,
    /// The medium's own δ = n − 1.
    pub delta: f64,
    /// The medium's own ∂δ/∂h (per m).
    pub dn_dh: f64,
    /// dT/dh (K/m); not written (the warnings use it).
    #[serde(skip)]
    pub dt_dh: f64,
}

/// Implied air that no weather makes, over a run of rows.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Warning {
    /// `too_cold`, `too_hot` or `too_steep`.
    pub kind: &'static str,
    /// The lowest height of the run (m).
    pub h: f64,
    /// The highest height of the run (m).
    pub to_h: f64,
    /// In words, naming the heights and the extreme value.
    pub message: String,
}

/// A medium's profile at one position (what `mirage air -o` writes).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AirProfile {
    /// `air`, `logistic` or `linear_square`.
    pub medium_kind: &'static str,
    /// The horizontal position `[x, z]` (m).
    pub at: [f64; 2],
    /// Whether T is the implied air's (any kind but real air).
    pub implied: bool,
    /// The top of the profile (m).
    pub top: f64,
    /// Rows from the ground to the top, heights increasing.
    pub rows: Vec<ProfileRow>,
    /// Implausible implied air.
    pub warnings: Vec<Warning>,
}

/// The implied air of a fitted non-air medium, in brief (the fit report's
/// `implied_air`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ImpliedAirSummary {
    /// Where it was taken (m): the first hot spot's centre, or 0, 0.
    pub at: [f64; 2],
    /// The top the implied air is pinned to the standard at (m).
    pub top: f64,
    /// T − T_std at the ground (K).
    pub ground_excess_k: f64,
    /// The warmest implied T (°C) and its height.
    pub warmest_c: [f64; 2],
    /// The coldest implied T (°C) and its height.
    pub coldest_c: [f64; 2],
    /// As in [`AirProfile::warnings`].
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<Warning>,
}

/// The US 1976 standard atmosphere as Gladstone–Dale air: 15 °C at the
/// ground, the standard layers, hydrostatic from 101 325 Pa, dry, with K
/// chosen so that δ at the ground is Ciddor's at 550 nm.
pub fn standard_atmosphere() -> AirMedium {
    let ground = AirState {
        celsius: T0 - KELVIN,
        pressure: P0,
        humidity: 0.0,
        wavelength_nm: 550.0,
        co2_ppm: crate::medium::air::DEFAULT_CO2,
    };
    let k = refractivity(Formula::Ciddor, &ground) * T0;
    AirMedium {
        air: Air {
            temperature: Temperature {
                base: Some(T0 - KELVIN),
                lapse: Some(Lapse::Standard),
                exponential: None,
                inversion: None,
                table: None,
            },
            pressure: P0,
            hydrostatic: true,
            humidity: Humidity::Constant(0.0),
            wavelength: 550.0,
            co2: crate::medium::air::DEFAULT_CO2,
            refractivity: Formula::GladstoneDale(k),
        },
        hotspots: Vec::new(),
    }
}

/// Gladstone–Dale inverted: the temperature (K) and its height derivative of
/// air with δ = `delta` (derivative `d_delta`) at pressure `p` (derivative
/// `dp`), T = K·(P/101 325)/δ.
pub fn gladstone_dale_kelvin(
    k: f64,
    (p, dp): (f64, f64),
    (delta, d_delta): (f64, f64),
) -> (f64, f64) {
    let t = k * (p / P0) / delta;
    (t, t * (dp / p - d_delta / delta))
}

/// The first hot spot's centre `[x, z]`, if the medium has hot spots.
pub fn hot_centre(medium: &Medium) -> Option<[f64; 2]> {
    match medium {
        Medium::Logistic(m) => m.hotspots.first().map(|h| [h.x, h.z]),
        Medium::Air(m) => m.hotspots.first().map(|h| [h.x, h.z]),
        Medium::LinearSquare(_) => None,
    }
}

/// The default position: the first hot spot's centre, else 0, 0.
pub fn default_at(medium: &Medium) -> [f64; 2] {
    hot_centre(medium).unwrap_or([0.0, 0.0])
}

/// The thin vertical features of a medium as (centre, reach) in metres: where
/// a feature is centred, and how far from that centre it has mostly played out.
/// Smooth terms (a lapse rate, the pressure) are not features.
fn features(medium: &Medium) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    match medium {
        Medium::Logistic(m) => {
            if let Some(b) = &m.background {
                out.push((0.0, b.a.abs()));
            }
            if let Some(i) = &m.inversion {
                out.push((i.height, i.a.abs()));
            }
            out.extend(m.hotspots.iter().map(|h| (0.0, h.a.abs())));
        }
        Medium::Air(m) => {
            let t = &m.air.temperature;
            if let Some(e) = &t.exponential {
                out.push((0.0, e.scale_height.abs()));
            }
            if let Some(i) = &t.inversion {
                out.push((i.height, i.thickness.abs()));
            }
            if let Some(rows) = &t.table
                && let Some(last) = rows.last()
            {
                out.push((0.0, last[0].max(0.0)));
            }
            out.extend(m.hotspots.iter().map(|h| (0.0, h.scale_height.abs())));
        }
        Medium::LinearSquare(_) => {}
    }
    out.retain(|(c, r)| c.is_finite() && r.is_finite());
    out
}

/// The default top (m): three times the highest reach (centre + reach) of the
/// medium's features, at least 20 m.
pub fn default_top(medium: &Medium) -> f64 {
    features(medium)
        .iter()
        .map(|(c, r)| TOP_REACHES * (c + r))
        .fold(MIN_TOP, f64::max)
}

/// The heights of the rows (see the module documentation).
fn heights(medium: &Medium, top: f64) -> Vec<f64> {
    let mut hs: Vec<f64> = (0..=UNIFORM_ROWS)
        .map(|k| top * k as f64 / UNIFORM_ROWS as f64)
        .collect();
    for (c, r) in features(medium) {
        if r > 0.0 && r < top / 20.0 {
            let (lo, hi) = ((c - 3.0 * r).max(0.0), (c + 3.0 * r).min(top));
            hs.extend((0..=FEATURE_ROWS).map(|k| lo + (hi - lo) * k as f64 / FEATURE_ROWS as f64));
        }
    }
    hs.retain(|h| (0.0..=top).contains(h));
    hs.sort_by(f64::total_cmp);
    hs.dedup_by(|a, b| (*a - *b).abs() <= 1e-12 * top);
    hs
}

/// The profile of `medium` at `at` (default [`default_at`]) from the ground to
/// `top` (default [`default_top`]; callers validate a given top as > 0).
pub fn air_profile(medium: &Medium, at: Option<[f64; 2]>, top: Option<f64>) -> AirProfile {
    let at = at.unwrap_or_else(|| default_at(medium));
    let top = top.unwrap_or_else(|| default_top(medium));
    let field = medium.field();
    let point = |h: f64| V3::new(at[0], h, at[1]);
    let hs = heights(medium, top);
    let (rows, implied): (Vec<ProfileRow>, bool) = match medium {
        Medium::Air(m) => {
            let air = AirField::new(m);
            let rows = hs
                .iter()
                .map(|&h| {
                    let (t, grad) = air.kelvin(point(h));
                    let (d, g) = air.delta_gradient(point(h));
                    ProfileRow {
                        h,
                        temperature_c: t - KELVIN,
                        excess_k: None,
                        pressure_pa: air.pressure(h).0,
                        delta: d,
                        dn_dh: g.y,
                        dt_dh: grad.y,
                    }
                })
                .collect();
            (rows, false)
        }
        _ => {
            let std = standard_atmosphere();
            let Formula::GladstoneDale(k) = std.air.refractivity else {
                unreachable!("the standard atmosphere is Gladstone–Dale air")
            };
            let std = AirField::new(&std);
            let delta_top = field.delta(point(top));
            let rows = hs
                .iter()
                .map(|&h| {
                    let (d, g) = field.delta_gradient(point(h));
                    let (ds, gs) = std.delta_gradient(point(h));
                    let (ts, _) = std.uniform_kelvin(h);
                    let p = std.pressure(h);
                    let air = (ds + (d - delta_top), gs.y + g.y);
                    let (t, dt) = gladstone_dale_kelvin(k, p, air);
                    ProfileRow {
                        h,
                        temperature_c: t - KELVIN,
                        excess_k: Some(t - ts),
                        pressure_pa: p.0,
                        delta: d,
                        dn_dh: g.y,
                        dt_dh: dt,
                    }
                })
                .collect();
            (rows, true)
        }
    };
    let warnings = if implied { warnings(&rows) } else { Vec::new() };
    AirProfile {
        medium_kind: medium.kind_name(),
        at,
        implied,
        top,
        rows,
        warnings,
    }
}

/// The runs of rows whose implied air is implausible, one warning per run and
/// kind. A δ_air ≤ 0 (no air has it) reads as infinitely hot.
fn warnings(rows: &[ProfileRow]) -> Vec<Warning> {
    type Test = fn(&ProfileRow) -> Option<f64>;
    let tests: [(&'static str, Test); 3] = [
        ("too_cold", |r| {
            (-KELVIN..COLDEST_PLAUSIBLE)
                .contains(&r.temperature_c)
                .then_some(r.temperature_c)
        }),
        ("too_hot", |r| {
            (r.temperature_c > HOTTEST_PLAUSIBLE
                || r.temperature_c.is_nan()
                || r.temperature_c < -KELVIN)
                .then_some(r.temperature_c)
        }),
        ("too_steep", |r| {
            (r.dt_dh.abs() > STEEPEST_PLAUSIBLE || r.dt_dh.is_nan()).then_some(r.dt_dh)
        }),
    ];
    let mut out = Vec::new();
    for (kind, test) in tests {
        let mut run: Option<(f64, f64, f64)> = None;
        let mut flush = |run: &mut Option<(f64, f64, f64)>| {
            if let Some((lo, hi, worst)) = run.take() {
                out.push(warning(kind, lo, hi, worst));
            }
        };
        for r in rows {
            match (test(r), run.as_mut()) {
                (Some(v), Some((_, hi, worst))) => {
                    *hi = r.h;
                    if v.abs() > worst.abs() || v.is_nan() {
                        *worst = v;
                    }
                }
                (Some(v), None) => run = Some((r.h, r.h, v)),
                (None, _) => flush(&mut run),
            }
        }
        flush(&mut run);
    }
    out.sort_by(|a, b| a.h.total_cmp(&b.h));
    out
}

fn warning(kind: &'static str, lo: f64, hi: f64, worst: f64) -> Warning {
    let heights = if lo == hi {
        format!("at h = {} m", sig(lo))
    } else {
        format!("from h = {} m to {} m", sig(lo), sig(hi))
    };
    let message = match kind {
        "too_cold" => format!(
            "implied air colder than {COLDEST_PLAUSIBLE} °C {heights} (down to {:.1} °C): no weather makes it",
            worst
        ),
        "too_hot" if worst < -KELVIN => format!(
            "implied n − 1 ≤ 0 {heights}: no air has it (the medium's δ falls more than the air's whole n − 1)"
        ),
        "too_hot" => format!(
            "implied air hotter than +{HOTTEST_PLAUSIBLE} °C {heights} (up to {:.1} °C): no weather makes it",
            worst
        ),
        _ => format!(
            "implied air changes faster than {STEEPEST_PLAUSIBLE} K/m (asphalt in the sun: 50 K over 2 cm) {heights} (|dT/dh| up to {:.0} K/m)",
            worst.abs()
        ),
    };
    Warning {
        kind,
        h: lo,
        to_h: hi,
        message,
    }
}

/// A height for messages: 4 significant digits, no trailing zeros.
fn sig(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let digits = (3 - v.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// The fit report's summary of the implied air, for any kind but real air
/// (`None` for real air, which has its own temperatures).
pub fn implied_air_summary(medium: &Medium) -> Option<ImpliedAirSummary> {
    if matches!(medium, Medium::Air(_)) {
        return None;
    }
    let p = air_profile(medium, None, None);
    let first = p.rows.first()?;
    let pick = |better: fn(f64, f64) -> bool| {
        p.rows
            .iter()
            .fold([first.temperature_c, first.h], |acc, r| {
                if better(r.temperature_c, acc[0]) {
                    [r.temperature_c, r.h]
                } else {
                    acc
                }
            })
    };
    Some(ImpliedAirSummary {
        at: p.at,
        top: p.top,
        ground_excess_k: first.excess_k.unwrap_or(0.0),
        warmest_c: pick(|a, b| a > b),
        coldest_c: pick(|a, b| a < b),
        warnings: p.warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::medium::air::Exponential;

    /// Gladstone–Dale air at constant pressure, a warm surface layer.
    fn gd_air() -> AirMedium {
        let mut m = standard_atmosphere();
        m.air.hydrostatic = false;
        m.air.pressure = 98_000.0;
        m.air.temperature.lapse = Some(Lapse::Rate(-0.0065));
        m.air.temperature.base = Some(25.0);
        m.air.temperature.exponential = Some(Exponential {
            delta: 12.0,
            scale_height: 0.3,
        });
        m
    }

    #[test]
    fn gladstone_dale_inversion_gives_back_the_airs_own_temperature() {
        let m = gd_air();
        let Formula::GladstoneDale(k) = m.air.refractivity else {
            unreachable!()
        };
        let f = AirField::new(&m);
        for k_h in 0..=200 {
            let h = 5.0 * k_h as f64 / 200.0;
            let p = V3::new(3.0, h, -2.0);
            let (delta, g) = f.delta_gradient(p);
            let (t, dt) = gladstone_dale_kelvin(k, f.pressure(h), (delta, g.y));
            let (t_own, grad) = f.kelvin(p);
            assert!((t - t_own).abs() < 1e-6, "h {h}: {t} vs {t_own}");
            assert!((dt - grad.y).abs() < 1e-6 * (1.0 + grad.y.abs()), "h {h}");
        }
    }

    #[test]
    fn a_constant_delta_implies_the_standard_atmosphere() {
        let m = Medium::LinearSquare(crate::medium::analytic::LinearSquare { n0: 1.0003, g: 0.0 });
        let p = air_profile(&m, None, Some(100.0));
        assert!(p.implied && p.warnings.is_empty());
        for r in &p.rows {
            assert!(r.excess_k.unwrap().abs() < 1e-9, "{r:?}");
        }
        assert!((p.rows[0].temperature_c - 15.0).abs() < 1e-9);
        assert!((p.rows[0].pressure_pa - P0).abs() < 1e-6);
    }

    #[test]
    fn default_top_is_three_reaches_at_least_twenty_metres() {
        let mut m = gd_air();
        assert_eq!(default_top(&Medium::Air(m.clone())), MIN_TOP);
        m.air.temperature.inversion = Some(crate::medium::air::Step {
            delta: 3.0,
            height: 30.0,
            thickness: 2.0,
        });
        assert_eq!(default_top(&Medium::Air(m)), 96.0);
    }

    #[test]
    fn warnings_name_the_heights_of_each_run() {
        let row = |h: f64, t: f64, dt: f64| ProfileRow {
            h,
            temperature_c: t,
            excess_k: Some(0.0),
            pressure_pa: P0,
            delta: 0.0,
            dn_dh: 0.0,
            dt_dh: dt,
        };
        let rows = [
            row(0.0, 120.0, 3000.0),
            row(0.01, 95.0, 10.0),
            row(0.02, 20.0, 0.0),
            row(5.0, -70.0, 0.0),
        ];
        let w = warnings(&rows);
        assert_eq!(w.len(), 3, "{w:?}");
        assert_eq!((w[0].kind, w[0].h), ("too_hot", 0.0));
        assert!(
            w[0].message.contains("from h = 0 m to 0.01 m"),
            "{}",
            w[0].message
        );
        assert!(w.iter().any(|w| w.kind == "too_steep" && w.to_h == 0.0));
        assert!(
            w.iter()
                .any(|w| w.kind == "too_cold" && w.message.contains("h = 5 m"))
        );
    }
}
