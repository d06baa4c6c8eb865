//! Nelder–Mead's stopping tests on bundled problems: it stops at the target
//! objective (the iteration after F first meets it), when its simplex has
//! collapsed, when F has levelled off, and at its iteration limit; each stop
//! reason names its test. The same holds for `auto`'s Nelder–Mead stage.

use mirage::fit::nelder_mead::NmStop;
use mirage::fit::report::FitReport;
use mirage::problem::Problem;
use serde_json::{Value, json};
use std::path::Path;

fn problem(name: &str, edit: impl FnOnce(&mut Value)) -> Problem {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("problems/{name}.json"));
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    edit(&mut v);
    Problem::parse(&v.to_string(), &path).unwrap()
}

fn nelder_mead(name: &str, solver: Value) -> FitReport {
    let p = problem(name, |v| {
        let mut s = json!({ "method": "nelder-mead" });
        for (k, x) in solver.as_object().unwrap() {
            s[k] = x.clone();
        }
        v["solver"] = s;
    });
    mirage::fit::fit(&p, None).unwrap()
}

fn stop_of(r: &FitReport) -> Option<NmStop> {
    NmStop::ALL
        .into_iter()
        .find(|s| s.text() == r.solver.stop_reason)
}

#[test]
fn it_stops_at_the_target_objective() {
    for name in ["hot-road", "cold-sea", "sinking-mast"] {
        let r = nelder_mead(name, json!({}));
        assert_eq!(
            stop_of(&r),
            Some(NmStop::Target),
            "{name}: {}",
            r.solver.stop_reason
        );
        assert!(r.solver.converged && r.solver.reached_target);
        assert!(
            r.totals.objective <= 1e-12,
            "{name}: F = {:e}",
            r.totals.objective
        );
        // It stopped at the first iterate that met the target.
        let records = &r.history.runs[0].records;
        let n = records.len();
        assert!(records[n - 1].objective <= 1e-12);
        assert!(
            records[n - 2].objective > 1e-12,
            "{name}: ran on past the target"
        );
        assert!(
            r.solver.iterations < 400,
            "{name}: {} iterations",
            r.solver.iterations
        );
    }
    // A looser target stops it sooner.
    let strict = nelder_mead("hot-road", json!({}));
    let loose = nelder_mead("hot-road", json!({ "target_objective": 1e-6 }));
    assert!(loose.totals.objective <= 1e-6 && loose.solver.iterations < strict.solver.iterations);
}

#[test]
fn it_stops_when_the_simplex_has_collapsed() {
    // Targets that can be met exactly and a target of 0 that cannot: F falls
    // with the simplex, so the size test is the one that ends the run.
    let r = nelder_mead(
        "hot-road",
        json!({ "target_objective": 0.0, "simplex_ftol": 0.0, "simplex_xtol": 1e-8 }),
    );
    assert_eq!(
        stop_of(&r),
        Some(NmStop::SimplexSize),
        "{}",
        r.solver.stop_reason
    );
    assert!(r.solver.stop_reason.contains("simplex_xtol"));
    assert!(r.solver.converged && !r.solver.reached_target);
    assert!(r.totals.objective < 1e-15, "F = {:e}", r.totals.objective);
    assert!(r.solver.iterations < 4000, "{}", r.solver.iterations);
    // A tighter size means more iterations and a better F.
    let tighter = nelder_mead(
        "hot-road",
        json!({ "target_objective": 0.0, "simplex_ftol": 0.0, "simplex_xtol": 1e-10 }),
    );
    assert_eq!(stop_of(&tighter), Some(NmStop::SimplexSize));
    assert!(tighter.solver.iterations > r.solver.iterations);
}

#[test]
fn it_stops_when_f_has_levelled_off() {
    // One target moved by 10 cm: the targets cannot all be met, F levels off
    // above 0 and the spread test ends the run.
    let p = problem("hot-road", |v| {
        let y = v["pairs"][1]["target"][1].as_f64().unwrap();
        v["pairs"][1]["target"][1] = json!(y + 0.1);
        v["solver"] = json!({ "method": "nelder-mead", "target_objective": 0.0 });
    });
    let r = mirage::fit::fit(&p, None).unwrap();
    assert_eq!(
        stop_of(&r),
        Some(NmStop::FSpread),
        "{}",
        r.solver.stop_reason
    );
    assert!(r.solver.stop_reason.contains("simplex_ftol"));
    assert!(r.totals.objective > 1e-4, "F = {:e}", r.totals.objective);
    assert!(r.solver.iterations < 1000, "{}", r.solver.iterations);
    // LM agrees on the minimum.
    let mut lm = p.clone();
    lm.solver.method = mirage::problem::SolverMethod::Lm;
    let best = mirage::fit::fit(&lm, None).unwrap().totals.objective;
    assert!(
        (r.totals.objective - best).abs() <= 1e-6 * best,
        "Nelder–Mead F = {:e}, LM F = {best:e}",
        r.totals.objective
    );
}

#[test]
fn it_stops_at_its_iteration_limit_and_says_so() {
    let r = nelder_mead("hot-road", json!({ "max_iterations": 2 }));
    assert_eq!(stop_of(&r), None);
    assert_eq!(r.solver.iterations, 40);
    assert!(!r.solver.converged && !r.solver.reached_target);
    assert!(
        r.solver
            .stop_reason
            .starts_with("Maximum number of iterations reached (40 = 20 × solver.max_iterations)"),
        "{}",
        r.solver.stop_reason
    );
}

#[test]
fn autos_nelder_mead_stage_stops_by_its_tests_too() {
    // A target of 0 cannot be met: `auto` runs its restarts, then Nelder–Mead
    // from the best of them, which must stop by collapse, not by its limit.
    let p = problem("fata-morgana", |v| {
        v["solver"]["target_objective"] = json!(0.0);
        v["solver"]["starts"] = json!(2);
    });
    let r = mirage::fit::fit(&p, None).unwrap();
    let nm = r.runs.iter().find(|r| r.label == "nelder-mead").unwrap();
    assert!(
        nm.converged && !nm.stop_reason.starts_with("Maximum"),
        "{}: {} iterations",
        nm.stop_reason,
        nm.iterations
    );
    assert!(nm.iterations < 2000, "{}", nm.iterations);
}
