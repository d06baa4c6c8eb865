//! Many rays at once: fixed-step RK4 through a [`LogisticField`] over
//! [`LANES`] rays held in structure-of-arrays lanes, with the instruction set
//! picked at run time.
//!
//! # Semantics
//!
//! Each ray is traced exactly as [`trace`](super::trace) traces it with
//! [`Method::Rk4`] and a target plane: the same τ-form state, the same step
//! sequence, the endpoint where the quintic Hermite interpolant of the crossing
//! step meets the plane, `occluded` (also for dips below the ground between two
//! step ends), `unreachable` with the traced point nearest the plane, the
//! maximum length (default 4 × the distance to the target), the step limit,
//! [`GroundMode`], and the same [`Stats`]. The only numerical difference is
//! the exponential: a polynomial ([`fastexp`](super::fastexp), within 1 ulp of
//! `f64::exp`) instead of libm's, and fused multiply–adds where the CPU has
//! them; endpoints agree with the scalar tracer to about 10⁻¹¹ m
//! (`tests/fast_paths.rs` checks 10⁻⁹ m).
//!
//! # How it is fast
//!
//! The scalar tracer spends its time in 16 `exp` calls per RK4 step (full
//! medium, one hot spot), which the compiler cannot vectorize. Here each
//! right-hand-side term is one branch-free loop over the lanes, with the
//! polynomial exponential inlined, so it compiles to SIMD code; [`Isa`] selects
//! an AVX-512, AVX2+FMA or baseline build of the whole kernel at run time.
//! Several terms share a lane loop (the layers with the first hot spot, hot
//! spots two by two) so that independent exponentials overlap. On the CPU this
//! was written on (AMD EPYC with AVX-512) that is about 50 M RK4 steps per
//! second per core through the full medium with one hot spot, ten times the
//! scalar tracer (`cargo bench --bench trace`).
//! Events (plane, ground, maximum length) are screened for all lanes with a
//! cheap vector test after each step and resolved per lane by the scalar code
//! of the tracer; a lane whose ray is done takes the next job, and when none is
//! left it is frozen (step 0). Nothing is allocated per step.
//!
//! # Use
//!
//! ```
//! use mirage::medium::{Background, LogisticMedium};
//! use mirage::pair::PointPair;
//! use mirage::trace::lanes::{BatchOptions, RayJob, trace_batch};
//! use mirage::trace::{Method, TraceOptions};
//!
//! let medium = LogisticMedium {
//!     background: Some(Background { n: 1.0, a: 40.0 }),
//!     ..LogisticMedium::vacuum()
//! };
//! let pair = PointPair {
//!     origin: [0.0, 2.0, 0.0],
//!     through: [0.0, 2.0, 100.0],
//!     target: [0.0, 2.0, 100.0],
//!     weight: 1.0,
//! };
//! let options = BatchOptions::from_trace_options(&TraceOptions::new(Method::Rk4 { step: 1.0 }))
//!     .expect("an RK4 method");
//! let traces = trace_batch(&medium.field(), &[RayJob::from_pair(&pair)], &options);
//! assert!(!traces[0].unreachable);
//! ```

// Lane loops index several arrays in lockstep; `for i in 0..N` over fixed-size
// arrays is the form the compiler vectorizes.
#![allow(clippy::needless_range_loop)]

use super::hermite::bracketed_root;
use super::{
    End, GroundMode, Method, RayRate, RayState, Segment, Stats, TargetPlane, Trace, TraceOptions,
    fastexp::{exp_core, fmadd, sigmoid},
    state, stratified,
};
use crate::math::V3;
use crate::medium::{IndexField, LogisticField};
use crate::pair::PointPair;

/// Rays traced side by side: two AVX-512 (four AVX2) registers per
/// operation. Measured faster than 8 (too few independent chains to hide the
/// latency of the polynomial's dependent multiply–adds) and than 32 (register
/// spills). Batches of at most `LANES / 2` rays run an 8-lane build instead,
/// which leaves no idle half to compute.
pub const LANES: usize = 16;
const _: () = assert!(LANES <= 64, "lane masks are u64");

/// Screening margin (metres) for the plane-crossing test of the vector scan:
/// the exact test runs afterwards in scalar code, so the screen only needs to
/// let through every step that the exact test could accept.
pub(crate) const CROSSING_MARGIN: f64 = 1e-6;

/// An instruction set the kernels are compiled for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Isa {
    /// Whatever the build target guarantees (SSE2 on x86-64); no FMA.
    Baseline,
    /// AVX2 with FMA.
    Avx2,
    /// AVX-512F (with AVX2 and FMA).
    Avx512,
}

impl Isa {
    /// Every instruction set, widest last.
    pub const ALL: [Isa; 3] = [Isa::Baseline, Isa::Avx2, Isa::Avx512];

    /// The widest instruction set this CPU has.
    pub fn detect() -> Isa {
        if Isa::Avx512.is_available() {
            Isa::Avx512
        } else if Isa::Avx2.is_available() {
            Isa::Avx2
        } else {
            Isa::Baseline
        }
    }

    /// Whether this CPU can run code built for `self`.
    pub fn is_available(self) -> bool {
        match self {
            Isa::Baseline => true,
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => {
                std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma")
            }
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => {
                std::is_x86_feature_detected!("avx512f")
                    && std::is_x86_feature_detected!("avx2")
                    && std::is_x86_feature_detected!("fma")
            }
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// The instruction sets this CPU can run.
    pub fn available() -> Vec<Isa> {
        Isa::ALL.into_iter().filter(|i| i.is_available()).collect()
    }

    /// Short name, for reports and benchmark labels.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Baseline => "baseline",
            Isa::Avx2 => "avx2",
            Isa::Avx512 => "avx512",
        }
    }
}

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

impl RayJob {
    /// The ray of a point pair, as [`PointPair::evaluate`] traces it.
    pub fn from_pair(pair: &PointPair) -> Self {
        RayJob {
            origin: pair.origin(),
            direction: pair.direction(),
            target: pair.plane(),
        }
    }
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

/// Traces every job by the fastest path for this field and CPU: the 2-D
/// [`stratified`] kernel when the field has no hot spots, the 3-D lanes kernel
/// otherwise. `result[i]` is the trace of `jobs[i]`.
pub fn trace_batch(field: &LogisticField, jobs: &[RayJob], options: &BatchOptions) -> Vec<Trace> {
    let mut out = vec![placeholder(); jobs.len()];
    trace_batch_into(field, jobs, options, &mut out);
    out
}

/// [`trace_batch`] into a slice of the same length as `jobs` (reusable across
/// calls; its contents are overwritten).
///
/// # Panics
/// If `out.len() != jobs.len()`.
pub fn trace_batch_into(
    field: &LogisticField,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) {
    let isa = Isa::detect();
    if stratified::trace_batch_2d(isa, field, jobs, options, out).is_err() {
        trace_batch_3d(isa, field, jobs, options, out);
    }
}

/// Traces every job with the 3-D lanes kernel built for `isa` (any field).
///
/// # Panics
/// If `out.len() != jobs.len()`, or if this CPU cannot run `isa`.
pub fn trace_batch_3d(
    isa: Isa,
    field: &LogisticField,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) {
    let c = Coefficients::of(field);
    // A small batch (a fit with few pairs, split over threads) would leave
    // half of the lanes idle, yet computed: take the half-width kernel.
    if jobs.len() <= LANES / 2 {
        run(
            isa,
            &mut Lanes3::<{ LANES / 2 }>::new(c),
            field,
            jobs,
            options,
            out,
        );
    } else {
        run(isa, &mut Lanes3::<LANES>::new(c), field, jobs, options, out);
    }
}

/// Replaces each element of `xs` by its exponential as the kernels built for
/// `isa` compute it (the polynomial of [`fastexp`](super::fastexp), fused
/// multiply–adds on AVX2 and AVX-512), so that tests can check every build.
/// Below −708 this gives 0, like [`fastexp::exp`](super::fastexp::exp); the
/// kernels' logistic function clamps such arguments to −708 instead (the same
/// σ to within 3.3·10⁻³⁰⁸).
///
/// # Panics
/// If this CPU cannot run `isa`.
pub fn exp_in_place(isa: Isa, xs: &mut [f64]) {
    #[inline(always)]
    fn each<const FMA: bool>(xs: &mut [f64]) {
        for x in xs {
            *x = if *x > 709.0 {
                f64::INFINITY
            } else {
                exp_core::<FMA>(*x)
            };
        }
    }
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx2,fma")]
    unsafe fn avx512(xs: &mut [f64]) {
        each::<true>(xs)
    }
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn avx2(xs: &mut [f64]) {
        each::<true>(xs)
    }
    assert!(isa.is_available(), "this CPU cannot run {isa:?} code");
    match isa {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the CPU has AVX-512F, AVX2 and FMA (checked above).
        Isa::Avx512 => unsafe { avx512(xs) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the CPU has AVX2 and FMA (checked above).
        Isa::Avx2 => unsafe { avx2(xs) },
        _ => each::<false>(xs),
    }
}

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

/// The compiled field as plain numbers (see `LogisticField::coefficients`).
#[derive(Clone, Debug)]
pub(crate) struct Coefficients {
    /// Background `[amp, 1/a]`.
    pub background: Option<[f64; 2]>,
    /// Inversion `[amp, 1/a, height]`.
    pub inversion: Option<[f64; 3]>,
    /// Hot spots `[amp, 1/a, x, z, radius, edge]`.
    pub hotspots: Vec<[f64; 6]>,
}

impl Coefficients {
    pub(crate) fn of(field: &LogisticField) -> Self {
        let raw = field.coefficients();
        Coefficients {
            background: raw.background,
            inversion: raw.inversion,
            hotspots: raw.hotspots,
        }
    }

    /// Adds the stratified terms' δ and dδ/dy at heights `y` to `d` and `gy`,
    /// with the operations of `LogisticField::delta_gradient` in its order.
    #[inline(always)]
    pub(crate) fn layers<const N: usize, const FMA: bool>(
        &self,
        y: &[f64; N],
        d: &mut [f64; N],
        gy: &mut [f64; N],
    ) {
        // Each combination of terms gets its own loop (the const parameters),
        // so no lane loop tests for absent terms.
        match (self.background, self.inversion) {
            (Some(bg), Some(inv)) => layer_loop::<N, FMA, true, true>(bg, inv, y, d, gy),
            (Some(bg), None) => layer_loop::<N, FMA, true, false>(bg, [0.0; 3], y, d, gy),
            (None, Some(inv)) => layer_loop::<N, FMA, false, true>([0.0; 2], inv, y, d, gy),
            (None, None) => {}
        }
    }

    /// δ and ∇δ at the lanes' positions, the whole field with hot spots,
    /// accumulated into `d` and `g` (which the caller zeroes).
    #[inline(always)]
    fn delta_gradient<const N: usize, const FMA: bool>(
        &self,
        p: [&[f64; N]; 3],
        d: &mut [f64; N],
        g: [&mut [f64; N]; 3],
    ) {
        match (self.background, self.inversion) {
            (Some(bg), Some(inv)) => self.full::<N, FMA, true, true>(bg, inv, p, d, g),
            (Some(bg), None) => self.full::<N, FMA, true, false>(bg, [0.0; 3], p, d, g),
            (None, Some(inv)) => self.full::<N, FMA, false, true>([0.0; 2], inv, p, d, g),
            (None, None) => self.full::<N, FMA, false, false>([0.0; 2], [0.0; 3], p, d, g),
        }
    }

    /// [`Self::delta_gradient`] for one combination of layers. The layers
    /// share a lane loop with the first hot spot, and further hot spots go two
    /// to a loop: several independent exponentials per lane keep enough
    /// multiply–add chains in flight to hide their latency. Terms are still
    /// added in the scalar code's order.
    #[inline(always)]
    fn full<const N: usize, const FMA: bool, const BG: bool, const INV: bool>(
        &self,
        bg: [f64; 2],
        inv: [f64; 3],
        [x, y, z]: [&[f64; N]; 3],
        d: &mut [f64; N],
        [gx, gy, gz]: [&mut [f64; N]; 3],
    ) {
        let Some((first, rest)) = self.hotspots.split_first() else {
            if BG || INV {
                layer_loop::<N, FMA, BG, INV>(bg, inv, y, d, gy);
            }
            return;
        };
        for i in 0..N {
            let (di, gyi) = layer_point::<FMA, BG, INV>(bg, inv, y[i], d[i], gy[i]);
            let acc = hot_point::<FMA>(*first, x[i], y[i], z[i], [di, gx[i], gyi, gz[i]]);
            [d[i], gx[i], gy[i], gz[i]] = acc;
        }
        for pair in rest.chunks(2) {
            match *pair {
                [h0, h1] => {
                    for i in 0..N {
                        let acc = [d[i], gx[i], gy[i], gz[i]];
                        let acc = hot_point::<FMA>(h0, x[i], y[i], z[i], acc);
                        let acc = hot_point::<FMA>(h1, x[i], y[i], z[i], acc);
                        [d[i], gx[i], gy[i], gz[i]] = acc;
                    }
                }
                [h0] => {
                    for i in 0..N {
                        let acc = [d[i], gx[i], gy[i], gz[i]];
                        [d[i], gx[i], gy[i], gz[i]] = hot_point::<FMA>(h0, x[i], y[i], z[i], acc);
                    }
                }
                _ => unreachable!("chunks of at most two"),
            }
        }
    }
}

/// The layers' loop over lanes: adds the background (if `BG`) and the
/// inversion (if `INV`) to `d` and `gy`.
#[inline(always)]
fn layer_loop<const N: usize, const FMA: bool, const BG: bool, const INV: bool>(
    bg: [f64; 2],
    inv: [f64; 3],
    y: &[f64; N],
    d: &mut [f64; N],
    gy: &mut [f64; N],
) {
    for i in 0..N {
        (d[i], gy[i]) = layer_point::<FMA, BG, INV>(bg, inv, y[i], d[i], gy[i]);
    }
}

/// `d` and `gy` plus the layers' terms at height y, in the scalar order.
#[inline(always)]
fn layer_point<const FMA: bool, const BG: bool, const INV: bool>(
    bg: [f64; 2],
    inv: [f64; 3],
    y: f64,
    mut d: f64,
    mut gy: f64,
) -> (f64, f64) {
    if BG {
        let (db, gb) = background_term::<FMA>(bg, y);
        d += db;
        gy += gb;
    }
    if INV {
        let (di, gi) = inversion_term::<FMA>(inv, y);
        d += di;
        gy -= gi;
    }
    (d, gy)
}

/// (δ, ∂δ/∂x, ∂δ/∂y, ∂δ/∂z) plus one hot spot's terms at (x, y, z), with the
/// operations of `LogisticField::delta_gradient`.
#[inline(always)]
fn hot_point<const FMA: bool>(
    [amp, inv_rate, hx, hz, radius, edge]: [f64; 6],
    x: f64,
    y: f64,
    z: f64,
    [d, gx, gy, gz]: [f64; 4],
) -> [f64; 4] {
    let dx = x - hx;
    let dz = z - hz;
    // ρ without the scalar code's rescaling: an overflow to ∞ for
    // |dx| > 10¹⁵⁴ still gives w = 0 and a zero gradient, not NaN.
    let rho = fmadd::<FMA>(dx, dx, dz * dz).sqrt();
    let (w, dw) = sigmoid::<FMA>(edge * (radius - rho));
    let dw_drho = -(edge * dw);
    // At the cone tip (ρ = 0) the horizontal derivative is 0; so it is where
    // dx² + dz² underflows (within 10⁻¹⁶² m of the centre), where ρ = 0 too
    // and dx/ρ would blow up.
    let inv_rho = if rho > 0.0 { 1.0 / rho } else { 0.0 };
    let ux = dx * inv_rho;
    let uz = dz * inv_rho;
    let (s, ds) = sigmoid::<FMA>(y * inv_rate);
    let amp_s = amp * s;
    [
        d + amp_s * w,
        gx + amp_s * dw_drho * ux,
        gy + amp * w * ds * inv_rate,
        gz + amp_s * dw_drho * uz,
    ]
}

/// The background's (δ, dδ/dy) at height y.
#[inline(always)]
fn background_term<const FMA: bool>([amp, inv_rate]: [f64; 2], y: f64) -> (f64, f64) {
    let (s, ds) = sigmoid::<FMA>(y * inv_rate);
    (amp * s, amp * ds * inv_rate)
}

/// The inversion's δ and −dδ/dy at height y (subtracted, as in the scalar code).
#[inline(always)]
fn inversion_term<const FMA: bool>([amp, inv_rate, height]: [f64; 3], y: f64) -> (f64, f64) {
    let (s, ds) = sigmoid::<FMA>((height - y) * inv_rate);
    (amp * s, amp * ds * inv_rate)
}

/// A lane kernel: the state of [`LANES`] rays and one RK4 step over all of
/// them. The driver ([`run`]) owns the jobs and the event logic.
pub(crate) trait Kernel<const N: usize> {
    /// Puts a ray into `lane`: its start state and rate (evaluated by the
    /// scalar field, exactly as the scalar tracer starts), step and limits.
    fn load(
        &mut self,
        lane: usize,
        job: &RayJob,
        start: &RayState,
        rate: &RayRate,
        step: f64,
        max_length: f64,
    );
    /// Stops `lane` from moving (its step becomes 0).
    fn freeze(&mut self, lane: usize);
    /// One RK4 step of every lane; the previous state stays readable.
    fn step<const FMA: bool>(&mut self);
    /// After a step: updates each lane's nearest point to its plane and returns
    /// the lanes whose step may hold an event (plane crossing, ground, maximum
    /// length), as a bit mask. May report more lanes, never fewer.
    fn scan(&mut self) -> u64;
    /// The last step of `lane`, in 3-D.
    fn segment(&self, lane: usize) -> Segment<f64>;
    /// The traced point of `lane` nearest its plane so far.
    fn nearest(&self, lane: usize) -> RayState;
}

/// Runs `kernel` over `jobs` with the build for `isa`.
pub(crate) fn run<K: Kernel<N>, const N: usize>(
    isa: Isa,
    kernel: &mut K,
    field: &LogisticField,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) {
    assert_eq!(out.len(), jobs.len(), "one output slot per job");
    assert!(isa.is_available(), "this CPU cannot run {isa:?} code");
    match isa {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the CPU has AVX-512F, AVX2 and FMA (checked above).
        Isa::Avx512 => unsafe { drive_avx512(kernel, field, jobs, options, out) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the CPU has AVX2 and FMA (checked above).
        Isa::Avx2 => unsafe { drive_avx2(kernel, field, jobs, options, out) },
        _ => drive::<K, N, false>(kernel, field, jobs, options, out),
    }
}

/// [`drive`] compiled for AVX-512: its inlined lane loops become 512-bit code.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
unsafe fn drive_avx512<K: Kernel<N>, const N: usize>(
    kernel: &mut K,
    field: &LogisticField,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) {
    drive::<K, N, true>(kernel, field, jobs, options, out)
}

/// [`drive`] compiled for AVX2 with FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn drive_avx2<K: Kernel<N>, const N: usize>(
    kernel: &mut K,
    field: &LogisticField,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) {
    drive::<K, N, true>(kernel, field, jobs, options, out)
}

/// Bookkeeping of the ray in one lane.
#[derive(Clone, Copy)]
struct Slot {
    job: usize,
    /// Global step count when the ray was loaded.
    start: u64,
    occluded: bool,
    max_length: f64,
}

/// The batch loop, inlined into each instruction-set build so that the kernel's
/// step is compiled for that set.
#[inline(always)]
fn drive<K: Kernel<N>, const N: usize, const FMA: bool>(
    kernel: &mut K,
    field: &LogisticField,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) {
    let mut slots = [Slot {
        job: 0,
        start: 0,
        occluded: false,
        max_length: 0.0,
    }; N];
    let mut next = 0;
    let mut live = 0u64;
    let mut global = 0u64;
    for lane in 0..N {
        refill(
            kernel, lane, field, jobs, options, out, &mut next, &mut slots, &mut live, global,
        );
    }
    while live != 0 {
        kernel.step::<FMA>();
        global += 1;
        let mut events = kernel.scan() & live;
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
            let steps = global - slot.start;
            let job = &jobs[slot.job];
            let seg = kernel.segment(lane);
            if let Some(t) = after_step(&seg, job, slot, options, steps, || kernel.nearest(lane)) {
                out[slot.job] = t;
                refill(
                    kernel, lane, field, jobs, options, out, &mut next, &mut slots, &mut live,
                    global,
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
    field: &LogisticField,
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
        let occluded = job.origin.y < 0.0;
        if options.max_steps == 0 {
            out[j] = finished(y.x, y.v, y.s, End::StepLimit, occluded, 0);
            continue;
        }
        kernel.load(lane, job, &y, &f, options.step, max_length);
        slots[lane] = Slot {
            job: j,
            start: global,
            occluded,
            max_length,
        };
        *live |= 1 << lane;
        return;
    }
    kernel.freeze(lane);
    *live &= !(1 << lane);
}

/// The scalar tracer's logic after one accepted step (see `trace` in
/// `mod.rs`): the finished trace if the ray ends in this step.
fn after_step(
    seg: &Segment<f64>,
    job: &RayJob,
    slot: &mut Slot,
    options: &BatchOptions,
    steps: u64,
    nearest: impl FnOnce() -> RayState,
) -> Option<Trace> {
    let t = &job.target;
    let plane_theta = (t.signed_distance(seg.y1.x) >= 0.0).then(|| {
        bracketed_root(0.0, 1.0, |th| {
            let (x, dx) = seg.position_and_slope(th);
            (t.signed_distance(x), dx.dot(t.normal))
        })
    });
    let ground_theta = if seg.y0.x.y >= 0.0 {
        super::first_ground_crossing(seg)
    } else {
        None
    };
    let ground_end = |theta: f64, occluded: bool| {
        let (e, st) = super::locate(seg, seg, theta, V3::new(0.0, 1.0, 0.0), V3::ZERO);
        finished(e, st.v, st.s, End::Ground, occluded, steps)
    };
    match (plane_theta, ground_theta) {
        (Some(tp), tg) => {
            if let Some(tg) = tg.filter(|&tg| tg < tp) {
                slot.occluded = true;
                if options.ground == GroundMode::Stop {
                    return Some(ground_end(tg, true));
                }
            }
            let (e, st) = super::locate(seg, seg, tp, t.normal, t.point);
            return Some(finished(e, st.v, st.s, End::Plane, slot.occluded, steps));
        }
        (None, Some(tg)) => {
            slot.occluded = true;
            if options.ground == GroundMode::Stop {
                return Some(ground_end(tg, true));
            }
        }
        (None, None) => {}
    }
    let end = if seg.y1.s >= slot.max_length {
        End::MaxLength
    } else if steps >= options.max_steps {
        End::StepLimit
    } else {
        return None;
    };
    let best = nearest();
    Some(finished(best.x, best.v, best.s, end, slot.occluded, steps))
}

/// A finished trace (a target plane is always given, so any other end than the
/// plane makes the ray unreachable).
fn finished(endpoint: V3, v: V3, s: f64, end: End, occluded: bool, steps: u64) -> Trace {
    Trace {
        endpoint,
        direction: v.normalized(),
        arc_length: s,
        end,
        occluded,
        unreachable: end != End::Plane,
        stats: Stats {
            // The start rate, then four new evaluations per RK4 step.
            rhs_evaluations: 1 + 4 * steps,
            accepted_steps: steps,
            rejected_steps: 0,
        },
    }
}

/// One buffer of lane states: position, v = n·t, arc length, and the rate's
/// non-trivial parts (a = dv/dτ = n∇n, n = ds/dτ; dx/dτ is v itself).
#[derive(Clone, Copy)]
struct Buf3<const N: usize> {
    x: [f64; N],
    y: [f64; N],
    z: [f64; N],
    vx: [f64; N],
    vy: [f64; N],
    vz: [f64; N],
    s: [f64; N],
    ax: [f64; N],
    ay: [f64; N],
    az: [f64; N],
    n: [f64; N],
}

impl<const N: usize> Buf3<N> {
    const ZERO: Self = Buf3 {
        x: [0.0; N],
        y: [0.0; N],
        z: [0.0; N],
        vx: [0.0; N],
        vy: [0.0; N],
        vz: [0.0; N],
        s: [0.0; N],
        ax: [0.0; N],
        ay: [0.0; N],
        az: [0.0; N],
        // n = 1 in idle lanes: the state of a ray in vacuum, harmless to step.
        n: [1.0; N],
    };

    fn state(&self, i: usize) -> (RayState, RayRate) {
        let v = V3::new(self.vx[i], self.vy[i], self.vz[i]);
        (
            RayState {
                x: V3::new(self.x[i], self.y[i], self.z[i]),
                v,
                s: self.s[i],
            },
            RayRate {
                dx: v,
                dv: V3::new(self.ax[i], self.ay[i], self.az[i]),
                ds: self.n[i],
            },
        )
    }

    /// Sets the rate from the field at the buffer's positions (n = 1 + δ,
    /// a = ∇δ·n, as `state::rate`), accumulating δ and ∇δ in place.
    #[inline(always)]
    fn set_rate<const FMA: bool>(&mut self, c: &Coefficients) {
        self.n = [0.0; N];
        self.ax = [0.0; N];
        self.ay = [0.0; N];
        self.az = [0.0; N];
        c.delta_gradient::<N, FMA>(
            [&self.x, &self.y, &self.z],
            &mut self.n,
            [&mut self.ax, &mut self.ay, &mut self.az],
        );
        for i in 0..N {
            let n = self.n[i] + 1.0;
            self.n[i] = n;
            self.ax[i] *= n;
            self.ay[i] *= n;
            self.az[i] *= n;
        }
    }
}

/// RK4's final sum `y + h/6·k1 + h/3·k2 + h/3·k3 + h/6·k4` for one component,
/// added in the scalar `RayState::advanced`'s order; `b` holds the four
/// weights times h.
#[inline(always)]
pub(crate) fn combine<const FMA: bool>(y: f64, k: [f64; 4], b: [f64; 4]) -> f64 {
    let y = fmadd::<FMA>(k[0], b[0], y);
    let y = fmadd::<FMA>(k[1], b[1], y);
    let y = fmadd::<FMA>(k[2], b[2], y);
    fmadd::<FMA>(k[3], b[3], y)
}

/// The 3-D lane kernel: the full field, hot spots included.
pub(crate) struct Lanes3<const N: usize> {
    c: Coefficients,
    buf: [Buf3<N>; 2],
    /// The stages k2, k3, k4 of a step (kept here, not re-initialised on the
    /// stack every step).
    stages: [Buf3<N>; 3],
    /// Index of the buffer with the current state; the other holds the
    /// previous one (the start of the last step).
    cur: usize,
    h: [f64; N],
    /// Target plane: point and normal.
    plane: [[f64; N]; 6],
    max_length: [f64; N],
    /// Distance to the plane of the nearest point so far, and that point's
    /// state (x, y, z, vx, vy, vz, s).
    near_d: [f64; N],
    near: [[f64; N]; 7],
}

impl<const N: usize> Lanes3<N> {
    pub(crate) fn new(c: Coefficients) -> Self {
        Lanes3 {
            c,
            buf: [Buf3::ZERO; 2],
            stages: [Buf3::ZERO; 3],
            cur: 0,
            h: [0.0; N],
            plane: [[0.0; N]; 6],
            max_length: [f64::INFINITY; N],
            near_d: [f64::INFINITY; N],
            near: [[0.0; N]; 7],
        }
    }
}

impl<const N: usize> Kernel<N> for Lanes3<N> {
    fn load(
        &mut self,
        lane: usize,
        job: &RayJob,
        start: &RayState,
        rate: &RayRate,
        step: f64,
        max_length: f64,
    ) {
        let b = &mut self.buf[self.cur];
        let vals = [
            start.x.x, start.x.y, start.x.z, start.v.x, start.v.y, start.v.z, start.s,
        ];
        for (k, (dst, v)) in [
            &mut b.x, &mut b.y, &mut b.z, &mut b.vx, &mut b.vy, &mut b.vz, &mut b.s,
        ]
        .into_iter()
        .zip(vals)
        .enumerate()
        {
            dst[lane] = v;
            self.near[k][lane] = v;
        }
        b.ax[lane] = rate.dv.x;
        b.ay[lane] = rate.dv.y;
        b.az[lane] = rate.dv.z;
        b.n[lane] = rate.ds;
        self.h[lane] = step;
        let t = &job.target;
        let plane = [
            t.point.x, t.point.y, t.point.z, t.normal.x, t.normal.y, t.normal.z,
        ];
        for (p, v) in self.plane.iter_mut().zip(plane) {
            p[lane] = v;
        }
        self.max_length[lane] = max_length;
        self.near_d[lane] = t.signed_distance(start.x).abs();
    }

    fn freeze(&mut self, lane: usize) {
        self.h[lane] = 0.0;
        self.max_length[lane] = f64::INFINITY;
    }

    #[inline(always)]
    fn step<const FMA: bool>(&mut self) {
        let (first, second) = self.buf.split_at_mut(1);
        let (y0, y1) = if self.cur == 0 {
            (&first[0], &mut second[0])
        } else {
            (&second[0], &mut first[0])
        };
        rk4_3d::<N, FMA>(&self.c, &self.h, y0, &mut self.stages, y1);
        self.cur ^= 1;
    }

    #[inline(always)]
    fn scan(&mut self) -> u64 {
        let y0 = &self.buf[self.cur ^ 1];
        let y1 = &self.buf[self.cur];
        scan_3d(
            y0,
            y1,
            &self.plane,
            &self.max_length,
            &mut self.near_d,
            &mut self.near,
        )
    }

    fn segment(&self, lane: usize) -> Segment<f64> {
        let (y0, f0) = self.buf[self.cur ^ 1].state(lane);
        let (y1, f1) = self.buf[self.cur].state(lane);
        Segment {
            y0,
            f0,
            y1,
            f1,
            h: self.h[lane],
        }
    }

    fn nearest(&self, lane: usize) -> RayState {
        let v = |k: usize| self.near[k][lane];
        RayState {
            x: V3::new(v(0), v(1), v(2)),
            v: V3::new(v(3), v(4), v(5)),
            s: v(6),
        }
    }
}

/// One RK4 step of every lane from `y0` into `y1`, the operations of the
/// scalar `rk4_step` in its order. A free function so that every array is a
/// distinct reference: the compiler then knows they do not overlap and
/// vectorizes each lane loop (through `self` it could not tell `y0` from `y1`,
/// two elements of one array, and kept the final sum scalar).
#[inline(always)]
fn rk4_3d<const N: usize, const FMA: bool>(
    c: &Coefficients,
    h: &[f64; N],
    y0: &Buf3<N>,
    [k2, k3, k4]: &mut [Buf3<N>; 3],
    y1: &mut Buf3<N>,
) {
    // Stage states of the scalar `rk4_step` (y + c·h·k), each with its rate.
    // k2 at y + h/2·k1.
    for i in 0..N {
        let f = 0.5 * h[i];
        k2.x[i] = fmadd::<FMA>(y0.vx[i], f, y0.x[i]);
        k2.y[i] = fmadd::<FMA>(y0.vy[i], f, y0.y[i]);
        k2.z[i] = fmadd::<FMA>(y0.vz[i], f, y0.z[i]);
        k2.vx[i] = fmadd::<FMA>(y0.ax[i], f, y0.vx[i]);
        k2.vy[i] = fmadd::<FMA>(y0.ay[i], f, y0.vy[i]);
        k2.vz[i] = fmadd::<FMA>(y0.az[i], f, y0.vz[i]);
    }
    k2.set_rate::<FMA>(c);
    // k3 at y + h/2·k2.
    for i in 0..N {
        let f = 0.5 * h[i];
        k3.x[i] = fmadd::<FMA>(k2.vx[i], f, y0.x[i]);
        k3.y[i] = fmadd::<FMA>(k2.vy[i], f, y0.y[i]);
        k3.z[i] = fmadd::<FMA>(k2.vz[i], f, y0.z[i]);
        k3.vx[i] = fmadd::<FMA>(k2.ax[i], f, y0.vx[i]);
        k3.vy[i] = fmadd::<FMA>(k2.ay[i], f, y0.vy[i]);
        k3.vz[i] = fmadd::<FMA>(k2.az[i], f, y0.vz[i]);
    }
    k3.set_rate::<FMA>(c);
    // k4 at y + h·k3.
    for i in 0..N {
        let f = h[i];
        k4.x[i] = fmadd::<FMA>(k3.vx[i], f, y0.x[i]);
        k4.y[i] = fmadd::<FMA>(k3.vy[i], f, y0.y[i]);
        k4.z[i] = fmadd::<FMA>(k3.vz[i], f, y0.z[i]);
        k4.vx[i] = fmadd::<FMA>(k3.ax[i], f, y0.vx[i]);
        k4.vy[i] = fmadd::<FMA>(k3.ay[i], f, y0.vy[i]);
        k4.vz[i] = fmadd::<FMA>(k3.az[i], f, y0.vz[i]);
    }
    k4.set_rate::<FMA>(c);
    for i in 0..N {
        let h6 = (1.0 / 6.0) * h[i];
        let h3 = (1.0 / 3.0) * h[i];
        let b = [h6, h3, h3, h6];
        y1.x[i] = combine::<FMA>(y0.x[i], [y0.vx[i], k2.vx[i], k3.vx[i], k4.vx[i]], b);
        y1.y[i] = combine::<FMA>(y0.y[i], [y0.vy[i], k2.vy[i], k3.vy[i], k4.vy[i]], b);
        y1.z[i] = combine::<FMA>(y0.z[i], [y0.vz[i], k2.vz[i], k3.vz[i], k4.vz[i]], b);
        y1.vx[i] = combine::<FMA>(y0.vx[i], [y0.ax[i], k2.ax[i], k3.ax[i], k4.ax[i]], b);
        y1.vy[i] = combine::<FMA>(y0.vy[i], [y0.ay[i], k2.ay[i], k3.ay[i], k4.ay[i]], b);
        y1.vz[i] = combine::<FMA>(y0.vz[i], [y0.az[i], k2.az[i], k3.az[i], k4.az[i]], b);
        y1.s[i] = combine::<FMA>(y0.s[i], [y0.n[i], k2.n[i], k3.n[i], k4.n[i]], b);
    }
    y1.set_rate::<FMA>(c);
}

/// The event screen of the 3-D kernel (see [`Kernel::scan`]), on distinct
/// references for the same reason as [`rk4_3d`].
#[inline(always)]
fn scan_3d<const N: usize>(
    y0: &Buf3<N>,
    y1: &Buf3<N>,
    plane: &[[f64; N]; 6],
    max_length: &[f64; N],
    near_d: &mut [f64; N],
    near: &mut [[f64; N]; 7],
) -> u64 {
    let [px, py, pz, nx, ny, nz] = plane;
    let mut mask = 0u64;
    for i in 0..N {
        // `TargetPlane::signed_distance`, operation for operation.
        let g = (y1.x[i] - px[i]) * nx[i] + (y1.y[i] - py[i]) * ny[i] + (y1.z[i] - pz[i]) * nz[i];
        let d = g.abs();
        let closer = d < near_d[i];
        near_d[i] = if closer { d } else { near_d[i] };
        let now = [
            y1.x[i], y1.y[i], y1.z[i], y1.vx[i], y1.vy[i], y1.vz[i], y1.s[i],
        ];
        for (k, v) in now.into_iter().enumerate() {
            near[k][i] = if closer { v } else { near[k][i] };
        }
        let crossed = g >= -CROSSING_MARGIN;
        let ground = (y0.y[i] >= 0.0) & ((y1.y[i] < 0.0) | ((y0.vy[i] < 0.0) & (y1.vy[i] > 0.0)));
        let long = y1.s[i] >= max_length[i];
        mask |= u64::from(crossed | ground | long) << i;
    }
    mask
}
