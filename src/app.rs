//! The commands behind the `mirage` binary, as library functions (the binary only
//! parses its arguments and calls these).

use crate::error::Result;
use crate::evaluate::{TraceReport, trace_pairs};
use crate::io::{check_not_input, write_json};
use crate::problem::Problem;
use std::fmt::Write as _;
use std::path::Path;

/// `mirage trace`: traces every pair with the problem's medium and settings,
/// prints a table, and writes the JSON report to `output` if given.
pub fn trace(problem_path: &Path, output: Option<&Path>) -> Result<TraceReport> {
    let problem = Problem::load(problem_path)?;
    if let Some(out) = output {
        check_not_input(out, &[problem_path])?;
    }
    let report = trace_pairs(&problem, &problem.medium);
    if let Some(out) = output {
        write_json(out, &report)?;
    }
    print!("{}", trace_table(&problem, &report));
    Ok(report)
}

/// The terminal table of a trace report.
pub fn trace_table(problem: &Problem, report: &TraceReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{}: {} pair(s), trace {}",
        problem.name,
        problem.pairs.len(),
        describe_trace(problem)
    );
    let _ = writeln!(
        s,
        "{:>4}  {:>30}  {:>12}  {:>9}  {:>7}  flags",
        "pair", "endpoint (m)", "distance (m)", "length", "rhs"
    );
    for (i, p) in report.pairs.iter().enumerate() {
        let mut flags = Vec::new();
        if p.occluded {
            flags.push("occluded");
        }
        if p.unreachable {
            flags.push("unreachable");
        }
        let _ = writeln!(
            s,
            "{:>4}  {:>9.3} {:>9.4} {:>10.3}  {:>12.4e}  {:>9.2}  {:>7}  {}",
            i,
            p.endpoint[0],
            p.endpoint[1],
            p.endpoint[2],
            p.distance,
            p.arc_length,
            p.stats.rhs_evaluations,
            flags.join(",")
        );
    }
    let _ = writeln!(
        s,
        "objective F = {:.6e} m²   summed distance = {:.6e} m   largest distance = {:.6e} m",
        report.totals.objective, report.totals.summed_distance, report.totals.max_distance
    );
    s
}

fn describe_trace(problem: &Problem) -> String {
    let t = &problem.trace_spec;
    match (t.step, t.tolerance) {
        (Some(h), _) => format!("{} step {h} m", t.method),
        (_, Some(tol)) => format!("{} tolerance {tol:e}", t.method),
        _ => t.method.clone(),
    }
}

/// Options of `mirage fit` beyond the problem file.
#[derive(Clone, Debug, Default)]
pub struct FitOptions {
    /// Write the JSON result here.
    pub output: Option<std::path::PathBuf>,
    /// Draw the convergence plot here (`.png` or `.svg`).
    pub plot: Option<std::path::PathBuf>,
    /// Draw the ray diagram of the fitted medium here.
    pub rays: Option<std::path::PathBuf>,
    /// Override the problem's solver method (`lm`, `nelder-mead`, `auto`).
    pub method: Option<String>,
    /// Show a progress line on stderr (only drawn on a terminal).
    pub progress: bool,
}

/// `mirage fit`: fits the free parameters, prints a summary, writes the result
/// and plots. All outputs are checked before the fit and written atomically.
pub fn fit(problem_path: &Path, options: &FitOptions) -> Result<crate::fit::report::FitReport> {
    let mut problem = Problem::load(problem_path)?;
    if let Some(m) = &options.method {
        let spec = crate::problem::SolverSpec {
            method: m.clone(),
            ..Default::default()
        };
        problem.solver.method = crate::problem::solver_settings(&spec, Path::new("<command line>"))
            .map_err(|e| match e {
                crate::error::Error::Input { error, .. } => {
                    crate::error::Error::usage("--method", error.message)
                }
                other => other,
            })?
            .method;
    }
    for out in [&options.output, &options.plot, &options.rays]
        .into_iter()
        .flatten()
    {
        check_not_input(out, &[problem_path])?;
    }
    for plot in [&options.plot, &options.rays].into_iter().flatten() {
        crate::plot::ImageFormat::from_path(plot)?;
    }
    let bar = options.progress.then(|| {
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
    if let Some(out) = &options.output {
        write_json(out, &report)?;
    }
    if let Some(plot) = &options.plot {
        crate::plot::draw_convergence(&report.history, plot)?;
    }
    if let Some(rays) = &options.rays {
        crate::plot::draw_rays(&problem, &report.medium, rays)?;
    }
    print!("{}", fit_summary(&problem, &report));
    Ok(report)
}

/// The terminal summary of a fit.
pub fn fit_summary(problem: &Problem, r: &crate::fit::report::FitReport) -> String {
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
    let _ = writeln!(s, "stopped: {}", sv.stop_reason);
    let _ = writeln!(
        s,
        "objective F = {:.6e} m² ({} target {:.1e})   summed distance = {:.4e} m   largest = {:.4e} m",
        r.totals.objective,
        if sv.reached_target { "meets" } else { "ABOVE" },
        sv.target_objective,
        r.totals.summed_distance,
        r.totals.max_distance
    );
    if !r.parameters.is_empty() {
        let _ = writeln!(
            s,
            "{:<24} {:>14} {:>16} {:>12}",
            "parameter", "start", "fitted", "std. error"
        );
        for p in &r.parameters {
            let se = match p.standard_error {
                Some(e) => format!("{e:.3e}"),
                None => "undetermined".into(),
            };
            let _ = writeln!(
                s,
                "{:<24} {:>14.6} {:>16.9} {:>12}{}",
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
    s
}

/// `mirage rays`: the ray diagram of a problem's pairs through its medium.
pub fn rays(problem_path: &Path, output: &Path) -> Result<()> {
    let problem = Problem::load(problem_path)?;
    check_not_input(output, &[problem_path])?;
    crate::plot::draw_rays(&problem, &problem.medium, output)
}

/// `mirage tradeoff`: measures endpoint error, trace cost and fit quality for a
/// range of RK4 steps and Dormand–Prince tolerances; prints a table and writes
/// JSON, CSV and a Pareto plot where asked.
pub fn tradeoff(
    problem_path: &Path,
    output: Option<&Path>,
    csv: Option<&Path>,
    plot: Option<&Path>,
    fit: bool,
) -> Result<crate::tradeoff::Tradeoff> {
    let problem = Problem::load(problem_path)?;
    for out in [output, csv, plot].into_iter().flatten() {
        check_not_input(out, &[problem_path])?;
    }
    if let Some(p) = plot {
        crate::plot::ImageFormat::from_path(p)?;
    }
    if fit {
        crate::tradeoff::check_fit(&problem)?;
    }
    let t = crate::tradeoff::measure(&problem, fit)?;
    if let Some(out) = output {
        write_json(out, &t)?;
    }
    if let Some(c) = csv {
        crate::io::write_atomic(c, t.to_csv().as_bytes())?;
    }
    if let Some(p) = plot {
        crate::plot::draw_tradeoff(&t, p)?;
    }
    print!("{}", t.to_table());
    Ok(t)
}
