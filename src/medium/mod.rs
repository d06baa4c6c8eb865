//! The refractive index of the air, as δ = n − 1 (see `docs/model.md`).
//!
//! - [`IndexField`] is the one thing the tracer needs from a medium: δ and ∇δ at
//!   a point.
//! - [`Medium`] is the closed set of kinds, by their parameters (what files and
//!   the fitter see), and [`Field`] the same kinds compiled for evaluation; both
//!   dispatch statically (an `enum` and a `match`, in `kind.rs`). The kinds: the
//!   logistic model ([`LogisticMedium`], compiled [`LogisticField`]), real
//!   air ([`air::AirMedium`], compiled [`air::AirField`]; `docs/air.md`) and
//!   the analytic n²-linear medium ([`analytic::LinearSquare`]).
//! - [`Envelope`] gives the bounds and features a stepper needs beyond δ.
//! - [`Param`] names every parameter by its path (`hotspots[2].radius`).

pub mod air;
pub mod analytic;
pub mod compiled;
pub mod cull;
pub mod dispersion;
mod envelope;
mod kind;
mod logistic;
mod params;
mod rim;

pub use dispersion::PairFields;
pub use envelope::{Envelope, Patch, VerticalFeature};
pub use kind::{Field, Medium};
pub use logistic::{Background, C_SCALE, HotSpot, Inversion, LogisticField, LogisticMedium};
pub use params::{AirParam, HotField, Param, ParamParseError};

use crate::math::{Real, V3};

/// The air seen by a ray: δ = n − 1 and its gradient, at any point (also below the
/// ground, so rays can be integrated through it without a special case).
///
/// Implementations must return finite values for every finite input.
pub trait IndexField<T: Real = f64>: Sync {
    /// δ(p).
    fn delta(&self, p: V3<T>) -> T {
        self.delta_gradient(p).0
    }

    /// δ(p) and ∇δ(p).
    fn delta_gradient(&self, p: V3<T>) -> (T, V3<T>);

    /// True when δ depends on the height y alone: then Snell's invariant holds and
    /// a ray stays in the vertical plane of its launch direction.
    fn is_stratified(&self) -> bool {
        false
    }

    /// The height (m) above which the medium is not defined as air (real air
    /// colder than −150 °C): the tracers stop a ray that rises past it.
    fn ceiling(&self) -> f64 {
        f64::INFINITY
    }

    /// The longest adaptive step (τ units, about metres) a ray at height `y`
    /// with vertical velocity `vy` (τ form) may take without leaping into a
    /// thin layer it is heading for: an adaptive stepper far above a 5 cm
    /// surface layer would otherwise grow steps of hundreds of metres whose
    /// stages all miss the layer. Infinite by default (no such layer).
    fn step_limit(&self, _y: f64, _vy: f64) -> f64 {
        f64::INFINITY
    }
}
