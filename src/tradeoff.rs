//! The speed/accuracy trade: for fixed RK4 steps and Dormand–Prince tolerances,
//! how far endpoints are from a tight reference, what a trace costs (time and
//! right-hand-side evaluations), and what that does to a fit.

use crate::error::{Error, Result};
use crate::evaluate::trace_pairs;
use crate::problem::Problem;
use crate::trace::{Method, TraceOptions};
use serde::Serialize;
use std::time::{Duration, Instant};

/// RK4 steps measured (metres).
pub const RK4_STEPS: [f64; 7] = [8.0, 4.0, 2.0, 1.0, 0.5, 0.25, 0.125];
/// Dormand–Prince tolerances measured.
pub const TOLERANCES: [f64; 10] = [
    1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12,
];
/// The reference the errors are measured against.
pub const REFERENCE: Method = Method::Dopri5 { tolerance: 1e-14 };

/// What one fit at one setting gave.
#[derive(Clone, Debug, Serialize)]
pub struct FitPoint {
    /// Final objective F (m²), with this setting's tracer.
    pub objective: f64,
    /// F of the fitted medium traced with the reference tracer (m²).
    pub objective_at_reference: f64,
    /// Largest relative difference of a fitted parameter from the reference fit's.
    pub parameter_error: f64,
    /// Fit wall time (s).
    pub time_s: f64,
}

/// One setting of one method.
#[derive(Clone, Debug, Serialize)]
pub struct TradeoffPoint {
    /// `rk4` or `dopri5`.
    pub method: &'static str,
    /// Step (m) for RK4, tolerance for Dormand–Prince.
    pub setting: f64,
    /// Largest endpoint distance from the reference over all pairs (m).
    pub endpoint_error: f64,
    /// Wall time to trace every pair once, one thread (s).
    pub trace_time_s: f64,
    /// Right-hand-side evaluations per ray (mean).
    pub rhs_per_ray: f64,
    /// The fit at this setting, if measured.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fit: Option<FitPoint>,
}

/// The whole measurement.
#[derive(Clone, Debug, Serialize)]
pub struct Tradeoff {
    /// Problem name.
    pub problem: String,
    /// Number of pairs.
    pub pairs: usize,
    /// Reference tolerance (Dormand–Prince).
    pub reference_tolerance: f64,
    /// Reference fit wall time (s).
    pub reference_fit_time_s: Option<f64>,
    /// Every point.
    pub points: Vec<TradeoffPoint>,
}

fn with_method(problem: &Problem, method: Method) -> Problem {
    let mut p = problem.clone();
    p.trace = TraceOptions {
        method,
        ..problem.trace
    };
    p.trace_spec.method = method.name().to_string();
    match method {
        Method::Rk4 { step } => {
            p.trace_spec.step = Some(step);
            p.trace_spec.tolerance = None;
        }
        Method::Dopri5 { tolerance } => {
            p.trace_spec.step = None;
            p.trace_spec.tolerance = Some(tolerance);
        }
    }
    p
}

/// Median time of `f` over repeats filling at least `budget`.
fn time_it(budget: Duration, mut f: impl FnMut()) -> f64 {
    let mut times = Vec::new();
    let start = Instant::now();
    while times.len() < 3 || (start.elapsed() < budget && times.len() < 1000) {
        if crate::interrupt::requested() {
            // The caller's next cancellation point reports it.
            break;
        }
        let t = Instant::now();
        f();
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    times.get(times.len() / 2).copied().unwrap_or(f64::NAN)
}

/// Measures the trade on `problem`'s medium and pairs; with `fit`, also fits at
/// every setting (the problem must have free parameters). Traces run on the
/// calling thread, so times are per core.
pub fn measure(problem: &Problem, fit: bool) -> Result<Tradeoff> {
    let reference = trace_pairs(&with_method(problem, REFERENCE), &problem.medium);
    crate::interrupt::check()?;
    let ref_fit = if fit && !problem.free.is_empty() {
        let p = with_method(problem, REFERENCE);
        let t = Instant::now();
        let r = crate::fit::fit(&p, None)?;
        Some((r, t.elapsed().as_secs_f64()))
    } else {
        None
    };
    let fields = crate::evaluate::pair_fields(problem, &problem.medium);
    let methods = RK4_STEPS.iter().map(|&step| Method::Rk4 { step }).chain(
        TOLERANCES
            .iter()
            .map(|&tolerance| Method::Dopri5 { tolerance }),
    );
    let mut points = Vec::new();
    for method in methods {
        crate::interrupt::check()?;
        let p = with_method(problem, method);
        let report = trace_pairs(&p, &problem.medium);
        let endpoint_error = report
            .pairs
            .iter()
            .zip(&reference.pairs)
            .map(|(a, b)| {
                let d: f64 = (0..3)
                    .map(|k| (a.endpoint[k] - b.endpoint[k]).powi(2))
                    .sum();
                d.sqrt()
            })
            .fold(0.0, f64::max);
        let trace_time_s = time_it(Duration::from_millis(60), || {
            for (i, pair) in p.pairs.iter().enumerate() {
                std::hint::black_box(pair.evaluate::<f64, _>(fields.of(i), &p.trace, None));
            }
        });
        let rhs_per_ray = report.stats.rhs_evaluations as f64 / p.pairs.len().max(1) as f64;
        let fit_point = match &ref_fit {
            Some((reference_fit, _)) => {
                let t = Instant::now();
                let r = crate::fit::fit(&p, None)?;
                let time_s = t.elapsed().as_secs_f64();
                crate::interrupt::check()?;
                let at_ref = trace_pairs(&with_method(problem, REFERENCE), &r.medium);
                let parameter_error = r
                    .parameters
                    .iter()
                    .zip(&reference_fit.parameters)
                    .map(|(a, b)| ((a.value - b.value) / b.value.abs().max(1e-300)).abs())
                    .fold(0.0, f64::max);
                Some(FitPoint {
                    objective: r.totals.objective,
                    objective_at_reference: at_ref.totals.objective,
                    parameter_error,
                    time_s,
                })
            }
            None => None,
        };
        points.push(TradeoffPoint {
            method: method.name(),
            setting: match method {
                Method::Rk4 { step } => step,
                Method::Dopri5 { tolerance } => tolerance,
            },
            endpoint_error,
            trace_time_s,
            rhs_per_ray,
            fit: fit_point,
        });
    }
    Ok(Tradeoff {
        problem: problem.name.clone(),
        pairs: problem.pairs.len(),
        reference_tolerance: match REFERENCE {
            Method::Dopri5 { tolerance } => tolerance,
            Method::Rk4 { step } => step,
        },
        reference_fit_time_s: ref_fit.map(|(_, t)| t),
        points,
    })
}

impl Tradeoff {
    /// The table as CSV (one row per point).
    pub fn to_csv(&self) -> String {
        let mut s = String::from(
            "method,setting,endpoint_error_m,trace_time_s,rhs_per_ray,fit_objective_m2,fit_objective_at_reference_m2,fit_parameter_error,fit_time_s\n",
        );
        for p in &self.points {
            let f = |v: Option<f64>| v.map(|v| format!("{v:e}")).unwrap_or_default();
            s.push_str(&format!(
                "{},{:e},{:e},{:e},{:.1},{},{},{},{}\n",
                p.method,
                p.setting,
                p.endpoint_error,
                p.trace_time_s,
                p.rhs_per_ray,
                f(p.fit.as_ref().map(|f| f.objective)),
                f(p.fit.as_ref().map(|f| f.objective_at_reference)),
                f(p.fit.as_ref().map(|f| f.parameter_error)),
                f(p.fit.as_ref().map(|f| f.time_s)),
            ));
        }
        s
    }

    /// The table for the terminal.
    pub fn to_table(&self) -> String {
        let mut s = format!(
            "{}: {} pair(s), endpoint error against Dormand–Prince at {:e}\n{:<7} {:>8} {:>12} {:>12} {:>10} {:>12} {:>12} {:>10}\n",
            self.problem,
            self.pairs,
            self.reference_tolerance,
            "method",
            "setting",
            "error (m)",
            "trace (s)",
            "rhs/ray",
            "fit F (m²)",
            "param err",
            "fit (s)"
        );
        for p in &self.points {
            let (fo, fe, ft) = match &p.fit {
                Some(f) => (
                    format!("{:.2e}", f.objective_at_reference),
                    format!("{:.2e}", f.parameter_error),
                    format!("{:.4}", f.time_s),
                ),
                None => ("-".into(), "-".into(), "-".into()),
            };
            s.push_str(&format!(
                "{:<7} {:>8.0e} {:>12.3e} {:>12.3e} {:>10.0} {:>12} {:>12} {:>10}\n",
                p.method, p.setting, p.endpoint_error, p.trace_time_s, p.rhs_per_ray, fo, fe, ft
            ));
        }
        s
    }
}

/// Checks that `problem` can be measured with a fit.
pub fn check_fit(problem: &Problem) -> Result<()> {
    if problem.free.is_empty() {
        return Err(Error::input(
            &problem.source,
            "free",
            "no free parameters: nothing to fit (use --no-fit to measure traces only)",
        ));
    }
    Ok(())
}
