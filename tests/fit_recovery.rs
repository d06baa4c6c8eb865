//! Recovery of known media from synthetic pairs: trace a known medium to get the
//! targets, start from a perturbed medium, fit, and compare.

use mirage::fit::objective::Objective;
use mirage::fit::solve::{IterateHook, solve};
use mirage::fit::synthetic::retarget;
use mirage::medium::{Background, HotSpot, Inversion, LogisticMedium, Param};
use mirage::pair::PointPair;
use mirage::problem::{SolverMethod, SolverSettings, SolverSpec, solver_settings};
use mirage::trace::{Method, TraceOptions};
use std::path::Path;
use std::sync::{Arc, Mutex};

fn options() -> TraceOptions {
    TraceOptions::new(Method::Dopri5 { tolerance: 1e-9 })
}

/// Fifteen pairs from two observers, over 400–1200 m, across azimuths and
/// elevations from just below the horizon to 1°.
fn geometry() -> Vec<PointPair> {
    let observers = [[0.0, 1.6, 0.0], [25.0, 4.0, -40.0]];
    let mut pairs = Vec::new();
    let mut k = 0usize;
    for (oi, o) in observers.iter().enumerate() {
        for (zi, &z) in [400.0, 700.0, 1000.0, 1200.0].iter().enumerate() {
            for &x in &[-90.0f64, 10.0, 70.0] {
                k += 1;
                if pairs.len() == 15 || (oi == 1 && zi == 0 && x < 0.0) {
                    continue;
                }
                let elevation = [-0.12f64, 0.05, 0.35, 0.9][k % 4].to_radians();
                let dist = ((x - o[0]) * (x - o[0]) + (z - o[2]) * (z - o[2])).sqrt();
                let through = [x, o[1] + dist * elevation.tan(), z];
                pairs.push(PointPair {
                    origin: *o,
                    through,
                    target: through,
                    weight: 1.0,
                    wavelength: None,
                });
            }
        }
    }
    assert_eq!(pairs.len(), 15);
    pairs
}

fn settings(method: &str) -> SolverSettings {
    let spec = SolverSpec {
        method: method.into(),
        max_iterations: Some(400),
        ..Default::default()
    };
    solver_settings(&spec, Path::new("test")).unwrap()
}

struct Case {
    truth: LogisticMedium,
    free: Vec<Param>,
    /// Relative perturbation of each free parameter at the start.
    perturb: Vec<f64>,
}

/// Fits the case and returns (final F, worst relative parameter error, iterates).
fn recover(
    case: &Case,
    method: &str,
    bounds: Option<Vec<(f64, f64)>>,
) -> (f64, f64, Vec<Vec<f64>>, Vec<f64>) {
    let (pairs, failed) = retarget(&geometry(), &case.truth.field(), &options());
    assert!(
        failed.is_empty(),
        "every synthetic ray must reach its plane"
    );
    let mut start = case.truth.clone();
    for (p, f) in case.free.iter().zip(&case.perturb) {
        start
            .set(*p, case.truth.get(*p).unwrap() * (1.0 + f))
            .unwrap();
    }
    let obj = Objective::new(start, case.free.clone(), pairs, options());
    let bounds =
        bounds.unwrap_or_else(|| vec![(f64::NEG_INFINITY, f64::INFINITY); case.free.len()]);
    let seen = Arc::new(Mutex::new(Vec::new()));
    let seen2 = seen.clone();
    let hook: IterateHook =
        Arc::new(move |_: &str, rec| seen2.lock().unwrap().push(rec.params.clone()));
    let sol = solve(&obj, &settings(method), &bounds, 1e-14, Some(hook)).unwrap();
    let worst = case
        .free
        .iter()
        .zip(&sol.x)
        .map(|(p, v)| {
            let t = case.truth.get(*p).unwrap();
            ((v - t) / t).abs()
        })
        .fold(0.0, f64::max);
    eprintln!(
        "{method}: F = {:.3e}, worst relative error {worst:.3e}, runs {:?}",
        sol.objective,
        sol.runs
            .iter()
            .map(|r| (&r.label, r.iterations, &r.reason))
            .collect::<Vec<_>>()
    );
    let seen = seen.lock().unwrap().clone();
    (sol.objective, worst, seen, sol.x)
}

fn background_only() -> Case {
    Case {
        truth: LogisticMedium {
            scale: 1.2,
            background: Some(Background { n: 1.0, a: 30.0 }),
            inversion: None,
            hotspots: vec![],
        },
        free: vec![Param::Scale, Param::BackgroundA],
        perturb: vec![0.15, -0.2],
    }
}

fn inversion_layer() -> Case {
    Case {
        truth: LogisticMedium {
            scale: 1.0,
            background: Some(Background { n: 1.0, a: 40.0 }),
            inversion: Some(Inversion {
                n: 0.8,
                a: 1.5,
                height: 9.0,
            }),
            hotspots: vec![],
        },
        free: vec![Param::InversionHeight, Param::InversionA],
        perturb: vec![0.1, 0.25],
    }
}

fn hot_spot() -> Case {
    Case {
        truth: LogisticMedium {
            scale: 1.0,
            background: Some(Background { n: 1.0, a: 40.0 }),
            inversion: None,
            hotspots: vec![HotSpot {
                x: 5.0,
                z: 550.0,
                radius: 180.0,
                n: -2.0,
                a: -0.8,
                edge: 0.08,
            }],
        },
        free: vec![
            Param::Hot(0, mirage::medium::HotField::X),
            Param::Hot(0, mirage::medium::HotField::Z),
            Param::Hot(0, mirage::medium::HotField::Radius),
            Param::Hot(0, mirage::medium::HotField::N),
        ],
        perturb: vec![1.0, 0.04, -0.08, 0.1],
    }
}

fn all_terms() -> Case {
    use mirage::medium::HotField;
    let mut truth = hot_spot().truth;
    truth.inversion = Some(Inversion {
        n: 0.8,
        a: 1.5,
        height: 9.0,
    });
    Case {
        truth,
        free: vec![
            Param::BackgroundA,
            Param::InversionHeight,
            Param::InversionN,
            Param::Hot(0, HotField::X),
            Param::Hot(0, HotField::Radius),
            Param::Hot(0, HotField::N),
        ],
        perturb: vec![0.1, 0.05, -0.1, 0.6, 0.05, -0.05],
    }
}

fn assert_recovered(case: Case, method: &str) {
    let (f, worst, _, _) = recover(&case, method, None);
    assert!(f < 1e-12, "{method}: objective {f:e} m²");
    assert!(
        worst < 1e-6,
        "{method}: parameters off by {worst:e} (relative)"
    );
}

#[test]
fn lm_recovers_a_background() {
    assert_recovered(background_only(), "lm");
}

#[test]
fn lm_recovers_an_inversion_layer() {
    assert_recovered(inversion_layer(), "lm");
}

#[test]
fn lm_recovers_a_hot_spot_position_radius_and_strength() {
    assert_recovered(hot_spot(), "lm");
}

#[test]
fn lm_recovers_six_parameters_of_all_terms() {
    assert_recovered(all_terms(), "lm");
}

#[test]
fn nelder_mead_recovers_the_two_parameter_cases() {
    assert_recovered(background_only(), "nelder-mead");
    assert_recovered(inversion_layer(), "nelder-mead");
}

#[test]
fn auto_recovers_all_terms() {
    assert_recovered(all_terms(), "auto");
}

#[test]
fn no_iterate_leaves_the_bounds() {
    // Bounds that exclude the truth on one parameter: the fit must end on that
    // bound, and no iterate, of any run, may step outside.
    let case = hot_spot();
    let bounds = vec![(-20.0, 20.0), (500.0, 600.0), (150.0, 175.0), (-3.0, -1.0)];
    for method in ["lm", "nelder-mead", "auto"] {
        let (_, _, iterates, x) = recover(&case, method, Some(bounds.clone()));
        assert!(iterates.len() > 5);
        for x in &iterates {
            for (v, (l, u)) in x.iter().zip(&bounds) {
                assert!(
                    v >= l && v <= u,
                    "{method}: iterate {x:?} outside {bounds:?}"
                );
            }
        }
        // Nelder–Mead's change of variables approaches a bound without reaching
        // it exactly; LM lands on it.
        assert!(
            (x[2] - 175.0).abs() < 1e-9 * 175.0,
            "{method}: radius {} ends on its upper bound",
            x[2]
        );
    }
}

#[test]
fn a_gauge_degenerate_fit_finishes_and_names_the_direction() {
    // All amplitudes free together: δ is invariant under scaling them all.
    let mut case = all_terms();
    case.free = vec![
        Param::BackgroundN,
        Param::InversionN,
        Param::Hot(0, mirage::medium::HotField::N),
    ];
    case.perturb = vec![0.0, 0.2, -0.1];
    let (pairs, _) = retarget(&geometry(), &case.truth.field(), &options());
    let mut start = case.truth.clone();
    start.set(Param::InversionN, 0.8 * 1.2).unwrap();
    start
        .set(Param::Hot(0, mirage::medium::HotField::N), -2.0 * 0.9)
        .unwrap();
    let obj = Objective::new(start, case.free.clone(), pairs, options());
    let sol = solve(
        &obj,
        &settings("lm"),
        &[(f64::NEG_INFINITY, f64::INFINITY); 3],
        1e-14,
        None,
    )
    .unwrap();
    assert!(sol.x.iter().all(|v| v.is_finite()) && sol.objective.is_finite());
    assert!(
        sol.objective < 1e-12,
        "the fit itself still succeeds: F = {:e}",
        sol.objective
    );
    // The ratios are recovered even though the scale is free.
    let ratio = sol.x[1] / sol.x[0];
    assert!((ratio - 0.8).abs() < 1e-6, "n_inv / n_bg = {ratio}");
    let (_, jac) = obj.jacobian(&sol.x);
    let report = mirage::fit::identify::analyse(&jac, &sol.x, &case.free, sol.objective);
    assert_eq!(report.undetermined.len(), 1);
    assert!(
        report.undetermined[0].note.contains("gauge"),
        "{}",
        report.undetermined[0].note
    );
    assert!(report.params.iter().all(|p| p.standard_error.is_none()));
    assert!(matches!(settings("lm").method, SolverMethod::Lm));
}
