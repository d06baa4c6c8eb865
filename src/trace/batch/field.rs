//! The medium as the lanes kernels see it: δ and its gradient at every
//! lane's position at once ([`LaneField`]), for each medium kind that has a
//! lane form: the logistic model ([`LogisticLanes`], its terms in `terms`)
//! and real air ([`AirLanes`](super::air::AirLanes)).
//!
//! A lane field is also an ordinary [`IndexField`] (the scalar field it was
//! made from): the kernels start each ray and decide its events with the
//! scalar code, exactly as the scalar tracer does, and step with the lane
//! form.

// Lane loops index several arrays in lockstep; `for i in 0..N` over fixed-size
// arrays is the form the compiler vectorizes.
#![allow(clippy::needless_range_loop)]

use super::terms::{Coefficients, HotCache};
use crate::math::V3;
use crate::medium::{IndexField, LogisticField};
use crate::trace::OnEarth;

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

    /// What [`LaneField::full`] keeps from one call to the next for `N`
    /// lanes (each lane's culled hot spots); `()` where nothing.
    type Cache<const N: usize>;

    /// A fresh cache for `N` lanes.
    fn cache<const N: usize>(&self) -> Self::Cache<N>;

    /// δ and ∇δ at positions `p`.
    fn full<const N: usize, const FMA: bool>(
        &self,
        cache: &mut Self::Cache<N>,
        p: [&[f64; N]; 3],
        d: &mut [f64; N],
        g: [&mut [f64; N]; 3],
    );

    /// Caps each lane's adaptive step `h` at [`IndexField::step_limit`] for
    /// its height `y` and vertical velocity `vy` (as `Stepper::limit` does).
    /// The default has no limit.
    #[inline(always)]
    fn cap_steps<const N: usize>(&self, _y: &[f64; N], _vy: &[f64; N], _h: &mut [f64; N]) {}

    /// [`LaneField::cap_steps`] for rays at positions `p` with velocities
    /// `v`: over the flat ground their y and v_y.
    #[inline(always)]
    fn cap_steps_at<const N: usize>(&self, p: [&[f64; N]; 3], v: [&[f64; N]; 3], h: &mut [f64; N]) {
        self.cap_steps(p[1], v[1], h);
    }
}

/// A lane field over the round earth: the field evaluated at (x, h(p), z),
/// its gradient by the chain rule, as [`OnEarth`] does it for the scalar
/// tracer (the lanes' heights are the same formula, lane-wise).
pub(crate) struct EarthLanes<'a, F> {
    inner: &'a F,
    scalar: OnEarth<'a, F>,
    radius: f64,
}

impl<'a, F: LaneField> EarthLanes<'a, F> {
    pub(crate) fn new(inner: &'a F, radius: f64) -> Self {
        EarthLanes {
            inner,
            scalar: OnEarth {
                field: inner,
                radius,
            },
            radius,
        }
    }

    /// Heights and the local vertical at the lanes' positions.
    #[inline(always)]
    fn heights<const N: usize>(&self, [x, y, z]: [&[f64; N]; 3]) -> ([f64; N], [[f64; N]; 3]) {
        let r = self.radius;
        let mut h = [0.0; N];
        let mut up = [[0.0; N]; 3];
        for i in 0..N {
            let qy = y[i] + r;
            let q = (x[i] * x[i] + qy * qy + z[i] * z[i]).sqrt();
            h[i] = (x[i] * x[i] + z[i] * z[i] + y[i] * (y[i] + 2.0 * r)) / (q + r);
            let inv = 1.0 / q;
            up[0][i] = x[i] * inv;
            up[1][i] = qy * inv;
            up[2][i] = z[i] * inv;
        }
        (h, up)
    }
}

impl<F: LaneField> IndexField<f64> for EarthLanes<'_, F> {
    #[inline]
    fn delta_gradient(&self, p: V3) -> (f64, V3) {
        self.scalar.delta_gradient(p)
    }

    fn is_stratified(&self) -> bool {
        false
    }

    fn ceiling(&self) -> f64 {
        self.inner.ceiling()
    }

    fn step_limit(&self, h: f64, vh: f64) -> f64 {
        self.inner.step_limit(h, vh)
    }
}

impl<F: LaneField> LaneField for EarthLanes<'_, F> {
    type Cache<const N: usize> = F::Cache<N>;

    fn cache<const N: usize>(&self) -> Self::Cache<N> {
        self.inner.cache()
    }

    /// Never called: a field over the sphere is not stratified in a
    /// vertical plane, so the 2-D kernels decline it.
    fn layers<const N: usize, const FMA: bool>(
        &self,
        _y: &[f64; N],
        _d: &mut [f64; N],
        _gy: &mut [f64; N],
    ) {
        unreachable!("a field over the round earth takes the 3-D kernel");
    }

    #[inline(always)]
    fn full<const N: usize, const FMA: bool>(
        &self,
        cache: &mut Self::Cache<N>,
        p: [&[f64; N]; 3],
        d: &mut [f64; N],
        [gx, gy, gz]: [&mut [f64; N]; 3],
    ) {
        let (h, up) = self.heights(p);
        self.inner
            .full::<N, FMA>(cache, [p[0], &h, p[2]], d, [&mut *gx, &mut *gy, &mut *gz]);
        for i in 0..N {
            let g = gy[i];
            gx[i] += g * up[0][i];
            gz[i] += g * up[2][i];
            gy[i] = g * up[1][i];
        }
    }

    #[inline(always)]
    fn cap_steps_at<const N: usize>(
        &self,
        p: [&[f64; N]; 3],
        [vx, vy, vz]: [&[f64; N]; 3],
        h: &mut [f64; N],
    ) {
        let (height, up) = self.heights(p);
        let mut vh = [0.0; N];
        for i in 0..N {
            vh[i] = vx[i] * up[0][i] + vy[i] * up[1][i] + vz[i] * up[2][i];
        }
        self.inner.cap_steps(&height, &vh, h);
    }
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
    type Cache<const N: usize> = HotCache<N>;

    fn cache<const N: usize>(&self) -> Self::Cache<N> {
        HotCache::new(self.c.grid.as_ref())
    }

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
        cache: &mut Self::Cache<N>,
        p: [&[f64; N]; 3],
        d: &mut [f64; N],
        [gx, gy, gz]: [&mut [f64; N]; 3],
    ) {
        *d = [0.0; N];
        *gx = [0.0; N];
        *gy = [0.0; N];
        *gz = [0.0; N];
        self.c.delta_gradient::<N, FMA>(cache, p, d, [gx, gy, gz]);
    }
}
