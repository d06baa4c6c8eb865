//! mirage's albedo renders against Mitsuba 3 references
//! (`notebooks/validation/run.py`): straight rays against Mitsuba's stock
//! integrators, curved rays (inferior, superior, hot spot) against the custom
//! curved-ray integrator. Fails when a case has fewer than 99 % of its pixels
//! within 0.05 or a PSNR below 35 dB, or when Mitsuba's lookup of the exported
//! sky map disagrees with the sky.

mod common;

use std::process::Command;

#[test]
fn renders_match_mitsuba_references() {
    let Some(python) = common::python_or_skip("Mitsuba 3 validation suite") else {
        return;
    };
    let out = tempfile::tempdir().unwrap();
    let run = Command::new(python)
        .arg(common::root().join("notebooks/validation/run.py"))
        .arg("--mirage")
        .arg(env!("CARGO_BIN_EXE_mirage"))
        .arg("--out")
        .arg(out.path())
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    common::loud(&format!("Mitsuba 3 validation:\n{stdout}{stderr}"));
    assert!(
        run.status.success(),
        "validation failed:\n{stdout}\n{stderr}"
    );
    // Every case ran and reported its metrics.
    let results: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.path().join("results.json")).unwrap())
            .unwrap();
    let cases: Vec<&str> = results
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["case"].as_str().unwrap())
        .collect();
    assert_eq!(
        cases,
        [
            "straight",
            "straight-custom",
            "straight-physical",
            "inferior",
            "superior",
            "hotspot"
        ]
    );
    for m in results.as_array().unwrap() {
        assert!(m["passed"].as_bool().unwrap(), "{m}");
        assert!(m["share_over"].as_f64().unwrap() <= 0.01, "{m}");
    }
}
