//! How sure a fit is: an ensemble of fits to resampled observations
//! (`mirage ensemble`, `docs/ensemble.md`).
//!
//! # Algorithm
//!
//! 1. The problem is fitted once (grown first if its solver says so; the
//!    members then fit the grown model's terms). Its parameters x̂, medium
//!    M̂ and residuals are the best fit.
//! 2. Each member k (seeded by `seed` and k alone, so a member's result does
//!    not depend on which thread or machine ran it) makes new observations
//!    and fits them with Levenberg–Marquardt from x̂:
//!    - **parametric** (default): every pair's target is moved to where M̂
//!      puts its ray, plus Gaussian noise of σᵢ in the two directions of
//!      its target plane. σᵢ is the observations' noise: `noise` (metres,
//!      or arcseconds with angle residuals), else the pair's own `noise`,
//!      else the fit's own residual scale σ̂ = √(2F / (2m − p)) (m pairs,
//!      p parameters), each divided by the pair's weight;
//!    - **bootstrap**: the m pairs are drawn with replacement.
//!      Pairs whose best-fit ray never meets its plane keep their target.
//! 3. Per parameter: the best value, its linearised standard error, the
//!    members' mean, standard deviation and the 2.5, 16, 50, 84 and 97.5 %
//!    percentiles (linear interpolation between order statistics). Where
//!    the ensemble's spread and the linearised error differ by more than a
//!    factor 1.5, or the median sits more than half an error from the best
//!    value, the report says so: the residuals are nonlinear in that
//!    parameter over the noise.
//! 4. Profiles: every member's temperature (real air's own, the implied air
//!    of other media, `crate::profile`) and δ = n − 1 on one grid of
//!    heights (the best fit's profile rows: uniform to its top, dense about
//!    its layers) at the best fit's [`crate::profile::default_at`], with the
//!    same percentiles pointwise (members interpolated linearly).
//!
//! A parametric ensemble is exact in law when the residuals are linear in
//! the parameters over the noise (its 68 % band then holds the truth in 68
//! % of problems); `tests/ensemble.rs` checks the rate over seeded
//! synthetic problems.

use super::objective::Objective;
use super::report::FitReport;
use super::solve;
use crate::error::Result;
use crate::math::{SplitMix64, V3};
use crate::medium::{Medium, Param};
use crate::problem::{Problem, ProblemFile, Residual, SolverMethod};
use crate::profile::{air_profile, default_at, default_top};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// The percentiles reported (per cent).
pub const PERCENTILES: [f64; 5] = [2.5, 16.0, 50.0, 84.0, 97.5];

/// What an ensemble does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnsembleSettings {
    /// Number of members (≥ 1).
    pub members: usize,
    /// The observations' noise σ (metres, or arcseconds with angle
    /// residuals); `None`: the pairs' own `noise`, else the fit's residual
    /// scale. Parametric resampling only.
    pub noise: Option<f64>,
    /// Resample the pairs with replacement instead of adding noise.
    pub bootstrap: bool,
    /// The ensemble's seed.
    pub seed: u64,
}

/// One member's fit.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Member {
    /// Its parameters, in the order of [`EnsembleReport::parameters`].
    pub params: Vec<f64>,
    /// Its F at the end (m², or rad² with angle residuals).
    pub objective: f64,
}

/// A parameter across the ensemble.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ParamSpread {
    /// Its path.
    pub name: String,
    /// The best fit's value.
    pub best: f64,
    /// The linearised standard error at the ensemble's noise (absent where
    /// the pairs do not determine it): √diag((Jᵀ S⁻² J)⁻¹).
    pub standard_error: Option<f64>,
    /// The members' mean.
    pub mean: f64,
    /// The members' standard deviation.
    pub std: f64,
    /// The members' values at [`PERCENTILES`].
    pub percentiles: [f64; 5],
    /// Where the ensemble and the linearised error disagree, in words.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub disagreement: Option<String>,
}

/// Envelopes of a profile on a grid of heights.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Envelope {
    /// The best fit's value per height.
    pub best: Vec<f64>,
    /// Per percentile of [`PERCENTILES`], the value per height.
    pub percentiles: [Vec<f64>; 5],
    /// The truth's, when one was given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truth: Option<Vec<f64>>,
}

/// Temperature and δ envelopes.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Profiles {
    /// Where (x, z, metres).
    pub at: [f64; 2],
    /// Whether the temperature is implied (a medium other than real air).
    pub implied: bool,
    /// Heights (m), from the ground up.
    pub heights: Vec<f64>,
    /// Temperature (°C).
    pub temperature: Envelope,
    /// δ = n − 1.
    pub delta: Envelope,
}

/// How the observations were resampled.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Resampling {
    /// `parametric` or `bootstrap`.
    pub kind: &'static str,
    /// Parametric: σ as used, in the residual's unit (m, or arcseconds)
    /// (per pair where the pairs give their own; this is the common one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise: Option<f64>,
    /// Where σ came from: `given`, `pairs`, or `fit` (the residual scale).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise_from: Option<&'static str>,
    /// The seed.
    pub seed: u64,
}

/// The whole ensemble (what `mirage ensemble -o` writes).
#[derive(Clone, Debug, Serialize)]
pub struct EnsembleReport {
    /// Problem name.
    pub problem: String,
    /// How the observations were resampled.
    pub resampling: Resampling,
    /// The best fit's F.
    pub objective: f64,
    /// The parameters, across the ensemble.
    pub parameters: Vec<ParamSpread>,
    /// Every member.
    pub members: Vec<Member>,
    /// Temperature and δ envelopes.
    pub profiles: Profiles,
    /// The best fit's medium.
    pub medium: Medium,
    /// Seconds, wall clock.
    pub wall_time_s: f64,
}

/// The percentile `q` (per cent) of sorted `v`, interpolated linearly
/// between order statistics (NumPy's default, `linear`).
pub fn percentile(sorted: &[f64], q: f64) -> f64 {
    let n = sorted.len();
    if n == 1 {
        return sorted[0];
    }
    let pos = q / 100.0 * (n - 1) as f64;
    let i = (pos.floor() as usize).min(n - 2);
    let f = pos - i as f64;
    sorted[i] + f * (sorted[i + 1] - sorted[i])
}

fn percentiles_of(values: &mut [f64]) -> [f64; 5] {
    values.sort_by(f64::total_cmp);
    PERCENTILES.map(|q| percentile(values, q))
}

/// A standard normal draw (Box–Muller, one of the pair).
fn gaussian(rng: &mut SplitMix64) -> f64 {
    let u1 = 1.0 - rng.next_f64(); // (0, 1]
    let u2 = rng.next_f64();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Member k's generator: independent of every other member's.
fn member_rng(seed: u64, k: usize) -> SplitMix64 {
    let mut mix = SplitMix64(seed ^ (k as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
    SplitMix64(mix.next_u64())
}

/// Two unit vectors spanning the plane of unit normal `n`: the one nearest
/// the vertical, then n × it.
fn plane_basis(n: V3) -> (V3, V3) {
    let y = V3::new(0.0, 1.0, 0.0);
    let k = y.dot(n);
    let mut u = V3::new(-k * n.x, 1.0 - k * n.y, -k * n.z);
    if u.norm() < 1e-9 {
        u = V3::new(1.0, 0.0, 0.0);
    }
    let u = u.normalized();
    let v = V3::new(
        n.y * u.z - n.z * u.y,
        n.z * u.x - n.x * u.z,
        n.x * u.y - n.y * u.x,
    );
    (u, v)
}

/// The problem the members start from: grown if its solver grows (the
/// members then fit the grown terms), then fitted.
fn best_fit(problem: &Problem) -> Result<(Problem, FitReport)> {
    let base = match problem.solver.grow {
        Some(settings) => {
            let grown = super::grow::grow(problem, &settings)?;
            let mut p = super::grow::grown_problem(problem, &grown);
            p.solver.grow = None;
            p
        }
        None => problem.clone(),
    };
    let report = super::fit(&base, None)?;
    Ok((base, report))
}

/// Runs the ensemble of `problem` (see the module doc); `truth`, when
/// given, is drawn beside the envelopes. [`EnsemblePlan::new`], then every
/// member ([`EnsemblePlan::members`]) on all threads, then
/// [`EnsemblePlan::summarise`].
pub fn ensemble(
    problem: &Problem,
    settings: &EnsembleSettings,
    truth: Option<&Medium>,
) -> Result<EnsembleReport> {
    let started = std::time::Instant::now();
    let plan = EnsemblePlan::new(problem, settings, truth)?;
    let members = plan.members(0..settings.members)?;
    plan.summarise(members, started.elapsed().as_secs_f64())
}

/// Where σ came from, as [`Resampling::noise_from`] names it.
const NOISE_FROM: [&str; 3] = ["given", "pairs", "fit"];

/// An ensemble made ready to run: the best fit, the noise, and the problem
/// the members fit. Its members are independent tasks: [`EnsemblePlan::member`]
/// `(k)` depends on the plan and k alone, so they may run in any order, on
/// any thread or machine (a plan travels as JSON:
/// [`EnsemblePlan::to_json`], [`EnsemblePlan::from_json`]), and
/// [`EnsemblePlan::summarise`] of members 0..N is what [`ensemble`] returns.
#[derive(Clone, Debug)]
pub struct EnsemblePlan {
    settings: EnsembleSettings,
    /// The problem's name and residual, as given.
    name: String,
    residual: Residual,
    /// The problem the members fit: the (grown) problem at the best fit,
    /// Levenberg–Marquardt converged fully.
    fitted: Problem,
    /// The best fit's parameters (names, values), F and medium.
    names: Vec<String>,
    x_best: Vec<f64>,
    objective: f64,
    medium: Medium,
    /// Per pair: where the best fit puts its ray; `None` where it never
    /// meets its plane.
    endpoints: Vec<Option<[f64; 3]>>,
    /// Per pair: its targets' σ (residual units over its weight).
    sigma: Vec<f64>,
    /// Per parameter: the linearised standard error at the ensemble's noise.
    linearised: Vec<Option<f64>>,
    /// The common σ (residual units) and where it came from.
    common: f64,
    noise_from: &'static str,
    truth: Option<Medium>,
}

/// An [`EnsemblePlan`] as JSON: the problem document and everything the best
/// fit found, so a plan is re-created without fitting again.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PlanFile {
    /// The problem as its file holds it, and the path that names it.
    problem: ProblemFile,
    path: std::path::PathBuf,
    members: usize,
    noise: Option<f64>,
    bootstrap: bool,
    seed: u64,
    truth: Option<Medium>,
    /// The model the members fit (the grown one's terms where the problem
    /// grows): its free parameters and bounds (`null`: unbounded).
    free: Vec<String>,
    bounds: Vec<[Option<f64>; 2]>,
    /// The best fit.
    medium: Medium,
    objective: f64,
    parameters: Vec<PlanParameter>,
    endpoints: Vec<Option<[f64; 3]>>,
    sigma: Vec<f64>,
    noise_used: f64,
    noise_from: String,
}

/// A parameter of a [`PlanFile`]: the best fit's value and linearised error.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct PlanParameter {
    name: String,
    value: f64,
    standard_error: Option<f64>,
}

impl EnsemblePlan {
    /// Fits `problem` (grown first if its solver grows) and derives each
    /// pair's σ and the linearised errors (steps 1 and 2 of the module doc,
    /// up to the members). `truth`, when given, is drawn beside the
    /// envelopes.
    pub fn new(
        problem: &Problem,
        settings: &EnsembleSettings,
        truth: Option<&Medium>,
    ) -> Result<Self> {
        let (base, best) = best_fit(problem)?;
        let x_best: Vec<f64> = best.parameters.iter().map(|p| p.value).collect();
        let mut fitted = base;
        fitted.medium = best.medium.clone();
        converge_fully(&mut fitted);
        let m = fitted.pairs.len();
        let p = x_best.len();

        // σ in the residual's unit, per pair.
        let residual_scale = {
            let dof = (2 * m).saturating_sub(p).max(1) as f64;
            (2.0 * best.totals.objective / dof).sqrt()
        };
        let (common, noise_from) = match settings.noise {
            Some(s) => (problem.residual.noise_in_residual_units(s), NOISE_FROM[0]),
            None if fitted.pair_noise.iter().any(Option::is_some) => {
                (residual_scale, NOISE_FROM[1])
            }
            None => (residual_scale, NOISE_FROM[2]),
        };
        // Per pair: the residual's noise (residual units), and the targets'.
        let residual_sigma: Vec<f64> = (0..m)
            .map(|i| match (settings.noise, fitted.pair_noise[i]) {
                (None, Some(own)) => problem.residual.noise_in_residual_units(own),
                _ => common,
            })
            .collect();
        let sigma: Vec<f64> = (0..m)
            .map(|i| residual_sigma[i] / fitted.pairs[i].weight)
            .collect();
        let linearised = linearised_errors(&fitted, &x_best, &residual_sigma);
        // An occluded ray still has its residual (traced through the
        // ground); only a ray that never meets its plane has none to perturb.
        let endpoints = best
            .pairs
            .iter()
            .map(|r| (!r.unreachable).then_some(r.endpoint))
            .collect();
        Ok(EnsemblePlan {
            settings: *settings,
            name: problem.name.clone(),
            residual: problem.residual,
            fitted,
            names: best.parameters.iter().map(|p| p.name.clone()).collect(),
            x_best,
            objective: best.totals.objective,
            medium: best.medium,
            endpoints,
            sigma,
            linearised,
            common,
            noise_from,
            truth: truth.cloned(),
        })
    }

    /// The settings it was made with.
    pub fn settings(&self) -> &EnsembleSettings {
        &self.settings
    }

    /// Member k: the fit to the k-th resampled observations (step 2 of the
    /// module doc), seeded by the ensemble's seed and k alone. Runs on the
    /// current rayon pool; its result does not depend on the pool's size.
    pub fn member(&self, k: usize) -> Result<Member> {
        crate::interrupt::check()?;
        let fitted = &self.fitted;
        let m = fitted.pairs.len();
        let mut rng = member_rng(self.settings.seed, k);
        let mut mp = fitted.clone();
        if self.settings.bootstrap {
            let picks: Vec<usize> = (0..m)
                .map(|_| ((rng.next_f64() * m as f64) as usize).min(m - 1))
                .collect();
            mp.pairs = picks.iter().map(|&i| fitted.pairs[i]).collect();
            mp.pair_noise = picks.iter().map(|&i| fitted.pair_noise[i]).collect();
        } else {
            let earth = fitted.trace.earth;
            for (i, pair) in mp.pairs.iter_mut().enumerate() {
                let (g1, g2) = (gaussian(&mut rng), gaussian(&mut rng));
                let Some(endpoint) = self.endpoints[i] else {
                    continue;
                };
                let normal = fitted.pairs[i].plane_on(earth).normal;
                let (u, v) = plane_basis(normal);
                let t = V3::from(endpoint) + (u * g1 + v * g2) * self.sigma[i];
                pair.target = t.to_array();
            }
        }
        let objective = Objective::from_problem(&mp);
        let solution = solve::solve(&objective, &mp.solver, &mp.bounds, 0.0, None)?;
        Ok(Member {
            params: solution.x,
            objective: solution.objective,
        })
    }

    /// Members `ks`, on the current rayon pool's threads, in the order of
    /// `ks`.
    pub fn members(&self, ks: std::ops::Range<usize>) -> Result<Vec<Member>> {
        let members: Vec<Result<Member>> = ks.into_par_iter().map(|k| self.member(k)).collect();
        crate::interrupt::check()?;
        members.into_iter().collect()
    }

    /// The report of members 0..N (steps 3 and 4 of the module doc), in
    /// that order, however they were run; `wall_time_s` is reported as the
    /// ensemble's wall-clock time. Fails, naming `members`, unless there
    /// are [`EnsembleSettings::members`] of them, each with the plan's
    /// number of parameters.
    pub fn summarise(&self, members: Vec<Member>, wall_time_s: f64) -> Result<EnsembleReport> {
        if members.len() != self.settings.members {
            return Err(crate::error::Error::usage(
                "members",
                format!(
                    "the plan has {} members, got {}",
                    self.settings.members,
                    members.len()
                ),
            ));
        }
        if let Some(k) = members
            .iter()
            .position(|mm| mm.params.len() != self.x_best.len())
        {
            return Err(crate::error::Error::usage(
                "members",
                format!(
                    "member {k} has {} parameters, the plan {}",
                    members[k].params.len(),
                    self.x_best.len()
                ),
            ));
        }
        let parameters = self
            .names
            .iter()
            .enumerate()
            .map(|(j, name)| self.spread(j, name, &members))
            .collect();
        let profiles = profiles_of(
            &self.fitted,
            &self.medium,
            &members,
            &self.x_best,
            self.truth.as_ref(),
        );
        let settings = &self.settings;
        let resampling = if settings.bootstrap {
            Resampling {
                kind: "bootstrap",
                noise: None,
                noise_from: None,
                seed: settings.seed,
            }
        } else {
            let shown = match self.residual {
                Residual::Distance => self.common,
                Residual::Angle => self.common * crate::sightline::ARCSEC_PER_RADIAN,
            };
            Resampling {
                kind: "parametric",
                noise: Some(shown),
                noise_from: Some(self.noise_from),
                seed: settings.seed,
            }
        };
        Ok(EnsembleReport {
            problem: self.name.clone(),
            resampling,
            objective: self.objective,
            parameters,
            members,
            profiles,
            medium: self.medium.clone(),
            wall_time_s,
        })
    }

    /// Parameter j across the members (step 3 of the module doc).
    fn spread(&self, j: usize, name: &str, members: &[Member]) -> ParamSpread {
        let best = self.x_best[j];
        let mut values: Vec<f64> = members.iter().map(|mm| mm.params[j]).collect();
        let n = values.len() as f64;
        let mean = values.iter().sum::<f64>() / n;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
        let std = var.sqrt();
        let percentiles = percentiles_of(&mut values);
        let disagreement = self.linearised[j].and_then(|se| {
            if se.is_nan() || se <= 0.0 || members.len() < 10 {
                return None;
            }
            let ratio = std / se;
            let shift = (percentiles[2] - best).abs() / se;
            if !(1.0 / 1.5..=1.5).contains(&ratio) {
                Some(format!(
                    "the ensemble's spread is {ratio:.2} × the linearised standard error: the residuals are not linear in it over the noise"
                ))
            } else if shift > 0.5 {
                Some(format!(
                    "the ensemble's median lies {shift:.2} standard errors from the best fit: its distribution is skewed"
                ))
            } else {
                None
            }
        });
        ParamSpread {
            name: name.to_string(),
            best,
            standard_error: self.linearised[j],
            mean,
            std,
            percentiles,
            disagreement,
        }
    }

    /// The plan as JSON text, for [`EnsemblePlan::from_json`] elsewhere
    /// (another process or machine). `file` must be the document the
    /// plan's problem was read from ([`Problem::from_file`]'s): the plan
    /// keeps the best fit, not the problem's pairs.
    pub fn to_json(&self, file: &ProblemFile) -> Result<String> {
        let plan = PlanFile {
            problem: file.clone(),
            path: self.fitted.source.clone(),
            members: self.settings.members,
            noise: self.settings.noise,
            bootstrap: self.settings.bootstrap,
            seed: self.settings.seed,
            truth: self.truth.clone(),
            free: self.fitted.free.iter().map(|p| p.to_string()).collect(),
            bounds: self
                .fitted
                .bounds
                .iter()
                .map(|&(lo, hi)| [lo.is_finite().then_some(lo), hi.is_finite().then_some(hi)])
                .collect(),
            medium: self.medium.clone(),
            objective: self.objective,
            parameters: (0..self.names.len())
                .map(|j| PlanParameter {
                    name: self.names[j].clone(),
                    value: self.x_best[j],
                    standard_error: self.linearised[j],
                })
                .collect(),
            endpoints: self.endpoints.clone(),
            sigma: self.sigma.clone(),
            noise_used: self.common,
            noise_from: self.noise_from.to_string(),
        };
        serde_json::to_string(&plan).map_err(|e| crate::error::Error::encode("the plan", e))
    }

    /// The plan that [`EnsemblePlan::to_json`] wrote: the problem parsed
    /// again, its model set to the best fit, nothing fitted. Its members
    /// equal the original plan's bit for bit. Errors name the plan's field
    /// (in the file `<plan>`).
    pub fn from_json(text: &str) -> Result<Self> {
        let here = std::path::Path::new("<plan>");
        let bad = |field: &str, message: String| crate::error::Error::input(here, field, message);
        let f: PlanFile = crate::io::json::parse_json(text, here, "plan")?;
        let problem = Problem::from_file(f.problem, &f.path)?;
        check_members(f.members).map_err(|e| bad("members", e.to_string()))?;
        let mut fitted = problem.clone();
        fitted.free = f
            .free
            .iter()
            .enumerate()
            .map(|(i, name)| {
                name.parse::<Param>()
                    .map_err(|e| bad(&format!("free[{i}]"), e.to_string()))
            })
            .collect::<Result<_>>()?;
        fitted.bounds = f
            .bounds
            .iter()
            .map(|[lo, hi]| (lo.unwrap_or(f64::NEG_INFINITY), hi.unwrap_or(f64::INFINITY)))
            .collect();
        f.medium
            .validate()
            .map_err(|e| e.within("medium").in_file(here))?;
        if let Some(t) = &f.truth {
            t.validate().map_err(|e| e.within("truth").in_file(here))?;
        }
        fitted.medium = f.medium.clone();
        converge_fully(&mut fitted);
        let (m, p) = (fitted.pairs.len(), fitted.free.len());
        for (field, len, want) in [
            ("bounds", fitted.bounds.len(), p),
            ("parameters", f.parameters.len(), p),
            ("endpoints", f.endpoints.len(), m),
            ("sigma", f.sigma.len(), m),
        ] {
            if len != want {
                return Err(bad(field, format!("has {len} entries, the problem {want}")));
            }
        }
        let noise_from = NOISE_FROM
            .into_iter()
            .find(|n| *n == f.noise_from)
            .ok_or_else(|| {
                bad(
                    "noise_from",
                    format!("must be `given`, `pairs` or `fit`, got `{}`", f.noise_from),
                )
            })?;
        Ok(EnsemblePlan {
            settings: EnsembleSettings {
                members: f.members,
                noise: f.noise,
                bootstrap: f.bootstrap,
                seed: f.seed,
            },
            name: problem.name,
            residual: problem.residual,
            fitted,
            names: f.parameters.iter().map(|q| q.name.clone()).collect(),
            x_best: f.parameters.iter().map(|q| q.value).collect(),
            objective: f.objective,
            medium: f.medium,
            endpoints: f.endpoints,
            sigma: f.sigma,
            linearised: f.parameters.iter().map(|q| q.standard_error).collect(),
            common: f.noise_used,
            noise_from,
            truth: f.truth,
        })
    }
}

/// The members' solver: Levenberg–Marquardt, converged fully. Stopping
/// early would keep them near x̂ and shrink the spread (at the default
/// tolerances the ensemble came out 7 % narrower than the linearised
/// errors).
fn converge_fully(fitted: &mut Problem) {
    fitted.solver.method = SolverMethod::Lm;
    fitted.solver.ftol = fitted.solver.ftol.min(1e-15);
    fitted.solver.xtol = fitted.solver.xtol.min(1e-15);
    fitted.solver.gtol = fitted.solver.gtol.min(1e-15);
    fitted.solver.grow = None;
}

/// The linearised standard errors at the ensemble's noise: the square roots
/// of the diagonal of (Jᵀ S⁻² J)⁻¹, J the residuals' Jacobian at the best
/// fit and S the residuals' noise (`residual_sigma` per pair). `None` where
/// JᵀJ is singular (a combination the pairs do not determine).
fn linearised_errors(fitted: &Problem, x: &[f64], residual_sigma: &[f64]) -> Vec<Option<f64>> {
    let p = x.len();
    if p == 0 {
        return Vec::new();
    }
    let objective = Objective::from_problem(fitted);
    let (_, mut j) = objective.jacobian(x);
    for (i, s) in residual_sigma.iter().enumerate() {
        for c in 0..3 {
            let mut row = j.row_mut(3 * i + c);
            row /= *s;
        }
    }
    let jtj = j.transpose() * &j;
    match jtj.clone().try_inverse() {
        Some(cov) if cov.iter().all(|v| v.is_finite()) => (0..p)
            .map(|k| (cov[(k, k)] > 0.0).then(|| cov[(k, k)].sqrt()))
            .collect(),
        _ => vec![None; p],
    }
}

/// The temperature and δ of `medium` on `heights` at `at`, interpolated
/// linearly from its profile rows.
fn profile_on(
    medium: &Medium,
    at: [f64; 2],
    top: f64,
    heights: &[f64],
) -> (Vec<f64>, Vec<f64>, bool) {
    let prof = air_profile(medium, Some(at), Some(top));
    let rows = &prof.rows;
    let at_h = |h: f64, f: &dyn Fn(usize) -> f64| -> f64 {
        let j = rows.partition_point(|r| r.h < h);
        if j == 0 {
            return f(0);
        }
        if j >= rows.len() {
            return f(rows.len() - 1);
        }
        let (a, b) = (&rows[j - 1], &rows[j]);
        let w = if b.h > a.h {
            (h - a.h) / (b.h - a.h)
        } else {
            0.0
        };
        f(j - 1) + w * (f(j) - f(j - 1))
    };
    let t = heights
        .iter()
        .map(|&h| at_h(h, &|i| rows[i].temperature_c))
        .collect();
    let d = heights
        .iter()
        .map(|&h| at_h(h, &|i| rows[i].delta))
        .collect();
    (t, d, prof.implied)
}

/// A member's temperature and δ per height.
type Column = (Vec<f64>, Vec<f64>);

fn profiles_of(
    fitted: &Problem,
    best: &Medium,
    members: &[Member],
    x_best: &[f64],
    truth: Option<&Medium>,
) -> Profiles {
    let at = default_at(best);
    let top = default_top(best);
    // The best fit's own rows: uniform to the top, dense about its features.
    let heights: Vec<f64> = air_profile(best, Some(at), Some(top))
        .rows
        .iter()
        .map(|r| r.h)
        .collect();
    let objective = Objective::from_problem(fitted);
    let (t_best, d_best, implied) = profile_on(best, at, top, &heights);
    let each: Vec<Column> = members
        .par_iter()
        .map(|mm| {
            let medium = if mm.params.len() == x_best.len() {
                objective.medium(&mm.params)
            } else {
                best.clone()
            };
            let (t, d, _) = profile_on(&medium, at, top, &heights);
            (t, d)
        })
        .collect();
    let band = |pick: &dyn Fn(&Column) -> &Vec<f64>| -> [Vec<f64>; 5] {
        let mut out: [Vec<f64>; 5] = Default::default();
        for r in 0..heights.len() {
            let mut col: Vec<f64> = each.iter().map(|e| pick(e)[r]).collect();
            let q = percentiles_of(&mut col);
            for (o, v) in out.iter_mut().zip(q) {
                o.push(v);
            }
        }
        out
    };
    let truth = truth.map(|m| profile_on(m, at, top, &heights));
    Profiles {
        at,
        implied,
        heights: heights.clone(),
        temperature: Envelope {
            best: t_best,
            percentiles: band(&|e| &e.0),
            truth: truth.as_ref().map(|t| t.0.clone()),
        },
        delta: Envelope {
            best: d_best,
            percentiles: band(&|e| &e.1),
            truth: truth.map(|t| t.1),
        },
    }
}

/// Checks, before any work, that `problem` has something to resample: free
/// parameters, and more residual components (two per pair) than them.
/// Errors name the field (`free`, `pairs`) in the problem's file.
pub fn check_problem(problem: &Problem) -> Result<()> {
    if problem.photo.is_some() {
        return Err(crate::error::Error::input(
            &problem.source,
            "photo",
            "an ensemble of a photo problem (marks resampled in pixels) is not built yet",
        ));
    }
    if problem.free.is_empty() {
        return Err(crate::error::Error::input(
            &problem.source,
            "free",
            "empty: an ensemble refits the free parameters, and this problem has none",
        ));
    }
    if 2 * problem.pairs.len() <= problem.free.len() {
        return Err(crate::error::Error::input(
            &problem.source,
            "pairs",
            format!(
                "{} pair(s) give {} residual components, not more than the {} free parameters: nothing to resample",
                problem.pairs.len(),
                2 * problem.pairs.len(),
                problem.free.len()
            ),
        ));
    }
    Ok(())
}

/// Checks an ensemble's settings before any work: at least one member.
pub fn check_members(n: usize) -> std::result::Result<usize, crate::error::ValueError> {
    if n == 0 {
        return Err(crate::error::ValueError::OutOfRange {
            rule: "must be at least 1 member, got 0".into(),
        });
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_interpolate_like_numpy() {
        // numpy.percentile([1, 2, 3, 4], [2.5, 16, 50, 84, 97.5])
        let v = [1.0, 2.0, 3.0, 4.0];
        let q = PERCENTILES.map(|p| percentile(&v, p));
        let want = [1.075, 1.48, 2.5, 3.52, 3.925];
        for (a, b) in q.iter().zip(want) {
            assert!((a - b).abs() < 1e-12, "{q:?}");
        }
        assert_eq!(percentile(&[7.0], 84.0), 7.0);
    }

    #[test]
    fn the_plane_basis_is_orthonormal_and_in_the_plane() {
        for n in [
            V3::new(0.0, 0.0, 1.0),
            V3::new(0.6, 0.0, 0.8),
            V3::new(0.1, 0.2, -0.9).normalized(),
            V3::new(0.0, 1.0, 0.0),
        ] {
            let (u, v) = plane_basis(n);
            for (a, b) in [(u, n), (v, n), (u, v)] {
                assert!(a.dot(b).abs() < 1e-12);
            }
            assert!((u.norm() - 1.0).abs() < 1e-12 && (v.norm() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn gaussian_draws_have_unit_variance() {
        let mut rng = SplitMix64(7);
        let n = 200_000;
        let xs: Vec<f64> = (0..n).map(|_| gaussian(&mut rng)).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(
            mean.abs() < 0.01 && (var - 1.0).abs() < 0.01,
            "{mean} {var}"
        );
    }
}
