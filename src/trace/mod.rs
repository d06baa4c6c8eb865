//! Rays through the medium: the ray equation integrated by RK4 or Dormand–Prince
//! 5(4), with events located inside the step that contains them.
//!
//! The tracer integrates the τ form of the ray equation (see [`state`]); the
//! endpoint on a target plane is where the quintic Hermite interpolant of the
//! crossing step meets the plane, so its error is the integrator's, not O(step).
//!
//! Everything is generic over [`Real`]: traced with dual numbers, the same code
//! returns the exact derivative of the discrete endpoint map (see `fit`).

pub mod batch;
pub mod earth;
mod event;
pub mod fastexp;
pub mod hermite;
mod scalar;
pub mod state;
mod stepper;

pub use earth::{Earth, EarthSpec, OnEarth};
pub use hermite::Segment;
pub use state::{RayRate, RayState};
pub use stepper::{Method, rk4_step};

pub(crate) use event::first_ground_crossing;

pub use scalar::{trace, trace_launched};

use crate::math::{Real, V3};
use serde::Serialize;

/// What happens when a ray reaches the ground (y = 0, or the sphere of
/// [`Earth::Round`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum GroundMode {
    /// Flag the ray as occluded and go on: the medium is defined below ground, so
    /// the endpoint map stays smooth for fitting.
    #[default]
    Flag,
    /// Stop at the ground (rendering).
    Stop,
}

/// Settings of one trace.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceOptions {
    /// Integrator and its accuracy.
    pub method: Method,
    /// Largest arc length (metres); `None`: 4 × the distance to the target.
    pub max_length: Option<f64>,
    /// Behaviour at the ground.
    pub ground: GroundMode,
    /// Hard cap on integration steps (accepted + rejected), against runaway.
    pub max_steps: u64,
    /// The ground: flat, or the round earth (heights, the ground's events
    /// and the media's vertical all follow it).
    pub earth: Earth,
}

impl TraceOptions {
    /// Options for a method with the default limits.
    pub fn new(method: Method) -> Self {
        TraceOptions {
            method,
            max_length: None,
            ground: GroundMode::Flag,
            max_steps: 10_000_000,
            earth: Earth::Flat,
        }
    }
}

/// The plane a ray must reach: through `point`, with unit `normal` pointing away
/// from the observer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TargetPlane {
    /// A point of the plane (the pair's target).
    pub point: V3,
    /// Unit normal, horizontal for point pairs.
    pub normal: V3,
}

impl TargetPlane {
    /// Signed distance of `x` past the plane (negative on the observer's side).
    #[inline]
    pub fn signed_distance<T: Real>(&self, x: V3<T>) -> T {
        (x - self.point.lift()).dot(self.normal.lift())
    }
}

/// Why a trace ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum End {
    /// It crossed the target plane.
    Plane,
    /// It reached the ground, in [`GroundMode::Stop`].
    Ground,
    /// It travelled `max_length` without reaching the plane.
    MaxLength,
    /// The step limit was hit, or the adaptive step underflowed.
    StepLimit,
    /// It rose past the medium's ceiling into air colder than −150 °C (real
    /// air with a steep lapse), where no refractivity formula holds.
    LeftAir,
}

/// Integration statistics of one trace.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Stats {
    /// Right-hand-side (index and gradient) evaluations.
    pub rhs_evaluations: u64,
    /// Accepted steps.
    pub accepted_steps: u64,
    /// Rejected steps (adaptive method only).
    pub rejected_steps: u64,
}

impl std::ops::AddAssign for Stats {
    fn add_assign(&mut self, o: Stats) {
        self.rhs_evaluations += o.rhs_evaluations;
        self.accepted_steps += o.accepted_steps;
        self.rejected_steps += o.rejected_steps;
    }
}

/// The result of tracing one ray.
#[derive(Clone, Debug)]
pub struct Trace<T = f64> {
    /// Where the ray ended: on the target plane, on the ground (stop mode), or,
    /// if it never reached the plane, the traced point nearest to it.
    pub endpoint: V3<T>,
    /// Unit tangent at the endpoint.
    pub direction: V3,
    /// Arc length travelled (metres).
    pub arc_length: f64,
    /// Why the trace ended.
    pub end: End,
    /// The ray went below y = 0 before its end.
    pub occluded: bool,
    /// A target plane was given and the ray did not reach it.
    pub unreachable: bool,
    /// Integration statistics.
    pub stats: Stats,
}

impl Default for Trace<f64> {
    /// A placeholder to size output buffers (a zero-length trace at the origin).
    fn default() -> Self {
        Trace {
            endpoint: V3::ZERO,
            direction: V3::ZERO,
            arc_length: 0.0,
            end: End::StepLimit,
            occluded: false,
            unreachable: false,
            stats: Stats::default(),
        }
    }
}
