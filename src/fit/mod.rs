//! Fitting the free parameters to the point pairs: the residual map with exact
//! Jacobians ([`objective`]), Levenberg–Marquardt and Nelder–Mead as argmin
//! solvers ([`lm`], [`nelder_mead`]), the strategies that run them
//! ([`solve`]), a cheaper tracer to converge under first ([`surrogate`]), and
//! what the pairs cannot determine ([`identify`]).

pub mod ensemble;
pub mod grow;
pub mod history;
pub mod identify;
pub mod lm;
pub mod nelder_mead;
pub mod objective;
pub mod photo;
pub mod report;
pub mod solve;
pub mod surrogate;
pub mod synthetic;

pub use history::{History, IterationRecord, RunHistory};

use crate::error::Result;
use crate::evaluate::trace_pairs;
use crate::problem::Problem;
use objective::Objective;
use report::{FitReport, ParamReport, RunReport, SolverReport, SurrogateReport};
use solve::IterateHook;
use std::time::Instant;

/// Fits `problem`'s free parameters and reports everything `docs/problem-format.md`
/// asks of a result. `hook` sees every iterate (progress display, tests).
///
/// With `solver.grow` set the model is grown first ([`grow`]), and the result
/// is the fit of the grown model from its kept seed
/// ([`grow::grown_problem`]), with the account of the growth in its `grow`
/// section.
pub fn fit(problem: &Problem, hook: Option<IterateHook>) -> Result<FitReport> {
    let Some(settings) = problem.solver.grow else {
        return fit_as_is(problem, hook);
    };
    let grown = grow::grow(problem, &settings)?;
    let mut report = fit_as_is(&grow::grown_problem(problem, &grown), hook)?;
    report.grow = Some(grown.report);
    Ok(report)
}

/// Fits the problem's medium as it is (no growth).
fn fit_as_is(problem: &Problem, hook: Option<IterateHook>) -> Result<FitReport> {
    let started = Instant::now();
    let objective = Objective::from_problem(problem);
    let settings = &problem.solver;
    let surrogate = surrogate::choose(&objective, settings, objective.start().as_slice());
    let bounds = problem.all_bounds();
    let solution = solve::solve_with_surrogate(
        &objective,
        surrogate.as_ref(),
        settings,
        &bounds,
        settings.target_objective,
        hook,
    )?;
    crate::interrupt::check()?;
    let medium = objective.medium(&solution.x);
    let (_, jac) = objective.jacobian(&solution.x);
    let names = objective.names();
    let ident = identify::analyse_named(
        &jac,
        &solution.x,
        &names,
        &objective.amplitudes(),
        solution.objective,
        // A photo's marks' noise (pixels, the residuals' unit).
        problem.photo.as_ref().and_then(|p| p.noise).map(|s| s * s),
    );
    // The pairs as the fitted camera launches them (a photo problem's).
    let at_fit;
    let traced_problem = if problem.photo.is_some() {
        let mut p = problem.clone();
        p.pairs = objective.pairs_at(&solution.x);
        at_fit = p;
        &at_fit
    } else {
        problem
    };
    let mut traced = trace_pairs(traced_problem, &medium);
    let photo = problem
        .photo
        .as_ref()
        .and_then(|s| photo::photo_report(&objective, &solution.x, &s.image.display().to_string()));
    if let Some(p) = &photo {
        // The horizon marks' rows count in F too.
        traced.totals.objective += p
            .marks
            .iter()
            .filter(|m| m.horizon)
            .map(|m| 0.5 * m.residual * m.residual)
            .sum::<f64>();
    }
    let wall_time_s = started.elapsed().as_secs_f64();
    let (residuals, jacobians, rhs) = objective.counts();

    let x0 = objective.start();
    let parameters = names
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let (lo, hi) = bounds[k];
            let bounded = lo.is_finite() || hi.is_finite();
            let v = solution.x[k];
            ParamReport {
                name: name.clone(),
                start: x0[k],
                value: v,
                standard_error: ident.params[k].standard_error,
                determined: ident.params[k].determined,
                bounds: bounded.then_some([lo, hi]),
                at_bound: v == lo || v == hi,
            }
        })
        .collect();
    let best = &solution.runs[solution.best_run];
    let implied_air = crate::profile::implied_air_summary(&medium);
    let report = FitReport {
        problem: problem.name.clone(),
        earth: problem.trace.earth.spec(),
        medium,
        parameters,
        undetermined: ident.undetermined,
        standard_errors_scaled: ident.scaled_by_residual_variance,
        totals: traced.totals,
        pairs: traced.pairs,
        solver: SolverReport {
            method: settings.method,
            best_run: best.label.clone(),
            iterations: solution.runs.iter().map(|r| r.iterations).sum(),
            residual_evaluations: residuals,
            jacobian_evaluations: jacobians,
            rhs_evaluations: rhs,
            surrogate: surrogate.as_ref().map(|s| {
                let (residual_evaluations, jacobian_evaluations, rhs_evaluations) =
                    s.objective.counts();
                SurrogateReport {
                    tracer: s.describe(),
                    problem_rhs_at_start: s.problem_rhs,
                    surrogate_rhs_at_start: s.surrogate_rhs,
                    iterations: solution
                        .runs
                        .iter()
                        .filter(|r| r.surrogate)
                        .map(|r| r.iterations)
                        .sum(),
                    residual_evaluations,
                    jacobian_evaluations,
                    rhs_evaluations,
                }
            }),
            wall_time_s,
            stop_reason: best.reason.clone(),
            converged: best.converged,
            reached_target: traced.totals.objective <= settings.target_objective,
            target_objective: settings.target_objective,
            target_enforced: settings.target_enforced,
        },
        runs: solution
            .runs
            .iter()
            .map(|r| RunReport {
                label: r.label.clone(),
                start: r.start.clone(),
                end: r.end.clone(),
                objective: r.objective,
                iterations: r.iterations,
                stop_reason: r.reason.clone(),
                converged: r.converged,
                surrogate: r.surrogate,
            })
            .collect(),
        history: History {
            param_names: names.clone(),
            runs: solution.runs.into_iter().map(|r| r.history).collect(),
        },
        trace: problem.trace_spec.clone(),
        implied_air,
        grow: None,
        photo,
    };
    Ok(report)
}
