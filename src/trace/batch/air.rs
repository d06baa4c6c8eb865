//! Real air in lanes: δ and ∇δ of a compiled [`AirField`] at every lane's
//! position, stage by stage as `AirField::delta_gradient` computes them:
//!
//! 1. the uniform temperature T_u(h) and dT_u/dh: base, lapse, surface layer
//!    and step aloft, each one lane loop with the polynomial exponential
//!    (the US 1976 layers and a measured table: the scalar code per lane);
//! 2. the hot spots' excesses (3-D only), one lane loop each;
//! 3. the pressure: constant, or the hydrostatic table per lane;
//! 4. the temperature held inside [−150 °C, 300 °C], the formula and the
//!    chain rule: one lane loop for Gladstone–Dale at a constant pressure,
//!    else the scalar `AirField::index_at` per lane (Ciddor's and Edlén's
//!    partials go through nested dual numbers, which have no lane form; a
//!    humidity table is evaluated at the lane's height there).
//!
//! Air without hot spots has a compiled profile of δ(h) and dδ/dh
//! (`medium::compiled`, [`AirField::profile`]): then every lane looks up its
//! piece and evaluates its two polynomials by Horner's rule, lane-wise, as
//! the scalar `AirField::delta_gradient` does (fused or not: the same
//! rounding up to 1 ulp per step); the lanes the profile leaves to the
//! formula (outside its range, at a knot) take stages 1–4 above.
//!
//! Where a stage runs per lane it runs the scalar code itself, so the lanes
//! and the scalar tracer differ only by the exponential (≤ 1 ulp) and fused
//! multiply–adds; `tests/fast_paths.rs` checks the endpoints.

// Lane loops index several arrays in lockstep; `for i in 0..N` over fixed-size
// arrays is the form the compiler vectorizes.
#![allow(clippy::needless_range_loop)]

use super::field::LaneField;
use crate::math::V3;
use crate::medium::IndexField;
use crate::medium::air::refractivity::STANDARD_PRESSURE;
use crate::medium::air::standard::us1976_offset;
use crate::medium::air::{AirField, COLDEST, HOTTEST, KELVIN, Lapse};
use crate::medium::air::{LaneTerms, UniformTerms};
use crate::medium::compiled::{CompiledProfile, DEGREE, Piece};
use crate::trace::fastexp::{exp_core, fmadd, sigmoid};

/// Real air in lanes: the compiled field and its terms as plain numbers.
pub(crate) struct AirLanes<'a> {
    field: &'a AirField,
    t: LaneTerms,
    /// The compiled profile, if the air has one.
    profile: Option<&'a CompiledProfile>,
    /// A piece for the lanes the profile leaves to the formula.
    zero: Piece,
}

impl<'a> AirLanes<'a> {
    pub(crate) fn new(field: &'a AirField) -> Self {
        AirLanes {
            field,
            t: field.lane_terms(),
            profile: field.profile(),
            zero: Piece {
                mid: 0.0,
                inv_half: 0.0,
                value: [0.0; DEGREE + 1],
                slope: [0.0; DEGREE + 1],
            },
        }
    }

    /// δ and dδ/dh at heights `y` from the compiled profile; `hit[i]` false
    /// where it leaves lane i to the formula (its outputs are then 0).
    /// Whether every lane was answered.
    #[inline(always)]
    fn compiled<const N: usize, const FMA: bool>(
        &self,
        profile: &CompiledProfile,
        y: &[f64; N],
        d: &mut [f64; N],
        gy: &mut [f64; N],
        hit: &mut [bool; N],
    ) -> bool {
        let mut pieces = [&self.zero; N];
        let mut t = [0.0; N];
        let mut all = true;
        for i in 0..N {
            if let Some(p) = profile.locate(y[i]) {
                pieces[i] = p;
                t[i] = (y[i] - p.mid) * p.inv_half;
                hit[i] = true;
            } else {
                hit[i] = false;
                all = false;
            }
        }
        for i in 0..N {
            d[i] = pieces[i].value[DEGREE];
            gy[i] = pieces[i].slope[DEGREE];
        }
        for k in (0..DEGREE).rev() {
            for i in 0..N {
                d[i] = fmadd::<FMA>(d[i], t[i], pieces[i].value[k]);
                gy[i] = fmadd::<FMA>(gy[i], t[i], pieces[i].slope[k]);
            }
        }
        all
    }

    /// δ and dδ/dy at heights `y` of stratified air by the formula's
    /// stages.
    #[inline(always)]
    fn formula_layers<const N: usize, const FMA: bool>(
        &self,
        y: &[f64; N],
        d: &mut [f64; N],
        gy: &mut [f64; N],
    ) {
        let mut tu = [0.0; N];
        self.uniform::<N, FMA>(y, &mut tu, gy);
        let (mut gx, mut gz) = ([0.0; N], [0.0; N]);
        self.finish::<N, FMA, false>(y, &tu, &tu, d, [&mut gx, gy, &mut gz]);
    }

    /// T_u (K) and dT_u/dh at heights `y` (stage 1).
    #[inline(always)]
    fn uniform<const N: usize, const FMA: bool>(
        &self,
        y: &[f64; N],
        t: &mut [f64; N],
        d: &mut [f64; N],
    ) {
        let Some(UniformTerms {
            kelvin0,
            lapse,
            exponential,
            inversion,
        }) = self.t.uniform
        else {
            for i in 0..N {
                (t[i], d[i]) = self.field.uniform_kelvin(y[i]);
            }
            return;
        };
        // The terms in the scalar `Profile::kelvin`'s order.
        *t = [kelvin0; N];
        *d = [0.0; N];
        match lapse {
            Some(Lapse::Rate(r)) => {
                for i in 0..N {
                    t[i] += r * y[i];
                    d[i] += r;
                }
            }
            Some(Lapse::Standard) => {
                for i in 0..N {
                    let (o, od) = us1976_offset(y[i]);
                    t[i] += o;
                    d[i] += od;
                }
            }
            None => {}
        }
        if let Some((delta, inv_h)) = exponential {
            for i in 0..N {
                // Held at its ground value below the ground.
                let above = y[i] > 0.0;
                let e = exp::<FMA>(-(y[i] * inv_h));
                let e = if above { e } else { 1.0 };
                t[i] += delta * e;
                let slope = delta * inv_h * e;
                d[i] -= if above { slope } else { 0.0 };
            }
        }
        if let Some((delta, height, inv_th)) = inversion {
            for i in 0..N {
                let (s, ds) = sigmoid::<FMA>((y[i] - height) * inv_th);
                t[i] += delta * s;
                d[i] += delta * ds * inv_th;
            }
        }
    }

    /// Stages 3 and 4 from the temperature `t` (K) and its gradient: δ and
    /// ∇δ into `d` and `g` (`g` holds ∇T on entry; `gx`, `gz` are ignored
    /// when not `FULL`).
    #[inline(always)]
    fn finish<const N: usize, const FMA: bool, const FULL: bool>(
        &self,
        y: &[f64; N],
        tu: &[f64; N],
        t: &[f64; N],
        d: &mut [f64; N],
        [gx, gy, gz]: [&mut [f64; N]; 3],
    ) {
        let (Some(k), Some(p)) = (self.t.gladstone_dale, self.t.constant_pressure) else {
            // Per lane, the scalar stages.
            for i in 0..N {
                let (p, dp) = self.field.pressure_with(y[i], tu[i]);
                let grad_t = if FULL {
                    V3::new(gx[i], gy[i], gz[i])
                } else {
                    V3::new(0.0, gy[i], 0.0)
                };
                let (di, g) = self.field.index_at(y[i], t[i], grad_t, p, dp);
                d[i] = di;
                gy[i] = g.y;
                if FULL {
                    gx[i] = g.x;
                    gz[i] = g.z;
                }
            }
            return;
        };
        let floor = COLDEST + KELVIN;
        let hottest = HOTTEST + KELVIN;
        for i in 0..N {
            // `AirField::index_from`, operation for operation, with a
            // constant pressure (dP/dh = 0, so d_dp·dP/dh adds 0).
            let cold = t[i] < floor;
            let hot = t[i] > hottest;
            let held = cold | hot;
            let ti = if cold {
                floor
            } else if hot {
                hottest
            } else {
                t[i]
            };
            let inv_t = 1.0 / ti;
            let d_dp = k * (1.0 / STANDARD_PRESSURE) * inv_t;
            let di = d_dp * p;
            let d_dt = -(di * inv_t);
            d[i] = di;
            let gyi = if held { 0.0 } else { gy[i] };
            gy[i] = d_dt * gyi + d_dp * 0.0;
            if FULL {
                let gxi = if held { 0.0 } else { gx[i] };
                let gzi = if held { 0.0 } else { gz[i] };
                gx[i] = d_dt * gxi;
                gz[i] = d_dt * gzi;
            }
        }
    }
}

impl IndexField<f64> for AirLanes<'_> {
    #[inline]
    fn delta_gradient(&self, p: V3) -> (f64, V3) {
        self.field.delta_gradient(p)
    }

    fn is_stratified(&self) -> bool {
        IndexField::<f64>::is_stratified(self.field)
    }

    fn ceiling(&self) -> f64 {
        self.field.ceiling()
    }

    fn step_limit(&self, y: f64, vy: f64) -> f64 {
        IndexField::<f64>::step_limit(self.field, y, vy)
    }
}

impl LaneField for AirLanes<'_> {
    type Cache<const N: usize> = ();

    fn cache<const N: usize>(&self) -> Self::Cache<N> {}
    #[inline(always)]
    fn layers<const N: usize, const FMA: bool>(
        &self,
        y: &[f64; N],
        d: &mut [f64; N],
        gy: &mut [f64; N],
    ) {
        let Some(profile) = self.profile else {
            self.formula_layers::<N, FMA>(y, d, gy);
            return;
        };
        let mut hit = [true; N];
        if self.compiled::<N, FMA>(profile, y, d, gy, &mut hit) {
            return;
        }
        let (mut d2, mut g2) = ([0.0; N], [0.0; N]);
        self.formula_layers::<N, FMA>(y, &mut d2, &mut g2);
        for i in 0..N {
            if !hit[i] {
                d[i] = d2[i];
                gy[i] = g2[i];
            }
        }
    }

    #[inline(always)]
    fn full<const N: usize, const FMA: bool>(
        &self,
        _cache: &mut (),
        [x, y, z]: [&[f64; N]; 3],
        d: &mut [f64; N],
        [gx, gy, gz]: [&mut [f64; N]; 3],
    ) {
        if self.profile.is_some() {
            // Only air without hot spots has a profile.
            self.layers::<N, FMA>(y, d, gy);
            *gx = [0.0; N];
            *gz = [0.0; N];
            return;
        }
        let mut tu = [0.0; N];
        self.uniform::<N, FMA>(y, &mut tu, gy);
        let mut t = tu;
        *gx = [0.0; N];
        *gz = [0.0; N];
        for &[hx, hz, radius, edge, delta, inv_scale] in &self.t.hotspots {
            for i in 0..N {
                let (w, dw_drho, ux, uz) = rim::<FMA>(x[i] - hx, z[i] - hz, radius, edge);
                // The excess decays with height, held at its ground value
                // below the ground (as the scalar `AirField::kelvin`).
                let above = y[i] > 0.0;
                let e = exp::<FMA>(-(y[i] * inv_scale));
                let e = if above { e } else { 1.0 };
                let de = if above { -(e * inv_scale) } else { 0.0 };
                let amp = delta * e;
                t[i] += amp * w;
                gy[i] += delta * w * de;
                gx[i] += amp * dw_drho * ux;
                gz[i] += amp * dw_drho * uz;
            }
        }
        self.finish::<N, FMA, true>(y, &tu, &t, d, [gx, gy, gz]);
    }

    #[inline(always)]
    fn cap_steps<const N: usize>(&self, y: &[f64; N], vy: &[f64; N], h: &mut [f64; N]) {
        // `AirField::step_limit` lane-wise, then `Stepper::limit`.
        let mut cap = [f64::INFINITY; N];
        for &(lo, hi, s) in &self.t.zones {
            let reach = self.t.zone_step_scales * s;
            let lo_finite = lo.is_finite();
            for i in 0..N {
                let (yi, vi) = (y[i], vy[i]);
                let heading_down = (yi > hi) & (vi < 0.0);
                let heading_up = (yi < lo) & (vi > 0.0);
                let inside = (lo <= yi) & (yi <= hi) & (lo_finite | (vi < 0.0));
                let limit = if heading_down {
                    (yi - hi + reach) / -vi
                } else if heading_up {
                    (lo - yi + reach) / vi
                } else if inside {
                    reach / vi.abs()
                } else {
                    f64::INFINITY
                };
                cap[i] = if limit < cap[i] { limit } else { cap[i] };
            }
        }
        for i in 0..N {
            h[i] = if h[i] > cap[i] { cap[i] } else { h[i] };
        }
    }
}

/// e^x as `f64::exp` gives it (∞ above 709, which an invalid medium's
/// negative scale can ask for), by the polynomial.
#[inline(always)]
fn exp<const FMA: bool>(x: f64) -> f64 {
    let e = exp_core::<FMA>(if x > 709.0 { 709.0 } else { x });
    if x > 709.0 { f64::INFINITY } else { e }
}

/// A hot spot's rim weight at offset (dx, dz) from its centre: `(w, dw/dρ,
/// ρ̂_x, ρ̂_z)`, as the logistic lanes compute it (`terms.rs`): ρ without
/// the scalar code's rescaling (an overflow to ∞ still gives w = 0 and a
/// zero gradient), and a zero direction at the centre.
#[inline(always)]
fn rim<const FMA: bool>(dx: f64, dz: f64, radius: f64, edge: f64) -> (f64, f64, f64, f64) {
    let rho = fmadd::<FMA>(dx, dx, dz * dz).sqrt();
    let (w, dw) = sigmoid::<FMA>(edge * (radius - rho));
    let inv_rho = if rho > 0.0 { 1.0 / rho } else { 0.0 };
    (w, -(edge * dw), dx * inv_rho, dz * inv_rho)
}
