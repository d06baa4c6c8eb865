//! The fitting problem as a residual map: free parameters → stacked pair
//! residuals r = (r_0, r_1, …) ∈ ℝ^{3m}, with F = ½|r|².
//!
//! The Jacobian is exact for the *discrete* map: the same generic tracer runs
//! with forward-mode dual numbers (`num_dual::DualSVec64<N>`) seeded on up to
//! eight free parameters at a time, so the derivative includes the integrator's
//! stages and the plane-crossing interpolation. With the adaptive method the
//! step sizes come from the real parts only, which freezes the step sequence for
//! the derivative: no step-control noise, unlike finite differences.

mod photo;

pub use photo::{PhotoPart, eps1, eps2, square_to, with_eps};

use crate::math::Real;
use crate::medium::{Field, Medium, PairFields, Param};
use crate::pair::PointPair;
use crate::problem::Problem;
use crate::trace::batch::tangent::trace_tangent;
use crate::trace::batch::{BatchOptions, RayJob};
use crate::trace::{Trace, TraceOptions};
use nalgebra::{DMatrix, DVector};
use num_dual::{DualSVec64, DualStruct};
use rayon::prelude::*;
use std::borrow::Cow;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

/// Parameters per dual pass: 8 partials cost about 4 plain traces.
const CHUNK: usize = 8;

/// Rays per task of the lanes kernel (its widest lane count).
const LANE_CHUNK: usize = 16;

/// Rays per task of the tangent lanes (their lane count).
const TANGENT_CHUNK: usize = 8;

/// The dual numbers of a pass over `N` parameters.
type D<const N: usize> = DualSVec64<N>;

/// One pair's rows: its residual, the residual's derivatives `[c][k]` along
/// the pass's parameters, and the ray's right-hand-side evaluations.
type Row<const N: usize> = ([f64; 3], [[f64; N]; 3], u64);

/// Flags of one pair at a parameter point.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PairFlags {
    /// Dipped below the ground before its target plane.
    pub occluded: bool,
    /// Never reached its target plane.
    pub unreachable: bool,
}

/// The last Jacobian computed: the point (bit for bit), residuals, Jacobian.
type Memo = (Vec<f64>, DVector<f64>, DMatrix<f64>);

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
    /// LM computes the Jacobian at every accepted point, the last one
    /// included, and the fit's report needs it there again (standard errors,
    /// identifiability): the memo serves the second request.
    last_jacobian: Mutex<Option<Memo>>,
    /// A photo problem's camera: its free numbers follow the medium's in
    /// x, and it sets the pairs' directions and weights at each point.
    photo: Option<PhotoPart>,
}

/// The pairs and their ray jobs at one parameter point (a photo's camera
/// moves them; otherwise the objective's own).
struct Rays<'a> {
    pairs: Cow<'a, [PointPair]>,
    jobs: Cow<'a, [RayJob]>,
}

impl Clone for Objective {
    fn clone(&self) -> Self {
        self.with_options(self.options)
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
            last_jacobian: Mutex::new(None),
            photo: None,
        }
    }

    /// The same map with a photo's camera (`docs/photo.md`): its free
    /// numbers are appended to x, and its horizon marks' residuals follow
    /// the pairs'.
    pub fn with_photo(mut self, photo: Option<PhotoPart>) -> Objective {
        self.photo = photo;
        self
    }

    /// The camera's part, if any.
    pub fn photo(&self) -> Option<&PhotoPart> {
        self.photo.as_ref()
    }

    /// The pairs at `x` (a photo's camera sets their directions and
    /// weights; otherwise the objective's own).
    pub fn pairs_at(&self, x: &[f64]) -> Vec<PointPair> {
        self.rays(x).pairs.into_owned()
    }

    /// The pairs and jobs at `x`.
    fn rays(&self, x: &[f64]) -> Rays<'_> {
        match &self.photo {
            None => Rays {
                pairs: Cow::Borrowed(&self.pairs),
                jobs: Cow::Borrowed(&self.jobs),
            },
            Some(photo) => {
                let pairs = photo.pairs_at(&self.pairs, &x[self.free.len().min(x.len())..]);
                let jobs = pairs
                    .iter()
                    .map(|p| p.ray_job_on(self.options.earth))
                    .collect();
                Rays {
                    pairs: Cow::Owned(pairs),
                    jobs: Cow::Owned(jobs),
                }
            }
        }
    }

    /// The same residual map traced with other settings (a surrogate's
    /// tracer, `crate::fit::surrogate`), with counts of its own.
    pub fn with_options(&self, options: TraceOptions) -> Objective {
        Objective::new(
            self.template.clone(),
            self.free.clone(),
            self.pairs.clone(),
            options,
        )
        .with_photo(self.photo.clone())
    }

    /// The residual map of a problem file.
    pub fn from_problem(p: &Problem) -> Self {
        let photo = p
            .photo
            .as_ref()
            .map(|s| PhotoPart::new(s, &p.pairs, p.trace.earth));
        Objective::new(p.medium.clone(), p.free.clone(), p.pairs.clone(), p.trace).with_photo(photo)
    }

    /// The names of the parameters in x: the medium's, then the camera's.
    pub fn names(&self) -> Vec<String> {
        let mut names: Vec<String> = self.free.iter().map(|p| p.to_string()).collect();
        if let Some(photo) = &self.photo {
            names.extend(photo.free().iter().map(|p| p.to_string()));
        }
        names
    }

    /// Whether parameter k of x is an amplitude of the logistic model (the
    /// gauge, `crate::fit::identify`).
    pub fn amplitudes(&self) -> Vec<bool> {
        let mut a: Vec<bool> = self.free.iter().map(|p| p.is_amplitude()).collect();
        a.extend(
            self.photo
                .iter()
                .flat_map(|p| p.free().iter().map(|_| false)),
        );
        a
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

    /// Number of residuals (3 per pair, then 1 per horizon mark).
    pub fn len(&self) -> usize {
        3 * self.pairs.len() + self.photo.as_ref().map_or(0, |p| p.horizon_len())
    }

    /// Whether there are no residuals.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The starting values of the free parameters.
    pub fn start(&self) -> DVector<f64> {
        let camera = self.photo.iter().flat_map(|p| p.start());
        DVector::from_iterator(
            self.dimension(),
            self.free
                .iter()
                .map(|p| self.template.get(*p).unwrap_or(f64::NAN))
                .chain(camera),
        )
    }

    /// The number of parameters in x (the medium's and the camera's).
    pub fn dimension(&self) -> usize {
        self.free.len() + self.photo.as_ref().map_or(0, |p| p.free().len())
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
        let medium = self.medium(x);
        let fields = self.fields(&medium);
        let rays = self.rays(x);
        let batch = BatchOptions::from_trace_options(&self.options);
        let mut traces = vec![Trace::default(); self.pairs.len()];
        // One batch per wavelength (a single one, of every pair in order,
        // without per-pair wavelengths).
        for (g, field) in fields.fields().iter().enumerate() {
            let (members, jobs) = self.group(&rays, fields.groups(), g);
            let mut part = vec![Trace::default(); members.len()];
            // Chunks of one lane width; the split is fixed, so threads only
            // change who computes a chunk, not what it computes.
            jobs.par_chunks(LANE_CHUNK)
                .zip(part.par_chunks_mut(LANE_CHUNK))
                .for_each(|(jobs, part)| {
                    // Ctrl-C: the chunks left are skipped, and the solver's
                    // next cancellation point discards these residuals.
                    if !crate::interrupt::requested() {
                        crate::trace::batch::trace_batch_into(field, jobs, &batch, part)
                    }
                });
            for (i, t) in members.into_iter().zip(part) {
                traces[i] = t;
            }
        }
        let mut r = DVector::zeros(self.len());
        let mut flags = Vec::with_capacity(self.pairs.len());
        for (i, (t, pair)) in traces.iter().zip(rays.pairs.iter()).enumerate() {
            let ri = (t.endpoint - pair.target()) * pair.weight;
            r.fixed_rows_mut::<3>(3 * i).copy_from_slice(&ri.to_array());
            flags.push(PairFlags {
                occluded: t.occluded,
                unreachable: t.unreachable,
            });
            self.rhs_evaluations
                .fetch_add(t.stats.rhs_evaluations, Ordering::Relaxed);
        }
        if let Some(photo) = &self.photo {
            let h = photo.horizon_residuals(&medium, &x[self.free.len()..]);
            r.rows_mut(3 * self.pairs.len(), h.len())
                .copy_from_slice(&h);
        }
        (r, flags)
    }

    /// The pairs traced through field `g` (per pair, its field index in
    /// `groups`), in order, and their ray jobs.
    fn group(&self, rays: &Rays, groups: &[usize], g: usize) -> (Vec<usize>, Vec<RayJob>) {
        let members: Vec<usize> = (0..self.pairs.len()).filter(|&i| groups[i] == g).collect();
        let jobs = members.iter().map(|&i| rays.jobs[i]).collect();
        (members, jobs)
    }

    /// F = ½|r|² at `x` (∞ where the residuals are not finite).
    pub fn cost(&self, x: &[f64]) -> f64 {
        let (r, _) = self.residuals(x);
        let f = 0.5 * r.norm_squared();
        if f.is_finite() { f } else { f64::INFINITY }
    }

    /// Residuals and the exact 3m × n Jacobian at `x`: for the logistic
    /// model in the tangent lanes (`trace::batch::tangent`), for the other
    /// kinds (and any ray that does not end on its plane) by dual numbers
    /// through the scalar tracer ([`Objective::jacobian_dual`]); both
    /// differentiate the same discrete map and agree to rounding.
    ///
    /// A request at the point of the previous one (bit for bit) returns that
    /// result again without tracing (and without counting an evaluation).
    pub fn jacobian(&self, x: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
        let same = |m: &Memo| {
            m.0.len() == x.len() && m.0.iter().zip(x).all(|(a, b)| a.to_bits() == b.to_bits())
        };
        if let Ok(memo) = self.last_jacobian.lock()
            && let Some(m) = memo.as_ref().filter(|m| same(m))
        {
            return (m.1.clone(), m.2.clone());
        }
        let (r, jac) = self.jacobian_by(x, true);
        // After Ctrl-C the rows are placeholders, to be discarded.
        if !crate::interrupt::requested()
            && let Ok(mut memo) = self.last_jacobian.lock()
        {
            *memo = Some((x.to_vec(), r.clone(), jac.clone()));
        }
        (r, jac)
    }

    /// [`Objective::jacobian`] on the dual-number path alone: the reference
    /// the tangent lanes are checked against.
    pub fn jacobian_dual(&self, x: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
        self.jacobian_by(x, false)
    }

    fn jacobian_by(&self, x: &[f64], lanes: bool) -> (DVector<f64>, DMatrix<f64>) {
        self.jacobian_evaluations.fetch_add(1, Ordering::Relaxed);
        let n = self.free.len();
        let mut r = DVector::zeros(self.len());
        let mut jac = DMatrix::zeros(self.len(), self.dimension());
        let base = self.medium(x);
        let rays = self.rays(x);
        let mut first = 0;
        while first < n || (n == 0 && first == 0) {
            let width = (n - first).min(CHUNK);
            let cols = first..first + width;
            match width {
                0..=2 => self.jacobian_chunk::<2>(&base, &rays, cols, lanes, &mut r, &mut jac),
                3..=4 => self.jacobian_chunk::<4>(&base, &rays, cols, lanes, &mut r, &mut jac),
                _ => self.jacobian_chunk::<8>(&base, &rays, cols, lanes, &mut r, &mut jac),
            }
            first += width.max(1);
        }
        if let Some(photo) = &self.photo {
            let camera = &x[n..];
            let m = self.pairs.len();
            // The target marks' camera columns (through the launch
            // direction and f), then the horizon rows.
            photo.camera_columns(&base, &rays.pairs, &self.options, camera, &r, &mut jac, n);
            let (h, dh) = photo.horizon_rows(&base, &self.free, camera);
            for (k, (hk, row)) in h.iter().zip(dh).enumerate() {
                r[3 * m + k] = *hk;
                for (c, v) in row.into_iter().enumerate() {
                    jac[(3 * m + k, c)] = v;
                }
            }
        }
        (r, jac)
    }

    /// `base` in dual numbers of width `W`, seeded on the parameters
    /// `cols` (derivative part k on `free[cols.start + k]`).
    fn seeded<const W: usize>(&self, base: &Medium, cols: &std::ops::Range<usize>) -> Medium<D<W>> {
        base.map(|p, v| {
            let lane = self.free[cols.clone()].iter().position(|q| *q == p);
            match lane {
                Some(k) => D::<W>::from_re(v).derivative(k),
                None => D::<W>::from_re(v),
            }
        })
    }

    fn jacobian_chunk<const N: usize>(
        &self,
        base: &Medium,
        rays: &Rays,
        cols: std::ops::Range<usize>,
        lanes: bool,
        r: &mut DVector<f64>,
        jac: &mut DMatrix<f64>,
    ) {
        let mut rows: Vec<Option<Row<N>>> = vec![None; self.pairs.len()];
        if lanes {
            // The tangent kernel is built for 4 and 8 seeds only (each width
            // is a kernel per instruction set and ground): a pass of 2 takes
            // the one of 4 with two idle seeds.
            let plain = self.fields(base);
            if N <= 4 {
                let seeded = self.fields(&self.seeded::<4>(base, &cols));
                self.tangent_rows::<N, 4>(rays, &plain, &seeded, &mut rows);
            } else {
                let seeded = self.fields(&self.seeded::<8>(base, &cols));
                self.tangent_rows::<N, 8>(rays, &plain, &seeded, &mut rows);
            }
        }
        // Whatever the lanes did not give: dual numbers, pair by pair. The
        // per-wavelength media come from the seeded one, so they carry the
        // same derivative parts: the Jacobian stays exact.
        let missing: Vec<usize> = (0..rows.len()).filter(|&i| rows[i].is_none()).collect();
        let fields = if missing.is_empty() {
            None
        } else {
            Some(self.fields(&self.seeded::<N>(base, &cols)))
        };
        let dual: Vec<Row<N>> = missing
            .par_iter()
            .map(|&i| {
                let fields = fields.as_ref().expect("compiled when a row is missing");
                self.dual_row::<N>(fields.of(i), &rays.pairs[i])
            })
            .collect();
        for (i, row) in missing.into_iter().zip(dual) {
            rows[i] = Some(row);
        }
        for (i, row) in rows.into_iter().enumerate() {
            let (ri, di, evals) = row.expect("every row is filled");
            for c in 0..3 {
                r[3 * i + c] = ri[c];
                for (k, col) in cols.clone().enumerate() {
                    jac[(3 * i + c, col)] = di[c][k];
                }
            }
            self.rhs_evaluations.fetch_add(evals, Ordering::Relaxed);
        }
    }

    /// The rows of the pairs whose field is the logistic model, by the
    /// tangent lanes with `P ≥ N` seeds (the first N of them those of the
    /// pass), in chunks traced in parallel (a fixed split: the result does
    /// not depend on the number of threads). A ray that does not end on its
    /// plane keeps `None`.
    fn tangent_rows<const N: usize, const P: usize>(
        &self,
        rays: &Rays,
        plain: &PairFields,
        seeded: &PairFields<D<P>>,
        rows: &mut [Option<Row<N>>],
    ) {
        let batch = BatchOptions::from_trace_options(&self.options);
        for (g, (field, dual)) in plain.fields().iter().zip(seeded.fields()).enumerate() {
            let (Field::Logistic(field), Field::Logistic(dual)) = (field, dual) else {
                continue;
            };
            let (members, jobs) = self.group(rays, plain.groups(), g);
            let mut traces = vec![Trace::default(); members.len()];
            let ends: Vec<_> = jobs
                .par_chunks(TANGENT_CHUNK)
                .zip(traces.par_chunks_mut(TANGENT_CHUNK))
                .flat_map_iter(|(jobs, part)| {
                    if crate::interrupt::requested() {
                        // Ctrl-C: rows to be discarded (see `residuals`).
                        return vec![None; jobs.len()];
                    }
                    trace_tangent::<P>(field, dual, jobs, &batch, part)
                })
                .collect();
            for ((i, t), end) in members.into_iter().zip(traces).zip(ends) {
                let Some(d) = end else { continue };
                let pair = &rays.pairs[i];
                let ri = (t.endpoint - pair.target()) * pair.weight;
                let di = d.map(|c| std::array::from_fn(|k| c[k] * pair.weight));
                rows[i] = Some((ri.to_array(), di, t.stats.rhs_evaluations));
            }
        }
    }

    /// Pair `i`'s row by dual numbers through the scalar tracer.
    fn dual_row<const N: usize>(&self, field: &Field<D<N>>, pair: &PointPair) -> Row<N> {
        if crate::interrupt::requested() {
            // Ctrl-C: as in `residuals`, a row to be discarded.
            return ([0.0; 3], [[0.0; N]; 3], 0);
        }
        let (t, res) = pair.evaluate::<D<N>, _>(field, &self.options, None);
        let comps = [res.x, res.y, res.z];
        let mut d = [[0.0; N]; 3];
        for (row, c) in d.iter_mut().zip(&comps) {
            // A residual that does not depend on the chunk's parameters
            // carries no derivative part: unwrap_generic gives zeros then.
            let eps = c.eps.unwrap_generic(nalgebra::Const::<N>, nalgebra::U1);
            row.copy_from_slice(eps.as_slice());
        }
        (comps.map(|c| c.re()), d, t.stats.rhs_evaluations)
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
