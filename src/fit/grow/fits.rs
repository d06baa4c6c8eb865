//! One model's fit during growth, and its judgement: what ran away, what
//! the pairs do not determine, and the fit again with those held.
//!
//! - [`Fitter::fit`] runs Levenberg–Marquardt from the model's values (a
//!   failed run is F = ∞) and remembers every fit by its starting model, so
//!   a model already visited is never fitted again.
//! - [`Fitter::settle`] judges a fit. A parameter that moved more than
//!   [`RUNAWAY`] times its size from where the fit started ran away: in a
//!   grown term that makes the candidate a failure (criterion ∞); in the
//!   problem's own parameters it is held at its start. Then the Jacobian at
//!   the fit is analysed ([`crate::fit::identify`]; the models growing fits
//!   are gauge-free, [`super::model::GAUGE_REASON`]): for each direction
//!   the pairs cannot see, its largest parameter is held where the fit put
//!   it (along such a direction no endpoint moves, so holding it there costs
//!   nothing, and a value that ran away was caught before). The reduced
//!   model is fitted again, at most
//!   [`SETTLE_ROUNDS`] times; a fit still unsettled then is a failure.
//!
//! The size of a parameter, for [`RUNAWAY`]: the amplitude sum S of the
//! model the fit started from for a logistic amplitude, |scale| for
//! `scale`, max(|start|, 1) for every other (metres, kelvins, K/m).

use super::criterion::Criterion;
use super::model::{Model, amplitude_sum};
use crate::error::{Error, Result};
use crate::fit::identify;
use crate::fit::objective::Objective;
use crate::fit::solve::run_lm;
use crate::medium::{HotField, Param};
use crate::problem::{Problem, SolverSettings};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A parameter that moves more than this many times its size in one fit
/// ran away.
pub const RUNAWAY: f64 = 1e6;

/// Most rounds of holding and refitting in [`Fitter::settle`].
pub const SETTLE_ROUNDS: usize = 3;

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
    /// The criterion (∞ for a failed fit).
    pub criterion: f64,
}

impl Fitted {
    /// The same fit marked failed: criterion ∞.
    fn failed(mut self) -> Fitted {
        self.criterion = f64::INFINITY;
        self
    }
}

/// Fits models of one problem with one setting and one criterion, and
/// remembers every fit.
pub struct Fitter<'a> {
    problem: &'a Problem,
    settings: SolverSettings,
    criterion: &'a Criterion,
    memo: Mutex<HashMap<String, Fitted>>,
    fits: AtomicUsize,
}

impl<'a> Fitter<'a> {
    /// A fitter of `problem`'s pairs with `settings`, judged by `criterion`.
    pub fn new(problem: &'a Problem, settings: SolverSettings, criterion: &'a Criterion) -> Self {
        Fitter {
            problem,
            settings,
            criterion,
            memo: Mutex::new(HashMap::new()),
            fits: AtomicUsize::new(0),
        }
    }

    /// Fits run so far (a remembered fit counts once).
    pub fn fits(&self) -> usize {
        self.fits.load(Ordering::Relaxed)
    }

    /// The objective of `model`'s free parameters.
    fn objective(&self, model: &Model) -> Objective {
        Objective::new(
            model.medium.clone(),
            model.free.clone(),
            self.problem.pairs.clone(),
            self.problem.trace,
        )
    }

    /// Fits `model` from its current values; a failed run counts as F = ∞.
    pub fn fit(&self, model: &Model) -> Result<Fitted> {
        // Debug prints every f64 in its shortest exact form: equal keys are
        // equal models.
        let key = format!("{model:?}");
        if let Some(f) = self.memo.lock().map_err(|_| poisoned())?.get(&key) {
            return Ok(f.clone());
        }
        self.fits.fetch_add(1, Ordering::Relaxed);
        let objective = self.objective(model);
        let x0 = model.x();
        let (x, f) = if x0.is_empty() {
            (x0, objective.cost(&[]))
        } else {
            // A seed whose run fails (its first step off the model's domain,
            // say) is a seed that did not fit: F = ∞, the other seeds decide.
            match run_lm(&objective, &self.settings, &model.bounds, &x0, "grow", None) {
                Ok(run) => (run.end, run.objective),
                // Ctrl-C is no failed seed: it stops the growth.
                Err(Error::Interrupted) => return Err(Error::Interrupted),
                Err(_) => (x0, f64::INFINITY),
            }
        };
        let f = if f.is_finite() { f } else { f64::INFINITY };
        let pair_sq = if self.criterion.needs_pairs() && f.is_finite() {
            pair_norms(&objective.residuals(&x).0)
        } else {
            vec![]
        };
        let chi2 = self.criterion.chi2(f, &pair_sq);
        let fitted = Fitted {
            start: model.clone(),
            model: model.at(&x),
            objective: f,
            chi2,
            criterion: self.criterion.value(f, chi2, model.free.len()),
        };
        self.memo
            .lock()
            .map_err(|_| poisoned())?
            .insert(key, fitted.clone());
        Ok(fitted)
    }

    /// Fits every model in parallel; results in input order.
    pub fn fit_all(&self, models: &[Model]) -> Result<Vec<Fitted>> {
        models.par_iter().map(|m| self.fit(m)).collect()
    }

    /// Judges `fitted` and fits it again with what ran away or is
    /// undetermined held (see the module doc).
    pub fn settle(&self, fitted: Fitted) -> Result<Fitted> {
        let mut fitted = fitted;
        for _ in 0..SETTLE_ROUNDS {
            if !fitted.criterion.is_finite() {
                return Ok(fitted);
            }
            let (runaway, grown_ran) = self.runaway(&fitted);
            if grown_ran {
                return Ok(fitted.failed());
            }
            let hold = if runaway.is_empty() {
                self.undetermined(&fitted)
            } else {
                runaway
            };
            if hold.is_empty() {
                return Ok(fitted);
            }
            let model = fitted.model.hold(&hold);
            fitted = self.fit(&model)?;
        }
        let (runaway, _) = self.runaway(&fitted);
        if runaway.is_empty() && self.undetermined(&fitted).is_empty() {
            Ok(fitted)
        } else {
            Ok(fitted.failed())
        }
    }

    /// The parameters of `fitted` that ran away, each with its start value
    /// and the reason; and whether one of them is a grown term's.
    fn runaway(&self, fitted: &Fitted) -> (Vec<(Param, f64, String)>, bool) {
        let start = &fitted.start;
        let s = amplitude_sum(&start.medium);
        let mut out = Vec::new();
        let mut grown = false;
        for (p, x0) in start.free.iter().zip(start.x()) {
            let x = fitted.model.medium.get(*p).unwrap_or(f64::NAN);
            let size = match p {
                Param::BackgroundN | Param::InversionN | Param::Hot(_, HotField::N) => s,
                _ => x0.abs().max(1.0),
            }
            .max(f64::MIN_POSITIVE);
            // NaN counts as ran away.
            let within = (x - x0).abs() <= RUNAWAY * size;
            if !within {
                grown |= start.grown.iter().any(|t| t.owns(*p));
                out.push((
                    *p,
                    x0,
                    format!("ran away: went from {x0} to {x:e} in one fit (more than {RUNAWAY:e} times its size {size})"),
                ));
            }
        }
        (out, grown)
    }

    /// For each direction the pairs cannot see at `fitted`, its largest
    /// parameter (not one already chosen), with its fitted value: holding it
    /// there moves no endpoint, so the refit starts where this fit ended.
    fn undetermined(&self, fitted: &Fitted) -> Vec<(Param, f64, String)> {
        let model = &fitted.model;
        if model.free.is_empty() {
            return vec![];
        }
        let x = model.x();
        let (_, jac) = self.objective(model).jacobian(&x);
        let ident = identify::analyse(&jac, &x, &model.free, fitted.objective);
        let mut out: Vec<(Param, f64, String)> = Vec::new();
        for dir in &ident.undetermined {
            // The combination's names are the free parameters' own, largest
            // weight first.
            let chosen = dir.combination.iter().find_map(|(name, _)| {
                let k = model.free.iter().position(|p| p.to_string() == *name)?;
                let p = model.free[k];
                (!out.iter().any(|(q, _, _)| *q == p)).then_some((k, p))
            });
            if let Some((k, p)) = chosen {
                let names: Vec<&str> = dir.combination.iter().map(|(n, _)| n.as_str()).collect();
                out.push((
                    p,
                    x[k],
                    format!(
                        "undetermined: the pairs cannot tell {} apart ({})",
                        names.join(", "),
                        dir.note
                    ),
                ));
            }
        }
        out
    }

    /// Per pair, |rᵢ| at the fitted model.
    pub fn misfits(&self, fitted: &Fitted) -> Vec<f64> {
        let objective = Objective::new(
            fitted.model.medium.clone(),
            vec![],
            self.problem.pairs.clone(),
            self.problem.trace,
        );
        let (r, _) = objective.residuals(&[]);
        pair_norms(&r).into_iter().map(f64::sqrt).collect()
    }
}

fn poisoned() -> Error {
    Error::Solver {
        run: "grow".into(),
        message: "a fit's thread panicked".into(),
    }
}

/// Per pair, |rᵢ|² of the residual vector `r` (three components a pair).
pub fn pair_norms(r: &nalgebra::DVector<f64>) -> Vec<f64> {
    r.as_slice()
        .chunks(3)
        .map(|c| c.iter().map(|v| v * v).sum::<f64>())
        .collect()
}
