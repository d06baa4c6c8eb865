//! Results written by `mirage trace` (and the pieces `mirage fit` reuses).

use crate::io::Problem;
use crate::io::problem::TraceSpec;
use crate::medium::{IndexField, LogisticMedium};
use crate::trace::{End, RayState, Stats};
use serde::Serialize;

/// One pair's traced outcome.
#[derive(Clone, Debug, Serialize)]
pub struct PairReport {
    /// Where the ray ended (on the target plane unless `unreachable`).
    pub endpoint: [f64; 3],
    /// The target.
    pub target: [f64; 3],
    /// |endpoint − target| (metres).
    pub distance: f64,
    /// w·(endpoint − target).
    pub residual: [f64; 3],
    /// The ray dipped below the ground before its target plane.
    pub occluded: bool,
    /// The ray never reached its target plane.
    pub unreachable: bool,
    /// Why the trace ended.
    pub end: End,
    /// Arc length travelled (metres).
    pub arc_length: f64,
    /// Integration statistics.
    pub stats: Stats,
}

/// Totals over all pairs.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Totals {
    /// F = ½ Σ |r_i|² (m²).
    pub objective: f64,
    /// Σ w_i d_i (m).
    pub summed_distance: f64,
    /// max d_i (m).
    pub max_distance: f64,
}

/// The result of `mirage trace`.
#[derive(Clone, Debug, Serialize)]
pub struct TraceReport {
    /// Problem name.
    pub problem: String,
    /// The medium traced.
    pub medium: LogisticMedium,
    /// Trace settings used.
    pub trace: TraceSpec,
    /// Totals.
    #[serde(flatten)]
    pub totals: Totals,
    /// Per pair.
    pub pairs: Vec<PairReport>,
    /// Integration statistics summed over pairs.
    pub stats: Stats,
}

/// Traces every pair of `problem` through `medium` and reports endpoints,
/// distances, flags and totals. Pairs are traced in parallel; the result does
/// not depend on the number of threads.
pub fn trace_pairs(problem: &Problem, medium: &LogisticMedium) -> TraceReport {
    use rayon::prelude::*;
    let field = medium.field();
    let pairs: Vec<PairReport> = problem
        .pairs
        .par_iter()
        .map(|pair| pair_report(pair, &field, &problem.trace, None))
        .collect();
    let mut totals = Totals::default();
    let mut stats = Stats::default();
    for (p, pr) in problem.pairs.iter().zip(&pairs) {
        totals.objective += 0.5 * pr.residual.iter().map(|r| r * r).sum::<f64>();
        totals.summed_distance += p.weight * pr.distance;
        totals.max_distance = totals.max_distance.max(pr.distance);
        stats += pr.stats;
    }
    TraceReport {
        problem: problem.name.clone(),
        medium: medium.clone(),
        trace: problem.trace_spec.clone(),
        totals,
        pairs,
        stats,
    }
}

/// Traces one pair (optionally recording its path).
pub fn pair_report<F: IndexField + ?Sized>(
    pair: &crate::pair::PointPair,
    field: &F,
    options: &crate::trace::TraceOptions,
    path: Option<&mut Vec<RayState>>,
) -> PairReport {
    let (t, r) = pair.evaluate::<f64, _>(field, options, path);
    PairReport {
        endpoint: t.endpoint.to_array(),
        target: pair.target,
        distance: (t.endpoint - pair.target()).norm(),
        residual: r.to_array(),
        occluded: t.occluded,
        unreachable: t.unreachable,
        end: t.end,
        arc_length: t.arc_length,
        stats: t.stats,
    }
}

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
}

/// The solver's account of the fit.
#[derive(Clone, Debug, Serialize)]
pub struct SolverReport {
    /// `lm`, `nelder-mead` or `auto`.
    pub method: crate::io::problem::SolverMethod,
    /// The run whose result was kept.
    pub best_run: String,
    /// Iterations over all runs.
    pub iterations: u64,
    /// Residual evaluations (each traces every pair).
    pub residual_evaluations: u64,
    /// Jacobian evaluations (each traces every pair with dual numbers).
    pub jacobian_evaluations: u64,
    /// Evaluations of the ray equation's right-hand side, over everything.
    pub rhs_evaluations: u64,
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
}

/// The result of `mirage fit` (`docs/problem-format.md`, "The result of a fit").
#[derive(Clone, Debug, Serialize)]
pub struct FitReport {
    /// Problem name.
    pub problem: String,
    /// The fitted medium, in the problem schema (reusable as input).
    pub medium: LogisticMedium,
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
}
