//! Growing the model (`mirage fit --grow`): from the problem's medium (a
//! background alone, say), add the terms the pairs call for, one at a time,
//! and only those.
//!
//! # Algorithm
//!
//! 1. Fit the starting model (the problem's medium and `free`).
//! 2. Propose candidates ([`candidates`]), each with several seeds. The
//!    logistic model: the inversion, if the medium has none, and one more hot
//!    spot. Real air: the surface layer (`air.temperature.exponential`) and
//!    the step aloft (`air.temperature.inversion`), each if absent and the
//!    temperature is no table, and one more hot spot in kelvins.
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
//! BIC = m·ln(2F/m) + p·ln m. When pairs carry their own σᵢ
//! (`pairs[i].noise`; a pair without one takes `--noise`), χ² =
//! Σᵢ |rᵢ|²/(wᵢσᵢ)² over the weighted residuals rᵢ = wᵢ·(eᵢ − tᵢ), that is
//! Σᵢ |eᵢ − tᵢ|²/σᵢ² (a pair of weight 0 counts nothing). The fits still
//! minimise F; weights wᵢ ∝ 1/σᵢ make F's minimum χ²'s. BIC rather than AICc: AICc's penalty per
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
//! ([`candidates::GROWN_EDGE`]). Real air grows only its temperature:
//! the surface layer, the step aloft and hot spots, never a lapse, a table,
//! the pressure or the humidity, and nothing but hot spots beside a table; a
//! grown real-air term's excess stays within ±[`candidates::AIR_MAX_DELTA`] K.
//! The logistic model needs a term to start from (a background). Other kinds
//! do not grow.

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

/// What the criterion knows of the endpoint noise.
#[derive(Clone, Debug, PartialEq)]
pub enum Noise {
    /// σ unknown: estimated from the residuals.
    Unknown,
    /// One σ (m) for every pair: χ² = 2F/σ².
    Uniform(f64),
    /// A σᵢ per pair: χ² = Σᵢ kᵢ·|rᵢ|² with kᵢ = 1/(wᵢσᵢ)² held here, one per
    /// pair (0 for a pair of weight 0, whose residual is 0).
    PerPair(Vec<f64>),
}

/// The information criterion of least squares with endpoint noise σ.
#[derive(Clone, Debug, PartialEq)]
pub struct Criterion {
    /// The noise.
    pub noise: Noise,
    /// Residual components m.
    pub m: usize,
}

impl Criterion {
    /// The criterion of `problem`'s pairs with the global σ `noise`
    /// (`--noise`, `solver.noise`): per-pair σᵢ when some pair carries one
    /// (then every pair must have one, its own or the global one).
    pub fn of(problem: &Problem, noise: Option<f64>) -> Result<Criterion> {
        let m = 2 * problem.pairs.len();
        let own = |i: usize| problem.pair_noise.get(i).copied().flatten();
        let with_own = (0..problem.pairs.len())
            .filter(|&i| own(i).is_some())
            .count();
        if with_own == 0 {
            let noise = noise.map_or(Noise::Unknown, Noise::Uniform);
            return Ok(Criterion { noise, m });
        }
        let mut k = Vec::with_capacity(problem.pairs.len());
        for (i, pair) in problem.pairs.iter().enumerate() {
            let Some(sigma) = own(i).or(noise) else {
                return Err(Error::input(
                    &problem.source,
                    "solver.noise",
                    format!(
                        "{with_own} of {} pairs carry their own `noise` but pairs[{i}] does not: give every pair a `noise`, or a σ for the rest in `solver.noise` (or --noise)",
                        problem.pairs.len()
                    ),
                ));
            };
            let ws = pair.weight * sigma;
            k.push(if pair.weight > 0.0 {
                1.0 / (ws * ws)
            } else {
                0.0
            });
        }
        Ok(Criterion {
            noise: Noise::PerPair(k),
            m,
        })
    }

    /// The criterion in words.
    pub fn describe(&self) -> String {
        match &self.noise {
            Noise::Uniform(s) => format!("BIC, σ = {s} m known: χ² + p·ln m, χ² = 2F/σ²"),
            Noise::PerPair(_) => "BIC, σᵢ per pair known: χ² + p·ln m, χ² = Σ|rᵢ|²/(wᵢσᵢ)²".into(),
            Noise::Unknown => "BIC, σ estimated: m·ln(2F/m) + p·ln m".into(),
        }
    }

    /// Whether χ² needs each pair's |rᵢ|², not only F.
    pub fn needs_pairs(&self) -> bool {
        matches!(self.noise, Noise::PerPair(_))
    }

    /// χ² of a fit with objective `f` and per-pair |rᵢ|² `pair_sq` (read only
    /// with per-pair σᵢ), if σ is known.
    pub fn chi2(&self, f: f64, pair_sq: &[f64]) -> Option<f64> {
        match &self.noise {
            Noise::Unknown => None,
            Noise::Uniform(s) => Some(2.0 * f / (s * s)),
            Noise::PerPair(_) if !f.is_finite() => Some(f64::INFINITY),
            Noise::PerPair(k) => {
                let c: f64 = k.iter().zip(pair_sq).map(|(k, r2)| k * r2).sum();
                Some(if c.is_finite() { c } else { f64::INFINITY })
            }
        }
    }

    /// The criterion of a fit with objective `f`, χ² `chi2` (from
    /// [`Criterion::chi2`]) and `p` free parameters.
    pub fn value(&self, f: f64, chi2: Option<f64>, p: usize) -> f64 {
        let m = self.m as f64;
        let penalty = p as f64 * m.ln();
        match chi2 {
            Some(c) => c + penalty,
            None => m * (2.0 * f / m).max(f64::MIN_POSITIVE).ln() + penalty,
        }
    }

    /// Whether χ² is within the noise floor (`None` when σ is unknown).
    pub fn at_floor(&self, chi2: Option<f64>, p: usize) -> Option<bool> {
        let dof = self.m.saturating_sub(p).max(1) as f64;
        chi2.map(|c| c <= dof + 2.0 * (2.0 * dof).sqrt())
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
    /// χ², when σ is known.
    pub chi2: Option<f64>,
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
        model.medium.clone(),
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
    let pair_sq = if criterion.needs_pairs() && f.is_finite() {
        pair_norms(&objective.residuals(&x).0)
    } else {
        vec![]
    };
    let chi2 = criterion.chi2(f, &pair_sq);
    Ok(Fitted {
        start: model.clone(),
        model: model.at(&x),
        objective: f,
        chi2,
        criterion: criterion.value(f, chi2, model.free.len()),
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

/// Per pair, |rᵢ|² of the residual vector `r` (three components a pair).
fn pair_norms(r: &nalgebra::DVector<f64>) -> Vec<f64> {
    r.as_slice()
        .chunks(3)
        .map(|c| c.iter().map(|v| v * v).sum::<f64>())
        .collect()
}

/// Per pair, |rᵢ| at the fitted model.
fn misfits(problem: &Problem, fitted: &Fitted) -> Vec<f64> {
    let objective = Objective::new(
        fitted.model.medium.clone(),
        vec![],
        problem.pairs.clone(),
        problem.trace,
    );
    let (r, _) = objective.residuals(&[]);
    pair_norms(&r).into_iter().map(f64::sqrt).collect()
}

/// The grown term of `fitted` with a parameter the pairs do not determine.
fn undetermined_term(problem: &Problem, fitted: &Fitted) -> Option<Term> {
    let model = &fitted.model;
    if model.free.is_empty() || model.grown.is_empty() {
        return None;
    }
    let objective = Objective::new(
        model.medium.clone(),
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

/// The starting model of `problem`: its medium and free parameters.
fn start_model(problem: &Problem) -> Result<Model> {
    match unsupported(&problem.medium) {
        None => Ok(Model {
            medium: problem.medium.clone(),
            free: problem.free.clone(),
            bounds: problem.bounds.clone(),
            grown: vec![],
        }),
        Some(reason) => Err(Error::input(&problem.source, "solver.grow", reason)),
    }
}

/// Grows `problem`'s model as `settings` say (see the module doc).
pub fn grow(problem: &Problem, settings: &GrowSettings) -> Result<Grown> {
    let started = Instant::now();
    let criterion = Criterion::of(problem, settings.noise)?;
    let lm = candidate_settings(&problem.solver);
    let mut fits = 1;
    let mut current = fit_model(problem, &start_model(problem)?, &lm, &criterion)?;
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
                term: c.term.name(&c.seeds[0].medium),
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
            let mut last = step_record(step, "none kept".into(), &current, reports);
            last.action = "no candidate lowers the criterion".into();
            steps.push(last);
            break "no candidate term lowers the criterion".to_string();
        };
        current = better;
        steps.push(step_record(
            steps.len(),
            format!("add {}", term.name(&current.model.medium)),
            &current,
            reports,
        ));
        // Prune, one term at a time, until nothing more goes.
        while steps.len() <= MAX_STEPS {
            if let Some(t) = undetermined_term(problem, &current) {
                let name = t.name(&current.model.medium);
                current = fit_model(problem, &current.model.without(t), &lm, &criterion)?;
                fits += 1;
                steps.push(step_record(
                    steps.len(),
                    format!("drop {name} (undetermined)"),
                    &current,
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
                    let name = older[i].name(&current.model.medium);
                    current = refits[i].clone();
                    steps.push(step_record(
                        steps.len(),
                        format!("drop {name} (criterion)"),
                        &current,
                        vec![],
                    ));
                }
                _ => break,
            }
        }
    };
    let at_noise_floor = criterion.at_floor(current.chi2, current.model.free.len());
    let report = GrowReport {
        criterion: criterion.describe(),
        noise: settings.noise,
        pairs_with_noise: problem.pair_noise.iter().flatten().count(),
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
    fn the_criterion_charges_ln_m_per_parameter_and_knows_its_floor() {
        let c = Criterion {
            noise: Noise::Uniform(0.01),
            m: 50,
        };
        // χ² = 2F/σ² = 50 at F = 2.5e-3.
        let chi2 = c.chi2(2.5e-3, &[]);
        assert!((chi2.unwrap() - 50.0).abs() < 1e-9);
        let d = c.value(2.5e-3, chi2, 6) - c.value(2.5e-3, chi2, 0);
        assert!((d - 6.0 * 50f64.ln()).abs() < 1e-9);
        // Floor for p = 0: 50 + 2·√100 = 70.
        assert_eq!(c.at_floor(c.chi2(0.5 * 70.0e-4, &[]), 0), Some(true));
        assert_eq!(c.at_floor(c.chi2(0.5 * 70.1e-4, &[]), 0), Some(false));
        let unknown = Criterion {
            noise: Noise::Unknown,
            m: 50,
        };
        assert_eq!(unknown.at_floor(unknown.chi2(1.0, &[]), 0), None);
    }

    /// A problem of three pairs with weights 1, 2, 0 and the given `noise`
    /// fields.
    fn three_pairs(noise: [&str; 3]) -> Problem {
        let pair = |w: f64, n: &str| {
            format!(
                r#"{{"origin": [0, 1.6, 0], "through": [0, 1.0, 900], "target": [0, 2.0, 900], "weight": {w}{n}}}"#
            )
        };
        let text = format!(
            r#"{{"medium": {{"scale": 1.0, "background": {{"n": 1.0, "a": 40.0}}}}, "pairs": [{}, {}, {}]}}"#,
            pair(1.0, noise[0]),
            pair(2.0, noise[1]),
            pair(0.0, noise[2]),
        );
        Problem::parse(&text, std::path::Path::new("p.json")).unwrap()
    }

    #[test]
    fn per_pair_noise_weighs_each_pairs_residual_by_its_own_sigma() {
        let p = three_pairs([r#", "noise": 0.01"#, r#", "noise": 0.02"#, ""]);
        assert_eq!(p.pair_noise, vec![Some(0.01), Some(0.02), None]);
        // The third pair has no σ of its own and none is given: refused,
        // naming `solver.noise`.
        let e = Criterion::of(&p, None).unwrap_err().to_string();
        assert!(e.contains("solver.noise") && e.contains("pairs[2]"), "{e}");
        // With a global σ for it: kᵢ = 1/(wᵢσᵢ)², 0 at weight 0.
        let c = Criterion::of(&p, Some(0.5)).unwrap();
        assert_eq!(
            c.noise,
            Noise::PerPair(vec![1e4, 1.0 / (0.04f64 * 0.04), 0.0])
        );
        assert!(c.needs_pairs());
        // |r₁|² = (1·3 cm)², |r₂|² = (2·2 cm)²: each pair at 3σ and 1σ,
        // χ² = 9 + 1 (the pair of weight 0 counts nothing).
        let sq = [0.03f64.powi(2), 0.04f64.powi(2), 0.0];
        let f = 0.5 * sq.iter().sum::<f64>();
        let chi2 = c.chi2(f, &sq).unwrap();
        assert!((chi2 - 10.0).abs() < 1e-9, "{chi2}");
        // One global σ would have read 2F/σ² = Σ|rᵢ|²/σ² instead.
        let uniform = Criterion::of(&three_pairs(["", "", ""]), Some(0.01)).unwrap();
        assert_eq!(uniform.noise, Noise::Uniform(0.01));
        assert!((uniform.chi2(f, &[]).unwrap() - 25.0).abs() < 1e-9);
        assert!(uniform.describe().contains("2F/σ²"));
        assert!(c.describe().contains("σᵢ"));
        // A failed fit has χ² = ∞.
        assert_eq!(c.chi2(f64::INFINITY, &[]), Some(f64::INFINITY));
    }

    #[test]
    fn ties_go_to_the_earliest() {
        assert_eq!(argmin([3.0, 1.0, 1.0, 2.0]), Some(1));
        assert_eq!(argmin([f64::INFINITY, f64::INFINITY]), Some(0));
        assert_eq!(argmin(std::iter::empty()), None);
    }
}
