//! The surrogate tracer (`mirage::fit::surrogate`): an RK4 fit that converges
//! under Dormand–Prince first lands where the fit under RK4 alone lands (with
//! consistent targets and with noisy ones), at a fraction of RK4's Jacobians;
//! it is left out where it would not pay or is not wanted; a refined fit that
//! misses the target the surrogate met falls back to the problem's own
//! strategy; and a bad `solver.surrogate` is refused by name.

use mirage::fit::fit;
use mirage::fit::objective::Objective;
use mirage::fit::report::FitReport;
use mirage::fit::surrogate::choose;
use mirage::problem::Problem;
use serde_json::{Value, json};
use std::path::Path;
use std::process::Command;

fn bundled(name: &str) -> Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("problems")
        .join(format!("{name}.json"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn problem(v: &Value) -> Problem {
    Problem::parse(&v.to_string(), Path::new("test.json")).unwrap()
}

/// `v` traced by RK4 at `step` metres, the surrogate on or off.
fn rk4(v: &Value, step: f64, surrogate: bool) -> Value {
    let mut v = v.clone();
    v["trace"] = json!({ "method": "rk4", "step": step });
    v["solver"]["surrogate"] = json!(surrogate);
    v
}

/// Moves every target by up to ±`size` metres (a fixed pattern), so that no
/// medium meets them all: the answer is a least-squares one, F > 0.
fn noisy(v: &Value, size: f64) -> Value {
    let mut v = v.clone();
    for (i, pair) in v["pairs"].as_array_mut().unwrap().iter_mut().enumerate() {
        for c in 0..3 {
            let t = pair["target"][c].as_f64().unwrap();
            let wobble = ((i * 3 + c) as f64 * 2.399_963).sin();
            pair["target"][c] = json!(t + size * wobble);
        }
    }
    v
}

/// Fits with and without the surrogate and checks that both land on the same
/// answer.
fn same_answer(name: &str, v: &Value) -> (FitReport, FitReport) {
    let with = fit(&problem(&rk4(v, 0.5, true)), None).unwrap();
    let without = fit(&problem(&rk4(v, 0.5, false)), None).unwrap();

    let s = with
        .solver
        .surrogate
        .as_ref()
        .unwrap_or_else(|| panic!("{name}: the surrogate should pay here"));
    assert_eq!(s.tracer, "dopri5 tolerance 1e-9");
    assert!(s.problem_rhs_at_start >= 2 * s.surrogate_rhs_at_start);
    assert!(with.runs.iter().any(|r| r.surrogate));
    assert_eq!(with.solver.best_run, "lm (refine)", "{name}");
    assert!(without.solver.surrogate.is_none());
    assert!(without.runs.iter().all(|r| !r.surrogate));

    // The refined answer is RK4's: F is the problem's tracer's, and it
    // matches the direct fit's to rounding (both at a converged minimum).
    let (fw, fo) = (with.totals.objective, without.totals.objective);
    assert!(
        (fw - fo).abs() <= 1e-6 * fo.max(1e-18),
        "{name}: F {fw:e} with the surrogate, {fo:e} without"
    );
    for (a, b) in with.parameters.iter().zip(&without.parameters) {
        let scale = a.standard_error.unwrap_or(0.0) + 1e-9 * a.value.abs();
        assert!(
            (a.value - b.value).abs() <= 1e-3 * scale,
            "{name}: {} = {} with the surrogate, {} without (standard error {:?})",
            a.name,
            a.value,
            b.value,
            a.standard_error
        );
        // The standard errors come from RK4's exact Jacobian at the answer.
        let (sa, sb) = (a.standard_error.unwrap(), b.standard_error.unwrap());
        assert!(
            (sa - sb).abs() <= 1e-4 * sb,
            "{name}: {} {sa:e} {sb:e}",
            a.name
        );
    }
    (with, without)
}

#[test]
fn with_the_bundled_targets_it_lands_where_rk4_alone_does() {
    // The targets were made by Dormand–Prince at 1e-9: RK4 at 0.5 m meets
    // them to some 1e-8 m (hot-road: F = 7e-16 m²).
    for name in ["hot-road", "desert-lake"] {
        let (with, without) = same_answer(name, &bundled(name));
        assert!(
            with.totals.objective < 1e-12,
            "{name}: {:e}",
            with.totals.objective
        );
        assert!(with.solver.converged, "{name}: {}", with.solver.stop_reason);
        // What it is for: the refining takes a few of RK4's Jacobians where
        // the fit under RK4 alone takes one per iteration.
        assert!(
            3 * with.solver.jacobian_evaluations <= without.solver.jacobian_evaluations,
            "{name}: {} RK4 Jacobians with the surrogate, {} without",
            with.solver.jacobian_evaluations,
            without.solver.jacobian_evaluations
        );
    }
}

#[test]
fn with_noisy_targets_it_lands_where_rk4_alone_does() {
    // A centimetre of noise: F far above rounding, so a fit that stopped at
    // the surrogate's minimum instead of RK4's would show.
    // LM alone: with F above the default target, `auto` would also run its
    // restarts, which this test is not about.
    for name in ["hot-road", "fata-morgana"] {
        let mut v = noisy(&bundled(name), 0.01);
        v["solver"]["method"] = json!("lm");
        let (with, _) = same_answer(name, &v);
        assert!(
            with.totals.objective > 1e-6,
            "{name}: {:e}",
            with.totals.objective
        );
        assert!(with.solver.converged, "{name}: {}", with.solver.stop_reason);
    }
}

#[test]
fn it_is_left_out_where_it_would_not_pay_or_is_not_wanted() {
    let v = bundled("desert-lake");
    let decide = |v: &Value| {
        let p = problem(v);
        let o = Objective::from_problem(&p);
        choose(&o, &p.solver, o.start().as_slice()).map(|s| (s.problem_rhs, s.surrogate_rhs))
    };
    // Fine RK4 steps: it pays.
    let (rk, dp) = decide(&rk4(&v, 0.5, true)).unwrap();
    assert!(rk >= 2 * dp, "{rk} {dp}");
    // Turned off; with Nelder–Mead; for an adaptive tracer; with nothing free.
    assert!(decide(&rk4(&v, 0.5, false)).is_none());
    let mut nm = rk4(&v, 0.5, true);
    nm["solver"]["method"] = json!("nelder-mead");
    assert!(decide(&nm).is_none());
    assert!(decide(&v).is_none());
    let mut fixed = rk4(&v, 0.5, true);
    fixed["free"] = json!([]);
    fixed["bounds"] = json!({});
    assert!(decide(&fixed).is_none());
    // Steps so long that RK4 needs fewer than twice the surrogate's
    // evaluations: not worth a second stage.
    let coarse = rk4(&v, 200.0, true);
    assert!(decide(&coarse).is_none());
    let r = fit(&problem(&coarse), None).unwrap();
    assert!(r.solver.surrogate.is_none() && r.runs.iter().all(|r| !r.surrogate));
}

#[test]
fn a_refined_fit_that_misses_the_target_falls_back_to_the_problems_own_strategy() {
    // Targets made by Dormand–Prince at 1e-9 (the surrogate's tracer): the
    // surrogate meets them to rounding, RK4 at 2 m cannot. A target between
    // the two F makes the refined fit miss what the surrogate met.
    let v = bundled("desert-lake");
    let surrogate_alone = fit(&problem(&v), None).unwrap().totals.objective;
    let rk4_alone = fit(&problem(&rk4(&v, 2.0, false)), None)
        .unwrap()
        .totals
        .objective;
    assert!(
        rk4_alone > 1e4 * surrogate_alone,
        "RK4 at 2 m should miss the targets by far more: {rk4_alone:e} vs {surrogate_alone:e}"
    );
    let mut v = rk4(&v, 2.0, true);
    v["solver"]["target_objective"] = json!((surrogate_alone * rk4_alone).sqrt());
    let r = fit(&problem(&v), None).unwrap();
    let labels: Vec<&str> = r.runs.iter().map(|r| r.label.as_str()).collect();
    let refine = labels.iter().position(|l| *l == "lm (refine)").unwrap();
    assert!(r.runs[..refine].iter().all(|r| r.surrogate), "{labels:?}");
    assert!(
        r.runs[refine + 1..]
            .iter()
            .any(|r| r.label == "lm" && !r.surrogate),
        "the problem's own strategy ran after the refined fit: {labels:?}"
    );
    // The kept run is the best of those on RK4, never a surrogate run.
    let best = r
        .runs
        .iter()
        .find(|x| x.label == r.solver.best_run)
        .unwrap();
    assert!(!best.surrogate);
    let lowest = r
        .runs
        .iter()
        .filter(|x| !x.surrogate)
        .map(|x| x.objective)
        .fold(f64::INFINITY, f64::min);
    assert_eq!(best.objective, lowest);
    assert!(!r.solver.reached_target);
}

#[test]
fn a_bad_surrogate_field_is_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let mut v = rk4(&bundled("hot-road"), 0.5, true);
    v["solver"]["surrogate"] = json!("yes");
    let file = dir.path().join("p.json");
    std::fs::write(&file, v.to_string()).unwrap();
    let out = dir.path().join("r.json");
    let o = Command::new(env!("CARGO_BIN_EXE_mirage"))
        .args(["fit", "-q"])
        .arg(&file)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("solver.surrogate") && err.contains("p.json"),
        "{err}"
    );
    assert!(!out.exists());
}
