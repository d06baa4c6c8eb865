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
//!
//! With a surrogate tracer ([`super::surrogate`]) the strategy runs on the
//! surrogate objective first, and LM refines its answer under the problem's
//! own tracer.

use super::history::{IterationRecord, RunHistory};
use super::lm::{LevenbergMarquardt, LmState};
use super::nelder_mead::{NelderMead, NmStop};
use super::objective::Objective;
use super::surrogate::{REFINE_DAMPING, Surrogate};
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
use std::cell::RefCell;
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
    /// Whether it ran on the surrogate objective ([`super::surrogate`]): its
    /// F is another tracer's, so it is never the best run.
    pub surrogate: bool,
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
/// In [`LmMode::Refine`], while trials are being accepted, a residual
/// request computes the Jacobian too (the tangent trace yields the residuals),
/// and LM's request for the Jacobian at the accepted point is then served by
/// the objective's memo. After a rejected trial the next one is traced
/// plainly: at the floor of F, where trials are accepted or rejected by
/// rounding, a Jacobian per trial would be wasted.
struct Residuals<'a> {
    objective: &'a Objective,
    mode: LmMode,
    /// The last trial point, and whether LM asked for its Jacobian (that is,
    /// accepted it); `true` before the first.
    last: RefCell<(Option<DVector<f64>>, bool)>,
}

impl<'a> Residuals<'a> {
    fn new(objective: &'a Objective, mode: LmMode) -> Self {
        Residuals {
            objective,
            mode,
            last: RefCell::new((None, true)),
        }
    }
}

impl Operator for Residuals<'_> {
    type Param = DVector<f64>;
    type Output = DVector<f64>;
    fn apply(&self, x: &DVector<f64>) -> Result<DVector<f64>, ArgminError> {
        crate::interrupt::check()?;
        let mut last = self.last.borrow_mut();
        let speculate = self.mode == LmMode::Refine && last.1;
        *last = (Some(x.clone()), false);
        Ok(if speculate {
            self.objective.jacobian(x.as_slice()).0
        } else {
            self.objective.residuals(x.as_slice()).0
        })
    }
}

impl Jacobian for Residuals<'_> {
    type Param = DVector<f64>;
    type Jacobian = DMatrix<f64>;
    fn jacobian(&self, x: &DVector<f64>) -> Result<DMatrix<f64>, ArgminError> {
        crate::interrupt::check()?;
        let mut last = self.last.borrow_mut();
        if last.0.as_ref() == Some(x) {
            last.1 = true;
        }
        Ok(self.objective.jacobian(x.as_slice()).1)
    }
}

/// How an LM run starts and what it evaluates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LmMode {
    /// From a start that may be far from the answer: heavy initial damping
    /// (τ = 0.1) against jumps into other minima; the Jacobian only at
    /// accepted points.
    Search,
    /// From next to the answer (the surrogate's, [`super::surrogate`]):
    /// light damping (τ = [`REFINE_DAMPING`]), and the Jacobian at each trial
    /// point that follows an accepted one, since trials are then nearly
    /// always accepted and the tangent trace that gives the Jacobian gives
    /// the residuals with it (a separate residual trace would only repeat
    /// that work).
    Refine,
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

    /// The finished run and its recorded history. `known` is F at `end`
    /// when the solver has it (LM's best cost, from the same residuals);
    /// otherwise the end point is evaluated again.
    #[allow(clippy::too_many_arguments)]
    fn finish(
        &self,
        objective: &Objective,
        x0: &[f64],
        end: Vec<f64>,
        known: Option<f64>,
        iterations: u64,
        reason: String,
        converged: bool,
    ) -> Run {
        Run {
            label: self.label.clone(),
            start: x0.to_vec(),
            objective: known
                .filter(|f| f.is_finite())
                .unwrap_or_else(|| objective.cost(&end)),
            end,
            iterations,
            reason,
            converged,
            history: RunHistory {
                label: self.label.clone(),
                records: self.records.lock().map(|r| r.clone()).unwrap_or_default(),
            },
            surrogate: false,
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
    run_lm_in(objective, settings, bounds, x0, label, hook, LmMode::Search)
}

/// One Levenberg–Marquardt run from `x0` in `mode`.
pub fn run_lm_in(
    objective: &Objective,
    settings: &SolverSettings,
    bounds: &[(f64, f64)],
    x0: &[f64],
    label: &str,
    hook: Option<IterateHook>,
    mode: LmMode,
) -> Result<Run, Error> {
    let damping = match mode {
        LmMode::Search => INITIAL_DAMPING,
        LmMode::Refine => REFINE_DAMPING,
    };
    let lower = DVector::from_iterator(bounds.len(), bounds.iter().map(|b| b.0));
    let upper = DVector::from_iterator(bounds.len(), bounds.iter().map(|b| b.1));
    let solver = LevenbergMarquardt::new()
        .with_initial_damping(damping)
        .and_then(|s| s.with_ftol(settings.ftol))
        .and_then(|s| s.with_xtol(settings.xtol))
        .and_then(|s| s.with_gtol(settings.gtol))
        .and_then(|s| s.with_bounds(lower, upper))
        .map_err(|e| solver_error(label, e))?;
    let recorder = Recorder::new(label, None, hook);
    let start = DVector::from_column_slice(x0);
    let result = Executor::new(Residuals::new(objective, mode), solver)
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
    // LM's best cost is ½|r|² of the residuals at `end`, as `Objective::cost`
    // computes it: no need to trace the pairs again.
    let known = state.get_best_param().map(|_| state.get_best_cost());
    Ok(recorder.finish(
        objective,
        x0,
        end,
        known,
        state.get_iter(),
        reason,
        converged,
    ))
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
    Ok(recorder.finish(
        objective,
        x0,
        end,
        None,
        state.get_iter(),
        reason,
        converged,
    ))
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
///
/// Every evaluation traces with the objective's own tracer; see
/// [`solve_with_surrogate`] for a fit that converges under a cheaper one
/// first.
pub fn solve(
    objective: &Objective,
    settings: &SolverSettings,
    bounds: &[(f64, f64)],
    target: f64,
    hook: Option<IterateHook>,
) -> Result<Solution, Error> {
    solve_with_surrogate(objective, None, settings, bounds, target, hook)
}

/// [`solve`], with a `surrogate` ([`super::surrogate`]): the strategy runs on
/// the surrogate objective (its runs labelled `surrogate …`), then LM refines
/// its best answer under the problem's own tracer (`lm (refine)`,
/// [`LmMode::Refine`]). If the refined F misses `target` where the
/// surrogate's met it, the strategy runs again on the problem's own objective
/// from the start. Without a surrogate, exactly [`solve`].
pub fn solve_with_surrogate(
    objective: &Objective,
    surrogate: Option<&Surrogate>,
    settings: &SolverSettings,
    bounds: &[(f64, f64)],
    target: f64,
    hook: Option<IterateHook>,
) -> Result<Solution, Error> {
    let runs = match surrogate {
        None => strategy(objective, settings, bounds, target, hook, "")?,
        Some(s) => {
            let mut runs = strategy(
                &s.objective,
                settings,
                bounds,
                target,
                hook.clone(),
                SURROGATE_LABEL,
            )?;
            for r in &mut runs {
                r.surrogate = true;
            }
            let best = best_of(&runs, |_| true);
            let met = runs[best].objective <= target;
            let from = runs[best].end.clone();
            let refined = run_lm_in(
                objective,
                settings,
                bounds,
                &from,
                REFINE_LABEL,
                hook.clone(),
                LmMode::Refine,
            )?;
            let missed = refined.objective > target;
            runs.push(refined);
            if missed && met {
                runs.extend(strategy(objective, settings, bounds, target, hook, "")?);
            }
            runs
        }
    };
    let best = best_run(&runs);
    Ok(Solution {
        x: runs[best].end.clone(),
        objective: runs[best].objective,
        best_run: best,
        runs,
    })
}

/// Label prefix of the runs on the surrogate objective.
pub const SURROGATE_LABEL: &str = "surrogate ";

/// Label of the LM run that refines the surrogate's answer.
pub const REFINE_LABEL: &str = "lm (refine)";

/// The runs of `settings.method`'s strategy ([`solve`]), labels prefixed by
/// `prefix`.
fn strategy(
    objective: &Objective,
    settings: &SolverSettings,
    bounds: &[(f64, f64)],
    target: f64,
    hook: Option<IterateHook>,
    prefix: &str,
) -> Result<Vec<Run>, Error> {
    let x0 = objective.start().as_slice().to_vec();
    let label = |l: &str| format!("{prefix}{l}");
    let mut runs = Vec::new();
    match settings.method {
        SolverMethod::Lm => runs.push(run_lm(
            objective,
            settings,
            bounds,
            &x0,
            &label("lm"),
            hook,
        )?),
        SolverMethod::NelderMead => runs.push(run_nelder_mead(
            objective,
            settings,
            bounds,
            &x0,
            &label("nelder-mead"),
            target,
            hook,
        )?),
        SolverMethod::Auto => {
            runs.push(run_lm(
                objective,
                settings,
                bounds,
                &x0,
                &label("lm"),
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
                            &label(&format!("lm (start {})", k + 1)),
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
                        &label("nelder-mead"),
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
                        &label("lm (polish)"),
                        hook,
                    )?);
                }
            }
        }
    }
    Ok(runs)
}

/// The run with the lowest objective among those on the problem's own
/// tracer (all of them when none is); the earliest wins ties, so the choice
/// does not depend on thread timing.
fn best_run(runs: &[Run]) -> usize {
    if runs.iter().any(|r| !r.surrogate) {
        best_of(runs, |r| !r.surrogate)
    } else {
        best_of(runs, |_| true)
    }
}

/// The earliest run of lowest objective among those `eligible` keeps (0 if
/// none).
fn best_of(runs: &[Run], eligible: impl Fn(&Run) -> bool) -> usize {
    let mut best: Option<usize> = None;
    for (i, r) in runs.iter().enumerate() {
        if eligible(r) && best.is_none_or(|b| r.objective < runs[b].objective) {
            best = Some(i);
        }
    }
    best.unwrap_or(0)
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
