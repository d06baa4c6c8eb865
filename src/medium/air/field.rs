//! Real air compiled for evaluation: δ = n − 1 and ∇δ at a point.
//!
//! ```text
//! T(p)  = T_u(h) + Σ_j δT_j · w_j(x, z) · e^(−h⁺/H_j)          (h⁺ = max(h, 0))
//! P(h)  = P₀ · exp(−(gM/R) ∫₀^h dh'/T_u(h'))   (hydrostatic; else P₀)
//! δ     = f(T, P, RH(h); λ, CO₂)                  (Ciddor, Edlén or Gladstone–Dale)
//! ∇δ    = ∂f/∂T · ∇T + (∂f/∂P · dP/dh + ∂f/∂RH · dRH/dh) ŷ
//! ```
//!
//! RH is one number, or a humidity table's shape-preserving cubic in h (the
//! temperature table's interpolant, held beyond the end rows); with one
//! number dRH/dh = 0 and the last term is not computed at all, so such air
//! gives exactly the numbers it gave before humidity tables existed.
//!
//! T_u is the horizontally uniform profile (analytic terms or the table's
//! shape-preserving cubic); the pressure follows it alone, as the contract
//! says (hot spots do not change the pressure). ∂f/∂T and ∂f/∂P come exactly
//! from the formula (`refractivity::refractivity_partials`), dP/dh from the
//! hydrostatic law at the point's own T_u, so ∇δ is the analytic gradient of δ.
//!
//! Below the ground (rays integrated through it) the surface terms are held
//! at their ground value, which keeps every value finite for any finite point;
//! above the height where the uniform air falls below −150 °C (a steep lapse
//! far up) the medium is not air: [`AirField::ceiling`] gives that height and
//! the tracers stop there (`End::LeftAir`), and δ is evaluated with the
//! temperature held at that floor so that it stays finite.

use super::hydrostatic::{Hydrostatic, MAX_SPACING};
use super::model::{AirMedium, DEFAULT_BASE, Humidity, Lapse};
use super::pchip::Pchip;
use super::refractivity::{
    AirState, Formula, STANDARD_PRESSURE, humidity_partial, refractivity_partials,
};
use super::standard::{US1976_BREAKS, US1976_TOP, us1976_offset};
use crate::math::{Real, V3, sigmoid};
use crate::medium::IndexField;
use crate::medium::compiled::CompiledProfile;
use crate::medium::rim::rim_weight;
use std::sync::Arc;

/// 0 °C in kelvins.
pub const KELVIN: f64 = 273.15;
/// The coldest air the formulas are asked about (°C): the contract's floor.
pub const COLDEST: f64 = -150.0;
/// The hottest air the formulas are asked about (°C): far above any air, below
/// water's critical point (374 °C), where the saturation pressure ends.
pub const HOTTEST: f64 = 300.0;
/// Where the hydrostatic table starts (m below the ground: rays dip under it
/// by a step at most).
const TABLE_BOTTOM: f64 = -200.0;

/// The horizontally uniform temperature, compiled.
#[derive(Clone, Debug)]
enum Profile<T> {
    /// Analytic terms: base (K), lapse, surface layer, step aloft.
    Terms {
        kelvin0: T,
        lapse: Option<Lapse<T>>,
        /// (δT, 1/H).
        exponential: Option<(T, T)>,
        /// (δT, height, 1/thickness).
        inversion: Option<(T, T, T)>,
    },
    /// A measured table (°C), interpolated.
    Table(Pchip<T>),
}

impl<T: Real> Profile<T> {
    /// (T_u in kelvins, dT_u/dh) at height h.
    #[inline(always)]
    fn kelvin(&self, h: T) -> (T, T) {
        match self {
            Profile::Terms {
                kelvin0,
                lapse,
                exponential,
                inversion,
            } => {
                let mut t = *kelvin0;
                let mut d = T::cst(0.0);
                match lapse {
                    Some(Lapse::Rate(r)) => {
                        t += *r * h;
                        d += *r;
                    }
                    Some(Lapse::Standard) => {
                        let (o, od) = us1976_offset(h);
                        t += o;
                        d += od;
                    }
                    None => {}
                }
                if let Some((delta, inv_h)) = exponential {
                    if h.val() > 0.0 {
                        let e = (-(h * *inv_h)).exp();
                        t += *delta * e;
                        d -= *delta * *inv_h * e;
                    } else {
                        t += *delta;
                    }
                }
                if let Some((delta, height, inv_th)) = inversion {
                    let (s, ds) = sigmoid((h - *height) * *inv_th);
                    t += *delta * s;
                    d += *delta * ds * *inv_th;
                }
                (t, d)
            }
            Profile::Table(p) => {
                let (v, dv) = p.eval(h);
                (v + KELVIN, dv)
            }
        }
    }
}

/// The relative humidity, compiled.
#[derive(Clone, Debug)]
enum Moisture<T> {
    /// One number everywhere.
    Constant(T),
    /// A measured table (0…1), interpolated.
    Table(Pchip<T>),
}

#[derive(Clone, Debug)]
enum Pressure<T> {
    Constant(T),
    Hydrostatic(Hydrostatic<T>),
}

#[derive(Clone, Copy, Debug)]
struct HotTerm<T> {
    x: T,
    z: T,
    radius: T,
    edge: T,
    delta: T,
    inv_scale: T,
}

/// Real air compiled for evaluation (see the module documentation).
#[derive(Clone, Debug)]
pub struct AirField<T = f64> {
    profile: Profile<T>,
    pressure: Pressure<T>,
    formula: Formula<T>,
    humidity: Moisture<T>,
    wavelength: T,
    co2: T,
    hotspots: Vec<HotTerm<T>>,
    ceiling: f64,
    /// The top of the described air (m): see [`AirField::top`].
    top: f64,
    /// The thin layers as height zones `(lo, hi, scale)`: outside them the
    /// layer's share of T is below 1e-13 of its amplitude.
    zones: Vec<(f64, f64, f64)>,
    /// δ(h) and dδ/dh compiled (`medium::compiled`): plain `f64` air without
    /// hot spots only (see [`AirField::profile`]).
    compiled: Option<Arc<CompiledProfile>>,
}

/// How many scales a layer's zone reaches (e^(−30) ≈ 1e-13).
const ZONE_SCALES: f64 = 30.0;
/// How many scales of height a step may cover inside a zone.
const ZONE_STEP_SCALES: f64 = 4.0;

impl<T: Real> AirField<T> {
    /// Compiles a medium (validated or not: an invalid medium gives non-finite
    /// values, which callers treat as a failed evaluation).
    pub fn new(m: &AirMedium<T>) -> Self {
        let t = &m.air.temperature;
        let profile = match &t.table {
            Some(rows) if !t.has_analytic_terms() => {
                let rows: Vec<(T, T)> = rows.iter().map(|r| (r[0], r[1])).collect();
                Profile::Table(Pchip::new(&rows))
            }
            _ => Profile::Terms {
                kelvin0: t.base.unwrap_or(T::cst(DEFAULT_BASE)) + KELVIN,
                lapse: t.lapse,
                exponential: t.exponential.map(|e| (e.delta, e.scale_height.recip())),
                inversion: t
                    .inversion
                    .map(|i| (i.delta, i.height, i.thickness.recip())),
            },
        };
        let top = table_top(m);
        let pressure = if m.air.hydrostatic {
            let scales = feature_scales(m);
            let p = profile.clone();
            Pressure::Hydrostatic(Hydrostatic::new(
                m.air.pressure,
                move |h| p.kelvin(h),
                TABLE_BOTTOM,
                top,
                &scales,
            ))
        } else {
            Pressure::Constant(m.air.pressure)
        };
        let hotspots: Vec<HotTerm<T>> = m
            .hotspots
            .iter()
            .map(|h| HotTerm {
                x: h.x,
                z: h.z,
                radius: h.radius,
                edge: h.edge,
                delta: h.delta,
                inv_scale: h.scale_height.recip(),
            })
            .collect();
        let ceiling = ceiling(&profile, &hotspots);
        let zones = zones(m);
        let mut field = AirField {
            profile,
            pressure,
            formula: m.air.refractivity,
            humidity: match &m.air.humidity {
                Humidity::Constant(h) => Moisture::Constant(*h),
                Humidity::Table(rows) => {
                    let rows: Vec<(T, T)> = rows.iter().map(|r| (r[0], r[1])).collect();
                    Moisture::Table(Pchip::new(&rows))
                }
            },
            wavelength: m.air.wavelength,
            co2: m.air.co2,
            hotspots,
            ceiling,
            top,
            zones,
            compiled: None,
        };
        field.compiled = compile(&field, m).map(Arc::new);
        field
    }

    /// The compiled profile of δ(h) and dδ/dh, which
    /// [`IndexField::delta_gradient`] answers from wherever it covers: built
    /// for plain `f64` air without hot spots (the value paths: traces,
    /// renders, a fit's residuals). Dual numbers (a fit's exact Jacobian)
    /// always evaluate the formula, so the derivatives in every parameter
    /// are the formula's own, exactly; compiling them too would multiply
    /// the compile's work by the parameter count at every fit iteration.
    pub fn profile(&self) -> Option<&CompiledProfile> {
        self.compiled.as_deref()
    }

    /// The same air without its compiled profile: every evaluation by the
    /// formula.
    pub fn without_profile(mut self) -> Self {
        self.compiled = None;
        self
    }

    /// The height (m) above which the air is colder than −150 °C somewhere
    /// (infinite when it never is): the tracers stop rays there.
    pub fn ceiling(&self) -> f64 {
        self.ceiling
    }

    /// The top of the air this medium describes (m): 86 km (the US 1976
    /// layers' top), or higher when a table's last row or an inversion
    /// reaches higher. The hydrostatic pressure is tabulated up to it; above
    /// it the air is held isothermal at its temperature there. `mirage
    /// refraction` traces rays out of the atmosphere to it.
    pub fn top(&self) -> f64 {
        self.top
    }

    /// The horizontally uniform temperature (K) and its height derivative at h.
    pub fn uniform_kelvin(&self, h: T) -> (T, T) {
        self.profile.kelvin(h)
    }

    /// The pressure (Pa) and its height derivative at h.
    #[inline]
    pub fn pressure(&self, h: T) -> (T, T) {
        match &self.pressure {
            Pressure::Constant(p) => (*p, T::cst(0.0)),
            Pressure::Hydrostatic(table) => table.eval(h, self.profile.kelvin(h).0),
        }
    }

    /// The temperature (K) at p and its gradient.
    #[inline]
    pub fn kelvin(&self, p: V3<T>) -> (T, V3<T>) {
        let (tu, dtu) = self.profile.kelvin(p.y);
        let zero = T::cst(0.0);
        let mut t = tu;
        let mut grad = V3::new(zero, dtu, zero);
        for hs in &self.hotspots {
            let (w, dw_drho, ux, uz) = rim_weight(p.x - hs.x, p.z - hs.z, hs.radius, hs.edge);
            let (e, de) = if p.y.val() > 0.0 {
                let e = (-(p.y * hs.inv_scale)).exp();
                (e, -(e * hs.inv_scale))
            } else {
                (T::cst(1.0), zero)
            };
            let amp = hs.delta * e;
            t += amp * w;
            grad.y += hs.delta * w * de;
            grad.x += amp * dw_drho * ux;
            grad.z += amp * dw_drho * uz;
        }
        (t, grad)
    }
}

impl<T: Real> AirField<T> {
    /// The relative humidity (0…1) and its height derivative at h.
    pub fn humidity(&self, h: T) -> (T, T) {
        match &self.humidity {
            Moisture::Constant(rh) => (*rh, T::cst(0.0)),
            Moisture::Table(p) => p.eval(h),
        }
    }

    /// The temperature held inside [−150 °C, 300 °C] (K), its gradient 0
    /// where held.
    #[inline]
    fn held(t: T, grad_t: V3<T>) -> (T, V3<T>) {
        // Past the ceiling the tracers stop; hold the floor so δ stays finite.
        let floor = COLDEST + KELVIN;
        let hottest = HOTTEST + KELVIN;
        if t.val() < floor {
            let z = T::cst(0.0);
            (T::cst(floor), V3::new(z, z, z))
        } else if t.val() > hottest {
            // Past any air (water's saturation pressure has no value above
            // its critical point, 374 °C): held, as below the floor.
            let z = T::cst(0.0);
            (T::cst(hottest), V3::new(z, z, z))
        } else {
            (t, grad_t)
        }
    }

    /// δ and ∇δ from the temperature `t` (K) with its gradient and the
    /// pressure with its height derivative: the temperature held inside
    /// [−150 °C, 300 °C], then the formula and the chain rule. The last stage
    /// of [`IndexField::delta_gradient`], apart so that the lanes kernels
    /// (`trace::batch`) call it per lane where they have no vector form.
    /// It takes no height, so it serves air of one humidity only: with a
    /// humidity table it gives NaN, never a silently wrong value (callers
    /// with a height use [`AirField::index_at`]).
    #[inline]
    pub(crate) fn index_from(&self, t: T, grad_t: V3<T>, pressure: T, dp_dh: T) -> (T, V3<T>) {
        let (t, grad_t) = Self::held(t, grad_t);
        let (delta, d_dt, d_dp) = self.partials(t, pressure);
        let grad = V3::new(
            d_dt * grad_t.x,
            d_dt * grad_t.y + d_dp * dp_dh,
            d_dt * grad_t.z,
        );
        (delta, grad)
    }

    /// [`AirField::index_from`] at height `h`, where a humidity table is
    /// evaluated: the full last stage of [`IndexField::delta_gradient`].
    #[inline]
    pub(crate) fn index_at(&self, h: T, t: T, grad_t: V3<T>, pressure: T, dp_dh: T) -> (T, V3<T>) {
        let Moisture::Table(table) = &self.humidity else {
            return self.index_from(t, grad_t, pressure, dp_dh);
        };
        let (rh, drh_dh) = table.eval(h);
        let (t, grad_t) = Self::held(t, grad_t);
        let (delta, d_dt, d_dp) = self.partials_with(t, pressure, rh);
        let d_drh = match self.formula {
            Formula::GladstoneDale(_) => T::cst(0.0),
            formula => humidity_partial(formula, &self.state(t, pressure, rh)),
        };
        let grad = V3::new(
            d_dt * grad_t.x,
            d_dt * grad_t.y + d_dp * dp_dh + d_drh * drh_dh,
            d_dt * grad_t.z,
        );
        (delta, grad)
    }

    /// (δ, ∂δ/∂T, ∂δ/∂P) of the formula at temperature `t` (K, inside the
    /// held range) and `pressure`, with the one humidity (NaN with a
    /// humidity table, which needs the height: [`AirField::index_at`]).
    #[inline]
    pub(crate) fn partials(&self, t: T, pressure: T) -> (T, T, T) {
        let rh = match &self.humidity {
            Moisture::Constant(rh) => *rh,
            Moisture::Table(_) => T::cst(f64::NAN),
        };
        self.partials_with(t, pressure, rh)
    }

    /// The state of the air the formulas take.
    #[inline]
    fn state(&self, t: T, pressure: T, rh: T) -> AirState<T> {
        AirState {
            celsius: t - KELVIN,
            pressure,
            humidity: rh,
            wavelength_nm: self.wavelength,
            co2_ppm: self.co2,
        }
    }

    /// (δ, ∂δ/∂T, ∂δ/∂P) at `t` (K), `pressure` and relative humidity `rh`.
    #[inline]
    fn partials_with(&self, t: T, pressure: T, rh: T) -> (T, T, T) {
        match self.formula {
            // δ = K·(P/P₀)/T: its partials in closed form (the tracer's hot
            // path for the many mirage papers that use this law).
            Formula::GladstoneDale(k) => {
                let inv_t = t.recip();
                let d_dp = k * (1.0 / STANDARD_PRESSURE) * inv_t;
                let d = d_dp * pressure;
                (d, -(d * inv_t), d_dp)
            }
            formula => refractivity_partials(formula, &self.state(t, pressure, rh)),
        }
    }

    /// The pressure (Pa) and its height derivative at h, where the uniform
    /// temperature is `kelvin_u` (K): [`AirField::pressure`] without
    /// evaluating the profile again.
    #[inline]
    pub(crate) fn pressure_with(&self, h: T, kelvin_u: T) -> (T, T) {
        match &self.pressure {
            Pressure::Constant(p) => (*p, T::cst(0.0)),
            Pressure::Hydrostatic(table) => table.eval(h, kelvin_u),
        }
    }
}

impl<T: Real> AirField<T> {
    /// δ and ∇δ by the formula, never the compiled profile.
    #[inline]
    pub fn formula_delta_gradient(&self, p: V3<T>) -> (T, V3<T>) {
        let (t, grad_t) = self.kelvin(p);
        let (pressure, dp_dh) = self.pressure(p.y);
        self.index_at(p.y, t, grad_t, pressure, dp_dh)
    }
}

impl<T: Real> IndexField<T> for AirField<T> {
    #[inline]
    fn delta_gradient(&self, p: V3<T>) -> (T, V3<T>) {
        // Only `f64` air has a profile: T is f64 here, and `cst` exact.
        if let Some(c) = &self.compiled
            && let Some((d, g)) = c.eval(p.y.val())
        {
            let z = T::cst(0.0);
            return (T::cst(d), V3::new(z, T::cst(g), z));
        }
        self.formula_delta_gradient(p)
    }

    fn is_stratified(&self) -> bool {
        self.hotspots.is_empty()
    }

    fn ceiling(&self) -> f64 {
        self.ceiling
    }

    fn step_limit(&self, y: f64, vy: f64) -> f64 {
        // Heading for a zone from outside: reach it, and a few scales into it;
        // inside one, at most a few scales a step toward its core (a surface
        // layer's core is the ground: rising out of it is not limited).
        let mut cap = f64::INFINITY;
        for &(lo, hi, s) in &self.zones {
            let reach = ZONE_STEP_SCALES * s;
            let limit = if y > hi && vy < 0.0 {
                (y - hi + reach) / -vy
            } else if y < lo && vy > 0.0 {
                (lo - y + reach) / vy
            } else if (lo..=hi).contains(&y) && (lo.is_finite() || vy < 0.0) {
                reach / vy.abs()
            } else {
                continue;
            };
            cap = cap.min(limit);
        }
        cap
    }
}

/// The analytic part of the uniform profile, as the lanes kernels evaluate
/// it: base (K), lapse, surface layer (δT, 1/H), step aloft (δT, height,
/// 1/thickness).
#[derive(Clone, Copy, Debug)]
pub(crate) struct UniformTerms {
    pub kelvin0: f64,
    pub lapse: Option<Lapse<f64>>,
    pub exponential: Option<(f64, f64)>,
    pub inversion: Option<(f64, f64, f64)>,
}

/// Real air as plain numbers for the lanes kernels (`trace::batch::air`):
/// what has a vector form there, and `None` where the kernels call the
/// scalar stage per lane instead.
#[derive(Clone, Debug)]
pub(crate) struct LaneTerms {
    /// The analytic uniform profile; `None` for a table.
    pub uniform: Option<UniformTerms>,
    /// Hot spots `[x, z, radius, edge, δT, 1/H]`.
    pub hotspots: Vec<[f64; 6]>,
    /// The pressure when it is constant; `None` when hydrostatic.
    pub constant_pressure: Option<f64>,
    /// K of the Gladstone–Dale law; `None` for Ciddor and Edlén.
    pub gladstone_dale: Option<f64>,
    /// The thin layers' zones `(lo, hi, scale)` of [`AirField::step_limit`].
    pub zones: Vec<(f64, f64, f64)>,
    /// How many scales of height a step may cover inside a zone.
    pub zone_step_scales: f64,
}

impl AirField<f64> {
    /// This air as the lanes kernels evaluate it.
    pub(crate) fn lane_terms(&self) -> LaneTerms {
        let uniform = match &self.profile {
            Profile::Terms {
                kelvin0,
                lapse,
                exponential,
                inversion,
            } => Some(UniformTerms {
                kelvin0: *kelvin0,
                lapse: *lapse,
                exponential: *exponential,
                inversion: *inversion,
            }),
            Profile::Table(_) => None,
        };
        LaneTerms {
            uniform,
            hotspots: self
                .hotspots
                .iter()
                .map(|h| [h.x, h.z, h.radius, h.edge, h.delta, h.inv_scale])
                .collect(),
            constant_pressure: match &self.pressure {
                Pressure::Constant(p) => Some(*p),
                Pressure::Hydrostatic(_) => None,
            },
            gladstone_dale: match self.formula {
                Formula::GladstoneDale(k) => Some(k),
                _ => None,
            },
            zones: self.zones.clone(),
            zone_step_scales: ZONE_STEP_SCALES,
        }
    }
}

/// The compiled profile of `field` (see [`AirField::profile`]): `None` for
/// dual numbers and for air with hot spots. It covers the hydrostatic
/// table's bottom up to the top of the described air or the ceiling,
/// whichever is lower, with knots where the formula is not smooth: the
/// ground, the table's ends, the US 1976 layers' kinks and the rows of the
/// temperature and humidity tables.
fn compile<T: Real>(field: &AirField<T>, m: &AirMedium<T>) -> Option<CompiledProfile> {
    let air = (field as &dyn std::any::Any).downcast_ref::<AirField<f64>>()?;
    if !air.hotspots.is_empty() {
        return None;
    }
    let t = &m.air.temperature;
    let mut breaks = vec![0.0, TABLE_BOTTOM, air.top];
    if let Some(Lapse::Standard) = t.lapse {
        breaks.extend(US1976_BREAKS);
    }
    if let Some(rows) = &t.table {
        breaks.extend(rows.iter().map(|r| r[0].val()));
    }
    if let Some(rows) = m.air.humidity.table() {
        breaks.extend(rows.iter().map(|r| r[0].val()));
    }
    let hi = air.top.min(air.ceiling);
    breaks.extend(freezing_heights(air, TABLE_BOTTOM, hi));
    Some(CompiledProfile::compile(TABLE_BOTTOM, hi, &breaks, |h| {
        let (d, g) = air.formula_delta_gradient(V3::new(0.0, h, 0.0));
        (d, g.y)
    }))
}

/// The heights in [lo, hi] where the air's temperature crosses 0 °C: the
/// saturation vapour pressure switches there from water to ice
/// (`humidity.rs`), a small step in δ that a compiled piece must not span.
/// Sampled every 5 m, each sign change bisected to the last bit; a layer
/// thinner than 5 m that dips below 0 °C and back is left to the
/// compile's own bisection (its piece is then left to the formula).
fn freezing_heights(air: &AirField<f64>, lo: f64, hi: f64) -> Vec<f64> {
    let above = |h: f64| air.kelvin(V3::new(0.0, h, 0.0)).0 >= KELVIN;
    let mut out = Vec::new();
    if !(lo.is_finite() && hi.is_finite() && lo < hi) {
        return out;
    }
    let n = ((hi - lo) / 5.0).ceil().min(1e6) as usize;
    let mut a = lo;
    let mut sa = above(a);
    for k in 1..=n {
        let b = if k == n {
            hi
        } else {
            lo + (hi - lo) * k as f64 / n as f64
        };
        let sb = above(b);
        if sa != sb {
            let (mut x, mut y) = (a, b);
            for _ in 0..200 {
                let m = 0.5 * (x + y);
                if m <= x || m >= y {
                    break;
                }
                if above(m) == sa {
                    x = m;
                } else {
                    y = m;
                }
            }
            out.push(y);
        }
        (a, sa) = (b, sb);
    }
    out
}

/// The thin layers' zones (see [`AirField::step_limit`]).
fn zones<T: Real>(m: &AirMedium<T>) -> Vec<(f64, f64, f64)> {
    let t = &m.air.temperature;
    let mut out = Vec::new();
    if let Some(e) = t.exponential {
        let s = e.scale_height.val().abs();
        out.push((f64::NEG_INFINITY, ZONE_SCALES * s, s));
    }
    if let Some(i) = t.inversion {
        let (c, s) = (i.height.val(), i.thickness.val().abs());
        out.push((c - ZONE_SCALES * s, c + ZONE_SCALES * s, s));
    }
    if let Some(rows) = &t.table
        && let (Some(first), Some(last)) = (rows.first(), rows.last())
    {
        let gap = rows
            .windows(2)
            .map(|w| (w[1][0].val() - w[0][0].val()).abs())
            .fold(f64::INFINITY, f64::min);
        out.push((first[0].val() - gap, last[0].val() + gap, gap));
    }
    if let Some(rows) = m.air.humidity.table()
        && let (Some(first), Some(last)) = (rows.first(), rows.last())
    {
        let gap = rows
            .windows(2)
            .map(|w| (w[1][0].val() - w[0][0].val()).abs())
            .fold(f64::INFINITY, f64::min);
        out.push((first[0].val() - gap, last[0].val() + gap, gap));
    }
    for h in &m.hotspots {
        let s = h.scale_height.val().abs();
        out.push((f64::NEG_INFINITY, ZONE_SCALES * s, s));
    }
    out.retain(|(lo, hi, s)| !lo.is_nan() && hi.is_finite() && s.is_finite() && *s > 0.0);
    out
}

/// The profile's sharp features as (centre, scale) pairs, for the hydrostatic
/// table's node spacing.
pub(super) fn feature_scales<T: Real>(m: &AirMedium<T>) -> Vec<(f64, f64)> {
    let t = &m.air.temperature;
    let mut out = Vec::new();
    if let Some(Lapse::Standard) = t.lapse {
        // The layers' kinks become nodes, without refining the spacing.
        out.extend(US1976_BREAKS.iter().map(|&b| (b, 8.0 * MAX_SPACING)));
    }
    if let Some(e) = t.exponential {
        out.push((0.0, e.scale_height.val().abs()));
    }
    if let Some(i) = t.inversion {
        out.push((i.height.val(), i.thickness.val().abs()));
    }
    if let Some(rows) = &t.table {
        for w in rows.windows(2) {
            let gap = (w[1][0].val() - w[0][0].val()).abs();
            out.push((w[0][0].val(), gap.max(1e-3)));
        }
    }
    out.retain(|(c, s)| c.is_finite() && s.is_finite() && *s > 0.0);
    out
}

/// The top of the hydrostatic table: the US 1976 layers' top, above every
/// feature and table row.
fn table_top<T: Real>(m: &AirMedium<T>) -> f64 {
    let t = &m.air.temperature;
    let mut top = US1976_TOP;
    if let Some(i) = t.inversion {
        top = top.max(i.height.val() + 40.0 * i.thickness.val().abs());
    }
    if let Some(rows) = &t.table
        && let Some(last) = rows.last()
    {
        top = top.max(last[0].val());
    }
    if top.is_finite() { top } else { US1976_TOP }
}

/// The lowest height (m, ≥ 0) where the uniform profile with the coldest
/// hot-spot excesses falls below −150 °C, scanned every 50 m up to the table
/// top and then far beyond (a lapse keeps falling); infinite if never.
fn ceiling<T: Real>(profile: &Profile<T>, hotspots: &[HotTerm<T>]) -> f64 {
    let floor = COLDEST + KELVIN;
    let cold = |h: f64| -> f64 {
        let (tu, _) = profile.kelvin(T::cst(h));
        let spots: f64 = hotspots
            .iter()
            .map(|s| s.delta.val().min(0.0) * (-(h.max(0.0)) * s.inv_scale.val()).exp())
            .sum();
        tu.val() + spots
    };
    let mut h = 0.0;
    let mut step = 50.0;
    while h < 1e9 {
        let t = cold(h);
        if t.is_nan() || t < floor {
            // Refine between the last good height and this one.
            let (mut lo, mut hi) = ((h - step).max(0.0), h);
            if h == 0.0 {
                return 0.0;
            }
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if cold(mid) >= floor {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            return lo;
        }
        if h >= 100_000.0 {
            step = h;
        }
        h += step;
    }
    f64::INFINITY
}
