//! A second medium kind runs through every consumer: the analytic n²-linear
//! medium (`Medium::LinearSquare`, n² = n0² + g·y, whose rays are the exact
//! parabolas `x(τ) = o + v0·τ + ¼·(0, g, 0)·τ²`, v0 = n(o)·d) is traced, fitted
//! and rendered through the same `Medium`/`Field` as the logistic model, and
//! every answer is checked against the parabola.
//!
//! RK4 and Dormand–Prince are exact on this medium: dx/dτ = v and dv/dτ =
//! (0, g/2, 0) is constant, so x is a quadratic in τ, which both integrators
//! and the quintic Hermite interpolant of the crossing step reproduce up to
//! rounding. That is why endpoints must match to ~1e-9 m over a kilometre.

use mirage::evaluate::trace_pairs;
use mirage::fit::objective::Objective;
use mirage::fit::solve::solve;
use mirage::math::V3;
use mirage::medium::analytic::LinearSquare;
use mirage::medium::{Field, Medium, Param};
use mirage::pair::PointPair;
use mirage::problem::{Problem, SolverSpec, solver_settings};
use mirage::render::march::{MarchStats, Outcome};
use mirage::render::{RenderOptions, Renderer, render};
use mirage::scene::Scene;
use mirage::trace::batch::{BatchOptions, RayJob, trace_batch};
use mirage::trace::{End, GroundMode, Method, TargetPlane, TraceOptions, trace};
use std::path::Path;

/// n decreasing with height (rays bend down, as over cold water).
const SUPERIOR: LinearSquare = LinearSquare {
    n0: 1.0003,
    g: -2e-5,
};

/// n increasing with height (rays bend up, as over hot ground).
const INFERIOR: LinearSquare = LinearSquare {
    n0: 1.00027,
    g: 4e-6,
};

/// The smallest positive root of a·τ² + b·τ + c (cancellation-free).
fn first_positive_root(a: f64, b: f64, c: f64) -> f64 {
    let roots = if a == 0.0 {
        [-c / b, f64::NAN]
    } else {
        let disc = b * b - 4.0 * a * c;
        assert!(disc >= 0.0, "the parabola never meets the plane");
        let q = -0.5 * (b + b.signum() * disc.sqrt());
        [q / a, c / q]
    };
    roots
        .into_iter()
        .filter(|t| *t > 0.0)
        .fold(f64::INFINITY, f64::min)
}

/// Where the exact parabola from `o` along `d` first meets `plane`: the plane
/// equation N·(x(τ) − P) = 0 is the quadratic ¼·g·N_y·τ² + (v0·N)·τ + (o − P)·N.
fn exact_crossing(m: &LinearSquare, o: V3, d: V3, plane: &TargetPlane) -> V3 {
    let n_o = (m.n0 * m.n0 + m.g * o.y).sqrt();
    let tau = first_positive_root(
        0.25 * m.g * plane.normal.y,
        (d * n_o).dot(plane.normal),
        (o - plane.point).dot(plane.normal),
    );
    m.exact_position(o, d, tau)
}

/// Rays from two observers at several elevations, towards a tilted plane
/// about a kilometre away.
fn jobs() -> Vec<RayJob> {
    let target = TargetPlane {
        point: V3::new(40.0, 0.0, 1000.0),
        normal: V3::new(0.1, 0.05, 1.0).normalized(),
    };
    let mut jobs = Vec::new();
    for origin in [V3::new(0.0, 2.0, 0.0), V3::new(15.0, 6.0, -30.0)] {
        for elevation in [-0.05f64, 0.1, 0.25, 0.5, 0.9] {
            for azimuth in [-0.04f64, 0.0, 0.03] {
                let e = elevation.to_radians();
                jobs.push(RayJob {
                    origin,
                    direction: V3::new(azimuth.sin() * e.cos(), e.sin(), azimuth.cos() * e.cos())
                        .normalized(),
                    target,
                });
            }
        }
    }
    jobs
}

#[test]
fn the_tracer_follows_the_exact_parabola_through_field() {
    for m in [SUPERIOR, INFERIOR] {
        let field = Medium::LinearSquare(m).field();
        assert!(matches!(field, Field::LinearSquare(_)));
        let methods = [
            Method::Rk4 { step: 7.3 },
            Method::Rk4 { step: 0.5 },
            Method::Dopri5 { tolerance: 1e-9 },
        ];
        for method in methods {
            let options = TraceOptions::new(method);
            for job in jobs() {
                let t = trace::<f64, _>(
                    &field,
                    job.origin,
                    job.direction,
                    Some(&job.target),
                    &options,
                    None,
                );
                let exact = exact_crossing(&m, job.origin, job.direction, &job.target);
                assert_eq!(t.end, End::Plane);
                let err = (t.endpoint - exact).norm();
                assert!(err < 1e-9, "{m:?} {method:?}: {err:e} m off the parabola");
            }
        }
    }
}

#[test]
fn the_batch_entry_traces_the_kind_as_the_scalar_tracer_does() {
    for m in [SUPERIOR, INFERIOR] {
        let field = Medium::LinearSquare(m).field();
        let jobs = jobs();
        for step in [7.3, 0.5] {
            let options = TraceOptions::new(Method::Rk4 { step });
            let batch = BatchOptions::from_trace_options(&options);
            let traces = trace_batch(&field, &jobs, &batch);
            assert_eq!(traces.len(), jobs.len());
            for (job, t) in jobs.iter().zip(&traces) {
                let exact = exact_crossing(&m, job.origin, job.direction, &job.target);
                let err = (t.endpoint - exact).norm();
                assert!(err < 1e-9, "{m:?} step {step}: {err:e} m off the parabola");
                // Same semantics as the scalar tracer: the very same trace.
                let s = trace::<f64, _>(
                    &field,
                    job.origin,
                    job.direction,
                    Some(&job.target),
                    &options,
                    None,
                );
                assert_eq!(t.endpoint, s.endpoint);
                assert_eq!(t.end, s.end);
                assert_eq!(t.stats, s.stats);
                assert_eq!(t.arc_length, s.arc_length);
            }
        }
    }
}

#[test]
fn the_batch_entry_keeps_ground_mode_max_length_and_step_limit() {
    let m = SUPERIOR;
    let field = Medium::LinearSquare(m).field();
    let down = RayJob {
        origin: V3::new(0.0, 2.0, 0.0),
        direction: V3::new(0.0, -0.01, 1.0).normalized(),
        target: TargetPlane {
            point: V3::new(0.0, 0.0, 1000.0),
            normal: V3::new(0.0, 0.0, 1.0),
        },
    };
    let ground = TargetPlane {
        point: V3::ZERO,
        normal: V3::new(0.0, 1.0, 0.0),
    };
    let base = TraceOptions::new(Method::Rk4 { step: 3.0 });
    let variants = [
        TraceOptions {
            ground: GroundMode::Stop,
            ..base
        },
        TraceOptions {
            max_length: Some(50.0),
            ..base
        },
        TraceOptions {
            max_steps: 4,
            ..base
        },
        base,
    ];
    for options in variants {
        let batch = BatchOptions::from_trace_options(&options);
        let t = &trace_batch(&field, &[down], &batch)[0];
        let s = trace::<f64, _>(
            &field,
            down.origin,
            down.direction,
            Some(&down.target),
            &options,
            None,
        );
        assert_eq!(
            (t.endpoint, t.end, t.occluded),
            (s.endpoint, s.end, s.occluded)
        );
        assert_eq!(t.unreachable, s.unreachable);
    }
    // Each option does what it says.
    let run = |options: TraceOptions| {
        let batch = BatchOptions::from_trace_options(&options);
        trace_batch(&field, &[down], &batch).remove(0)
    };
    let stop = run(variants[0]);
    assert_eq!(stop.end, End::Ground);
    let exact_ground = exact_crossing(&m, down.origin, down.direction, &ground);
    assert!((stop.endpoint - exact_ground).norm() < 1e-9);
    assert_eq!(run(variants[1]).end, End::MaxLength);
    // It ends at the traced point nearest its plane, within a step of 50 m.
    let short = run(variants[1]);
    assert!(short.unreachable && (short.arc_length - 50.0).abs() <= 3.0 * 1.01);
    assert_eq!(run(variants[2]).end, End::StepLimit);
    let flagged = run(variants[3]);
    assert!(flagged.occluded && flagged.end == End::Plane);
}

/// Pairs whose targets are where the true medium's parabolas cross each
/// pair's plane: three observer heights, five elevations, 400–1200 m.
fn exact_pairs(truth: &LinearSquare) -> Vec<PointPair> {
    let mut pairs = Vec::new();
    for (k, oy) in [1.6, 4.0, 11.0].into_iter().enumerate() {
        for (j, elevation) in [-0.04f64, 0.05, 0.15, 0.3, 0.5].into_iter().enumerate() {
            let dist = 400.0 + 200.0 * ((k + j) % 5) as f64;
            let azimuth = 0.02 * (j as f64 - 2.0);
            let origin = [3.0 * k as f64, oy, -10.0 * k as f64];
            let through = [
                origin[0] + dist * azimuth.sin(),
                oy + dist * elevation.to_radians().tan(),
                origin[2] + dist * azimuth.cos(),
            ];
            let mut pair = PointPair {
                origin,
                through,
                target: through,
                weight: 1.0,
                wavelength: None,
            };
            // The pair's plane is vertical through the target and normal to
            // the horizontal launch direction, so it is the plane at
            // horizontal distance `dist`, whatever the target's height.
            let plane = pair.plane();
            let exact = exact_crossing(truth, pair.origin(), pair.direction(), &plane);
            pair.target = exact.to_array();
            pairs.push(pair);
        }
    }
    pairs
}

fn lm() -> mirage::problem::SolverSettings {
    let spec = SolverSpec {
        method: "lm".into(),
        max_iterations: Some(400),
        ..Default::default()
    };
    solver_settings(&spec, Path::new("test")).unwrap()
}

fn methods() -> [TraceOptions; 2] {
    [
        TraceOptions::new(Method::Rk4 { step: 5.0 }),
        TraceOptions::new(Method::Dopri5 { tolerance: 1e-9 }),
    ]
}

#[test]
fn the_fit_recovers_g_of_the_analytic_kind() {
    let truth = INFERIOR;
    for options in methods() {
        let mut start = Medium::LinearSquare(truth);
        start.set(Param::LinearG, truth.g * 1.3).unwrap();
        let obj = Objective::new(start, vec![Param::LinearG], exact_pairs(&truth), options);
        // The true medium meets every pair (the targets are its parabolas).
        let (r, flags) = obj.residuals(&[truth.g]);
        assert!(
            r.amax() < 1e-9,
            "{:?}: residual {:e} m",
            options.method,
            r.amax()
        );
        assert!(flags.iter().all(|f| !f.unreachable));
        let sol = solve(
            &obj,
            &lm(),
            &[(f64::NEG_INFINITY, f64::INFINITY)],
            0.0,
            None,
        )
        .unwrap();
        let err = ((sol.x[0] - truth.g) / truth.g).abs();
        eprintln!(
            "{:?}: F = {:.2e}, g error {err:.2e}",
            options.method, sol.objective
        );
        assert!(
            err < 1e-8,
            "{:?}: g = {} vs {}",
            options.method,
            sol.x[0],
            truth.g
        );
    }
}

/// Rays depend on n only up to a constant factor (n → λn leaves the ray
/// equation unchanged), so endpoints see n0 and g only through g/n0²: the two
/// cannot be told apart, and a fit of both recovers that ratio.
#[test]
fn the_fit_of_both_parameters_recovers_their_identifiable_ratio() {
    let truth = INFERIOR;
    let free = vec![Param::LinearN0, Param::LinearG];
    let mut start = Medium::LinearSquare(truth);
    start.set(Param::LinearN0, truth.n0 * (1.0 + 2e-4)).unwrap();
    start.set(Param::LinearG, truth.g * 1.3).unwrap();
    let obj = Objective::new(start, free, exact_pairs(&truth), methods()[0]);
    let unbounded = [(f64::NEG_INFINITY, f64::INFINITY); 2];
    let sol = solve(&obj, &lm(), &unbounded, 0.0, None).unwrap();
    let ratio = |n0: f64, g: f64| g / (n0 * n0);
    let err = (ratio(sol.x[0], sol.x[1]) / ratio(truth.n0, truth.g) - 1.0).abs();
    eprintln!(
        "both free: F = {:.2e}, g/n0² error {err:.2e}",
        sol.objective
    );
    assert!(err < 1e-8, "fitted {:?} vs {truth:?}", sol.x);
    // The dependence, exactly: n0·∂r/∂n0 = −2·g·∂r/∂g.
    let x = [truth.n0, truth.g];
    let (_, jac) = obj.jacobian(&x);
    let lhs = jac.column(0) * x[0];
    let rhs = jac.column(1) * (-2.0 * x[1]);
    assert!((&lhs - &rhs).norm() <= 1e-6 * rhs.norm());
}

#[test]
fn the_exact_jacobian_of_the_kind_matches_finite_differences() {
    let truth = INFERIOR;
    for (options, rel) in methods().into_iter().zip([1e-6, 1e-6]) {
        let mut start = Medium::LinearSquare(truth);
        start.set(Param::LinearG, truth.g * 1.3).unwrap();
        let free = vec![Param::LinearN0, Param::LinearG];
        let obj = Objective::new(start, free.clone(), exact_pairs(&truth), options);
        let x = obj.start();
        let (r, jac) = obj.jacobian(x.as_slice());
        let (r_plain, _) = obj.residuals(x.as_slice());
        assert!((&r - &r_plain).norm() <= 1e-12 * r.norm().max(1e-9));
        for (k, p) in free.iter().enumerate() {
            // Relative steps: the residuals are nearly linear in g and smooth
            // in n0, so central differences are accurate to O(h²) ≪ 1e-6.
            let h = 1e-4 * x[k].abs();
            let mut xp = x.clone();
            xp[k] += h;
            let mut xm = x.clone();
            xm[k] -= h;
            let fd = (obj.residuals(xp.as_slice()).0 - obj.residuals(xm.as_slice()).0) / (2.0 * h);
            let col = jac.column(k);
            let err = (&fd - col).norm() / col.norm();
            eprintln!(
                "{:?} {p}: |J| = {:.3e}, error {err:.2e}",
                options.method,
                col.norm()
            );
            assert!(err < rel, "{:?} {p}: {col:?} vs {fd:?}", options.method);
        }
    }
}

const PROBLEM: &str = r#"{
  "medium": { "scale": 1.0, "background": { "n": 1.0, "a": 40.0 } },
  "free": [],
  "pairs": [
    { "origin": [0, 1.6, 0], "through": [0, 2.0, 500], "target": [0, 2.0, 500] },
    { "origin": [0, 4.0, 0], "through": [30, 5.0, 900], "target": [30, 5.0, 900] },
    { "origin": [5, 11.0, -10], "through": [-40, 10.0, 1100], "target": [-40, 10.0, 1100] }
  ],
  "trace": { "method": "rk4", "step": 2.0 }
}"#;

#[test]
fn trace_pairs_reports_the_parabola_endpoints() {
    let mut problem = Problem::parse(PROBLEM, Path::new("kinds.json")).unwrap();
    let m = SUPERIOR;
    problem.medium = Medium::LinearSquare(m);
    let report = trace_pairs(&problem, &problem.medium);
    assert_eq!(report.pairs.len(), 3);
    for (pair, pr) in problem.pairs.iter().zip(&report.pairs) {
        let exact = exact_crossing(&m, pair.origin(), pair.direction(), &pair.plane());
        let err = (V3::from(pr.endpoint) - exact).norm();
        assert!(err < 1e-9, "{err:e} m off the parabola");
        assert!((pr.distance - (exact - pair.target()).norm()).abs() < 1e-9);
    }
}

/// A small scene: camera 2 m up looking slightly down over the ground, a box
/// to one side.
const SCENE: &str = r#"{
  "camera": { "position": [0, 2, 0], "look_at": [0, -3, 300], "vertical_fov": 2.0,
              "width": 12, "height": 8 },
  "medium": { "scale": 0.02, "background": { "n": 1.0, "a": 150.0 } },
  "ground": { "albedo": [0.3, 0.3, 0.3] },
  "sky": { "type": "gradient", "zenith": [0.2, 0.3, 0.8], "horizon": [0.7, 0.8, 1.0] },
  "objects": [ { "albedo": [1, 0, 0],
                 "shape": { "type": "box", "center": [6, 1, 250], "half_extents": [1, 1, 1] } } ],
  "trace": { "step": 4, "max_distance": 3000 }
}"#;

fn scene(m: LinearSquare) -> Scene {
    let mut scene = Scene::parse(SCENE, Path::new("kinds-scene.json")).unwrap();
    // Files hold the logistic kind; the analytic one is put in in code.
    scene.medium = Medium::LinearSquare(m);
    scene
}

/// Where the exact parabola of a camera ray meets the ground.
fn exact_ground(m: &LinearSquare, origin: V3, dir: V3) -> V3 {
    let ground = TargetPlane {
        point: V3::ZERO,
        normal: V3::new(0.0, 1.0, 0.0),
    };
    exact_crossing(m, origin, dir, &ground)
}

fn v3(p: glam::DVec3) -> V3 {
    V3::new(p.x, p.y, p.z)
}

#[test]
fn camera_rays_meet_the_ground_where_the_parabola_does() {
    let m = INFERIOR;
    let s = scene(m);
    // Integrated rays: RK4 is exact on this medium whatever the render's step
    // (x is quadratic in τ; the render's RK4 step here is the scene's 4 m) and
    // the ground crossing is located on the step's quintic Hermite
    // interpolant, exact for a quadratic, to full precision: only rounding is
    // left, ~1e-12 m over a few hundred metres; 1e-7 m leaves room for it.
    let marched = Renderer::new(
        &s,
        &RenderOptions {
            path_reuse: false,
            ..RenderOptions::default()
        },
    );
    // Along the path table: the interpolation between tabulated paths is
    // within its tolerance, 0.02 px as an angle seen from the camera, i.e. a
    // height error ≤ 0.02·px·ρ at horizontal distance ρ, which moves the
    // ground point by that over the tangent of the ray's descent there.
    let tabled = Renderer::new(&s, &RenderOptions::default());
    assert!(tabled.table().is_some(), "stratified air gets a path table");
    let px = tabled.camera().pixel_angle();
    let origin = v3(marched.camera().origin);
    let mut grounds = 0;
    for (x, y) in [(6.0, 7.5), (0.5, 7.9), (11.5, 6.0), (3.2, 5.1), (8.0, 4.4)] {
        let dir = marched.camera().direction(x, y);
        let exact = exact_ground(&m, origin, v3(dir));
        // Slope of the exact path at the ground: dy/dρ = vy / c.
        let n_o = (m.n0 * m.n0 + m.g * origin.y).sqrt();
        let c = n_o * dir.x.hypot(dir.z);
        let tau = (exact - origin).x.hypot((exact - origin).z) / c;
        let vy = n_o * dir.y + 0.5 * m.g * tau;
        let rho = c * tau;
        let table_tolerance = 2.0 * 0.02 * px * rho * c / vy.abs();
        for (renderer, tolerance) in [(&marched, 1e-7), (&tabled, table_tolerance)] {
            let mut stats = MarchStats::default();
            match renderer.trace_pixel(x, y, &mut stats) {
                Outcome::Ground { point, .. } => {
                    let err = (v3(point) - exact).norm();
                    eprintln!("pixel ({x}, {y}): {err:.2e} m off (tolerance {tolerance:.2e} m)");
                    assert!(
                        err < tolerance,
                        "pixel ({x}, {y}): ground {point:?} vs {exact:?}, {err:e} m"
                    );
                    grounds += 1;
                }
                other => panic!("pixel ({x}, {y}) should see the ground, got {other:?}"),
            }
        }
        // The medium does bend: the straight line lands elsewhere.
        let straight = origin + v3(dir) * (-origin.y / dir.y);
        assert!((straight - exact).norm() > 0.01);
    }
    assert_eq!(grounds, 10);
}

#[test]
fn the_whole_image_renders_through_the_kind() {
    for m in [INFERIOR, SUPERIOR] {
        for path_reuse in [true, false] {
            let options = RenderOptions {
                path_reuse,
                samples_per_pixel: Some(2),
                ..RenderOptions::default()
            };
            let img = render(&scene(m), &options);
            assert_eq!(img.pixels.len(), 12 * 8);
            assert!(
                img.pixels
                    .iter()
                    .flatten()
                    .all(|v| v.is_finite() && *v >= 0.0),
                "{m:?}: non-finite pixels"
            );
        }
    }
}

#[test]
fn a_uniform_vacuum_of_the_kind_renders_as_straight_rays() {
    let options = RenderOptions {
        samples_per_pixel: Some(2),
        ..RenderOptions::default()
    };
    let kind = render(&scene(LinearSquare { n0: 1.0, g: 0.0 }), &options);
    let straight = render(
        &scene(INFERIOR),
        &RenderOptions {
            straight: true,
            ..options
        },
    );
    assert_eq!(kind.pixels, straight.pixels);
}
