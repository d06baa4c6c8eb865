//! The instruction sets the kernels are built for, and the run-time dispatch
//! to the widest one this CPU has: each entry point is compiled once per
//! [`Isa`] with `#[target_feature]`, and the inlined lane loops under it
//! become code for that set.

use super::driver::{Kernel, drive};
use super::job::{BatchOptions, RayJob};
use crate::trace::Trace;
use crate::trace::fastexp::exp_core;

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

/// Replaces each element of `xs` by its exponential as the kernels built for
/// `isa` compute it (the polynomial of [`fastexp`](crate::trace::fastexp), fused
/// multiply–adds on AVX2 and AVX-512), so that tests can check every build.
/// Below −708 this gives 0, like [`fastexp::exp`](crate::trace::fastexp::exp); the
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
    /// # Safety
    /// The CPU must have AVX-512F, AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx2,fma")]
    unsafe fn avx512(xs: &mut [f64]) {
        each::<true>(xs)
    }
    /// # Safety
    /// The CPU must have AVX2 and FMA.
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

/// Runs `kernel` over `jobs` with the build for `isa`.
pub(crate) fn run<K: Kernel<N>, const N: usize>(
    isa: Isa,
    kernel: &mut K,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) {
    assert_eq!(out.len(), jobs.len(), "one output slot per job");
    assert!(isa.is_available(), "this CPU cannot run {isa:?} code");
    match isa {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the CPU has AVX-512F, AVX2 and FMA (checked above).
        Isa::Avx512 => unsafe { drive_avx512(kernel, jobs, options, out) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the CPU has AVX2 and FMA (checked above).
        Isa::Avx2 => unsafe { drive_avx2(kernel, jobs, options, out) },
        _ => drive::<K, N, false>(kernel, jobs, options, out),
    }
}

/// [`drive`] compiled for AVX-512: its inlined lane loops become 512-bit code.
///
/// # Safety
/// The CPU must have AVX-512F, AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx2,fma")]
unsafe fn drive_avx512<K: Kernel<N>, const N: usize>(
    kernel: &mut K,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) {
    drive::<K, N, true>(kernel, jobs, options, out)
}

/// [`drive`] compiled for AVX2 with FMA.
///
/// # Safety
/// The CPU must have AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn drive_avx2<K: Kernel<N>, const N: usize>(
    kernel: &mut K,
    jobs: &[RayJob],
    options: &BatchOptions,
    out: &mut [Trace],
) {
    drive::<K, N, true>(kernel, jobs, options, out)
}
