//! The `solver` section of a problem: as written ([`SolverSpec`]) and validated
//! ([`SolverSettings`]), which is what the fit runs with.

use crate::error::{Error, Result, ValueError};
use crate::medium::Medium;
use serde::{Deserialize, Serialize};
use std::path::Path;

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
    /// Objective F (m²) at or below which a fit counts as reaching its targets
    /// and Nelder–Mead stops; above it, `auto` restarts. Set here, a fit that
    /// ends above it fails (exit code 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub target_objective: Option<f64>,
    /// Size of the simplex, relative to the starting one, below which
    /// Nelder–Mead stops.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub simplex_xtol: Option<f64>,
    /// Relative spread of F over the simplex below which Nelder–Mead stops.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub simplex_ftol: Option<f64>,
    /// Grow the model (`mirage fit --grow`, `crate::fit::grow`): add the terms
    /// the pairs call for, one at a time, instead of fitting the medium as is.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grow: Option<bool>,
    /// Endpoint noise σ (metres, per residual component) that the grown
    /// model's criterion assumes; absent: estimated from the residuals.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise: Option<f64>,
    /// Most terms growing may add (default [`DEFAULT_MAX_TERMS`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_terms: Option<usize>,
    /// Whether LM may first converge under a cheaper tracer and then finish
    /// under the problem's own (`crate::fit::surrogate`); default `true`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surrogate: Option<bool>,
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
            simplex_xtol: None,
            simplex_ftol: None,
            grow: None,
            noise: None,
            max_terms: None,
            surrogate: None,
        }
    }
}

/// Which optimiser fits the free parameters (also `mirage fit --method`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
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
    /// Whether a fit that ends above `target_objective` fails (exit code 1):
    /// the problem file sets it (or `mirage fit --target-objective` does). The
    /// default target steers `auto` and stops Nelder–Mead, but failing on it
    /// would fail every fit of targets that cannot all be met.
    pub target_enforced: bool,
    /// Nelder–Mead stops when its simplex is this small relative to the
    /// starting one (`crate::fit::nelder_mead`).
    pub simplex_xtol: f64,
    /// Nelder–Mead stops when F differs over the simplex by less than this
    /// times F.
    pub simplex_ftol: f64,
    /// Grow the model instead of fitting it as is (`crate::fit::grow`).
    pub grow: Option<GrowSettings>,
    /// Whether LM may converge under a cheaper tracer first and then finish
    /// under the problem's own, when that is cheaper (`crate::fit::surrogate`).
    pub surrogate: bool,
}

/// Validated settings of `mirage fit --grow` (`solver.grow`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GrowSettings {
    /// Endpoint noise σ (m per residual component); `None`: estimated.
    pub noise: Option<f64>,
    /// Most terms to add.
    pub max_terms: usize,
}

/// Default of `solver.max_terms` / `--max-terms`.
pub const DEFAULT_MAX_TERMS: usize = 4;

/// Checks a noise σ (`solver.noise`, `--noise`, `pairs[i].noise`): finite
/// and > 0 metres. It lives beside the pairs, which use it too.
pub use crate::pair::check_noise;

/// Checks a term limit (`solver.max_terms`, `--max-terms`): at least 1.
pub fn check_max_terms(v: usize) -> std::result::Result<usize, ValueError> {
    if v >= 1 {
        Ok(v)
    } else {
        Err(ValueError::OutOfRange {
            rule: "must be at least 1 (the number of terms growing may add)".into(),
        })
    }
}

/// Why `medium` cannot be grown (`crate::fit::grow`), if it cannot: growing
/// adds terms of the logistic model (scaled against the terms already there)
/// or of real air (temperature terms in kelvins).
pub fn grow_unsupported(medium: &Medium) -> Option<String> {
    match medium {
        Medium::Logistic(m) if m.amplitude_sum() > 0.0 => None,
        Medium::Logistic(_) => Some(
            "growing starts from a medium with at least one term (a background): the terms it adds are scaled against it"
                .into(),
        ),
        Medium::Air(_) => None,
        other => Some(format!(
            "growing adds terms of the logistic model (an inversion, hot spots) or of real air (a surface layer, an inversion, hot spots in kelvins); this medium is the {} model",
            other.kind_name()
        )),
    }
}

/// Validates the growth fields of a `solver` section against `method`.
fn grow_settings(
    spec: &SolverSpec,
    method: SolverMethod,
    path: &Path,
) -> Result<Option<GrowSettings>> {
    let noise = spec
        .noise
        .map(check_noise)
        .transpose()
        .map_err(|e| Error::input(path, "solver.noise", e.to_string()))?;
    let max_terms = spec
        .max_terms
        .map(check_max_terms)
        .transpose()
        .map_err(|e| Error::input(path, "solver.max_terms", e.to_string()))?;
    if spec.grow != Some(true) {
        let stray = [
            ("noise", noise.is_some()),
            ("max_terms", max_terms.is_some()),
        ];
        if let Some((field, _)) = stray.iter().find(|(_, set)| *set) {
            return Err(Error::input(
                path,
                format!("solver.{field}"),
                "applies only when the model is grown (`\"grow\": true`)",
            ));
        }
        return Ok(None);
    }
    if method == SolverMethod::NelderMead {
        return Err(Error::input(
            path,
            "solver.grow",
            "growing fits every candidate with Levenberg–Marquardt: use method `lm` or `auto`, not `nelder-mead`",
        ));
    }
    Ok(Some(GrowSettings {
        noise,
        max_terms: max_terms.unwrap_or(DEFAULT_MAX_TERMS),
    }))
}

/// Default of `simplex_xtol`: the simplex 1e-10 of its starting size, that is
/// about 1e-11 of each parameter's value or range (`crate::fit::solve`'s
/// starting simplex), near LM's `xtol`.
pub const DEFAULT_SIMPLEX_XTOL: f64 = 1e-10;

/// Default of `simplex_ftol`: F the same at every vertex to 1e-12 (relative).
pub const DEFAULT_SIMPLEX_FTOL: f64 = 1e-12;

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
        target_enforced: spec.target_objective.is_some(),
        simplex_xtol: tol("simplex_xtol", spec.simplex_xtol, DEFAULT_SIMPLEX_XTOL)?,
        simplex_ftol: tol("simplex_ftol", spec.simplex_ftol, DEFAULT_SIMPLEX_FTOL)?,
        grow: grow_settings(spec, method, path)?,
        surrogate: spec.surrogate.unwrap_or(true),
    })
}
