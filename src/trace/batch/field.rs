//! The medium as the lanes kernels see it: δ and its gradient at every
//! lane's position at once ([`LaneField`]), for each medium kind that has a
//! lane form: the logistic model ([`LogisticLanes`], its terms in `terms`)
//! and real air ([`AirLanes`](super::air::AirLanes)).
//!
//! A lane field is also an ordinary [`IndexField`] (the scalar field it was
//! made from): the kernels start each ray and decide its events with the
//! scalar code, exactly as the scalar tracer does, and step with the lane
//! form.

use super::terms::Coefficients;
use crate::math::V3;
use crate::medium::{IndexField, LogisticField};

/// A medium evaluated over `N` lanes at once. Implementations write (not
/// add) their outputs, and compute what the scalar field computes, in its
/// order of operations where they can, with the polynomial exponential of
/// [`fastexp`](crate::trace::fastexp) and, when `FMA`, fused multiply–adds.
pub(crate) trait LaneField: IndexField<f64> {
    /// δ and dδ/dy at heights `y`, for a stratified field (no horizontal
    /// dependence: [`IndexField::is_stratified`]).
    fn layers<const N: usize, const FMA: bool>(
        &self,
        y: &[f64; N],
        d: &mut [f64; N],
        gy: &mut [f64; N],
    );

    /// δ and ∇δ at positions `p`.
    fn full<const N: usize, const FMA: bool>(
        &self,
        p: [&[f64; N]; 3],
        d: &mut [f64; N],
        g: [&mut [f64; N]; 3],
    );

    /// Caps each lane's adaptive step `h` at [`IndexField::step_limit`] for
    /// its height `y` and vertical velocity `vy` (as `Stepper::limit` does).
    /// The default has no limit.
    #[inline(always)]
    fn cap_steps<const N: usize>(&self, _y: &[f64; N], _vy: &[f64; N], _h: &mut [f64; N]) {}
}

/// The logistic model in lanes: the compiled field and its terms as plain
/// numbers.
pub(crate) struct LogisticLanes<'a> {
    field: &'a LogisticField,
    c: Coefficients,
}

impl<'a> LogisticLanes<'a> {
    pub(crate) fn new(field: &'a LogisticField) -> Self {
        LogisticLanes {
            field,
            c: Coefficients::of(field),
        }
    }
}

impl IndexField<f64> for LogisticLanes<'_> {
    #[inline]
    fn delta_gradient(&self, p: V3) -> (f64, V3) {
        self.field.delta_gradient(p)
    }

    fn is_stratified(&self) -> bool {
        IndexField::<f64>::is_stratified(self.field)
    }
}

impl LaneField for LogisticLanes<'_> {
    #[inline(always)]
    fn layers<const N: usize, const FMA: bool>(
        &self,
        y: &[f64; N],
        d: &mut [f64; N],
        gy: &mut [f64; N],
    ) {
        // The scalar code starts from 0 and adds the terms.
        *d = [0.0; N];
        *gy = [0.0; N];
        self.c.layers::<N, FMA>(y, d, gy);
    }

    #[inline(always)]
    fn full<const N: usize, const FMA: bool>(
        &self,
        p: [&[f64; N]; 3],
        d: &mut [f64; N],
        [gx, gy, gz]: [&mut [f64; N]; 3],
    ) {
        *d = [0.0; N];
        *gx = [0.0; N];
        *gy = [0.0; N];
        *gz = [0.0; N];
        self.c.delta_gradient::<N, FMA>(p, d, [gx, gy, gz]);
    }
}
