//! `mirage trace`: every point pair traced through the problem's own medium.

use crate::error::Result;
use crate::evaluate::{TraceReport, trace_pairs};
use crate::io::{Output, OutputKind, check_outputs, write_json};
use crate::problem::Problem;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Trace every point pair through the problem's medium and report endpoints.
#[derive(Clone, Debug, Default, PartialEq, clap::Args)]
pub struct TracePairsOptions {
    /// Problem file (JSON).
    pub problem: PathBuf,
    /// Write the JSON report here.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

/// Traces every pair with the problem's medium and settings, prints a table,
/// and writes the JSON report to `output` if given.
pub fn run(o: &TracePairsOptions) -> Result<TraceReport> {
    let problem = Problem::load(&o.problem)?;
    check_outputs(
        Output::optional("-o", o.output.as_ref(), OutputKind::Any),
        &[o.problem.as_path()],
    )?;
    let report = trace_pairs(&problem, &problem.medium);
    if let Some(out) = &o.output {
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

/// The problem's integrator in words (`rk4 step 2 m`), for the headers of the
/// trace table and the fit summary.
pub(crate) fn describe_trace(problem: &Problem) -> String {
    let t = &problem.trace_spec;
    match (t.step, t.tolerance) {
        (Some(h), _) => format!("{} step {h} m", t.method),
        (_, Some(tol)) => format!("{} tolerance {tol:e}", t.method),
        _ => t.method.clone(),
    }
}
