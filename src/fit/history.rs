//! What a fit remembers of its path: one record per solver iteration, per start.
//! The result file stores it and the convergence plots are drawn from it.

use serde::{Deserialize, Serialize};

/// The state after one iteration of a solver.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct IterationRecord {
    /// Iteration number (0: the starting point).
    pub iteration: u64,
    /// Wall time since the start of this run (seconds).
    pub elapsed_s: f64,
    /// Objective F = ½ Σ |r_i|² at the best point so far (m²).
    pub objective: f64,
    /// Free parameter values at the best point so far, in the order of
    /// [`History::param_names`].
    pub params: Vec<f64>,
}

/// One solver run from one starting point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunHistory {
    /// Label for legends, e.g. `lm (start 0)` or `nelder-mead`.
    pub label: String,
    /// Records in iteration order.
    pub records: Vec<IterationRecord>,
}

/// All runs of one fit.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct History {
    /// Path names of the free parameters (`hotspots[0].radius`).
    pub param_names: Vec<String>,
    /// The runs, in the order they were made.
    pub runs: Vec<RunHistory>,
}
