//! Parameter path names: one vocabulary for files, the fitter and the reports,
//! over every kind of medium (each kind answers only for its own paths).

use std::fmt;
use std::str::FromStr;

/// A field of a hot spot.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum HotField {
    /// Centre, x (metres).
    X,
    /// Centre, z (metres).
    Z,
    /// Radius (metres).
    Radius,
    /// Strength (amplitude).
    N,
    /// Vertical rate (metres).
    A,
    /// Rim sharpness (1/metre).
    Edge,
    /// Temperature excess at the ground (kelvins): real air's hot spots.
    Delta,
    /// Height over which the excess falls by 1/e (metres): real air's hot spots.
    ScaleHeight,
}

impl HotField {
    /// The fields of a logistic hot spot, in the order parameters are listed.
    pub const LOGISTIC: [HotField; 6] = [
        HotField::X,
        HotField::Z,
        HotField::Radius,
        HotField::N,
        HotField::A,
        HotField::Edge,
    ];

    /// The fields of a real-air hot spot, in the order parameters are listed.
    pub const AIR: [HotField; 6] = [
        HotField::X,
        HotField::Z,
        HotField::Radius,
        HotField::Edge,
        HotField::Delta,
        HotField::ScaleHeight,
    ];

    /// Every field of either kind (for parsing names).
    pub const ALL: [HotField; 8] = [
        HotField::X,
        HotField::Z,
        HotField::Radius,
        HotField::N,
        HotField::A,
        HotField::Edge,
        HotField::Delta,
        HotField::ScaleHeight,
    ];

    /// The name used in files.
    pub fn name(self) -> &'static str {
        match self {
            HotField::X => "x",
            HotField::Z => "z",
            HotField::Radius => "radius",
            HotField::N => "n",
            HotField::A => "a",
            HotField::Edge => "edge",
            HotField::Delta => "delta",
            HotField::ScaleHeight => "scale_height",
        }
    }
}

/// A parameter of a medium, addressed by its path name.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Param {
    /// `scale`: k_s.
    Scale,
    /// `background.n`.
    BackgroundN,
    /// `background.a`.
    BackgroundA,
    /// `inversion.n`.
    InversionN,
    /// `inversion.a`.
    InversionA,
    /// `inversion.height`.
    InversionHeight,
    /// `hotspots[j].<field>`.
    Hot(usize, HotField),
    /// `linear_square.n0`: n at y = 0 of the analytic n²-linear kind.
    LinearN0,
    /// `linear_square.g`: d(n²)/dy of the analytic n²-linear kind (per metre).
    LinearG,
    /// `air.…`: a parameter of real air (`docs/air.md`).
    Air(AirParam),
}

/// A parameter of real air's `air` section, by its path below `air.`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum AirParam {
    /// `temperature.base` (°C).
    Base,
    /// `temperature.lapse` (K/m), when it is a number.
    Lapse,
    /// `temperature.exponential.delta` (K).
    ExponentialDelta,
    /// `temperature.exponential.scale_height` (m).
    ExponentialScaleHeight,
    /// `temperature.inversion.delta` (K).
    InversionDelta,
    /// `temperature.inversion.height` (m).
    InversionHeight,
    /// `temperature.inversion.thickness` (m).
    InversionThickness,
    /// `temperature.table[i][0]`: the height of row i (m).
    TableHeight(usize),
    /// `temperature.table[i][1]`: the temperature of row i (°C).
    TableTemperature(usize),
    /// `pressure` (Pa at h = 0).
    Pressure,
    /// `humidity` (relative, 0…1), when it is one number.
    Humidity,
    /// `humidity.table[i][0]`: the height of row i of a humidity table (m).
    HumidityTableHeight(usize),
    /// `humidity.table[i][1]`: the relative humidity of row i (0…1).
    HumidityTableValue(usize),
    /// `wavelength` (nm, vacuum).
    Wavelength,
    /// `co2` (ppm by mole).
    Co2,
    /// `refractivity.gladstone_dale`: K of n − 1 = K·(P/101325 Pa)/T (kelvins).
    GladstoneDale,
}

impl AirParam {
    /// The fixed names (every one but the tables').
    const NAMED: [(AirParam, &'static str); 12] = [
        (AirParam::Base, "temperature.base"),
        (AirParam::Lapse, "temperature.lapse"),
        (AirParam::ExponentialDelta, "temperature.exponential.delta"),
        (
            AirParam::ExponentialScaleHeight,
            "temperature.exponential.scale_height",
        ),
        (AirParam::InversionDelta, "temperature.inversion.delta"),
        (AirParam::InversionHeight, "temperature.inversion.height"),
        (
            AirParam::InversionThickness,
            "temperature.inversion.thickness",
        ),
        (AirParam::Pressure, "pressure"),
        (AirParam::Humidity, "humidity"),
        (AirParam::Wavelength, "wavelength"),
        (AirParam::Co2, "co2"),
        (AirParam::GladstoneDale, "refractivity.gladstone_dale"),
    ];
}

impl fmt::Display for AirParam {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            AirParam::TableHeight(i) => write!(f, "temperature.table[{i}][0]"),
            AirParam::TableTemperature(i) => write!(f, "temperature.table[{i}][1]"),
            AirParam::HumidityTableHeight(i) => write!(f, "humidity.table[{i}][0]"),
            AirParam::HumidityTableValue(i) => write!(f, "humidity.table[{i}][1]"),
            named => {
                let name = AirParam::NAMED
                    .iter()
                    .find(|(p, _)| p == named)
                    .map(|(_, n)| *n)
                    .unwrap_or("?");
                f.write_str(name)
            }
        }
    }
}

impl FromStr for AirParam {
    type Err = ();

    /// Parses the part after `air.`.
    fn from_str(s: &str) -> Result<Self, ()> {
        if let Some((p, _)) = AirParam::NAMED.iter().find(|(_, n)| *n == s) {
            return Ok(*p);
        }
        let (rest, humidity) = match s.strip_prefix("temperature.table[") {
            Some(rest) => (rest, false),
            None => (s.strip_prefix("humidity.table[").ok_or(())?, true),
        };
        let (index, column) = rest.split_once("][").ok_or(())?;
        if index.is_empty() || !index.bytes().all(|b| b.is_ascii_digit()) {
            return Err(());
        }
        let i: usize = index.parse().map_err(|_| ())?;
        match (column, humidity) {
            ("0]", false) => Ok(AirParam::TableHeight(i)),
            ("1]", false) => Ok(AirParam::TableTemperature(i)),
            ("0]", true) => Ok(AirParam::HumidityTableHeight(i)),
            ("1]", true) => Ok(AirParam::HumidityTableValue(i)),
            _ => Err(()),
        }
    }
}

impl Param {
    /// Whether this parameter is an amplitude (n_bg, n_inv, n_hot_j): the
    /// amplitudes share the model's gauge freedom.
    pub fn is_amplitude(self) -> bool {
        matches!(
            self,
            Param::BackgroundN | Param::InversionN | Param::Hot(_, HotField::N)
        )
    }
}

impl fmt::Display for Param {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Param::Scale => f.write_str("scale"),
            Param::BackgroundN => f.write_str("background.n"),
            Param::BackgroundA => f.write_str("background.a"),
            Param::InversionN => f.write_str("inversion.n"),
            Param::InversionA => f.write_str("inversion.a"),
            Param::InversionHeight => f.write_str("inversion.height"),
            Param::Hot(j, field) => write!(f, "hotspots[{j}].{}", field.name()),
            Param::LinearN0 => f.write_str("linear_square.n0"),
            Param::LinearG => f.write_str("linear_square.g"),
            Param::Air(a) => write!(f, "air.{a}"),
        }
    }
}

/// A name that is not the path of any parameter of the model.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "`{0}` is not a parameter name (expected e.g. `scale`, `background.a`, `inversion.height`, `hotspots[0].radius`, `air.temperature.exponential.delta`, `hotspots[0].delta`)"
)]
pub struct ParamParseError(pub String);

impl FromStr for Param {
    type Err = ParamParseError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let err = || ParamParseError(s.to_string());
        Ok(match s {
            "scale" => Param::Scale,
            "background.n" => Param::BackgroundN,
            "background.a" => Param::BackgroundA,
            "inversion.n" => Param::InversionN,
            "inversion.a" => Param::InversionA,
            "inversion.height" => Param::InversionHeight,
            "linear_square.n0" => Param::LinearN0,
            "linear_square.g" => Param::LinearG,
            _ if s.starts_with("air.") => {
                Param::Air(s["air.".len()..].parse().map_err(|()| err())?)
            }
            _ => {
                let rest = s.strip_prefix("hotspots[").ok_or_else(err)?;
                let (index, field) = rest.split_once("].").ok_or_else(err)?;
                if index.is_empty() || !index.bytes().all(|b| b.is_ascii_digit()) {
                    return Err(err());
                }
                let j: usize = index.parse().map_err(|_| err())?;
                let field = HotField::ALL
                    .into_iter()
                    .find(|f| f.name() == field)
                    .ok_or_else(err)?;
                Param::Hot(j, field)
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        let mut all = vec![
            Param::Scale,
            Param::BackgroundN,
            Param::BackgroundA,
            Param::InversionN,
            Param::InversionA,
            Param::InversionHeight,
            Param::LinearN0,
            Param::LinearG,
        ];
        all.extend(HotField::ALL.map(|f| Param::Hot(12, f)));
        all.extend(AirParam::NAMED.map(|(a, _)| Param::Air(a)));
        all.push(Param::Air(AirParam::TableHeight(3)));
        all.push(Param::Air(AirParam::TableTemperature(17)));
        all.push(Param::Air(AirParam::HumidityTableHeight(0)));
        all.push(Param::Air(AirParam::HumidityTableValue(5)));
        for p in all {
            assert_eq!(p.to_string().parse::<Param>(), Ok(p));
        }
    }

    #[test]
    fn malformed_names_are_rejected() {
        for bad in [
            "",
            "Scale",
            "inversion.heigth",
            "hotspots[].x",
            "hotspots[-1].x",
            "hotspots[0]x",
            "hotspots[0].colour",
            "hotspots[+1].x",
            "hotspots[99999999999999999999999].x",
            "air.",
            "air.temperature",
            "air.temperature.table[1][2]",
            "air.temperature.table[][1]",
            "air.temperature.table[1]",
            "air.humidity.table[1][2]",
            "air.humidity.table[x][0]",
            "air.humidity.table",
            "air.Pressure",
        ] {
            assert!(bad.parse::<Param>().is_err(), "{bad:?} accepted");
        }
    }
}
