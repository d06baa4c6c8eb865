//! The refractive index of the air, as δ = n − 1 (see `docs/model.md`).
//!
//! - [`IndexField`] is the one thing the tracer needs from a medium: δ and ∇δ at
//!   a point. The logistic model implements it, and so do the analytic media in
//!   [`analytic`] that the tests trace against exact answers.
//! - [`LogisticMedium`] holds the model's parameters (what files and the fitter
//!   see); [`LogisticField`] is its compiled, evaluation-ready form.
//! - [`Param`] names every parameter by its path (`hotspots[2].radius`).

pub mod analytic;
mod logistic;
mod params;

pub use logistic::{
    Background, C_SCALE, HotSpot, Inversion, LogisticField, LogisticMedium, MediumError,
};
pub use params::{HotField, Param, ParamParseError};

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
}
