//! Exit codes and early checks: `mirage fit` exits 1 when F ends above a target
//! objective the problem or `--target-objective` sets (0 when none is set), the
//! codes are in `--help`, and every command that writes files refuses a bad
//! output path (missing folder, wrong extension, an input, a repeated output)
//! in under a second, naming the flag and the path, before a fit or render
//! that would take much longer.

use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

fn mirage() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mirage"))
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// `problems/NAME.json` edited by `edit`, written into `dir`.
fn problem_in(dir: &Path, name: &str, edit: impl FnOnce(&mut Value)) -> PathBuf {
    let source = root().join(format!("problems/{name}.json"));
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(source).unwrap()).unwrap();
    edit(&mut v);
    let path = dir.join(format!("{name}.json"));
    std::fs::write(&path, v.to_string()).unwrap();
    path
}

fn fit(problem: &Path, out: &Path, extra: &[&str]) -> Output {
    mirage()
        .args(["--threads", "1", "fit", "-q"])
        .arg(problem)
        .arg("-o")
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

fn result(out: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(out).unwrap()).unwrap()
}

#[test]
fn a_fit_above_the_target_the_problem_sets_exits_1_after_writing_its_result() {
    let dir = tempfile::tempdir().unwrap();
    // LM ends near 5e-27 m² on hot-road: a target of 1e-30 is out of reach.
    let p = problem_in(dir.path(), "hot-road", |v| {
        v["solver"] = json!({ "method": "lm", "target_objective": 1e-30 });
    });
    let out = dir.path().join("r.json");
    let o = fit(&p, &out, &[]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let t = text(&o);
    assert!(t.contains("ABOVE target"), "the summary is printed: {t}");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("hot-road.json")
            && err.contains("above the target objective 1e-30 m² (solver.target_objective)"),
        "{err}"
    );
    let r = result(&out);
    assert_eq!(r["solver"]["reached_target"], json!(false));
    assert_eq!(r["solver"]["target_enforced"], json!(true));

    // The flag overrides the file, either way.
    let o = fit(&p, &out, &["--target-objective", "1e-10"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert_eq!(result(&out)["solver"]["reached_target"], json!(true));
    let plain = root().join("problems/hot-road.json");
    let o = fit(&plain, &out, &["--method", "lm", "--target-objective", "0"]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("(--target-objective)"), "{}", text(&o));
}

#[test]
fn a_fit_with_no_target_set_exits_0_even_above_the_default() {
    let dir = tempfile::tempdir().unwrap();
    // One target moved by 10 cm: F cannot reach the default 1e-12 m².
    let p = problem_in(dir.path(), "hot-road", |v| {
        let y = v["pairs"][1]["target"][1].as_f64().unwrap();
        v["pairs"][1]["target"][1] = json!(y + 0.1);
        v["solver"] = json!({ "method": "lm" });
    });
    let out = dir.path().join("r.json");
    let o = fit(&p, &out, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
    assert!(
        text(&o).contains("above the default target"),
        "{}",
        text(&o)
    );
    let r = result(&out);
    assert_eq!(r["solver"]["reached_target"], json!(false));
    assert_eq!(r["solver"]["target_enforced"], json!(false));
    // A bundled problem meets its (default) target and exits 0.
    let o = fit(&root().join("problems/hot-road.json"), &out, &[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o));
}

#[test]
fn a_bad_target_flag_exits_2_naming_it() {
    for bad in ["-1", "nan", "inf", "small"] {
        let o = mirage()
            .args(["fit", "problems/hot-road.json", "--target-objective", bad])
            .current_dir(root())
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{bad}: {}", text(&o));
        assert!(text(&o).contains("--target-objective"), "{}", text(&o));
    }
}

#[test]
fn the_exit_codes_are_in_the_help() {
    let o = mirage().arg("--help").output().unwrap();
    let t = text(&o);
    assert!(o.status.success());
    for line in [
        "Exit codes:",
        "  0  ",
        "  1  ",
        "  2  ",
        "--target-objective",
    ] {
        assert!(
            t.contains(line),
            "{line:?} missing from mirage --help:\n{t}"
        );
    }
    let o = mirage().args(["fit", "--help"]).output().unwrap();
    let t = text(&o);
    assert!(
        t.contains("Exit codes:") && t.contains("F ended above the target objective"),
        "{t}"
    );
    assert!(t.contains("--target-objective"), "{t}");
}

/// Runs `cmd` and asserts it exits 2 within a second with one line that starts
/// `error: FLAG PATH` and says `why`.
fn fails_fast(mut cmd: Command, flag: &str, path: &Path, why: &str) {
    let started = Instant::now();
    let o = cmd.output().unwrap();
    let took = started.elapsed();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{flag}: {}", text(&o));
    assert!(
        took < Duration::from_secs(1),
        "{flag}: refused only after {took:?}"
    );
    let head = format!("error: {flag} {}: ", path.display());
    assert!(err.starts_with(&head), "expected {head:?}, got {err}");
    assert!(err.contains(why), "{why:?} missing: {err}");
    assert!(!err.contains(": -:"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}

/// Asserts that `cmd` is still at work after 1.5 s (then stops it): the work
/// the early check saves.
fn takes_longer(mut cmd: Command) {
    let mut child = cmd
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    let running = child.try_wait().unwrap().is_none();
    let _ = child.kill();
    let _ = child.wait();
    assert!(
        running,
        "the work finished in under 1.5 s: the test proves nothing"
    );
}

/// A fit of many seconds: eight pairs traced with 1 mm RK4 steps, and a target
/// of 0 that keeps `auto` going through its restarts.
fn slow_problem(dir: &Path) -> PathBuf {
    problem_in(dir, "hot-road", |v| {
        v["trace"] = json!({ "method": "rk4", "step": 0.001 });
        v["solver"] = json!({ "method": "auto", "target_objective": 0.0 });
    })
}

#[test]
fn a_fit_refuses_a_bad_output_path_before_it_starts() {
    let dir = tempfile::tempdir().unwrap();
    let p = slow_problem(dir.path());
    let good = dir.path().join("r.json");
    let mut cmd = mirage();
    cmd.args(["fit", "-q"]).arg(&p).arg("-o").arg(&good);
    takes_longer(cmd);

    let missing = dir.path().join("no-such-folder/r.json");
    let mut cmd = mirage();
    cmd.args(["fit", "-q"]).arg(&p).arg("-o").arg(&missing);
    fails_fast(cmd, "-o", &missing, "does not exist");

    let png = dir.path().join("conv.png");
    for (flag, bad, why) in [
        (
            "--plot",
            dir.path().join("missing/conv.png"),
            "does not exist",
        ),
        (
            "--plot",
            dir.path().join("conv.jpg"),
            "expected .png or .svg",
        ),
        (
            "--rays",
            dir.path().join("missing/rays.svg"),
            "does not exist",
        ),
        ("--rays", png.clone(), "the same file as --plot"),
    ] {
        let mut cmd = mirage();
        cmd.args(["fit", "-q"]).arg(&p).arg("-o").arg(&good);
        if flag == "--rays" {
            cmd.arg("--plot").arg(&png);
        }
        cmd.arg(flag).arg(&bad);
        fails_fast(cmd, flag, &bad, why);
    }
    let mut cmd = mirage();
    cmd.args(["fit", "-q"]).arg(&p).arg("-o").arg(&p);
    fails_fast(cmd, "-o", &p, "would overwrite an input");
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(left.len(), 1, "only the problem: {left:?}");
}

#[test]
fn a_render_refuses_a_bad_output_path_before_it_starts() {
    let dir = tempfile::tempdir().unwrap();
    let scene = root().join("problems/scenes/road.json");
    let render = |out: &Path| {
        let mut cmd = mirage();
        cmd.args(["render", "-q", "--width", "800", "--height", "600"])
            .arg(&scene)
            .arg("-o")
            .arg(out);
        cmd
    };
    takes_longer(render(&dir.path().join("road.png")));

    let missing = dir.path().join("renders/road.png");
    fails_fast(render(&missing), "-o", &missing, "the folder");
    let jpg = dir.path().join("road.jpg");
    fails_fast(
        render(&jpg),
        "-o",
        &jpg,
        "expected .png (a render is a raster image)",
    );
    let svg = dir.path().join("road.svg");
    fails_fast(render(&svg), "-o", &svg, "expected .png");
    let exr = dir.path().join("hdr/road.exr");
    let mut cmd = render(&dir.path().join("road.png"));
    cmd.arg("--exr").arg(&exr);
    fails_fast(cmd, "--exr", &exr, "does not exist");
    let not_exr = dir.path().join("road.hdr");
    let mut cmd = render(&dir.path().join("road.png"));
    cmd.arg("--exr").arg(&not_exr);
    fails_fast(cmd, "--exr", &not_exr, "expected .exr");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

#[test]
fn every_other_command_that_writes_files_checks_them_first() {
    let dir = tempfile::tempdir().unwrap();
    let p = slow_problem(dir.path());
    let missing = dir.path().join("missing");
    let scene = root().join("problems/scenes/road.json");
    let cases: Vec<(Vec<&str>, &Path, &str, &str)> = vec![
        (vec!["trace"], &p, "-o", "t.json"),
        (vec!["tradeoff"], &p, "-o", "t.json"),
        (vec!["tradeoff"], &p, "--csv", "t.csv"),
        (vec!["tradeoff"], &p, "--plot", "t.png"),
        (vec!["rays"], &p, "-o", "rays.png"),
        (vec!["air"], &p, "-o", "air.json"),
        (vec!["air"], &p, "--csv", "air.csv"),
        (vec!["air"], &p, "--plot", "air.svg"),
        (vec!["sky"], &scene, "-o", "sky.exr"),
    ];
    for (args, input, flag, name) in cases {
        let bad = missing.join(name);
        let mut cmd = mirage();
        cmd.args(&args).arg(input).arg(flag).arg(&bad);
        fails_fast(cmd, flag, &bad, "does not exist");
    }
    // Extensions each output cannot have.
    for (args, input, flag, name, why) in [
        (vec!["rays"], &p, "-o", "rays.jpg", "expected .png or .svg"),
        (
            vec!["tradeoff"],
            &p,
            "--plot",
            "t.pdf",
            "expected .png or .svg",
        ),
        (vec!["sky"], &scene, "-o", "sky.png", "expected .exr"),
    ] {
        let bad = dir.path().join(name);
        let mut cmd = mirage();
        cmd.args(&args).arg(input).arg(flag).arg(&bad);
        fails_fast(cmd, flag, &bad, why);
    }
    // compare: the heat map and the metrics.
    let img = dir.path().join("a.npy");
    write_npy(&img);
    for (flag, name, why) in [
        ("--diff", "missing/heat.png", "does not exist"),
        (
            "--diff",
            "heat.svg",
            "expected .png (the heat map is a raster image)",
        ),
        ("--json", "missing/m.json", "does not exist"),
    ] {
        let bad = dir.path().join(name);
        let mut cmd = mirage();
        cmd.arg("compare").arg(&img).arg(&img).arg(flag).arg(&bad);
        fails_fast(cmd, flag, &bad, why);
    }
    let mut cmd = mirage();
    cmd.arg("compare")
        .arg(&img)
        .arg(&img)
        .arg("--json")
        .arg(&img);
    fails_fast(cmd, "--json", &img, "would overwrite an input");
}

/// A 4×4 grey image as NumPy's `.npy` (float32, C order, H×W×3).
fn write_npy(path: &Path) {
    let header = "{'descr': '<f4', 'fortran_order': False, 'shape': (4, 4, 3), }";
    let mut h = header.to_string();
    while (10 + h.len() + 1) % 64 != 0 {
        h.push(' ');
    }
    h.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend_from_slice(&(h.len() as u16).to_le_bytes());
    bytes.extend_from_slice(h.as_bytes());
    for _ in 0..48 {
        bytes.extend_from_slice(&0.5f32.to_le_bytes());
    }
    std::fs::write(path, bytes).unwrap();
}
