//! Real air's parameters as files hold them (`docs/air.md`): the `air`
//! section and its hot spots, with their defaults.

use super::refractivity::Formula;
use serde::de::{self, Deserializer, Visitor};
use serde::{Deserialize, Serialize, Serializer};
use std::fmt;

/// The pressure at h = 0 when a file gives none (Pa).
pub const DEFAULT_PRESSURE: f64 = 101_325.0;
/// The vacuum wavelength when a file gives none (nm).
pub const DEFAULT_WAVELENGTH: f64 = 550.0;
/// The carbon dioxide content when a file gives none (ppm by mole, as NIST's
/// calculator).
pub const DEFAULT_CO2: f64 = 450.0;
/// The temperature at h = 0 of analytic terms without a `base` (°C: the US
/// 1976 standard atmosphere's).
pub const DEFAULT_BASE: f64 = 15.0;

fn default_pressure<T: From<f64>>() -> T {
    T::from(DEFAULT_PRESSURE)
}
fn default_wavelength<T: From<f64>>() -> T {
    T::from(DEFAULT_WAVELENGTH)
}
fn default_co2<T: From<f64>>() -> T {
    T::from(DEFAULT_CO2)
}
fn default_edge<T: From<f64>>() -> T {
    T::from(10.0)
}
fn yes() -> bool {
    true
}
fn is_true(b: &bool) -> bool {
    *b
}

/// A real-air medium: the air and its hot spots.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(bound(serialize = "T: Serialize + Copy"))]
pub struct AirMedium<T = f64> {
    /// The air: temperature, pressure, humidity, wavelength, formula.
    pub air: Air<T>,
    /// Circular hot spots, in kelvins.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub hotspots: Vec<AirHotSpot<T>>,
}

/// The `air` section.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(
    deny_unknown_fields,
    bound(
        serialize = "T: Serialize + Copy",
        deserialize = "T: Deserialize<'de> + From<f64>"
    )
)]
pub struct Air<T = f64> {
    /// The horizontally uniform temperature profile.
    pub temperature: Temperature<T>,
    /// Pressure at h = 0 (Pa).
    #[serde(default = "default_pressure")]
    pub pressure: T,
    /// Whether the pressure falls hydrostatically with height (else constant).
    #[serde(default = "yes", skip_serializing_if = "is_true")]
    pub hydrostatic: bool,
    /// Relative humidity, 0…1: one number, or a measured table by height.
    #[serde(default)]
    pub humidity: Humidity<T>,
    /// Vacuum wavelength (nm).
    #[serde(default = "default_wavelength")]
    pub wavelength: T,
    /// Carbon dioxide (ppm by mole), used by Ciddor's formula.
    #[serde(default = "default_co2")]
    pub co2: T,
    /// The formula that turns the state of the air into n − 1.
    #[serde(default = "ciddor", with = "formula_file")]
    pub refractivity: Formula<T>,
}

fn ciddor<T>() -> Formula<T> {
    Formula::Ciddor
}

/// The file form of [`Formula`]: `"ciddor"`, `"edlen"` or
/// `{"gladstone_dale": K}` (serde's external tagging of this enum).
mod formula_file {
    use super::Formula;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    #[derive(Serialize, Deserialize)]
    #[serde(rename_all = "snake_case", deny_unknown_fields)]
    enum File<T> {
        Ciddor,
        Edlen,
        GladstoneDale(T),
    }

    pub fn serialize<T: Serialize + Copy, S: Serializer>(
        f: &Formula<T>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        match *f {
            Formula::Ciddor => File::<T>::Ciddor,
            Formula::Edlen => File::Edlen,
            Formula::GladstoneDale(k) => File::GladstoneDale(k),
        }
        .serialize(s)
    }

    pub fn deserialize<'de, T: Deserialize<'de>, D: Deserializer<'de>>(
        d: D,
    ) -> Result<Formula<T>, D::Error> {
        Ok(match File::<T>::deserialize(d)? {
            File::Ciddor => Formula::Ciddor,
            File::Edlen => Formula::Edlen,
            File::GladstoneDale(k) => Formula::GladstoneDale(k),
        })
    }
}

/// The `temperature` section: analytic terms, or a measured table. The file
/// form holds both kinds of field so that a mix is reported by name
/// (validation refuses `table` beside any analytic term).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(
    deny_unknown_fields,
    bound(deserialize = "T: Deserialize<'de> + From<f64>")
)]
pub struct Temperature<T = f64> {
    /// T at h = 0 (°C); absent: [`DEFAULT_BASE`] (with analytic terms).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub base: Option<T>,
    /// The lapse: a rate (K/m) or the US 1976 layers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lapse: Option<Lapse<T>>,
    /// A surface layer: δT·e^(−h/H).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub exponential: Option<Exponential<T>>,
    /// A step aloft: δT·σ((h − height)/thickness).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inversion: Option<Step<T>>,
    /// A measured profile: rows `[h (m), T (°C)]`, heights strictly increasing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub table: Option<Vec<[T; 2]>>,
}

impl<T> Temperature<T> {
    /// Whether any analytic term (base, lapse, exponential, inversion) is given.
    pub fn has_analytic_terms(&self) -> bool {
        self.base.is_some()
            || self.lapse.is_some()
            || self.exponential.is_some()
            || self.inversion.is_some()
    }
}

/// How T changes with height besides the named layers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lapse<T = f64> {
    /// dT/dh (K/m; the troposphere's is about −0.0065).
    Rate(T),
    /// The US Standard Atmosphere 1976 layers to 86 km, shifted so that the
    /// profile starts at `base`.
    Standard,
}

impl<T: Serialize> Serialize for Lapse<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Lapse::Rate(r) => r.serialize(s),
            Lapse::Standard => s.serialize_str("standard"),
        }
    }
}

impl<'de, T: From<f64>> Deserialize<'de> for Lapse<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(std::marker::PhantomData<T>);
        impl<T: From<f64>> Visitor<'_> for V<T> {
            type Value = Lapse<T>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a lapse rate in K/m (a number) or \"standard\" (the US 1976 layers)")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Self::Value, E> {
                Ok(Lapse::Rate(T::from(v)))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Self::Value, E> {
                Ok(Lapse::Rate(T::from(v as f64)))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Self::Value, E> {
                Ok(Lapse::Rate(T::from(v as f64)))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Self::Value, E> {
                if v == "standard" {
                    Ok(Lapse::Standard)
                } else {
                    Err(E::invalid_value(de::Unexpected::Str(v), &self))
                }
            }
        }
        d.deserialize_any(V(std::marker::PhantomData))
    }
}

/// The surface layer δT·e^(−h/H): a warm road (δT > 0) or a cold sea (δT < 0).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Exponential<T = f64> {
    /// The excess at the ground (K).
    pub delta: T,
    /// The height over which it falls by 1/e (m, > 0).
    pub scale_height: T,
}

/// The step aloft δT·σ((h − height)/thickness): an inversion when δT > 0.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Step<T = f64> {
    /// The rise across the step (K).
    pub delta: T,
    /// The height of its middle (m).
    pub height: T,
    /// Its thickness, the logistic's rate (m, > 0).
    pub thickness: T,
}

/// A hot spot of real air: δT·w(x, z)·e^(−h/H), with the rim w of
/// `docs/model.md`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(
    deny_unknown_fields,
    bound(deserialize = "T: Deserialize<'de> + From<f64>")
)]
pub struct AirHotSpot<T = f64> {
    /// Centre x (m).
    pub x: T,
    /// Centre z (m).
    pub z: T,
    /// Radius (m).
    pub radius: T,
    /// Rim sharpness (1/m, default 10).
    #[serde(default = "default_edge")]
    pub edge: T,
    /// The excess at the ground over the centre (K).
    pub delta: T,
    /// The height over which it falls by 1/e (m, > 0).
    pub scale_height: T,
}

/// The relative humidity (0…1): one number everywhere (the file's plain
/// number, default 0), or a measured profile `{"table": [[h, rh], ...]}`
/// interpolated by height as `temperature.table` is (the same
/// shape-preserving cubic, held beyond the end rows).
#[derive(Clone, Debug, PartialEq)]
pub enum Humidity<T = f64> {
    /// One relative humidity everywhere.
    Constant(T),
    /// Rows `[h (m), rh (0…1)]`, heights strictly increasing.
    Table(Vec<[T; 2]>),
}

impl<T: From<f64>> Default for Humidity<T> {
    fn default() -> Self {
        Humidity::Constant(T::from(0.0))
    }
}

impl<T> Humidity<T> {
    /// The table's rows, if this is a table.
    pub fn table(&self) -> Option<&[[T; 2]]> {
        match self {
            Humidity::Constant(_) => None,
            Humidity::Table(rows) => Some(rows),
        }
    }
}

impl<T: Serialize> Serialize for Humidity<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        match self {
            Humidity::Constant(v) => v.serialize(s),
            Humidity::Table(rows) => {
                let mut st = s.serialize_struct("Humidity", 1)?;
                st.serialize_field("table", rows)?;
                st.end()
            }
        }
    }
}

impl<'de, T: Deserialize<'de> + From<f64>> Deserialize<'de> for Humidity<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de> + From<f64>> Visitor<'de> for V<T> {
            type Value = Humidity<T>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(
                    "a relative humidity 0…1 (a number) or {\"table\": [[height, humidity], ...]}",
                )
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Self::Value, E> {
                Ok(Humidity::Constant(T::from(v)))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Self::Value, E> {
                Ok(Humidity::Constant(T::from(v as f64)))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Self::Value, E> {
                Ok(Humidity::Constant(T::from(v as f64)))
            }
            fn visit_map<A: de::MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
                let mut rows: Option<Vec<[T; 2]>> = None;
                while let Some(key) = map.next_key::<String>()? {
                    match key.as_str() {
                        "table" if rows.is_none() => rows = Some(map.next_value()?),
                        "table" => return Err(de::Error::duplicate_field("table")),
                        other => return Err(de::Error::unknown_field(other, &["table"])),
                    }
                }
                rows.map(Humidity::Table)
                    .ok_or_else(|| de::Error::missing_field("table"))
            }
        }
        d.deserialize_any(V(std::marker::PhantomData))
    }
}
