//! The result of a fit, as `mirage fit -o` writes it (`docs/problem-format.md`,
//! "The result of a fit").

use crate::evaluate::{PairReport, Totals};
use crate::medium::Medium;
use crate::problem::{SolverMethod, TraceSpec};
use serde::Serialize;

/// One free parameter in a fit result.
#[derive(Clone, Debug, Serialize)]
pub struct ParamReport {
    /// Path name (`hotspots[0].radius`).
    pub name: String,
    /// Value in the problem file.
    pub start: f64,
    /// Fitted value.
    pub value: f64,
    /// Standard error; `null` when the pairs do not determine the parameter.
    pub standard_error: Option<f64>,
    /// Whether the pairs determine it.
    pub determined: bool,
    /// `[low, high]` if bounded.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bounds: Option<[f64; 2]>,
    /// The fitted value sits on a bound.
    pub at_bound: bool,
}

/// One solver run, summarised.
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    /// `lm`, `lm (start 3)`, `nelder-mead`, `lm (polish)`.
    pub label: String,
    /// Starting parameters.
    pub start: Vec<f64>,
    /// Final parameters.
    pub end: Vec<f64>,
    /// Final objective F (m²).
    pub objective: f64,
    /// Iterations.
    pub iterations: u64,
    /// Why it stopped.
    pub stop_reason: String,
    /// Whether the solver reports convergence.
    pub converged: bool,
    /// Whether it ran on the surrogate tracer (`crate::fit::surrogate`): its
    /// `objective` is that tracer's F.
    pub surrogate: bool,
}

/// The surrogate stage of a fit (`crate::fit::surrogate`).
#[derive(Clone, Debug, Serialize)]
pub struct SurrogateReport {
    /// The surrogate tracer, in words (`dopri5 tolerance 1e-9`).
    pub tracer: String,
    /// Right-hand-side evaluations of one trace of the pairs at the start by
    /// the problem's tracer (estimated: RK4's 4 a step).
    pub problem_rhs_at_start: u64,
    /// The same by the surrogate tracer (counted).
    pub surrogate_rhs_at_start: u64,
    /// Iterations of the surrogate runs.
    pub iterations: u64,
    /// Residual evaluations under the surrogate tracer.
    pub residual_evaluations: u64,
    /// Jacobian evaluations under the surrogate tracer.
    pub jacobian_evaluations: u64,
    /// Right-hand-side evaluations under the surrogate tracer.
    pub rhs_evaluations: u64,
}

/// The solver's account of the fit.
#[derive(Clone, Debug, Serialize)]
pub struct SolverReport {
    /// `lm`, `nelder-mead` or `auto`.
    pub method: SolverMethod,
    /// The run whose result was kept.
    pub best_run: String,
    /// Iterations over all runs.
    pub iterations: u64,
    /// Residual evaluations under the problem's tracer (each traces every
    /// pair).
    pub residual_evaluations: u64,
    /// Jacobian evaluations under the problem's tracer (each traces every
    /// pair with its derivatives).
    pub jacobian_evaluations: u64,
    /// Evaluations of the ray equation's right-hand side under the problem's
    /// tracer, over everything.
    pub rhs_evaluations: u64,
    /// The surrogate stage, when the fit had one (its counts are apart from
    /// the ones above).
    pub surrogate: Option<SurrogateReport>,
    /// Wall time of the fit (seconds).
    pub wall_time_s: f64,
    /// Why the kept run stopped.
    pub stop_reason: String,
    /// Whether the kept run converged.
    pub converged: bool,
    /// Whether F ≤ the target objective.
    pub reached_target: bool,
    /// The target objective (m²).
    pub target_objective: f64,
    /// Whether the problem (or `mirage fit --target-objective`) sets the
    /// target, so that a fit above it fails (exit code 1); a default target
    /// does not.
    pub target_enforced: bool,
}

/// The result of `mirage fit` (`docs/problem-format.md`, "The result of a fit").
#[derive(Clone, Debug, Serialize)]
pub struct FitReport {
    /// Problem name.
    pub problem: String,
    /// The fitted medium, in the problem schema (reusable as input).
    pub medium: Medium,
    /// The free parameters.
    pub parameters: Vec<ParamReport>,
    /// Parameter combinations the pairs cannot determine.
    pub undetermined: Vec<crate::fit::identify::NullDirection>,
    /// Whether the standard errors are scaled by the residual variance.
    pub standard_errors_scaled: bool,
    /// Totals at the fitted medium.
    #[serde(flatten)]
    pub totals: Totals,
    /// Per pair, at the fitted medium.
    pub pairs: Vec<PairReport>,
    /// Solver summary.
    pub solver: SolverReport,
    /// Every run.
    pub runs: Vec<RunReport>,
    /// Objective and parameters per iteration, per run.
    pub history: crate::fit::History,
    /// Trace settings used.
    pub trace: TraceSpec,
    /// The round earth the pairs were traced over (absent: the flat ground).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub earth: Option<crate::trace::EarthSpec>,
    /// For a medium that is not real air: the air that makes the same mirage
    /// (`crate::profile`, as `mirage air` reports it), in brief.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub implied_air: Option<crate::profile::ImpliedAirSummary>,
    /// How the model was grown (`mirage fit --grow`), step by step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grow: Option<crate::fit::grow::GrowReport>,
    /// A photo problem's camera and marks (`docs/photo.md`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub photo: Option<crate::fit::photo::PhotoReport>,
}
