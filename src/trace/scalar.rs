//! The general tracer: one ray at a time, any medium kind, any [`Real`] (so
//! that dual numbers carry exact parameter derivatives), RK4 or Dormand–Prince;
//! each step's events are decided on its real parts by the shared
//! `event::decide_step`, and the dual-number endpoint is refined apart by
//! `event::locate`.

use super::event::{StepEnd, locate_ground};
use super::stepper::{Attempt, Stepper};
use super::{
    Earth, End, OnEarth, RayState, Segment, Stats, TargetPlane, Trace, TraceOptions, event::locate,
    state,
};
use crate::math::{Real, V3};
use crate::medium::IndexField;

/// Traces the ray from `origin` along the unit vector `direction` until it
/// crosses `target` (if given), reaches the ground in [`GroundMode::Stop`](super::GroundMode::Stop), or
/// travels the maximum length. If `path` is given, the start and every step's end
/// are appended to it (for plots); nothing is allocated otherwise. Over the
/// round earth (`options.earth`) the medium is evaluated at heights above
/// the sphere ([`OnEarth`]) and the ground is the sphere.
pub fn trace<T: Real, F: IndexField<T> + ?Sized>(
    field: &F,
    origin: V3,
    direction: V3,
    target: Option<&TargetPlane>,
    options: &TraceOptions,
    path: Option<&mut Vec<RayState>>,
) -> Trace<T> {
    trace_launched(field, origin, direction.lift(), target, options, path)
}

/// [`trace`] with a launch direction in `T`: its derivative parts (tangent
/// to the unit sphere: d·∂d = 0) carry the endpoint's derivatives with
/// respect to whatever set the direction (a camera's orientation,
/// `crate::fit::objective`), through the same steps.
pub fn trace_launched<T: Real, F: IndexField<T> + ?Sized>(
    field: &F,
    origin: V3,
    direction: V3<T>,
    target: Option<&TargetPlane>,
    options: &TraceOptions,
    path: Option<&mut Vec<RayState>>,
) -> Trace<T> {
    match options.earth {
        Earth::Flat => trace_over(field, origin, direction, target, options, path),
        Earth::Round { radius } => {
            let field = OnEarth { field, radius };
            trace_over(&field, origin, direction, target, options, path)
        }
    }
}

/// [`trace`] through `field` as the tracer sees it (over the round earth,
/// already mapped to heights).
fn trace_over<T: Real, F: IndexField<T> + ?Sized>(
    field: &F,
    origin: V3,
    direction: V3<T>,
    target: Option<&TargetPlane>,
    options: &TraceOptions,
    mut path: Option<&mut Vec<RayState>>,
) -> Trace<T> {
    let earth = options.earth;
    let max_length = match (options.max_length, target) {
        (Some(l), _) => l,
        (None, Some(t)) => 4.0 * (t.point - origin).norm(),
        (None, None) => f64::INFINITY,
    };
    let mut stats = Stats::default();
    let ceiling = field.ceiling();
    let x0 = origin.lift::<T>();
    let (delta0, _) = field.delta_gradient(x0);
    let mut y = RayState {
        x: x0,
        v: direction * (delta0 + 1.0),
        s: T::cst(0.0),
    };
    let mut f = state::rate(field, &y, &mut stats.rhs_evaluations);
    let mut stepper = Stepper::new(options.method, max_length);
    if let Some(p) = path.as_deref_mut() {
        p.push(real_state(&y));
    }

    let plane_distance =
        |x: V3<T>| target.map_or(f64::NEG_INFINITY, |t| t.signed_distance(x).val());
    let mut occluded = earth.height(origin) < 0.0;
    let mut nearest = (plane_distance(y.x).abs(), y);
    let mut steps = 0u64;
    // A stratified field keeps the ray in its vertical plane: the planar
    // stepper gives the same steps with stages for the vertical part alone.
    let planar = field.is_stratified();

    let finish = |endpoint: V3<T>, v: V3, s: f64, end: End, occluded: bool, stats: Stats| Trace {
        endpoint,
        direction: v.normalized(),
        arc_length: s,
        end,
        occluded,
        unreachable: target.is_some() && end != End::Plane,
        stats,
    };

    loop {
        if steps >= options.max_steps {
            let (_, best) = nearest;
            return finish(
                best.x,
                best.v.val(),
                best.s.val(),
                End::StepLimit,
                occluded,
                stats,
            );
        }
        steps += 1;
        let (h, up) = earth.height_and_up(y.x.val());
        stepper.limit(field.step_limit(h, y.v.val().dot(up)));
        let attempt = if planar {
            stepper.attempt_planar(field, &y, &f, &mut stats.rhs_evaluations)
        } else {
            stepper.attempt(field, &y, &f, &mut stats.rhs_evaluations)
        };
        let (y1, f1, h) = match attempt {
            Attempt::Accepted(y1, f1, h) => (y1, f1, h),
            Attempt::Rejected => {
                stats.rejected_steps += 1;
                continue;
            }
            Attempt::Underflow => {
                let (_, best) = nearest;
                return finish(
                    best.x,
                    best.v.val(),
                    best.s.val(),
                    End::StepLimit,
                    occluded,
                    stats,
                );
            }
        };
        stats.accepted_steps += 1;
        let seg = Segment {
            y0: y,
            f0: f,
            y1,
            f1,
            h,
        };
        let real = seg.val();
        if let Some(p) = path.as_deref_mut() {
            p.push(real.y1);
        }

        if earth.height(real.y1.x) > ceiling {
            return finish(y1.x, real.y1.v, real.y1.s, End::LeftAir, occluded, stats);
        }
        let d = plane_distance(y1.x).abs();
        if d < nearest.0 {
            nearest = (d, y1);
        }
        let events = super::event::decide_step(&real, target, options.ground, max_length, earth);
        occluded |= events.occluded;
        match events.end {
            Some(StepEnd::Plane(theta)) => {
                let t = target.expect("a plane crossing implies a target");
                let (endpoint, st) = locate(&seg, &real, theta, t.normal, t.point);
                return finish(endpoint, st.v, st.s, End::Plane, occluded, stats);
            }
            Some(StepEnd::Ground(theta)) => {
                let (endpoint, st) = locate_ground(&seg, &real, theta, earth);
                return finish(endpoint, st.v, st.s, End::Ground, occluded, stats);
            }
            Some(StepEnd::MaxLength) => {
                let best = if target.is_some() { nearest.1 } else { y1 };
                return finish(
                    best.x,
                    best.v.val(),
                    best.s.val(),
                    End::MaxLength,
                    occluded,
                    stats,
                );
            }
            None => {}
        }
        y = y1;
        f = f1;
    }
}

fn real_state<T: Real>(y: &RayState<T>) -> RayState {
    RayState {
        x: y.x.val(),
        v: y.v.val(),
        s: y.s.val(),
    }
}
