//! Growing the model (`mirage fit --grow`): from the problem's medium (a
//! background alone, say), add the terms the pairs call for, one at a time,
//! and only those.
//!
//! # Algorithm
//!
//! A stepwise search that only ever goes down the criterion:
//!
//! 1. Fit the starting model (the problem's medium and `free`; a logistic
//!    start that frees every amplitude has one held to fix the gauge) and
//!    settle it ([`fits::Fitter::settle`]: what ran away or is undetermined
//!    is held at its start and the rest fitted again).
//! 2. Propose candidates ([`candidates`]), each with several seeds. The
//!    logistic model: the inversion, if the medium has none, and one more hot
//!    spot. Real air: the surface layer (`air.temperature.exponential`) and
//!    the step aloft (`air.temperature.inversion`), each if absent and the
//!    temperature is no table, and one more hot spot in kelvins.
//! 3. Fit every (candidate, seed) with Levenberg–Marquardt
//!    ([`crate::fit::solve::run_lm`]), all of them at once with rayon, and
//!    settle each candidate's best seed: a grown parameter that runs away
//!    makes the candidate a failure, an undetermined one is held at its seed.
//!    Each fit is deterministic and independent of the thread count (the
//!    residual map's own parallel split is fixed), results are collected in
//!    input order, and every choice is by (value, index): the grown model is
//!    the same bit for bit on any number of threads.
//! 4. **Add** the candidate with the lowest criterion, only if that is below
//!    the current model's; if none is, stop. Candidates within
//!    [`INDISTINGUISHABLE`] of the lowest are evidence too close to call:
//!    of those, the one with the fewest free parameters is taken (a cold
//!    surface layer, say, over a warm step just above the ground, which the
//!    pairs may see alike).
//! 5. **Drop**: each older grown term is taken out in turn (the others
//!    refitted from their current values, then settled); the removal with the
//!    lowest criterion is made only if that is below the current model's.
//!    Repeat until no removal lowers it. A term the pairs cannot determine is
//!    not dropped for that: its undetermined parameters are held, and it
//!    goes only if the criterion without it is lower, i.e. the fit loses less
//!    than the penalty of its parameters.
//! 6. Stop when the fit reaches the noise floor, when `max_terms` terms were
//!    added, or after [`MAX_STEPS`] steps; else go to 2.
//!
//! Each model added, and the one kept at the end, is polished: fitted on
//! with the problem's own iteration limit (candidates stop at 100) and
//! settled, kept if that lowers the criterion.
//!
//! Every accepted step lowers the criterion, so the model kept is the best
//! one visited, no sequence of steps can return to a model (no cycle), and a
//! model already fitted from the same start is never fitted again (the fits
//! are remembered).
//!
//! # Criterion
//!
//! The residuals are m = 2N components for N pairs (each endpoint lies on its
//! target plane, so one of its three components is zero). With the endpoint
//! noise σ known (`--noise`), χ² = 2F/σ² and the criterion is the Bayesian
//! information criterion BIC = χ² + p·ln m (p free parameters); with σ unknown,
//! BIC = m·ln(2F/m) + p·ln m. When pairs carry their own σᵢ
//! (`pairs[i].noise`; a pair without one takes `--noise`), χ² =
//! Σᵢ |rᵢ|²/(wᵢσᵢ)² over the weighted residuals rᵢ = wᵢ·(eᵢ − tᵢ), that is
//! Σᵢ |eᵢ − tᵢ|²/σᵢ² (a pair of weight 0 counts nothing). The fits still
//! minimise F; weights wᵢ ∝ 1/σᵢ make F's minimum χ²'s. BIC rather than AICc: AICc's penalty per
//! parameter is about 2 for m in the tens to hundreds, BIC's ln m is 3.7–6,
//! and a spurious hot spot (5 parameters, which can always absorb some noise)
//! lowers χ² by about its p — by chance often more than 2p, rarely more than
//! p·ln m. BIC is consistent (the true model wins as m grows); AIC is not.
//! Held parameters are not free: they count nothing in p.
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
//! pairs' launch lines (where they meet the ground, flat or round): a spot
//! whose rays already fit well after an earlier term bent them is not
//! proposed. A grown hot spot's rim sharpness is fixed
//! ([`candidates::GROWN_EDGE`]). Real air grows only its temperature:
//! the surface layer, the step aloft and hot spots, never a lapse, a table,
//! the pressure or the humidity, and nothing but hot spots beside a table; a
//! grown real-air term's excess stays within ±[`candidates::AIR_MAX_DELTA`] K.
//! The logistic model needs a term to start from (a background). Other kinds
//! do not grow.

pub mod candidates;
pub mod criterion;
pub mod fits;
pub mod model;
pub mod report;

pub use criterion::{Criterion, Noise};
pub use fits::Fitted;
pub use model::{Held, Model, Term};
pub use report::{CandidateReport, GrowReport, GrowStep, HeldReport};

use crate::error::{Error, Result};
use crate::medium::Medium;
use crate::problem::{GrowSettings, Problem, SolverSettings};
use fits::Fitter;
use std::time::Instant;

/// The most steps (additions and drops together) a growth makes.
pub const MAX_STEPS: usize = 16;

/// Iteration limit of one candidate fit (at most the problem's).
const CANDIDATE_ITERATIONS: u64 = 100;

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

/// The record of a step.
fn step_record(
    step: usize,
    action: String,
    fitted: &Fitted,
    candidates: Vec<CandidateReport>,
) -> GrowStep {
    GrowStep {
        step,
        action,
        terms: fitted.model.terms(),
        free: fitted.model.free.iter().map(|p| p.to_string()).collect(),
        objective: fitted.objective,
        chi2: fitted.chi2,
        criterion: fitted.criterion,
        candidates,
    }
}

/// Why `medium` cannot be grown, if it cannot
/// ([`crate::problem::grow_unsupported`]).
pub fn unsupported(medium: &Medium) -> Option<String> {
    crate::problem::grow_unsupported(medium)
}

/// The starting model of `problem`: its medium and free parameters (the
/// logistic gauge fixed, [`Model::start`]).
fn start_model(problem: &Problem) -> Result<Model> {
    match unsupported(&problem.medium) {
        None => Ok(Model::start(
            problem.medium.clone(),
            problem.free.clone(),
            problem.bounds.clone(),
        )),
        Some(reason) => Err(Error::input(&problem.source, "solver.grow", reason)),
    }
}

/// The candidates' reports, and the one chosen with its settled fit.
type Choice = (Vec<CandidateReport>, Option<(Term, Fitted)>);

/// The best (lowest criterion) of `fits`, settled, with the report of each
/// candidate term; `None` when nothing was tried.
fn best_candidate(
    fitter: &Fitter,
    cands: &[candidates::Candidate],
    results: &[Fitted],
) -> Result<Choice> {
    let mut reports = Vec::new();
    let mut best_of: Vec<(Term, Fitted)> = Vec::new();
    let mut first = 0;
    for c in cands {
        let own = &results[first..first + c.seeds.len()];
        first += c.seeds.len();
        let Some(b) = argmin(own.iter().map(|f| f.criterion)) else {
            continue;
        };
        let settled = fitter.settle(own[b].clone())?;
        reports.push(CandidateReport {
            term: c.term.name(&c.seeds[0].medium),
            seeds: own.len(),
            best_seed: b,
            objective: settled.objective,
            criterion: settled.criterion,
            held: settled.model.held.len() - c.seeds[b].held.len(),
        });
        best_of.push((c.term, settled));
    }
    Ok((reports, simplest_of_best(best_of)))
}

/// Criterion differences below this are evidence "not worth more than a
/// bare mention" (Kass & Raftery 1995, on BIC): between candidates that
/// close, the one with fewer free parameters is taken.
pub const INDISTINGUISHABLE: f64 = 2.0;

/// Of `fits`, the one with the fewest free parameters among those within
/// [`INDISTINGUISHABLE`] of the lowest criterion; the lowest criterion among
/// those, then the earliest.
fn simplest_of_best<T>(mut fits: Vec<(T, Fitted)>) -> Option<(T, Fitted)> {
    let best = fits
        .iter()
        .map(|(_, f)| f.criterion)
        .fold(f64::INFINITY, f64::min);
    let near = |f: &Fitted| f.criterion <= best + INDISTINGUISHABLE;
    let fewest = fits
        .iter()
        .filter(|(_, f)| near(f))
        .map(|(_, f)| f.model.free.len())
        .min()?;
    let i = argmin(fits.iter().map(|(_, f)| {
        if near(f) && f.model.free.len() == fewest {
            f.criterion
        } else {
            f64::INFINITY
        }
    }))?;
    Some(fits.swap_remove(i))
}

/// The best removal of one older grown term from `current`, settled, if it
/// lowers the criterion.
fn best_drop(fitter: &Fitter, current: &Fitted) -> Result<Option<(String, Fitted)>> {
    // The term added last lowered the criterion: only older ones may go.
    let grown = &current.model.grown;
    let older: Vec<Term> = grown
        .iter()
        .copied()
        .take(grown.len().saturating_sub(1))
        .collect();
    if older.is_empty() {
        return Ok(None);
    }
    let without: Vec<Model> = older.iter().map(|t| current.model.without(*t)).collect();
    let refits = fitter.fit_all(&without)?;
    let mut settled = Vec::with_capacity(refits.len());
    for f in refits {
        settled.push(fitter.settle(f)?);
    }
    Ok(match argmin(settled.iter().map(|f| f.criterion)) {
        Some(i) if settled[i].criterion < current.criterion => {
            Some((older[i].name(&current.model.medium), settled.swap_remove(i)))
        }
        _ => None,
    })
}

/// `fitted` fitted on with the problem's own iteration limit (candidates
/// stop at [`CANDIDATE_ITERATIONS`]) and settled; kept only if that lowers
/// the criterion.
fn polish(problem: &Problem, full: &Fitter, fitted: Fitted) -> Result<Fitted> {
    if problem.solver.max_iterations <= CANDIDATE_ITERATIONS || fitted.model.free.is_empty() {
        return Ok(fitted);
    }
    let polished = full.settle(full.fit(&fitted.model)?)?;
    Ok(if polished.criterion < fitted.criterion {
        polished
    } else {
        fitted
    })
}

/// Grows `problem`'s model as `settings` say (see the module doc).
pub fn grow(problem: &Problem, settings: &GrowSettings) -> Result<Grown> {
    let started = Instant::now();
    let criterion = Criterion::of(problem, settings.noise)?;
    let fitter = Fitter::new(problem, candidate_settings(&problem.solver), &criterion);
    let full = Fitter::new(problem, problem.solver, &criterion);
    let start = start_model(problem)?;
    let mut current = fitter.settle(fitter.fit(&start)?)?;
    let mut steps = vec![step_record(0, "start".into(), &current, vec![])];
    let stop_reason = loop {
        let p = current.model.free.len();
        if criterion.at_floor(current.chi2, p) == Some(true) {
            break "the fit reaches the noise floor (χ² ≤ (m − p) + 2·√(2(m − p)))".to_string();
        }
        if current.model.grown.len() >= settings.max_terms {
            break format!("{} terms added: the limit (max_terms)", settings.max_terms);
        }
        if steps.len() > MAX_STEPS {
            break format!("{MAX_STEPS} steps made: the limit");
        }
        let misfit = fitter.misfits(&current);
        let cands =
            candidates::propose(&current.model, &problem.pairs, &misfit, problem.trace.earth);
        let seeds: Vec<Model> = cands.iter().flat_map(|c| c.seeds.clone()).collect();
        let results = fitter.fit_all(&seeds)?;
        let (reports, chosen) = best_candidate(&fitter, &cands, &results)?;
        let Some((term, better)) = chosen.filter(|(_, f)| f.criterion < current.criterion) else {
            // Record what was tried, then stop.
            let step = steps.len();
            let mut last = step_record(step, "none kept".into(), &current, reports);
            last.action = "no candidate lowers the criterion".into();
            steps.push(last);
            break "no candidate term lowers the criterion".to_string();
        };
        current = polish(problem, &full, better)?;
        steps.push(step_record(
            steps.len(),
            format!("add {}", term.name(&current.model.medium)),
            &current,
            reports,
        ));
        // Drop, one term at a time, while a removal lowers the criterion.
        while steps.len() <= MAX_STEPS {
            let Some((name, without)) = best_drop(&fitter, &current)? else {
                break;
            };
            current = without;
            steps.push(step_record(
                steps.len(),
                format!("drop {name}"),
                &current,
                vec![],
            ));
        }
    };
    let current = polish(problem, &full, current)?;
    let at_noise_floor = criterion.at_floor(current.chi2, current.model.free.len());
    let held = current
        .model
        .held
        .iter()
        .map(|h| HeldReport {
            name: h.param.to_string(),
            value: h.value,
            reason: h.reason.clone(),
        })
        .collect();
    let report = GrowReport {
        criterion: criterion.describe(),
        noise: settings.noise,
        pairs_with_noise: problem.pair_noise.iter().flatten().count(),
        residual_components: criterion.m,
        max_terms: settings.max_terms,
        steps,
        stop_reason,
        at_noise_floor,
        held,
        fits: fitter.fits() + full.fits(),
        wall_time_s: started.elapsed().as_secs_f64(),
    };
    Ok(Grown {
        fitted: current,
        report,
    })
}

/// The problem whose fit is the grown model: its terms and free parameters
/// (held ones fixed at their values), started from the seed the kept fit
/// started from, fitted by Levenberg–Marquardt alone. That repeats the kept
/// fit (deterministic, and with at least its iterations), so the result's
/// history and convergence plot show the fit from its seed.
pub fn grown_problem(problem: &Problem, grown: &Grown) -> Problem {
    let model = &grown.fitted.start;
    let mut p = problem.clone();
    p.medium = model.medium.clone();
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
    fn ties_go_to_the_earliest() {
        assert_eq!(argmin([3.0, 1.0, 1.0, 2.0]), Some(1));
        assert_eq!(argmin([f64::INFINITY, f64::INFINITY]), Some(0));
        assert_eq!(argmin(std::iter::empty()), None);
    }
}
