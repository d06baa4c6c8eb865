//! Arbitrary media and rays (`arbitrary`): a logistic or real-air medium built
//! from fuzzed numbers (most across many decades, some any f64 at all), written
//! as JSON and read back as a file would be, then validated; a valid one is
//! traced along fuzzed rays (grazing to vertical, RK4 or Dormand–Prince, flat
//! or round earth of any radius the validator allows). No panic, no NaN or inf
//! in any output, and every refusal names a field.
#![no_main]

#[path = "common.rs"]
mod common;

use arbitrary::{Arbitrary, Unstructured};
use libfuzzer_sys::fuzz_target;
use mirage::io::json::parse_json;
use mirage::math::V3;
use mirage::medium::Medium;
use mirage::trace::{Earth, EarthSpec, Method};
use serde_json::{Value, json};
use std::path::Path;

/// A number: mostly ±m·10^k with k in −6 … 8 (the decades the physics lives
/// in), sometimes any f64 (NaN and ±∞ become JSON `null`, which is refused).
#[derive(Debug, Clone, Copy)]
struct Num(f64);

impl<'a> Arbitrary<'a> for Num {
    fn arbitrary(u: &mut Unstructured<'a>) -> arbitrary::Result<Self> {
        Ok(Num(match u.int_in_range(0u8..=7)? {
            0 => f64::arbitrary(u)?,
            1 => 0.0,
            _ => {
                let m = f64::from(u16::arbitrary(u)?) / 32767.5 - 1.0;
                m * 10f64.powi(u.int_in_range(-6i32..=8)?)
            }
        }))
    }
}

impl Num {
    fn v(self) -> Value {
        json!(self.0)
    }
}

#[derive(Arbitrary, Debug)]
enum MediumCase {
    Logistic {
        scale: Num,
        background: Option<(Num, Num)>,
        inversion: Option<(Num, Num, Num)>,
        hotspots: Vec<[Num; 6]>,
    },
    Air {
        base: Option<Num>,
        lapse: Option<Option<Num>>,
        exponential: Option<(Num, Num)>,
        inversion: Option<(Num, Num, Num)>,
        table: Option<Vec<(Num, Num)>>,
        pressure: Option<Num>,
        hydrostatic: bool,
        humidity: Option<Num>,
        wavelength: Option<Num>,
        formula: Option<Option<Num>>,
        edlen: bool,
        hotspots: Vec<[Num; 6]>,
    },
}

#[derive(Arbitrary, Debug)]
struct Ray {
    x: Num,
    height: Num,
    /// Elevation as a fraction of ±90°.
    elevation: i16,
    azimuth: u8,
    distance: Num,
}

#[derive(Arbitrary, Debug)]
struct Case {
    medium: MediumCase,
    rays: Vec<Ray>,
    adaptive: bool,
    /// 10^(−k) tolerance or 10^(k−3) m step.
    accuracy: u8,
    earth: Option<Num>,
}

fn medium_json(m: &MediumCase) -> Value {
    match m {
        MediumCase::Logistic {
            scale,
            background,
            inversion,
            hotspots,
        } => {
            let mut v = json!({ "scale": scale.v() });
            if let Some((n, a)) = background {
                v["background"] = json!({ "n": n.v(), "a": a.v() });
            }
            if let Some((n, a, h)) = inversion {
                v["inversion"] = json!({ "n": n.v(), "a": a.v(), "height": h.v() });
            }
            v["hotspots"] = hotspots
                .iter()
                .take(4)
                .map(|[x, z, r, n, a, e]| {
                    json!({"x": x.v(), "z": z.v(), "radius": r.v(), "n": n.v(), "a": a.v(), "edge": e.v()})
                })
                .collect();
            v
        }
        MediumCase::Air {
            base,
            lapse,
            exponential,
            inversion,
            table,
            pressure,
            hydrostatic,
            humidity,
            wavelength,
            formula,
            edlen,
            hotspots,
        } => {
            let mut t = json!({});
            if let Some(b) = base {
                t["base"] = b.v();
            }
            match lapse {
                Some(Some(l)) => t["lapse"] = l.v(),
                Some(None) => t["lapse"] = json!("standard"),
                None => {}
            }
            if let Some((d, s)) = exponential {
                t["exponential"] = json!({ "delta": d.v(), "scale_height": s.v() });
            }
            if let Some((d, h, w)) = inversion {
                t["inversion"] = json!({ "delta": d.v(), "height": h.v(), "thickness": w.v() });
            }
            if let Some(rows) = table {
                t["table"] = rows
                    .iter()
                    .take(12)
                    .map(|(h, c)| json!([h.v(), c.v()]))
                    .collect();
            }
            let mut air = json!({ "temperature": t, "hydrostatic": hydrostatic });
            for (k, n) in [
                ("pressure", pressure),
                ("humidity", humidity),
                ("wavelength", wavelength),
            ] {
                if let Some(n) = n {
                    air[k] = n.v();
                }
            }
            match formula {
                Some(Some(k)) => air["refractivity"] = json!({ "gladstone_dale": k.v() }),
                Some(None) => air["refractivity"] = json!(if *edlen { "edlen" } else { "ciddor" }),
                None => {}
            }
            let spots: Vec<Value> = hotspots
                .iter()
                .take(4)
                .map(|[x, z, r, e, d, s]| {
                    json!({"x": x.v(), "z": z.v(), "radius": r.v(), "edge": e.v(), "delta": d.v(), "scale_height": s.v()})
                })
                .collect();
            json!({ "air": air, "hotspots": spots })
        }
    }
}

fuzz_target!(|case: Case| {
    let path = Path::new("structured.json");
    let text = medium_json(&case.medium).to_string();
    let m: Medium = match parse_json(&text, path, "medium") {
        Ok(m) => m,
        Err(e) => return common::check_error(&e),
    };
    if let Err(e) = m.validate() {
        return common::check_error(&e.in_file(path));
    }
    let earth = match case.earth {
        None => Earth::Flat,
        Some(r) => {
            let spec = EarthSpec { radius: r.0.abs() };
            match spec.validate() {
                Ok(()) => Earth::Round {
                    radius: spec.radius,
                },
                Err(e) => return common::check_error(&e.in_file(path)),
            }
        }
    };
    let method = if case.adaptive {
        Method::Dopri5 {
            tolerance: 10f64.powi(-i32::from(3 + case.accuracy % 10)),
        }
    } else {
        Method::Rk4 {
            step: 10f64.powi(i32::from(case.accuracy % 6) - 2),
        }
    };
    let field = m.field();
    for ray in case.rays.iter().take(3) {
        let origin = V3::new(ray.x.0.clamp(-1e5, 1e5), ray.height.0.abs().min(1e5), 0.0);
        if !origin.is_finite() {
            continue;
        }
        let e = (f64::from(ray.elevation) / f64::from(i16::MAX)) * std::f64::consts::FRAC_PI_2;
        let az = f64::from(ray.azimuth) / 255.0 - 0.5;
        let d = V3::new(e.cos() * az.sin(), e.sin(), e.cos() * az.cos()).normalized();
        // Rk4 at a 1 cm step over 10 km would be a million steps: the cap ends it.
        let distance = ray.distance.0.abs().clamp(1.0, 1e5);
        if !distance.is_finite() {
            continue;
        }
        common::check_ray(&field, origin, d, earth, distance, method, &m);
    }
});
