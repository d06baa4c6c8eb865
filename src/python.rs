//! The Python module `mirage_air._native` (feature `python`, built by maturin:
//! `pip install .` from the repository root, `pyproject.toml`).
//!
//! The boundary is deliberately narrow: documents cross it as JSON text (the
//! same schema as the files, parsed and validated by the same code as the CLI
//! parses them, so a dict from Python and a file on disk give the same problem
//! and the same messages), and arrays as little-endian bytes that the Python
//! side (`python/mirage_air/__init__.py`) views as NumPy arrays without a copy.
//! So the Python results are the CLI's results bit for bit: the fit report is
//! the very `FitReport` that `mirage fit -o` writes.
//!
//! Invariants:
//! - Nothing panics across the boundary: the work runs on a thread of its own
//!   and a panic there becomes a `RuntimeError`.
//! - Every input error the CLI reports with exit code 2 becomes `InputError`
//!   (a `ValueError`) carrying `.file` and `.field`.
//! - Long calls release the GIL and poll for signals every 50 ms, so Ctrl-C
//!   raises `KeyboardInterrupt` at once. The library's cancellation points
//!   poll a process-wide flag ([`crate::interrupt`]) that only the command
//!   line's handler sets (setting it here would stop every other call in the
//!   process too), so the abandoned computation runs to its end on its own
//!   thread and its result is dropped; nothing it would have returned is
//!   written anywhere.

use crate::error::Error;
use crate::fit::ensemble::{EnsemblePlan, EnsembleSettings, Member};
use crate::math::V3;
use crate::medium::{IndexField, Medium};
use crate::problem::{Problem, ProblemFile};
use crate::render::{RenderOptions, Shading};
use crate::scene::description::{Scene, SceneFile};
use crate::trace::earth::OnEarth;
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use std::path::PathBuf;
use std::sync::mpsc::{RecvTimeoutError, channel};
use std::time::Duration;

pyo3::create_exception!(
    _native,
    InputError,
    PyValueError,
    "Bad input: a document, a field or an argument mirage rejects (the CLI's exit code 2). `.file` names the document, `.field` the field path (`medium.background.a`)."
);

/// An error of the library as the Python exception a user expects.
fn to_py(py: Python<'_>, e: Error) -> PyErr {
    let (file, field) = match &e {
        Error::Input { file, error } => (Some(file.clone()), Some(error.path.clone())),
        Error::Usage { flag, .. } => (None, Some(flag.clone())),
        Error::Output { flag, path, .. } => (Some(path.display().to_string()), Some(flag.clone())),
        _ => (None, None),
    };
    let message = e.to_string();
    let err = match e {
        Error::Input { .. } | Error::Usage { .. } | Error::Output { .. } => {
            InputError::new_err(message)
        }
        Error::Io { .. } => PyOSError::new_err(message),
        _ => PyRuntimeError::new_err(message),
    };
    if err.is_instance_of::<InputError>(py) {
        let value = err.value(py);
        let _ = value.setattr("file", file);
        let _ = value.setattr("field", field);
    }
    err
}

/// An input error about an argument of a Python call (no file).
fn argument_error(py: Python<'_>, name: &str, message: String) -> PyErr {
    to_py(py, Error::usage(name, message))
}

/// Runs `work` on a thread of its own with the GIL released, polling for
/// signals; with `threads`, inside a rayon pool of that many threads.
fn run<T: Send + 'static>(
    py: Python<'_>,
    threads: Option<usize>,
    work: impl FnOnce() -> T + Send + 'static,
) -> PyResult<T> {
    let pool = match threads {
        Some(0) => {
            return Err(argument_error(
                py,
                "threads",
                "must be at least 1, got 0".into(),
            ));
        }
        Some(n) => Some(
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| PyRuntimeError::new_err(format!("threads: {e}")))?,
        ),
        None => None,
    };
    let (tx, rx) = channel();
    std::thread::Builder::new()
        .name("mirage_air".into())
        .spawn(move || {
            let out = match pool {
                Some(pool) => pool.install(work),
                None => work(),
            };
            let _ = tx.send(out);
        })
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start a thread: {e}")))?;
    let mut rx = rx;
    loop {
        // The receiver moves into the detached closure and back: it is Send
        // but not Sync, so it cannot be borrowed across the detach.
        let (got, back) = py.detach(move || (rx.recv_timeout(Duration::from_millis(50)), rx));
        rx = back;
        match got {
            Ok(v) => return Ok(v),
            Err(RecvTimeoutError::Timeout) => py.check_signals()?,
            Err(RecvTimeoutError::Disconnected) => {
                return Err(PyRuntimeError::new_err(
                    "mirage failed inside (a panic); please report it with the input",
                ));
            }
        }
    }
}

/// Parses a problem document (JSON text; `path` names it in messages).
fn problem_of(text: &str, path: &str) -> Result<(ProblemFile, Problem), Error> {
    let path = PathBuf::from(path);
    let file: ProblemFile = crate::io::json::parse_json(text, &path, "problem")?;
    let problem = Problem::from_file(file.clone(), &path)?;
    Ok((file, problem))
}

/// Loads a problem or a scene: returns its kind (`"problem"` or `"scene"`) and
/// the document as mirage reads it (defaults filled in), as JSON text.
#[pyfunction]
#[pyo3(signature = (kind, text, path))]
fn load(py: Python<'_>, kind: &str, text: &str, path: &str) -> PyResult<String> {
    let out = match kind {
        "problem" => problem_of(text, path).and_then(|(file, _)| {
            serde_json::to_string(&file).map_err(|e| Error::encode("the problem", e))
        }),
        "scene" => {
            let p = PathBuf::from(path);
            crate::io::json::parse_json::<SceneFile>(text, &p, "scene").and_then(|file| {
                Scene::from_file(file.clone(), &p)?;
                serde_json::to_string(&file).map_err(|e| Error::encode("the scene", e))
            })
        }
        other => {
            return Err(argument_error(
                py,
                "kind",
                format!("must be `problem` or `scene`, got `{other}`"),
            ));
        }
    };
    out.map_err(|e| to_py(py, e))
}

/// Traces every pair of a problem through its medium: the trace report as
/// `mirage trace -o` writes it, as JSON text.
#[pyfunction]
#[pyo3(signature = (text, path, threads=None))]
fn trace(py: Python<'_>, text: &str, path: &str, threads: Option<usize>) -> PyResult<String> {
    let (_, problem) = problem_of(text, path).map_err(|e| to_py(py, e))?;
    let report = run(py, threads, move || {
        crate::evaluate::trace_pairs(&problem, &problem.medium)
    })?;
    serde_json::to_string(&report).map_err(|e| to_py(py, Error::encode("the trace report", e)))
}

/// Fits a problem: the result as `mirage fit -o` writes it (pretty JSON text).
/// `method`, `grow`, `noise` and `max_terms` are `mirage fit`'s `--method`,
/// `--grow`, `--noise` and `--max-terms`, applied and checked by the same
/// code; errors name the keyword argument.
#[pyfunction]
#[pyo3(signature = (text, path, method=None, grow=false, noise=None, max_terms=None, threads=None))]
#[allow(clippy::too_many_arguments)]
fn fit(
    py: Python<'_>,
    text: &str,
    path: &str,
    method: Option<&str>,
    grow: bool,
    noise: Option<f64>,
    max_terms: Option<usize>,
    threads: Option<usize>,
) -> PyResult<String> {
    use crate::problem::{SolverMethod, check_max_terms, check_noise};
    let (_, mut problem) = problem_of(text, path).map_err(|e| to_py(py, e))?;
    let method = match method {
        None => None,
        Some(m) => Some(
            [
                SolverMethod::Lm,
                SolverMethod::NelderMead,
                SolverMethod::Auto,
            ]
            .into_iter()
            .find(|v| v.name() == m)
            .ok_or_else(|| {
                argument_error(
                    py,
                    "method",
                    format!("must be `lm`, `nelder-mead` or `auto`, got `{m}`"),
                )
            })?,
        ),
    };
    let noise = noise
        .map(check_noise)
        .transpose()
        .map_err(|e| argument_error(py, "noise", e.to_string()))?;
    let max_terms = max_terms
        .map(check_max_terms)
        .transpose()
        .map_err(|e| argument_error(py, "max_terms", e.to_string()))?;
    let options = crate::cli::fit::FitOptions {
        method,
        grow,
        noise,
        max_terms,
        ..Default::default()
    };
    crate::cli::fit::apply_flags(&options, &mut problem).map_err(|e| {
        // The CLI's flags are this function's keyword arguments.
        let e = match e {
            Error::Usage { flag, message } => Error::Usage {
                flag: flag.trim_start_matches('-').replace('-', "_"),
                message: message
                    .replace("--grow", "grow=True")
                    .replace("--method", "method="),
            },
            e => e,
        };
        to_py(py, e)
    })?;
    let report = run(py, threads, move || crate::fit::fit(&problem, None))?;
    let report = report.map_err(|e| to_py(py, e))?;
    serde_json::to_string_pretty(&report)
        .map_err(|e| to_py(py, Error::encode("the result as JSON", e)))
}

/// Checks [`render`]'s size arguments without rendering (so that a batch of
/// frames fails before any work); errors name the argument.
#[pyfunction]
#[pyo3(signature = (width=None, height=None, spp=None))]
fn render_check(
    py: Python<'_>,
    width: Option<u32>,
    height: Option<u32>,
    spp: Option<u32>,
) -> PyResult<()> {
    use crate::scene::description::{MAX_IMAGE_SIDE, MAX_SAMPLES_PER_PIXEL};
    for (name, v, max) in [
        ("width", width, MAX_IMAGE_SIDE),
        ("height", height, MAX_IMAGE_SIDE),
        ("spp", spp, MAX_SAMPLES_PER_PIXEL),
    ] {
        if let Some(v) = v
            && (v == 0 || v > max)
        {
            return Err(argument_error(
                py,
                name,
                format!("must be between 1 and {max}, got {v}"),
            ));
        }
    }
    Ok(())
}

/// Renders a scene: `(width, height, bytes)`, the bytes linear radiance as
/// little-endian `f32` RGB, row-major, top row first (what `--exr` writes);
/// with `srgb`, the 8-bit sRGB values of `mirage render`'s PNG instead (three
/// bytes a pixel, tone-mapped by the scene's `exposure`).
#[pyfunction]
#[pyo3(signature = (text, path, width=None, height=None, spp=None, albedo=false, straight=false, threads=None, srgb=false))]
#[allow(clippy::too_many_arguments)]
fn render<'py>(
    py: Python<'py>,
    text: &str,
    path: &str,
    width: Option<u32>,
    height: Option<u32>,
    spp: Option<u32>,
    albedo: bool,
    straight: bool,
    threads: Option<usize>,
    srgb: bool,
) -> PyResult<(u32, u32, Bound<'py, PyBytes>)> {
    render_check(py, width, height, spp)?;
    let scene = Scene::parse(text, &PathBuf::from(path)).map_err(|e| to_py(py, e))?;
    let options = RenderOptions {
        shading: if albedo {
            Shading::Albedo
        } else {
            Shading::Lit
        },
        straight,
        samples_per_pixel: spp,
        width,
        height,
        progress: false,
        ..RenderOptions::default()
    };
    let tone = crate::render::tone_map(options.shading, scene.exposure);
    let image = run(py, threads, move || {
        let image = crate::render::render(&scene, &options);
        let srgb = srgb.then(|| crate::render::output::to_srgb8(&image.pixels, tone));
        (image, srgb)
    })?;
    let (image, srgb) = image;
    if let Some(raw) = srgb {
        return Ok((image.width, image.height, PyBytes::new(py, &raw)));
    }
    let mut bytes = Vec::with_capacity(image.pixels.len() * 12);
    for p in &image.pixels {
        for c in p {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    Ok((image.width, image.height, PyBytes::new(py, &bytes)))
}

/// A photo problem's overlay, as `mirage overlay` draws it (its starting
/// air and camera) or, given `photo` (the `photo` section of the problem's
/// fit result, JSON text), as `mirage fit --overlay` draws it: `(width,
/// height, bytes)`, the PNG's RGB pixels row by row.
#[pyfunction]
#[pyo3(signature = (text, path, photo=None, threads=None))]
fn overlay<'py>(
    py: Python<'py>,
    text: &str,
    path: &str,
    photo: Option<&str>,
    threads: Option<usize>,
) -> PyResult<(u32, u32, Bound<'py, PyBytes>)> {
    use crate::cli::overlay::{overlay_image, overlay_title, starting_report};
    use crate::fit::photo::PhotoReport;
    let (_, problem) = problem_of(text, path).map_err(|e| to_py(py, e))?;
    let fitted = match photo {
        None => None,
        Some(t) => Some(serde_json::from_str::<PhotoReport>(t).map_err(|e| {
            argument_error(
                py,
                "result",
                format!("is not the fit of a photo problem (its `photo` section: {e})"),
            )
        })?),
    };
    if let (Some(r), Some(setup)) = (&fitted, &problem.photo) {
        let image = setup.image.display().to_string();
        if r.image != image || r.marks.len() != setup.marks.len() {
            return Err(argument_error(
                py,
                "result",
                format!(
                    "is the fit of another photo problem ({}, {} marks), not of this one ({image}, {} marks)",
                    r.image,
                    r.marks.len(),
                    setup.marks.len()
                ),
            ));
        }
    }
    let image = run(py, threads, move || {
        let (report, fitted) = match fitted {
            Some(r) => (r, true),
            None => (starting_report(&problem)?, false),
        };
        overlay_image(&problem, &report, &overlay_title(&problem, fitted))
    })?
    .map_err(|e| to_py(py, e))?;
    Ok((
        image.width(),
        image.height(),
        PyBytes::new(py, image.as_raw()),
    ))
}

/// δ = n − 1 and ∇δ of a medium (JSON text of the `medium` field) at `k`
/// points given as little-endian `f64` triples; over the round earth of
/// `earth_radius` when given. Returns `(delta, gradient)` as bytes of `k` and
/// `3k` `f64`s.
#[pyfunction]
#[pyo3(signature = (medium, points, earth_radius=None))]
fn medium_eval<'py>(
    py: Python<'py>,
    medium: &str,
    points: &[u8],
    earth_radius: Option<f64>,
) -> PyResult<(Bound<'py, PyBytes>, Bound<'py, PyBytes>)> {
    let path = PathBuf::from("<medium>");
    let m: Medium =
        crate::io::json::parse_json(medium, &path, "medium").map_err(|e| to_py(py, e))?;
    m.validate()
        .map_err(|e| to_py(py, e.within("medium").in_file(&path)))?;
    if let Some(r) = earth_radius {
        crate::trace::EarthSpec { radius: r }
            .validate()
            .map_err(|e| to_py(py, e.within("earth").in_file(&path)))?;
    }
    if points.len() % 24 != 0 {
        return Err(argument_error(
            py,
            "points",
            "must be a (k, 3) array of float64".into(),
        ));
    }
    let pts: Vec<V3> = points
        .chunks_exact(24)
        .map(|c| {
            let f = |i: usize| {
                let mut b = [0u8; 8];
                b.copy_from_slice(&c[8 * i..8 * i + 8]);
                f64::from_le_bytes(b)
            };
            V3::new(f(0), f(1), f(2))
        })
        .collect();
    if let Some(i) = pts.iter().position(|p| !p.is_finite()) {
        return Err(argument_error(
            py,
            "points",
            format!("row {i} is not finite: {:?}", pts[i].to_array()),
        ));
    }
    let field = m.field();
    let mut delta = Vec::with_capacity(pts.len() * 8);
    let mut gradient = Vec::with_capacity(pts.len() * 24);
    for p in pts {
        let (d, g) = match earth_radius {
            Some(radius) => OnEarth {
                field: &field,
                radius,
            }
            .delta_gradient(p),
            None => field.delta_gradient(p),
        };
        delta.extend_from_slice(&d.to_le_bytes());
        for c in g.to_array() {
            gradient.extend_from_slice(&c.to_le_bytes());
        }
    }
    Ok((PyBytes::new(py, &delta), PyBytes::new(py, &gradient)))
}

/// An ensemble's problem, settings and truth, checked before any work as
/// `mirage ensemble` checks its problem and flags; errors name the keyword
/// argument (`n`, `noise`, `bootstrap`) or the document's field.
#[allow(clippy::too_many_arguments)]
fn ensemble_inputs(
    py: Python<'_>,
    text: &str,
    path: &str,
    n: usize,
    noise: Option<f64>,
    bootstrap: bool,
    seed: u64,
    truth: Option<(&str, &str)>,
) -> PyResult<(ProblemFile, Problem, EnsembleSettings, Option<Medium>)> {
    use crate::fit::ensemble::{check_members, check_problem};
    let members = check_members(n).map_err(|e| argument_error(py, "n", e.to_string()))?;
    let noise = noise
        .map(crate::problem::check_noise)
        .transpose()
        .map_err(|e| argument_error(py, "noise", e.to_string()))?;
    if bootstrap && noise.is_some() {
        return Err(argument_error(
            py,
            "bootstrap",
            "cannot be combined with noise: bootstrap resamples the pairs and adds no noise".into(),
        ));
    }
    let (file, problem) = problem_of(text, path).map_err(|e| to_py(py, e))?;
    check_problem(&problem).map_err(|e| to_py(py, e))?;
    let truth = truth
        .map(|(text, path)| crate::cli::ensemble::truth_of(text, std::path::Path::new(path)))
        .transpose()
        .map_err(|e| to_py(py, e))?;
    let settings = EnsembleSettings {
        members,
        noise,
        bootstrap,
        seed,
    };
    Ok((file, problem, settings, truth))
}

/// Runs an ensemble of fits, as `mirage ensemble` does: the report as `-o`
/// writes it (pretty JSON text). `n`, `noise`, `bootstrap`, `seed` are
/// `-n`, `--noise`, `--bootstrap`, `--seed`; `truth` the text of a document
/// with a `medium` (`--truth`'s file) and `truth_path` its name.
#[pyfunction]
#[pyo3(signature = (text, path, n, noise=None, bootstrap=false, seed=0, truth=None, truth_path="<truth>", threads=None))]
#[allow(clippy::too_many_arguments)]
fn ensemble(
    py: Python<'_>,
    text: &str,
    path: &str,
    n: usize,
    noise: Option<f64>,
    bootstrap: bool,
    seed: u64,
    truth: Option<&str>,
    truth_path: &str,
    threads: Option<usize>,
) -> PyResult<String> {
    let (_, problem, settings, truth) = ensemble_inputs(
        py,
        text,
        path,
        n,
        noise,
        bootstrap,
        seed,
        truth.map(|t| (t, truth_path)),
    )?;
    let report = run(py, threads, move || {
        crate::fit::ensemble::ensemble(&problem, &settings, truth.as_ref())
    })?;
    let report = report.map_err(|e| to_py(py, e))?;
    serde_json::to_string_pretty(&report)
        .map_err(|e| to_py(py, Error::encode("the ensemble as JSON", e)))
}

/// The first part of an ensemble: the best fit and the noise, as a plan
/// (JSON text, [`EnsemblePlan::to_json`]) from which each member is one
/// independent task ([`ensemble_member`]). Arguments as [`ensemble`]'s.
#[pyfunction]
#[pyo3(signature = (text, path, n, noise=None, bootstrap=false, seed=0, truth=None, truth_path="<truth>", threads=None))]
#[allow(clippy::too_many_arguments)]
fn ensemble_plan(
    py: Python<'_>,
    text: &str,
    path: &str,
    n: usize,
    noise: Option<f64>,
    bootstrap: bool,
    seed: u64,
    truth: Option<&str>,
    truth_path: &str,
    threads: Option<usize>,
) -> PyResult<String> {
    let (file, problem, settings, truth) = ensemble_inputs(
        py,
        text,
        path,
        n,
        noise,
        bootstrap,
        seed,
        truth.map(|t| (t, truth_path)),
    )?;
    let plan = run(py, threads, move || {
        EnsemblePlan::new(&problem, &settings, truth.as_ref()).and_then(|p| p.to_json(&file))
    })?;
    plan.map_err(|e| to_py(py, e))
}

/// A plan's text as the plan; errors name its field (in the file `<plan>`).
fn plan_of(py: Python<'_>, plan: &str) -> PyResult<EnsemblePlan> {
    EnsemblePlan::from_json(plan).map_err(|e| to_py(py, e))
}

/// Member `k` of a plan ([`EnsemblePlan::member`]): its parameters and F.
/// The same numbers on any thread, process or machine.
#[pyfunction]
#[pyo3(signature = (plan, k, threads=None))]
fn ensemble_member(
    py: Python<'_>,
    plan: &str,
    k: usize,
    threads: Option<usize>,
) -> PyResult<(Vec<f64>, f64)> {
    let plan = plan_of(py, plan)?;
    let member = run(py, threads, move || plan.member(k))?;
    let member = member.map_err(|e| to_py(py, e))?;
    Ok((member.params, member.objective))
}

/// The report of a plan's members 0..N, given in that order as
/// `(parameters, F)` ([`EnsemblePlan::summarise`]): what [`ensemble`]
/// returns, with `wall_time_s` as its wall-clock time.
#[pyfunction]
#[pyo3(signature = (plan, members, wall_time_s))]
fn ensemble_summarise(
    py: Python<'_>,
    plan: &str,
    members: Vec<(Vec<f64>, f64)>,
    wall_time_s: f64,
) -> PyResult<String> {
    let plan = plan_of(py, plan)?;
    let members = members
        .into_iter()
        .map(|(params, objective)| Member { params, objective })
        .collect();
    let report = run(py, None, move || plan.summarise(members, wall_time_s))?;
    let report = report.map_err(|e| to_py(py, e))?;
    serde_json::to_string_pretty(&report)
        .map_err(|e| to_py(py, Error::encode("the ensemble as JSON", e)))
}

/// Reads a sounding file (IGRA 2, Wyoming TEXT:LIST or CSV) into a real-air
/// medium, as `mirage sounding` does: the medium's JSON text (what `-o`
/// writes). `format` is `igra2`, `wyoming` or `csv` (default: inferred);
/// `site_height` as `--site-height`.
#[pyfunction]
#[pyo3(signature = (path, format=None, site_height=None))]
fn sounding(
    py: Python<'_>,
    path: &str,
    format: Option<&str>,
    site_height: Option<f64>,
) -> PyResult<String> {
    use crate::io::sounding::Format;
    let format = match format {
        None => None,
        Some(f) => Some(
            [Format::Igra2, Format::Wyoming, Format::Csv]
                .into_iter()
                .find(|k| k.name() == f)
                .ok_or_else(|| {
                    argument_error(
                        py,
                        "format",
                        format!("must be `igra2`, `wyoming` or `csv`, got `{f}`"),
                    )
                })?,
        ),
    };
    if let Some(h) = site_height
        && !h.is_finite()
    {
        return Err(argument_error(
            py,
            "site_height",
            format!("must be a finite number of metres, got {h}"),
        ));
    }
    let (medium, _, _) =
        crate::cli::sounding::medium_of(std::path::Path::new(path), format, site_height)
            .map_err(|e| to_py(py, e))?;
    serde_json::to_string(&medium).map_err(|e| to_py(py, Error::encode("the medium", e)))
}

/// The module: `mirage_air._native`.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("InputError", m.py().get_type::<InputError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(trace, m)?)?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(render_check, m)?)?;
    m.add_function(wrap_pyfunction!(overlay, m)?)?;
    m.add_function(wrap_pyfunction!(medium_eval, m)?)?;
    m.add_function(wrap_pyfunction!(sounding, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble_plan, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble_member, m)?)?;
    m.add_function(wrap_pyfunction!(ensemble_summarise, m)?)?;
    Ok(())
}
