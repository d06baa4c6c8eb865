//! What the 3-D and 2-D lane kernels share: the lane count, the double buffer
//! of lane states with the stages of a step, each lane's step control
//! ([`Control`]: RK4's fixed step, or Dormand–Prince's adaptive one), target
//! plane and limits, the nearest-point tracking and the vector event screen.
//! A kernel supplies its state buffer ([`LaneBuf`]) and its steps;
//! everything else is here.

// Lane loops index several arrays in lockstep; `for i in 0..N` over fixed-size
// arrays is the form the compiler vectorizes.
#![allow(clippy::needless_range_loop)]

use super::job::RayJob;
use crate::trace::fastexp::fmadd;
use crate::trace::{Earth, Method, RayRate, RayState, Segment};

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

/// One buffer of `N` lane states, as a kernel lays it out; `M` is the number
/// of components kept for the nearest point.
pub(crate) trait LaneBuf<const N: usize, const M: usize>: Copy {
    /// Writes a ray's start state and rate into `lane`.
    fn put(&mut self, lane: usize, start: &RayState, rate: &RayRate);
    /// The components the nearest point keeps, enough to rebuild its state.
    fn tracked(&self) -> [&[f64; N]; M];
    /// The components the event screen reads: x, y, z, v_y, s.
    fn screened(&self) -> [&[f64; N]; 5];
    /// v_x and v_z, where the buffer holds them (the 3-D kernel's); the
    /// screen over the round earth needs the whole velocity.
    fn horizontal_velocity(&self) -> Option<[&[f64; N]; 2]> {
        None
    }
}

/// Each lane's step control. RK4: `h` is the fixed step. Dormand–Prince: the
/// state of the scalar `Stepper::Dopri5`, lane by lane: the next step `h`,
/// the longest `h_max` and the growth limit `grow`; `used` is the step the
/// last attempt took (the accepted step's length, for its segment).
#[derive(Clone, Copy)]
pub(crate) struct Control<const N: usize> {
    pub h: [f64; N],
    pub used: [f64; N],
    pub h_max: [f64; N],
    pub grow: [f64; N],
    /// Dormand–Prince's local error bound (0 for RK4).
    pub tolerance: f64,
}

/// What one step of every lane did, as lane masks.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Attempts {
    /// The lanes whose step was taken (RK4: every lane).
    pub accepted: u64,
    /// The lanes whose adaptive step had shrunk below what f64 resolves
    /// (nothing moved; the scalar tracer gives up there).
    pub underflow: u64,
}

impl Attempts {
    /// Every one of `N` lanes accepted (a fixed step).
    pub(crate) fn all<const N: usize>() -> Self {
        Attempts {
            accepted: if N == 64 { u64::MAX } else { (1u64 << N) - 1 },
            underflow: 0,
        }
    }
}

/// The lane state of a kernel over buffers `B`: the current and previous
/// states, the stages of a step, and each lane's step control, plane, limit
/// and nearest point so far.
pub(crate) struct LaneSet<B, const N: usize, const M: usize> {
    buf: [B; 2],
    /// The stages of a step: k2, k3, k4 for RK4, k2 … k6 for Dormand–Prince
    /// (kept here, not re-initialised on the stack every step).
    stages: [B; 5],
    /// Index of the buffer with the current state; the other holds the
    /// previous one (the start of the last step).
    cur: usize,
    control: Control<N>,
    method: Method,
    /// Target plane: point and normal.
    plane: [[f64; N]; 6],
    max_length: [f64; N],
    /// The medium's ceiling (`IndexField::ceiling`): a ray that rises past it
    /// has left the air.
    ceiling: f64,
    /// The ground: heights for the ground and the ceiling are taken above it.
    earth: Earth,
    /// Distance to the plane of the nearest point so far, and that point's
    /// tracked components.
    near_d: [f64; N],
    near: [[f64; N]; M],
}

impl<B: LaneBuf<N, M>, const N: usize, const M: usize> LaneSet<B, N, M> {
    /// Every lane idle, its buffers `zero` (a state harmless to step).
    ///
    /// # Panics
    /// Over the round earth, if the buffers do not hold the horizontal
    /// velocity the screen needs (the 2-D kernel's do not).
    pub(crate) fn new(zero: B, method: Method, ceiling: f64, earth: Earth) -> Self {
        assert!(
            earth.is_flat() || zero.horizontal_velocity().is_some(),
            "this kernel traces over the flat ground only"
        );
        LaneSet {
            buf: [zero; 2],
            stages: [zero; 5],
            cur: 0,
            control: Control {
                h: [0.0; N],
                used: [0.0; N],
                h_max: [0.0; N],
                grow: [5.0; N],
                tolerance: match method {
                    Method::Rk4 { .. } => 0.0,
                    Method::Dopri5 { tolerance } => tolerance,
                },
            },
            method,
            plane: [[0.0; N]; 6],
            max_length: [f64::INFINITY; N],
            ceiling,
            earth,
            near_d: [f64::INFINITY; N],
            near: [[0.0; N]; M],
        }
    }

    /// Puts a ray into `lane` (see `Kernel::load`), its step control set as
    /// `Stepper::new` sets it.
    pub(crate) fn load(
        &mut self,
        lane: usize,
        job: &RayJob,
        start: &RayState,
        rate: &RayRate,
        max_length: f64,
    ) {
        let b = &mut self.buf[self.cur];
        b.put(lane, start, rate);
        for (near, v) in self.near.iter_mut().zip(b.tracked()) {
            near[lane] = v[lane];
        }
        let c = &mut self.control;
        match self.method {
            Method::Rk4 { step } => {
                c.h[lane] = step;
                c.used[lane] = step;
            }
            Method::Dopri5 { .. } => {
                // No step longer than a quarter of the path (`Stepper::new`).
                let h_max = if max_length.is_finite() {
                    0.25 * max_length
                } else {
                    1e3
                };
                c.h[lane] = h_max.min(0.2 * h_max.max(1.0));
                c.used[lane] = 0.0;
                c.h_max[lane] = h_max;
                c.grow[lane] = 5.0;
            }
        }
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

    /// Stops `lane` from moving (its step becomes 0, and it never reaches
    /// its maximum length).
    pub(crate) fn freeze(&mut self, lane: usize) {
        let c = &mut self.control;
        c.h[lane] = 0.0;
        c.used[lane] = 0.0;
        c.h_max[lane] = 0.0;
        self.max_length[lane] = f64::INFINITY;
    }

    /// How rays are stepped.
    pub(crate) fn method(&self) -> Method {
        self.method
    }

    /// The parts of a step of every lane: the step control, the current
    /// state `y0`, the stages and the buffer `y1` for the new state;
    /// [`Self::flip`] then makes `y1` current and `y0` the previous state.
    /// They are distinct references, so that the compiler knows they do not
    /// overlap and vectorizes each lane loop (through `self` it could not tell
    /// `y0` from `y1`, two elements of one array). Not a closure: a closure is
    /// compiled without the caller's target features, and its fused
    /// multiply–adds would become calls to the software `fma`.
    #[inline(always)]
    pub(crate) fn step_parts(&mut self) -> (&mut Control<N>, &B, &mut [B; 5], &mut B) {
        let (first, second) = self.buf.split_at_mut(1);
        let (y0, y1) = if self.cur == 0 {
            (&first[0], &mut second[0])
        } else {
            (&second[0], &mut first[0])
        };
        (&mut self.control, y0, &mut self.stages, y1)
    }

    /// The current state's buffer (a kernel writes what `LaneBuf::put`
    /// leaves out, such as the tangent kernel's derivative parts).
    pub(crate) fn current_mut(&mut self) -> &mut B {
        &mut self.buf[self.cur]
    }

    /// The previous and the current state's buffers: the start and end of
    /// the last step.
    pub(crate) fn buffers(&self) -> (&B, &B) {
        (&self.buf[self.cur ^ 1], &self.buf[self.cur])
    }

    /// After a step written by [`Self::step_parts`]: the new state becomes
    /// the current one.
    #[inline(always)]
    pub(crate) fn flip(&mut self) {
        self.cur ^= 1;
    }

    /// The event screen after a step (see `Kernel::scan`).
    #[inline(always)]
    pub(crate) fn scan(&mut self) -> u64 {
        let y0 = &self.buf[self.cur ^ 1];
        let y1 = &self.buf[self.cur];
        let round = match self.earth {
            Earth::Flat => None,
            Earth::Round { radius } => Some(Round {
                radius,
                before: y0.horizontal_velocity().expect("checked in `new`"),
                after: y1.horizontal_velocity().expect("checked in `new`"),
            }),
        };
        scan(
            y0.screened(),
            y1.screened(),
            y1.tracked(),
            &self.plane,
            &self.max_length,
            self.ceiling,
            round,
            &mut self.near_d,
            &mut self.near,
        )
    }

    /// The last step of `lane`, with `state` reading a lane's 3-D state and
    /// rate from a buffer.
    pub(crate) fn segment(
        &self,
        lane: usize,
        state: impl Fn(&B, usize) -> (RayState, RayRate),
    ) -> Segment<f64> {
        let (y0, f0) = state(&self.buf[self.cur ^ 1], lane);
        let (y1, f1) = state(&self.buf[self.cur], lane);
        Segment {
            y0,
            f0,
            y1,
            f1,
            h: self.control.used[lane],
        }
    }

    /// The tracked components of the point of `lane` nearest its plane so far.
    pub(crate) fn nearest(&self, lane: usize) -> [f64; M] {
        std::array::from_fn(|k| self.near[k][lane])
    }
}

/// What the screen needs over the round earth: the radius and v_x, v_z
/// before and after the step.
struct Round<'a, const N: usize> {
    radius: f64,
    before: [&'a [f64; N]; 2],
    after: [&'a [f64; N]; 2],
}

/// A height above the sphere of radius `r` (as `Earth::height`) and the sign
/// carrier of the vertical speed, v·(p − c).
#[inline(always)]
fn above(r: f64, p: [f64; 3], v: [f64; 3]) -> (f64, f64) {
    let [x, y, z] = p;
    let qy = y + r;
    let q = (x * x + qy * qy + z * z).sqrt();
    let h = (x * x + z * z + y * (y + 2.0 * r)) / (q + r);
    (h, v[0] * x + v[1] * qy + v[2] * z)
}

/// The event screen on distinct references (see [`LaneSet::step_parts`] for
/// why):
/// updates the nearest points from `now` and returns the lanes whose step
/// from `y0` to `y1` (each x, y, z, v_y, s) may cross the plane, go below
/// the ground, reach the maximum length or rise past the ceiling.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn scan<const N: usize, const M: usize>(
    y0: [&[f64; N]; 5],
    y1: [&[f64; N]; 5],
    now: [&[f64; N]; M],
    plane: &[[f64; N]; 6],
    max_length: &[f64; N],
    ceiling: f64,
    round: Option<Round<'_, N>>,
    near_d: &mut [f64; N],
    near: &mut [[f64; N]; M],
) -> u64 {
    let [px, py, pz, nx, ny, nz] = plane;
    let [y0x, y0y, y0z, y0vy, _] = y0;
    let [x, y, z, vy, s] = y1;
    // Heights and vertical speeds (their signs): y and v_y over the flat
    // ground, computed apart over the sphere.
    let mut heights = [[0.0; N]; 4];
    let [h0, vh0, h1, vh1]: [&[f64; N]; 4] = match &round {
        None => [y0y, y0vy, y, vy],
        Some(Round {
            radius,
            before: [vx0, vz0],
            after: [vx1, vz1],
        }) => {
            let [a, b, c, d] = &mut heights;
            for i in 0..N {
                (a[i], b[i]) = above(*radius, [y0x[i], y0y[i], y0z[i]], [vx0[i], y0vy[i], vz0[i]]);
                (c[i], d[i]) = above(*radius, [x[i], y[i], z[i]], [vx1[i], vy[i], vz1[i]]);
            }
            let [a, b, c, d] = &heights;
            [a, b, c, d]
        }
    };
    let mut mask = 0u64;
    for i in 0..N {
        // `TargetPlane::signed_distance`, operation for operation.
        let g = (x[i] - px[i]) * nx[i] + (y[i] - py[i]) * ny[i] + (z[i] - pz[i]) * nz[i];
        let d = g.abs();
        let closer = d < near_d[i];
        near_d[i] = if closer { d } else { near_d[i] };
        for k in 0..M {
            near[k][i] = if closer { now[k][i] } else { near[k][i] };
        }
        let crossed = g >= -CROSSING_MARGIN;
        let ground = (h0[i] >= 0.0) & ((h1[i] < 0.0) | ((vh0[i] < 0.0) & (vh1[i] > 0.0)));
        let long = s[i] >= max_length[i];
        let high = h1[i] > ceiling;
        mask |= u64::from(crossed | ground | long | high) << i;
    }
    mask
}
