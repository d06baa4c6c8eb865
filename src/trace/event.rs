//! The events of one accepted step, decided on its real (f64) parts: the
//! first crossing of the target plane, the ground (dips below it between the
//! step's ends included) and the maximum length. Every tracer (scalar, lanes,
//! stratified) decides by [`decide_step`], so they flag and stop the same
//! rays; the step limit, which counts attempts, is each tracer's own check.
//!
//! Where an event lies is then found by [`locate`], which refines the real θ
//! in the tracer's number type (dual numbers carry the implicit derivative).

use super::hermite::{Segment, bracketed_root};
use super::{Earth, GroundMode, RayState, TargetPlane};
use crate::math::{Real, V3};

/// How a step ends the ray, with θ ∈ [0, 1] along the step where it does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum StepEnd {
    /// It crosses the target plane at θ.
    Plane(f64),
    /// It reaches the ground at θ, in [`GroundMode::Stop`].
    Ground(f64),
    /// It reaches the maximum length (the step's end is past it).
    MaxLength,
}

/// What one step holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct StepEvents {
    /// The step goes below the ground before its end (the ray is occluded
    /// from here on).
    pub occluded: bool,
    /// How the ray ends in this step, if it does.
    pub end: Option<StepEnd>,
}

/// The events of the step `seg` toward `target` (if any): a plane crossing
/// ends the ray, a ground crossing before it flags the ray as occluded (and
/// ends it in [`GroundMode::Stop`]), and otherwise an arc length of
/// `max_length` ends it.
#[inline]
pub(crate) fn decide_step(
    seg: &Segment<f64>,
    target: Option<&TargetPlane>,
    ground: GroundMode,
    max_length: f64,
    earth: Earth,
) -> StepEvents {
    let plane_theta = target
        .filter(|t| t.signed_distance(seg.y1.x) >= 0.0)
        .map(|t| {
            bracketed_root(0.0, 1.0, |th| {
                let (x, dx) = seg.position_and_slope(th);
                (t.signed_distance(x), dx.dot(t.normal))
            })
        });
    let ground_theta = if earth.height(seg.y0.x) >= 0.0 {
        first_ground_crossing(seg, earth)
    } else {
        None
    };
    // Only a ground crossing before the plane's counts.
    let ground_theta = match plane_theta {
        Some(tp) => ground_theta.filter(|&tg| tg < tp),
        None => ground_theta,
    };
    let end = match (ground_theta, plane_theta) {
        (Some(tg), _) if ground == GroundMode::Stop => Some(StepEnd::Ground(tg)),
        (_, Some(tp)) => Some(StepEnd::Plane(tp)),
        _ => (seg.y1.s >= max_length).then_some(StepEnd::MaxLength),
    };
    StepEvents {
        occluded: ground_theta.is_some(),
        end,
    }
}

/// The first θ ∈ [0, 1] where the step goes below the ground (y = 0, or the
/// sphere), given that it starts on or above it.
pub(crate) fn first_ground_crossing(seg: &Segment<f64>, earth: Earth) -> Option<f64> {
    // The height along the step and its rate dh/dθ = ∇h · dx/dθ.
    let height = |th: f64| {
        let (x, dx) = seg.position_and_slope(th);
        let (h, up) = earth.height_and_up(x);
        (h, dx.dot(up))
    };
    if earth.height(seg.y1.x) < 0.0 {
        return Some(bracketed_root(0.0, 1.0, height));
    }
    // Both ends above ground: the step can still dip below it if it turns from
    // descending to rising inside (a mirage ray's lowest point).
    let rate = |x: V3, v: V3| v.dot(earth.up(x));
    if rate(seg.y0.x, seg.f0.dx) < 0.0
        && rate(seg.y1.x, seg.f1.dx) > 0.0
        && !surely_above_flat_ground(seg, earth)
    {
        let slope = |th: f64| {
            let (_, rate) = height(th);
            // d²h/dθ² by a central difference of the analytic rate: only the
            // sign pattern matters for bracketing the minimum.
            let e = 1e-6;
            let (hi, lo) = ((th + e).min(1.0), (th - e).max(0.0));
            (rate, (height(hi).1 - height(lo).1) / (hi - lo))
        };
        let lowest = bracketed_root(0.0, 1.0, slope);
        if earth.height(seg.position(lowest)) < 0.0 {
            return Some(bracketed_root(0.0, lowest, height));
        }
    }
    None
}

/// Whether the step's height over flat ground is surely positive all along:
/// the quintic's Bernstein coefficients over θ ∈ [0, 1] bound it from below
/// (its graph lies in their convex hull), so when the least of them clears a
/// margin far above rounding, the search for the lowest point, which would
/// find it above ground, is skipped; the answer is the same.
fn surely_above_flat_ground(seg: &Segment<f64>, earth: Earth) -> bool {
    if earth != Earth::Flat {
        return false;
    }
    let (h, h2) = (seg.h, seg.h * seg.h);
    let (p0, p1) = (seg.y0.x.y, seg.y1.x.y);
    let (v0, v1) = (h * seg.f0.dx.y, h * seg.f1.dx.y);
    let (a0, a1) = (h2 * seg.f0.dv.y, h2 * seg.f1.dv.y);
    let b = [
        p0 + 0.2 * v0,
        p0 + 0.4 * v0 + a0 / 20.0,
        p1 - 0.4 * v1 + a1 / 20.0,
        p1 - 0.2 * v1,
    ];
    let scale = [p0, p1, v0, v1, a0, a1]
        .iter()
        .fold(0.0f64, |m, x| m.max(x.abs()));
    let lowest = b.iter().fold(p0.min(p1), |m, &x| m.min(x));
    lowest > 1e-12 * scale
}

/// Where the step meets the ground at θ (found on the real trajectory): on
/// the flat ground [`locate`] on y = 0; over the sphere, on the plane tangent
/// to it below the point at θ, whose Newton step is that of the sphere to
/// first order, so dual parts carry the implicit derivative as on the plane.
pub(crate) fn locate_ground<T: Real>(
    seg: &Segment<T>,
    real: &Segment<f64>,
    theta: f64,
    earth: Earth,
) -> (V3<T>, RayState) {
    match earth {
        Earth::Flat => locate(seg, real, theta, V3::new(0.0, 1.0, 0.0), V3::ZERO),
        Earth::Round { .. } => {
            let at = real.position(theta);
            locate(seg, real, theta, earth.up(at), earth.foot(at))
        }
    }
}

/// The point where the step meets the plane through `point` with `normal`,
/// found at θ on the real trajectory and refined by one Newton step in `T`, so
/// that dual parts carry the implicit derivative dθ = −∂g/∂p / ∂g/∂θ.
pub(crate) fn locate<T: Real>(
    seg: &Segment<T>,
    real: &Segment<f64>,
    theta: f64,
    normal: V3,
    point: V3,
) -> (V3<T>, RayState) {
    let (_, slope) = real.position_and_slope(theta);
    let slope = slope.dot(normal);
    let g = (seg.position(T::cst(theta)) - point.lift()).dot(normal.lift());
    let theta_t = if slope != 0.0 && slope.is_finite() {
        T::cst(theta) - g * (1.0 / slope)
    } else {
        T::cst(theta)
    };
    (seg.position(theta_t), real.state(theta))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::RayRate;

    /// A step over flat ground that descends, then rises (a mirage ray's
    /// lowest point), with its lowest height about `low`.
    fn dip(low: f64, tilt: f64, bend: f64, h: f64) -> Segment<f64> {
        let state = |x: V3, v: V3| RayState { x, v, s: 0.0 };
        let rate = |v: V3, a: V3| RayRate {
            dx: v,
            dv: a,
            ds: 1.0,
        };
        // Heights at the ends from a parabola of curvature `bend` whose
        // vertex (height `low`) lies inside the step.
        let (x0, x1) = (-h * (0.5 + tilt), h * (0.5 - tilt));
        let y = |x: f64| low + 0.5 * bend * x * x;
        let slope = |x: f64| bend * x;
        let a = V3::new(0.0, bend, 0.0);
        Segment {
            y0: state(V3::new(0.0, y(x0), x0), V3::new(0.0, slope(x0), 1.0)),
            f0: rate(V3::new(0.0, slope(x0), 1.0), a),
            y1: state(V3::new(0.0, y(x1), x1), V3::new(0.0, slope(x1), 1.0)),
            f1: rate(V3::new(0.0, slope(x1), 1.0), a),
            h,
        }
    }

    /// The Bernstein test never skips a step that dips below the ground, and
    /// skips most of those that stay clear of it; where it skips, the full
    /// search agrees.
    #[test]
    fn the_bernstein_bound_skips_only_steps_above_the_ground() {
        let (mut skipped, mut above) = (0, 0);
        for i in 0..2000 {
            let u = |k: u32| ((i * 7919 + k as usize * 104_729) % 1000) as f64 / 1000.0;
            let low = -0.05 + 0.3 * u(1) * u(1);
            let seg = dip(
                low,
                0.45 * (2.0 * u(2) - 1.0),
                1e-4 * (1.0 + 20.0 * u(3)),
                8.0,
            );
            let sampled = (0..=10_000)
                .map(|k| seg.position(k as f64 / 10_000.0).y)
                .fold(f64::INFINITY, f64::min);
            let sure = surely_above_flat_ground(&seg, Earth::Flat);
            if sure {
                skipped += 1;
                assert!(sampled > 0.0, "step {i} dips to {sampled} yet was skipped");
                assert!(!surely_above_flat_ground(
                    &seg,
                    Earth::Round { radius: 6.371e6 }
                ));
            }
            if sampled > 1e-3 {
                above += 1;
            }
            // The search with and without the bound.
            let found = first_ground_crossing(&seg, Earth::Flat);
            assert_eq!(
                found.is_some(),
                sampled < 0.0,
                "step {i}: {found:?}, lowest {sampled}"
            );
        }
        assert!(
            skipped * 10 > above * 9,
            "{skipped} skipped of {above} well above"
        );
    }
}
