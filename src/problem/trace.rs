//! The `trace` section of a problem: as written ([`TraceSpec`]) and validated into
//! the tracer's [`TraceOptions`].

use crate::error::{Error, Result};
use crate::trace::{Method, TraceOptions};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The `trace` section as written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TraceSpec {
    /// `rk4`, `dopri5` or `adaptive`.
    pub method: String,
    /// RK4 step (metres).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub step: Option<f64>,
    /// Dormand–Prince local error bound.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tolerance: Option<f64>,
    /// Largest arc length (metres); default 4 × |target − origin|.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_length: Option<f64>,
}

impl Default for TraceSpec {
    fn default() -> Self {
        TraceSpec {
            method: "dopri5".into(),
            step: None,
            tolerance: Some(DEFAULT_TOLERANCE),
            max_length: None,
        }
    }
}

/// Default RK4 step when a file names `rk4` without a step (metres).
pub const DEFAULT_STEP: f64 = 1.0;
/// Default Dormand–Prince tolerance when none is given.
pub const DEFAULT_TOLERANCE: f64 = 1e-9;

fn positive(path: &Path, field: &str, v: f64) -> Result<f64> {
    crate::validate::positive(field, v).map_err(|e| e.in_file(path))
}

/// Validates a `trace` section: known method, its parameters and no others.
pub fn trace_options(spec: &TraceSpec, path: &Path) -> Result<(TraceOptions, TraceSpec)> {
    let unused = |field: &str, method: &str| {
        Error::input(
            path,
            format!("trace.{field}"),
            format!("is not a parameter of method `{method}`"),
        )
    };
    let mut normal = spec.clone();
    let method = match spec.method.as_str() {
        "rk4" => {
            if spec.tolerance.is_some() {
                return Err(unused("tolerance", "rk4"));
            }
            let step = positive(path, "trace.step", spec.step.unwrap_or(DEFAULT_STEP))?;
            normal.step = Some(step);
            Method::Rk4 { step }
        }
        "dopri5" | "adaptive" => {
            if spec.step.is_some() {
                return Err(unused("step", &spec.method));
            }
            let tolerance = positive(
                path,
                "trace.tolerance",
                spec.tolerance.unwrap_or(DEFAULT_TOLERANCE),
            )?;
            normal.method = "dopri5".into();
            normal.tolerance = Some(tolerance);
            Method::Dopri5 { tolerance }
        }
        other => {
            return Err(Error::input(
                path,
                "trace.method",
                format!("unknown method `{other}` (expected `rk4`, `dopri5` or `adaptive`)"),
            ));
        }
    };
    let mut options = TraceOptions::new(method);
    if let Some(l) = spec.max_length {
        options.max_length = Some(positive(path, "trace.max_length", l)?);
    }
    Ok((options, normal))
}
