//! Point pairs: "an observer at `origin` who looks toward `through` must see
//! `target`", and the residual that measures how far the air is from that.

use crate::error::{FieldError, ValueError};
use crate::geo::{Angle, Horizon, Point, Site};
use crate::math::{Real, V3};
use crate::medium::IndexField;
use crate::medium::air::WAVELENGTH_RANGE;
use crate::trace::batch::RayJob;
use crate::trace::{Earth, RayState, TargetPlane, Trace, TraceOptions, trace};
use serde::{Deserialize, Serialize};

/// One point pair, as written in a problem file.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointPair {
    /// The observer (metres).
    pub origin: [f64; 3],
    /// A point on the line of sight, which fixes the launch direction.
    pub through: [f64; 3],
    /// The point the observer must see.
    pub target: [f64; 3],
    /// Weight of this pair's residual (default 1).
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub weight: f64,
    /// The vacuum wavelength (nm) this pair is seen at, replacing the
    /// medium's `air.wavelength` for this pair only (real air only; absent:
    /// the medium's own).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wavelength: Option<f64>,
}

fn one() -> f64 {
    1.0
}
fn is_one(w: &f64) -> bool {
    *w == 1.0
}

/// Checks an endpoint noise σ (`pairs[i].noise`, `solver.noise`, `--noise`):
/// a finite number > 0 metres.
pub fn check_noise(v: f64) -> std::result::Result<f64, ValueError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(ValueError::OutOfRange {
            rule: format!("must be a finite number > 0 (metres), got {v}"),
        })
    }
}

/// One pair as a problem file holds it: the [`PointPair`] and, optionally,
/// the noise σ of its endpoint, which only a grown model's criterion reads
/// (`crate::fit::grow`). Points may be geographic (`crate::geo`, with the
/// file's `site`), and the line of sight may be given by `elevation` and
/// `azimuth` instead of `through`; [`PairEntry::resolve`] turns it into the
/// [`PointPair`] that is traced. Its fields repeat [`PointPair`]'s rather
/// than `#[serde(flatten)]` it, because serde's `flatten` cannot be combined
/// with `deny_unknown_fields`, which names a misspelt field.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairEntry {
    /// The observer: `[x, y, z]` (metres) or a geographic point.
    pub origin: Point,
    /// A point on the line of sight, which fixes the launch direction
    /// (or `elevation` and `azimuth`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub through: Option<Point>,
    /// The launch direction's elevation above the local horizontal at the
    /// origin (degrees, or a degree-minute-second string), instead of
    /// `through`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub elevation: Option<Angle>,
    /// The launch direction's azimuth from north toward east (degrees, or a
    /// degree-minute-second string); absent with `elevation`: the target's
    /// geometric azimuth.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub azimuth: Option<Angle>,
    /// The point the observer must see: `[x, y, z]` or a geographic point.
    pub target: Point,
    /// Weight of this pair's residual (default 1).
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub weight: f64,
    /// The vacuum wavelength (nm) this pair is seen at (real air only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wavelength: Option<f64>,
    /// The endpoint noise σᵢ of this pair (metres per component in the
    /// target plane; arcseconds with angle residuals); absent: the
    /// problem's `solver.noise`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise: Option<f64>,
}

impl PairEntry {
    /// The pair to trace: points in the local frame (geographic ones placed
    /// from `site` over `earth`'s sphere), the line of sight from `through`
    /// or from `elevation` and `azimuth` at the origin's horizon (`through`
    /// is then put on that line at the target's distance).
    pub fn resolve(&self, site: Option<&Site>, earth: Earth) -> Result<PointPair, FieldError> {
        let radius = earth.radius();
        let place = |p: &Point, name: &str| {
            p.resolve(site, radius.unwrap_or(f64::INFINITY))
                .map_err(|e| e.within(name))
        };
        let origin = place(&self.origin, "origin")?;
        let target = place(&self.target, "target")?;
        let through = match (&self.through, self.elevation, self.azimuth) {
            (Some(t), None, None) => place(t, "through")?,
            (Some(_), Some(_), _) => {
                return Err(FieldError::new(
                    "elevation",
                    "give the line of sight once: `through`, or `elevation` (with `azimuth`), not both",
                ));
            }
            (Some(_), None, Some(_)) => {
                return Err(FieldError::new(
                    "azimuth",
                    "give the line of sight once: `through`, or `elevation` with `azimuth`, not both",
                ));
            }
            (None, None, Some(_)) => {
                return Err(FieldError::new(
                    "elevation",
                    "missing: an `azimuth` needs an `elevation` (degrees above the horizontal)",
                ));
            }
            (None, None, None) => {
                return Err(FieldError::new(
                    "through",
                    "missing: give `through` (a point on the line of sight), or `elevation` and `azimuth`",
                ));
            }
            (None, Some(e), a) => {
                if !(e.degrees > -90.0 && e.degrees < 90.0) {
                    return Err(FieldError::new(
                        "elevation",
                        format!(
                            "must lie strictly between -90 and 90 degrees, got {}",
                            e.degrees
                        ),
                    ));
                }
                let h = Horizon::at(origin, radius).map_err(|e| e.within("origin"))?;
                let to = std::array::from_fn(|k| target[k] - origin[k]);
                let azimuth = match a {
                    Some(a) => a.degrees,
                    None => h.azimuth(to),
                };
                // The square root of the sum of squares overflowed to ∞ beyond
                // 10¹⁵⁴ m and put `through` at ±∞ (found by fuzzing).
                let range = distance(V3::from(to));
                if range > RANGE_LIMITS.1 {
                    return Err(range_error("target", range));
                }
                let range = range.max(1.0);
                let d = h.direction(e.degrees, azimuth);
                let through: [f64; 3] = std::array::from_fn(|k| origin[k] + range * d[k]);
                if through.iter().any(|c| !c.is_finite()) {
                    return Err(FieldError::new(
                        "origin",
                        format!(
                            "coordinates {origin:?} are too large to put a line of sight through them"
                        ),
                    ));
                }
                through
            }
        };
        Ok(PointPair {
            origin,
            through,
            target,
            weight: self.weight,
            wavelength: self.wavelength,
        })
    }

    /// The noise (if any) as [`check_noise`] says.
    pub fn validate(&self) -> Result<(), FieldError> {
        match self.noise.map(check_noise) {
            Some(Err(e)) => Err(FieldError::new("noise", e.to_string())),
            _ => Ok(()),
        }
    }
}

/// The distances a target and a `through` point may lie from their origin
/// (m): both are squared (norms, the launch direction, the angle residual's
/// weight w/|target − origin|), and a distance of 10⁻³⁰⁴ m squared to 0 and
/// made that weight ∞ (found by fuzzing).
pub const RANGE_LIMITS: (f64, f64) = (1.0e-150, 1.0e150);

/// |`v`|, without overflow or underflow in the squares.
fn distance(v: V3) -> f64 {
    v.x.hypot(v.y).hypot(v.z)
}

/// A `field` (`target`, `through`) `range` metres from its origin, outside
/// [`RANGE_LIMITS`].
fn range_error(field: &str, range: f64) -> FieldError {
    let (lo, hi) = RANGE_LIMITS;
    FieldError::new(
        field,
        format!("lies {range:e} m from `origin`; it must lie {lo:e} to {hi:e} m away"),
    )
}

impl From<PointPair> for PairEntry {
    fn from(p: PointPair) -> Self {
        PairEntry {
            origin: p.origin.into(),
            through: Some(p.through.into()),
            elevation: None,
            azimuth: None,
            target: p.target.into(),
            weight: p.weight,
            wavelength: p.wavelength,
            noise: None,
        }
    }
}

impl PointPair {
    /// Checks the pair's geometry: finite coordinates, `through` ≠ `origin`, the
    /// target not straight above or below the origin, both [`RANGE_LIMITS`]
    /// away from it, a non-negative weight,
    /// a wavelength (if any) in [`WAVELENGTH_RANGE`]. Whether the medium has
    /// a wavelength at all is the problem's check.
    pub fn validate(&self) -> Result<(), FieldError> {
        for (name, v) in [
            ("origin", self.origin),
            ("through", self.through),
            ("target", self.target),
        ] {
            if v.iter().any(|c| !c.is_finite()) {
                return Err(FieldError::new(
                    name,
                    format!("coordinates must be finite numbers, got {v:?}"),
                ));
            }
        }
        if !self.weight.is_finite() || self.weight < 0.0 {
            return Err(FieldError::new(
                "weight",
                format!("must be a finite number ≥ 0, got {}", self.weight),
            ));
        }
        if let Some(nm) = self.wavelength {
            let (lo, hi) = WAVELENGTH_RANGE;
            if !(lo..=hi).contains(&nm) {
                return Err(FieldError::new(
                    "wavelength",
                    format!(
                        "the vacuum wavelength must lie in {lo}…{hi} nm (the refractivity formulas' range), got {nm}"
                    ),
                ));
            }
        }
        let o = V3::from(self.origin);
        if (V3::from(self.through) - o).norm() == 0.0 {
            return Err(FieldError::new(
                "through",
                "equals `origin`, so there is no direction to look in".to_string(),
            ));
        }
        // Beyond 10¹⁵⁴ m the direction's norm overflowed and it became 0;
        // below 10⁻¹⁵⁴ m it underflowed and the direction was not a unit.
        let reach = distance(V3::from(self.through) - o);
        if !(RANGE_LIMITS.0..=RANGE_LIMITS.1).contains(&reach) {
            return Err(range_error("through", reach));
        }
        let d = V3::from(self.target) - o;
        if d.x.hypot(d.z) == 0.0 {
            return Err(FieldError::new(
                "target",
                "is straight above or below `origin`: the target plane (facing the observer) is undefined".to_string(),
            ));
        }
        let range = distance(d);
        if !(RANGE_LIMITS.0..=RANGE_LIMITS.1).contains(&range) {
            return Err(range_error("target", range));
        }
        Ok(())
    }

    /// The observer's position.
    pub fn origin(&self) -> V3 {
        V3::from(self.origin)
    }

    /// The target point.
    pub fn target(&self) -> V3 {
        V3::from(self.target)
    }

    /// Unit launch direction, normalize(through − origin).
    pub fn direction(&self) -> V3 {
        (V3::from(self.through) - self.origin()).normalized()
    }

    /// The plane through the target that faces the observer over the flat
    /// ground: its normal is the horizontal part of target − origin.
    pub fn plane(&self) -> TargetPlane {
        self.plane_on(Earth::Flat)
    }

    /// The plane through the target that faces the observer over `earth`
    /// (`docs/air.md`): it holds the target and the local vertical there, and
    /// its normal is the horizontal direction from the origin to the target.
    pub fn plane_on(&self, earth: Earth) -> TargetPlane {
        let d = self.target() - self.origin();
        let normal = match earth {
            // The flat ground's normal, as it always was (bit for bit).
            Earth::Flat => V3::new(d.x, 0.0, d.z).normalized(),
            Earth::Round { .. } => earth
                .plane_normal(self.origin(), self.target())
                .unwrap_or_else(|| V3::new(d.x, 0.0, d.z).normalized()),
        };
        TargetPlane {
            point: self.target(),
            normal,
        }
    }

    /// This pair's ray as a batch job over the flat ground, traced as
    /// [`PointPair::evaluate`] traces it.
    pub fn ray_job(&self) -> RayJob {
        self.ray_job_on(Earth::Flat)
    }

    /// This pair's ray as a batch job over `earth`.
    pub fn ray_job_on(&self, earth: Earth) -> RayJob {
        RayJob {
            origin: self.origin(),
            direction: self.direction(),
            target: self.plane_on(earth),
        }
    }

    /// The checks that depend on the ground: over the round earth the origin
    /// must not lie below the sphere, and the target must have a horizontal
    /// direction from the origin at its own vertical.
    pub fn validate_on(&self, earth: Earth) -> Result<(), FieldError> {
        let Earth::Round { radius } = earth else {
            return Ok(());
        };
        let h = earth.height(self.origin());
        if h < 0.0 {
            return Err(FieldError::new(
                "origin",
                format!(
                    "lies {:.6} m below the ground (the sphere of radius {radius} m centred at (0, −{radius}, 0)): an observer stands on or above it",
                    -h
                ),
            ));
        }
        if earth.plane_normal(self.origin(), self.target()).is_none() {
            return Err(FieldError::new(
                "target",
                "is straight above or below `origin` along the local vertical: the target plane (facing the observer) is undefined".to_string(),
            ));
        }
        Ok(())
    }

    /// Traces this pair's ray (over `options.earth`) and returns its trace
    /// and residual `r = w·(e − target)`.
    pub fn evaluate<T: Real, F: IndexField<T> + ?Sized>(
        &self,
        field: &F,
        options: &TraceOptions,
        path: Option<&mut Vec<RayState>>,
    ) -> (Trace<T>, V3<T>) {
        let plane = self.plane_on(options.earth);
        let t = trace(
            field,
            self.origin(),
            self.direction(),
            Some(&plane),
            options,
            path,
        );
        let r = (t.endpoint - self.target().lift()) * T::cst(self.weight);
        (t, r)
    }
}
