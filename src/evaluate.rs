//! A problem's pairs evaluated at one medium: each pair's endpoint, distance,
//! residual and flags, and the totals F, summed and largest distance. This is
//! what `mirage trace` writes and what a fit result reports at its end point.

use crate::medium::{IndexField, Medium, PairFields};
use crate::problem::{Problem, TraceSpec};
use crate::sightline::Sightline;
use crate::trace::batch::{BatchOptions, RayJob, trace_batch_into};
use crate::trace::{End, RayState, Stats, Trace};
use serde::Serialize;

/// One pair's traced outcome.
#[derive(Clone, Debug, Serialize)]
pub struct PairReport {
    /// Where the ray ended (on the target plane unless `unreachable`).
    pub endpoint: [f64; 3],
    /// The target.
    pub target: [f64; 3],
    /// |endpoint − target| (metres).
    pub distance: f64,
    /// w·(endpoint − target).
    pub residual: [f64; 3],
    /// The unit direction of the ray where it ended (on its target plane
    /// unless `unreachable`).
    pub direction: [f64; 3],
    /// The ray dipped below the ground before its target plane.
    pub occluded: bool,
    /// The ray never reached its target plane.
    pub unreachable: bool,
    /// Why the trace ended.
    pub end: End,
    /// Arc length travelled (metres).
    pub arc_length: f64,
    /// Integration statistics.
    pub stats: Stats,
    /// Over the round earth: the line of sight's elevations, refraction,
    /// k, horizon and clearance ([`Sightline`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sightline: Option<Sightline>,
}

/// Totals over all pairs.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Totals {
    /// F = ½ Σ |r_i|² (m²).
    pub objective: f64,
    /// Σ w_i d_i (m).
    pub summed_distance: f64,
    /// max d_i (m).
    pub max_distance: f64,
}

/// The result of `mirage trace`.
#[derive(Clone, Debug, Serialize)]
pub struct TraceReport {
    /// Problem name.
    pub problem: String,
    /// The medium traced.
    pub medium: Medium,
    /// Trace settings used.
    pub trace: TraceSpec,
    /// The round earth the pairs were traced over (absent: the flat ground).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub earth: Option<crate::trace::EarthSpec>,
    /// Totals.
    #[serde(flatten)]
    pub totals: Totals,
    /// Per pair.
    pub pairs: Vec<PairReport>,
    /// Integration statistics summed over pairs.
    pub stats: Stats,
}

/// Traces every pair of `problem` through `medium` and reports endpoints,
/// distances, flags and totals. A pair with its own `wavelength` is traced
/// through `medium` at that wavelength (one compiled field per distinct
/// wavelength, [`PairFields`]). Pairs go through the batch entry
/// ([`trace_batch_into`]: the SIMD lanes for the logistic kind and real air)
/// in fixed chunks traced in parallel; the result does not depend on the
/// number of threads.
pub fn trace_pairs(problem: &Problem, medium: &Medium) -> TraceReport {
    let fields = pair_fields(problem, medium);
    let traces = trace_all(problem, &fields);
    let pairs: Vec<PairReport> = problem
        .pairs
        .iter()
        .zip(&traces)
        .map(|(pair, t)| report_of(pair, t, problem.trace.earth))
        .collect();
    let mut totals = Totals::default();
    let mut stats = Stats::default();
    for (p, pr) in problem.pairs.iter().zip(&pairs) {
        totals.objective += 0.5 * pr.residual.iter().map(|r| r * r).sum::<f64>();
        totals.summed_distance += p.weight * pr.distance;
        totals.max_distance = totals.max_distance.max(pr.distance);
        stats += pr.stats;
    }
    TraceReport {
        problem: problem.name.clone(),
        medium: medium.clone(),
        trace: problem.trace_spec.clone(),
        earth: problem.trace.earth.spec(),
        totals,
        pairs,
        stats,
    }
}

/// Rays of one lane width per parallel task: the split is fixed, so threads
/// change who traces a chunk, not what it computes.
const CHUNK: usize = 16;

/// Every pair's trace through its field, `result[i]` for `problem.pairs[i]`.
fn trace_all(problem: &Problem, fields: &PairFields) -> Vec<Trace> {
    use rayon::prelude::*;
    let batch = BatchOptions::from_trace_options(&problem.trace);
    let mut out = vec![Trace::default(); problem.pairs.len()];
    for (g, field) in fields.fields().iter().enumerate() {
        let members: Vec<usize> = (0..problem.pairs.len())
            .filter(|&i| fields.groups()[i] == g)
            .collect();
        let jobs: Vec<RayJob> = members
            .iter()
            .map(|&i| problem.pairs[i].ray_job_on(problem.trace.earth))
            .collect();
        let mut part = vec![Trace::default(); members.len()];
        jobs.par_chunks(CHUNK)
            .zip(part.par_chunks_mut(CHUNK))
            .for_each(|(jobs, part)| trace_batch_into(field, jobs, &batch, part));
        for (i, t) in members.into_iter().zip(part) {
            out[i] = t;
        }
    }
    out
}

/// A pair's report from its trace.
fn report_of(pair: &crate::pair::PointPair, t: &Trace, earth: crate::trace::Earth) -> PairReport {
    let r = (t.endpoint - pair.target()) * pair.weight;
    let sightline = Sightline::traced(pair, earth, t.endpoint.to_array());
    PairReport {
        endpoint: t.endpoint.to_array(),
        target: pair.target,
        distance: (t.endpoint - pair.target()).norm(),
        residual: r.to_array(),
        direction: t.direction.to_array(),
        occluded: t.occluded,
        unreachable: t.unreachable,
        end: t.end,
        arc_length: t.arc_length,
        stats: t.stats,
        sightline,
    }
}

/// The fields `problem`'s pairs are traced through at `medium`: one per
/// distinct pair wavelength.
pub fn pair_fields(problem: &Problem, medium: &Medium) -> PairFields {
    PairFields::new(medium, problem.pairs.iter().map(|p| p.wavelength))
}

/// Traces one pair (optionally recording its path) by the scalar tracer.
pub fn pair_report<F: IndexField + ?Sized>(
    pair: &crate::pair::PointPair,
    field: &F,
    options: &crate::trace::TraceOptions,
    path: Option<&mut Vec<RayState>>,
) -> PairReport {
    let (t, _) = pair.evaluate::<f64, _>(field, options, path);
    report_of(pair, &t, options.earth)
}
