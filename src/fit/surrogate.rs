//! Converging under a cheaper tracer first: two-fidelity Levenberg–Marquardt.
//!
//! A fit's cost is its tracer's. With fixed RK4 steps of a fraction of a
//! metre, a 36-pair, 6-parameter fit spends about a second in some 16 LM
//! iterations, and most of them only carry the parameters from the start to
//! the neighbourhood of the answer: work that needs the rays to far less than
//! the problem's accuracy. Adaptive Dormand–Prince at the default tolerance
//! (1e-9 per step) traces the same rays to better than a micrometre with a
//! few hundred right-hand-side evaluations where RK4 at 0.5 m takes 20,000
//! over 2.5 km.
//!
//! # Algorithm
//!
//! When the problem's tracer is fixed-step RK4 and the surrogate tracer,
//! Dormand–Prince 5(4) at [`SURROGATE_TOLERANCE`] with the problem's other
//! trace settings (ground, earth, length limit), traces the pairs at the
//! start with at most 1/[`MIN_SAVING`] of the right-hand-side evaluations
//! RK4 needs (4 a step over each pair's straight distance), the fit runs in
//! two stages:
//!
//! 1. the problem's strategy (`lm`, or `auto` with its restarts and
//!    Nelder–Mead fallback) on the *surrogate* objective: the same pairs,
//!    medium, free parameters and bounds, traced by Dormand–Prince;
//! 2. LM on the problem's own objective from the surrogate's answer, started
//!    with light damping ([`REFINE_DAMPING`]): it starts next to the answer,
//!    where the Gauss–Newton model is good, and the heavy first damping that
//!    keeps a far start out of local minima would only cost iterations (from
//!    a start 1e-7 off, the default damping took 13 iterations at 0.5 m).
//!    Its convergence tests are the problem's.
//!
//! Under `auto`, if that LM ends above the target objective although the
//! surrogate's answer met it, the two tracers disagree by more than the
//! target allows, and the problem's own strategy runs from the start as if
//! there were no surrogate. `nelder-mead` never uses a surrogate (it would no
//! longer be a derivative-free fit), nor do fits of adaptive problems (their
//! tracer is the surrogate's kind already) or problems with no free
//! parameters. `"surrogate": false` in the `solver` section turns it off.
//!
//! # Invariants
//!
//! - The answer is where LM under the problem's own tracer stopped: F, the
//!   residuals, the Jacobian behind the standard errors and every figure of
//!   the report are the problem's tracer's. The surrogate only chooses where
//!   that LM starts; its runs are reported, marked, and never chosen as the
//!   best run (their F is another tracer's).
//! - The decision counts evaluations, never time, so it is reproducible and
//!   the same for any number of threads.
//!
//! # Accuracy
//!
//! Nothing is approximated in the answer. How close the surrogate's answer
//! lands decides how many refining iterations follow: on the 36-pair RK4
//! sweep problem its parameters are 1e-8 to 1e-7 (relative) from the
//! problem's answer, and LM refines them in two iterations.

use super::objective::Objective;
use crate::problem::{SolverMethod, SolverSettings};
use crate::trace::Method;

/// Dormand–Prince's local error bound per step in the surrogate tracer: the
/// default of adaptive problems (metres).
pub const SURROGATE_TOLERANCE: f64 = crate::problem::DEFAULT_TOLERANCE;

/// The surrogate must trace the pairs with at most this fraction's inverse
/// of the problem tracer's right-hand-side evaluations. The refining stage
/// costs about two of the problem's iterations against a direct fit's ten to
/// twenty, so even a twofold saving per evaluation pays.
pub const MIN_SAVING: f64 = 2.0;

/// LM's initial damping τ in the refining stage (μ₀ = τ·max diag of the
/// scaled JᵀJ, which is 1): a Gauss–Newton step in every direction resolved
/// to better than 1e-6 of the best one.
pub const REFINE_DAMPING: f64 = 1e-12;

/// The surrogate objective of a fit, and why it was chosen.
#[derive(Debug)]
pub struct Surrogate {
    /// The pairs, medium and free parameters of the fit, traced by the
    /// surrogate tracer.
    pub objective: Objective,
    /// Right-hand-side evaluations the problem's tracer needs at the start
    /// (estimated: RK4's 4 a step over each pair's straight distance).
    pub problem_rhs: u64,
    /// Right-hand-side evaluations the surrogate took at the start.
    pub surrogate_rhs: u64,
}

impl Surrogate {
    /// The surrogate tracer, as `trace` sections write it.
    pub fn describe(&self) -> String {
        describe(self.objective.options().method)
    }
}

/// A tracer method in words: `dopri5 tolerance 1e-9`, `rk4 step 0.5 m`.
pub fn describe(method: Method) -> String {
    match method {
        Method::Rk4 { step } => format!("rk4 step {step} m"),
        Method::Dopri5 { tolerance } => format!("dopri5 tolerance {tolerance:e}"),
    }
}

/// The surrogate of `objective`'s fit with `settings`, when one is allowed
/// and saves at least [`MIN_SAVING`]× the right-hand-side evaluations at
/// `x0` (which costs one trace of the pairs by the surrogate tracer).
pub fn choose(objective: &Objective, settings: &SolverSettings, x0: &[f64]) -> Option<Surrogate> {
    if !settings.surrogate || settings.method == SolverMethod::NelderMead || x0.is_empty() {
        return None;
    }
    let Method::Rk4 { step } = objective.options().method else {
        return None;
    };
    let problem_rhs: f64 = objective
        .pairs()
        .iter()
        .map(|p| 4.0 * ((p.target() - p.origin()).norm() / step).ceil() + 1.0)
        .sum();
    let mut options = *objective.options();
    options.method = Method::Dopri5 {
        tolerance: SURROGATE_TOLERANCE,
    };
    let surrogate = objective.with_options(options);
    let (r, _) = surrogate.residuals(x0);
    let surrogate_rhs = surrogate.counts().2;
    // A start the surrogate cannot trace is left to the problem's own fit,
    // which reports it in its own terms.
    if !r.iter().all(|v| v.is_finite()) || surrogate_rhs as f64 * MIN_SAVING > problem_rhs {
        return None;
    }
    Some(Surrogate {
        objective: surrogate,
        problem_rhs: problem_rhs as u64,
        surrogate_rhs,
    })
}
