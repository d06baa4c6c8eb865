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
    /// Write the JSON report here. With a report, a problem of more than
    /// 40 pairs gets a short table (the first pairs and those farthest from
    /// their targets); without one, the table lists every pair.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

/// Above this many pairs, and with a report file to hold them all, the
/// terminal table is shortened (see [`trace_table`]).
pub const SHORT_TABLE_ABOVE: usize = 40;
/// How many of the first pairs, and of the farthest, a short table shows.
pub const SHORT_TABLE_ROWS: usize = 10;

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
    let short = o.output.is_some() && report.pairs.len() > SHORT_TABLE_ABOVE;
    print!("{}", trace_table(&problem, &report, !short));
    Ok(report)
}

/// The terminal table of a trace report: every pair when `full`, else the
/// first [`SHORT_TABLE_ROWS`] pairs, the as many farthest from their targets,
/// and how many pairs were left out and how many are flagged (a table of
/// thousands of lines says less than that, and formatting it costs as much
/// as tracing a fan of rays).
pub fn trace_table(problem: &Problem, report: &TraceReport, full: bool) -> String {
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
    let row = |s: &mut String, i: usize| {
        let p = &report.pairs[i];
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
    };
    let n = report.pairs.len();
    if full || n <= 2 * SHORT_TABLE_ROWS {
        for i in 0..n {
            row(&mut s, i);
        }
    } else {
        for i in 0..SHORT_TABLE_ROWS {
            row(&mut s, i);
        }
        // The farthest of the rest (ties by index), shown in index order.
        let mut rest: Vec<usize> = (SHORT_TABLE_ROWS..n).collect();
        rest.sort_by(|&a, &b| {
            report.pairs[b]
                .distance
                .total_cmp(&report.pairs[a].distance)
                .then(a.cmp(&b))
        });
        rest.truncate(SHORT_TABLE_ROWS);
        rest.sort_unstable();
        let occluded = report.pairs.iter().filter(|p| p.occluded).count();
        let unreachable = report.pairs.iter().filter(|p| p.unreachable).count();
        let _ = writeln!(
            s,
            "   … {} more pair(s) in the report ({occluded} occluded, {unreachable} unreachable in all); the {} farthest from their targets:",
            n - SHORT_TABLE_ROWS,
            rest.len()
        );
        for i in rest {
            row(&mut s, i);
        }
    }
    s.push_str(&super::sightline::sightline_table(&report.pairs));
    let _ = writeln!(
        s,
        "objective F = {:.6e} {}   summed distance = {:.6e} {}   largest distance = {:.6e} m",
        report.totals.objective,
        super::sightline::objective_unit(problem),
        report.totals.summed_distance,
        super::sightline::summed_unit(problem),
        report.totals.max_distance
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
