//! The previewer's window under Xvfb: it opens, renders frames with its
//! panels, saves a screenshot and exits cleanly.
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

#[test]
fn the_window_opens_renders_frames_and_exits_cleanly() {
    let required = std::env::var("MIRAGE_REQUIRE_GPU").is_ok_and(|v| v == "1");
    if !have("xvfb-run") {
        assert!(!required, "MIRAGE_REQUIRE_GPU=1 but xvfb-run is missing");
        loud(
            "*** SKIPPED the_window_opens_renders_frames_and_exits_cleanly: no xvfb-run (apt-get install xvfb xauth) ***",
        );
        return;
    }
    if let Err(e) = mirage::preview::gpu::Gpu::new() {
        assert!(!required, "MIRAGE_REQUIRE_GPU=1 but {e}");
        loud(&format!(
            "*** SKIPPED the_window_opens_renders_frames_and_exits_cleanly: {e} ***"
        ));
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("window.png");
    let problem = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/hot-road.json");
    let run = Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1024x768x24"])
        .arg(env!("CARGO_BIN_EXE_mirage"))
        .args([
            "preview", "--frames", "5", "--width", "800", "--height", "450",
        ])
        .arg("--screenshot")
        .arg(&shot)
        .arg(&problem)
        .env(
            "XDG_RUNTIME_DIR",
            std::env::var("XDG_RUNTIME_DIR").unwrap_or_else(|_| dir.path().display().to_string()),
        )
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "status {:?}\nstdout: {}\nstderr: {}",
        run.status,
        String::from_utf8_lossy(&run.stdout),
        String::from_utf8_lossy(&run.stderr)
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
