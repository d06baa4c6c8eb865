//! The previewer's window under Xvfb: it opens, renders frames with its
//! panels, saves a screenshot and exits cleanly; and once its view is still it
//! accumulates samples, then shows the scene's veiling glare.
//!
//! Needs `xvfb-run` (Debian `xvfb xauth`) and a GPU adapter (lavapipe will
//! do). Without them the test prints a loud SKIPPED line and passes, unless
//! `MIRAGE_REQUIRE_GPU=1` (set by `.ci/run`), where it fails.
#![cfg(feature = "preview")]

use std::path::Path;
use std::process::Command;

/// Writes to the process's stderr directly, past the test harness's capture,
/// so that a skip is seen in a plain `cargo test`.
fn loud(message: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "\n{message}\n");
}

fn have(program: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {program} >/dev/null 2>&1")])
        .status()
        .is_ok_and(|s| s.success())
}

/// Whether the window can be tested here: `false` (after a loud SKIPPED
/// line) when xvfb-run or a GPU adapter is missing, a failure instead when
/// `MIRAGE_REQUIRE_GPU=1`.
fn can_run(test: &str) -> bool {
    let required = std::env::var("MIRAGE_REQUIRE_GPU").is_ok_and(|v| v == "1");
    if !have("xvfb-run") {
        assert!(!required, "MIRAGE_REQUIRE_GPU=1 but xvfb-run is missing");
        loud(&format!(
            "*** SKIPPED {test}: no xvfb-run (apt-get install xvfb xauth) ***"
        ));
        return false;
    }
    if let Err(e) = mirage::preview::gpu::Gpu::new() {
        assert!(!required, "MIRAGE_REQUIRE_GPU=1 but {e}");
        loud(&format!("*** SKIPPED {test}: {e} ***"));
        return false;
    }
    true
}

/// Runs `mirage preview` in a window under Xvfb with `args`, saving the last
/// frame to `shot`; asserts that it exits cleanly and returns its stderr.
fn run_window(dir: &Path, input: &str, args: &[&str], shot: &Path) -> String {
    let input = Path::new(env!("CARGO_MANIFEST_DIR")).join(input);
    let run = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1024x768x24"])
        .arg(env!("CARGO_BIN_EXE_mirage"))
        .arg("preview")
        .args(args)
        .arg("--screenshot")
        .arg(shot)
        .arg(&input)
        .env(
            "XDG_RUNTIME_DIR",
            std::env::var("XDG_RUNTIME_DIR").unwrap_or_else(|_| dir.display().to_string()),
        )
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr).into_owned();
    assert!(
        run.status.success(),
        "status {:?}\nstdout: {}\nstderr: {stderr}",
        run.status,
        String::from_utf8_lossy(&run.stdout),
    );
    stderr
}

#[test]
fn the_window_opens_renders_frames_and_exits_cleanly() {
    if !can_run("the_window_opens_renders_frames_and_exits_cleanly") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("window.png");
    run_window(
        dir.path(),
        "problems/hot-road.json",
        &["--frames", "5", "--width", "800", "--height", "450"],
        &shot,
    );
    let img = image::open(&shot).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (800, 450));
    // The picture (left) and the panel (right) differ: something was drawn in both.
    let left = img.get_pixel(100, 100);
    let right = img.get_pixel(780, 440);
    assert_ne!(left, right);
    let distinct: std::collections::HashSet<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    assert!(distinct.len() > 50, "only {} colours", distinct.len());
}

/// The source pixels the window reported glaring, if it did.
fn glare_sources(stderr: &str) -> Option<usize> {
    stderr
        .lines()
        .find_map(|l| l.strip_prefix("glare: "))
        .and_then(|rest| rest.split_whitespace().next())
        .map(|n| n.parse().unwrap())
}

#[test]
fn the_window_shows_the_glare_once_the_view_is_still() {
    if !can_run("the_window_shows_the_glare_once_the_view_is_still") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // Glare waits for the accumulation of a still view: two samples here.
    let size = [
        "--frames", "6", "--width", "480", "--height", "270", "--spp", "2",
    ];
    let (with, without) = (dir.path().join("glare.png"), dir.path().join("none.png"));
    let scene = "problems/scenes/road-sunset.json";
    let stderr = run_window(dir.path(), scene, &size, &with);
    let sources = glare_sources(&stderr);
    eprintln!("glare sources in the window: {sources:?}");
    assert!(sources.is_some_and(|n| n > 0), "no glare: {stderr}");
    assert!(
        stderr.contains("accumulated: 2 samples per pixel"),
        "no accumulation: {stderr}"
    );
    let mut args = size.to_vec();
    args.push("--no-glare");
    let stderr = run_window(dir.path(), scene, &args, &without);
    assert_eq!(glare_sources(&stderr), None, "{stderr}");
    // The sun is in the frame: its glare veils the picture (the left part of
    // the window), brightening it on the whole.
    let (a, b) = (
        image::open(&with).unwrap().to_rgb8(),
        image::open(&without).unwrap().to_rgb8(),
    );
    let (mut brighter, mut darker, mut n) = (0u64, 0u64, 0u64);
    for y in 0..270 {
        for x in 0..100 {
            let (p, q) = (a.get_pixel(x, y).0, b.get_pixel(x, y).0);
            for c in 0..3 {
                brighter += p[c].saturating_sub(q[c]) as u64;
                darker += q[c].saturating_sub(p[c]) as u64;
            }
            n += 3;
        }
    }
    let (up, down) = (brighter as f64 / n as f64, darker as f64 / n as f64);
    eprintln!(
        "glare brightens the picture by {up:.2} and darkens it by {down:.2} levels on average"
    );
    assert!(up > 2.0 && up > 4.0 * down, "{up} {down}");
}

/// The photo mode's fixture in `dir`: a 480 × 320 photograph (sky, sea, a
/// dark post under each target where the true air and camera show it) over
/// the flat ground, seven targets at 0.6–9 km with round coordinates, and
/// the problem as a user would have it half marked: targets 0–4 marked on
/// their posts, target 5 marked 28 px off its post, target 6 not marked; the
/// camera started 0.03° off in azimuth and tilt, the air's strength at 0.002
/// (truth 0.0025). Returns the problem's path and each target's true pixel.
fn photo_fixture(dir: &Path) -> (std::path::PathBuf, Vec<[f64; 2]>) {
    use serde_json::{Value, json};
    let targets = [
        [-40.0, 3.0, 600.0],
        [-90.0, 8.0, 2500.0],
        [20.0, 14.0, 1200.0],
        [-10.0, 26.0, 7000.0],
        [120.0, 5.0, 3500.0],
        [200.0, 18.0, 9000.0],
        [300.0, 22.0, 5000.0],
    ];
    let (w, h) = (480u32, 320u32);
    image::RgbImage::from_pixel(w, h, image::Rgb([120, 150, 190]))
        .save(dir.join("photo.png"))
        .unwrap();
    let marks: Vec<Value> = targets
        .iter()
        .enumerate()
        .map(|(k, t)| json!({"name": format!("target {k}"), "pixel": [240.0, 160.0], "target": t}))
        .collect();
    let mut v = json!({
        "name": "photo-mode",
        "description": "the previewer's photo mode, marked and fitted by a script",
        "photo": {"image": "photo.png", "camera": {"horizontal_fov": 8.0,
            "azimuth": 0.0, "tilt": 0.0, "position": [0.0, 10.0, 0.0]}},
        "medium": {"scale": 0.0025, "background": {"n": 1.0, "a": 300.0},
                   "inversion": {"n": 0.9, "a": 5.0, "height": 6.0}},
        "marks": marks,
        "free": ["scale", "camera.azimuth", "camera.tilt"],
        "trace": {"method": "dopri5", "tolerance": 1e-10},
    });
    let path = dir.join("harbour.json");
    std::fs::write(&path, v.to_string()).unwrap();
    let truth = mirage::preview::photo::PhotoSession::open(&path).unwrap();
    let pixels: Vec<[f64; 2]> = truth
        .report
        .marks
        .iter()
        .map(|m| m.predicted.unwrap())
        .collect();
    // The photograph: sky over a darker sea below the straight horizon
    // (v = 159.5), and the posts.
    let mut img = image::RgbImage::from_fn(w, h, |_, y| {
        if y < 160 {
            image::Rgb([150, 180, 215 - (y / 4) as u8])
        } else {
            image::Rgb([50, 70, 95])
        }
    });
    for p in &pixels {
        let (u, v0) = (p[0].round() as i64, p[1].round() as i64);
        for y in v0..v0 + 14 {
            for x in u - 1..=u + 1 {
                if (0..w as i64).contains(&x) && (0..h as i64).contains(&y) {
                    img.put_pixel(x as u32, y as u32, image::Rgb([25, 22, 20]));
                }
            }
        }
    }
    img.save(dir.join("photo.png")).unwrap();
    let mut marks = Vec::new();
    for (k, p) in pixels.iter().enumerate().take(6) {
        let mut m = v["marks"][k].clone();
        m["pixel"] = if k == 5 {
            json!([p[0] - 20.0, p[1] + 20.0])
        } else {
            json!(p)
        };
        marks.push(m);
    }
    v["marks"] = Value::Array(marks);
    v["photo"]["camera"]["azimuth"] = json!(0.03);
    v["photo"]["camera"]["tilt"] = json!(0.03);
    v["medium"]["scale"] = json!(0.002);
    std::fs::write(&path, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    (path, pixels)
}

/// The number after `prefix` in `line` (up to a space).
fn number_after(line: &str, prefix: &str) -> f64 {
    line.split(prefix)
        .nth(1)
        .unwrap()
        .split_whitespace()
        .next()
        .unwrap()
        .parse()
        .unwrap()
}

#[test]
fn the_photo_mode_is_marked_fitted_and_saved_by_a_script() {
    if !can_run("the_photo_mode_is_marked_fitted_and_saved_by_a_script") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (problem, truth) = photo_fixture(dir.path());
    let off = [truth[5][0] - 20.0, truth[5][1] + 20.0];
    // Mark 5 dragged onto its post, a new mark on target 6's post with its
    // coordinates typed in, the fit, the save.
    let script = format!(
        "drag {} {} {} {}\nclick {} {}\n\
         button field x\ntype 300\nbutton field y\ntype 22\nbutton field z\ntype 5000\n\
         button Add typed point\nbutton Fit\nwait-fit\nbutton Save\nwait 2\n",
        off[0], off[1], truth[5][0], truth[5][1], truth[6][0], truth[6][1]
    );
    let script_path = dir.path().join("script.txt");
    std::fs::write(&script_path, script).unwrap();
    let shot = dir.path().join("photo-window.png");
    let args = [
        "--width", "1000", "--height", "600", "--frames", "2000", "--script",
    ];
    let mut args: Vec<&str> = args.to_vec();
    let script_arg = script_path.display().to_string();
    args.push(&script_arg);
    let stderr = run_window(dir.path(), problem.to_str().unwrap(), &args, &shot);
    eprintln!("{stderr}");
    // The saved file: the dragged mark on its post, the new mark there with
    // the typed target.
    let saved: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&problem).unwrap()).unwrap();
    let marks = saved["marks"].as_array().unwrap();
    assert_eq!(marks.len(), 7, "{saved}");
    let px = |m: &serde_json::Value| {
        [
            m["pixel"][0].as_f64().unwrap(),
            m["pixel"][1].as_f64().unwrap(),
        ]
    };
    for k in [5, 6] {
        let p = px(&marks[k]);
        assert!(
            (p[0] - truth[k][0]).abs() < 0.01 && (p[1] - truth[k][1]).abs() < 0.01,
            "mark {k} at {p:?}, its post at {:?}",
            truth[k]
        );
    }
    assert_eq!(marks[6]["target"], serde_json::json!([300.0, 22.0, 5000.0]));
    assert_eq!(
        saved["description"],
        "the previewer's photo mode, marked and fitted by a script"
    );
    // The fit: from the misplaced start to the marks' rounding.
    let fit = stderr
        .lines()
        .find(|l| l.starts_with("fit: "))
        .expect("no fit line");
    let before = number_after(fit, "RMS residual ");
    let after = number_after(fit, "→ ");
    assert!(before > 1.5 && after < 0.01, "{fit}");
    // The screenshot: the photo, and the new (selected) mark's yellow ring
    // around its post.
    let line = stderr
        .lines()
        .find(|l| l.starts_with("photo frame: "))
        .unwrap();
    let origin = [
        number_after(line, "origin "),
        line.split_whitespace()
            .nth(4)
            .unwrap()
            .parse::<f64>()
            .unwrap(),
    ];
    let scale = number_after(line, "scale ");
    if let Ok(keep) = std::env::var("MIRAGE_KEEP_PHOTO_WINDOW") {
        std::fs::copy(&shot, keep).unwrap();
    }
    let img = image::open(&shot).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (1000, 600));
    let at = |p: [f64; 2], dx: f64, dy: f64| {
        let x = origin[0] + (p[0] + 0.5) * scale + dx;
        let y = origin[1] + (p[1] + 0.5) * scale + dy;
        img.get_pixel(x.round() as u32, y.round() as u32).0
    };
    let ring = mirage::preview::photo_window::RING as f64;
    // The stroke is a few pixels wide and antialiased: some pixel within
    // two of the circle's point is its full yellow.
    let yellow = |c: [u8; 3]| c[0] > 200 && c[1] > 160 && c[2] < 90;
    for (dx, dy) in [
        (-ring, 0.0),
        (0.0, ring),
        (
            ring * std::f64::consts::FRAC_1_SQRT_2,
            ring * std::f64::consts::FRAC_1_SQRT_2,
        ),
    ] {
        let near: Vec<[u8; 3]> = (-2..=2)
            .flat_map(|i| (-2..=2).map(move |j| (i as f64, j as f64)))
            .map(|(i, j)| at(truth[6], dx + i, dy + j))
            .collect();
        assert!(
            near.iter().any(|&c| yellow(c)),
            "not the ring's yellow near {dx}, {dy}: {near:?}"
        );
    }
    // The sea under the posts, away from the marks.
    let sea = at([20.0, 300.0], 0.0, 0.0);
    assert!(
        sea.iter()
            .zip([50, 70, 95])
            .all(|(a, b)| (*a as i32 - b).abs() < 8),
        "{sea:?}"
    );
}
