//! The Python package `mirage_air` (`python/`, built by maturin from the
//! `python` feature): its pytest suite (`python/tests/`), run with the
//! notebooks' venv, where `bash notebooks/setup.sh` installs this checkout's
//! package. The suite compares every function with the CLI, so it gets this
//! build's `mirage` binary.

mod common;

use std::path::Path;
use std::process::Command;
use std::time::SystemTime;

/// The newest modification time under `path` (a file or a folder).
fn newest(path: &Path) -> SystemTime {
    let meta = std::fs::metadata(path).unwrap();
    if meta.is_dir() {
        std::fs::read_dir(path)
            .unwrap()
            .map(|e| newest(&e.unwrap().path()))
            .max()
            .unwrap_or(SystemTime::UNIX_EPOCH)
    } else {
        meta.modified().unwrap()
    }
}

#[test]
fn the_python_suite_passes() {
    let Some(python) = common::python_or_skip("the mirage_air pytest suite") else {
        return;
    };
    // The installed package must be this checkout's: setup.sh stamps each
    // install, and a source newer than the stamp means it is stale.
    let root = common::root();
    let stamp = root.join("notebooks/.venv/.installed-mirage-air");
    let stale = match std::fs::metadata(&stamp).and_then(|m| m.modified()) {
        Err(_) => Some("mirage_air is not installed in notebooks/.venv".to_string()),
        Ok(installed) => [
            "src",
            "python/mirage_air",
            "Cargo.toml",
            "Cargo.lock",
            "pyproject.toml",
        ]
        .iter()
        .find(|p| newest(&root.join(p)) > installed)
        .map(|p| format!("{p} changed after mirage_air was installed in notebooks/.venv")),
    };
    if let Some(why) = stale {
        let m = format!("{why}: run `bash notebooks/setup.sh`");
        if std::env::var("MIRAGE_REQUIRE_MITSUBA").is_ok_and(|v| v == "1") {
            panic!("the mirage_air pytest suite: MIRAGE_REQUIRE_MITSUBA=1 but {m}");
        }
        common::loud(&format!("SKIPPED: the mirage_air pytest suite: {m}"));
        return;
    }
    let run = Command::new(python)
        .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
        .arg(root.join("python/tests"))
        .env("MIRAGE_BIN", env!("CARGO_BIN_EXE_mirage"))
        .current_dir(root)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    common::loud(&format!("mirage_air pytest:\n{stdout}"));
    assert!(run.status.success(), "pytest failed:\n{stdout}\n{stderr}");
    assert!(
        stdout.contains(" passed") && !stdout.contains(" skipped"),
        "every Python test must run here (none skipped):\n{stdout}"
    );
}
