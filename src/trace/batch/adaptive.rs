//! Dormand–Prince 5(4) over lanes: what the 3-D and 2-D adaptive steps share.
//! Each lane runs the scalar `Stepper::Dopri5` on its own ray, with its own
//! step: before the attempt the medium caps the step
//! ([`LaneField::cap_steps`], as `Stepper::limit`) and a step that has shrunk
//! below what f64 resolves is flagged (`Stepper::next_step`); after it, the
//! error estimate of every lane goes through the scalar controller's
//! arithmetic (`stepper::control_step`), lane by lane in one loop. Rejected
//! lanes keep their state (the kernel copies it over the new one) and try
//! again with the smaller step on the next round, while accepted lanes move
//! on: the lanes never wait for each other.
//!
//! The step sequence of a lane is the scalar tracer's for the same ray up to
//! rounding (the polynomial exponential, fused multiply–adds): the same
//! steps, accepted and rejected, except where an error estimate lies within
//! rounding of the tolerance.

// Lane loops index several arrays in lockstep; `for i in 0..N` over fixed-size
// arrays is the form the compiler vectorizes.
#![allow(clippy::needless_range_loop)]

use super::field::LaneField;
use super::lanes::Control;
use crate::trace::fastexp::fmadd;
use crate::trace::stepper::{E1, E3, E4, E5, E6, E7, control_step};

/// `y0 + h·Σ c_j k_j` per lane, in `RayState::advanced`'s order (zero
/// coefficients, known when this is inlined, are skipped as there).
#[inline(always)]
pub(crate) fn advance<const N: usize, const K: usize, const FMA: bool>(
    y0: &[f64; N],
    h: &[f64; N],
    c: [f64; K],
    k: [&[f64; N]; K],
    out: &mut [f64; N],
) {
    for i in 0..N {
        let mut acc = y0[i];
        for j in 0..K {
            if c[j] != 0.0 {
                acc = fmadd::<FMA>(k[j][i], c[j] * h[i], acc);
            }
        }
        out[i] = acc;
    }
}

/// The error estimate's component per lane: `stepper::error_sum` of the
/// rates k1, k3 … k7 of one component, times the step.
#[inline(always)]
pub(crate) fn error_term<const N: usize>(k: [&[f64; N]; 6], h: &[f64; N], out: &mut [f64; N]) {
    for i in 0..N {
        out[i] = (k[0][i] * E1
            + k[1][i] * E3
            + k[2][i] * E4
            + k[3][i] * E5
            + k[4][i] * E6
            + k[5][i] * E7)
            * h[i];
    }
}

/// The squared error norm of a 3-D attempt per lane, as the scalar
/// stepper's: the error terms of the position (from the rates `v[c]` of
/// component c of v: k1, k3 … k7) and of v (from the rates `a[c]`),
/// squared and summed, the position's three before v's three.
#[inline(always)]
pub(crate) fn error_norm2<const N: usize>(
    v: [[&[f64; N]; 6]; 3],
    a: [[&[f64; N]; 6]; 3],
    h: &[f64; N],
) -> [f64; N] {
    let mut e = [[0.0; N]; 6];
    let [ex, ey, ez, evx, evy, evz] = &mut e;
    error_term(v[0], h, ex);
    error_term(v[1], h, ey);
    error_term(v[2], h, ez);
    error_term(a[0], h, evx);
    error_term(a[1], h, evy);
    error_term(a[2], h, evz);
    let mut err2 = [0.0; N];
    for i in 0..N {
        err2[i] = (ex[i] * ex[i] + ey[i] * ey[i] + ez[i] * ez[i])
            + (evx[i] * evx[i] + evy[i] * evy[i] + evz[i] * evz[i]);
    }
    err2
}

/// The error estimate's component per lane for a rate that is the same
/// constant `v` at every stage (a planar step's horizontal velocity):
/// `stepper::error_sum([v; 6])·h`, a rounding residue of Σ E_j = 0.
#[inline(always)]
pub(crate) fn constant_error_term<const N: usize>(v: &[f64; N], h: &[f64; N], out: &mut [f64; N]) {
    for i in 0..N {
        let vi = v[i];
        out[i] = (vi * E1 + vi * E3 + vi * E4 + vi * E5 + vi * E6 + vi * E7) * h[i];
    }
}

/// Before an attempt: caps each lane's step by the medium, records it as the
/// step this attempt takes, and returns the lanes whose step has shrunk
/// below `10⁻¹²·(1 + |x|)` (`Stepper::next_step`), as a mask.
#[inline(always)]
pub(crate) fn prepare<F: LaneField, const N: usize>(
    field: &F,
    control: &mut Control<N>,
    [x, y, z]: [&[f64; N]; 3],
    v: [&[f64; N]; 3],
) -> u64 {
    field.cap_steps_at([x, y, z], v, &mut control.h);
    control.used = control.h;
    let mut underflow = 0u64;
    for i in 0..N {
        let norm = (x[i] * x[i] + y[i] * y[i] + z[i] * z[i]).sqrt();
        let resolved = control.h[i] > 1e-12 * (1.0 + norm);
        underflow |= u64::from(!resolved) << i;
    }
    underflow
}

/// After an attempt of `control.used` with squared error norms `err2`: each
/// lane's next step and growth limit by the scalar controller, and the mask
/// of accepted lanes.
#[inline(always)]
pub(crate) fn judge<const N: usize, const FMA: bool>(
    control: &mut Control<N>,
    err2: &[f64; N],
) -> u64 {
    let mut accepted = 0u64;
    for i in 0..N {
        let (accept, h, grow) = control_step::<FMA>(
            control.used[i],
            err2[i],
            control.tolerance,
            control.h_max[i],
            control.grow[i],
        );
        control.h[i] = h;
        control.grow[i] = grow;
        accepted |= u64::from(accept) << i;
    }
    accepted
}

/// Copies the lanes of `mask` from `from` into `to` (a rejected attempt
/// leaves its lane where it was).
#[inline(always)]
pub(crate) fn keep<const N: usize>(mask: u64, from: &[f64; N], to: &mut [f64; N]) {
    for i in 0..N {
        to[i] = if mask >> i & 1 == 1 { from[i] } else { to[i] };
    }
}
