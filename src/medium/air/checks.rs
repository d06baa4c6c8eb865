//! Real air's rules (`docs/air.md`, "bad input"): the first violation, with
//! the path of its field relative to the medium.

use super::field::{AirField, COLDEST, HOTTEST, KELVIN};
use super::model::{AirMedium, Humidity, Lapse};
use super::refractivity::Formula;
use crate::error::FieldError;
use crate::math::V3;
use crate::medium::{AirParam, HotField, Param};

/// The wavelengths the formulas are used over (nm).
pub const WAVELENGTH_RANGE: (f64, f64) = (300.0, 1700.0);
/// The largest Gladstone–Dale constant (K): about 13× air's 0.079, so that
/// n − 1 stays below 0.01 for any temperature the checks allow (≥ −150 °C) at
/// a sea-level pressure. Beyond that no gas is air, and a constant of 10⁸
/// (found by fuzzing) made n ≈ 10⁵ and the tracer overflow.
pub const MAX_GLADSTONE_DALE: f64 = 1.0;
/// The highest pressure at the ground (Pa): 100 atmospheres, far beyond any
/// weather, where n − 1 is still below 0.1 by every formula.
pub const MAX_PRESSURE: f64 = 1.0e7;
/// The heights over which the profile must be air (m).
const CHECKED_TOP: f64 = 11_000.0;

/// A humidity table's rules: at least two rows, heights strictly
/// increasing, every relative humidity in [0, 1].
fn check_humidity_table(rows: &[[f64; 2]]) -> Result<(), FieldError> {
    let bad =
        |p: AirParam, message: String| Err(FieldError::new(Param::Air(p).to_string(), message));
    if rows.len() < 2 {
        return Err(FieldError::new(
            "air.humidity.table",
            format!(
                "a table needs at least two rows [height, relative humidity], got {}",
                rows.len()
            ),
        ));
    }
    for (i, w) in rows.windows(2).enumerate() {
        if w[1][0] <= w[0][0] {
            return bad(
                AirParam::HumidityTableHeight(i + 1),
                format!(
                    "the heights must be strictly increasing: row {} has {} m after {} m",
                    i + 1,
                    w[1][0],
                    w[0][0]
                ),
            );
        }
    }
    for (i, r) in rows.iter().enumerate() {
        if !(0.0..=1.0).contains(&r[1]) {
            return bad(
                AirParam::HumidityTableValue(i),
                format!(
                    "the relative humidity must lie in [0, 1] (0.2 is 20 %), got {}",
                    r[1]
                ),
            );
        }
    }
    Ok(())
}

impl AirMedium<f64> {
    /// Checks every rule; the first violation is returned with its path.
    pub fn validate(&self) -> Result<(), FieldError> {
        let bad = |p: Param, message: String| Err(FieldError::new(p.to_string(), message));
        for (p, v) in self.params() {
            if !v.is_finite() {
                return bad(p, format!("must be a finite number, got {v}"));
            }
        }
        let air = &self.air;
        let t = &air.temperature;
        if air.pressure > MAX_PRESSURE {
            return bad(
                Param::Air(AirParam::Pressure),
                format!(
                    "the pressure at the ground must be at most {MAX_PRESSURE} Pa (100 atmospheres), got {}",
                    air.pressure
                ),
            );
        }
        if air.pressure <= 0.0 {
            return bad(
                Param::Air(AirParam::Pressure),
                format!(
                    "the pressure at the ground must be > 0 Pa, got {}",
                    air.pressure
                ),
            );
        }
        match &air.humidity {
            Humidity::Constant(h) => {
                if !(0.0..=1.0).contains(h) {
                    return bad(
                        Param::Air(AirParam::Humidity),
                        format!("the relative humidity must lie in [0, 1] (0.2 is 20 %), got {h}"),
                    );
                }
            }
            Humidity::Table(rows) => check_humidity_table(rows)?,
        }
        let (lo, hi) = WAVELENGTH_RANGE;
        if !(lo..=hi).contains(&air.wavelength) {
            return bad(
                Param::Air(AirParam::Wavelength),
                format!(
                    "the vacuum wavelength must lie in {lo}…{hi} nm (the formulas' range), got {}",
                    air.wavelength
                ),
            );
        }
        if air.co2 < 0.0 {
            return bad(
                Param::Air(AirParam::Co2),
                format!("the CO₂ content must be ≥ 0 ppm, got {}", air.co2),
            );
        }
        if let Formula::GladstoneDale(k) = air.refractivity
            && !(0.0..=MAX_GLADSTONE_DALE).contains(&k)
        {
            return bad(
                Param::Air(AirParam::GladstoneDale),
                format!(
                    "the Gladstone–Dale constant must lie in [0, {MAX_GLADSTONE_DALE}] K (air's is about 0.079), got {k}"
                ),
            );
        }
        if let Some(e) = t.exponential
            && e.scale_height <= 0.0
        {
            return bad(
                Param::Air(AirParam::ExponentialScaleHeight),
                format!("a scale height must be > 0 m, got {}", e.scale_height),
            );
        }
        if let Some(i) = t.inversion
            && i.thickness <= 0.0
        {
            return bad(
                Param::Air(AirParam::InversionThickness),
                format!("a thickness must be > 0 m, got {}", i.thickness),
            );
        }
        if let Some(rows) = &t.table {
            let field = |s: &str| FieldError::new(format!("air.temperature.{s}"), String::new());
            if t.has_analytic_terms() {
                let named = [
                    (t.base.is_some(), "base"),
                    (t.lapse.is_some(), "lapse"),
                    (t.exponential.is_some(), "exponential"),
                    (t.inversion.is_some(), "inversion"),
                ]
                .into_iter()
                .filter(|(on, _)| *on)
                .map(|(_, n)| format!("`{n}`"))
                .collect::<Vec<_>>()
                .join(", ");
                return Err(FieldError {
                    message: format!(
                        "a table is the whole profile: remove {named}, or the table (hot spots may still be added)"
                    ),
                    ..field("table")
                });
            }
            if rows.len() < 2 {
                return Err(FieldError {
                    message: format!(
                        "a table needs at least two rows [height, temperature], got {}",
                        rows.len()
                    ),
                    ..field("table")
                });
            }
            for (i, w) in rows.windows(2).enumerate() {
                if w[1][0] <= w[0][0] {
                    return bad(
                        Param::Air(AirParam::TableHeight(i + 1)),
                        format!(
                            "the heights must be strictly increasing: row {} has {} m after {} m",
                            i + 1,
                            w[1][0],
                            w[0][0]
                        ),
                    );
                }
            }
            for (i, r) in rows.iter().enumerate() {
                if r[1] < COLDEST {
                    return bad(
                        Param::Air(AirParam::TableTemperature(i)),
                        format!(
                            "air colder than {COLDEST} °C is outside every formula, got {} °C",
                            r[1]
                        ),
                    );
                }
            }
        }
        for (j, h) in self.hotspots.iter().enumerate() {
            if h.radius < 0.0 {
                return bad(
                    Param::Hot(j, HotField::Radius),
                    format!("a radius must be ≥ 0, got {}", h.radius),
                );
            }
            if h.edge <= 0.0 {
                return bad(
                    Param::Hot(j, HotField::Edge),
                    format!("the rim sharpness must be > 0 (1/metre), got {}", h.edge),
                );
            }
            if h.scale_height <= 0.0 {
                return bad(
                    Param::Hot(j, HotField::ScaleHeight),
                    format!("a scale height must be > 0 m, got {}", h.scale_height),
                );
            }
        }
        self.check_profile()
    }

    /// The profile with the coldest hot-spot excesses must be air (≥ −150 °C)
    /// from the ground to 11 km, and not hotter than makes sense for air.
    fn check_profile(&self) -> Result<(), FieldError> {
        let field = AirField::new(self);
        let cold: f64 = self.hotspots.iter().map(|h| h.delta.min(0.0)).sum();
        let hot: f64 = self.hotspots.iter().map(|h| h.delta.max(0.0)).sum();
        let where_ = match (&self.air.temperature.table, self.air.temperature.lapse) {
            (Some(_), _) => "air.temperature.table",
            (None, Some(Lapse::Rate(_))) => "air.temperature.lapse",
            _ => "air.temperature",
        };
        let n = 2200;
        for i in 0..=n {
            let h = CHECKED_TOP * i as f64 / n as f64;
            let (tu, _) = field.uniform_kelvin(h);
            let coldest = tu - KELVIN + cold * if i == 0 { 1.0 } else { 0.0 };
            if coldest.is_nan() || coldest < COLDEST {
                return Err(FieldError::new(
                    where_,
                    format!(
                        "the air would be {coldest:.1} °C at {h:.0} m, colder than {COLDEST} °C (outside every formula; the profile must stay air from the ground to 11 km)"
                    ),
                ));
            }
            if i == 0 && tu - KELVIN + hot > HOTTEST {
                return Err(FieldError::new(
                    where_,
                    format!(
                        "the air would be {:.0} °C at the ground, hotter than {HOTTEST} °C: not air",
                        tu - KELVIN + hot
                    ),
                ));
            }
        }
        let (d, g) =
            crate::medium::IndexField::<f64>::delta_gradient(&field, V3::new(0.0, 0.0, 0.0));
        if !(d.is_finite() && g.y.is_finite()) {
            return Err(FieldError::new(
                "air",
                "this air gives no finite refractive index at the ground",
            ));
        }
        Ok(())
    }
}
