//! The Maine surveyor (`problems/maine-surveyor.json`, issue #40): two
//! sightings written as the surveyor gave them (degrees, minutes and
//! seconds; metres; places by latitude and longitude), fitted with angle
//! residuals for the lapse.
//!
//! - k of the fitted air along each line is 0.20 ± 0.01 (Bislin's analysis:
//!   k ≈ 0.20);
//! - the refraction the fitted air gives each sighting, as `mirage fit`
//!   reports it, is within 1″ of an independent check: the ray through the
//!   fitted air's n(h) integrated in polar coordinates over the sphere
//!   (u = 1/r as a function of the angle θ, u'' = −u − n·n'(r)/(C²u²), C the
//!   Bouguer invariant n·r·cos e) and shot at the target by the secant
//!   method — another equation, another integrator, no code of the tracer;
//! - the same problem written in the local frame (today's form: points in
//!   metres, `through` points, the sphere's radius given) fits to the same
//!   lapse to 1e-9 relative.

use mirage::math::V3;
use mirage::medium::IndexField;
use mirage::problem::Problem;
use mirage::trace::Earth;
use std::path::Path;

fn load() -> Problem {
    Problem::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/maine-surveyor.json"))
        .unwrap()
}

/// The elevation (radians) at which a ray from height `h0` meets the target
/// at arc `s` and height `h1`, through n(h) = 1 + δ(h), over the sphere of
/// radius `r`.
fn shoot(delta: &dyn Fn(f64) -> f64, r: f64, h0: f64, s: f64, h1: f64, guess: f64) -> f64 {
    let n = |h: f64| 1.0 + delta(h);
    let dn = |h: f64| (delta(h + 0.01) - delta(h - 0.01)) / 0.02;
    let land = |e: f64| {
        let r0 = r + h0;
        let c = n(h0) * r0 * e.cos();
        let steps = 20_000;
        let dt = s / r / steps as f64;
        // y = (u, u').
        let f = |y: [f64; 2]| {
            let rr = 1.0 / y[0];
            let h = rr - r;
            [y[1], -y[0] - n(h) * dn(h) / (c * c * y[0] * y[0])]
        };
        let mut y = [1.0 / r0, -e.tan() / r0];
        for _ in 0..steps {
            let k1 = f(y);
            let k2 = f([y[0] + 0.5 * dt * k1[0], y[1] + 0.5 * dt * k1[1]]);
            let k3 = f([y[0] + 0.5 * dt * k2[0], y[1] + 0.5 * dt * k2[1]]);
            let k4 = f([y[0] + dt * k3[0], y[1] + dt * k3[1]]);
            for k in 0..2 {
                y[k] += dt / 6.0 * (k1[k] + 2.0 * k2[k] + 2.0 * k3[k] + k4[k]);
            }
        }
        1.0 / y[0] - r - h1
    };
    let (mut a, mut b) = (guess, guess + 1e-5);
    let (mut fa, mut fb) = (land(a), land(b));
    for _ in 0..30 {
        if fb == fa {
            break;
        }
        let c = b - fb * (b - a) / (fb - fa);
        (a, fa) = (b, fb);
        b = c;
        fb = land(b);
        if fb.abs() < 1e-7 {
            break;
        }
    }
    b
}

#[test]
fn the_surveyor_s_k_and_refraction_come_out() {
    let problem = load();
    let report = mirage::fit::fit(&problem, None).unwrap();
    let lapse = report.parameters[0].value;
    let Earth::Round { radius } = problem.trace.earth else {
        panic!("a site makes the earth round");
    };
    let field = report.medium.field();
    let delta = |h: f64| IndexField::<f64>::delta(&field, V3::new(0.0, h, 0.0));
    let heights = [24.38, 56.08];
    for (i, p) in report.pairs.iter().enumerate() {
        let l = p.sightline.expect("a round-earth line of sight");
        let k = l.air_k.unwrap();
        assert!((k - 0.20).abs() <= 0.01, "pair {i}: k = {k}");
        let e = shoot(
            &delta,
            radius,
            23.42,
            l.arc_distance,
            heights[i],
            l.apparent_elevation.to_radians(),
        );
        let independent = (e.to_degrees() - l.geometric_elevation) * 3600.0;
        let reported = l.air_refraction_arcsec.unwrap();
        eprintln!(
            "pair {i}: lapse {lapse:.6} K/m, k {k:.4} (sighting {:.4}), refraction {reported:.3}″ reported, {independent:.3}″ by the polar integration",
            l.k
        );
        assert!(
            (reported - independent).abs() < 1.0,
            "pair {i}: {reported}″ vs {independent}″"
        );
    }
}

#[test]
fn the_local_form_fits_the_same_lapse() {
    let geo = load();
    let Earth::Round { radius } = geo.trace.earth else {
        panic!("round");
    };
    // The same file in today's form: points in metres, `through` points,
    // the radius given; the angle residuals kept.
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/maine-surveyor.json"),
    )
    .unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v.as_object_mut().unwrap().remove("site");
    v["earth"] = serde_json::json!({ "radius": radius });
    let pairs: Vec<serde_json::Value> = geo
        .pairs
        .iter()
        .map(|p| serde_json::json!({"origin": p.origin, "through": p.through, "target": p.target}))
        .collect();
    v["pairs"] = serde_json::Value::Array(pairs);
    let local = Problem::parse(&v.to_string(), Path::new("local.json")).unwrap();
    let a = mirage::fit::fit(&geo, None).unwrap().parameters[0].value;
    let b = mirage::fit::fit(&local, None).unwrap().parameters[0].value;
    assert!(((a - b) / a).abs() <= 1e-9, "{a} vs {b}");
}
