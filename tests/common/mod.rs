//! The Python side (Mitsuba 3, Jupyter) for the tests that need it: found, or
//! skipped loudly, or — with `MIRAGE_REQUIRE_MITSUBA=1`, as `.ci/run` sets — a
//! failure.

use std::io::Write as _;
use std::path::{Path, PathBuf};

/// The repository root.
pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Writes past the test harness's capture, so that a skip is seen in the log.
pub fn loud(message: &str) {
    let bar = "=".repeat(78);
    let _ = writeln!(std::io::stderr(), "\n{bar}\n{message}\n{bar}\n");
}

/// The notebooks' Python (`notebooks/.venv`) if it and LLVM 19 (for Mitsuba's
/// llvm variant) are installed; `None` after a loud skip message otherwise.
/// Panics instead of skipping when `MIRAGE_REQUIRE_MITSUBA=1`.
pub fn python_or_skip(what: &str) -> Option<PathBuf> {
    let python = root().join("notebooks/.venv/bin/python");
    let llvm = std::env::var_os("DRJIT_LIBLLVM_PATH")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"));
    let missing = if !python.exists() {
        Some("notebooks/.venv is missing: run `bash notebooks/setup.sh`".to_string())
    } else if !llvm.exists() {
        Some(format!(
            "LLVM 19 is missing ({}): `apt-get install libllvm19`, or set DRJIT_LIBLLVM_PATH",
            llvm.display()
        ))
    } else {
        None
    };
    match missing {
        None => Some(python),
        Some(m) => {
            if std::env::var("MIRAGE_REQUIRE_MITSUBA").is_ok_and(|v| v == "1") {
                panic!("{what}: MIRAGE_REQUIRE_MITSUBA=1 but {m}");
            }
            loud(&format!("SKIPPED: {what}: {m}"));
            None
        }
    }
}
