//! What a batch traces: the rays ([`RayJob`]) and the settings they share
//! ([`BatchOptions`]).

use crate::math::V3;
use crate::trace::{GroundMode, Method, TargetPlane, TraceOptions};

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

/// Settings of a batch: [`TraceOptions`] restricted to fixed-step RK4.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BatchOptions {
    /// RK4 step in τ (metres).
    pub step: f64,
    /// Largest arc length; `None`: 4 × each ray's distance to its target.
    pub max_length: Option<f64>,
    /// Behaviour at the ground.
    pub ground: GroundMode,
    /// Cap on steps per ray.
    pub max_steps: u64,
}

impl BatchOptions {
    /// The batch equivalent of `options`, or `None` when its method is not
    /// [`Method::Rk4`] (the adaptive method has no batch kernel: its step
    /// sequence differs per ray).
    pub fn from_trace_options(options: &TraceOptions) -> Option<Self> {
        match options.method {
            Method::Rk4 { step } => Some(BatchOptions {
                step,
                max_length: options.max_length,
                ground: options.ground,
                max_steps: options.max_steps,
            }),
            Method::Dopri5 { .. } => None,
        }
    }
}
