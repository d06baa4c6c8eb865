//! Problem files (`docs/problem-format.md`): load, validate, and turn into a
//! [`Problem`] the rest of mirage can trust.
//!
//! ```json
//! {
//!   "name": "desert-road",
//!   "description": "Hot asphalt: the sky appears as water below the horizon.",
//!   "medium": { "scale": 1.0, "background": { "n": 1.0, "a": 40.0 },
//!               "hotspots": [ { "x": 0, "z": 600, "radius": 120, "n": -2, "a": -0.4 } ] },
//!   "free": ["hotspots[0].n", "hotspots[0].radius"],
//!   "bounds": { "hotspots[0].radius": [1.0, 500.0] },
//!   "pairs": [ { "origin": [0, 1.6, 0], "through": [0, -1.2, 900], "target": [0, 30, 900] } ],
//!   "trace":  { "method": "rk4", "step": 1.0 },
//!   "solver": { "method": "lm", "max_iterations": 200 }
//! }
//! ```
//!
//! | field | meaning |
//! | --- | --- |
//! | `medium` | the starting medium ([`LogisticMedium`]); a term left out is not modelled |
//! | `free` | parameters the fit may change, by path name; absent: trace and report only |
//! | `bounds` | optional `[low, high]` per free parameter |
//! | `pairs` | point pairs: `origin`, `through`, `target` (metres), optional `weight` |
//! | `trace` | `method`: `rk4` (with `step`, metres) or `dopri5` (alias `adaptive`, with `tolerance`); optional `max_length` |
//! | `solver` | `method`: `lm`, `nelder-mead` or `auto` (LM, restarts, Nelder–Mead fallback); `max_iterations`, `starts`, `ftol`, `xtol`, `gtol`, `seed`, `target_objective` (m², default 1e-12) |

use crate::error::{Error, Result};
use crate::medium::{LogisticMedium, Param};
use crate::pair::PointPair;
use crate::trace::{Method, TraceOptions};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The `trace` section as written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TraceSpec {
    /// `rk4`, `dopri5` or `adaptive`.
    pub method: String,
    /// RK4 step (metres).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub step: Option<f64>,
    /// Dormand–Prince local error bound.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
    /// Largest arc length (metres); default 4 × |target − origin|.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_length: Option<f64>,
}

impl Default for TraceSpec {
    fn default() -> Self {
        TraceSpec {
            method: "dopri5".into(),
            step: None,
            tolerance: Some(DEFAULT_TOLERANCE),
            max_length: None,
        }
    }
}

/// Default RK4 step when a file names `rk4` without a step (metres).
pub const DEFAULT_STEP: f64 = 1.0;
/// Default Dormand–Prince tolerance when none is given.
pub const DEFAULT_TOLERANCE: f64 = 1e-9;

/// The `solver` section as written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// `lm`, `nelder-mead` or `auto`.
    #[serde(default = "default_solver")]
    pub method: String,
    /// Iteration limit per start.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_iterations: Option<u64>,
    /// Number of starting points tried when the first start stalls (`auto`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub starts: Option<usize>,
    /// Relative reduction of the objective below which LM stops.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ftol: Option<f64>,
    /// Relative step below which LM stops.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub xtol: Option<f64>,
    /// Scaled gradient below which LM stops.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gtol: Option<f64>,
    /// Seed of the starting points (restarts are reproducible).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Objective F (m²) below which a fit counts as reaching its targets; above
    /// it, `auto` restarts.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_objective: Option<f64>,
}

fn default_solver() -> String {
    "auto".into()
}

impl Default for SolverSpec {
    fn default() -> Self {
        SolverSpec {
            method: default_solver(),
            max_iterations: None,
            starts: None,
            ftol: None,
            xtol: None,
            gtol: None,
            seed: None,
            target_objective: None,
        }
    }
}

/// Which optimiser fits the free parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SolverMethod {
    /// Levenberg–Marquardt on exact Jacobians.
    Lm,
    /// Nelder–Mead simplex (derivative-free).
    NelderMead,
    /// LM; if it stalls above tolerance, restarts in parallel and a Nelder–Mead
    /// fallback, the best polished by LM.
    Auto,
}

impl SolverMethod {
    /// The name used in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            SolverMethod::Lm => "lm",
            SolverMethod::NelderMead => "nelder-mead",
            SolverMethod::Auto => "auto",
        }
    }
}

/// Validated solver settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolverSettings {
    /// The optimiser.
    pub method: SolverMethod,
    /// Iteration limit per start.
    pub max_iterations: u64,
    /// Starting points for restarts.
    pub starts: usize,
    /// LM ftol.
    pub ftol: f64,
    /// LM xtol.
    pub xtol: f64,
    /// LM gtol.
    pub gtol: f64,
    /// Seed of the restart points.
    pub seed: u64,
    /// F (m²) below which the targets count as reached.
    pub target_objective: f64,
}

/// The problem file exactly as written.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProblemFile {
    /// Short name.
    #[serde(default)]
    pub name: Option<String>,
    /// What a user would see.
    #[serde(default)]
    pub description: Option<String>,
    /// Starting medium.
    pub medium: LogisticMedium,
    /// Free parameters by path name.
    #[serde(default)]
    pub free: Vec<String>,
    /// Bounds per free parameter.
    #[serde(default)]
    pub bounds: BTreeMap<String, [f64; 2]>,
    /// The point pairs.
    pub pairs: Vec<PointPair>,
    /// Integration settings.
    #[serde(default)]
    pub trace: TraceSpec,
    /// Solver settings.
    #[serde(default)]
    pub solver: SolverSpec,
}

/// A validated problem.
#[derive(Clone, Debug)]
pub struct Problem {
    /// Where it was read from (for messages).
    pub source: PathBuf,
    /// Short name (the file stem if the file has none).
    pub name: String,
    /// What a user would see.
    pub description: String,
    /// Starting medium (valid per `docs/model.md`).
    pub medium: LogisticMedium,
    /// Free parameters, in the order of the file.
    pub free: Vec<Param>,
    /// `[low, high]` per free parameter (±∞ where unbounded).
    pub bounds: Vec<(f64, f64)>,
    /// The point pairs.
    pub pairs: Vec<PointPair>,
    /// Integration settings.
    pub trace: TraceOptions,
    /// The `trace` section, normalised (echoed in results).
    pub trace_spec: TraceSpec,
    /// Solver settings.
    pub solver: SolverSettings,
}

impl Problem {
    /// Reads and validates a problem file.
    pub fn load(path: &Path) -> Result<Problem> {
        Problem::parse(&read_input(path)?, path)
    }

    /// Parses and validates the text of a problem file; `path` is only used in
    /// messages.
    pub fn parse(text: &str, path: &Path) -> Result<Problem> {
        let file: ProblemFile = parse_json(text, path, "problem")?;
        Problem::from_file(file, path)
    }

    /// Validates a parsed problem file.
    pub fn from_file(file: ProblemFile, path: &Path) -> Result<Problem> {
        let bad = |field: String, message: String| Error::input(path, field, message);
        file.medium
            .validate()
            .map_err(|e| bad(format!("medium.{}", e.field), e.message))?;

        for (i, pair) in file.pairs.iter().enumerate() {
            pair.validate()
                .map_err(|(f, m)| bad(format!("pairs[{i}].{f}"), m))?;
        }

        let mut free = Vec::with_capacity(file.free.len());
        for (i, name) in file.free.iter().enumerate() {
            let p: Param = name.parse().map_err(|e: crate::medium::ParamParseError| {
                bad(format!("free[{i}]"), e.to_string())
            })?;
            if file.medium.get(p).is_none() {
                return Err(bad(
                    format!("free[{i}]"),
                    format!(
                        "`{name}` is not a parameter of this medium: {}",
                        file.medium.absent_reason(p)
                    ),
                ));
            }
            if free.contains(&p) {
                return Err(bad(
                    format!("free[{i}]"),
                    format!("`{name}` is listed twice"),
                ));
            }
            free.push(p);
        }
        if !free.is_empty() && file.pairs.is_empty() {
            return Err(bad(
                "pairs".into(),
                format!(
                    "{} free parameter(s) but no point pairs to fit them to",
                    free.len()
                ),
            ));
        }

        let mut bounds = vec![(f64::NEG_INFINITY, f64::INFINITY); free.len()];
        for (name, &[low, high]) in &file.bounds {
            let field = format!("bounds.{name}");
            let p: Param = name
                .parse()
                .map_err(|e: crate::medium::ParamParseError| bad(field.clone(), e.to_string()))?;
            let Some(k) = free.iter().position(|q| *q == p) else {
                return Err(bad(
                    field,
                    format!(
                        "`{name}` is not a free parameter; bounds apply only to parameters listed in `free`"
                    ),
                ));
            };
            if low.is_nan() || high.is_nan() {
                return Err(bad(field, "bounds must be numbers".into()));
            }
            if low > high {
                return Err(bad(
                    field,
                    format!("low bound {low} is above high bound {high}"),
                ));
            }
            let start = file.medium.get(p).unwrap_or(f64::NAN);
            if !(low..=high).contains(&start) {
                return Err(bad(
                    field,
                    format!(
                        "the starting value {start} of `{name}` lies outside its bounds [{low}, {high}]"
                    ),
                ));
            }
            bounds[k] = (low, high);
        }

        let (trace, trace_spec) = trace_options(&file.trace, path)?;
        let solver = solver_settings(&file.solver, path)?;
        let name = file.name.clone().unwrap_or_else(|| {
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "problem".into())
        });
        Ok(Problem {
            source: path.to_path_buf(),
            name,
            description: file.description.clone().unwrap_or_default(),
            medium: file.medium,
            free,
            bounds,
            pairs: file.pairs,
            trace,
            trace_spec,
            solver,
        })
    }
}

fn positive(path: &Path, field: &str, v: f64) -> Result<f64> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(Error::input(
            path,
            field,
            format!("must be a finite number > 0, got {v}"),
        ))
    }
}

/// Validates a `trace` section: known method, its parameters and no others.
pub fn trace_options(spec: &TraceSpec, path: &Path) -> Result<(TraceOptions, TraceSpec)> {
    let unused = |field: &str, method: &str| {
        Error::input(
            path,
            format!("trace.{field}"),
            format!("is not a parameter of method `{method}`"),
        )
    };
    let mut normal = spec.clone();
    let method = match spec.method.as_str() {
        "rk4" => {
            if spec.tolerance.is_some() {
                return Err(unused("tolerance", "rk4"));
            }
            let step = positive(path, "trace.step", spec.step.unwrap_or(DEFAULT_STEP))?;
            normal.step = Some(step);
            Method::Rk4 { step }
        }
        "dopri5" | "adaptive" => {
            if spec.step.is_some() {
                return Err(unused("step", &spec.method));
            }
            let tolerance = positive(
                path,
                "trace.tolerance",
                spec.tolerance.unwrap_or(DEFAULT_TOLERANCE),
            )?;
            normal.method = "dopri5".into();
            normal.tolerance = Some(tolerance);
            Method::Dopri5 { tolerance }
        }
        other => {
            return Err(Error::input(
                path,
                "trace.method",
                format!("unknown method `{other}` (expected `rk4`, `dopri5` or `adaptive`)"),
            ));
        }
    };
    let mut options = TraceOptions::new(method);
    if let Some(l) = spec.max_length {
        options.max_length = Some(positive(path, "trace.max_length", l)?);
    }
    Ok((options, normal))
}

/// Validates a `solver` section.
pub fn solver_settings(spec: &SolverSpec, path: &Path) -> Result<SolverSettings> {
    let method = match spec.method.as_str() {
        "lm" => SolverMethod::Lm,
        "nelder-mead" => SolverMethod::NelderMead,
        "auto" => SolverMethod::Auto,
        other => {
            return Err(Error::input(
                path,
                "solver.method",
                format!("unknown method `{other}` (expected `lm`, `nelder-mead` or `auto`)"),
            ));
        }
    };
    let tol = |field: &str, v: Option<f64>, default: f64| -> Result<f64> {
        match v {
            None => Ok(default),
            Some(v) if v.is_finite() && v >= 0.0 => Ok(v),
            Some(v) => Err(Error::input(
                path,
                format!("solver.{field}"),
                format!("must be a finite number ≥ 0, got {v}"),
            )),
        }
    };
    let max_iterations = spec.max_iterations.unwrap_or(200);
    if max_iterations == 0 {
        return Err(Error::input(
            path,
            "solver.max_iterations",
            "must be at least 1",
        ));
    }
    let starts = spec.starts.unwrap_or(8);
    if starts == 0 {
        return Err(Error::input(path, "solver.starts", "must be at least 1"));
    }
    Ok(SolverSettings {
        method,
        max_iterations,
        starts,
        ftol: tol("ftol", spec.ftol, 1e-15)?,
        xtol: tol("xtol", spec.xtol, 1e-12)?,
        gtol: tol("gtol", spec.gtol, 1e-15)?,
        seed: spec.seed.unwrap_or(0x6d69_7261_6765),
        target_objective: tol("target_objective", spec.target_objective, 1e-12)?,
    })
}

/// Reads an input file; failure is an input error naming the file (exit 2).
pub fn read_input(path: &Path) -> Result<String> {
    std::fs::read_to_string(path)
        .map_err(|e| Error::input(path, "-", format!("cannot read the file: {e}")))
}

/// Parses JSON text into `T`, turning every failure into one message that names
/// the file and the field (`what` names the kind of file for the top level).
pub fn parse_json<T: serde::de::DeserializeOwned>(
    text: &str,
    path: &Path,
    what: &str,
) -> Result<T> {
    let trimmed = text.trim_start();
    if trimmed.is_empty() {
        return Err(Error::input(
            path,
            "-",
            format!("the file is empty; a {what} file is a JSON object"),
        ));
    }
    if !trimmed.starts_with('{') {
        return Err(Error::input(
            path,
            "-",
            format!(
                "the top level must be a JSON object ({{ ... }}), found `{}`",
                trimmed.chars().next().unwrap_or(' ')
            ),
        ));
    }
    let mut de = serde_json::Deserializer::from_str(text);
    let value: T = serde_path_to_error::deserialize(&mut de).map_err(|e| {
        let field = e.path().to_string();
        let field = if field == "." { "-".to_string() } else { field };
        let inner = e.into_inner();
        let message = if inner.is_eof() {
            format!("the JSON ends too early (truncated file?): {inner}")
        } else {
            inner.to_string()
        };
        Error::input(path, field, message)
    })?;
    de.end().map_err(|e| {
        Error::input(
            path,
            "-",
            format!("unexpected text after the JSON object: {e}"),
        )
    })?;
    Ok(value)
}
