//! Box-constrained Levenberg–Marquardt least-squares solver for [`argmin`].
//!
//! Minimises `F(x) = ½‖r(x)‖²` for a residual vector `r: ℝⁿ → ℝᵐ` with
//! Jacobian `J = ∂r/∂x`, optionally subject to box bounds `lower ≤ x ≤ upper`.
//! [`LevenbergMarquardt`] implements [`Solver`] for [`LmState`], so it runs
//! under [`argmin::core::Executor`] with observers, counters and
//! `max_iters` like argmin's built-in solvers.
//!
//! # Algorithm
//!
//! One argmin iteration evaluates at most one trial point (none when the
//! step is exactly zero or already within xtol, see Termination):
//!
//! 1. **Scaling** (Moré 1978). `D = diag(d)` with `dⱼ` the running maximum of
//!    the Euclidean norms of column `j` of `J` over all accepted points
//!    (a column that has only ever been zero gets `dⱼ = 1`). All step-size
//!    and damping decisions are made in the scaled variables `D x`, so the
//!    iterates do not depend on the units of the parameters.
//! 2. **Active set** (projected LM). A parameter sitting on a bound whose
//!    gradient `g = Jᵀr` points out of the box (or whose bounds coincide) is
//!    held fixed for the step; the remaining parameters are *free*.
//! 3. **Damped step.** On the free parameters the step solves the linear
//!    least-squares problem `[J; √μ·D] δ = [−r; 0]`. It is computed from an
//!    SVD of the column-scaled free Jacobian `J D⁻¹` (after a thin QR when
//!    `m > n`), never from `JᵀJ`, with singular values below
//!    `ε·max(m, n)·σ_max` discarded. An exactly flat direction therefore gets
//!    a zero step component instead of a NaN, and the decomposition is
//!    reused for every `μ` tried at the same point.
//! 4. **Projection.** The trial point is `P(x + δ)`, the clamp onto the box,
//!    so no trial point ever leaves the box. If the clamp changed the step,
//!    a projected scaled-gradient (Cauchy) step `P(x − t D⁻²g)` with the
//!    exact minimising `t` of the damped model is also formed, and the one
//!    with the smaller damped model value is used. The Cauchy candidate
//!    guarantees sufficient model decrease, which the clamped LM step
//!    alone does not, and keeps the method converging to a KKT point.
//! 5. **Gain ratio** `ρ = (F(x) − F(x_trial)) / (L(0) − L(x_trial − x))`,
//!    where `L(s) = ½‖r + J s‖²` is the Gauss–Newton model evaluated at the
//!    *projected* step. The actual reduction is computed as
//!    `½(r − r_trial)ᵀ(r + r_trial)`, which stays accurate when it is far
//!    below `ε·F`; with `F − F_trial` the iterates would stall at about
//!    `√ε` relative accuracy. The step is accepted iff `ρ > 0` and the trial
//!    residual is finite; a non-finite residual counts as a rejection.
//! 6. **Damping update** (Nielsen 1999). Accept:
//!    `μ ← μ·max(⅓, 1 − (2ρ − 1)³)`, `ν ← 2`; reject: `μ ← μ·ν`, `ν ← 2ν`.
//!    Initially `μ = τ·max diag(D⁻¹JᵀJD⁻¹)`. One deviation: on rejection a
//!    `μ` below `σ²_min` (smallest resolved singular value of `J D⁻¹`, squared)
//!    is first raised to `σ²_min`, because smaller values leave the step
//!    unchanged and would only re-evaluate the same trial point. The
//!    Jacobian is evaluated only at accepted points.
//!
//! # Termination
//!
//! Checked after every iteration (and once at the starting point); the
//! reason is set on the state with `state.terminate_with(...)` as
//! `TerminationReason::SolverExit(s)`, `s` the text of one of the [`LmStop`]
//! variants ([`LmStop::from_reason`] reads it back):
//!
//! | reason | test |
//! |---|---|
//! | [`ZeroResidual`](LmStop::ZeroResidual) | `F(x) == 0` exactly |
//! | [`Gtol`](LmStop::Gtol) | `maxⱼ |pgⱼ| / (‖Jⱼ‖·‖r‖) ≤ gtol`, `pg` the projected gradient (MINPACK's cosine test) |
//! | [`Ftol`](LmStop::Ftol) | actual and predicted relative reductions of `F` both `≤ ftol`, `ρ ≤ 2` (MINPACK) |
//! | [`Xtol`](LmStop::Xtol) | `‖D δ‖ ≤ xtol·(‖D x‖ + xtol)`, `δ` the step just tried (accepted or not), or the step about to be tried when its predicted reduction is at most `F/2` (it is then not evaluated) |
//! | [`StallDamping`](LmStop::StallDamping) | `μ > 1e20` |
//! | [`StallRejections`](LmStop::StallRejections) | `max_rejections` consecutive rejected steps |
//!
//! The xtol test also runs on each step before it is evaluated: a step that
//! passes it, and that the Gauss–Newton model expects to lower `F` by at
//! most half, could only move `x` by less than the tolerance and `F` by a
//! fraction, so the run ends without the evaluation (MINPACK evaluates it
//! first: one residual and one Jacobian more). The ftol and xtol tests also run after rejected steps, as
//! in MINPACK:
//! once no step can improve `F` at working precision, `μ` grows until the
//! tried step passes one of them. They are skipped while the last evaluated
//! trial residual was non-finite, so shrinking away from a non-finite region
//! ends as a stall rather than as convergence. A tolerance of `0` disables
//! the ftol/xtol test; `gtol = 0` still stops at an exactly stationary point.
//!
//! argmin itself adds `MaxItersReached` (`max_iters`, counting accepted *and*
//! rejected iterations) and `TargetCostReached` (an absolute target on `F`,
//! set with `state.target_cost(t)` in `Executor::configure`).
//! [`LevenbergMarquardt::is_converged`] tells successful reasons from the rest.
//!
//! # Bookkeeping
//!
//! The state holds the current accepted parameter vector, its cost `F` and
//! its Jacobian (`state.get_jacobian()`), so the final `J` is available to
//! the caller, e.g. for a covariance estimate. Each iteration returns a
//! [`KV`] with `mu`, `rho`, `step_norm` (`‖D δ‖`), `accepted`, `cost_trial`,
//! `pred` (predicted reduction), `gnorm`, `n_fixed` and `rejections`
//! (`rho` is `−∞` and `cost_trial` `+∞` for a non-finite trial residual).
//! Every accepted point is also recorded as the state's best point, even
//! when its rounded `F` ties the previous one (argmin's own bookkeeping
//! records only strict decreases), so `get_param()` and `get_best_param()`
//! agree at the end of a run.
//!
//! # References
//!
//! * J. J. Moré, *The Levenberg–Marquardt algorithm: implementation and
//!   theory*, Numerical Analysis, LNM 630, Springer, 1978, pp. 105–116.
//! * H. B. Nielsen, *Damping parameter in Marquardt's method*,
//!   Tech. Rep. IMM-REP-1999-05, DTU, 1999.
//! * C. Kanzow, N. Yamashita, M. Fukushima, *Levenberg–Marquardt methods
//!   with strong local convergence properties for solving nonlinear
//!   equations with convex constraints*, J. Comput. Appl. Math. 172 (2004)
//!   375–397.
//! * D. P. Bertsekas, *Projected Newton methods for optimization problems
//!   with simple constraints*, SIAM J. Control Optim. 20 (1982) 221–246.
//!
//! # Example
//!
//! ```
//! use argmin::core::{Error, Executor, Jacobian, Operator, State};
//! use nalgebra::{DMatrix, DVector, dmatrix, dvector};
//! use mirage::fit::lm::LevenbergMarquardt;
//!
//! /// Rosenbrock as least squares: r = [10(x₁ − x₀²), 1 − x₀].
//! struct Rosenbrock;
//!
//! impl Operator for Rosenbrock {
//!     type Param = DVector<f64>;
//!     type Output = DVector<f64>;
//!     fn apply(&self, x: &DVector<f64>) -> Result<DVector<f64>, Error> {
//!         Ok(dvector![10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]])
//!     }
//! }
//!
//! impl Jacobian for Rosenbrock {
//!     type Param = DVector<f64>;
//!     type Jacobian = DMatrix<f64>;
//!     fn jacobian(&self, x: &DVector<f64>) -> Result<DMatrix<f64>, Error> {
//!         Ok(dmatrix![-20.0 * x[0], 10.0; -1.0, 0.0])
//!     }
//! }
//!
//! let solver = LevenbergMarquardt::new()
//!     .with_bounds(dvector![f64::NEG_INFINITY, -1.0], dvector![0.5, f64::INFINITY])?;
//! let res = Executor::new(Rosenbrock, solver)
//!     .configure(|s| s.param(dvector![-1.2, 1.0]).max_iters(200))
//!     .run()?;
//! let x = res.state().get_best_param().unwrap();
//! // The unconstrained minimum (1, 1) is outside the box: KKT point on x₀ = 0.5.
//! assert!((x[0] - 0.5).abs() < 1e-12 && (x[1] - 0.25).abs() < 1e-8);
//! assert!(LevenbergMarquardt::is_converged(
//!     res.state().get_termination_reason().unwrap()
//! ));
//! # Ok::<(), Error>(())
//! ```

use argmin::core::{
    ArgminError, Error, IterState, Jacobian, KV, Operator, Problem, Solver, State,
    TerminationReason,
};
use nalgebra::{DMatrix, DVector, SVD};

mod stop;
#[cfg(test)]
mod tests;

pub use stop::LmStop;

/// The argmin state type [`LevenbergMarquardt`] works on: parameters and
/// residuals are `DVector<f64>`, the Jacobian is an `m × n` `DMatrix<f64>`,
/// the cost is `F = ½‖r‖²`. Gradient, Hessian and residual slots are unused.
pub type LmState = IterState<DVector<f64>, (), DMatrix<f64>, (), (), f64>;

/// Damping above which no acceptable step is considered findable. In the
/// scaled variables the undamped curvature is at most of order one, so at
/// `μ = 1e20` the step is ~20 orders of magnitude below a gradient step.
const MU_MAX: f64 = 1e20;

/// Keeps the damping strictly positive after many `×⅓` reductions. Small
/// values are harmless because rounding-level singular values are cut off
/// in the SVD solve; a floor any higher would throttle convergence on
/// problems whose Jacobian becomes singular at the solution (Powell).
const MU_MIN: f64 = 1e-300;

/// Levenberg–Marquardt solver with Moré scaling, Nielsen damping, an
/// SVD-based damped step and projected box constraints.
///
/// See the [module documentation](self) for the algorithm, the termination
/// tests and references.
///
/// Defaults:
///
/// | setting | default | setter |
/// |---|---|---|
/// | `ftol` | `1e-10` | [`with_ftol`](Self::with_ftol) |
/// | `xtol` | `1e-10` | [`with_xtol`](Self::with_xtol) |
/// | `gtol` | `1e-12` | [`with_gtol`](Self::with_gtol) |
/// | `τ` (initial damping factor) | `1e-3` | [`with_initial_damping`](Self::with_initial_damping) |
/// | max consecutive rejections | `30` | [`with_max_rejections`](Self::with_max_rejections) |
/// | bounds | none | [`with_bounds`](Self::with_bounds) |
#[derive(Clone, Debug)]
pub struct LevenbergMarquardt {
    ftol: f64,
    xtol: f64,
    gtol: f64,
    tau: f64,
    max_rejections: u64,
    bounds: Option<(DVector<f64>, DVector<f64>)>,
    /// Per-run working data; rebuilt by `init`, so a solver value can be reused.
    work: Option<Work>,
}

/// Quantities tied to the current accepted point that the solver keeps
/// between iterations (the state only carries `x`, `F` and `J`).
#[derive(Clone, Debug)]
struct Work {
    r: DVector<f64>,
    g: DVector<f64>,
    d: DVector<f64>,
    free: Vec<usize>,
    decomp: Option<Decomp>,
    gnorm: f64,
    mu: f64,
    nu: f64,
    rejections: u64,
    /// Whether the most recently evaluated trial residual was finite. The
    /// ftol/xtol tests are skipped while it is not: a step that shrank to
    /// nothing while fleeing non-finite residuals is a stall, not convergence.
    last_trial_finite: bool,
}

/// SVD of the scaled free Jacobian `J_F D_F⁻¹ = U Σ Vᵀ`, with `c = Uᵀ r`
/// precomputed so that a step for any `μ` costs only `O(n²)`.
#[derive(Clone, Debug)]
struct Decomp {
    sigma: DVector<f64>,
    v: DMatrix<f64>,
    c: DVector<f64>,
    cutoff: f64,
}

/// What one iteration tried, as its [`KV`] reports it.
struct Trial {
    mu: f64,
    rho: f64,
    step_norm: f64,
    accepted: bool,
    cost_trial: f64,
    pred: f64,
}

impl Trial {
    /// The iteration's key-value record (see "Bookkeeping" above), with the
    /// working data `w` after the iteration and `n` parameters.
    fn kv(self, w: &Work, n: usize) -> KV {
        argmin::kv!(
            "mu" => self.mu;
            "rho" => self.rho;
            "step_norm" => self.step_norm;
            "accepted" => self.accepted;
            "cost_trial" => self.cost_trial;
            "pred" => self.pred;
            "gnorm" => w.gnorm;
            "n_fixed" => (n - w.free.len()) as u64;
            "rejections" => w.rejections;
        )
    }
}

/// A candidate trial point together with its model quantities.
struct Candidate {
    x_trial: DVector<f64>,
    step: DVector<f64>,
    /// Predicted reduction of the undamped Gauss–Newton model.
    pred: f64,
    /// Predicted reduction of the damped model (used to compare candidates).
    damped_red: f64,
}

fn invalid(text: impl Into<String>) -> Error {
    ArgminError::InvalidParameter { text: text.into() }.into()
}

fn not_initialized(text: impl Into<String>) -> Error {
    ArgminError::NotInitialized { text: text.into() }.into()
}

fn condition(text: impl Into<String>) -> Error {
    ArgminError::ConditionViolated { text: text.into() }.into()
}

fn all_finite<'a>(it: impl IntoIterator<Item = &'a f64>) -> bool {
    it.into_iter().all(|v| v.is_finite())
}

impl Default for LevenbergMarquardt {
    fn default() -> Self {
        Self::new()
    }
}

impl LevenbergMarquardt {
    /// Creates a solver with the default settings listed on
    /// [`LevenbergMarquardt`] and no bounds.
    pub fn new() -> Self {
        LevenbergMarquardt {
            ftol: 1e-10,
            xtol: 1e-10,
            gtol: 1e-12,
            tau: 1e-3,
            max_rejections: 30,
            bounds: None,
            work: None,
        }
    }

    fn check_tol(name: &str, tol: f64) -> Result<f64, Error> {
        if !tol.is_finite() || tol < 0.0 {
            return Err(invalid(format!(
                "LevenbergMarquardt: {name} must be finite and non-negative, got {tol}"
            )));
        }
        Ok(tol)
    }

    /// Sets the relative function tolerance: stop when both the actual and
    /// the predicted relative reduction of `F` in a step are at most `ftol`.
    /// `0` disables the test. Errors on negative or non-finite values.
    pub fn with_ftol(mut self, ftol: f64) -> Result<Self, Error> {
        self.ftol = Self::check_tol("ftol", ftol)?;
        Ok(self)
    }

    /// Sets the relative step tolerance: stop when
    /// `‖D δ‖ ≤ xtol·(‖D x‖ + xtol)`. `0` disables the test.
    /// Errors on negative or non-finite values.
    pub fn with_xtol(mut self, xtol: f64) -> Result<Self, Error> {
        self.xtol = Self::check_tol("xtol", xtol)?;
        Ok(self)
    }

    /// Sets the gradient tolerance: stop when the largest cosine between the
    /// residual and a Jacobian column, over parameters not held at a bound,
    /// is at most `gtol`. With `0` the test only fires at an exactly
    /// stationary point. Errors on negative or non-finite values.
    pub fn with_gtol(mut self, gtol: f64) -> Result<Self, Error> {
        self.gtol = Self::check_tol("gtol", gtol)?;
        Ok(self)
    }

    /// Sets `τ` in the initial damping `μ₀ = τ·max diag(D⁻¹JᵀJD⁻¹)`.
    /// Small values (`1e-6`) trust the Gauss–Newton model from the start,
    /// large ones (`1`) start closer to scaled gradient descent.
    /// Errors unless `τ` is finite and positive.
    pub fn with_initial_damping(mut self, tau: f64) -> Result<Self, Error> {
        if !tau.is_finite() || tau <= 0.0 {
            return Err(invalid(format!(
                "LevenbergMarquardt: initial damping tau must be finite and positive, got {tau}"
            )));
        }
        self.tau = tau;
        Ok(self)
    }

    /// Sets how many consecutive rejected steps end the run with
    /// [`LmStop::StallRejections`].
    /// Errors on `0`.
    pub fn with_max_rejections(mut self, max_rejections: u64) -> Result<Self, Error> {
        if max_rejections == 0 {
            return Err(invalid(
                "LevenbergMarquardt: max_rejections must be at least 1",
            ));
        }
        self.max_rejections = max_rejections;
        Ok(self)
    }

    /// Sets per-parameter box bounds `lower ≤ x ≤ upper`; `±∞` entries leave
    /// a side open and `lower[j] == upper[j]` fixes parameter `j`.
    ///
    /// Errors if the lengths differ, an entry is NaN, `lower[j] > upper[j]`,
    /// a lower bound is `+∞` or an upper bound is `−∞`. The length is checked
    /// against the parameter vector, and the starting point against the box,
    /// when the run starts.
    pub fn with_bounds(mut self, lower: DVector<f64>, upper: DVector<f64>) -> Result<Self, Error> {
        if lower.len() != upper.len() {
            return Err(invalid(format!(
                "LevenbergMarquardt: lower bound has length {} but upper bound has length {}",
                lower.len(),
                upper.len()
            )));
        }
        for (j, (&lo, &hi)) in lower.iter().zip(upper.iter()).enumerate() {
            if lo.is_nan() || hi.is_nan() {
                return Err(invalid(format!("LevenbergMarquardt: bound {j} is NaN")));
            }
            if lo > hi {
                return Err(invalid(format!(
                    "LevenbergMarquardt: lower bound {lo} exceeds upper bound {hi} for parameter {j}"
                )));
            }
            if lo == f64::INFINITY || hi == f64::NEG_INFINITY {
                return Err(invalid(format!(
                    "LevenbergMarquardt: bounds [{lo}, {hi}] of parameter {j} admit no finite value"
                )));
            }
        }
        self.bounds = Some((lower, upper));
        Ok(self)
    }

    /// Whether `reason` means the run ended at a solution: one of the
    /// `ftol`/`xtol`/`gtol`/zero-residual reasons of this solver, argmin's
    /// `SolverConverged` or `TargetCostReached`. Stalls, `MaxItersReached`,
    /// timeouts and interrupts are not.
    pub fn is_converged(reason: &TerminationReason) -> bool {
        match reason {
            TerminationReason::SolverConverged | TerminationReason::TargetCostReached => true,
            _ => LmStop::from_reason(reason).is_some_and(LmStop::is_converged),
        }
    }

    fn bound(&self, j: usize) -> (f64, f64) {
        match &self.bounds {
            Some((lo, hi)) => (lo[j], hi[j]),
            None => (f64::NEG_INFINITY, f64::INFINITY),
        }
    }

    /// Parameters that may move this step. A parameter is held when its
    /// bounds coincide or when it sits on a bound and descent (`−g`) would
    /// push it out of the box; moving it would only be undone by the
    /// projection and would spoil the step for the others.
    fn free_set(&self, x: &DVector<f64>, g: &DVector<f64>) -> Vec<usize> {
        (0..x.len())
            .filter(|&j| {
                let (lo, hi) = self.bound(j);
                let held = lo == hi || (x[j] <= lo && g[j] > 0.0) || (x[j] >= hi && g[j] < 0.0);
                !held
            })
            .collect()
    }

    /// MINPACK's scale-invariant gradient measure restricted to the free
    /// parameters: the largest cosine between `r` and a Jacobian column.
    fn gradient_measure(
        jac: &DMatrix<f64>,
        r: &DVector<f64>,
        g: &DVector<f64>,
        free: &[usize],
    ) -> f64 {
        let rnorm = r.norm();
        if rnorm == 0.0 {
            return 0.0;
        }
        free.iter()
            .filter_map(|&j| {
                let cn = jac.column(j).norm();
                (cn > 0.0).then(|| g[j].abs() / (cn * rnorm))
            })
            .fold(0.0, f64::max)
    }

    /// Moves `w` to a newly accepted point `(x, r, J)`: widens the running
    /// column-norm scaling and rebuilds the gradient, the active set, the
    /// factorisation and the gradient measure. Damping is left alone.
    fn refresh(
        &self,
        w: &mut Work,
        x: &DVector<f64>,
        r: DVector<f64>,
        jac: &DMatrix<f64>,
    ) -> Result<(), Error> {
        for (j, dj) in w.d.iter_mut().enumerate() {
            *dj = dj.max(jac.column(j).norm());
        }
        w.g = jac.tr_mul(&r);
        w.free = self.free_set(x, &w.g);
        w.decomp = Decomp::new(jac, &r, &w.d, &w.free)?;
        w.gnorm = Self::gradient_measure(jac, &r, &w.g, &w.free);
        w.r = r;
        Ok(())
    }

    /// Clamps `x + step` onto the box. The trial point is built directly
    /// from the clamped coordinates (not as `x + (clamped − x)`) so rounding
    /// can never put it outside; the returned step is what was actually taken.
    fn project(&self, x: &DVector<f64>, step: &DVector<f64>) -> (DVector<f64>, DVector<f64>, bool) {
        let mut clipped = false;
        let x_trial = DVector::from_fn(x.len(), |j, _| {
            let (lo, hi) = self.bound(j);
            let t = x[j] + step[j];
            let c = t.max(lo).min(hi);
            clipped |= c != t;
            c
        });
        let taken = &x_trial - x;
        (x_trial, taken, clipped)
    }

    fn candidate(
        &self,
        x: &DVector<f64>,
        step: &DVector<f64>,
        w: &Work,
        jac: &DMatrix<f64>,
    ) -> (Candidate, bool) {
        // An overflowing step must never reach `apply`; a zero step is
        // rejected without an evaluation and raises the damping instead.
        let (x_trial, taken, clipped) = if all_finite(step.iter()) {
            self.project(x, step)
        } else {
            (x.clone(), DVector::zeros(x.len()), false)
        };
        let js = jac * &taken;
        // L(0) − L(s) = −(Js)ᵀ(r + ½Js): avoids cancellation in ‖r‖² − ‖r + Js‖².
        let pred = -js.dot(&(&w.r + 0.5 * &js));
        let dstep = taken.component_mul(&w.d).norm_squared();
        let damped_red = pred - 0.5 * w.mu * dstep;
        (
            Candidate {
                x_trial,
                step: taken,
                pred,
                damped_red,
            },
            clipped,
        )
    }

    /// Chooses the trial point for the current `μ`: the projected LM step,
    /// or the projected scaled-gradient step when clipping made the LM step
    /// worse on the damped model.
    fn trial(&self, x: &DVector<f64>, w: &Work, jac: &DMatrix<f64>) -> Candidate {
        let n = x.len();
        let mut lm_step = DVector::zeros(n);
        if let Some(dec) = &w.decomp {
            let y = dec.solve(w.mu);
            for (c, &j) in w.free.iter().enumerate() {
                lm_step[j] = y[c] / w.d[j];
            }
        }
        let (lm, clipped) = self.candidate(x, &lm_step, w, jac);
        if !clipped && lm.damped_red > 0.0 {
            return lm;
        }

        let mut s = DVector::zeros(n);
        for &j in &w.free {
            s[j] = -w.g[j] / (w.d[j] * w.d[j]);
        }
        let num = -w.g.dot(&s);
        let denom = (jac * &s).norm_squared() + w.mu * s.component_mul(&w.d).norm_squared();
        if num > 0.0 && denom > 0.0 && num.is_finite() && denom.is_finite() {
            let (cauchy, _) = self.candidate(x, &(s * (num / denom)), w, jac);
            if cauchy.damped_red > lm.damped_red {
                return cauchy;
            }
        }
        lm
    }
}

impl Decomp {
    /// Factorises the scaled free Jacobian. Returns `None` when there is
    /// nothing to solve for (no residuals or no free parameters).
    fn new(
        jac: &DMatrix<f64>,
        r: &DVector<f64>,
        d: &DVector<f64>,
        free: &[usize],
    ) -> Result<Option<Decomp>, Error> {
        let m = jac.nrows();
        let k = free.len();
        if m == 0 || k == 0 {
            return Ok(None);
        }
        let scaled = DMatrix::from_fn(m, k, |i, c| jac[(i, free[c])] / d[free[c]]);
        // With m > k a thin QR first shrinks the SVD to k × k and avoids
        // forming the m × k left singular vectors.
        let (core, rhs) = if m > k {
            let qr = scaled.qr();
            let mut qtr = r.clone();
            qr.q_tr_mul(&mut qtr);
            (qr.r(), qtr.rows(0, k).into_owned())
        } else {
            (scaled, r.clone())
        };
        let max_niter = 1000 + 100 * k;
        let svd = SVD::try_new(core, true, true, 5.0 * f64::EPSILON, max_niter)
            .ok_or_else(|| condition("LevenbergMarquardt: SVD did not converge"))?;
        let (Some(u), Some(v_t)) = (svd.u, svd.v_t) else {
            return Err(condition(
                "LevenbergMarquardt: SVD did not return singular vectors",
            ));
        };
        let sigma = svd.singular_values;
        let sigma_max = sigma.iter().copied().fold(0.0, f64::max);
        Ok(Some(Decomp {
            c: u.tr_mul(&rhs),
            v: v_t.transpose(),
            cutoff: sigma_max * f64::EPSILON * (m.max(k) as f64),
            sigma,
        }))
    }

    /// Square of the smallest singular value the solve uses (0 if none).
    fn smallest_resolved_sq(&self) -> f64 {
        self.sigma
            .iter()
            .copied()
            .filter(|&s| s > self.cutoff && s > 0.0)
            .reduce(f64::min)
            .map_or(0.0, |s| s * s)
    }

    /// Scaled step `ŷ = −V diag(σ/(σ² + μ)) Uᵀr`, the minimiser of
    /// `‖r + Ĵŷ‖² + μ‖ŷ‖²`. Singular values at rounding level are dropped
    /// so flat directions get no step rather than an amplified error.
    fn solve(&self, mu: f64) -> DVector<f64> {
        let mut y = DVector::zeros(self.v.nrows());
        for (i, &s) in self.sigma.iter().enumerate() {
            if s > self.cutoff && s > 0.0 {
                let f = -s * self.c[i] / (s * s + mu);
                y.axpy(f, &self.v.column(i), 1.0);
            }
        }
        y
    }
}

impl<O> Solver<O, LmState> for LevenbergMarquardt
where
    O: Operator<Param = DVector<f64>, Output = DVector<f64>>
        + Jacobian<Param = DVector<f64>, Jacobian = DMatrix<f64>>,
{
    fn name(&self) -> &str {
        "Levenberg-Marquardt"
    }

    fn init(
        &mut self,
        problem: &mut Problem<O>,
        mut state: LmState,
    ) -> Result<(LmState, Option<KV>), Error> {
        self.work = None;
        let x = state.take_param().ok_or_else(|| {
            not_initialized(
                "LevenbergMarquardt requires an initial parameter vector; \
                 set it with `Executor::configure(|s| s.param(x0))`",
            )
        })?;
        let n = x.len();
        if !all_finite(x.iter()) {
            return Err(invalid(
                "LevenbergMarquardt: initial parameters are not finite",
            ));
        }
        if let Some((lo, hi)) = &self.bounds {
            if lo.len() != n {
                return Err(invalid(format!(
                    "LevenbergMarquardt: bounds have length {} but the parameter vector has length {n}",
                    lo.len()
                )));
            }
            if let Some(j) = (0..n).find(|&j| x[j] < lo[j] || x[j] > hi[j]) {
                return Err(invalid(format!(
                    "LevenbergMarquardt: initial parameter {j} = {} is outside its bounds [{}, {}]",
                    x[j], lo[j], hi[j]
                )));
            }
        }

        let r = problem.apply(&x)?;
        if !all_finite(r.iter()) {
            return Err(invalid(
                "LevenbergMarquardt: residual at the initial parameters is not finite",
            ));
        }
        let jac = problem.jacobian(&x)?;
        if jac.nrows() != r.len() || jac.ncols() != n {
            return Err(invalid(format!(
                "LevenbergMarquardt: Jacobian is {}x{} but residual has length {} and parameters length {n}",
                jac.nrows(),
                jac.ncols(),
                r.len()
            )));
        }
        if !all_finite(jac.iter()) {
            return Err(invalid(
                "LevenbergMarquardt: Jacobian at the initial parameters is not finite",
            ));
        }

        // Columns that are zero at the start get unit scale; the running max
        // below replaces it once the column becomes informative.
        let d = DVector::from_fn(n, |j, _| {
            let cn = jac.column(j).norm();
            if cn > 0.0 { cn } else { 1.0 }
        });
        let cost = 0.5 * r.norm_squared();
        let mut w = Work {
            r: DVector::zeros(0),
            g: DVector::zeros(n),
            d,
            free: Vec::new(),
            decomp: None,
            gnorm: 0.0,
            mu: 0.0,
            nu: 2.0,
            rejections: 0,
            last_trial_finite: true,
        };
        self.refresh(&mut w, &x, r, &jac)?;
        let max_diag = (0..n)
            .map(|j| (jac.column(j).norm() / w.d[j]).powi(2))
            .fold(0.0, f64::max);
        let mu = (self.tau * if max_diag > 0.0 { max_diag } else { 1.0 }).max(MU_MIN);
        w.mu = mu;
        let n_fixed = (n - w.free.len()) as u64;
        let gnorm = w.gnorm;

        let stop = if cost == 0.0 {
            Some(LmStop::ZeroResidual)
        } else if gnorm <= self.gtol {
            Some(LmStop::Gtol)
        } else {
            None
        };
        self.work = Some(w);
        let kv = argmin::kv!(
            "mu" => mu;
            "gnorm" => gnorm;
            "n_fixed" => n_fixed;
        );
        let mut state = state.param(x).cost(cost).jacobian(jac);
        if let Some(stop) = stop {
            state = state.terminate_with(stop.into());
        }
        Ok((state, Some(kv)))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<O>,
        mut state: LmState,
    ) -> Result<(LmState, Option<KV>), Error> {
        let mut w = self
            .work
            .take()
            .ok_or_else(|| not_initialized("LevenbergMarquardt: next_iter called before init"))?;
        let x = state
            .get_param()
            .cloned()
            .ok_or_else(|| not_initialized("LevenbergMarquardt: state has no parameter vector"))?;
        let cost = state.get_cost();
        let mu_used = w.mu;

        let cand = {
            let jac = state
                .get_jacobian()
                .ok_or_else(|| not_initialized("LevenbergMarquardt: state has no Jacobian"))?;
            self.trial(&x, &w, jac)
        };
        let step_norm = cand.step.component_mul(&w.d).norm();
        let pred = cand.pred;

        // A step already within xtol that the Gauss–Newton model expects to
        // lower F by at most half could only move x by less than the
        // tolerance and F by a fraction: stop without evaluating it. (MINPACK
        // evaluates it first; here that costs a trace of every ray, and its
        // Jacobian when accepted. A step predicted to do more is taken: near a
        // zero-residual answer a step below xtol can still lower F a
        // thousandfold.)
        if self.xtol > 0.0
            && w.last_trial_finite
            && pred <= 0.5 * cost
            && step_norm <= self.xtol * (x.component_mul(&w.d).norm() + self.xtol)
        {
            let kv = Trial {
                mu: mu_used,
                rho: 0.0,
                step_norm,
                accepted: false,
                cost_trial: cost,
                pred,
            }
            .kv(&w, x.len());
            self.work = Some(w);
            return Ok((state.terminate_with(LmStop::Xtol.into()), Some(kv)));
        }

        // A zero step (everything held or resolved below rounding) would only
        // re-evaluate r(x); skip the call and let the tests below end the run.
        let mut r_trial_ok: Option<DVector<f64>> = None;
        let (cost_trial, actred) = if cand.step.iter().all(|&s| s == 0.0) {
            (cost, 0.0)
        } else {
            let r_trial = problem.apply(&cand.x_trial)?;
            if r_trial.len() != w.r.len() {
                return Err(invalid(format!(
                    "LevenbergMarquardt: residual length changed from {} to {}",
                    w.r.len(),
                    r_trial.len()
                )));
            }
            // NaN/inf entries, or finite entries whose squares overflow, all
            // make this non-finite; such a trial point is simply rejected.
            let c = 0.5 * r_trial.norm_squared();
            w.last_trial_finite = c.is_finite();
            if c.is_finite() {
                // ½(r − r_t)ᵀ(r + r_t) resolves reductions far below eps·F,
                // where F − F_t would be pure rounding; without it the
                // iterates stall at ~√eps relative accuracy.
                let red = 0.5 * (&w.r - &r_trial).dot(&(&w.r + &r_trial));
                r_trial_ok = Some(r_trial);
                (c, red)
            } else {
                (f64::INFINITY, f64::NEG_INFINITY)
            }
        };
        let rho = if !cost_trial.is_finite() {
            f64::NEG_INFINITY
        } else if pred > 0.0 {
            actred / pred
        } else {
            0.0
        };

        let mut accepted = false;
        if rho > 0.0 && pred > 0.0 {
            if let Some(r_trial) = r_trial_ok.take() {
                let jac = problem.jacobian(&cand.x_trial)?;
                if jac.nrows() != r_trial.len() || jac.ncols() != x.len() {
                    return Err(invalid(format!(
                        "LevenbergMarquardt: Jacobian is {}x{}, expected {}x{}",
                        jac.nrows(),
                        jac.ncols(),
                        r_trial.len(),
                        x.len()
                    )));
                }
                // A point whose Jacobian is unusable cannot be stepped from;
                // treat it like a non-finite residual.
                if all_finite(jac.iter()) {
                    self.refresh(&mut w, &cand.x_trial, r_trial, &jac)?;
                    let t = 2.0 * rho - 1.0;
                    w.mu = (w.mu * (1.0 / 3.0f64).max(1.0 - t * t * t)).max(MU_MIN);
                    w.nu = 2.0;
                    w.rejections = 0;
                    accepted = true;
                    state = state
                        .param(cand.x_trial.clone())
                        .cost(cost_trial)
                        .jacobian(jac);
                    // The accurate `actred > 0` proves this point is better,
                    // but its rounded F may tie (or exceed by an ulp) the
                    // previous one, and the Executor's `update()` only records
                    // strict decreases. LM is monotone, so record it here.
                    if cost_trial >= state.best_cost {
                        state.prev_best_param = state.best_param.replace(cand.x_trial.clone());
                        state.prev_best_cost = state.best_cost;
                        state.best_cost = cost_trial;
                        state.last_best_iter = state.iter;
                    }
                }
            }
        }
        if !accepted {
            // Below the smallest resolved σ² the damping does not change the
            // step, so doubling from there would only re-evaluate the same
            // trial point; start the increase where it has an effect.
            let effective = w.decomp.as_ref().map_or(0.0, Decomp::smallest_resolved_sq);
            w.mu = w.mu.max(effective) * w.nu;
            w.nu = (2.0 * w.nu).min(1e100);
            w.rejections += 1;
        }

        let x_now = state.get_param().unwrap_or(&x);
        let xnorm = x_now.component_mul(&w.d).norm();
        let rho_ftol = if pred > 0.0 && rho.is_finite() {
            rho
        } else {
            0.0
        };
        let reason = if accepted && cost_trial == 0.0 {
            Some(LmStop::ZeroResidual)
        } else if accepted && w.gnorm <= self.gtol {
            Some(LmStop::Gtol)
        } else if self.ftol > 0.0
            && w.last_trial_finite
            && actred.abs() <= self.ftol * cost
            && pred <= self.ftol * cost
            && rho_ftol <= 2.0
        {
            Some(LmStop::Ftol)
        } else if self.xtol > 0.0
            && w.last_trial_finite
            && step_norm <= self.xtol * (xnorm + self.xtol)
        {
            Some(LmStop::Xtol)
        } else if w.mu > MU_MAX {
            Some(LmStop::StallDamping)
        } else if w.rejections >= self.max_rejections {
            Some(LmStop::StallRejections)
        } else {
            None
        };

        let kv = Trial {
            mu: mu_used,
            rho,
            step_norm,
            accepted,
            cost_trial,
            pred,
        }
        .kv(&w, x.len());
        self.work = Some(w);
        let state = match reason {
            Some(stop) => state.terminate_with(stop.into()),
            None => state,
        };
        Ok((state, Some(kv)))
    }
}
