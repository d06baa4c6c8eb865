//! The bundled problems: every file loads, traces, and fits; and a fit's result
//! does not depend on the number of threads.

use mirage::evaluate::trace_pairs;
use mirage::problem::Problem;
use std::path::{Path, PathBuf};
use std::process::Command;

fn problem_files() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    assert!(files.len() >= 5, "at least five bundled problems");
    files
}

#[test]
fn every_bundled_problem_loads_traces_and_is_documented() {
    for f in problem_files() {
        let p = Problem::load(&f).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            p.description.len() > 80,
            "{}: describe what a user would see",
            f.display()
        );
        assert!(!p.free.is_empty() && !p.pairs.is_empty());
        let r = trace_pairs(&p, &p.medium);
        assert_eq!(r.pairs.len(), p.pairs.len());
        for pr in &r.pairs {
            assert!(pr.endpoint.iter().all(|c| c.is_finite()), "{}", f.display());
            assert!(
                !pr.unreachable,
                "{}: every ray reaches its target plane",
                f.display()
            );
        }
        assert!(r.totals.objective.is_finite() && r.totals.objective > 0.0);
    }
}

#[test]
fn every_bundled_problem_fits() {
    for f in problem_files() {
        let p = Problem::load(&f).unwrap();
        let r = mirage::fit::fit(&p, None).unwrap();
        assert!(
            r.totals.objective < 1e-12,
            "{}: F = {:e} after {:?}",
            f.display(),
            r.totals.objective,
            r.runs
                .iter()
                .map(|r| (&r.label, r.objective))
                .collect::<Vec<_>>()
        );
        assert!(r.solver.reached_target);
        // The fitted medium is a valid medium and reproduces the fit when traced.
        r.medium.validate().unwrap();
        assert!((trace_pairs(&p, &r.medium).totals.objective - r.totals.objective).abs() < 1e-20);
    }
}

/// Removes the fields that measure time.
fn without_timing(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(m) => {
            m.remove("wall_time_s");
            m.remove("elapsed_s");
            m.values_mut().for_each(without_timing);
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(without_timing),
        _ => {}
    }
}

#[test]
fn fit_results_are_identical_with_one_and_two_threads() {
    // A target objective of 0 cannot be met, so `auto` runs everything it has:
    // LM, the restarts in parallel, Nelder–Mead and the LM polish; and since
    // the problem sets it, the fit exits 1 after writing its result.
    let source = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/fata-morgana.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&source).unwrap()).unwrap();
    v["solver"]["target_objective"] = serde_json::json!(0.0);
    v["solver"]["starts"] = serde_json::json!(4);
    let dir = tempfile::tempdir().unwrap();
    let problem = dir.path().join("problem.json");
    std::fs::write(&problem, v.to_string()).unwrap();
    let mut results = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.path().join(format!("r{threads}.json"));
        let run = Command::new(env!("CARGO_BIN_EXE_mirage"))
            .args(["--threads", threads, "fit", "-q"])
            .arg(&problem)
            .arg("-o")
            .arg(&out)
            .output()
            .unwrap();
        assert_eq!(
            run.status.code(),
            Some(1),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let mut v: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
        assert_eq!(v["solver"]["reached_target"], serde_json::json!(false));
        without_timing(&mut v);
        results.push(v);
    }
    let labels: Vec<&str> = results[0]["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["label"].as_str().unwrap())
        .collect();
    assert_eq!(
        labels,
        [
            "lm",
            "lm (start 1)",
            "lm (start 2)",
            "lm (start 3)",
            "lm (start 4)",
            "nelder-mead",
            "lm (polish)"
        ]
    );
    assert_eq!(results[0], results[1]);
}

#[test]
fn the_fit_result_holds_what_the_format_promises_and_its_medium_feeds_back() {
    let problem_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/hot-road.json");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("result.json");
    let run = Command::new(env!("CARGO_BIN_EXE_mirage"))
        .args(["fit", "-q"])
        .arg(&problem_path)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        stdout.contains("hotspots[0].radius") && stdout.contains("std. error"),
        "{stdout}"
    );
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    for key in [
        "medium",
        "parameters",
        "undetermined",
        "objective",
        "summed_distance",
        "max_distance",
        "pairs",
        "solver",
        "runs",
        "history",
    ] {
        assert!(v.get(key).is_some(), "result lacks `{key}`");
    }
    for key in [
        "method",
        "iterations",
        "residual_evaluations",
        "jacobian_evaluations",
        "wall_time_s",
        "stop_reason",
    ] {
        assert!(v["solver"].get(key).is_some(), "solver lacks `{key}`");
    }
    for p in v["parameters"].as_array().unwrap() {
        assert!(
            p["value"].is_f64() && p["standard_error"].is_f64() && p["determined"] == true,
            "{p}"
        );
    }
    for p in v["pairs"].as_array().unwrap() {
        assert!(p["endpoint"].is_array() && p["distance"].is_f64());
        assert!(p["occluded"].is_boolean() && p["unreachable"].is_boolean());
    }
    let history = &v["history"]["runs"][0]["records"];
    assert!(
        history.as_array().unwrap().len() > 2,
        "objective per iteration"
    );
    // No NaN can hide in JSON (serde_json writes null for it): no nulls but the
    // documented standard errors of undetermined parameters.
    assert!(!std::fs::read_to_string(&out).unwrap().contains("NaN"));

    // Feed the fitted medium back as the problem's medium: the pairs are met.
    let mut problem: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&problem_path).unwrap()).unwrap();
    problem["medium"] = v["medium"].clone();
    let p = Problem::parse(&problem.to_string(), Path::new("refit.json")).unwrap();
    assert!(trace_pairs(&p, &p.medium).totals.objective < 1e-12);
}
