//! Rays against exact answers: straight lines, the n²-linear parabola, Snell's
//! invariant, and the integrators' convergence orders.

use mirage::math::V3;
use mirage::medium::analytic::{LinearSquare, Vacuum};
use mirage::medium::{Background, IndexField, Inversion, LogisticMedium};
use mirage::trace::{End, Method, RayState, TargetPlane, TraceOptions, trace};

fn plane_at_z(z: f64) -> TargetPlane {
    TargetPlane {
        point: V3::new(0.0, 0.0, z),
        normal: V3::new(0.0, 0.0, 1.0),
    }
}

fn methods() -> Vec<Method> {
    vec![
        Method::Rk4 { step: 7.3 },
        Method::Rk4 { step: 0.5 },
        Method::Dopri5 { tolerance: 1e-6 },
        Method::Dopri5 { tolerance: 1e-12 },
    ]
}

#[test]
fn vacuum_rays_are_straight_and_hit_the_plane_where_the_line_does() {
    let origin = V3::new(3.0, 1.6, -2.0);
    let dir = V3::new(0.3, -0.01, 1.0).normalized();
    let target = TargetPlane {
        point: V3::new(100.0, 5.0, 900.0),
        normal: V3::new(0.1, 0.0, 1.0).normalized(),
    };
    // Straight line: o + t d meets the plane at t = n·(p − o) / n·d.
    let t = (target.point - origin).dot(target.normal) / dir.dot(target.normal);
    let exact = origin + dir * t;
    let no_terms = LogisticMedium::vacuum().field();
    for method in methods() {
        let opts = TraceOptions::new(method);
        let mut path = Vec::new();
        let a = trace::<f64, _>(&Vacuum, origin, dir, Some(&target), &opts, Some(&mut path));
        let b = trace::<f64, _>(&no_terms, origin, dir, Some(&target), &opts, None);
        for r in [&a, &b] {
            assert_eq!(r.end, End::Plane);
            assert!(
                (r.endpoint - exact).norm() < 1e-9,
                "{method:?}: {:?} vs {exact:?}",
                r.endpoint
            );
            assert!((r.direction - dir).norm() < 1e-14);
        }
        // Every recorded point lies on the line.
        for p in &path {
            let off = p.x - origin;
            let along = off.dot(dir);
            assert!((off - dir * along).norm() < 1e-9);
        }
    }
}

#[test]
fn n_squared_linear_gives_the_exact_parabola() {
    // n² = n0² + g·y: the path in τ is o + v0 τ + ¼ g ŷ τ².
    let medium = LinearSquare {
        n0: 1.0003,
        g: -2e-5,
    };
    let origin = V3::new(0.0, 2.0, 0.0);
    let dir = V3::new(0.0, 0.004, 1.0).normalized();
    let target = plane_at_z(1000.0);
    for method in methods() {
        let opts = TraceOptions::new(method);
        let mut path: Vec<RayState> = Vec::new();
        let r = trace::<f64, _>(&medium, origin, dir, Some(&target), &opts, Some(&mut path));
        // Each step end must match the parabola at the same τ; τ is recovered from
        // the horizontal coordinate, which is linear in τ.
        let v0z = dir.z * 1.0003f64.mul_add(1.0003, -2e-5 * 2.0).sqrt();
        for p in &path {
            let exact = medium.exact_position(origin, dir, p.x.z / v0z);
            assert!(
                (p.x - exact).norm() < 1e-10,
                "{method:?}: off by {}",
                (p.x - exact).norm()
            );
        }
        let exact_end = medium.exact_position(origin, dir, 1000.0 / v0z);
        let err = (r.endpoint - exact_end).norm();
        assert!(
            err < 1e-10,
            "{method:?}: endpoint off the parabola by {err} m"
        );
    }
}

fn stratified() -> LogisticMedium {
    LogisticMedium {
        scale: 1.0,
        background: Some(Background { n: 1.0, a: 40.0 }),
        inversion: Some(Inversion {
            n: -0.6,
            a: 2.0,
            height: 25.0,
        }),
        hotspots: vec![],
    }
}

#[test]
fn snell_invariant_is_conserved_and_the_ray_stays_in_its_launch_plane() {
    let field = stratified().field();
    assert!(field.is_stratified());
    let origin = V3::new(5.0, 1.6, 0.0);
    let dir = V3::new(0.35, 0.02, 1.0).normalized();
    let target = TargetPlane {
        point: V3::new(700.0, 0.0, 2000.0),
        normal: V3::new(0.35, 0.0, 1.0).normalized(),
    };
    let opts = TraceOptions::new(Method::Dopri5 { tolerance: 1e-13 });
    let mut path = Vec::new();
    let r = trace::<f64, _>(&field, origin, dir, Some(&target), &opts, Some(&mut path));
    assert_eq!(r.end, End::Plane);
    assert!(r.endpoint.y > 30.0, "the ray crossed the inversion layer");
    let invariant = |p: &RayState| {
        let n = 1.0 + field.delta(p.x);
        let t = p.v.normalized();
        (n * t.x, n * t.z)
    };
    let (ix, iz) = invariant(&path[0]);
    // The launch plane contains the origin and the horizontal direction (dx, dz).
    let side = V3::new(dir.z, 0.0, -dir.x).normalized();
    let mut worst = 0.0f64;
    for p in &path {
        let (jx, jz) = invariant(p);
        worst = worst
            .max(((jx - ix) / ix).abs())
            .max(((jz - iz) / iz).abs());
        assert!(
            (p.x - origin).dot(side).abs() < 1e-9,
            "left the launch plane"
        );
    }
    assert!(
        worst < 1e-12,
        "Snell's invariant drifted by {worst:e} (relative)"
    );
}

/// A ray that climbs through the inversion layer: its curvature changes over a
/// few metres, which makes integration error measurable.
fn climbing_ray() -> (LogisticMedium, V3, V3, TargetPlane) {
    let m = stratified();
    let origin = V3::new(0.0, 1.6, 0.0);
    let dir = V3::new(0.0, (2.0f64).to_radians().tan(), 1.0).normalized();
    (m, origin, dir, plane_at_z(1200.0))
}

fn endpoint(method: Method) -> (V3, u64) {
    let (m, o, d, t) = climbing_ray();
    let r = trace::<f64, _>(&m.field(), o, d, Some(&t), &TraceOptions::new(method), None);
    assert_eq!(r.end, End::Plane);
    (r.endpoint, r.stats.rhs_evaluations)
}

#[test]
fn rk4_endpoint_error_converges_with_order_four() {
    let (reference, _) = endpoint(Method::Dopri5 { tolerance: 1e-14 });
    let steps = [16.0, 8.0, 4.0, 2.0, 1.0];
    let errors: Vec<f64> = steps
        .iter()
        .map(|&h| (endpoint(Method::Rk4 { step: h }).0 - reference).norm())
        .collect();
    // Least-squares slope of log(error) against log(step).
    let slope = slope(
        &steps.map(f64::ln),
        &errors.iter().map(|e| e.ln()).collect::<Vec<_>>(),
    );
    eprintln!("steps {steps:?}\nerrors {errors:?}\nslope {slope}");
    assert!(
        errors[errors.len() - 1] > 1e-13,
        "errors must stay above the reference's own error"
    );
    assert!(
        (3.8..=4.2).contains(&slope),
        "RK4 order {slope} (errors {errors:?})"
    );
}

fn slope(xs: &[f64], ys: &[f64]) -> f64 {
    let n = xs.len() as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    xs.iter()
        .zip(ys)
        .map(|(x, y)| (x - mx) * (y - my))
        .sum::<f64>()
        / xs.iter().map(|x| (x - mx).powi(2)).sum::<f64>()
}

#[test]
fn adaptive_error_follows_its_tolerance() {
    // Reference: Dormand–Prince at 1e-14, cross-checked against fine RK4 (whose
    // own floor is rounding, a few 1e-11 m after 3000 steps).
    let (reference, _) = endpoint(Method::Dopri5 { tolerance: 1e-14 });
    let (rk4_fine, _) = endpoint(Method::Rk4 { step: 0.4 });
    assert!((reference - rk4_fine).norm() < 1e-10);
    let tolerances = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10];
    let mut errors = Vec::new();
    let mut last_evals = 0;
    for &tol in &tolerances {
        let (e, evals) = endpoint(Method::Dopri5 { tolerance: tol });
        let err = (e - reference).norm();
        eprintln!("tol {tol:e}: error {err:e} m, {evals} evaluations");
        assert!(err <= 10.0 * tol, "tolerance {tol:e}: error {err:e}");
        assert!(
            evals > last_evals,
            "a tighter tolerance must cost more evaluations"
        );
        last_evals = evals;
        errors.push(err);
    }
    let k = slope(
        &tolerances.map(f64::ln),
        &errors.iter().map(|e| e.ln()).collect::<Vec<_>>(),
    );
    assert!(
        (0.8..=1.4).contains(&k),
        "log-log slope of error vs tolerance {k}"
    );
}

#[test]
fn ground_stop_mode_ends_on_the_ground_where_the_line_meets_it() {
    use mirage::trace::GroundMode;
    let origin = V3::new(1.0, 1.6, 0.0);
    let dir = V3::new(0.05, -0.01, 1.0).normalized();
    // Straight line: y = 1.6 + t·d.y = 0.
    let t = -1.6 / dir.y;
    let exact = origin + dir * t;
    for method in methods() {
        let mut opts = TraceOptions::new(method);
        opts.ground = GroundMode::Stop;
        opts.max_length = Some(1000.0);
        let r = trace::<f64, _>(&Vacuum, origin, dir, None, &opts, None);
        assert_eq!(r.end, End::Ground, "{method:?}");
        assert!(r.occluded && !r.unreachable);
        assert!(
            (r.endpoint - exact).norm() < 1e-9,
            "{method:?}: {:?} vs {exact:?}",
            r.endpoint
        );
        assert!((r.arc_length - t).abs() < 1e-6);
    }
}

#[test]
fn a_dip_below_the_ground_between_two_steps_is_flagged_occluded() {
    // A parabola (n² linear in y, rising n upward bends rays up) that goes below
    // y = 0 and comes back up inside one long RK4 step: both step ends are above
    // ground, the lowest point is not.
    let medium = LinearSquare { n0: 1.0, g: 4e-5 };
    let origin = V3::new(0.0, 0.5, 0.0);
    let dir = V3::new(0.0, -0.006, 1.0).normalized();
    // y(τ) = 0.5 + v_y τ + g τ²/4 is below zero for τ between about 100 and 500
    // (lowest at τ = −2 v_y / g ≈ 300); a 600 m step jumps over all of it.
    let lowest = 0.5 - dir.y * dir.y / 4e-5;
    assert!(
        lowest < 0.0 && lowest > -0.5,
        "test geometry: lowest point {lowest}"
    );
    let target = plane_at_z(1000.0);
    let big_step = TraceOptions::new(Method::Rk4 { step: 600.0 });
    let mut path = Vec::new();
    let r = trace::<f64, _>(
        &medium,
        origin,
        dir,
        Some(&target),
        &big_step,
        Some(&mut path),
    );
    assert!(
        path.iter().all(|p| p.x.y >= 0.0),
        "no step end below ground: {path:?}"
    );
    assert!(r.occluded, "the dip between steps must be found");
    assert_eq!(r.end, End::Plane);
    // The same ray launched a little higher clears the ground: not occluded.
    let clear = trace::<f64, _>(
        &medium,
        V3::new(0.0, 1.5, 0.0),
        dir,
        Some(&target),
        &big_step,
        None,
    );
    assert!(!clear.occluded);
}

#[test]
fn a_ray_that_never_reaches_its_plane_is_unreachable_and_ends_nearest_to_it() {
    // Aimed away from the plane: nearest traced point is the origin itself.
    let origin = V3::new(0.0, 2.0, 0.0);
    let dir = V3::new(0.0, 0.0, -1.0);
    let target = plane_at_z(100.0);
    for method in methods() {
        let r = trace::<f64, _>(
            &Vacuum,
            origin,
            dir,
            Some(&target),
            &TraceOptions::new(method),
            None,
        );
        assert!(r.unreachable, "{method:?}");
        assert_eq!(r.end, End::MaxLength);
        assert!((r.endpoint - origin).norm() < 1e-12);
        // The arc length reported is the endpoint's (here, the origin's).
        assert_eq!(r.arc_length, 0.0);
        assert!(r.stats.accepted_steps > 0);
    }
}
