//! Tangent lanes: the exact Jacobian of the discrete endpoint map in the
//! SIMD lanes, for the logistic model over the flat ground or the round
//! earth, by RK4 or Dormand–Prince 5(4).
//!
//! # Algorithm
//!
//! Forward sensitivities: each ray carries, beside its state (x, v, s) and
//! rate (n∇n, n), their derivatives along up to eight parameter seeds, as
//! [`Tan`](super::num::Tan) numbers laid out lane-wise. The medium's
//! compiled coefficients carry their derivatives with respect to the seeded
//! parameters (the dual-number compilation of the seeded medium: the
//! normalisation by S and the scale included), and the terms are `terms`'
//! own generic functions evaluated in `Tan` numbers, so the rate's
//! derivative parts are ∂(n∇n)/∂x·∂x/∂p + ∂(n∇n)/∂p, with the medium's
//! analytic derivatives, through the same operations as the value. Each
//! step's derivative parts are the step's own linear combination of the
//! stages' (RK4, or Dormand–Prince with the step sequence chosen from the
//! values only, which freezes it for the derivative: no step-control noise).
//! At the crossing step, the dual-number Hermite segment is located by the
//! scalar tracer's `event::locate`, whose Newton step carries the implicit
//! derivative of the crossing.
//!
//! # Invariants and accuracy
//!
//! - The value parts are the plain 3-D lanes kernel's numbers, so the
//!   residuals that come with a Jacobian are those of
//!   [`trace_batch`](super::trace_batch) (to the last bit where it takes
//!   the 3-D kernel; to ~10⁻¹² m where it takes the stratified one).
//! - The derivative parts are those of the dual-number path
//!   (`PointPair::evaluate` in `num_dual::DualSVec64`) to rounding: the same
//!   chain rule through the same formulas, with the lanes' polynomial
//!   exponential instead of libm's. `tests/tangent_lanes.rs` checks every
//!   bundled logistic problem and each part of the kernel to 10⁻⁸ of each
//!   column's size (measured: 10⁻¹⁴ typically, 2·10⁻¹⁰ at worst, where an
//!   adaptive step's error estimate lies within rounding of its tolerance);
//!   `tests/fit_jacobian.rs` checks the Jacobian against central
//!   differences.
//! - A ray that does not end on its plane (unreachable: the maximum length,
//!   the step limit, leaving the air) gets no derivative here ([`None`]); its
//!   caller differentiates that one ray on the dual-number path.
//!
//! # Cost
//!
//! Each term is evaluated once per stage in tangent numbers over 8 lanes,
//! its exponentials on the values only; a pass carries 4 or 8 seeds (a
//! pass of 2 parameters takes 4). `cargo bench --bench trace` reports one
//! Jacobian's cost in residual evaluations, tangent lanes against dual
//! numbers; whole fits of 36 pairs with 6 parameters run 3.4–4.2× faster
//! than on the dual-number path (README, "Performance").

mod field;
mod kernel;

use super::field::{EarthLanes, LaneField, LogisticLanes};
use super::isa::{Isa, run};
use super::job::{BatchOptions, RayJob};
use crate::medium::LogisticField;
use crate::trace::{Earth, Trace};
use field::TanField;
use kernel::TanKernel;
use num_dual::DualSVec64;

pub(crate) use kernel::EndDerivative;

/// Lanes of the tangent kernel: one AVX-512 register per component (its
/// state is P + 1 times the plain kernel's, so 16 lanes would only spill).
const TANGENT_LANES: usize = 8;

/// Traces every job through `field` (the plain compiled medium) with the
/// derivative parts of `seeded` (the same medium compiled in dual numbers
/// seeded on P parameters): `out[i]` is job i's trace, as
/// [`trace_batch`](super::trace_batch) gives it, and the result's entry i
/// its endpoint's derivatives (`None` if it did not end on its plane).
///
/// # Panics
/// If `out.len() != jobs.len()`.
pub(crate) fn trace_tangent<const P: usize>(
    field: &LogisticField,
    seeded: &LogisticField<DualSVec64<P>>,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) -> Vec<EndDerivative<P>> {
    assert_eq!(out.len(), jobs.len(), "one output per job");
    let isa = Isa::detect();
    let lanes = LogisticLanes::new(field);
    match options.earth {
        Earth::Flat => {
            let tan = TanField::new(seeded, None);
            drive(isa, &lanes, &tan, jobs, options, out)
        }
        Earth::Round { radius } => {
            let tan = TanField::new(seeded, Some(radius));
            let earth = EarthLanes::new(&lanes, radius);
            drive(isa, &earth, &tan, jobs, options, out)
        }
    }
}

/// The tangent kernel over `field` as the driver sees it.
fn drive<F: LaneField, const P: usize>(
    isa: Isa,
    field: &F,
    tan: &TanField<P>,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) -> Vec<EndDerivative<P>> {
    let mut kernel = TanKernel::<F, TANGENT_LANES, P>::new(
        field,
        tan,
        options.method,
        options.earth,
        jobs.len(),
    );
    run(isa, &mut kernel, jobs, options, out);
    kernel.ends
}
