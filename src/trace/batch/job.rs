//! What a batch traces: the rays ([`RayJob`]) and the settings they share
//! ([`BatchOptions`]).

use crate::math::V3;
use crate::trace::{Earth, GroundMode, Method, TargetPlane, TraceOptions};

/// One ray to trace: where it starts, where it looks, the plane it must reach.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayJob {
    /// Start point (metres).
    pub origin: V3,
    /// Unit launch direction.
    pub direction: V3,
    /// The plane whose first crossing is the endpoint.
    pub target: TargetPlane,
}

/// Settings of a batch: the [`TraceOptions`] of every ray in it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BatchOptions {
    /// Integrator and its accuracy (RK4's step or Dormand–Prince's
    /// tolerance), as the scalar tracer takes it.
    pub method: Method,
    /// Largest arc length; `None`: 4 × each ray's distance to its target.
    pub max_length: Option<f64>,
    /// Behaviour at the ground.
    pub ground: GroundMode,
    /// Cap on steps per ray.
    pub max_steps: u64,
    /// The ground.
    pub earth: Earth,
}

impl BatchOptions {
    /// The batch equivalent of `options`: the same rays, traced the same way.
    pub fn from_trace_options(options: &TraceOptions) -> Self {
        BatchOptions {
            method: options.method,
            max_length: options.max_length,
            ground: options.ground,
            max_steps: options.max_steps,
            earth: options.earth,
        }
    }

    /// The scalar tracer's options for the same rays.
    pub fn trace_options(&self) -> TraceOptions {
        TraceOptions {
            method: self.method,
            max_length: self.max_length,
            ground: self.ground,
            max_steps: self.max_steps,
            earth: self.earth,
        }
    }
}
