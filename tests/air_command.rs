//! `mirage air` (docs/air.md, "`mirage air`"): the profile of real air and the
//! implied air of a logistic medium, written as JSON, CSV and a figure; bad
//! flags refused naming the flag, without writing anything; and the ray
//! diagram of a real-air problem (δ and T panels).

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn problem(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("problems")
        .join(name)
}

fn mirage(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mirage"))
        .args(args)
        .output()
        .unwrap()
}

/// Runs `mirage air FILE -o JSON --plot PNG --csv CSV` and reads the JSON.
fn run_air(file: &str, dir: &Path) -> (Value, String) {
    let (json, png, csv) = (
        dir.join("air.json"),
        dir.join("air.png"),
        dir.join("air.csv"),
    );
    let run = mirage(&[
        "air",
        problem(file).to_str().unwrap(),
        "-o",
        json.to_str().unwrap(),
        "--plot",
        png.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr).to_string();
    assert!(run.status.success(), "{file}: {stderr}");
    let img = image::open(&png).expect("the PNG decodes").to_rgb8();
    let colours: std::collections::HashSet<_> = img.pixels().map(|p| p.0).collect();
    assert!(colours.len() > 8, "the figure looks blank");
    assert!(std::fs::metadata(&png).unwrap().len() > 10_000);
    let csv = std::fs::read_to_string(&csv).unwrap();
    let value: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(
        csv.lines().count(),
        value["rows"].as_array().unwrap().len() + 1
    );
    (value, stderr)
}

fn rows(v: &Value) -> &Vec<Value> {
    v["rows"].as_array().unwrap()
}

fn f(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} not a number: {v}"))
}

#[test]
fn real_air_reports_its_own_temperature_and_pressure() {
    let dir = tempfile::tempdir().unwrap();
    let (v, _) = run_air("hot-road-kelvin.json", dir.path());
    assert_eq!(v["medium_kind"], "air");
    assert_eq!(v["implied"], false);
    assert_eq!(v["at"], serde_json::json!([0.0, 160.0]));
    assert!(v["warnings"].as_array().unwrap().is_empty());
    let rows = rows(&v);
    assert!(rows.len() > 100);
    let ground = &rows[0];
    assert_eq!(f(ground, "h"), 0.0);
    // base 30 °C + hotspots[0].delta 18 K at the centre (rim weight 1 − σ(−30)
    // ≈ 1 − 9e-14); the lapse adds nothing at h = 0.
    assert!((f(ground, "temperature_c") - 48.0).abs() < 1e-6, "{ground}");
    assert!((f(ground, "pressure_pa") - 101_325.0).abs() < 1e-6);
    assert!(ground.get("excess_k").is_none());
    for r in rows {
        for key in ["h", "temperature_c", "pressure_pa", "delta", "dn_dh"] {
            assert!(f(r, key).is_finite(), "{r}");
        }
    }
    // The hot layer (0.6 m) lies well inside the default 20 m.
    assert_eq!(f(&v, "top"), 20.0);
    let top = rows.last().unwrap();
    assert!(f(top, "temperature_c") < 30.0 && f(top, "pressure_pa") < 101_325.0);
}

#[test]
fn a_logistic_medium_reports_its_implied_air() {
    let dir = tempfile::tempdir().unwrap();
    let (v, stderr) = run_air("hot-road.json", dir.path());
    assert_eq!(v["medium_kind"], "logistic");
    assert_eq!(v["implied"], true);
    let rows = rows(&v);
    let excess = f(&rows[0], "excess_k");
    assert!(excess.is_finite() && excess > 0.0, "{}", rows[0]);
    // Pinned to the standard atmosphere at the top.
    assert!(f(rows.last().unwrap(), "excess_k").abs() < 1e-9);
    // hot-road's implied air is plausible: about 30 K of excess, tens of K/m.
    assert!(v["warnings"].as_array().unwrap().is_empty(), "{v}");
    assert!(!stderr.contains("warning"), "{stderr}");
}

#[test]
fn bad_flags_exit_2_naming_the_flag_and_write_nothing() {
    for (flag, value) in [("--top", "-1"), ("--at", "1"), ("--top", "0")] {
        let dir = tempfile::tempdir().unwrap();
        let json = dir.path().join("air.json");
        let png = dir.path().join("air.png");
        let run = mirage(&[
            "air",
            problem("hot-road.json").to_str().unwrap(),
            "-o",
            json.to_str().unwrap(),
            "--plot",
            png.to_str().unwrap(),
            flag,
            value,
        ]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{flag} {value}: {stderr}");
        assert!(stderr.contains(flag), "{stderr}");
        assert!(!json.exists() && !png.exists());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }
}

#[test]
fn ray_diagram_of_real_air_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rays.png");
    let run = mirage(&[
        "rays",
        problem("hot-road-kelvin.json").to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let img = image::open(&out).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (1400, 700));
}
