//! Refraction near the horizon (`mirage refraction`, `docs/air.md`): the
//! astronomical refraction against apparent elevation for an observer at any
//! height over the round earth, the dip of the apparent horizon, and the
//! terrestrial refraction coefficient k.
//!
//! # Algorithm
//!
//! The observer stands at (0, H, 0) over the sphere of radius R centred at
//! (0, −R, 0) (`trace::Earth::Round`); the medium is taken at heights above
//! the sphere, exactly (no earth flattening). A ray leaves the observer at
//! apparent elevation e (degrees, negative allowed) along (0, sin e, cos e)
//! and is traced by Dormand–Prince 5(4) (local error [`TOLERANCE`] in metres
//! and in the direction, with the medium's own step caps) until
//!
//! - it rises past the **top** of the atmosphere ([`AirField::top`]: 86 km for
//!   the US 1976 layers, higher when a table or an inversion reaches higher;
//!   or the medium's ceiling, where its air would be colder than −150 °C, if
//!   that is lower). A star is at infinity, so what counts is the direction
//!   the ray leaves in: its true elevation is the angle of that unit vector
//!   above the *observer's* horizontal plane, atan2(d_y, √(d_x² + d_z²)), and
//!   the refraction is e minus it. The ray is stopped at the end of the step
//!   that crosses the top; above 86 km n − 1 < 2·10⁻⁸·e^(−h/6 km), which
//!   bends a ray by less than 10⁻⁴′ more.
//! - or it meets the sphere: no refraction value, `hits_ground`.
//! - or neither within [`max_path`] (a ray trapped in a duct, or an
//!   integrator that gave up): `trapped`, no value.
//!
//! The **dip** of the apparent horizon is minus the lowest apparent elevation
//! whose ray does not meet the sphere: the grazing ray, found by bisection
//! on "meets the ground" (which the tracer decides on the quintic Hermite
//! interpolant of each step, its lowest point located to rounding) down to
//! [`DIP_RESOLUTION`] radians. The bracket starts at [−(geometric dip +
//! 10⁻³), 0] and is widened (down by doubling, up by 10⁻³ rad steps to 0.1
//! rad) until its lower end hits and its upper end does not. It assumes the
//! answer is monotone in e (true without a duct below the observer). With no
//! refraction (n − 1 = 0 everywhere) the rays are straight, the
//! Dormand–Prince steps are exact and the dip is acos(R/(R + H)) to the
//! bisection's resolution.
//!
//! **k** is the curvature of a horizontal ray at the observer times R:
//! κ = |∇n × t|/n, so for a horizontal ray k = −R·(∂δ/∂h)/(1 + δ), from the
//! medium's analytic gradient. `k_traced` measures it: a horizontal ray
//! traced over [`K_PATH`] metres at tolerance 10⁻¹² turns down by β, and
//! k = R·β/s (its arc length s); the two agree to the change of the
//! curvature over the first few centimetres of rise (about 10⁻⁴ relative in
//! the standard atmosphere).
//!
//! # Accuracy
//!
//! The refraction of a row is accurate to the integration (local error
//! 10⁻⁹ per step over a few hundred steps: about 10⁻⁷ rad, 3·10⁻⁴′, at
//! worst). Against Bennett's formula ([`bennett_arcmin`]), itself within
//! 0.07′ of Garfinkel's, the US 1976 atmosphere (15 °C, 101 325 Pa, dry,
//! 550 nm) is within 0.1′ at 5° and 10° (0.077′, 0.092′ below it) and gives
//! 33.0′ at the horizon against Bennett's 34.0′: high up any layered air
//! refracts by (n₀ − 1)·cot e, and Bennett's constant implies an n₀ − 1
//! about 3 % above Ciddor's at 550 nm (the repository's README, "Refraction near the
//! horizon"). Without refraction the dip is acos(R/(R + H)) to 10⁻⁹ rad
//! (`tests/refraction.rs`).

use crate::error::FieldError;
use crate::math::V3;
use crate::medium::IndexField;
use crate::medium::air::{AirField, AirMedium, KELVIN};
use crate::trace::{Earth, End, GroundMode, Method, TraceOptions, trace};
use serde::Serialize;

/// The local error bound of each Dormand–Prince step (metres, and
/// dimensionless in the direction).
pub const TOLERANCE: f64 = 1e-9;
/// The dip's bisection stops when its bracket is this narrow (radians,
/// 3.4·10⁻⁸ arcminutes).
pub const DIP_RESOLUTION: f64 = 1e-11;
/// The path over which `k_traced` is measured (m).
pub const K_PATH: f64 = 1000.0;
/// Radians per arcminute.
const ARCMIN: f64 = std::f64::consts::PI / (180.0 * 60.0);

/// One apparent elevation and what its ray does.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RefractionRow {
    /// The apparent elevation (degrees above the observer's horizontal).
    pub elevation_deg: f64,
    /// Apparent minus true elevation (arcminutes); `null` when the ray does
    /// not leave the atmosphere.
    pub refraction_arcmin: Option<f64>,
    /// The true elevation of the star seen there (degrees); `null` likewise.
    pub true_elevation_deg: Option<f64>,
    /// The ray meets the ground.
    pub hits_ground: bool,
    /// The ray neither left the air nor met the ground within the longest
    /// path (trapped in a duct, or the integrator gave up).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub trapped: bool,
    /// Bennett's formula at this elevation with the observer's pressure and
    /// temperature ([`bennett_arcmin`]); only for 0° ≤ e ≤ 90°, its range.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bennett_arcmin: Option<f64>,
}

/// What `mirage refraction` reports (`docs/air.md`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Refraction {
    /// The observer's height above the ground (m).
    pub height: f64,
    /// The earth's radius (m).
    pub earth_radius: f64,
    /// Where the rays leave the atmosphere (m above the ground).
    pub top: f64,
    /// One row per apparent elevation, in the order asked.
    pub rows: Vec<RefractionRow>,
    /// The dip of the apparent horizon (arcminutes below the horizontal;
    /// negative when the horizon is raised above it); `null` when no ray up
    /// to 0.1 rad clears the ground.
    pub dip_arcmin: Option<f64>,
    /// The geometric dip acos(R/(R + H)) (arcminutes), for comparison.
    pub geometric_dip_arcmin: f64,
    /// The terrestrial refraction coefficient at the observer: a horizontal
    /// ray's curvature times R, from the medium's gradient.
    pub k: f64,
    /// k measured on a traced horizontal ray over [`K_PATH`] metres.
    pub k_traced: f64,
    /// The air's pressure at the observer (Pa), for Bennett's factor; absent
    /// for a medium that is not real air.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pressure_pa: Option<f64>,
    /// The air's temperature at the observer (°C), likewise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub temperature_c: Option<f64>,
}

/// Bennett's (1982) refraction for apparent elevation `e_deg` (degrees, for
/// 0…90°) in arcminutes: R = cot(e + 7.31/(e + 4.4)), the argument in
/// degrees, for 101.0 kPa and 10 °C, scaled by (P/101.0 kPa)·(283/(273 + T))
/// for pressure P and temperature T (°C). Within 0.07′ of Garfinkel's
/// (1967) algorithm over 0…90° (Bennett, G. G. 1982, "The calculation of
/// astronomical refraction in marine navigation", Journal of Navigation 35,
/// 255–259; the pressure and temperature factor as in J. Meeus, *Astronomical
/// Algorithms*, 1991, ch. 15, pp. 102–103).
pub fn bennett_arcmin(e_deg: f64, pressure_pa: f64, celsius: f64) -> f64 {
    let cot = 1.0 / (e_deg + 7.31 / (e_deg + 4.4)).to_radians().tan();
    cot * (pressure_pa / 101_000.0) * (283.0 / (273.0 + celsius))
}

/// The geometric dip of the horizon from height `height` over a sphere of
/// radius `radius` (radians): acos(R/(R + H)), computed as
/// 2·asin(√(H/(2(R + H)))) to keep its digits for small H.
pub fn geometric_dip(height: f64, radius: f64) -> f64 {
    2.0 * (0.5 * height / (radius + height)).sqrt().asin()
}

/// The longest path a ray from `height` is traced (m): four times the
/// longest straight path from the observer out of a shell `top` thick
/// around a sphere of radius `radius` (down to a grazing point and up).
pub fn max_path(height: f64, radius: f64, top: f64) -> f64 {
    let tangent = |h: f64| (h * (2.0 * radius + h)).sqrt();
    4.0 * (tangent(top) + tangent(height) + top)
}

/// A medium with its ceiling lowered to the top of the atmosphere, so that
/// the tracer ends a rising ray there (`End::LeftAir`).
struct Capped<'a, F: ?Sized> {
    field: &'a F,
    top: f64,
}

impl<F: IndexField + ?Sized> IndexField for Capped<'_, F> {
    fn delta_gradient(&self, p: V3) -> (f64, V3) {
        self.field.delta_gradient(p)
    }
    fn is_stratified(&self) -> bool {
        self.field.is_stratified()
    }
    fn ceiling(&self) -> f64 {
        self.field.ceiling().min(self.top)
    }
    fn step_limit(&self, h: f64, vh: f64) -> f64 {
        self.field.step_limit(h, vh)
    }
}

/// Where a ray from the observer goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fate {
    /// It leaves the atmosphere at this true elevation (radians).
    Out(f64),
    /// It meets the ground.
    Ground,
    /// Neither, within [`max_path`].
    Trapped,
}

/// An observer over the round earth in a medium, with the top of its
/// atmosphere: the rays of [`Refraction`].
pub struct Observer<'a, F: ?Sized> {
    field: Capped<'a, F>,
    height: f64,
    radius: f64,
    top: f64,
}

impl<'a, F: IndexField + ?Sized> Observer<'a, F> {
    /// An observer `height` metres above the sphere of `radius` metres in
    /// `field` (heights as the medium's y), whose atmosphere ends at `top`
    /// (or at the medium's ceiling if lower). Errors name the argument:
    /// `height` below 0, at or above the top, or not finite; `radius` below
    /// [`crate::trace::earth::MIN_RADIUS`]; `top` not finite or ≤ 0.
    pub fn new(field: &'a F, height: f64, radius: f64, top: f64) -> Result<Self, FieldError> {
        crate::trace::EarthSpec { radius }.validate()?;
        let top = top.min(field.ceiling());
        if !top.is_finite() || top <= 0.0 {
            return Err(FieldError::new(
                "top",
                format!("the atmosphere must end at a finite height > 0 m, got {top}"),
            ));
        }
        if !height.is_finite() || height < 0.0 {
            return Err(FieldError::new(
                "height",
                format!("must be a height ≥ 0 m above the ground, got {height}"),
            ));
        }
        if height >= top {
            return Err(FieldError::new(
                "height",
                format!("must be below the top of the atmosphere ({top} m), got {height}"),
            ));
        }
        Ok(Observer {
            field: Capped { field, top },
            height,
            radius,
            top,
        })
    }

    /// The top of the atmosphere the rays leave at (m).
    pub fn top(&self) -> f64 {
        self.top
    }

    fn options(&self, tolerance: f64, max_length: f64) -> TraceOptions {
        TraceOptions {
            method: Method::Dopri5 { tolerance },
            max_length: Some(max_length),
            ground: GroundMode::Stop,
            max_steps: 1_000_000,
            earth: Earth::Round {
                radius: self.radius,
            },
        }
    }

    /// Traces the ray at apparent elevation `e` (radians) at `tolerance`.
    pub fn fate_at(&self, e: f64, tolerance: f64) -> Fate {
        let origin = V3::new(0.0, self.height, 0.0);
        let direction = V3::new(0.0, e.sin(), e.cos());
        let options = self.options(tolerance, max_path(self.height, self.radius, self.top));
        let t = trace::<f64, _>(&self.field, origin, direction, None, &options, None);
        match t.end {
            End::LeftAir => {
                let d = t.direction;
                Fate::Out(d.y.atan2(d.x.hypot(d.z)))
            }
            End::Ground => Fate::Ground,
            _ => Fate::Trapped,
        }
    }

    /// The ray at apparent elevation `e_deg` (degrees) as a row (without
    /// Bennett's value).
    pub fn row(&self, e_deg: f64) -> RefractionRow {
        let fate = self.fate_at(e_deg.to_radians(), TOLERANCE);
        let out = match fate {
            Fate::Out(t) => Some(t),
            _ => None,
        };
        RefractionRow {
            elevation_deg: e_deg,
            refraction_arcmin: out.map(|t| (e_deg.to_radians() - t) / ARCMIN),
            true_elevation_deg: out.map(f64::to_degrees),
            hits_ground: fate == Fate::Ground,
            trapped: fate == Fate::Trapped,
            bennett_arcmin: None,
        }
    }

    fn hits(&self, e: f64) -> bool {
        self.fate_at(e, TOLERANCE) == Fate::Ground
    }

    /// The dip of the apparent horizon (radians below the horizontal), by
    /// bisection on the grazing ray (see the module documentation); `None`
    /// when no ray up to 0.1 rad clears the ground, or none down to −90°
    /// meets it.
    pub fn dip(&self) -> Option<f64> {
        let mut hi = 0.0;
        while self.hits(hi) {
            hi += 1e-3;
            if hi > 0.1 {
                return None;
            }
        }
        let half_pi = std::f64::consts::FRAC_PI_2;
        let mut lo = -(geometric_dip(self.height, self.radius) + 1e-3);
        while !self.hits(lo) {
            if lo <= -half_pi {
                return None;
            }
            lo = (2.0 * lo).max(-half_pi);
        }
        while hi - lo > DIP_RESOLUTION {
            let mid = 0.5 * (lo + hi);
            if self.hits(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(-0.5 * (lo + hi))
    }

    /// k from the medium's gradient at the observer: −R·(∂δ/∂h)/(1 + δ).
    pub fn k(&self) -> f64 {
        let (delta, grad) = self.field.delta_gradient(V3::new(0.0, self.height, 0.0));
        -self.radius * grad.y / (1.0 + delta)
    }

    /// k measured on a horizontal ray traced over [`K_PATH`] metres at
    /// tolerance 10⁻¹²: R times the angle it turns down by over its path.
    pub fn k_traced(&self) -> f64 {
        let origin = V3::new(0.0, self.height, 0.0);
        let mut options = self.options(1e-12, K_PATH);
        options.ground = GroundMode::Flag;
        let t = trace::<f64, _>(
            &self.field,
            origin,
            V3::new(0.0, 0.0, 1.0),
            None,
            &options,
            None,
        );
        let d = t.direction;
        let turn = -d.y.atan2(d.z);
        self.radius * turn / t.arc_length
    }

    /// Every row of `elevations_deg`, the dip and k. Errors name the
    /// elevation (`elevations[i]`) outside [−90°, 90°] or not finite.
    pub fn refraction(&self, elevations_deg: &[f64]) -> Result<Refraction, FieldError> {
        for (i, &e) in elevations_deg.iter().enumerate() {
            if !(-90.0..=90.0).contains(&e) {
                return Err(FieldError::new(
                    format!("elevations[{i}]"),
                    format!("an elevation must be within −90…90 degrees, got {e}"),
                ));
            }
        }
        Ok(Refraction {
            height: self.height,
            earth_radius: self.radius,
            top: self.top,
            rows: elevations_deg.iter().map(|&e| self.row(e)).collect(),
            dip_arcmin: self.dip().map(|d| d / ARCMIN),
            geometric_dip_arcmin: geometric_dip(self.height, self.radius) / ARCMIN,
            k: self.k(),
            k_traced: self.k_traced(),
            pressure_pa: None,
            temperature_c: None,
        })
    }
}

/// [`Observer::refraction`] through real air: the top is the air's
/// ([`AirField::top`]), and each row from 0° to 90° carries Bennett's value
/// with the air's pressure and temperature at the observer. Errors name
/// `height`, `radius` or `elevations[i]`.
pub fn air_refraction(
    medium: &AirMedium,
    height: f64,
    radius: f64,
    elevations_deg: &[f64],
) -> Result<Refraction, FieldError> {
    let field = AirField::new(medium);
    let observer = Observer::new(&field, height, radius, field.top())?;
    let mut r = observer.refraction(elevations_deg)?;
    let (pressure, _) = field.pressure(height);
    let (kelvin, _) = field.kelvin(V3::new(0.0, height, 0.0));
    let celsius = kelvin - KELVIN;
    for row in &mut r.rows {
        if (0.0..=90.0).contains(&row.elevation_deg) {
            row.bennett_arcmin = Some(bennett_arcmin(row.elevation_deg, pressure, celsius));
        }
    }
    r.pressure_pa = Some(pressure);
    r.temperature_c = Some(celsius);
    Ok(r)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bennett_matches_its_published_values() {
        // Meeus (1991), ch. 15: at the standard 101.0 kPa and 10 °C, R(0°)
        // = 34.5′ and R(90°) ≈ 0 (−0.08″); the factor is 1 there.
        let r0 = bennett_arcmin(0.0, 101_000.0, 10.0);
        assert!((r0 - 34.478).abs() < 1e-3, "{r0}");
        assert!(bennett_arcmin(90.0, 101_000.0, 10.0).abs() < 0.002);
        // 1 % more per 0.9 kPa more pressure, 1 % less per 3 K warmer, roughly.
        let p = bennett_arcmin(5.0, 101_900.0, 10.0) / bennett_arcmin(5.0, 101_000.0, 10.0);
        assert!((p - 1.0089).abs() < 1e-3, "{p}");
        let t = bennett_arcmin(5.0, 101_000.0, 13.0) / bennett_arcmin(5.0, 101_000.0, 10.0);
        assert!((t - 0.9896).abs() < 1e-3, "{t}");
    }

    #[test]
    fn the_geometric_dip_is_acos_without_cancellation() {
        let r = 6_371_000.0;
        for h in [1e-3, 2.0, 100.0, 1e5] {
            let d = geometric_dip(h, r);
            assert!((d.cos() - r / (r + h)).abs() < 1e-15, "{h}");
            // For small H, √(2H/R).
            if h < 10.0 {
                assert!((d / (2.0 * h / r).sqrt() - 1.0).abs() < 1e-6);
            }
        }
        assert_eq!(geometric_dip(0.0, r), 0.0);
    }
}
