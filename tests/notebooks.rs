//! The notebooks: stored without outputs (always checked), and executed with
//! nbclient at small sizes against the freshly built `mirage` when the Python
//! side is installed (`bash notebooks/setup.sh`).

mod common;

use std::process::Command;

const NOTEBOOKS: [&str; 6] = [
    "fit_walkthrough.ipynb",
    "tradeoff.ipynb",
    "validation.ipynb",
    "python_api.ipynb",
    "ensemble.ipynb",
    "photo.ipynb",
];

#[test]
fn notebooks_are_stored_without_outputs() {
    for name in NOTEBOOKS {
        let path = common::root().join("notebooks").join(name);
        let text = std::fs::read_to_string(&path).unwrap();
        let nb: serde_json::Value = serde_json::from_str(&text).unwrap();
        let cells = nb["cells"].as_array().unwrap();
        assert!(cells.len() > 3, "{name}: too few cells");
        let mut code = 0;
        for (i, cell) in cells.iter().enumerate() {
            if cell["cell_type"] == "code" {
                code += 1;
                assert_eq!(
                    cell["outputs"],
                    serde_json::json!([]),
                    "{name}: cell {i} has outputs (strip them before committing)"
                );
                assert!(
                    cell["execution_count"].is_null(),
                    "{name}: cell {i} has an execution count"
                );
            }
        }
        assert!(code >= 3, "{name}: too few code cells");
        assert!(
            text.contains("mirage(\\\"")
                || text.contains("\\\"--mirage\\\"")
                || text.contains("import mirage_air"),
            "{name}: the notebook should show the mirage command, as a user runs it, or the Python package"
        );
    }
}

#[test]
fn notebooks_execute() {
    let Some(python) = common::python_or_skip("notebook execution") else {
        return;
    };
    let out = tempfile::tempdir().unwrap();
    let run = Command::new(python)
        .arg(common::root().join("notebooks/run_notebooks.py"))
        .env("MIRAGE_BIN", env!("CARGO_BIN_EXE_mirage"))
        .env("MIRAGE_SMALL", "1")
        .env("MIRAGE_NB_OUT", out.path())
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    common::loud(&format!("notebooks:\n{stdout}"));
    assert!(
        run.status.success(),
        "a notebook failed:\n{stdout}\n{stderr}"
    );
    for name in NOTEBOOKS {
        assert!(stdout.contains(&format!("{name}: executed")), "{stdout}");
    }
    // What the notebooks made is there (a fit result, a Pareto plot, the
    // validation table, the ensemble's bands, the hot road's video, and
    // the bundled photo's fitted profile and overlay).
    assert!(out.path().join("fit.json").exists());
    assert!(out.path().join("pareto.png").exists());
    assert!(out.path().join("validation/results.json").exists());
    assert!(out.path().join("ensemble-bands.png").exists());
    assert!(out.path().join("hot-road.mp4").exists());
    assert!(out.path().join("photo-profile.png").exists());
    assert!(out.path().join("photo-overlay.png").exists());
}
