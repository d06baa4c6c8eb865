//! `mirage fit`: the free parameters fitted so that every pair's ray lands on
//! its target.
//!
//! Exit codes: 0 when the fit ran (and, if the problem's `solver` section or
//! `--target-objective` sets a target objective, F ended at or below it); 1
//! when F ended above a target so set (the outputs are written all the same,
//! as `mirage compare` writes its evidence before failing), or the solver or
//! an output failed; 2 for bad input (the problem, a flag, an output path,
//! all checked before the fit starts). A fit with no target set steers by
//! the default target (1e-12 m²) but does not fail on it: a problem whose
//! targets cannot all be met would otherwise never exit 0.

use super::trace::describe_trace;
use crate::error::{Error, Result, ValueError};
use crate::fit::report::FitReport;
use crate::io::{Output, OutputKind, check_outputs, write_json};
use crate::problem::Problem;
use crate::problem::SolverMethod;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Fit the free parameters so that every pair's ray lands on its target.
#[derive(Clone, Debug, Default, PartialEq, clap::Args)]
pub struct FitOptions {
    /// Problem file (JSON).
    pub problem: PathBuf,
    /// Write the JSON result here.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Convergence plot (.png or .svg).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Ray diagram of the fitted medium (.png or .svg).
    #[arg(long)]
    pub rays: Option<PathBuf>,
    /// A photo problem's marks drawn on its photo where the fitted air and
    /// camera put them (.png).
    #[arg(long)]
    pub overlay: Option<PathBuf>,
    /// Solver (overrides the problem file).
    #[arg(long, value_enum)]
    pub method: Option<SolverMethod>,
    /// Target objective F in m², finite ≥ 0 (overrides the problem file's
    /// `solver.target_objective`): the fit exits with code 1 if it ends above it.
    #[arg(long, allow_negative_numbers = true, value_parser = target_objective)]
    pub target_objective: Option<f64>,
    /// Grow the model: from the problem's medium (a background alone, say),
    /// add the terms the pairs call for (an inversion, hot spots), one at a
    /// time, while they lower the information criterion (BIC).
    #[arg(long)]
    pub grow: bool,
    /// Endpoint noise σ in metres, finite > 0, that growing assumes (per
    /// residual component; overrides `solver.noise`); without it σ is
    /// estimated from the residuals. Only with --grow.
    #[arg(long, allow_negative_numbers = true, value_parser = noise)]
    pub noise: Option<f64>,
    /// Most terms growing may add, ≥ 1 (overrides `solver.max_terms`;
    /// default 4). Only with --grow.
    #[arg(long, value_parser = max_terms)]
    pub max_terms: Option<usize>,
    /// No progress line.
    #[arg(long, short)]
    pub quiet: bool,
}

/// `--noise`: a finite σ > 0 (m).
fn noise(s: &str) -> std::result::Result<f64, ValueError> {
    let v: f64 = s.trim().parse().map_err(|_| ValueError::NotANumber {
        value: s.to_string(),
    })?;
    crate::problem::check_noise(v)
}

/// `--max-terms`: at least 1.
fn max_terms(s: &str) -> std::result::Result<usize, ValueError> {
    let v: usize = s.trim().parse().map_err(|_| ValueError::NotAWholeNumber {
        value: s.to_string(),
    })?;
    crate::problem::check_max_terms(v)
}

/// Applies the flags to the problem's solver settings, in one step, and checks
/// the combination: `--noise` and `--max-terms` only with growth (`--grow` or
/// `solver.grow`), growth not with Nelder–Mead.
pub(crate) fn apply_flags(options: &FitOptions, problem: &mut Problem) -> Result<()> {
    let unsupported = crate::fit::grow::unsupported(&problem.medium);
    let solver = &mut problem.solver;
    if let Some(m) = options.method {
        solver.method = m;
    }
    if let Some(t) = options.target_objective {
        solver.target_objective = t;
        solver.target_enforced = true;
    }
    let grows = options.grow || solver.grow.is_some();
    if grows && problem.photo.is_some() {
        return Err(Error::usage(
            "--grow",
            "growing a model from a photo's marks is not built yet: fit the terms the problem names",
        ));
    }
    for (flag, set) in [
        ("--noise", options.noise.is_some()),
        ("--max-terms", options.max_terms.is_some()),
    ] {
        if set && !grows {
            return Err(Error::usage(
                flag,
                "applies only when the model is grown: add --grow (or `\"grow\": true` to the problem's `solver`)",
            ));
        }
    }
    if !grows {
        return Ok(());
    }
    if solver.method == SolverMethod::NelderMead {
        let flag = if options.method.is_some() {
            "--method"
        } else {
            "--grow"
        };
        return Err(Error::usage(
            flag,
            "growing fits every candidate with Levenberg–Marquardt: use --method lm or auto, not nelder-mead",
        ));
    }
    if let Some(why) = unsupported {
        return Err(Error::usage("--grow", why));
    }
    let file = solver.grow.unwrap_or(crate::problem::GrowSettings {
        noise: None,
        max_terms: crate::problem::DEFAULT_MAX_TERMS,
    });
    solver.grow = Some(crate::problem::GrowSettings {
        noise: options.noise.or(file.noise),
        max_terms: options.max_terms.unwrap_or(file.max_terms),
    });
    Ok(())
}

/// `--target-objective`: a finite F ≥ 0 (m²).
fn target_objective(s: &str) -> std::result::Result<f64, ValueError> {
    let v: f64 = s.trim().parse().map_err(|_| ValueError::NotANumber {
        value: s.to_string(),
    })?;
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(ValueError::OutOfRange {
            rule: format!("must be a finite number ≥ 0 (m²), got {v}"),
        })
    }
}

/// Fits the free parameters, prints a summary, writes the result and plots.
/// All outputs are checked before the fit and written atomically. A fit that
/// ends above a target objective the problem or `--target-objective` sets is
/// [`Error::LimitsMissed`] (exit code 1), after the outputs are written.
pub fn run(options: &FitOptions) -> Result<FitReport> {
    let problem_path = options.problem.as_path();
    let mut problem = Problem::load(problem_path)?;
    apply_flags(options, &mut problem)?;
    if options.overlay.is_some() && problem.photo.is_none() {
        return Err(Error::usage(
            "--overlay",
            "draws a photo problem's marks on its photo; this problem has no `photo` section",
        ));
    }
    check_outputs(
        [
            Output::optional("-o", options.output.as_ref(), OutputKind::Any),
            Output::optional("--plot", options.plot.as_ref(), OutputKind::Plot),
            Output::optional("--rays", options.rays.as_ref(), OutputKind::Plot),
            Output::optional(
                "--overlay",
                options.overlay.as_ref(),
                OutputKind::Png("an overlay"),
            ),
        ]
        .into_iter()
        .flatten(),
        &[problem_path],
    )?;
    let bar = (!options.quiet).then(|| {
        let bar = indicatif::ProgressBar::new_spinner();
        bar.set_style(
            indicatif::ProgressStyle::with_template("{spinner} {elapsed:>4} {msg}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
        );
        bar.enable_steady_tick(std::time::Duration::from_millis(120));
        bar
    });
    let hook: Option<crate::fit::solve::IterateHook> = bar.clone().map(|bar| {
        std::sync::Arc::new(move |label: &str, rec: &crate::fit::IterationRecord| {
            bar.set_message(format!(
                "{label}: iteration {} F = {:.3e} m²",
                rec.iteration, rec.objective
            ));
        }) as crate::fit::solve::IterateHook
    });
    let report = crate::fit::fit(&problem, hook);
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let report = report?;
    // The last cancellation point: once writing starts, it finishes.
    crate::interrupt::check()?;
    if let Some(out) = &options.output {
        write_json(out, &report)?;
    }
    if let Some(plot) = &options.plot {
        match &report.grow {
            Some(g) => crate::plot::draw_grow(&report.history, g, plot)?,
            None => crate::plot::draw_convergence(&report.history, plot)?,
        }
    }
    if let Some(rays) = &options.rays {
        crate::plot::draw_rays(&problem, &report.medium, rays)?;
    }
    if let (Some(path), Some(photo)) = (&options.overlay, &report.photo) {
        let title = super::overlay::overlay_title(&problem, true);
        super::overlay::write_overlay(&problem, photo, &title, path)?;
    }
    print!("{}", fit_summary(&problem, &report));
    let sv = &report.solver;
    if sv.target_enforced && !sv.reached_target {
        return Err(Error::LimitsMissed {
            subject: options.problem.display().to_string(),
            missed: vec![format!(
                "F = {:.6e} m² is above the target objective {:e} m² ({})",
                report.totals.objective,
                sv.target_objective,
                if options.target_objective.is_some() {
                    "--target-objective"
                } else {
                    "solver.target_objective"
                }
            )],
        });
    }
    Ok(report)
}

/// The terminal summary of a fit.
pub fn fit_summary(problem: &Problem, r: &FitReport) -> String {
    let mut s = String::new();
    let sv = &r.solver;
    let _ = writeln!(
        s,
        "{}: {} free parameter(s), {} pair(s), trace {}",
        r.problem,
        r.parameters.len(),
        r.pairs.len(),
        describe_trace(problem)
    );
    let _ = writeln!(
        s,
        "solver {} ({} run(s), best: {}): {} iterations, {} residual + {} Jacobian evaluations, {:.3} s",
        sv.method.name(),
        r.runs.len(),
        sv.best_run,
        sv.iterations,
        sv.residual_evaluations,
        sv.jacobian_evaluations,
        sv.wall_time_s
    );
    if let Some(g) = &sv.surrogate {
        let _ = writeln!(
            s,
            "  converged first under the surrogate tracer {} ({:.1}× cheaper at the start): {} of those iterations, with {} residual + {} Jacobian evaluations of its own",
            g.tracer,
            g.problem_rhs_at_start as f64 / g.surrogate_rhs_at_start.max(1) as f64,
            g.iterations,
            g.residual_evaluations,
            g.jacobian_evaluations
        );
    }
    let _ = writeln!(s, "stopped: {}", sv.stop_reason);
    // A photo problem's F is in px², where the default target (made for
    // metres²) says nothing: it is named only when the file sets one.
    let target = match (sv.reached_target, sv.target_enforced) {
        (true, _) => format!(" (meets target {:.1e})", sv.target_objective),
        (false, true) => format!(" (ABOVE target {:.1e})", sv.target_objective),
        (false, false) if problem.photo.is_some() => String::new(),
        (false, false) => format!(" (above the default target {:.1e})", sv.target_objective),
    };
    let largest = if problem.photo.is_some() {
        "largest miss at a target"
    } else {
        "largest"
    };
    let _ = writeln!(
        s,
        "objective F = {:.6e} {}{target}   summed distance = {:.4e} {}   {largest} = {:.4e} m",
        r.totals.objective,
        super::sightline::objective_unit(problem),
        r.totals.summed_distance,
        super::sightline::summed_unit(problem),
        r.totals.max_distance
    );
    if !r.parameters.is_empty() {
        // Real air's paths run to 40 characters: the column fits the longest.
        let w = r
            .parameters
            .iter()
            .map(|p| p.name.chars().count())
            .max()
            .unwrap_or(0)
            .max(24);
        let _ = writeln!(
            s,
            "{:<w$} {:>14} {:>16} {:>12}",
            "parameter", "start", "fitted", "std. error"
        );
        for p in &r.parameters {
            let se = match p.standard_error {
                Some(e) => format!("{e:.3e}"),
                None => "undetermined".into(),
            };
            let _ = writeln!(
                s,
                "{:<w$} {:>14.6} {:>16.9} {:>12}{}",
                p.name,
                p.start,
                p.value,
                se,
                if p.at_bound { "  (at bound)" } else { "" }
            );
        }
    }
    for u in &r.undetermined {
        let combo: Vec<String> = u
            .combination
            .iter()
            .map(|(n, w)| format!("{w:+.3}·{n}"))
            .collect();
        let _ = writeln!(s, "undetermined: {}\n  {}", combo.join(" "), u.note);
    }
    let flagged: Vec<String> = r
        .pairs
        .iter()
        .enumerate()
        .filter(|(_, p)| p.occluded || p.unreachable)
        .map(|(i, p)| {
            format!(
                "pair {i}{}{}",
                if p.occluded { " occluded" } else { "" },
                if p.unreachable { " unreachable" } else { "" }
            )
        })
        .collect();
    if !flagged.is_empty() {
        let _ = writeln!(s, "flags: {}", flagged.join(", "));
    }
    if let Some(photo) = &r.photo {
        s.push_str(&super::overlay::photo_summary(photo));
    } else {
        s.push_str(&super::sightline::sightline_table(&r.pairs));
    }
    if let Some(g) = &r.grow {
        s.push_str(&grow_summary(g));
    }
    s
}

/// The sequence of a grown model: one line per step.
pub fn grow_summary(g: &crate::fit::grow::GrowReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "grown ({}; m = {} residual components; {} fits, {:.3} s):",
        g.criterion, g.residual_components, g.fits, g.wall_time_s
    );
    for st in &g.steps {
        let chi2 = st
            .chi2
            .map(|c| format!("  χ² = {c:.1}"))
            .unwrap_or_default();
        let _ = writeln!(
            s,
            "  step {:>2}  {:<34} F = {:.4e} m²{}  criterion = {:.2}  [{}; {} free]",
            st.step,
            st.action,
            st.objective,
            chi2,
            st.criterion,
            st.terms.join(", "),
            st.free.len()
        );
        for c in &st.candidates {
            let _ = writeln!(
                s,
                "           tried {:<13} best of {} seeds: F = {:.4e} m², criterion = {:.2}",
                c.term, c.seeds, c.objective, c.criterion
            );
        }
    }
    let _ = writeln!(s, "stopped growing: {}", g.stop_reason);
    for h in &g.held {
        let _ = writeln!(s, "held {} = {}: {}", h.name, h.value, h.reason);
    }
    s
}
