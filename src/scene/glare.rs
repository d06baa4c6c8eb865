//! The `glare` section of a scene: as written ([`GlareSpec`]) and validated
//! ([`AngularGlare`], kernel sizes in degrees). The renderer turns it into
//! pixels for its camera and applies it (`crate::render::glare`, which also
//! holds the kernels' mathematics).

use crate::error::FieldError;
use crate::validate::positive;
use serde::{Deserialize, Serialize};

/// One kernel of the `glare` section as written (sizes in degrees).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum GlareKernelSpec {
    /// A Gaussian of standard deviation `sigma` degrees.
    Gaussian {
        /// Standard deviation (degrees).
        sigma: f64,
        /// Fraction of a source's light it spreads.
        weight: f64,
    },
    /// (1 − u²/r²)³ within `radius` degrees.
    Compact {
        /// Radius (degrees).
        radius: f64,
        /// Fraction of a source's light it spreads.
        weight: f64,
    },
}

/// The `glare` section as written ([`crate::render::glare`]).
#[derive(Clone, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GlareSpec {
    /// On/off (default on).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub enabled: Option<bool>,
    /// Multiplies every kernel's weight (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strength: Option<f64>,
    /// Luminance above which a pixel is a source (default 20).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub threshold: Option<f64>,
    /// Truncation error relative to the sources' peaks (default 1e-3).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub epsilon: Option<f64>,
    /// The kernels (default: bloom, veil and halo).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kernels: Option<Vec<GlareKernelSpec>>,
}

/// A bell-shaped kernel with peak 1, radial in the image plane (pixels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kernel {
    /// e^(−u²/2σ²).
    Gaussian {
        /// Standard deviation (pixels).
        sigma: f64,
    },
    /// (1 − u²/r²)³ inside radius r, zero outside.
    Compact {
        /// Radius (pixels).
        radius: f64,
    },
}

/// A kernel of the glare and the fraction of a source's light it spreads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeightedKernel {
    /// Shape, in pixels.
    pub kernel: Kernel,
    /// Fraction of the source's light it carries.
    pub weight: f64,
}

/// A scene's glare with kernel sizes in degrees (what scene files say);
/// [`AngularGlare::in_pixels`] turns it into `render::glare::GlareSettings` for a camera.
#[derive(Clone, Debug, PartialEq)]
pub struct AngularGlare {
    /// Kernels with `sigma`/`radius` in degrees and weights already scaled by
    /// the strength.
    pub kernels: Vec<WeightedKernel>,
    /// Source threshold (luminance, linear units).
    pub threshold: f64,
    /// Truncation error relative to the sources' peaks.
    pub epsilon: f64,
}

/// Default source threshold (luminance).
pub const DEFAULT_THRESHOLD: f64 = 20.0;
/// Default truncation error.
pub const DEFAULT_EPSILON: f64 = 1e-3;

/// The default glare: a narrow bloom, a wider veil, and a compact halo
/// (sizes in degrees).
pub fn default_kernels() -> Vec<WeightedKernel> {
    vec![
        WeightedKernel {
            kernel: Kernel::Gaussian { sigma: 0.08 },
            weight: 0.004,
        },
        WeightedKernel {
            kernel: Kernel::Gaussian { sigma: 0.5 },
            weight: 0.0015,
        },
        WeightedKernel {
            kernel: Kernel::Compact { radius: 2.0 },
            weight: 0.0005,
        },
    ]
}

/// Checks a `glare` section; `None` when it is switched off.
impl GlareSpec {
    /// Checks the section; `None` when it is switched off. Paths are relative to
    /// the section (`kernels[0].sigma`).
    pub fn validate(&self) -> Result<Option<AngularGlare>, FieldError> {
        let g = self;
        if g.enabled == Some(false) {
            return Ok(None);
        }
        let strength = g.strength.unwrap_or(1.0);
        if !(strength.is_finite() && strength >= 0.0) {
            return Err(FieldError::new(
                "strength",
                format!("must be a finite number ≥ 0, got {strength}"),
            ));
        }
        let threshold = positive("threshold", g.threshold.unwrap_or(DEFAULT_THRESHOLD))?;
        let epsilon = g.epsilon.unwrap_or(DEFAULT_EPSILON);
        if !(epsilon.is_finite() && (1e-8..=0.1).contains(&epsilon)) {
            return Err(FieldError::new(
                "epsilon",
                format!("must be in [1e-8, 0.1], got {epsilon}"),
            ));
        }
        let kernels = match &g.kernels {
            None => default_kernels(),
            Some(list) => {
                let mut out = Vec::with_capacity(list.len());
                for (i, k) in list.iter().enumerate() {
                    let (kernel, weight, size, name) = match *k {
                        GlareKernelSpec::Gaussian { sigma, weight } => {
                            (Kernel::Gaussian { sigma }, weight, sigma, "sigma")
                        }
                        GlareKernelSpec::Compact { radius, weight } => {
                            (Kernel::Compact { radius }, weight, radius, "radius")
                        }
                    };
                    if !(size.is_finite() && size > 0.0 && size <= 90.0) {
                        return Err(FieldError::new(
                            format!("kernels[{i}].{name}"),
                            format!("must be in (0, 90] degrees, got {size}"),
                        ));
                    }
                    if !(weight.is_finite() && (0.0..=1.0).contains(&weight)) {
                        return Err(FieldError::new(
                            format!("kernels[{i}].weight"),
                            format!("must be in [0, 1], got {weight}"),
                        ));
                    }
                    out.push(WeightedKernel { kernel, weight });
                }
                out
            }
        };
        let kernels: Vec<WeightedKernel> = kernels
            .into_iter()
            .map(|k| WeightedKernel {
                weight: k.weight * strength,
                ..k
            })
            .collect();
        let total: f64 = kernels.iter().map(|k| k.weight).sum();
        if total > 1.0 {
            return Err(FieldError::new(
                "strength",
                format!(
                    "the kernels would spread {total:.3} of a source's light (strength × Σ weights must be ≤ 1)"
                ),
            ));
        }
        Ok(Some(AngularGlare {
            kernels,
            threshold,
            epsilon,
        }))
    }
}
