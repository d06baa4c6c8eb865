//! The closed set of medium kinds, behind static dispatch: [`Medium`] (the
//! parameters, as files and the fitter see them) and [`Field`] (compiled for
//! evaluation). Every consumer — the tracers, the lanes kernels, the fit, the
//! renderer, the previewer — takes these two enums, and the `match`es below are
//! the only places that name every kind (pbrt-v4's tagged dispatch, without
//! `dyn`).
//!
//! Adding a kind: its file in `src/medium/` (parameters with `params`, `get`,
//! `set`, `map`, `validate`, `field`, `envelope`, and a compiled field
//! implementing [`IndexField`]), one variant in each enum here with its arms,
//! its parameter paths in [`Param`], and, where a fast path exists only for
//! some kinds (the SIMD lanes, the GPU shader), the arm that sends the new kind
//! to the general path or refuses it by name.
//!
//! Files hold two kinds: `"medium": { "scale": …, "background": … }` reads as
//! [`Medium::Logistic`], `"medium": { "air": { … }, "hotspots": … }` as
//! [`Medium::Air`] (`docs/air.md`), and each writes back the same way. The
//! analytic kind is built in code (tests and validation) and writes as
//! `{"linear_square": {"n0": …, "g": …}}`.

use super::air::{AirField, AirHotSpot, AirMedium};
use super::analytic::LinearSquare;
use super::{
    Background, Envelope, HotSpot, IndexField, Inversion, LogisticField, LogisticMedium, Param,
};
use crate::error::FieldError;
use crate::error::nested_message;
use crate::math::{Real, V3};
use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;

/// A medium of any kind, by its parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum Medium<T = f64> {
    /// The logistic model (`docs/model.md`): the artist's model.
    Logistic(LogisticMedium<T>),
    /// n² linear in height, with exact parabolic rays (`medium::analytic`).
    LinearSquare(LinearSquare<T>),
    /// Real air (`docs/air.md`): temperature, pressure, humidity, wavelength.
    Air(AirMedium<T>),
}

/// A medium of any kind, compiled for evaluation.
#[derive(Clone, Debug)]
pub enum Field<T = f64> {
    /// The compiled logistic model.
    Logistic(LogisticField<T>),
    /// The n²-linear medium (it needs no compiling).
    LinearSquare(LinearSquare<T>),
    /// Real air, compiled (its pressure tabulated).
    Air(AirField<T>),
}

impl<T: Real> IndexField<T> for Field<T> {
    #[inline]
    fn delta_gradient(&self, p: V3<T>) -> (T, V3<T>) {
        match self {
            Field::Logistic(f) => f.delta_gradient(p),
            Field::LinearSquare(f) => f.delta_gradient(p),
            Field::Air(f) => f.delta_gradient(p),
        }
    }

    fn is_stratified(&self) -> bool {
        match self {
            Field::Logistic(f) => IndexField::<T>::is_stratified(f),
            Field::LinearSquare(f) => IndexField::<T>::is_stratified(f),
            Field::Air(f) => IndexField::<T>::is_stratified(f),
        }
    }

    fn ceiling(&self) -> f64 {
        match self {
            Field::Air(f) => f.ceiling(),
            Field::Logistic(_) | Field::LinearSquare(_) => f64::INFINITY,
        }
    }

    #[inline]
    fn step_limit(&self, y: f64, vy: f64) -> f64 {
        match self {
            Field::Air(f) => IndexField::<T>::step_limit(f, y, vy),
            Field::Logistic(_) | Field::LinearSquare(_) => f64::INFINITY,
        }
    }
}

impl<T: Real> Field<T> {
    /// Compiles `medium` (validated or not: an invalid medium gives non-finite
    /// values, which callers treat as a failed evaluation).
    pub fn new(medium: &Medium<T>) -> Self {
        match medium {
            Medium::Logistic(m) => Field::Logistic(LogisticField::new(m)),
            Medium::LinearSquare(m) => Field::LinearSquare(*m),
            Medium::Air(m) => Field::Air(AirField::new(m)),
        }
    }
}

impl Field<f64> {
    /// The logistic field, if this is one (the SIMD and GPU kernels evaluate
    /// its formula lane-wise).
    pub fn as_logistic(&self) -> Option<&LogisticField> {
        match self {
            Field::Logistic(f) => Some(f),
            _ => None,
        }
    }
}

impl<T: Copy> Medium<T> {
    /// Every parameter with its value, in the kind's fixed order.
    pub fn params(&self) -> Vec<(Param, T)> {
        match self {
            Medium::Logistic(m) => m.params(),
            Medium::LinearSquare(m) => vec![(Param::LinearN0, m.n0), (Param::LinearG, m.g)],
            Medium::Air(m) => m.params(),
        }
    }

    /// The value of a parameter, or `None` if this medium has no such parameter.
    pub fn get(&self, p: Param) -> Option<T> {
        match self {
            Medium::Logistic(m) => m.get(p),
            Medium::LinearSquare(m) => match p {
                Param::LinearN0 => Some(m.n0),
                Param::LinearG => Some(m.g),
                _ => None,
            },
            Medium::Air(m) => m.get(p),
        }
    }

    /// Sets a parameter; errors (path relative to the medium) if this medium has
    /// no such parameter.
    pub fn set(&mut self, p: Param, value: T) -> Result<(), FieldError> {
        match self {
            Medium::Logistic(m) => m.set(p, value),
            Medium::LinearSquare(m) => {
                match p {
                    Param::LinearN0 => m.n0 = value,
                    Param::LinearG => m.g = value,
                    _ => return Err(FieldError::new(p.to_string(), self.absent_reason(p))),
                }
                Ok(())
            }
            Medium::Air(m) => m.set(p, value),
        }
    }

    /// Why `p` is not a parameter of this medium, in words.
    pub fn absent_reason(&self, p: Param) -> String {
        match self {
            Medium::Logistic(m) => m.absent_reason(p),
            Medium::LinearSquare(_) => format!(
                "`{p}` is not a parameter of the analytic n²-linear medium (it has `linear_square.n0` and `linear_square.g`)"
            ),
            Medium::Air(m) => m.absent_reason(p),
        }
    }

    /// The same medium with every parameter mapped through `f` (to lift the
    /// parameters to dual numbers for exact derivatives).
    pub fn map<U>(&self, mut f: impl FnMut(Param, T) -> U) -> Medium<U> {
        match self {
            Medium::Logistic(m) => Medium::Logistic(m.map(f)),
            Medium::LinearSquare(m) => Medium::LinearSquare(LinearSquare {
                n0: f(Param::LinearN0, m.n0),
                g: f(Param::LinearG, m.g),
            }),
            Medium::Air(m) => Medium::Air(m.map(f)),
        }
    }
}

impl<T: Real> Medium<T> {
    /// The compiled field.
    pub fn field(&self) -> Field<T> {
        Field::new(self)
    }
}

impl Medium<f64> {
    /// Checks every rule of the kind; the first violation is returned with the
    /// path of its field, relative to the medium.
    pub fn validate(&self) -> Result<(), FieldError> {
        match self {
            Medium::Logistic(m) => m.validate(),
            Medium::LinearSquare(m) => m.validate(),
            Medium::Air(m) => m.validate(),
        }
    }

    /// Whether the medium bends rays at all (a logistic medium without terms
    /// does not).
    pub fn has_terms(&self) -> bool {
        match self {
            Medium::Logistic(m) => m.has_terms(),
            Medium::LinearSquare(m) => m.g != 0.0 || m.n0 != 1.0,
            // Air always bends light: even uniform air has δ ≈ 2.7e-4.
            Medium::Air(_) => true,
        }
    }

    /// Bounds and feature sizes of the medium above the ground, for the
    /// renderer's step control and early decisions (see [`Envelope`]).
    pub fn envelope(&self) -> Envelope {
        match self {
            Medium::Logistic(m) => m.envelope(),
            Medium::LinearSquare(m) => m.envelope(),
            Medium::Air(m) => m.envelope(),
        }
    }

    /// The logistic parameters, if this is a logistic medium (the previewer's
    /// editor, the GPU packing).
    pub fn as_logistic(&self) -> Option<&LogisticMedium> {
        match self {
            Medium::Logistic(m) => Some(m),
            _ => None,
        }
    }

    /// The logistic parameters, mutably, if this is a logistic medium.
    pub fn as_logistic_mut(&mut self) -> Option<&mut LogisticMedium> {
        match self {
            Medium::Logistic(m) => Some(m),
            _ => None,
        }
    }

    /// The real-air parameters, if this is real air.
    pub fn as_air(&self) -> Option<&AirMedium> {
        match self {
            Medium::Air(m) => Some(m),
            _ => None,
        }
    }

    /// The kind's name, for messages (`logistic`, `linear_square`, `air`).
    pub fn kind_name(&self) -> &'static str {
        match self {
            Medium::Logistic(_) => "logistic",
            Medium::LinearSquare(_) => "linear_square",
            Medium::Air(_) => "air",
        }
    }
}

impl From<LogisticMedium> for Medium {
    fn from(m: LogisticMedium) -> Self {
        Medium::Logistic(m)
    }
}

impl From<AirMedium> for Medium {
    fn from(m: AirMedium) -> Self {
        Medium::Air(m)
    }
}

impl From<LinearSquare> for Medium {
    fn from(m: LinearSquare) -> Self {
        Medium::LinearSquare(m)
    }
}

#[derive(Serialize)]
struct LinearSquareFile {
    n0: f64,
    g: f64,
}

#[derive(Serialize)]
struct LinearSquareDoc {
    linear_square: LinearSquareFile,
}

impl Serialize for Medium {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Medium::Logistic(m) => m.serialize(s),
            Medium::LinearSquare(m) => LinearSquareDoc {
                linear_square: LinearSquareFile { n0: m.n0, g: m.g },
            }
            .serialize(s),
            Medium::Air(m) => m.serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for Medium {
    /// The kind is decided by the keys: `air` makes real air, `scale`,
    /// `background` or `inversion` the logistic model. Each value is read
    /// directly into its type (not through a buffer), which keeps serde's
    /// field paths and line numbers in errors; only hot spots that come
    /// before any key that decides the kind are read in a form common to both
    /// kinds and checked afterwards, with their paths marked by
    /// [`nested_message`].
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_map(MediumVisitor)
    }
}

/// The keys of either kind, for "unknown field" messages.
const MEDIUM_FIELDS: &[&str] = &["scale", "background", "inversion", "hotspots", "air"];

/// Hot spots read before the kind is known.
enum HotSpots {
    Logistic(Vec<HotSpot>),
    Air(Vec<AirHotSpot>),
    Either(Vec<EitherHotSpot>),
}

/// A hot spot with the fields of both kinds, each optional.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct EitherHotSpot {
    x: f64,
    z: f64,
    radius: f64,
    edge: Option<f64>,
    n: Option<f64>,
    a: Option<f64>,
    delta: Option<f64>,
    scale_height: Option<f64>,
}

impl EitherHotSpot {
    fn logistic<E: de::Error>(&self, j: usize) -> Result<HotSpot, E> {
        let stray = [("delta", self.delta), ("scale_height", self.scale_height)];
        if let Some((name, _)) = stray.iter().find(|(_, v)| v.is_some()) {
            return Err(E::custom(nested_message(
                &format!("hotspots[{j}].{name}"),
                "a field of real air's hot spots, but this medium is the logistic model (it has no `air`): a logistic hot spot has `n` and `a`",
            )));
        }
        match (self.n, self.a) {
            (Some(n), Some(a)) => Ok(HotSpot {
                x: self.x,
                z: self.z,
                radius: self.radius,
                n,
                a,
                edge: self.edge.unwrap_or(10.0),
            }),
            (None, _) => Err(E::custom(nested_message(
                &format!("hotspots[{j}]"),
                "missing field `n` (a logistic hot spot has `n` and `a`; with `air`, real air's have `delta` and `scale_height`)",
            ))),
            (_, None) => Err(E::custom(nested_message(
                &format!("hotspots[{j}]"),
                "missing field `a` (a logistic hot spot has `n` and `a`)",
            ))),
        }
    }

    fn air<E: de::Error>(&self, j: usize) -> Result<AirHotSpot, E> {
        let stray = [("n", self.n), ("a", self.a)];
        if let Some((name, _)) = stray.iter().find(|(_, v)| v.is_some()) {
            return Err(E::custom(nested_message(
                &format!("hotspots[{j}].{name}"),
                "a field of the logistic model's hot spots, but this medium is real air: its hot spots have `delta` (K) and `scale_height` (m)",
            )));
        }
        match (self.delta, self.scale_height) {
            (Some(delta), Some(scale_height)) => Ok(AirHotSpot {
                x: self.x,
                z: self.z,
                radius: self.radius,
                edge: self.edge.unwrap_or(10.0),
                delta,
                scale_height,
            }),
            (None, _) => Err(E::custom(nested_message(
                &format!("hotspots[{j}]"),
                "missing field `delta` (a real-air hot spot has `delta` in K and `scale_height` in m)",
            ))),
            (_, None) => Err(E::custom(nested_message(
                &format!("hotspots[{j}]"),
                "missing field `scale_height` (a real-air hot spot has `delta` in K and `scale_height` in m)",
            ))),
        }
    }
}

struct MediumVisitor;

impl<'de> Visitor<'de> for MediumVisitor {
    type Value = Medium;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a medium: the logistic model (`scale`, `background`, `inversion`, `hotspots`) or real air (`air`, `hotspots`)")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Medium, A::Error> {
        let mut scale: Option<f64> = None;
        let mut background: Option<Background> = None;
        let mut inversion: Option<Inversion> = None;
        let mut air = None;
        let mut hotspots: Option<HotSpots> = None;
        // The first key that decides the kind, for messages.
        let mut logistic_key: Option<&'static str> = None;
        while let Some(key) = map.next_key::<String>()? {
            let duplicate = |k: &'static str| Err(de::Error::duplicate_field(k));
            match key.as_str() {
                "scale" => {
                    if scale.is_some() {
                        return duplicate("scale");
                    }
                    scale = Some(map.next_value()?);
                    logistic_key.get_or_insert("scale");
                }
                "background" => {
                    if background.is_some() {
                        return duplicate("background");
                    }
                    background = Some(map.next_value()?);
                    logistic_key.get_or_insert("background");
                }
                "inversion" => {
                    if inversion.is_some() {
                        return duplicate("inversion");
                    }
                    inversion = Some(map.next_value()?);
                    logistic_key.get_or_insert("inversion");
                }
                "air" => {
                    if air.is_some() {
                        return duplicate("air");
                    }
                    air = Some(map.next_value()?);
                }
                "hotspots" => {
                    if hotspots.is_some() {
                        return duplicate("hotspots");
                    }
                    hotspots = Some(if air.is_some() {
                        HotSpots::Air(map.next_value()?)
                    } else if logistic_key.is_some() {
                        HotSpots::Logistic(map.next_value()?)
                    } else {
                        HotSpots::Either(map.next_value()?)
                    });
                }
                other => return Err(de::Error::unknown_field(other, MEDIUM_FIELDS)),
            }
            if let (Some(_), Some(k)) = (&air, logistic_key) {
                return Err(de::Error::custom(nested_message(
                    k,
                    "a field of the logistic model beside `air`: a medium is either the logistic model or real air (`air` and `hotspots`), not both",
                )));
            }
        }
        match air {
            Some(air) => {
                let hotspots = match hotspots {
                    None => Vec::new(),
                    Some(HotSpots::Air(h)) => h,
                    Some(HotSpots::Either(h)) => h
                        .iter()
                        .enumerate()
                        .map(|(j, s)| s.air(j))
                        .collect::<Result<_, _>>()?,
                    Some(HotSpots::Logistic(_)) => unreachable!("logistic keys beside air"),
                };
                Ok(Medium::Air(AirMedium { air, hotspots }))
            }
            None => {
                let hotspots = match hotspots {
                    None => Vec::new(),
                    Some(HotSpots::Logistic(h)) => h,
                    Some(HotSpots::Either(h)) => h
                        .iter()
                        .enumerate()
                        .map(|(j, s)| s.logistic(j))
                        .collect::<Result<_, _>>()?,
                    Some(HotSpots::Air(_)) => unreachable!("air hot spots without air"),
                };
                Ok(Medium::Logistic(LogisticMedium {
                    scale: scale.unwrap_or(1.0),
                    background,
                    inversion,
                    hotspots,
                }))
            }
        }
    }
}
