//! Real air (`docs/air.md`) through the whole pipeline: the file form, the
//! analytic gradient against finite differences (hydrostatic pressure, hot
//! spots, the table), the Wigner lab's water ray and fan against SciPy, exact
//! Jacobians in kelvins, recovery of a road's excess and layer, and the
//! ceiling of a steep lapse.

use mirage::fit::objective::Objective;
use mirage::fit::solve::solve;
use mirage::fit::synthetic::retarget;
use mirage::math::V3;
use mirage::medium::{HotField, IndexField, Medium, Param};
use mirage::pair::PointPair;
use mirage::problem::{SolverSpec, solver_settings};
use mirage::trace::batch::{BatchOptions, trace_batch};
use mirage::trace::{End, Method, TraceOptions, trace};
use std::path::Path;

fn medium(json: &str) -> Medium {
    let m: Medium = serde_json::from_str(json).unwrap_or_else(|e| panic!("{e}: {json}"));
    m.validate().unwrap_or_else(|e| panic!("{e:?}: {json}"));
    m
}

/// The Wigner lab's water case (Am. J. Phys. 91:999, 2023): T_a = 10 °C over
/// water at 13 °C, T = 10.033 + 3.15·e^(−20.1 h), n − 1 = 0.079386 / T_K.
const WIGNER: &str = r#"{"air": {
    "temperature": {"base": 10.033, "exponential": {"delta": 3.15, "scale_height": 0.04975124378109453}},
    "pressure": 101325.0, "hydrostatic": false, "refractivity": {"gladstone_dale": 0.079386}}}"#;

/// Media that exercise every term and formula.
fn media() -> Vec<(&'static str, Medium)> {
    vec![
        ("wigner", medium(WIGNER)),
        (
            "road: ciddor, hydrostatic, lapse, hot spot",
            medium(
                r#"{"air": {"temperature": {"base": 30.0, "lapse": -0.0065,
                    "exponential": {"delta": 4.0, "scale_height": 0.2}},
                    "humidity": 0.4, "wavelength": 589.0},
                  "hotspots": [{"x": 0.0, "z": 160.0, "radius": 80.0, "edge": 0.5, "delta": 20.0, "scale_height": 0.4}]}"#,
            ),
        ),
        (
            "sea: edlen, standard layers, inversion",
            medium(
                r#"{"air": {"temperature": {"base": 8.0, "lapse": "standard",
                    "exponential": {"delta": -6.0, "scale_height": 3.0},
                    "inversion": {"delta": 5.0, "height": 12.0, "thickness": 1.5}},
                    "humidity": 0.9, "refractivity": "edlen", "pressure": 100200.0}}"#,
            ),
        ),
        (
            "table with a cold hot spot",
            medium(
                r#"{"hotspots": [{"x": 50.0, "z": 400.0, "radius": 30.0, "delta": -3.0, "scale_height": 1.0}],
                  "air": {"temperature": {"table": [[0.0, 20.0], [0.5, 17.0], [2.0, 16.5], [10.0, 16.4], [200.0, 15.0]]}}}"#,
            ),
        ),
    ]
}

fn central_difference(field: &impl IndexField, p: V3, h: f64) -> V3 {
    let d = |e: V3| (field.delta(p + e * h) - field.delta(p - e * h)) / (2.0 * h);
    V3::new(
        d(V3::new(1.0, 0.0, 0.0)),
        d(V3::new(0.0, 1.0, 0.0)),
        d(V3::new(0.0, 0.0, 1.0)),
    )
}

#[test]
fn the_gradient_is_the_derivative_of_delta_everywhere() {
    let points = [
        V3::new(0.0, 0.01, 0.0),
        V3::new(3.0, 0.3, 150.0),
        V3::new(75.0, 0.2, 180.0), // hot spot rim
        V3::new(45.0, 0.7, 395.0), // cold spot
        V3::new(0.0, 1.1, 50.0),
        V3::new(0.0, 11.3, 900.0), // inversion flank
        V3::new(0.0, 150.0, 100.0),
        V3::new(0.0, 2500.0, 100.0),
        V3::new(0.0, 12_000.0, 100.0), // above the tropopause
    ];
    for (name, m) in media() {
        let field = m.field();
        for &p in &points {
            let (d, g) = field.delta_gradient(p);
            assert!(
                d.is_finite() && d > 0.0 && d < 4e-4,
                "{name}: δ = {d} at {p:?}"
            );
            let h = 1e-4 * (1.0 + 0.01 * p.y);
            let fd = central_difference(&field, p, h);
            // Relative to |∇δ|, plus the rounding of the difference quotient
            // (δ carries ~1e-16 relative error, divided by 2h).
            let noise = 8.0 * f64::EPSILON * d / h;
            let err = (g - fd).norm() / (g.norm() + noise / 2e-5);
            assert!(
                err < 2e-5,
                "{name} at {p:?}: analytic {g:?} vs finite differences {fd:?} ({err:.1e})"
            );
        }
    }
}

#[test]
fn hydrostatic_pressure_gives_the_barometric_fall_of_delta() {
    // Isothermal air: P = P₀·e^(−gMh/(RT)) exactly, and Gladstone–Dale makes
    // δ proportional to P.
    let m = medium(
        r#"{"air": {"temperature": {"base": 0.0}, "refractivity": {"gladstone_dale": 0.0787}}}"#,
    );
    let f = m.field();
    let d0 = f.delta(V3::new(0.0, 0.0, 0.0));
    let t: f64 = 273.15;
    for h in [1.0f64, 100.0, 2000.0, 8000.0] {
        let expect = d0 * (-9.80665 * 0.0289644 * h / (8.314462618 * t)).exp();
        let got = f.delta(V3::new(0.0, h, 0.0));
        assert!(
            ((got - expect) / expect).abs() < 1e-10,
            "h = {h}: {got} vs {expect}"
        );
    }
}

fn wigner_pair(angle_deg: f64, y_target: f64) -> PointPair {
    let drop = 3000.0 * angle_deg.to_radians().tan();
    PointPair {
        origin: [0.0, 1.1, 0.0],
        through: [0.0, 1.1 + drop, 3000.0],
        target: [0.0, y_target, 3000.0],
        weight: 1.0,
        wavelength: None,
    }
}

#[test]
fn the_wigner_water_ray_lands_where_scipy_and_gsl_say() {
    // The issue's value (SciPy DOP853 at 1e-13 and GSL rk8pd), to 1e-6 m; our
    // own SciPy reference (benches/peers/wigner/reference.py) gives
    // 5.078677225410544, 3e-10 above it.
    let field = medium(WIGNER).field();
    let pair = wigner_pair(-0.12, 5.0);
    for (tol, within) in [(1e-12, 1e-9), (1e-9, 1e-6f64)] {
        let (t, _) = pair.evaluate::<f64, _>(
            &field,
            &TraceOptions::new(Method::Dopri5 { tolerance: tol }),
            None,
        );
        assert_eq!(t.end, End::Plane);
        let y = t.endpoint.y;
        assert!(
            (y - 5.0786772251).abs() < within.max(1e-9),
            "tolerance {tol}: y(3000 m) = {y}"
        );
        assert!(
            (y - 5.078677225410544).abs() < within,
            "tolerance {tol}: y(3000 m) = {y}"
        );
    }
}

#[test]
fn the_wigner_fan_is_within_a_tenth_of_a_millimetre_of_scipy() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/peers/wigner/fan_reference.json");
    let reference: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let angles = reference["angles_deg"].as_array().unwrap();
    let ys = reference["y"].as_array().unwrap();
    assert_eq!(angles.len(), 1000);
    let field = medium(WIGNER).field();
    let options = TraceOptions::new(Method::Dopri5 { tolerance: 1e-6 });
    let pairs: Vec<PointPair> = angles
        .iter()
        .zip(ys)
        .map(|(a, y)| wigner_pair(a.as_f64().unwrap(), y.as_f64().unwrap()))
        .collect();
    // The lanes, as `mirage trace` takes them (the stratified adaptive
    // kernel), and the scalar tracer: both within 0.1 mm of SciPy, and the
    // lanes the scalar tracer's steps and endpoints on these well-behaved
    // rays.
    let jobs: Vec<_> = pairs.iter().map(PointPair::ray_job).collect();
    let lanes = trace_batch(&field, &jobs, &BatchOptions::from_trace_options(&options));
    let (mut worst, mut worst_lanes, mut apart): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for (pair, fast) in pairs.iter().zip(&lanes) {
        let (t, _) = pair.evaluate::<f64, _>(&field, &options, None);
        assert_eq!(t.end, End::Plane, "ray at {:?}", pair.through);
        assert_eq!((fast.end, fast.stats), (t.end, t.stats));
        worst = worst.max((t.endpoint - pair.target()).norm());
        worst_lanes = worst_lanes.max((fast.endpoint - pair.target()).norm());
        apart = apart.max((fast.endpoint - t.endpoint).norm());
    }
    eprintln!(
        "worst endpoint error at tolerance 1e-6: {worst:.3e} m (lanes {worst_lanes:.3e} m, {apart:.1e} m from the scalar tracer)"
    );
    assert!(worst < 1e-4, "worst endpoint error {worst} m");
    assert!(
        worst_lanes < 1e-4,
        "worst endpoint error of the lanes {worst_lanes} m"
    );
    assert!(apart < 1e-10, "lanes and scalar tracer {apart} m apart");
}

#[test]
fn snell_invariant_holds_in_stratified_air() {
    let field = medium(
        r#"{"air": {"temperature": {"base": 25.0, "lapse": -0.0065,
            "exponential": {"delta": 12.0, "scale_height": 0.3}}, "humidity": 0.5}}"#,
    )
    .field();
    let o = V3::new(0.0, 1.5, 0.0);
    let d = V3::new(0.3, -0.004, 1.0).normalized();
    let mut path = Vec::new();
    let _ = trace::<f64, _>(
        &field,
        o,
        d,
        None,
        &TraceOptions {
            max_length: Some(800.0),
            ..TraceOptions::new(Method::Dopri5 { tolerance: 1e-10 })
        },
        Some(&mut path),
    );
    assert!(path.len() > 10);
    let (vx0, vz0) = (path[0].v.x, path[0].v.z);
    for s in &path {
        // In the τ form v = n·t, and v_x, v_z are Snell's invariants.
        assert!((s.v.x - vx0).abs() < 1e-12 && (s.v.z - vz0).abs() < 1e-12);
    }
}

#[test]
fn a_ray_into_air_colder_than_the_formulas_stops_at_the_ceiling() {
    // 15 °C with −0.0145 K/m is −144.5 °C at 11 km (valid) and −150 °C at
    // 11.38 km: a ray climbing at 30° must stop there, finite, flagged.
    let m = medium(r#"{"air": {"temperature": {"base": 15.0, "lapse": -0.0145}}}"#);
    let field = m.field();
    let t = trace::<f64, _>(
        &field,
        V3::new(0.0, 2.0, 0.0),
        V3::new(0.0, 0.5, 0.75f64.sqrt()),
        None,
        &TraceOptions {
            max_length: Some(50_000.0),
            ..TraceOptions::new(Method::Dopri5 { tolerance: 1e-9 })
        },
        None,
    );
    assert_eq!(t.end, End::LeftAir);
    assert!(
        t.endpoint.y > 11_000.0 && t.endpoint.y < 11_600.0,
        "{:?}",
        t.endpoint
    );
    assert!(t.endpoint.x.is_finite() && t.endpoint.z.is_finite());
    // And a profile that is not air below 11 km is refused by name.
    let steep: Medium =
        serde_json::from_str(r#"{"air": {"temperature": {"base": 15.0, "lapse": -0.02}}}"#)
            .unwrap();
    let e = steep.validate().unwrap_err();
    assert_eq!(e.path, "air.temperature.lapse", "{e:?}");
}

/// A driver 1.2 m up glancing 0.15–0.4° down at points of cars 250–350 m
/// ahead over a road whose surface air is `delta` K above the air.
fn road(delta: f64, scale_height: f64) -> Medium {
    medium(&format!(
        r#"{{"air": {{"temperature": {{"base": 30.0,
            "exponential": {{"delta": {delta}, "scale_height": {scale_height}}}}},
            "humidity": 0.3}}}}"#
    ))
}

fn road_pairs() -> Vec<PointPair> {
    let mut pairs = Vec::new();
    for (k, z) in [250.0, 270.0, 290.0, 310.0, 330.0, 350.0]
        .into_iter()
        .enumerate()
    {
        let x = [-8.0, 3.0, 12.0][k % 3];
        for down in [0.2f64, 0.3] {
            let y = 1.2 - z * down.to_radians().tan();
            pairs.push(PointPair {
                origin: [0.0, 1.2, 0.0],
                through: [x, y, z],
                target: [x, y, z],
                weight: 1.0,
                wavelength: None,
            });
        }
    }
    pairs
}

#[test]
fn a_fit_in_kelvins_recovers_the_roads_excess_and_layer() {
    let options = TraceOptions::new(Method::Dopri5 { tolerance: 1e-11 });
    let truth = road(18.0, 0.35);
    let (pairs, failed) = retarget(&road_pairs(), &truth.field(), &options);
    assert!(failed.is_empty(), "every glance reaches its car");
    let free = vec![
        "air.temperature.exponential.delta"
            .parse::<Param>()
            .unwrap(),
        "air.temperature.exponential.scale_height".parse().unwrap(),
    ];
    let settings = solver_settings(
        &SolverSpec {
            method: "lm".into(),
            max_iterations: Some(200),
            ..Default::default()
        },
        Path::new("test"),
    )
    .unwrap();
    for factor in [0.5, 2.0] {
        let start = road(18.0 * factor, 0.35 * factor);
        let obj = Objective::new(start, free.clone(), pairs.clone(), options);
        let bounds = vec![(0.5, 80.0), (0.02, 3.0)];
        let sol = solve(&obj, &settings, &bounds, 1e-20, None).unwrap();
        let (d, s) = (sol.x[0], sol.x[1]);
        eprintln!(
            "start ×{factor}: ΔT = {d} K, H = {s} m, F = {:e}",
            sol.objective
        );
        assert!(
            ((d - 18.0) / 18.0).abs() < 1e-4,
            "start ×{factor}: ΔT = {d}"
        );
        assert!(((s - 0.35) / 0.35).abs() < 1e-4, "start ×{factor}: H = {s}");
    }
}

#[test]
fn the_jacobian_in_kelvins_matches_finite_differences() {
    let m = medium(
        r#"{"air": {"temperature": {"base": 28.0, "lapse": -0.0065,
            "exponential": {"delta": 9.0, "scale_height": 0.4},
            "inversion": {"delta": 2.0, "height": 6.0, "thickness": 1.0}},
            "humidity": 0.3, "pressure": 100000.0},
          "hotspots": [{"x": 0.0, "z": 300.0, "radius": 60.0, "edge": 0.5, "delta": 8.0, "scale_height": 0.3}]}"#,
    );
    let free: Vec<Param> = m.params().into_iter().map(|(p, _)| p).collect();
    assert!(free.len() > 8, "more than one dual chunk");
    let pairs: Vec<PointPair> = road_pairs().into_iter().step_by(3).collect();
    let obj = Objective::new(
        m,
        free.clone(),
        pairs,
        TraceOptions::new(Method::Rk4 { step: 2.0 }),
    );
    let x = obj.start();
    let (_, jac) = obj.jacobian(x.as_slice());
    for (k, p) in free.iter().enumerate() {
        // Positions and radii in metres: a millimetre keeps the quotient's
        // rounding (~1e-12 m of 300 m endpoints) far below the column; the
        // rim's curvature over 1/edge = 2 m makes the O(h²) error ~1e-7.
        let h = match p {
            Param::Hot(_, HotField::X | HotField::Z | HotField::Radius) => 1e-3,
            _ => 1e-4 * x[k].abs().max(1.0),
        };
        let (mut xp, mut xm) = (x.clone(), x.clone());
        xp[k] += h;
        xm[k] -= h;
        let fd = (obj.residuals(xp.as_slice()).0 - obj.residuals(xm.as_slice()).0) / (2.0 * h);
        let col = jac.column(k);
        let err = (&fd - col).norm() / col.norm().max(1e-14);
        eprintln!("{p}: |J| = {:.3e}, relative error {err:.1e}", col.norm());
        // CO₂ moves the endpoints by nanometres per ppm: there the difference
        // quotient's rounding (~1e-13 m / h) is 1e-4 of the column.
        let rel = if col.norm() < 1e-6 { 1e-3 } else { 2e-5 };
        assert!(err < rel, "{p}: exact {col:?} vs {fd:?}");
    }
}

#[test]
fn files_decide_the_kind_by_their_keys_and_round_trip() {
    for (name, m) in media() {
        let text = serde_json::to_string(&m).unwrap();
        let back: Medium = serde_json::from_str(&text).unwrap();
        assert_eq!(back, m, "{name}: {text}");
        assert_eq!(back.kind_name(), "air");
    }
    // Hot spots before `air`, and a logistic medium with hot spots first.
    let m = medium(
        r#"{"hotspots": [{"x": 0, "z": 9, "radius": 3, "delta": 2, "scale_height": 0.5}],
            "air": {"temperature": {"base": 10}}}"#,
    );
    assert_eq!(m.kind_name(), "air");
    let m = medium(r#"{"hotspots": [{"x": 0, "z": 9, "radius": 3, "n": -1, "a": -0.5}]}"#);
    assert_eq!(m.kind_name(), "logistic");
}
