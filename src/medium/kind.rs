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
//! Files hold the logistic kind: `"medium": { "scale": …, "background": … }`
//! reads as [`Medium::Logistic`], and a logistic medium writes back the same
//! way. The analytic kind is built in code (tests and validation) and writes as
//! `{"linear_square": {"n0": …, "g": …}}`.

use super::analytic::LinearSquare;
use super::{Envelope, IndexField, LogisticField, LogisticMedium, Param};
use crate::error::FieldError;
use crate::math::{Real, V3};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A medium of any kind, by its parameters.
#[derive(Clone, Debug, PartialEq)]
pub enum Medium<T = f64> {
    /// The logistic model (`docs/model.md`): the artist's model.
    Logistic(LogisticMedium<T>),
    /// n² linear in height, with exact parabolic rays (`medium::analytic`).
    LinearSquare(LinearSquare<T>),
}

/// A medium of any kind, compiled for evaluation.
#[derive(Clone, Debug)]
pub enum Field<T = f64> {
    /// The compiled logistic model.
    Logistic(LogisticField<T>),
    /// The n²-linear medium (it needs no compiling).
    LinearSquare(LinearSquare<T>),
}

impl<T: Real> IndexField<T> for Field<T> {
    #[inline]
    fn delta_gradient(&self, p: V3<T>) -> (T, V3<T>) {
        match self {
            Field::Logistic(f) => f.delta_gradient(p),
            Field::LinearSquare(f) => f.delta_gradient(p),
        }
    }

    fn is_stratified(&self) -> bool {
        match self {
            Field::Logistic(f) => IndexField::<T>::is_stratified(f),
            Field::LinearSquare(f) => IndexField::<T>::is_stratified(f),
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
        }
    }

    /// Why `p` is not a parameter of this medium, in words.
    pub fn absent_reason(&self, p: Param) -> String {
        match self {
            Medium::Logistic(m) => m.absent_reason(p),
            Medium::LinearSquare(_) => format!(
                "`{p}` is not a parameter of the analytic n²-linear medium (it has `linear_square.n0` and `linear_square.g`)"
            ),
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
        }
    }

    /// Whether the medium bends rays at all (a logistic medium without terms
    /// does not).
    pub fn has_terms(&self) -> bool {
        match self {
            Medium::Logistic(m) => m.has_terms(),
            Medium::LinearSquare(m) => m.g != 0.0 || m.n0 != 1.0,
        }
    }

    /// Bounds and feature sizes of the medium above the ground, for the
    /// renderer's step control and early decisions (see [`Envelope`]).
    pub fn envelope(&self) -> Envelope {
        match self {
            Medium::Logistic(m) => m.envelope(),
            Medium::LinearSquare(m) => m.envelope(),
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

    /// The kind's name, for messages (`logistic`, `linear_square`).
    pub fn kind_name(&self) -> &'static str {
        match self {
            Medium::Logistic(_) => "logistic",
            Medium::LinearSquare(_) => "linear_square",
        }
    }
}

impl From<LogisticMedium> for Medium {
    fn from(m: LogisticMedium) -> Self {
        Medium::Logistic(m)
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
        }
    }
}

impl<'de> Deserialize<'de> for Medium {
    /// Files hold the logistic kind; reading it directly (not through an
    /// untagged buffer) keeps serde's field paths and line numbers in errors.
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        LogisticMedium::deserialize(d).map(Medium::Logistic)
    }
}
