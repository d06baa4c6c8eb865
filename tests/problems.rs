//! The bundled problems: every file loads, traces, and fits; and no command's
//! output depends on the number of threads (bit for bit, timings aside), for
//! the logistic model and for real air alike.

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

/// Bundled problems of measured sightings, not traced from a known air:
/// their fit has a residual (`tests/maine.rs` checks what it finds).
const MEASURED: [&str; 1] = ["maine-surveyor.json"];

#[test]
fn every_bundled_problem_fits() {
    for f in problem_files() {
        let p = Problem::load(&f).unwrap();
        let r = mirage::fit::fit(&p, None).unwrap();
        if MEASURED.iter().any(|m| f.ends_with(m)) {
            let start = trace_pairs(&p, &p.medium).totals.objective;
            assert!(r.totals.objective < start, "{}", f.display());
            continue;
        }
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

/// Removes the fields that measure time (`wall_time_s`, `elapsed_s`, and
/// `tradeoff`'s `time_s`, `trace_time_s`, `reference_fit_time_s`).
fn without_timing(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(m) => {
            m.retain(|k, _| !k.ends_with("time_s") && k != "elapsed_s");
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

/// One command's outputs at `--threads 1` and at `--threads 2`: `args` with
/// `{out}` replaced by a file in a folder of its own per thread count; the
/// output files named in `outputs` (JSON compared without its timings, every
/// other file byte for byte) and, when `stdout` is set, standard output.
fn same_at_one_and_two_threads(args: &[&str], outputs: &[&str], stdout: bool) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let mut seen: Vec<Vec<(String, Vec<u8>)>> = Vec::new();
    for threads in ["1", "2"] {
        let out = dir.path().join(threads);
        std::fs::create_dir(&out).unwrap();
        let args: Vec<String> = args
            .iter()
            .map(|a| {
                if let Some(name) = a.strip_prefix("{out}/") {
                    out.join(name).to_str().unwrap().to_string()
                } else if a.starts_with("problems/") {
                    root.join(a).to_str().unwrap().to_string()
                } else {
                    a.to_string()
                }
            })
            .collect();
        let run = Command::new(env!("CARGO_BIN_EXE_mirage"))
            .args(["--threads", threads])
            .args(&args)
            .output()
            .unwrap();
        // `fit` exits 1 when it misses the problem's target; its result is
        // written all the same, and must be the same.
        assert!(
            matches!(run.status.code(), Some(0 | 1)),
            "{args:?}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        let mut files = Vec::new();
        for name in outputs {
            let bytes =
                std::fs::read(out.join(name)).unwrap_or_else(|e| panic!("{args:?}: {name}: {e}"));
            let bytes = if name.ends_with(".json") {
                let mut v: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
                without_timing(&mut v);
                v.to_string().into_bytes()
            } else {
                bytes
            };
            files.push((name.to_string(), bytes));
        }
        if stdout {
            files.push(("stdout".to_string(), run.stdout));
        }
        seen.push(files);
    }
    for (one, two) in seen[0].iter().zip(&seen[1]) {
        assert!(
            one.1 == two.1,
            "{args:?}: {} differs between 1 and 2 threads",
            one.0
        );
    }
}

/// Every command, on the logistic model (`hot-road`, the `road` scene) and on
/// real air (`hot-road-kelvin`, the `looming` scene, the US 1976 atmosphere).
#[test]
fn every_command_is_identical_with_one_and_two_threads_for_both_kinds() {
    for (problem, scene) in [
        ("problems/hot-road.json", "problems/scenes/road.json"),
        (
            "problems/hot-road-kelvin.json",
            "problems/scenes/looming.json",
        ),
    ] {
        same_at_one_and_two_threads(
            &["trace", problem, "-o", "{out}/t.json"],
            &["t.json"],
            false,
        );
        same_at_one_and_two_threads(
            &["fit", "-q", problem, "-o", "{out}/f.json"],
            &["f.json"],
            false,
        );
        same_at_one_and_two_threads(
            &[
                "tradeoff",
                "--no-fit",
                problem,
                "-o",
                "{out}/d.json",
                "--csv",
                "{out}/d.csv",
            ],
            &["d.json"],
            false,
        );
        same_at_one_and_two_threads(&["rays", problem, "-o", "{out}/r.svg"], &["r.svg"], false);
        same_at_one_and_two_threads(
            &["air", problem, "-o", "{out}/a.json", "--csv", "{out}/a.csv"],
            &["a.json", "a.csv"],
            false,
        );
        same_at_one_and_two_threads(
            &[
                "render",
                "-q",
                "--width",
                "48",
                "--height",
                "27",
                scene,
                "-o",
                "{out}/i.png",
                "--exr",
                "{out}/i.exr",
            ],
            &["i.png", "i.exr"],
            false,
        );
        same_at_one_and_two_threads(
            &[
                "sky",
                scene,
                "-o",
                "{out}/s.exr",
                "--width",
                "32",
                "--height",
                "17",
            ],
            &["s.exr"],
            false,
        );
        same_at_one_and_two_threads(&["air", scene, "-o", "{out}/a.json"], &["a.json"], false);
    }
    same_at_one_and_two_threads(
        &[
            "refraction",
            "problems/atmospheres/us1976.json",
            "--height",
            "2",
            "-o",
            "{out}/r.json",
            "--csv",
            "{out}/r.csv",
        ],
        &["r.json", "r.csv"],
        false,
    );
    same_at_one_and_two_threads(
        &["refractivity", "--temperature", "-40", "--humidity", "0.5"],
        &[],
        true,
    );
}
