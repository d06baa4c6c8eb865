//! RK4 steps of a caller's pack of rays in lanes: the 3-D kernel's step
//! ([`rk4_3d`], the scalar [`rk4_step`](crate::trace::rk4_step)'s operations
//! in its order) for up to [`PACK`] rays at once, each with its own step
//! length, without the batch driver's events.
//!
//! For a caller that decides per ray what to do between steps, as the
//! renderer's sphere tracer does: it integrates a pack of neighbouring camera
//! rays ahead through a hot spot's air here (the exponentials vectorized),
//! then walks each ray along its stored steps. The numbers are those of the
//! batch kernel: the polynomial exponential (within 1 ulp of libm's) and
//! fused multiply–adds where the CPU has them, so a step agrees with the
//! scalar one to rounding (`tests/fast_paths.rs` checks 10⁻⁹ m).
//!
//! A lane whose step length is 0 stays where it is (a step of 0 changes no
//! state; its rate is evaluated again there, by the lanes), which is how a
//! caller leaves a lane idle.

// Lane loops index several arrays in lockstep; `for i in 0..N` over fixed-size
// arrays is the form the compiler vectorizes.
#![allow(clippy::needless_range_loop)]

use super::air::AirLanes;
use super::field::{EarthLanes, LaneField, LogisticLanes};
use super::isa::Isa;
use super::kernel::{Buf3, rk4_3d};
use super::lanes::LaneBuf;
use super::terms::HotCache;
use crate::medium::Field;
use crate::trace::{Earth, RayRate, RayState};

/// Rays in one pack: two AVX-512 vectors of `f64`, four AVX2 ones (with 8
/// the compiler unrolled the lane loops completely and left much of them
/// scalar: a step took 3.7 times as long).
pub const PACK: usize = 16;

/// The medium kinds a pack can be stepped through.
enum PackField<'a> {
    Logistic(LogisticLanes<'a>),
    Air(AirLanes<'a>),
}

/// Steps packs of rays through a field over the flat ground or the sphere,
/// with the widest instruction set this CPU has. Shared by all threads; each
/// keeps its own [`PackCache`].
pub struct PackStepper<'a> {
    field: PackField<'a>,
    earth: Earth,
    isa: Isa,
}

/// What a pack's field evaluations keep from one step to the next (each
/// lane's culled hot spots), and the step's lane buffers; one per thread.
pub struct PackCache {
    hot: HotCache<PACK>,
    /// The start state and the three stage states, then the result: kept
    /// from step to step, since every field a step reads it has written in
    /// that step first (building them afresh copied 7 kB of zeros a step).
    work: Box<[Buf3<PACK>; 5]>,
}

impl<'a> PackStepper<'a> {
    /// A stepper for `field` over `earth`; `None` for a medium kind the lanes
    /// do not evaluate (the analytic test medium).
    pub fn new(field: &'a Field, earth: Earth) -> Option<Self> {
        let field = match field {
            Field::Logistic(f) => PackField::Logistic(LogisticLanes::new(f)),
            Field::Air(f) => PackField::Air(AirLanes::new(f)),
            Field::LinearSquare(_) => return None,
        };
        Some(PackStepper {
            field,
            earth,
            isa: Isa::detect(),
        })
    }

    /// The instruction set the steps run with.
    pub fn isa(&self) -> Isa {
        self.isa
    }

    /// A fresh cache for one thread's packs.
    pub fn cache(&self) -> PackCache {
        PackCache {
            hot: match &self.field {
                PackField::Logistic(f) => f.cache::<PACK>(),
                PackField::Air(_) => HotCache::new(None),
            },
            work: Box::new([Buf3::<PACK>::ZERO; 5]),
        }
    }

    /// One RK4 step of τ-length `h[i]` from `(y[i], f[i])` for every lane,
    /// the result written in place; a lane with `h[i] == 0` keeps its state
    /// (and gets the lanes' rate there).
    pub fn rk4(
        &self,
        cache: &mut PackCache,
        h: &[f64; PACK],
        y: &mut [RayState; PACK],
        f: &mut [RayRate; PACK],
    ) {
        match self.isa {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `Isa::detect` found AVX-512F, AVX2 and FMA on this CPU.
            Isa::Avx512 => unsafe { self.rk4_avx512(cache, h, y, f) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `Isa::detect` found AVX2 and FMA on this CPU.
            Isa::Avx2 => unsafe { self.rk4_avx2(cache, h, y, f) },
            _ => self.rk4_isa::<false>(cache, h, y, f),
        }
    }

    /// [`PackStepper::rk4`] built for AVX-512.
    ///
    /// # Safety
    /// The CPU must have AVX-512F, AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx2,fma")]
    unsafe fn rk4_avx512(
        &self,
        cache: &mut PackCache,
        h: &[f64; PACK],
        y: &mut [RayState; PACK],
        f: &mut [RayRate; PACK],
    ) {
        self.rk4_isa::<true>(cache, h, y, f)
    }

    /// [`PackStepper::rk4`] built for AVX2 with FMA.
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn rk4_avx2(
        &self,
        cache: &mut PackCache,
        h: &[f64; PACK],
        y: &mut [RayState; PACK],
        f: &mut [RayRate; PACK],
    ) {
        self.rk4_isa::<true>(cache, h, y, f)
    }

    #[inline(always)]
    fn rk4_isa<const FMA: bool>(
        &self,
        cache: &mut PackCache,
        h: &[f64; PACK],
        y: &mut [RayState; PACK],
        f: &mut [RayRate; PACK],
    ) {
        let work = &mut cache.work;
        match (&self.field, self.earth) {
            (PackField::Logistic(l), Earth::Flat) => {
                step::<_, FMA>(l, &mut cache.hot, work, h, y, f)
            }
            (PackField::Logistic(l), Earth::Round { radius }) => {
                step::<_, FMA>(&EarthLanes::new(l, radius), &mut cache.hot, work, h, y, f)
            }
            (PackField::Air(a), Earth::Flat) => step::<_, FMA>(a, &mut (), work, h, y, f),
            (PackField::Air(a), Earth::Round { radius }) => {
                step::<_, FMA>(&EarthLanes::new(a, radius), &mut (), work, h, y, f)
            }
        }
    }
}

/// Loads the lanes, takes the step, stores them back.
#[inline(always)]
fn step<F: LaneField, const FMA: bool>(
    field: &F,
    cache: &mut F::Cache<PACK>,
    work: &mut [Buf3<PACK>; 5],
    h: &[f64; PACK],
    y: &mut [RayState; PACK],
    f: &mut [RayRate; PACK],
) {
    let [y0, k2, k3, k4, y1] = work;
    for i in 0..PACK {
        y0.put(i, &y[i], &f[i]);
    }
    rk4_3d::<F, PACK, FMA>((field, cache), h, y0, [k2, k3, k4], y1);
    for i in 0..PACK {
        (y[i], f[i]) = y1.state(i);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::V3;
    use crate::medium::{Background, HotSpot, Inversion, LogisticMedium, Medium};
    use crate::trace::rk4_step;
    use crate::trace::state::rate;

    /// A full medium: background, inversion and a hot spot the rays cross.
    fn medium() -> Medium {
        Medium::Logistic(LogisticMedium {
            scale: 0.02,
            background: Some(Background { n: 1.0, a: 150.0 }),
            inversion: Some(Inversion {
                n: 0.4,
                a: 2.0,
                height: 8.0,
            }),
            hotspots: vec![HotSpot {
                x: 0.0,
                z: 60.0,
                radius: 40.0,
                n: -3.0,
                a: -0.35,
                edge: 0.5,
            }],
        })
    }

    /// Each lane's step equals the scalar RK4 step to rounding, over both
    /// grounds; a lane with h = 0 does not move.
    #[test]
    fn steps_agree_with_the_scalar_rk4() {
        let medium = medium();
        let field = medium.field();
        for earth in [Earth::Flat, Earth::Round { radius: 6.371e6 }] {
            let stepper = PackStepper::new(&field, earth).expect("logistic lanes");
            let mut cache = stepper.cache();
            let round = crate::trace::OnEarth {
                field: &field,
                radius: 6.371e6,
            };
            let optics: &dyn crate::medium::IndexField<f64> = match earth {
                Earth::Flat => &field,
                Earth::Round { .. } => &round,
            };
            let mut y = [RayState {
                x: V3::new(0.0, 0.0, 0.0),
                v: V3::new(0.0, 0.0, 1.0),
                s: 0.0,
            }; PACK];
            let mut f = [rate(optics, &y[0], &mut 0); PACK];
            let mut h = [0.0; PACK];
            for i in 0..PACK {
                let x = V3::new(-2.0 + 0.5 * i as f64, 0.2 + 0.3 * i as f64, 30.0);
                let n = 1.0 + crate::medium::IndexField::delta(optics, x);
                let dir = V3::new(0.001 * i as f64, -0.002, 1.0);
                y[i] = RayState {
                    x,
                    v: dir * (n / dir.norm()),
                    s: 1.0,
                };
                f[i] = rate(optics, &y[i], &mut 0);
                h[i] = if i == 3 { 0.0 } else { 2.0 + i as f64 };
            }
            let (y0, f0) = (y, f);
            for _ in 0..20 {
                let expected: Vec<_> = (0..PACK)
                    .map(|i| rk4_step(optics, &y[i], &f[i], h[i], &mut 0))
                    .collect();
                stepper.rk4(&mut cache, &h, &mut y, &mut f);
                for i in 0..PACK {
                    let (ye, fe) = expected[i];
                    let dx = (y[i].x - ye.x).norm();
                    let dv = (y[i].v - ye.v).norm();
                    assert!(
                        dx < 1e-10 && dv < 1e-13,
                        "{earth:?} lane {i}: {dx:e} m, {dv:e}"
                    );
                    assert!((y[i].s - ye.s).abs() < 1e-10);
                    assert!((f[i].dv - fe.dv).norm() < 1e-12 * (1.0 + fe.dv.norm()));
                }
            }
            assert_eq!(y[3], y0[3], "a lane with h = 0 stays put");
            assert!((f[3].dv - f0[3].dv).norm() < 1e-12 * f0[3].dv.norm());
            assert_eq!((f[3].dx, f[3].ds), (f0[3].dx, f0[3].ds));
            assert!(y[5].x.z > 100.0, "the other lanes moved");
        }
    }

    /// The analytic test medium has no lane form.
    #[test]
    fn declines_the_analytic_medium() {
        let field = Field::LinearSquare(crate::medium::analytic::LinearSquare { n0: 1.0, g: 1e-4 });
        assert!(PackStepper::new(&field, Earth::Flat).is_none());
    }
}
