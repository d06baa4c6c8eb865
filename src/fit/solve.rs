//! Running the solvers: Levenberg–Marquardt and Nelder–Mead under argmin's
//! `Executor`, restarts in parallel, and the default strategy that combines them.
//!
//! Nelder–Mead stops at the target objective, when its simplex has collapsed,
//! or when F is the same over the simplex ([`super::nelder_mead`], tolerances
//! `simplex_xtol` and `simplex_ftol` of the problem's `solver` section), else
//! at 20 × `max_iterations` (a simplex move costs one to n + 2 evaluations
//! of F, an LM iteration one residual and one Jacobian). LM runs do not stop at
//! the target: an LM run that meets it goes on to converge, which costs a few
//! iterations and leaves the polished answer.

use super::history::{IterationRecord, RunHistory};
use super::lm::{LevenbergMarquardt, LmState};
use super::nelder_mead::{NelderMead, NmStop};
use super::objective::Objective;
use crate::error::Error;
use crate::math::SplitMix64;
use crate::problem::{SolverMethod, SolverSettings};
use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{
    CostFunction, Error as ArgminError, Executor, IterState, Jacobian, KV, Operator, State,
    TerminationReason,
};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// Called with every iterate of every run (label, record): progress display,
/// and tests that watch the iterates.
pub type IterateHook = Arc<dyn Fn(&str, &IterationRecord) + Send + Sync>;

/// The outcome of one solver run.
#[derive(Clone, Debug)]
pub struct Run {
    /// `lm`, `lm (start 3)`, `nelder-mead`, `lm (polish)`.
    pub label: String,
    /// Where it started.
    pub start: Vec<f64>,
    /// Where it ended (the best point it found).
    pub end: Vec<f64>,
    /// F at `end`.
    pub objective: f64,
    /// Iterations made.
    pub iterations: u64,
    /// Why it stopped.
    pub reason: String,
    /// Whether the solver reports convergence (as opposed to a limit or stall).
    pub converged: bool,
    /// Its iterates.
    pub history: RunHistory,
}

/// Everything the solvers did.
#[derive(Clone, Debug)]
pub struct Solution {
    /// Best parameters found.
    pub x: Vec<f64>,
    /// F there.
    pub objective: f64,
    /// Index into `runs` of the run that produced `x`.
    pub best_run: usize,
    /// Every run, in the order made.
    pub runs: Vec<Run>,
}

/// Adapter: the objective as argmin's residual operator with Jacobian.
struct Residuals<'a>(&'a Objective);

impl Operator for Residuals<'_> {
    type Param = DVector<f64>;
    type Output = DVector<f64>;
    fn apply(&self, x: &DVector<f64>) -> Result<DVector<f64>, ArgminError> {
        crate::interrupt::check()?;
        Ok(self.0.residuals(x.as_slice()).0)
    }
}

impl Jacobian for Residuals<'_> {
    type Param = DVector<f64>;
    type Jacobian = DMatrix<f64>;
    fn jacobian(&self, x: &DVector<f64>) -> Result<DMatrix<f64>, ArgminError> {
        crate::interrupt::check()?;
        Ok(self.0.jacobian(x.as_slice()).1)
    }
}

/// Box bounds as a smooth change of variables (the MINUIT transforms), so that
/// Nelder–Mead, which knows no bounds, can never evaluate outside the box.
#[derive(Clone, Debug)]
struct BoxMap {
    bounds: Vec<(f64, f64)>,
}

impl BoxMap {
    fn to_box(&self, z: &[f64]) -> Vec<f64> {
        z.iter()
            .zip(&self.bounds)
            .map(|(&z, &(l, u))| match (l.is_finite(), u.is_finite()) {
                (true, true) => (l + 0.5 * (u - l) * (z.sin() + 1.0)).clamp(l, u),
                (true, false) => (l - 1.0 + (z * z + 1.0).sqrt()).max(l),
                (false, true) => (u + 1.0 - (z * z + 1.0).sqrt()).min(u),
                (false, false) => z,
            })
            .collect()
    }

    fn unbox(&self, x: &[f64]) -> Vec<f64> {
        x.iter()
            .zip(&self.bounds)
            .map(|(&x, &(l, u))| match (l.is_finite(), u.is_finite()) {
                (true, true) if u > l => (2.0 * (x - l) / (u - l) - 1.0).clamp(-1.0, 1.0).asin(),
                (true, true) => 0.0,
                (true, false) => ((x - l + 1.0).powi(2) - 1.0).max(0.0).sqrt(),
                (false, true) => ((u - x + 1.0).powi(2) - 1.0).max(0.0).sqrt(),
                (false, false) => x,
            })
            .collect()
    }
}

/// Adapter: the objective as argmin's cost function in the box's coordinates.
struct Cost<'a> {
    objective: &'a Objective,
    map: BoxMap,
}

impl CostFunction for Cost<'_> {
    type Param = DVector<f64>;
    type Output = f64;
    fn cost(&self, z: &DVector<f64>) -> Result<f64, ArgminError> {
        crate::interrupt::check()?;
        Ok(self.objective.cost(&self.map.to_box(z.as_slice())))
    }
}

/// Records every iterate (best point so far) of one run and forwards it to the hook.
#[derive(Clone)]
struct Recorder {
    label: String,
    started: Instant,
    records: Arc<Mutex<Vec<IterationRecord>>>,
    map: Option<BoxMap>,
    hook: Option<IterateHook>,
}

impl Recorder {
    fn new(label: &str, map: Option<BoxMap>, hook: Option<IterateHook>) -> Self {
        Recorder {
            label: label.to_string(),
            started: Instant::now(),
            records: Arc::default(),
            map,
            hook,
        }
    }

    fn record(&self, iteration: u64, objective: f64, param: Option<&DVector<f64>>) {
        let Some(p) = param else { return };
        let params = match &self.map {
            Some(m) => m.to_box(p.as_slice()),
            None => p.as_slice().to_vec(),
        };
        let rec = IterationRecord {
            iteration,
            elapsed_s: self.started.elapsed().as_secs_f64(),
            objective,
            params,
        };
        if let Some(h) = &self.hook {
            h(&self.label, &rec);
        }
        if let Ok(mut r) = self.records.lock() {
            r.push(rec);
        }
    }

    /// The finished run: its end point re-evaluated, and the recorded history.
    fn finish(
        &self,
        objective: &Objective,
        x0: &[f64],
        end: Vec<f64>,
        iterations: u64,
        reason: String,
        converged: bool,
    ) -> Run {
        Run {
            label: self.label.clone(),
            start: x0.to_vec(),
            objective: objective.cost(&end),
            end,
            iterations,
            reason,
            converged,
            history: RunHistory {
                label: self.label.clone(),
                records: self.records.lock().map(|r| r.clone()).unwrap_or_default(),
            },
        }
    }
}

impl<J: 'static> Observe<IterState<DVector<f64>, (), J, (), (), f64>> for Recorder {
    fn observe_init(
        &mut self,
        _name: &str,
        state: &IterState<DVector<f64>, (), J, (), (), f64>,
        _kv: &KV,
    ) -> Result<(), ArgminError> {
        self.record(0, state.get_best_cost(), state.get_best_param());
        Ok(())
    }
    fn observe_iter(
        &mut self,
        state: &IterState<DVector<f64>, (), J, (), (), f64>,
        _kv: &KV,
    ) -> Result<(), ArgminError> {
        // argmin observes an iteration before it increments the counter.
        self.record(
            state.get_iter() + 1,
            state.get_best_cost(),
            state.get_best_param(),
        );
        // An error from an observer ends the run: a cancellation point per
        // iterate, beside the one per evaluation.
        crate::interrupt::check()?;
        Ok(())
    }
}

fn describe(reason: Option<&TerminationReason>) -> (String, bool) {
    match reason {
        None => ("not terminated".into(), false),
        Some(r) => (r.text().to_string(), LevenbergMarquardt::is_converged(r)),
    }
}

/// Initial damping τ of LM runs (μ₀ = τ·max diag JᵀJ, scaled). Measured on the
/// bundled problems: with MINPACK's 1e-3 the first step of `fata-morgana` jumps
/// into a local minimum (F = 1.83) that only restarts escape; 0.1 reaches the
/// answer in 9 iterations and costs the other problems 2–5 iterations.
const INITIAL_DAMPING: f64 = 0.1;

/// A failed run as the error to report: [`Error::Interrupted`] when Ctrl-C
/// stopped it (the cancellation points above fail the run), else the
/// solver's message.
fn solver_error(run: &str, e: impl std::fmt::Display) -> Error {
    if crate::interrupt::requested() {
        return Error::Interrupted;
    }
    Error::Solver {
        run: run.to_string(),
        message: e.to_string(),
    }
}

/// One Levenberg–Marquardt run from `x0`.
pub fn run_lm(
    objective: &Objective,
    settings: &SolverSettings,
    bounds: &[(f64, f64)],
    x0: &[f64],
    label: &str,
    hook: Option<IterateHook>,
) -> Result<Run, Error> {
    let lower = DVector::from_iterator(bounds.len(), bounds.iter().map(|b| b.0));
    let upper = DVector::from_iterator(bounds.len(), bounds.iter().map(|b| b.1));
    let solver = LevenbergMarquardt::new()
        .with_initial_damping(INITIAL_DAMPING)
        .and_then(|s| s.with_ftol(settings.ftol))
        .and_then(|s| s.with_xtol(settings.xtol))
        .and_then(|s| s.with_gtol(settings.gtol))
        .and_then(|s| s.with_bounds(lower, upper))
        .map_err(|e| solver_error(label, e))?;
    let recorder = Recorder::new(label, None, hook);
    let start = DVector::from_column_slice(x0);
    let result = Executor::new(Residuals(objective), solver)
        .configure(|s: LmState| s.param(start).max_iters(settings.max_iterations))
        .add_observer(recorder.clone(), ObserverMode::Always)
        .timer(false)
        .run()
        .map_err(|e| solver_error(label, e))?;
    let state = result.state();
    let end = state
        .get_best_param()
        .map(|p| p.as_slice().to_vec())
        .unwrap_or_else(|| x0.to_vec());
    let (reason, converged) = describe(state.get_termination_reason());
    Ok(recorder.finish(objective, x0, end, state.get_iter(), reason, converged))
}

/// Nelder–Mead's iteration limit per `solver.max_iterations`.
pub const NELDER_MEAD_ITERATIONS_PER_LM: u64 = 20;

/// One Nelder–Mead run from `x0`, inside the bounds, that stops once F ≤
/// `target` (m²) or the simplex has collapsed ([`super::nelder_mead`]).
pub fn run_nelder_mead(
    objective: &Objective,
    settings: &SolverSettings,
    bounds: &[(f64, f64)],
    x0: &[f64],
    label: &str,
    target: f64,
    hook: Option<IterateHook>,
) -> Result<Run, Error> {
    let map = BoxMap {
        bounds: bounds.to_vec(),
    };
    let z0 = map.unbox(x0);
    // Initial simplex: 10% of each coordinate (in the box's coordinates), so the
    // simplex has the problem's own scales.
    let mut simplex = vec![DVector::from_vec(z0.clone())];
    for k in 0..z0.len() {
        let mut z = z0.clone();
        let step = if bounds[k].0.is_finite() && bounds[k].1.is_finite() {
            0.2
        } else {
            0.1 * z0[k].abs().max(1e-2)
        };
        z[k] += if z[k] > 1.2 { -step } else { step };
        simplex.push(DVector::from_vec(z));
    }
    let solver = NelderMead::new(simplex)
        .and_then(|s| s.with_target(target))
        .and_then(|s| s.with_xtol(settings.simplex_xtol))
        .and_then(|s| s.with_ftol(settings.simplex_ftol))
        .map_err(|e| solver_error(label, e))?;
    let max_iters = settings
        .max_iterations
        .saturating_mul(NELDER_MEAD_ITERATIONS_PER_LM);
    let recorder = Recorder::new(label, Some(map.clone()), hook);
    let cost = Cost {
        objective,
        map: map.clone(),
    };
    let result = Executor::new(cost, solver)
        .configure(|s| s.max_iters(max_iters))
        .add_observer(recorder.clone(), ObserverMode::Always)
        .timer(false)
        .run()
        .map_err(|e| solver_error(label, e))?;
    let state = result.state();
    let end = state
        .get_best_param()
        .map(|z| map.to_box(z.as_slice()))
        .unwrap_or_else(|| x0.to_vec());
    let (mut reason, _) = describe(state.get_termination_reason());
    if let Some(TerminationReason::MaxItersReached) = state.get_termination_reason() {
        reason = format!(
            "{reason} ({max_iters} = {NELDER_MEAD_ITERATIONS_PER_LM} × solver.max_iterations) \
             before F reached the target or the simplex collapsed"
        );
    }
    let converged = state
        .get_termination_reason()
        .and_then(NmStop::from_reason)
        .is_some();
    Ok(recorder.finish(objective, x0, end, state.get_iter(), reason, converged))
}

/// Deterministic starting points: uniform inside two-sided bounds, otherwise
/// within ±50% of the start (never crossing zero, so a rate keeps its sign).
pub fn starting_points(
    x0: &[f64],
    bounds: &[(f64, f64)],
    count: usize,
    seed: u64,
) -> Vec<Vec<f64>> {
    let mut rng = SplitMix64(seed);
    let mut uniform = move || rng.next_f64();
    (0..count)
        .map(|_| {
            x0.iter()
                .zip(bounds)
                .map(|(&x, &(l, u))| {
                    let t = uniform();
                    if l.is_finite() && u.is_finite() {
                        l + (u - l) * t
                    } else {
                        let v = if x == 0.0 {
                            2.0 * t - 1.0
                        } else {
                            x * (0.5 + t)
                        };
                        v.clamp(l, u)
                    }
                })
                .collect()
        })
        .collect()
}

/// Fits the objective's free parameters with the chosen method.
///
/// `auto`: LM from the start; if it ends above `target` (F, m²), LM from
/// `settings.starts` further starting points in parallel; if the best is still
/// above `target`, Nelder–Mead from it (stopping at `target`), then LM to
/// polish. `nelder-mead` also stops at `target`. Every run is kept.
pub fn solve(
    objective: &Objective,
    settings: &SolverSettings,
    bounds: &[(f64, f64)],
    target: f64,
    hook: Option<IterateHook>,
) -> Result<Solution, Error> {
    let x0 = objective.start().as_slice().to_vec();
    let mut runs = Vec::new();
    match settings.method {
        SolverMethod::Lm => runs.push(run_lm(objective, settings, bounds, &x0, "lm", hook)?),
        SolverMethod::NelderMead => runs.push(run_nelder_mead(
            objective,
            settings,
            bounds,
            &x0,
            "nelder-mead",
            target,
            hook,
        )?),
        SolverMethod::Auto => {
            runs.push(run_lm(
                objective,
                settings,
                bounds,
                &x0,
                "lm",
                hook.clone(),
            )?);
            if runs[0].objective > target && !x0.is_empty() {
                let starts = starting_points(&x0, bounds, settings.starts, settings.seed);
                let restarts: Vec<Result<Run, Error>> = starts
                    .par_iter()
                    .enumerate()
                    .map(|(k, s)| {
                        run_lm(
                            objective,
                            settings,
                            bounds,
                            s,
                            &format!("lm (start {})", k + 1),
                            hook.clone(),
                        )
                    })
                    .collect();
                for r in restarts {
                    runs.push(r?);
                }
                let best = best_run(&runs);
                if runs[best].objective > target {
                    let from = runs[best].end.clone();
                    let nm = run_nelder_mead(
                        objective,
                        settings,
                        bounds,
                        &from,
                        "nelder-mead",
                        target,
                        hook.clone(),
                    )?;
                    let polish_from = nm.end.clone();
                    runs.push(nm);
                    runs.push(run_lm(
                        objective,
                        settings,
                        bounds,
                        &polish_from,
                        "lm (polish)",
                        hook,
                    )?);
                }
            }
        }
    }
    let best = best_run(&runs);
    Ok(Solution {
        x: runs[best].end.clone(),
        objective: runs[best].objective,
        best_run: best,
        runs,
    })
}

/// The run with the lowest objective; the earliest wins ties, so the choice does
/// not depend on thread timing.
fn best_run(runs: &[Run]) -> usize {
    let mut best = 0;
    for (i, r) in runs.iter().enumerate() {
        if r.objective < runs[best].objective {
            best = i;
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_map_round_trips_and_stays_inside() {
        let m = BoxMap {
            bounds: vec![
                (1.0, 5.0),
                (0.0, f64::INFINITY),
                (f64::NEG_INFINITY, -2.0),
                (f64::NEG_INFINITY, f64::INFINITY),
            ],
        };
        let x = [2.5, 3.0, -7.0, 11.0];
        let back = m.to_box(&m.unbox(&x));
        for (a, b) in x.iter().zip(&back) {
            assert!((a - b).abs() < 1e-12, "{x:?} -> {back:?}");
        }
        for z in [-1e6, -3.0, 0.0, 0.4, 1e6] {
            let y = m.to_box(&[z; 4]);
            assert!((1.0..=5.0).contains(&y[0]) && y[1] >= 0.0 && y[2] <= -2.0);
        }
    }

    #[test]
    fn starting_points_are_reproducible_and_inside_the_bounds() {
        let b = [
            (1.0, 2.0),
            (f64::NEG_INFINITY, f64::INFINITY),
            (0.0, f64::INFINITY),
        ];
        let a = starting_points(&[1.5, -3.0, 0.0], &b, 16, 7);
        assert_eq!(a, starting_points(&[1.5, -3.0, 0.0], &b, 16, 7));
        assert_ne!(a, starting_points(&[1.5, -3.0, 0.0], &b, 16, 8));
        for p in &a {
            assert!((1.0..=2.0).contains(&p[0]));
            assert!(p[1] < 0.0, "a start never flips the sign of a parameter");
            assert!(p[2] >= 0.0);
        }
    }
}
