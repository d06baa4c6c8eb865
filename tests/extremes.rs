//! The extremes (issue #16, item 4): real air across every range `docs/air.md`
//! admits and beyond it, tables with wild rows, rays from grazing to vertical,
//! the round earth from 1 km to 10⁸ m. A medium is either refused with an error
//! that names a field, or valid, and then its δ and ∇δ are finite below its
//! ceiling and every ray ends at a finite point: never a NaN, never a panic.
//!
//! 10,000 cases a property by default (`PROPTEST_CASES` overrides it); each
//! case traces one short ray, RK4 or Dormand–Prince, capped in steps, so the
//! file stays within about a minute on one core in the test profile.

use mirage::math::V3;
use mirage::medium::{IndexField, Medium};
use mirage::trace::{Earth, EarthSpec, End, Method, TargetPlane, TraceOptions, trace};
use proptest::prelude::*;
use serde_json::{Value, json};

/// Cases per property: `PROPTEST_CASES`, else 10,000.
fn cases() -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(10_000)
}

/// A step cap: a ray that would need more ends at `step_limit`, a valid end.
const MAX_STEPS: u64 = 5_000;

/// ±10^k for k uniform in [lo, hi): magnitudes across decades.
fn decades(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo..hi, any::<bool>()).prop_map(|(k, neg)| if neg { -(10f64.powf(k)) } else { 10f64.powf(k) })
}

/// The medium of `json`, validated: `None` after checking that a refusal names
/// a field and says what is wrong.
fn valid(json: &Value) -> Option<Medium> {
    let m: Medium = match serde_json::from_value(json.clone()) {
        Ok(m) => m,
        // serde's own refusals (a wrong type) are named by the file readers.
        Err(_) => return None,
    };
    match m.validate() {
        Ok(()) => Some(m),
        Err(e) => {
            assert!(!e.path.is_empty() && !e.message.is_empty(), "{e:?}: {json}");
            None
        }
    }
}

/// δ and ∇δ finite at heights from the ground to 20 km (below the ceiling).
fn check_field(m: &Medium, json: &Value) {
    let field = m.field();
    let ceiling = IndexField::<f64>::ceiling(&field);
    for h in [0.0, 1e-4, 0.01, 0.3, 2.0, 15.0, 120.0, 900.0, 5e3, 2e4] {
        if h > ceiling {
            continue;
        }
        let (d, g) = field.delta_gradient(V3::new(7.0, h, 300.0));
        assert!(
            d.is_finite() && g.is_finite(),
            "δ({h}) = {d}, ∇δ = {g:?}: {json}"
        );
    }
}

/// Traces one ray and checks its end: a finite endpoint, direction and length.
fn check_ray(
    m: &Medium,
    origin: V3,
    elevation_deg: f64,
    earth: Earth,
    method: Method,
    json: &Value,
) -> End {
    let e = elevation_deg.to_radians();
    let d = V3::new(0.0, e.sin(), e.cos()).normalized();
    let mut o = TraceOptions::new(method);
    o.max_steps = MAX_STEPS;
    o.earth = earth;
    let distance = 2_000.0;
    o.max_length = Some(2.0 * distance);
    // The plane across the launch direction: reachable at any elevation.
    let plane = TargetPlane {
        point: origin + d * distance,
        normal: d,
    };
    let t = trace::<f64, _>(&m.field(), origin, d, Some(&plane), &o, None);
    assert!(
        t.endpoint.is_finite() && t.direction.is_finite() && t.arc_length.is_finite(),
        "ray at {elevation_deg}° from {origin:?} over {earth:?} with {method:?}: {t:?}\n{json}"
    );
    t.end
}

fn method() -> impl Strategy<Value = Method> {
    prop_oneof![
        (0.5f64..50.0).prop_map(|step| Method::Rk4 { step }),
        (-10.0f64..-4.0).prop_map(|k| Method::Dopri5 {
            tolerance: 10f64.powf(k)
        }),
    ]
}

/// Elevations from grazing (±10⁻⁶ °) to vertical.
fn elevation() -> impl Strategy<Value = f64> {
    prop_oneof![decades(-6.0, -1.0), -5.0f64..90.0, Just(90.0), Just(0.0),]
}

/// A real-air medium over the documented ranges and six decades of lapses and
/// scale heights; the refractivity formula any of the three.
fn real_air() -> impl Strategy<Value = Value> {
    let temperature = (
        -80.0f64..90.0,
        prop_oneof![
            Just(None),
            Just(Some(json!("standard"))),
            decades(-6.0, 0.0).prop_map(|l| Some(json!(l)))
        ],
        proptest::option::of((-60.0f64..60.0, decades(-3.0, 3.0))),
        proptest::option::of((-30.0f64..30.0, 0.0f64..2_000.0, decades(-3.0, 3.0))),
    )
        .prop_map(|(base, lapse, exponential, inversion)| {
            let mut t = json!({ "base": base });
            if let Some(l) = lapse {
                t["lapse"] = l;
            }
            if let Some((delta, s)) = exponential {
                t["exponential"] = json!({ "delta": delta, "scale_height": s.abs() });
            }
            if let Some((delta, height, w)) = inversion {
                t["inversion"] = json!({ "delta": delta, "height": height, "thickness": w.abs() });
            }
            t
        });
    let formula = prop_oneof![
        Just(json!("ciddor")),
        Just(json!("edlen")),
        (50.0f64..100.0).prop_map(|k| json!({ "gladstone_dale": k })),
    ];
    (
        temperature,
        50_000.0f64..110_000.0,
        any::<bool>(),
        0.0f64..=1.0,
        300.0f64..=1700.0,
        formula,
        proptest::option::of((-2.0f64..2.0, decades(-3.0, 3.0), -50.0f64..50.0)),
    )
        .prop_map(
            |(temperature, pressure, hydrostatic, humidity, wavelength, refractivity, spot)| {
                let air = json!({
                    "temperature": temperature, "pressure": pressure, "hydrostatic": hydrostatic,
                    "humidity": humidity, "wavelength": wavelength, "refractivity": refractivity,
                });
                let hotspots: Vec<Value> = spot
                    .into_iter()
                    .map(|(edge, s, delta)| {
                        json!({"x": 0.0, "z": 500.0, "radius": 100.0, "edge": edge.abs() + 0.01,
                               "delta": delta, "scale_height": s.abs()})
                    })
                    .collect();
                json!({ "air": air, "hotspots": hotspots })
            },
        )
}

/// A table of 2–8 rows: heights anywhere from −10 m to 10⁵ m, in any order,
/// temperatures from −273 °C to +1000 °C.
fn wild_table() -> impl Strategy<Value = Value> {
    (
        proptest::collection::vec((decades(-3.0, 5.0), -273.0f64..1000.0), 2..8),
        any::<bool>(),
        50_000.0f64..110_000.0,
    )
        .prop_map(|(mut rows, sorted, pressure)| {
            if sorted {
                rows.sort_by(|a, b| a.0.total_cmp(&b.0));
            }
            let table: Vec<Value> = rows.iter().map(|(h, t)| json!([h, t])).collect();
            json!({ "air": { "temperature": { "table": table }, "pressure": pressure } })
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: cases(), failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn real_air_across_its_range_is_finite(
        m in real_air(),
        elevation in elevation(),
        height in prop_oneof![Just(0.0), decades(-3.0, 3.0).prop_map(f64::abs)],
        method in method(),
    ) {
        if let Some(medium) = valid(&m) {
            check_field(&medium, &m);
            check_ray(&medium, V3::new(0.0, height, 0.0), elevation, Earth::Flat, method, &m);
        }
    }

    #[test]
    fn real_air_tables_with_wild_rows_are_refused_or_finite(
        m in wild_table(),
        elevation in elevation(),
        method in method(),
    ) {
        if let Some(medium) = valid(&m) {
            check_field(&medium, &m);
            check_ray(&medium, V3::new(0.0, 1.5, 0.0), elevation, Earth::Flat, method, &m);
        }
    }

    #[test]
    fn the_round_earth_from_1_km_to_1e8_m_is_finite(
        k in 3.0f64..=8.0,
        m in prop_oneof![
            real_air(),
            Just(json!({"air": {"temperature": {"base": 15.0, "lapse": "standard"}}})),
            Just(json!({"scale": 0.02, "background": {"n": 1.0, "a": 150.0}})),
        ],
        elevation in elevation(),
        height in prop_oneof![Just(0.0), decades(-3.0, 3.5).prop_map(f64::abs)],
        method in method(),
    ) {
        let radius = 10f64.powf(k);
        EarthSpec { radius }.validate().unwrap();
        if let Some(medium) = valid(&m) {
            let earth = Earth::Round { radius };
            check_ray(&medium, V3::new(0.0, height, 0.0), elevation, earth, method, &m);
        }
    }
}

/// Below a kilometre the round earth is refused, naming `radius`.
#[test]
fn a_round_earth_below_a_kilometre_is_refused_by_name() {
    for radius in [999.0, 1.0, 0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = EarthSpec { radius }.validate().unwrap_err();
        assert_eq!(e.path, "radius");
    }
    EarthSpec { radius: 1e3 }.validate().unwrap();
    EarthSpec { radius: 1e8 }.validate().unwrap();
}
