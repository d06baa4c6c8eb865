//! Many rays at once: RK4 or Dormand–Prince 5(4) through the logistic model
//! or real air over [`LANES`] rays held in structure-of-arrays lanes, with
//! the instruction set picked at run time. [`trace_batch`] takes a [`Field`]
//! of any kind and sends the kind the lanes do not evaluate (the analytic
//! test medium) to the scalar tracer, job by job.
//!
//! # Semantics
//!
//! Each ray is traced exactly as [`crate::trace::trace`] traces it with the
//! same [`Method`](crate::trace::Method) and a target plane: the same τ-form state, the same step
//! sequence (Dormand–Prince: each lane with its own adaptive step, the scalar
//! stepper's controller and the medium's step limits), the endpoint where the
//! quintic Hermite interpolant of the crossing step meets the plane,
//! `occluded` (also for dips below the ground between two step ends),
//! `unreachable` with the traced point nearest the plane, the maximum length
//! (default 4 × the distance to the target), the step limit, real air's
//! ceiling, [`GroundMode`](crate::trace::GroundMode), and the same
//! [`Stats`](crate::trace::Stats). The only numerical difference is the
//! exponential: a polynomial ([`fastexp`](crate::trace::fastexp), within 1 ulp
//! of `f64::exp`) instead of libm's, and fused multiply–adds where the CPU has
//! them; endpoints agree with the scalar tracer to about 10⁻¹¹ m
//! (`tests/fast_paths.rs` checks 10⁻⁹ m; an adaptive step whose error
//! estimate lies within rounding of the tolerance may be decided the other
//! way, which moves that ray's endpoint by about the tolerance).
//!
//! # How it is fast
//!
//! The scalar tracer spends its time in 16 `exp` calls per RK4 step (full
//! medium, one hot spot), which the compiler cannot vectorize. Here each
//! right-hand-side term is one branch-free loop over the lanes, with the
//! polynomial exponential inlined, so it compiles to SIMD code; [`Isa`] selects
//! an AVX-512, AVX2+FMA or baseline build of the whole kernel at run time.
//! Several terms share a lane loop (the layers with the first hot spot, hot
//! spots two by two) so that independent exponentials overlap. On the CPU this
//! was written on (AMD EPYC with AVX-512) that is about 50 M RK4 steps per
//! second per core through the full medium with one hot spot, ten times the
//! scalar tracer (`cargo bench --bench trace`).
//! With many hot spots, each lane evaluates only those listed in its cell of
//! the field's culling grid (`terms`, `docs/model.md` "Culling"), so a step
//! costs the longest list among the lanes rather than every hot spot.
//! Events (plane, ground, maximum length) are screened for all lanes with a
//! cheap vector test after each step and resolved per lane by the scalar code
//! of the tracer; a lane whose ray is done takes the next job, and when none is
//! left it is frozen (step 0). Nothing is allocated per step.
//!
//! # Use
//!
//! ```
//! use mirage::medium::{Background, LogisticMedium, Medium};
//! use mirage::pair::PointPair;
//! use mirage::trace::batch::{BatchOptions, trace_batch};
//! use mirage::trace::{Method, TraceOptions};
//!
//! let medium = Medium::Logistic(LogisticMedium {
//!     background: Some(Background { n: 1.0, a: 40.0 }),
//!     ..LogisticMedium::vacuum()
//! });
//! let pair = PointPair {
//!     origin: [0.0, 2.0, 0.0],
//!     through: [0.0, 2.0, 100.0],
//!     target: [0.0, 2.0, 100.0],
//!     weight: 1.0,
//!     wavelength: None,
//! };
//! let options = BatchOptions::from_trace_options(&TraceOptions::new(Method::Rk4 { step: 1.0 }));
//! let traces = trace_batch(&medium.field(), &[pair.ray_job()], &options);
//! assert!(!traces[0].unreachable);
//! ```
//!
//! # Layout
//!
//! `job` (what a batch traces), `lanes` (the lane state both kernels share,
//! each lane's step control, and the event screen), `adaptive` (Dormand–Prince's
//! step control over lanes), `field` (the medium lane-wise: the trait and the
//! logistic kind), `terms` (the logistic model's terms), `air` (real air),
//! `kernel` (the 3-D kernel), [`stratified`] (the 2-D one), `driver` (job
//! scheduling, lane refill, freezing, events), `isa` (instruction sets and
//! the run-time dispatch), `pack` ([`PackStepper`]: RK4 steps of a
//! caller's pack of rays, for the renderer), `num` (the numbers the terms are written in:
//! `f64` and forward-mode tangents) and `tangent` (the 3-D kernel with each
//! ray's parameter sensitivities: the fit's exact Jacobian in lanes).

mod adaptive;
mod air;
mod driver;
mod field;
mod isa;
mod job;
mod kernel;
mod lanes;
mod num;
mod pack;
pub mod stratified;
pub(crate) mod tangent;
mod terms;

pub use isa::{Isa, exp_in_place};
pub use job::{BatchOptions, RayJob};
pub use kernel::{trace_air_3d, trace_batch_3d};
pub use lanes::LANES;
pub use pack::{PACK, PackCache, PackStepper};
pub use stratified::{NotStratified, trace_air_2d, trace_batch_2d};

use crate::medium::Field;
use crate::trace::{Trace, trace};

/// Traces every job by the fastest path for this field and CPU: for the
/// logistic kind and real air, the 2-D [`stratified`] kernel when the field
/// has no hot spots and the ground is flat, and the 3-D lanes kernel
/// otherwise (over the round earth too); the analytic test medium (no lane
/// form) through the general scalar tracer [`crate::trace::trace`], job by
/// job, with the same options, so the results mean the same. `result[i]` is
/// the trace of `jobs[i]`.
pub fn trace_batch(field: &Field, jobs: &[RayJob], options: &BatchOptions) -> Vec<Trace> {
    let mut out = vec![driver::placeholder(); jobs.len()];
    trace_batch_into(field, jobs, options, &mut out);
    out
}

/// [`trace_batch`] into a slice of the same length as `jobs` (reusable across
/// calls; its contents are overwritten).
///
/// # Panics
/// If `out.len() != jobs.len()`.
pub fn trace_batch_into(field: &Field, jobs: &[RayJob], options: &BatchOptions, out: &mut [Trace]) {
    let isa = Isa::detect();
    match field {
        Field::Logistic(field) => {
            if trace_batch_2d(isa, field, jobs, options, out).is_err() {
                trace_batch_3d(isa, field, jobs, options, out);
            }
        }
        Field::Air(field) => {
            if trace_air_2d(isa, field, jobs, options, out).is_err() {
                trace_air_3d(isa, field, jobs, options, out);
            }
        }
        Field::LinearSquare(_) => trace_scalar(field, jobs, options, out),
    }
}

/// The general tracer, one job after the other, with the batch's options.
fn trace_scalar(field: &Field, jobs: &[RayJob], options: &BatchOptions, out: &mut [Trace]) {
    assert_eq!(out.len(), jobs.len(), "one output slot per job");
    let options = options.trace_options();
    for (job, out) in jobs.iter().zip(out) {
        *out = trace::<f64, _>(
            field,
            job.origin,
            job.direction,
            Some(&job.target),
            &options,
            None,
        );
    }
}
