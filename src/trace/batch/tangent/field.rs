//! The logistic model lane-wise in [`Tan`] numbers: δ and ∇δ at every lane's
//! position together with their derivatives along the seeds, where both the
//! positions (their sensitivities ∂x/∂p) and the field's coefficients
//! (∂c/∂p, from the dual-number compilation of the seeded medium) carry
//! derivative parts. The terms are `terms`' own generic functions, so the
//! value parts are the plain kernel's numbers and the derivative parts are
//! the chain rule through the same operations: the medium's analytic
//! parameter derivatives of δ and ∇δ, and its second derivatives in x
//! (∂∇δ/∂x · ∂x/∂p) without forming the Hessian.

// Lane loops index several arrays in lockstep; `for i in 0..N` over fixed-size
// arrays is the form the compiler vectorizes.
#![allow(clippy::needless_range_loop)]

use super::super::num::{LaneNum, Tan, TanLanes};
use super::super::terms::{
    background_term, hot_combine, hot_term, inversion_term, layer_part, rim_part,
};
use crate::medium::LogisticField;
use crate::medium::cull::HotSpotGrid;
use num_dual::DualSVec64;

/// A dual number's value and derivative parts as a [`Tan`] (a part that
/// `num_dual` left out is zero).
pub(crate) fn tan_of<const P: usize>(x: DualSVec64<P>) -> Tan<P> {
    let eps = x.eps.unwrap_generic(nalgebra::Const::<P>, nalgebra::U1);
    Tan {
        v: x.re,
        d: std::array::from_fn(|k| eps[k]),
    }
}

/// The compiled logistic field with derivative parts in its coefficients,
/// over the flat ground or the round earth.
pub(crate) struct TanField<const P: usize> {
    /// Background `[amp, 1/a]`, if any.
    background: Option<[Tan<P>; 2]>,
    /// Inversion `[amp, 1/a, height]`, if any.
    inversion: Option<[Tan<P>; 3]>,
    /// Hot spots `[amp, 1/a, x, z, radius, edge]`.
    hotspots: Vec<[Tan<P>; 6]>,
    /// The grid that culls them, as the scalar field's.
    grid: Option<HotSpotGrid>,
    /// The round earth's radius (`None`: the flat ground).
    radius: Option<f64>,
}

impl<const P: usize> TanField<P> {
    /// The field of a seeded medium's dual-number compilation, over the
    /// flat ground (`radius` `None`) or the sphere of that radius.
    pub(crate) fn new(field: &LogisticField<DualSVec64<P>>, radius: Option<f64>) -> Self {
        let raw = field.coefficients();
        TanField {
            background: raw.background.map(|c| c.map(tan_of)),
            inversion: raw.inversion.map(|c| c.map(tan_of)),
            hotspots: raw.hotspots.iter().map(|c| c.map(tan_of)).collect(),
            grid: raw.grid,
            radius,
        }
    }

    /// (δ, ∂δ/∂x, ∂δ/∂y, ∂δ/∂z) with derivative parts at the lanes'
    /// positions `p` (with theirs): over the round earth the field at
    /// (x, h(p), z) and its gradient by the chain rule, as `EarthLanes`.
    ///
    /// Every loop over the lanes works on local arrays and holds one small
    /// part of a term: the compiler then knows that no output overlaps an
    /// input and vectorizes it (a loop with a whole hot spot's term in `Tan`
    /// numbers has too many values and arrays for that, and stays scalar).
    #[inline(always)]
    pub(crate) fn full<const N: usize, const FMA: bool>(
        &self,
        p: [&TanLanes<N, P>; 3],
    ) -> [TanLanes<N, P>; 4] {
        let (x, y, z) = (*p[0], *p[1], *p[2]);
        let Some(r) = self.radius else {
            return self.flat::<N, FMA>(&x, &y, &z);
        };
        let mut h = TanLanes::<N, P>::splat(0.0);
        let mut up = [TanLanes::<N, P>::splat(0.0); 3];
        for i in 0..N {
            let (xi, yi, zi) = (x.at(i), y.at(i), z.at(i));
            let qy = yi + Tan::constant(r);
            let q = (xi * xi + qy * qy + zi * zi).sqrt();
            let num = xi * xi + zi * zi + yi * (yi + Tan::constant(2.0 * r));
            h.put(i, num / (q + Tan::constant(r)));
            let inv = q.recip();
            up[0].put(i, xi * inv);
            up[1].put(i, qy * inv);
            up[2].put(i, zi * inv);
        }
        let mut out = self.flat::<N, FMA>(&x, &h, &z);
        let [_, gx, gy, gz] = &mut out;
        for i in 0..N {
            let gh = gy.at(i);
            gx.put(i, gx.at(i) + gh * up[0].at(i));
            gz.put(i, gz.at(i) + gh * up[2].at(i));
            gy.put(i, gh * up[1].at(i));
        }
        out
    }

    /// [`Self::full`] over the flat ground: (δ, ∂δ/∂x, ∂δ/∂y, ∂δ/∂z) from
    /// the layers, then the hot spots (each lane's culled list where the
    /// field has a grid), added in the scalar code's order.
    #[inline(always)]
    fn flat<const N: usize, const FMA: bool>(
        &self,
        x: &TanLanes<N, P>,
        y: &TanLanes<N, P>,
        z: &TanLanes<N, P>,
    ) -> [TanLanes<N, P>; 4] {
        let mut acc = [TanLanes::<N, P>::splat(0.0); 4];
        let [d, _, gy, _] = &mut acc;
        if let Some(bg) = self.background {
            for i in 0..N {
                let (a, b) = background_term::<Tan<P>, FMA>(bg, y.at(i));
                d.put(i, d.at(i) + a);
                gy.put(i, gy.at(i) + b);
            }
        }
        if let Some(inv) = self.inversion {
            for i in 0..N {
                let (a, b) = inversion_term::<Tan<P>, FMA>(inv, y.at(i));
                d.put(i, d.at(i) + a);
                gy.put(i, gy.at(i) - b);
            }
        }
        match &self.grid {
            // Each lane's list (decided on the values, as the scalar field
            // decides on real parts): lane by lane.
            Some(grid) => {
                for i in 0..N {
                    for &j in grid.candidates(x.v[i], z.v[i]) {
                        add_spot::<N, P, FMA>(i, self.hotspots[j as usize], [x, y, z], &mut acc);
                    }
                }
            }
            // Each hot spot for all lanes, its term's parts one loop each.
            None => {
                for &[amp, inv_rate, hx, hz, radius, edge] in &self.hotspots {
                    let mut rim = [TanLanes::<N, P>::splat(0.0); 4];
                    for i in 0..N {
                        let part =
                            rim_part::<Tan<P>, FMA>([hx, hz, radius, edge], x.at(i), z.at(i));
                        for (r, v) in rim.iter_mut().zip(part) {
                            r.put(i, v);
                        }
                    }
                    let mut layer = [TanLanes::<N, P>::splat(0.0); 2];
                    for i in 0..N {
                        let part = layer_part::<Tan<P>, FMA>(inv_rate, y.at(i));
                        for (l, v) in layer.iter_mut().zip(part) {
                            l.put(i, v);
                        }
                    }
                    for i in 0..N {
                        let rim_i = [rim[0].at(i), rim[1].at(i), rim[2].at(i), rim[3].at(i)];
                        let layer_i = [layer[0].at(i), layer[1].at(i)];
                        let terms = hot_combine(amp, inv_rate, rim_i, layer_i);
                        for (a, t) in acc.iter_mut().zip(terms) {
                            a.put(i, a.at(i) + t);
                        }
                    }
                }
            }
        }
        acc
    }
}

/// Adds one hot spot's terms at lane `i`. A function, not a closure: a
/// closure is compiled without the kernel's target features, and its fused
/// multiply–adds would become calls to the software `fma`.
#[inline(always)]
fn add_spot<const N: usize, const P: usize, const FMA: bool>(
    i: usize,
    spot: [Tan<P>; 6],
    [x, y, z]: [&TanLanes<N, P>; 3],
    acc: &mut [TanLanes<N, P>; 4],
) {
    let terms = hot_term::<Tan<P>, FMA>(spot, x.at(i), y.at(i), z.at(i));
    for (a, t) in acc.iter_mut().zip(terms) {
        a.put(i, a.at(i) + t);
    }
}

/// `Tan` as a `num_dual` dual number (for the generic event code).
pub(crate) fn dual_of<const P: usize>(t: Tan<P>) -> DualSVec64<P> {
    let eps = nalgebra::SVector::<f64, P>::from(t.d);
    DualSVec64::new(t.v, num_dual::Derivative::some(eps))
}

/// The derivative parts of a dual number (zeros where `num_dual` left them
/// out).
pub(crate) fn parts<const P: usize>(x: DualSVec64<P>) -> [f64; P] {
    tan_of(x).d
}
