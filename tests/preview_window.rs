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
