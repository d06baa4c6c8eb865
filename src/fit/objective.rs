//! The fitting problem as a residual map: free parameters → stacked pair
//! residuals r = (r_0, r_1, …) ∈ ℝ^{3m}, with F = ½|r|².
//!
//! The Jacobian is exact for the *discrete* map: the same generic tracer runs
//! with forward-mode dual numbers (`num_dual::DualSVec64<N>`) seeded on up to
//! eight free parameters at a time, so the derivative includes the integrator's
//! stages and the plane-crossing interpolation. With the adaptive method the
//! step sizes come from the real parts only, which freezes the step sequence for
//! the derivative: no step-control noise, unlike finite differences.

use crate::math::Real;
use crate::medium::{Medium, PairFields, Param};
use crate::pair::PointPair;
use crate::problem::Problem;
use crate::trace::batch::{BatchOptions, RayJob, trace_batch_into};
use crate::trace::{Trace, TraceOptions};
use nalgebra::{DMatrix, DVector};
use num_dual::{DualSVec64, DualStruct};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Parameters per dual pass: 8 partials cost about 4 plain traces.
const CHUNK: usize = 8;

/// Rays per task of the lanes kernel (its widest lane count).
const LANE_CHUNK: usize = 16;

/// Flags of one pair at a parameter point.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PairFlags {
    /// Dipped below the ground before its target plane.
    pub occluded: bool,
    /// Never reached its target plane.
    pub unreachable: bool,
}

/// The residual map of a problem.
#[derive(Debug)]
pub struct Objective {
    template: Medium,
    free: Vec<Param>,
    pairs: Vec<PointPair>,
    jobs: Vec<RayJob>,
    options: TraceOptions,
    residual_evaluations: AtomicU64,
    jacobian_evaluations: AtomicU64,
    rhs_evaluations: AtomicU64,
}

impl Clone for Objective {
    fn clone(&self) -> Self {
        Objective::new(
            self.template.clone(),
            self.free.clone(),
            self.pairs.clone(),
            self.options,
        )
    }
}

impl Objective {
    /// The residual map of `pairs` with the `free` parameters of `template`.
    pub fn new(
        template: impl Into<Medium>,
        free: Vec<Param>,
        pairs: Vec<PointPair>,
        options: TraceOptions,
    ) -> Self {
        Objective {
            template: template.into(),
            free,
            jobs: pairs.iter().map(|p| p.ray_job_on(options.earth)).collect(),
            pairs,
            options,
            residual_evaluations: AtomicU64::new(0),
            jacobian_evaluations: AtomicU64::new(0),
            rhs_evaluations: AtomicU64::new(0),
        }
    }

    /// The residual map of a problem file.
    pub fn from_problem(p: &Problem) -> Self {
        Objective::new(p.medium.clone(), p.free.clone(), p.pairs.clone(), p.trace)
    }

    /// The free parameters, in order.
    pub fn free(&self) -> &[Param] {
        &self.free
    }

    /// The point pairs.
    pub fn pairs(&self) -> &[PointPair] {
        &self.pairs
    }

    /// The trace settings.
    pub fn options(&self) -> &TraceOptions {
        &self.options
    }

    /// Number of residuals (3 per pair).
    pub fn len(&self) -> usize {
        3 * self.pairs.len()
    }

    /// Whether there are no residuals.
    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// The starting values of the free parameters.
    pub fn start(&self) -> DVector<f64> {
        DVector::from_iterator(
            self.free.len(),
            self.free
                .iter()
                .map(|p| self.template.get(*p).unwrap_or(f64::NAN)),
        )
    }

    /// The medium with the free parameters set to `x`.
    pub fn medium(&self, x: &[f64]) -> Medium {
        let mut m = self.template.clone();
        for (p, v) in self.free.iter().zip(x) {
            // Free parameters were checked to exist when the problem was loaded.
            let _ = m.set(*p, *v);
        }
        m
    }

    /// The fields the pairs are traced through at `medium`: one per distinct
    /// pair wavelength ([`PairFields`]).
    fn fields<T: Real>(&self, medium: &Medium<T>) -> PairFields<T> {
        PairFields::new(medium, self.pairs.iter().map(|p| p.wavelength))
    }

    /// Residuals and flags at `x`. Pairs are traced in parallel through the
    /// batch entry (for the logistic kind and real air the SIMD lanes
    /// kernels: the scalar tracer's steps and endpoints to ~1e-12 m). The
    /// result is identical for any number of threads.
    pub fn residuals(&self, x: &[f64]) -> (DVector<f64>, Vec<PairFlags>) {
        self.residual_evaluations.fetch_add(1, Ordering::Relaxed);
        let fields = self.fields(&self.medium(x));
        let batch = BatchOptions::from_trace_options(&self.options);
        let mut traces = vec![Trace::default(); self.pairs.len()];
        // One batch per wavelength (a single one, of every pair in order,
        // without per-pair wavelengths).
        for (g, field) in fields.fields().iter().enumerate() {
            let members: Vec<usize> = (0..self.pairs.len())
                .filter(|&i| fields.groups()[i] == g)
                .collect();
            let jobs: Vec<RayJob> = members.iter().map(|&i| self.jobs[i]).collect();
            let mut part = vec![Trace::default(); members.len()];
            // Chunks of one lane width; the split is fixed, so threads only
            // change who computes a chunk, not what it computes.
            jobs.par_chunks(LANE_CHUNK)
                .zip(part.par_chunks_mut(LANE_CHUNK))
                .for_each(|(jobs, part)| {
                    // Ctrl-C: the chunks left are skipped, and the solver's
                    // next cancellation point discards these residuals.
                    if !crate::interrupt::requested() {
                        trace_batch_into(field, jobs, &batch, part)
                    }
                });
            for (i, t) in members.into_iter().zip(part) {
                traces[i] = t;
            }
        }
        let mut r = DVector::zeros(self.len());
        let mut flags = Vec::with_capacity(self.pairs.len());
        for (i, (t, pair)) in traces.iter().zip(&self.pairs).enumerate() {
            let ri = (t.endpoint - pair.target()) * pair.weight;
            r.fixed_rows_mut::<3>(3 * i).copy_from_slice(&ri.to_array());
            flags.push(PairFlags {
                occluded: t.occluded,
                unreachable: t.unreachable,
            });
            self.rhs_evaluations
                .fetch_add(t.stats.rhs_evaluations, Ordering::Relaxed);
        }
        (r, flags)
    }

    /// F = ½|r|² at `x` (∞ where the residuals are not finite).
    pub fn cost(&self, x: &[f64]) -> f64 {
        let (r, _) = self.residuals(x);
        let f = 0.5 * r.norm_squared();
        if f.is_finite() { f } else { f64::INFINITY }
    }

    /// Residuals and the exact 3m × n Jacobian at `x`.
    pub fn jacobian(&self, x: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
        self.jacobian_evaluations.fetch_add(1, Ordering::Relaxed);
        let n = self.free.len();
        let mut r = DVector::zeros(self.len());
        let mut jac = DMatrix::zeros(self.len(), n);
        let base = self.medium(x);
        let mut first = 0;
        while first < n || (n == 0 && first == 0) {
            let width = (n - first).min(CHUNK);
            let cols = first..first + width;
            match width {
                0..=2 => self.jacobian_chunk::<2>(&base, cols, &mut r, &mut jac),
                3..=4 => self.jacobian_chunk::<4>(&base, cols, &mut r, &mut jac),
                _ => self.jacobian_chunk::<8>(&base, cols, &mut r, &mut jac),
            }
            first += width.max(1);
        }
        (r, jac)
    }

    fn jacobian_chunk<const N: usize>(
        &self,
        base: &Medium,
        cols: std::ops::Range<usize>,
        r: &mut DVector<f64>,
        jac: &mut DMatrix<f64>,
    ) {
        type D<const N: usize> = DualSVec64<N>;
        let seeded = base.map(|p, v| {
            let lane = self.free[cols.clone()].iter().position(|q| *q == p);
            match lane {
                Some(k) => D::<N>::from_re(v).derivative(k),
                None => D::<N>::from_re(v),
            }
        });
        // The per-wavelength media come from the seeded one, so they carry
        // the same derivative parts: the Jacobian stays exact.
        let fields = self.fields(&seeded);
        let rows: Vec<([f64; 3], [[f64; N]; 3], u64)> = self
            .pairs
            .par_iter()
            .enumerate()
            .map(|(i, pair)| {
                if crate::interrupt::requested() {
                    // Ctrl-C: as in `residuals`, a row to be discarded.
                    return ([0.0; 3], [[0.0; N]; 3], 0);
                }
                let (t, res) = pair.evaluate::<D<N>, _>(fields.of(i), &self.options, None);
                let comps = [res.x, res.y, res.z];
                let mut d = [[0.0; N]; 3];
                for (row, c) in d.iter_mut().zip(&comps) {
                    // A residual that does not depend on the chunk's parameters
                    // carries no derivative part: unwrap_generic gives zeros then.
                    let eps = c.eps.unwrap_generic(nalgebra::Const::<N>, nalgebra::U1);
                    row.copy_from_slice(eps.as_slice());
                }
                (comps.map(|c| c.re()), d, t.stats.rhs_evaluations)
            })
            .collect();
        for (i, (ri, di, evals)) in rows.into_iter().enumerate() {
            for c in 0..3 {
                r[3 * i + c] = ri[c];
                for (k, col) in cols.clone().enumerate() {
                    jac[(3 * i + c, col)] = di[c][k];
                }
            }
            self.rhs_evaluations.fetch_add(evals, Ordering::Relaxed);
        }
    }

    /// Counts so far: (residual evaluations, Jacobian evaluations, right-hand-side
    /// evaluations of the ray equation).
    pub fn counts(&self) -> (u64, u64, u64) {
        (
            self.residual_evaluations.load(Ordering::Relaxed),
            self.jacobian_evaluations.load(Ordering::Relaxed),
            self.rhs_evaluations.load(Ordering::Relaxed),
        )
    }
}

/// `T`'s real part, for code generic over [`Real`].
pub fn re<T: Real>(t: T) -> f64 {
    t.val()
}
