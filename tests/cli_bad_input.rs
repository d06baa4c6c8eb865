//! Every kind of bad input in `docs/problem-format.md` gets one clear message naming
//! the file and the field, exit code 2, no panic, and no output file.

use std::path::Path;
use std::process::Command;

const GOOD: &str = r#"{
  "name": "t",
  "medium": {
    "scale": 1.0,
    "background": { "n": 1.0, "a": 40.0 },
    "inversion": { "n": 0.3, "a": 2.0, "height": 25.0 }
  },
  "free": ["background.a"],
  "bounds": { "background.a": [1.0, 100.0] },
  "pairs": [
    { "origin": [0.0, 1.6, 0.0], "through": [0.0, 1.0, 900.0], "target": [0.0, 2.0, 900.0] }
  ],
  "trace": { "method": "rk4", "step": 2.0 },
  "solver": { "method": "lm", "max_iterations": 50 }
}"#;

/// Runs `mirage trace` on `text`, asserts failure with code 2 and a message that
/// names the file and contains every one of `expected`, and that no output (nor
/// any temporary file) was left behind.
fn rejects(text: &str, expected: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("problem.json");
    std::fs::write(&input, text).unwrap();
    let output = dir.path().join("out.json");
    let run = Command::new(env!("CARGO_BIN_EXE_mirage"))
        .arg("trace")
        .arg(&input)
        .arg("-o")
        .arg(&output)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(
        run.status.code(),
        Some(2),
        "exit code for {expected:?}; stderr: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(
        stderr.contains(&input.display().to_string()),
        "file not named: {stderr}"
    );
    for e in expected {
        assert!(stderr.contains(e), "{e:?} missing from: {stderr}");
    }
    assert_eq!(
        stderr.trim().lines().count(),
        1,
        "one message, not several: {stderr}"
    );
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(
        left,
        vec![std::ffi::OsString::from("problem.json")],
        "files left behind"
    );
}

fn edit(from: &str, to: &str) -> String {
    assert!(
        GOOD.contains(from),
        "test bug: {from:?} not in the good problem"
    );
    GOOD.replacen(from, to, 1)
}

#[test]
fn the_good_problem_is_accepted() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("problem.json");
    std::fs::write(&input, GOOD).unwrap();
    let output = dir.path().join("out.json");
    let run = Command::new(env!("CARGO_BIN_EXE_mirage"))
        .args([
            "trace".as_ref(),
            input.as_os_str(),
            "-o".as_ref(),
            output.as_os_str(),
        ])
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&output).unwrap()).unwrap();
    assert_eq!(report["pairs"].as_array().unwrap().len(), 1);
    assert!(report["objective"].as_f64().unwrap().is_finite());
    // The report's medium can be fed back as a problem's medium.
    let medium: mirage::medium::LogisticMedium =
        serde_json::from_value(report["medium"].clone()).unwrap();
    assert_eq!(medium.background.unwrap().a, 40.0);
}

#[test]
fn malformed_or_truncated_json() {
    rejects(&GOOD[..GOOD.len() / 2], &["truncated"]);
    rejects(
        &edit(r#""scale": 1.0,"#, r#""scale": ,"#),
        &["medium.scale", "line"],
    );
}

#[test]
fn empty_file() {
    rejects("", &["empty"]);
    rejects("  \n ", &["empty"]);
}

#[test]
fn top_level_not_an_object() {
    rejects("[1, 2, 3]", &["top level", "object"]);
    rejects("42", &["top level"]);
}

#[test]
fn missing_field() {
    rejects(
        &edit(r#""name": "t","#, r#""name": "t", "pairs_": [],"#)
            .replace(r#""pairs": ["#, r#""unused": ["#),
        &["pairs_"],
    );
    let no_pairs: serde_json::Value = {
        let mut v: serde_json::Value = serde_json::from_str(GOOD).unwrap();
        v.as_object_mut().unwrap().remove("pairs");
        v
    };
    rejects(&no_pairs.to_string(), &["pairs", "no point pairs"]);
    rejects(
        &edit(r#""n": 1.0, "a": 40.0"#, r#""n": 1.0"#),
        &["medium.background", "missing field `a`"],
    );
    rejects(
        &edit(r#""origin": [0.0, 1.6, 0.0], "#, ""),
        &["pairs[0]", "missing field `origin`"],
    );
}

#[test]
fn unknown_field_is_named() {
    rejects(
        &edit(r#""height": 25.0"#, r#""heigth": 25.0"#),
        &["medium.inversion", "heigth"],
    );
    rejects(
        &edit(r#""name": "t","#, r#""name": "t", "colour": 1,"#),
        &["colour"],
    );
    rejects(
        &edit(r#""step": 2.0"#, r#""step": 2.0, "tol": 1"#),
        &["trace", "tol"],
    );
}

#[test]
fn wrong_types() {
    rejects(
        &edit(r#""a": 40.0"#, r#""a": "forty""#),
        &["medium.background.a", "invalid type"],
    );
    rejects(
        &edit(r#""origin": [0.0, 1.6, 0.0]"#, r#""origin": [0.0, 1.6]"#),
        &["pairs[0].origin", "length"],
    );
    rejects(
        &edit(r#""free": ["background.a"]"#, r#""free": "background.a""#),
        &["free", "invalid type"],
    );
}

#[test]
fn number_out_of_range() {
    rejects(
        &edit(r#""a": 40.0"#, r#""a": 1e400"#),
        &["medium.background.a", "out of range"],
    );
}

#[test]
fn zero_rate_and_all_amplitudes_zero() {
    rejects(
        &edit(r#""a": 40.0"#, r#""a": 0.0"#),
        &["medium.background.a", "zero"],
    );
    rejects(
        &edit(r#""n": 1.0, "a": 40.0"#, r#""n": 0.0, "a": 40.0"#)
            .replace(r#""n": 0.3"#, r#""n": 0"#),
        &["medium.background.n", "amplitudes are zero"],
    );
}

#[test]
fn scale_that_would_make_n_negative() {
    rejects(
        &edit(r#""scale": 1.0"#, r#""scale": 1000.0"#),
        &["medium.scale"],
    );
}

#[test]
fn degenerate_pairs() {
    rejects(
        &edit(
            r#""target": [0.0, 2.0, 900.0]"#,
            r#""target": [0.0, 50.0, 0.0]"#,
        ),
        &["pairs[0].target", "straight above or below"],
    );
    rejects(
        &edit(
            r#""through": [0.0, 1.0, 900.0]"#,
            r#""through": [0.0, 1.6, 0.0]"#,
        ),
        &["pairs[0].through", "equals"],
    );
    rejects(
        &edit(
            r#""target": [0.0, 2.0, 900.0] }"#,
            r#""target": [0.0, 2.0, 900.0], "weight": -1 }"#,
        ),
        &["pairs[0].weight"],
    );
    for noise in ["0", "-0.01", "1e999", "\"1 cm\""] {
        rejects(
            &edit(
                r#""target": [0.0, 2.0, 900.0] }"#,
                &format!(r#""target": [0.0, 2.0, 900.0], "noise": {noise} }}"#),
            ),
            &["pairs[0].noise"],
        );
    }
}

#[test]
fn free_names_that_are_not_parameters_of_this_medium() {
    rejects(
        &edit(
            r#""free": ["background.a"]"#,
            r#""free": ["hotspots[0].x"]"#,
        )
        .replace(r#""bounds": { "background.a": [1.0, 100.0] },"#, ""),
        &["free[0]", "no hot spots"],
    );
    rejects(
        &edit(
            r#""free": ["background.a"]"#,
            r#""free": ["inversion.heigth"]"#,
        )
        .replace(r#""bounds": { "background.a": [1.0, 100.0] },"#, ""),
        &["free[0]", "inversion.heigth"],
    );
    rejects(
        &edit(
            r#""free": ["background.a"]"#,
            r#""free": ["background.a", "background.a"]"#,
        ),
        &["free[1]", "twice"],
    );
}

#[test]
fn bad_bounds() {
    rejects(
        &edit("[1.0, 100.0]", "[100.0, 1.0]"),
        &["bounds.background.a", "above"],
    );
    rejects(
        &edit("[1.0, 100.0]", "[50.0, 100.0]"),
        &["bounds.background.a", "outside its bounds"],
    );
    rejects(
        &edit(
            r#""bounds": { "background.a""#,
            r#""bounds": { "inversion.a""#,
        ),
        &["bounds.inversion.a", "not a free parameter"],
    );
}

#[test]
fn free_parameters_with_no_pairs() {
    let mut v: serde_json::Value = serde_json::from_str(GOOD).unwrap();
    v["pairs"] = serde_json::json!([]);
    rejects(&v.to_string(), &["pairs", "no point pairs"]);
}

#[test]
fn bad_trace_and_solver_settings() {
    rejects(
        &edit(r#""method": "rk4""#, r#""method": "rk5""#),
        &["trace.method", "rk5"],
    );
    rejects(
        &edit(r#""method": "lm""#, r#""method": "bfgs""#),
        &["solver.method", "bfgs"],
    );
    rejects(
        &edit(r#""step": 2.0"#, r#""step": 0.0"#),
        &["trace.step", "> 0"],
    );
    rejects(&edit(r#""step": 2.0"#, r#""step": -1.0"#), &["trace.step"]);
    rejects(
        &edit(
            r#""method": "rk4", "step": 2.0"#,
            r#""method": "dopri5", "tolerance": -1e-9"#,
        ),
        &["trace.tolerance"],
    );
    rejects(
        &edit(
            r#""method": "rk4", "step": 2.0"#,
            r#""method": "dopri5", "step": 2.0"#,
        ),
        &["trace.step", "not a parameter"],
    );
    rejects(
        &edit(r#""max_iterations": 50"#, r#""max_iterations": -5"#),
        &["solver.max_iterations"],
    );
    rejects(
        &edit(r#""max_iterations": 50"#, r#""simplex_xtol": -1e-9"#),
        &["solver.simplex_xtol", "≥ 0"],
    );
    rejects(
        &edit(r#""max_iterations": 50"#, r#""simplex_ftol": "tight""#),
        &["solver.simplex_ftol"],
    );
    rejects(
        &edit(r#""max_iterations": 50"#, r#""simplex_tol": 1e-9"#),
        &["solver", "simplex_tol", "simplex_xtol"],
    );
}

#[test]
fn missing_input_file() {
    let run = Command::new(env!("CARGO_BIN_EXE_mirage"))
        .args(["trace", "/nonexistent/problem.json"])
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("/nonexistent/problem.json"));
}

#[test]
fn an_input_is_never_overwritten() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("problem.json");
    std::fs::write(&input, GOOD).unwrap();
    let run = Command::new(env!("CARGO_BIN_EXE_mirage"))
        .args([
            "trace".as_ref(),
            input.as_os_str(),
            "-o".as_ref(),
            input.as_os_str(),
        ])
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    assert_eq!(std::fs::read_to_string(&input).unwrap(), GOOD);
    assert!(Path::new(&input).exists());
}

/// The good problem with a real-air medium instead (`docs/air.md`).
fn air(medium: &str) -> String {
    let start = GOOD.find("\"medium\"").unwrap();
    let end = GOOD.find("\"free\"").unwrap();
    format!(
        "{}\"medium\": {medium},\n  \"free\": [\"air.temperature.base\"],\n  {}",
        &GOOD[..start],
        &GOOD[end..]
            .replacen(r#""free": ["background.a"],"#, "", 1)
            .replacen(r#""background.a""#, r#""air.temperature.base""#, 1)
    )
}

#[test]
fn the_good_real_air_problem_is_accepted() {
    let text = air(r#"{"air": {"temperature": {"base": 20.0}}}"#);
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("problem.json");
    std::fs::write(&input, &text).unwrap();
    let run = Command::new(env!("CARGO_BIN_EXE_mirage"))
        .arg("trace")
        .arg(&input)
        .arg("-o")
        .arg(dir.path().join("out.json"))
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
}

#[test]
fn real_air_fields_out_of_range_are_named() {
    let t = |temperature: &str, rest: &str| {
        air(&format!(
            r#"{{"air": {{"temperature": {temperature}{rest}}}}}"#
        ))
    };
    let base = r#"{"base": 20.0}"#;
    for (text, field, words) in [
        (
            t(base, r#", "pressure": 0"#),
            "medium.air.pressure",
            "> 0 Pa",
        ),
        (
            t(base, r#", "pressure": -5"#),
            "medium.air.pressure",
            "> 0 Pa",
        ),
        (
            t(base, r#", "humidity": 1.5"#),
            "medium.air.humidity",
            "[0, 1]",
        ),
        (
            t(base, r#", "humidity": -0.1"#),
            "medium.air.humidity",
            "[0, 1]",
        ),
        (
            t(base, r#", "wavelength": 250"#),
            "medium.air.wavelength",
            "300…1700 nm",
        ),
        (
            t(base, r#", "wavelength": 2000"#),
            "medium.air.wavelength",
            "300…1700 nm",
        ),
        (t(base, r#", "co2": -1"#), "medium.air.co2", "≥ 0"),
        (
            t(base, r#", "refractivity": {"gladstone_dale": -0.08}"#),
            "medium.air.refractivity.gladstone_dale",
            "[0, 1] K",
        ),
        (
            t(base, r#", "refractivity": {"gladstone_dale": 99475020}"#),
            "medium.air.refractivity.gladstone_dale",
            "[0, 1] K",
        ),
        (
            t(base, r#", "pressure": 1e9"#),
            "medium.air.pressure",
            "at most 10000000 Pa",
        ),
        (
            t(r#"{"exponential": {"delta": 3, "scale_height": 0}}"#, ""),
            "medium.air.temperature.exponential.scale_height",
            "> 0 m",
        ),
        (
            t(
                r#"{"inversion": {"delta": 3, "height": 10, "thickness": -1}}"#,
                "",
            ),
            "medium.air.temperature.inversion.thickness",
            "> 0 m",
        ),
        (
            t(r#"{"table": [[0, 10], [5, 9], [5, 8]]}"#, ""),
            "medium.air.temperature.table[2][0]",
            "strictly increasing",
        ),
        (
            t(r#"{"table": [[0, 10]]}"#, ""),
            "medium.air.temperature.table",
            "at least two rows",
        ),
        (
            t(r#"{"table": [[0, 10], [5, -160]]}"#, ""),
            "medium.air.temperature.table[1][1]",
            "colder than -150",
        ),
        (
            t(r#"{"base": 10, "table": [[0, 10], [5, 9]]}"#, ""),
            "medium.air.temperature.table",
            "remove `base`",
        ),
        (
            t(r#"{"base": 15, "lapse": -0.03}"#, ""),
            "medium.air.temperature.lapse",
            "colder than -150",
        ),
        (
            t(r#"{"lapse": "steep"}"#, ""),
            "medium.air.temperature.lapse",
            "\"standard\"",
        ),
        (
            t(base, r#", "refractivity": "ciddor1996""#),
            "medium.air.refractivity",
            "unknown variant",
        ),
        (
            t(base, r#", "humdity": 0.5"#),
            "medium.air",
            "unknown field `humdity`",
        ),
    ] {
        rejects(&text, &[field, words]);
    }
}

#[test]
fn real_air_hot_spots_are_checked_by_name() {
    let spot = |fields: &str| {
        air(&format!(
            r#"{{"air": {{"temperature": {{"base": 20.0}}}}, "hotspots": [{{"x": 0, "z": 300, "radius": 50, {fields}}}]}}"#
        ))
    };
    for (text, field, words) in [
        (
            spot(r#""delta": 10, "scale_height": 0"#),
            "medium.hotspots[0].scale_height",
            "> 0 m",
        ),
        (
            spot(r#""delta": 10, "scale_height": 0.3, "edge": 0"#),
            "medium.hotspots[0].edge",
            "> 0",
        ),
        (spot(r#""delta": 10"#), "medium.hotspots[0]", "scale_height"),
        (
            spot(r#""delta": 10, "scale_height": 0.3, "n": -2"#),
            "medium.hotspots[0]",
            "unknown field `n`",
        ),
    ] {
        rejects(&text, &[field, words]);
    }
    // Hot spots before `air`: the kind is not known yet when they are read.
    let early = GOOD.replacen(
        r#""scale": 1.0,"#,
        r#""hotspots": [{"x": 0, "z": 300, "radius": 50, "delta": 10, "scale_height": 0.3}],"#,
        1,
    );
    rejects(&early, &["medium.hotspots[0].delta", "real air"]);
    // A logistic field beside `air`.
    rejects(
        &air(r#"{"air": {"temperature": {"base": 20.0}}, "scale": 1.0}"#),
        &["medium.scale", "either the logistic model or real air"],
    );
}

#[test]
fn real_air_parameters_that_do_not_exist_are_named() {
    let text = air(r#"{"air": {"temperature": {"base": 20.0}}}"#)
        .replacen(
            r#""free": ["air.temperature.base"]"#,
            r#""free": ["air.temperature.exponential.delta"]"#,
            1,
        )
        .replacen(
            r#""bounds": { "air.temperature.base": [1.0, 100.0] },"#,
            "",
            1,
        );
    rejects(
        &text,
        &["air.temperature.exponential.delta", "no `exponential`"],
    );
}

#[test]
fn pair_wavelengths_out_of_range_or_on_a_logistic_medium() {
    let pair = r#""target": [0.0, 2.0, 900.0] }"#;
    rejects(
        &edit(
            pair,
            r#""target": [0.0, 2.0, 900.0], "wavelength": 550.0 }"#,
        ),
        &["pairs[0].wavelength", "real air"],
    );
    let air = GOOD
        .replacen(
            r#""scale": 1.0,
    "background": { "n": 1.0, "a": 40.0 },
    "inversion": { "n": 0.3, "a": 2.0, "height": 25.0 }"#,
            r#""air": { "temperature": { "base": 10.0 } }"#,
            1,
        )
        .replacen(r#""background.a""#, r#""air.temperature.base""#, 2);
    assert!(
        air.contains(r#""air""#),
        "test bug: the medium was not replaced"
    );
    for nm in ["200.0", "1800.0", "-550.0"] {
        rejects(
            &air.replacen(
                pair,
                &format!(r#""target": [0.0, 2.0, 900.0], "wavelength": {nm} }}"#),
                1,
            ),
            &["pairs[0].wavelength", "300…1700 nm"],
        );
    }
}

#[test]
fn dispersion_on_a_logistic_scene() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("scene.json");
    std::fs::write(
        &input,
        r#"{ "camera": { "position": [0, 2, 0], "look_at": [0, 2, 100], "vertical_fov": 10, "width": 16, "height": 9 },
             "medium": { "scale": 1.0, "background": { "n": 1.0, "a": 40.0 } },
             "dispersion": true }"#,
    )
    .unwrap();
    let output = dir.path().join("out.png");
    let run = Command::new(env!("CARGO_BIN_EXE_mirage"))
        .arg("render")
        .arg(&input)
        .arg("-o")
        .arg(&output)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains(&input.display().to_string()), "{stderr}");
    assert!(
        stderr.contains("dispersion") && stderr.contains("real air"),
        "{stderr}"
    );
    assert!(!output.exists());
}

#[test]
fn a_round_earth_that_is_not_one() {
    let earth = |e: &str| edit(r#""solver": {"#, &format!(r#""earth": {e}, "solver": {{"#));
    // The good problem over the earth is accepted (traced, exit 0).
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("problem.json");
    std::fs::write(&input, earth(r#"{"radius": 6371000.0}"#)).unwrap();
    let run = Command::new(env!("CARGO_BIN_EXE_mirage"))
        .arg("trace")
        .arg(&input)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    rejects(&earth(r#"{"radius": 0.0}"#), &["earth.radius", "positive"]);
    rejects(
        &earth(r#"{"radius": -6371000.0}"#),
        &["earth.radius", "positive"],
    );
    rejects(
        &earth(r#"{"radius": 500.0}"#),
        &["earth.radius", "at least 1000 m"],
    );
    rejects(
        &earth(r#"{"radius": "big"}"#),
        &["earth.radius", "invalid type"],
    );
    rejects(
        &earth(r#"{"radius": 6371000.0, "centre": [0, 0, 0]}"#),
        &["earth", "unknown field `centre`"],
    );
    rejects(&earth(r#"{}"#), &["earth", "missing field `radius`"]);
    rejects(&earth("6371000.0"), &["earth", "invalid type"]);
    // An observer below the sphere: 1 km out, the sphere is 7.8 cm above
    // the tangent plane's y = -0.0785.
    let below = earth(r#"{"radius": 6371000.0}"#).replace(
        r#""origin": [0.0, 1.6, 0.0]"#,
        r#""origin": [1000.0, -0.1, 0.0]"#,
    );
    rejects(&below, &["pairs[0].origin", "below the ground", "sphere"]);
}

/// Renders the scene `text` (written to a temporary `scene.json`) to a PNG:
/// the exit code, stderr, the scene's path, and whether an image was
/// written.
fn render(text: &str) -> (Option<i32>, String, std::path::PathBuf, bool) {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("scene.json");
    std::fs::write(&input, text).unwrap();
    let output = dir.path().join("out.png");
    let run = Command::new(env!("CARGO_BIN_EXE_mirage"))
        .arg("render")
        .arg(&input)
        .arg("-o")
        .arg(&output)
        .arg("--quiet")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr).into_owned();
    (run.status.code(), stderr, input, output.exists())
}

#[test]
fn a_scene_over_a_round_earth_that_is_not_one() {
    let scene = |earth: &str| {
        format!(
            r#"{{ "camera": {{ "position": [0, 2, 0], "look_at": [0, 2, 100], "vertical_fov": 10, "width": 16, "height": 9 }},
                 "medium": {{ "scale": 1.0, "background": {{ "n": 1.0, "a": 40.0 }} }},
                 "ground": {{ "albedo": [0.2, 0.3, 0.4] }},
                 "earth": {earth} }}"#
        )
    };
    // The good scene over the earth renders.
    let (code, stderr, _, written) = render(&scene(r#"{"radius": 6371000.0}"#));
    assert_eq!(code, Some(0), "{stderr}");
    assert!(written);
    for (earth, expected) in [
        (r#"{"radius": 0.0}"#, &["earth.radius", "positive"][..]),
        (r#"{"radius": 500.0}"#, &["earth.radius", "at least 1000 m"]),
        (r#"{"radius": "big"}"#, &["earth.radius", "invalid type"]),
        (
            r#"{"radius": 6371000.0, "centre": [0, 0, 0]}"#,
            &["earth", "unknown field `centre`"],
        ),
        ("{}", &["earth", "missing field `radius`"]),
        ("6371000.0", &["earth", "invalid type"]),
    ] {
        let (code, stderr, input, written) = render(&scene(earth));
        assert_eq!(code, Some(2), "{earth}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(stderr.contains(&input.display().to_string()), "{stderr}");
        for e in expected {
            assert!(stderr.contains(e), "{e:?} missing from: {stderr}");
        }
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        assert!(!written, "{earth}: an image was written");
    }
}

#[test]
fn bad_growth_settings_are_named() {
    let grow = |extra: &str| {
        edit(
            r#""max_iterations": 50"#,
            &format!(r#""max_iterations": 50, {extra}"#),
        )
    };
    rejects(
        &grow(r#""grow": true, "noise": 0"#),
        &["solver.noise", "> 0"],
    );
    rejects(
        &grow(r#""grow": true, "noise": -0.01"#),
        &["solver.noise", "> 0"],
    );
    rejects(
        &grow(r#""grow": true, "max_terms": 0"#),
        &["solver.max_terms", "at least 1"],
    );
    rejects(&grow(r#""noise": 0.01"#), &["solver.noise", "grow"]);
    rejects(
        &grow(r#""grow": false, "max_terms": 2"#),
        &["solver.max_terms", "grow"],
    );
    rejects(
        &edit(
            r#""method": "lm""#,
            r#""method": "nelder-mead", "grow": true"#,
        ),
        &["solver.grow", "nelder-mead"],
    );
    // Real air grows; a logistic medium with no term does not.
    rejects(
        &no_term().replacen(
            r#""max_iterations": 50"#,
            r#""max_iterations": 50, "grow": true"#,
            1,
        ),
        &["solver.grow", "at least one term"],
    );
}

/// The good problem with a logistic medium of no term (nothing to grow from).
fn no_term() -> String {
    GOOD.replacen(
        r#""scale": 1.0,
    "background": { "n": 1.0, "a": 40.0 },
    "inversion": { "n": 0.3, "a": 2.0, "height": 25.0 }"#,
        r#""scale": 1.0"#,
        1,
    )
    .replacen(
        r#""free": ["background.a"],
  "bounds": { "background.a": [1.0, 100.0] },"#,
        "",
        1,
    )
}

#[test]
fn bad_growth_flags_exit_2_naming_them() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("problem.json");
    std::fs::write(&input, GOOD).unwrap();
    let bare_input = dir.path().join("bare.json");
    std::fs::write(&bare_input, no_term()).unwrap();
    let output = dir.path().join("out.json");
    let cases: [(&Path, &[&str], &str); 8] = [
        (&input, &["--grow", "--noise", "0"], "--noise"),
        (&input, &["--grow", "--noise", "-0.001"], "--noise"),
        (&input, &["--grow", "--noise", "nan"], "--noise"),
        (&input, &["--grow", "--max-terms", "0"], "--max-terms"),
        (&input, &["--noise", "0.01"], "--noise"),
        (&input, &["--max-terms", "2"], "--max-terms"),
        (&input, &["--grow", "--method", "nelder-mead"], "--method"),
        (&bare_input, &["--grow"], "--grow"),
    ];
    for (file, args, flag) in cases {
        let run = Command::new(env!("CARGO_BIN_EXE_mirage"))
            .arg("fit")
            .arg(file)
            .args(args)
            .arg("-o")
            .arg(&output)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.contains(flag),
            "{args:?}: {flag} not named: {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(!output.exists(), "{args:?}: an output was written");
    }
}

/// Runs `mirage refraction` on `text` with `args` (and `-o`, `--csv`,
/// `--plot` into a fresh folder), asserts exit code 2, one message holding
/// every one of `expected`, and no file written.
fn refraction_rejects(text: &str, args: &[&str], expected: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("air.json");
    std::fs::write(&input, text).unwrap();
    let run = Command::new(env!("CARGO_BIN_EXE_mirage"))
        .arg("refraction")
        .arg(&input)
        .args(args)
        .arg("-o")
        .arg(dir.path().join("r.json"))
        .arg("--csv")
        .arg(dir.path().join("r.csv"))
        .arg("--plot")
        .arg(dir.path().join("r.png"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    for e in expected {
        assert!(stderr.contains(e), "{e:?} missing from: {stderr}");
    }
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, vec![std::ffi::OsString::from("air.json")]);
}

#[test]
fn refraction_refuses_bad_input_by_name() {
    let good = air(r#"{"air": {"temperature": {"base": 15.0, "lapse": "standard"}}}"#);
    refraction_rejects(
        GOOD,
        &["--height", "2"],
        &["air.json", "medium", "real air"],
    );
    refraction_rejects(&good, &["--height", "-1"], &["--height", "≥ 0"]);
    refraction_rejects(&good, &["--height", "nan"], &["--height"]);
    refraction_rejects(&good, &["--height", "90000"], &["--height", "top"]);
    refraction_rejects(
        &good,
        &["--height", "2", "--elevations", "0,95"],
        &["--elevations", "−90…90"],
    );
    refraction_rejects(
        &good,
        &["--height", "2", "--elevations", "0,x"],
        &["--elevations"],
    );
    refraction_rejects(
        &good,
        &["--height", "2", "--earth-radius", "500"],
        &["--earth-radius", "at least 1000"],
    );
    refraction_rejects("{ not json", &["--height", "2"], &["air.json"]);
    refraction_rejects(
        &good.replacen(
            "\"medium\"",
            "\"earth\": {\"radius\": 10.0},\n  \"medium\"",
            1,
        ),
        &["--height", "2"],
        &["earth.radius", "at least 1000"],
    );
    // A missing file is named.
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nowhere.json");
    let run = Command::new(env!("CARGO_BIN_EXE_mirage"))
        .arg("refraction")
        .arg(&missing)
        .args(["--height", "2"])
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&run.stderr).contains("nowhere.json"));
}

/// A problem over the round earth from a site, one pair given by places and
/// angles: `site`, `origin`, `target`, `elevation`, `azimuth` as given.
fn geo(site: &str, pair: &str) -> String {
    format!(
        r#"{{
  "name": "g",
  {site}
  "medium": {{ "scale": 1.0, "background": {{ "n": 1.0, "a": 40.0 }} }},
  "pairs": [ {pair} ],
  "trace": {{ "method": "rk4", "step": 20.0 }}
}}"#
    )
}

const SITE: &str = r#""site": { "latitude": 43.5, "longitude": -70.2, "height": 23.42 },"#;
const PLACE: &str = r#"{ "latitude": 43.4, "longitude": -70.25, "height": 24.38 }"#;

#[test]
fn geographic_fields_are_checked_by_name() {
    // The good one first: it traces.
    let good = geo(
        SITE,
        &format!(r#"{{ "origin": [0, 23.42, 0], "elevation": "-0°02'47\"", "target": {PLACE} }}"#),
    );
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("good.json");
    std::fs::write(&input, &good).unwrap();
    let run = Command::new(env!("CARGO_BIN_EXE_mirage"))
        .arg("trace")
        .arg(&input)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );

    let pair = |extra: &str| format!(r#"{{ "origin": [0, 23.42, 0], {extra} "target": {PLACE} }}"#);
    for (text, expected) in [
        (
            geo(
                r#""site": { "latitude": 91, "longitude": 0 },"#,
                &pair(r#""elevation": 0,"#),
            ),
            vec!["site.latitude", "[-90, 90]", "91"],
        ),
        (
            geo(
                r#""site": { "latitude": 10, "longitude": 400 },"#,
                &pair(r#""elevation": 0,"#),
            ),
            vec!["site.longitude", "400"],
        ),
        (
            geo(
                r#""site": { "latitude": 10, "longitude": 1, "height": 1e9 },"#,
                &pair(r#""elevation": 0,"#),
            ),
            vec!["site.height"],
        ),
        (
            geo(
                r#""site": { "latitude": 10, "longitude": 1, "heigth": 3 },"#,
                &pair(r#""elevation": 0,"#),
            ),
            vec!["site", "heigth"],
        ),
        (
            geo("", &pair(r#""elevation": 0,"#)),
            vec!["pairs[0].target", "needs a `site`"],
        ),
        (
            geo(
                SITE,
                r#"{ "origin": [0, 23.42, 0], "elevation": 0, "target": { "latitude": -91, "longitude": 0 } }"#,
            ),
            vec!["pairs[0].target.latitude", "[-90, 90]"],
        ),
        (
            geo(SITE, &pair(r#""through": [0, 20, 900], "elevation": 0,"#)),
            vec!["pairs[0].elevation", "not both"],
        ),
        (
            geo(SITE, &pair(r#""through": [0, 20, 900], "azimuth": 10,"#)),
            vec!["pairs[0].azimuth", "not both"],
        ),
        (
            geo(SITE, &pair(r#""azimuth": 10,"#)),
            vec!["pairs[0].elevation", "needs an `elevation`"],
        ),
        (geo(SITE, &pair("")), vec!["pairs[0].through", "missing"]),
        (
            geo(SITE, &pair(r#""elevation": "-0°02'x47\"","#)),
            vec!["pairs[0].elevation", "is not an angle"],
        ),
        (
            geo(SITE, &pair(r#""elevation": "1°75'","#)),
            vec!["pairs[0].elevation", "minutes must lie in [0, 60)"],
        ),
        (
            geo(SITE, &pair(r#""elevation": 90,"#)),
            vec!["pairs[0].elevation", "strictly between -90 and 90"],
        ),
        (
            geo(SITE, &pair(r#""elevation": true,"#)),
            vec!["pairs[0].elevation", "an angle"],
        ),
        (
            geo(
                SITE,
                r#"{ "origin": [0, 23.42], "elevation": 0, "target": [0, 1, 900] }"#,
            ),
            vec!["pairs[0].origin"],
        ),
        (
            geo(
                r#""residual": "angles", "site": { "latitude": 10, "longitude": 1 },"#,
                &pair(r#""elevation": 0,"#),
            ),
            vec!["residual", "angles"],
        ),
    ] {
        rejects(&text, &expected.to_vec());
    }
}

/// A scene with geographic fields: `camera.position`/`look_at` as places,
/// `elevation`/`azimuth` for the view, objects standing `at` a place.
fn geo_scene(site: &str, camera: &str, objects: &str) -> String {
    format!(
        r#"{{ {site}
             "camera": {{ {camera}, "vertical_fov": 2, "width": 16, "height": 9 }},
             "medium": {{ "air": {{ "temperature": {{ "base": 15, "lapse": -0.0065 }} }} }},
             "ground": {{ "albedo": [0.2, 0.3, 0.4] }},
             "objects": [ {objects} ],
             "trace": {{ "step": 200, "max_distance": 30000 }} }}"#
    )
}

#[test]
fn geographic_scene_fields_are_checked_by_name() {
    const SITE: &str = r#""site": { "latitude": 43.28, "longitude": 5.37, "height": 160 },"#;
    const CAMERA: &str = r#""position": [0, 164, 0], "elevation": "-0°10'", "azimuth": 250"#;
    const HILL: &str = r#"{ "albedo": [0.5, 0.5, 0.5], "at": { "latitude": 43.25, "longitude": 5.1 },
                            "shape": { "type": "sphere", "center": [0, -500, 0], "radius": 800 } }"#;
    let (code, stderr, _, written) = render(&geo_scene(SITE, CAMERA, HILL));
    assert_eq!(code, Some(0), "{stderr}");
    assert!(written);
    let place = r#"{ "latitude": 43.2, "longitude": 5.0, "height": 10 }"#;
    for (text, expected) in [
        (
            geo_scene(
                r#""site": { "latitude": 91, "longitude": 5 },"#,
                CAMERA,
                HILL,
            ),
            vec!["site.latitude", "91"],
        ),
        (
            geo_scene("", CAMERA, HILL),
            vec!["objects[0].at", "needs a `site`"],
        ),
        (
            geo_scene(
                "",
                &format!(r#""position": [0, 2, 0], "look_at": {place}"#),
                "",
            ),
            vec!["camera.look_at", "needs a `site`"],
        ),
        (
            geo_scene(
                SITE,
                &format!(r#""position": {place}, "look_at": {place}"#),
                "",
            ),
            vec!["camera.position", "must differ"],
        ),
        (
            geo_scene(
                SITE,
                r#""position": { "latitude": -90.5, "longitude": 5 }, "elevation": 0, "azimuth": 0"#,
                "",
            ),
            vec!["camera.position.latitude", "[-90, 90]"],
        ),
        (
            geo_scene(
                SITE,
                r#""position": { "latitude": 43.2, "longitude": 5, "heigth": 3 }, "elevation": 0, "azimuth": 0"#,
                "",
            ),
            vec!["camera.position", "heigth"],
        ),
        (
            geo_scene(
                SITE,
                &format!(r#""position": [0, 164, 0], "look_at": {place}, "elevation": 0"#),
                "",
            ),
            vec!["camera.elevation", "not both"],
        ),
        (
            geo_scene(SITE, r#""position": [0, 164, 0], "elevation": 0"#, ""),
            vec!["camera.azimuth", "missing"],
        ),
        (
            geo_scene(SITE, r#""position": [0, 164, 0], "azimuth": 0"#, ""),
            vec!["camera.elevation", "missing"],
        ),
        (
            geo_scene(SITE, r#""position": [0, 164, 0]"#, ""),
            vec!["camera.look_at", "missing"],
        ),
        (
            geo_scene(
                SITE,
                r#""position": [0, 164, 0], "elevation": "1°75'", "azimuth": 0"#,
                "",
            ),
            vec!["camera.elevation", "minutes must lie in [0, 60)"],
        ),
        (
            geo_scene(
                SITE,
                r#""position": [0, 164, 0], "elevation": 90, "azimuth": 0"#,
                "",
            ),
            vec!["camera.elevation", "strictly between -90 and 90"],
        ),
        (
            geo_scene(
                SITE,
                CAMERA,
                r#"{ "albedo": [0.5, 0.5, 0.5], "at": { "latitude": 43.2, "longitude": 999 },
                     "shape": { "type": "sphere", "center": [0, 0, 0], "radius": 8 } }"#,
            ),
            vec!["objects[0].at.longitude", "999"],
        ),
        (
            geo_scene(
                SITE,
                CAMERA,
                r#"{ "albedo": [0.5, 0.5, 0.5], "at": [1, 2],
                     "shape": { "type": "sphere", "center": [0, 0, 0], "radius": 8 } }"#,
            ),
            vec!["objects[0].at"],
        ),
        (
            geo_scene(
                SITE,
                CAMERA,
                r#"{ "albedo": [0.5, 0.5, 0.5], "at": [0, 0, 1000],
                     "shape": { "type": "sphere", "center": [0, 0, 0], "radius": -8 } }"#,
            ),
            vec!["objects[0].shape.radius"],
        ),
    ] {
        let (code, stderr, input, written) = render(&text);
        assert_eq!(code, Some(2), "{expected:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(stderr.contains(&input.display().to_string()), "{stderr}");
        for e in &expected {
            assert!(stderr.contains(e), "{e:?} missing from: {stderr}");
        }
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        assert!(!written, "{expected:?}: an image was written");
    }
}
