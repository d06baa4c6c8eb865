//! Growing the model (`mirage fit --grow`): from the problem's medium (a
//! background alone, say), add the terms the pairs call for, one at a time,
//! and only those.
//!
//! # Algorithm
//!
//! 1. Fit the starting model (the problem's medium and `free`).
//! 2. Propose candidates ([`candidates`]): the inversion, if the medium has
//!    none, and one more hot spot, each with several seeds.
//! 3. Fit every (candidate, seed) with Levenberg–Marquardt
//!    ([`crate::fit::solve::run_lm`]), all of them at once with rayon. Each
//!    fit is deterministic and independent of the thread count (the residual
//!    map's own parallel split is fixed), results are collected in input
//!    order, and every choice is by (value, index): the grown model is the
//!    same bit for bit on any number of threads.
//! 4. Keep the candidate whose best seed lowers the criterion most; if none
//!    lowers it, stop.
//! 5. Prune: a grown term with a parameter the pairs do not determine
//!    ([`crate::fit::identify`]) is dropped, as is one whose removal lowers the
//!    criterion (each refitted from the current values without it).
//! 6. Stop when the fit reaches the noise floor, when `max_terms` terms were
//!    added, or after [`MAX_STEPS`] steps; else go to 2.
//!
//! # Criterion
//!
//! The residuals are m = 2N components for N pairs (each endpoint lies on its
//! target plane, so one of its three components is zero). With the endpoint
//! noise σ known (`--noise`), χ² = 2F/σ² and the criterion is the Bayesian
//! information criterion BIC = χ² + p·ln m (p free parameters); with σ unknown,
//! BIC = m·ln(2F/m) + p·ln m. BIC rather than AICc: AICc's penalty per
//! parameter is about 2 for m in the tens to hundreds, BIC's ln m is 3.7–6,
//! and a spurious hot spot (5 parameters, which can always absorb some noise)
//! lowers χ² by about its p — by chance often more than 2p, rarely more than
//! p·ln m. BIC is consistent (the true model wins as m grows); AIC is not.
//!
//! The noise floor: at the true model χ² follows a χ² law with m − p degrees
//! of freedom, so a fit with χ² ≤ (m − p) + 2·√(2(m − p)) (two standard
//! deviations above its mean) fits as well as the noise allows, and growing
//! stops there.
//!
//! # What it cannot find
//!
//! A term no pair's ray passes through changes no endpoint: it is neither
//! proposed nor kept. Hot spots are seeded only under the worst-fitting
//! pairs' launch lines: a spot whose rays already fit well after an earlier
//! term bent them is not proposed. A grown hot spot's rim sharpness is fixed
//! ([`candidates::GROWN_EDGE`]). Only the logistic model grows.

pub mod candidates;
pub mod model;
pub mod report;

pub use model::{Model, Term};
pub use report::{CandidateReport, GrowReport, GrowStep};

use super::identify;
use super::objective::Objective;
use super::solve::run_lm;
use crate::error::{Error, Result};
use crate::medium::Medium;
use crate::problem::{GrowSettings, Problem, SolverSettings};
use rayon::prelude::*;
use std::time::Instant;

/// The most steps (additions and drops together) a growth makes.
pub const MAX_STEPS: usize = 16;

/// Iteration limit of one candidate fit (at most the problem's).
const CANDIDATE_ITERATIONS: u64 = 100;

/// The information criterion of least squares with endpoint noise σ.
#[derive(Clone, Copy, Debug)]
pub struct Criterion {
    /// σ (m), if known.
    pub noise: Option<f64>,
    /// Residual components m.
    pub m: usize,
}

impl Criterion {
    /// The criterion in words.
    pub fn describe(&self) -> String {
        match self.noise {
            Some(s) => format!("BIC, σ = {s} m known: χ² + p·ln m, χ² = 2F/σ²"),
            None => "BIC, σ estimated: m·ln(2F/m) + p·ln m".into(),
        }
    }

    /// χ² = 2F/σ², if σ is known.
    pub fn chi2(&self, f: f64) -> Option<f64> {
        self.noise.map(|s| 2.0 * f / (s * s))
    }

    /// The criterion of a fit with objective `f` and `p` free parameters.
    pub fn value(&self, f: f64, p: usize) -> f64 {
        let m = self.m as f64;
        let penalty = p as f64 * m.ln();
        match self.chi2(f) {
            Some(c) => c + penalty,
            None => m * (2.0 * f / m).max(f64::MIN_POSITIVE).ln() + penalty,
        }
    }

    /// Whether χ² is within the noise floor (`None` when σ is unknown).
    pub fn at_floor(&self, f: f64, p: usize) -> Option<bool> {
        let dof = self.m.saturating_sub(p).max(1) as f64;
        self.chi2(f).map(|c| c <= dof + 2.0 * (2.0 * dof).sqrt())
    }
}

/// A fitted model.
#[derive(Clone, Debug)]
pub struct Fitted {
    /// The model at its fitted values.
    pub model: Model,
    /// The model the fit started from (its seed).
    pub start: Model,
    /// F (m²).
    pub objective: f64,
    /// The criterion.
    pub criterion: f64,
}

/// The grown model and the account of how it grew.
#[derive(Clone, Debug)]
pub struct Grown {
    /// The final model, fitted.
    pub fitted: Fitted,
    /// Every step.
    pub report: GrowReport,
}

/// The solver settings of a candidate fit: the problem's, the iterations capped.
fn candidate_settings(settings: &SolverSettings) -> SolverSettings {
    SolverSettings {
        max_iterations: settings.max_iterations.min(CANDIDATE_ITERATIONS),
        ..*settings
    }
}

/// Fits `model` from its current values; a failed run counts as F = ∞.
fn fit_model(
    problem: &Problem,
    model: &Model,
    settings: &SolverSettings,
    criterion: &Criterion,
) -> Result<Fitted> {
    let objective = Objective::new(
        Medium::Logistic(model.medium.clone()),
        model.free.clone(),
        problem.pairs.clone(),
        problem.trace,
    );
    let x0 = model.x();
    let (x, f) = if x0.is_empty() {
        (x0, objective.cost(&[]))
    } else {
        // A seed whose run fails (its first step off the model's domain, say)
        // is a seed that did not fit: F = ∞, and the other seeds decide.
        match run_lm(&objective, settings, &model.bounds, &x0, "grow", None) {
            Ok(run) => (run.end, run.objective),
            // Ctrl-C is no failed seed: it stops the growth.
            Err(Error::Interrupted) => return Err(Error::Interrupted),
            Err(_) => (x0, f64::INFINITY),
        }
    };
    let f = if f.is_finite() { f } else { f64::INFINITY };
    Ok(Fitted {
        start: model.clone(),
        model: model.at(&x),
        objective: f,
        criterion: criterion.value(f, model.free.len()),
    })
}

/// Fits every model in parallel; results in input order.
fn fit_all(
    problem: &Problem,
    models: &[Model],
    settings: &SolverSettings,
    criterion: &Criterion,
) -> Result<Vec<Fitted>> {
    models
        .par_iter()
        .map(|m| fit_model(problem, m, settings, criterion))
        .collect()
}

/// The index of the lowest `key`, the earliest on ties.
fn argmin(keys: impl IntoIterator<Item = f64>) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, k) in keys.into_iter().enumerate() {
        if best.is_none_or(|(_, b)| k < b) {
            best = Some((i, k));
        }
    }
    best.map(|(i, _)| i)
}

/// Per pair, |rᵢ| at the fitted model.
fn misfits(problem: &Problem, fitted: &Fitted) -> Vec<f64> {
    let objective = Objective::new(
        Medium::Logistic(fitted.model.medium.clone()),
        vec![],
        problem.pairs.clone(),
        problem.trace,
    );
    let (r, _) = objective.residuals(&[]);
    r.as_slice()
        .chunks(3)
        .map(|c| c.iter().map(|v| v * v).sum::<f64>().sqrt())
        .collect()
}

/// The grown term of `fitted` with a parameter the pairs do not determine.
fn undetermined_term(problem: &Problem, fitted: &Fitted) -> Option<Term> {
    let model = &fitted.model;
    if model.free.is_empty() || model.grown.is_empty() {
        return None;
    }
    let objective = Objective::new(
        Medium::Logistic(model.medium.clone()),
        model.free.clone(),
        problem.pairs.clone(),
        problem.trace,
    );
    let x = model.x();
    let (_, jac) = objective.jacobian(&x);
    let ident = identify::analyse(&jac, &x, &model.free, fitted.objective);
    model.grown.iter().copied().find(|t| {
        model
            .free
            .iter()
            .zip(&ident.params)
            .any(|(p, v)| t.owns(*p) && !v.determined)
    })
}

/// The record of a step.
fn step_record(
    step: usize,
    action: String,
    fitted: &Fitted,
    criterion: &Criterion,
    candidates: Vec<CandidateReport>,
) -> GrowStep {
    GrowStep {
        step,
        action,
        terms: fitted.model.terms(),
        free: fitted.model.free.iter().map(|p| p.to_string()).collect(),
        objective: fitted.objective,
        chi2: criterion.chi2(fitted.objective),
        criterion: fitted.criterion,
        candidates,
    }
}

/// Why `medium` cannot be grown, if it cannot
/// ([`crate::problem::grow_unsupported`]).
pub fn unsupported(medium: &Medium) -> Option<String> {
    crate::problem::grow_unsupported(medium)
}

/// The starting model of `problem`: its medium and free parameters.
fn start_model(problem: &Problem) -> Result<Model> {
    match (&problem.medium, unsupported(&problem.medium)) {
        (Medium::Logistic(medium), None) => Ok(Model {
            medium: medium.clone(),
            free: problem.free.clone(),
            bounds: problem.bounds.clone(),
            grown: vec![],
        }),
        (_, reason) => Err(Error::input(
            &problem.source,
            "solver.grow",
            reason.unwrap_or_default(),
        )),
    }
}

/// Grows `problem`'s model as `settings` say (see the module doc).
pub fn grow(problem: &Problem, settings: &GrowSettings) -> Result<Grown> {
    let started = Instant::now();
    let criterion = Criterion {
        noise: settings.noise,
        m: 2 * problem.pairs.len(),
    };
    let lm = candidate_settings(&problem.solver);
    let mut fits = 1;
    let mut current = fit_model(problem, &start_model(problem)?, &lm, &criterion)?;
    let mut steps = vec![step_record(0, "start".into(), &current, &criterion, vec![])];
    let stop_reason = loop {
        let p = current.model.free.len();
        if criterion.at_floor(current.objective, p) == Some(true) {
            break "the fit reaches the noise floor (χ² ≤ (m − p) + 2·√(2(m − p)))".to_string();
        }
        if current.model.grown.len() >= settings.max_terms {
            break format!("{} terms added: the limit (max_terms)", settings.max_terms);
        }
        if steps.len() > MAX_STEPS {
            break format!("{MAX_STEPS} steps made: the limit");
        }
        let misfit = misfits(problem, &current);
        let cands = candidates::propose(&current.model, &problem.pairs, &misfit);
        let seeds: Vec<Model> = cands.iter().flat_map(|c| c.seeds.clone()).collect();
        let results = fit_all(problem, &seeds, &lm, &criterion)?;
        fits += results.len();
        let mut reports = Vec::new();
        let mut best_of = Vec::new();
        let mut first = 0;
        for c in &cands {
            let own = &results[first..first + c.seeds.len()];
            first += c.seeds.len();
            let Some(b) = argmin(own.iter().map(|f| f.criterion)) else {
                continue;
            };
            reports.push(CandidateReport {
                term: c.term.name(),
                seeds: own.len(),
                best_seed: b,
                objective: own[b].objective,
                criterion: own[b].criterion,
            });
            best_of.push((c.term, own[b].clone()));
        }
        let chosen = argmin(best_of.iter().map(|(_, f)| f.criterion));
        let Some((term, better)) = chosen
            .map(|i| best_of[i].clone())
            .filter(|(_, f)| f.criterion < current.criterion)
        else {
            // Record what was tried, then stop.
            let step = steps.len();
            let mut last = step_record(step, "none kept".into(), &current, &criterion, reports);
            last.action = "no candidate lowers the criterion".into();
            steps.push(last);
            break "no candidate term lowers the criterion".to_string();
        };
        current = better;
        steps.push(step_record(
            steps.len(),
            format!("add {}", term.name()),
            &current,
            &criterion,
            reports,
        ));
        // Prune, one term at a time, until nothing more goes.
        while steps.len() <= MAX_STEPS {
            if let Some(t) = undetermined_term(problem, &current) {
                current = fit_model(problem, &current.model.without(t), &lm, &criterion)?;
                fits += 1;
                steps.push(step_record(
                    steps.len(),
                    format!("drop {} (undetermined)", t.name()),
                    &current,
                    &criterion,
                    vec![],
                ));
                continue;
            }
            // The term just added lowered the criterion: only older ones may go.
            let older: Vec<Term> = current
                .model
                .grown
                .iter()
                .copied()
                .take(current.model.grown.len().saturating_sub(1))
                .collect();
            if older.is_empty() {
                break;
            }
            let without: Vec<Model> = older.iter().map(|t| current.model.without(*t)).collect();
            let refits = fit_all(problem, &without, &lm, &criterion)?;
            fits += refits.len();
            match argmin(refits.iter().map(|f| f.criterion)) {
                Some(i) if refits[i].criterion < current.criterion => {
                    current = refits[i].clone();
                    steps.push(step_record(
                        steps.len(),
                        format!("drop {} (criterion)", older[i].name()),
                        &current,
                        &criterion,
                        vec![],
                    ));
                }
                _ => break,
            }
        }
    };
    let at_noise_floor = criterion.at_floor(current.objective, current.model.free.len());
    let report = GrowReport {
        criterion: criterion.describe(),
        noise: criterion.noise,
        residual_components: criterion.m,
        max_terms: settings.max_terms,
        steps,
        stop_reason,
        at_noise_floor,
        fits,
        wall_time_s: started.elapsed().as_secs_f64(),
    };
    Ok(Grown {
        fitted: current,
        report,
    })
}

/// The problem whose fit is the grown model: its terms and free parameters,
/// started from the seed the kept fit started from, fitted by
/// Levenberg–Marquardt alone. That repeats the kept fit (deterministic, and
/// with at least its iterations), so the result's history and convergence
/// plot show the fit from its seed.
pub fn grown_problem(problem: &Problem, grown: &Grown) -> Problem {
    let model = &grown.fitted.start;
    let mut p = problem.clone();
    p.medium = Medium::Logistic(model.medium.clone());
    p.free = model.free.clone();
    p.bounds = model.bounds.clone();
    p.solver.method = crate::problem::SolverMethod::Lm;
    p.solver.grow = None;
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_criterion_charges_ln_m_per_parameter_and_knows_its_floor() {
        let c = Criterion {
            noise: Some(0.01),
            m: 50,
        };
        // χ² = 2F/σ² = 50 at F = 2.5e-3.
        assert!((c.chi2(2.5e-3).unwrap() - 50.0).abs() < 1e-9);
        let d = c.value(2.5e-3, 6) - c.value(2.5e-3, 0);
        assert!((d - 6.0 * 50f64.ln()).abs() < 1e-9);
        // Floor for p = 0: 50 + 2·√100 = 70.
        assert_eq!(c.at_floor(0.5 * 70.0e-4, 0), Some(true));
        assert_eq!(c.at_floor(0.5 * 70.1e-4, 0), Some(false));
        assert_eq!(Criterion { noise: None, m: 50 }.at_floor(1.0, 0), None);
    }

    #[test]
    fn ties_go_to_the_earliest() {
        assert_eq!(argmin([3.0, 1.0, 1.0, 2.0]), Some(1));
        assert_eq!(argmin([f64::INFINITY, f64::INFINITY]), Some(0));
        assert_eq!(argmin(std::iter::empty()), None);
    }
}
