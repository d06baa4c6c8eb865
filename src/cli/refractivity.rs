//! `mirage refractivity`: n − 1 of one state of the air (docs/air.md), printed
//! on a line of its own with 17 significant digits (enough to read the `f64`
//! back exactly). A state outside the range the formula is stated for is still
//! computed, with a warning on stderr; values no formula can take (humidity
//! outside [0, 1], a pressure ≤ 0, …) are refused by the flags' parsers.

use crate::error::{Result, ValueError};
use crate::medium::air::refractivity::{
    AirState, DEFAULT_CO2_PPM, Formula, STANDARD_PRESSURE, refractivity, validity,
};

/// Print n − 1 of air at a temperature, pressure, humidity and wavelength.
#[derive(Clone, Debug, PartialEq, clap::Args)]
pub struct RefractivityOptions {
    /// Air temperature, °C (−150 to 100).
    #[arg(long, default_value_t = 15.0, allow_negative_numbers = true, value_parser = temperature)]
    pub temperature: f64,
    /// Air pressure, Pa (> 0).
    #[arg(long, default_value_t = STANDARD_PRESSURE, allow_negative_numbers = true, value_parser = pressure)]
    pub pressure: f64,
    /// Relative humidity, a fraction from 0 to 1.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true, value_parser = humidity)]
    pub humidity: f64,
    /// Wavelength of the light in vacuum, nm (300 to 1700).
    #[arg(long, default_value_t = 550.0, allow_negative_numbers = true, value_parser = wavelength)]
    pub wavelength: f64,
    /// Carbon dioxide, ppm by mole (Ciddor only; Edlén assumes 450).
    #[arg(long, default_value_t = DEFAULT_CO2_PPM, allow_negative_numbers = true, value_parser = co2)]
    pub co2: f64,
    /// The formula: Ciddor 1996, or Edlén as modified by Birch and Downs.
    #[arg(long, value_enum, default_value_t)]
    pub formula: FormulaName,
}

/// The formulas by their command-line names.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum FormulaName {
    /// Ciddor 1996 (Applied Optics 35:1566), with CO₂.
    #[default]
    Ciddor,
    /// Edlén as modified by Birch and Downs, in NIST's form.
    Edlen,
}

impl FormulaName {
    /// The formula this name stands for.
    pub fn formula(self) -> Formula {
        match self {
            FormulaName::Ciddor => Formula::Ciddor,
            FormulaName::Edlen => Formula::Edlen,
        }
    }
}

/// Computes and prints n − 1; returns it.
pub fn run(o: &RefractivityOptions) -> Result<f64> {
    let formula = o.formula.formula();
    let air = AirState {
        celsius: o.temperature,
        pressure: o.pressure,
        humidity: o.humidity,
        wavelength_nm: o.wavelength,
        co2_ppm: o.co2,
    };
    if let Some(v) = validity(&formula) {
        for (flag, value, (lo, hi), unit) in [
            ("--temperature", o.temperature, v.celsius, "°C"),
            ("--pressure", o.pressure, v.pressure, "Pa"),
            ("--wavelength", o.wavelength, v.wavelength_nm, "nm"),
        ] {
            if !(lo..=hi).contains(&value) {
                eprintln!(
                    "warning: {flag} {value} is outside the range {formula:?} is stated for \
                     ({lo} to {hi} {unit}): extrapolated"
                );
            }
        }
    }
    let n1 = refractivity(formula, &air);
    println!("{n1:.16e}");
    Ok(n1)
}

/// A finite number, or why not.
fn number(s: &str) -> std::result::Result<f64, ValueError> {
    let v: f64 = s.trim().parse().map_err(|_| ValueError::NotANumber {
        value: s.to_string(),
    })?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(ValueError::OutOfRange {
            rule: format!("must be a finite number, got {v}"),
        })
    }
}

/// A number in [lo, hi], or the rule in words.
fn within(s: &str, lo: f64, hi: f64, unit: &str) -> std::result::Result<f64, ValueError> {
    match number(s)? {
        v if (lo..=hi).contains(&v) => Ok(v),
        v => Err(ValueError::OutOfRange {
            rule: format!("must be between {lo} and {hi}{unit}, got {v}"),
        }),
    }
}

/// `--temperature`: −150 to 100 °C (docs/air.md's coldest air; boiling water).
fn temperature(s: &str) -> std::result::Result<f64, ValueError> {
    within(s, -150.0, 100.0, " °C")
}

/// `--pressure`: a finite number of pascals > 0.
fn pressure(s: &str) -> std::result::Result<f64, ValueError> {
    match number(s)? {
        v if v > 0.0 => Ok(v),
        v => Err(ValueError::OutOfRange {
            rule: format!("must be a pressure > 0 Pa, got {v}"),
        }),
    }
}

/// `--humidity`: a relative humidity, 0 to 1.
fn humidity(s: &str) -> std::result::Result<f64, ValueError> {
    within(s, 0.0, 1.0, " (a fraction, not per cent)")
}

/// `--wavelength`: 300 to 1700 nm, the range of both formulas.
fn wavelength(s: &str) -> std::result::Result<f64, ValueError> {
    within(s, 300.0, 1700.0, " nm")
}

/// `--co2`: 0 to 10⁶ ppm (a mole fraction).
fn co2(s: &str) -> std::result::Result<f64, ValueError> {
    within(s, 0.0, 1e6, " ppm")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parsers_take_the_ranges_and_refuse_the_rest() {
        assert_eq!(temperature("-150"), Ok(-150.0));
        assert_eq!(temperature(" 20.5"), Ok(20.5));
        assert!(temperature("-150.01").is_err());
        assert!(temperature("nan").is_err());
        assert_eq!(
            temperature("warm").unwrap_err().to_string(),
            "not a number: `warm`"
        );
        assert!(pressure("0").is_err() && pressure("-1").is_err() && pressure("inf").is_err());
        assert_eq!(humidity("1"), Ok(1.0));
        assert_eq!(
            humidity("50").unwrap_err().to_string(),
            "must be between 0 and 1 (a fraction, not per cent), got 50"
        );
        assert!(wavelength("299.9").is_err() && wavelength("1700.1").is_err());
        assert!(co2("-1").is_err());
    }
}
