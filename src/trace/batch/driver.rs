//! The batch loop: lanes take jobs in order, step together (each lane
//! accepting or rejecting its own adaptive step), and the rays whose accepted
//! step may hold an event are resolved one by one by the scalar tracer's code
//! ([`decide_step`]); a lane whose ray is done takes the next job, and when
//! none is left it is frozen (step 0). Nothing is allocated per step.

use super::field::LaneField;
use super::job::{BatchOptions, RayJob};
use super::lanes::Attempts;
use crate::math::V3;
use crate::medium::IndexField;
use crate::trace::event::{StepEnd, decide_step, locate, locate_ground};
use crate::trace::{End, RayRate, RayState, Segment, Stats, Trace, state};

/// A trace that the driver overwrites (slots of the output before tracing).
pub(crate) fn placeholder() -> Trace {
    Trace {
        endpoint: V3::new(f64::NAN, f64::NAN, f64::NAN),
        direction: V3::ZERO,
        arc_length: f64::NAN,
        end: End::StepLimit,
        occluded: false,
        unreachable: true,
        stats: Stats::default(),
    }
}

/// A lane kernel: the state of `N` rays (at most [`LANES`](super::LANES)) and
/// one step over all of them (RK4, or a Dormand–Prince attempt per lane). The
/// driver ([`drive`]) owns the jobs and the event logic.
pub(crate) trait Kernel<const N: usize> {
    /// The medium it steps through.
    type Field: LaneField;
    /// That medium (its scalar form starts the rays).
    fn field(&self) -> &Self::Field;
    /// Puts a ray into `lane`: its start state and rate (evaluated by the
    /// scalar field, exactly as the scalar tracer starts) and its limits; its
    /// step control starts as the scalar stepper's.
    fn load(
        &mut self,
        lane: usize,
        job: &RayJob,
        start: &RayState,
        rate: &RayRate,
        max_length: f64,
    );
    /// Stops `lane` from moving (its step becomes 0).
    fn freeze(&mut self, lane: usize);
    /// Right-hand-side evaluations per attempted step.
    fn stages(&self) -> u64;
    /// One step (or attempt) of every lane; the previous state stays
    /// readable, and a lane whose attempt was not accepted keeps its state.
    fn step<const FMA: bool>(&mut self) -> Attempts;
    /// After a step: updates each lane's nearest point to its plane and returns
    /// the lanes whose step may hold an event (plane crossing, ground, maximum
    /// length), as a bit mask. May report more lanes, never fewer.
    fn scan(&mut self) -> u64;
    /// The last step of `lane`, in 3-D.
    fn segment(&self, lane: usize) -> Segment<f64>;
    /// The traced point of `lane` nearest its plane so far.
    fn nearest(&self, lane: usize) -> RayState;
    /// The ray of `job` (index `index` in the batch) in `lane` has ended,
    /// crossing its plane at θ = `plane` of its last step if `Some`, before
    /// the lane takes the next job. Nothing by default.
    #[inline(always)]
    fn finished(&mut self, _lane: usize, _index: usize, _job: &RayJob, _plane: Option<f64>) {}
}

/// Bookkeeping of the ray in one lane.
#[derive(Clone, Copy)]
struct Slot {
    job: usize,
    /// Global step count when the ray was loaded: every live lane attempts a
    /// step each round, so `global − start` is the ray's attempts.
    start: u64,
    /// Accepted and rejected attempts.
    accepted: u64,
    rejected: u64,
    occluded: bool,
    max_length: f64,
}

/// The batch loop, inlined into each instruction-set build so that the kernel's
/// step is compiled for that set.
#[inline(always)]
pub(crate) fn drive<K: Kernel<N>, const N: usize, const FMA: bool>(
    kernel: &mut K,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) {
    let mut slots = [Slot {
        job: 0,
        start: 0,
        accepted: 0,
        rejected: 0,
        occluded: false,
        max_length: 0.0,
    }; N];
    let stages = kernel.stages();
    let mut next = 0;
    let mut live = 0u64;
    let mut global = 0u64;
    for lane in 0..N {
        refill(
            kernel, lane, jobs, options, out, &mut next, &mut slots, &mut live, global,
        );
    }
    while live != 0 {
        let attempts = kernel.step::<FMA>();
        global += 1;
        let accepted = attempts.accepted & live;
        let underflow = attempts.underflow & live;
        for (lane, slot) in slots.iter_mut().enumerate() {
            if live >> lane & 1 == 1 {
                if accepted >> lane & 1 == 1 {
                    slot.accepted += 1;
                } else if underflow >> lane & 1 == 0 {
                    slot.rejected += 1;
                }
            }
        }
        let mut events = (kernel.scan() & accepted) | underflow;
        // Every live ray started at or after slot.start, so only a ray loaded
        // max_steps ago can hit the limit now.
        if let Some(first) = global.checked_sub(options.max_steps) {
            for (lane, slot) in slots.iter().enumerate() {
                if live >> lane & 1 == 1 && slot.start <= first {
                    events |= 1 << lane;
                }
            }
        }
        while events != 0 {
            let lane = events.trailing_zeros() as usize;
            events &= events - 1;
            let slot = &mut slots[lane];
            let attempts = global - slot.start;
            let job = &jobs[slot.job];
            let done = if accepted >> lane & 1 == 1 {
                let seg = kernel.segment(lane);
                let ceiling = kernel.field().ceiling();
                after_step(&seg, job, slot, options, attempts, ceiling, stages, || {
                    kernel.nearest(lane)
                })
            } else {
                // The step underflowed (the scalar tracer gives up there), or
                // a rejected attempt was the last one allowed.
                let best = kernel.nearest(lane);
                let t = finished(best.x, best.v, best.s, End::StepLimit, slot, stages);
                Some((t, None))
            };
            if let Some((t, plane)) = done {
                kernel.finished(lane, slot.job, job, plane);
                out[slot.job] = t;
                refill(
                    kernel, lane, jobs, options, out, &mut next, &mut slots, &mut live, global,
                );
            }
        }
    }
}

/// Loads the next job into `lane`, or freezes the lane when none is left.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn refill<K: Kernel<N>, const N: usize>(
    kernel: &mut K,
    lane: usize,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
    next: &mut usize,
    slots: &mut [Slot; N],
    live: &mut u64,
    global: u64,
) {
    while *next < jobs.len() {
        let j = *next;
        *next += 1;
        let job = &jobs[j];
        // The start state exactly as the scalar tracer computes it.
        let field = kernel.field();
        let (delta0, _) = field.delta_gradient(job.origin);
        let y = RayState {
            x: job.origin,
            v: job.direction * (delta0 + 1.0),
            s: 0.0,
        };
        let mut evaluations = 0;
        let f = state::rate(field, &y, &mut evaluations);
        let max_length = options
            .max_length
            .unwrap_or(4.0 * (job.target.point - job.origin).norm());
        let slot = Slot {
            job: j,
            start: global,
            accepted: 0,
            rejected: 0,
            occluded: options.earth.height(job.origin) < 0.0,
            max_length,
        };
        if options.max_steps == 0 {
            out[j] = finished(y.x, y.v, y.s, End::StepLimit, &slot, kernel.stages());
            continue;
        }
        kernel.load(lane, job, &y, &f, max_length);
        slots[lane] = slot;
        *live |= 1 << lane;
        return;
    }
    kernel.freeze(lane);
    *live &= !(1 << lane);
}

/// The scalar tracer's logic after one accepted step (the ceiling, the events
/// of [`decide_step`], then the step limit, as `trace` checks them): the
/// finished trace if the ray ends in this step, with the step's θ where it
/// crosses its plane (if that is how it ends).
#[allow(clippy::too_many_arguments)]
fn after_step(
    seg: &Segment<f64>,
    job: &RayJob,
    slot: &mut Slot,
    options: &BatchOptions,
    attempts: u64,
    ceiling: f64,
    stages: u64,
    nearest: impl FnOnce() -> RayState,
) -> Option<(Trace, Option<f64>)> {
    if options.earth.height(seg.y1.x) > ceiling {
        let y1 = &seg.y1;
        return Some((finished(y1.x, y1.v, y1.s, End::LeftAir, slot, stages), None));
    }
    let t = &job.target;
    let events = decide_step(seg, Some(t), options.ground, slot.max_length, options.earth);
    slot.occluded |= events.occluded;
    let end = match events.end {
        Some(StepEnd::Plane(theta)) => {
            let (e, st) = locate(seg, seg, theta, t.normal, t.point);
            let trace = finished(e, st.v, st.s, End::Plane, slot, stages);
            return Some((trace, Some(theta)));
        }
        Some(StepEnd::Ground(theta)) => {
            let (e, st) = locate_ground(seg, seg, theta, options.earth);
            return Some((finished(e, st.v, st.s, End::Ground, slot, stages), None));
        }
        Some(StepEnd::MaxLength) => End::MaxLength,
        None if attempts >= options.max_steps => End::StepLimit,
        None => return None,
    };
    let best = nearest();
    Some((finished(best.x, best.v, best.s, end, slot, stages), None))
}

/// A finished trace (a target plane is always given, so any other end than the
/// plane makes the ray unreachable), with the slot's statistics.
fn finished(endpoint: V3, v: V3, s: f64, end: End, slot: &Slot, stages: u64) -> Trace {
    Trace {
        endpoint,
        direction: v.normalized(),
        arc_length: s,
        end,
        occluded: slot.occluded,
        unreachable: end != End::Plane,
        stats: Stats {
            // The start rate, then the new evaluations of every attempt
            // that ran its stages (an underflowed one ran none).
            rhs_evaluations: 1 + stages * (slot.accepted + slot.rejected),
            accepted_steps: slot.accepted,
            rejected_steps: slot.rejected,
        },
    }
}
