//! The Nelder–Mead simplex method for [`argmin`], with the stopping tests a fit
//! needs.
//!
//! # Why not argmin's own
//!
//! argmin's `NelderMead` keeps its simplex private and stops only when the
//! standard deviation of F over the vertices falls below an absolute
//! tolerance. A fit has no absolute scale for F that suits every problem (the
//! bundled ones reach F = 1e-20 m² and keep improving by rounding noise), so
//! `mirage fit --method nelder-mead` ran to its iteration limit (4,000–6,000
//! iterations, seconds to a minute) long after it had met its target. This
//! solver makes the same moves and adds the tests below.
//!
//! # Algorithm
//!
//! Nelder & Mead (1965) in the form of Lagarias et al. (1998), with the
//! standard coefficients: reflection α = 1, expansion γ = 2, contraction
//! ρ = ½ (outside and inside), shrink σ = ½. One argmin iteration is one
//! move: the worst vertex is reflected through the centroid of the others;
//! a reflection better than the best vertex is tried expanded; one worse than
//! the second-worst is contracted (outside if it improved on the worst,
//! inside otherwise); a failed contraction shrinks every vertex halfway to
//! the best. The vertices are kept sorted by F, best first (ties keep their
//! order), and a non-finite F counts as +∞, so a vertex that cannot be traced
//! is the first to go. The state's parameter and cost are the best vertex's.
//!
//! # Termination
//!
//! Checked before every iteration, the first included (a start that already
//! meets the target makes no iteration), in this order; the reason is set as
//! `TerminationReason::SolverExit(s)`, `s` the text of one of the [`NmStop`]
//! variants ([`NmStop::from_reason`] reads it back):
//!
//! | reason | test |
//! |---|---|
//! | [`Target`](NmStop::Target) | `F_best ≤ target` ([`NelderMead::with_target`], the problem's `target_objective`) |
//! | [`SimplexSize`](NmStop::SimplexSize) | `maxᵢ,ₖ |vᵢₖ − v₀ₖ| / sₖ ≤ xtol`: every vertex `vᵢ` within `xtol` of the best `v₀` in every coordinate `k`, measured in units of `sₖ`, the starting simplex's extent along `k` (so the starting size is 1 and the test is free of the parameters' units) |
//! | [`FSpread`](NmStop::FSpread) | `F_worst − F_best ≤ ftol · F_best`: F is the same at every vertex to a relative `ftol` |
//!
//! argmin adds `MaxItersReached` (`max_iters` in `Executor::configure`).
//! The size test is what stops a fit whose targets can be met exactly (F
//! falls towards 0 with the simplex, so its relative spread does not shrink);
//! the spread test stops one whose targets cannot all be met (F levels off
//! above 0 while the simplex is still wide in the directions F barely
//! depends on). A tolerance of 0 turns its test off, except that a simplex
//! of identical vertices, or of identical values of F, still stops.

use argmin::core::{
    CostFunction, Error, IterState, KV, Problem, Solver, TerminationReason, TerminationStatus,
};
use nalgebra::DVector;
use std::fmt;

/// The state the solver runs with: parameters and F, no derivatives.
pub type NmState = IterState<DVector<f64>, (), (), (), (), f64>;

/// A stop by one of the solver's own tests.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NmStop {
    /// The best vertex meets the target.
    Target,
    /// The simplex has shrunk below `xtol` of its starting size.
    SimplexSize,
    /// F varies over the simplex by less than `ftol` relative.
    FSpread,
}

impl NmStop {
    /// Every stop, in the order the tests run.
    pub const ALL: [NmStop; 3] = [NmStop::Target, NmStop::SimplexSize, NmStop::FSpread];

    /// The text reported in `TerminationReason::SolverExit`.
    pub fn text(self) -> &'static str {
        match self {
            NmStop::Target => "Nelder–Mead reached the target: F ≤ target_objective",
            NmStop::SimplexSize => {
                "Nelder–Mead converged (simplex_xtol): the simplex has shrunk below \
                 simplex_xtol of its starting size"
            }
            NmStop::FSpread => {
                "Nelder–Mead converged (simplex_ftol): F differs over the simplex by less \
                 than simplex_ftol × F"
            }
        }
    }

    /// The stop an argmin termination reason carries, if it is one of ours.
    pub fn from_reason(reason: &TerminationReason) -> Option<NmStop> {
        match reason {
            TerminationReason::SolverExit(s) => {
                NmStop::ALL.into_iter().find(|stop| stop.text() == s)
            }
            _ => None,
        }
    }
}

impl fmt::Display for NmStop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.text())
    }
}

impl From<NmStop> for TerminationReason {
    fn from(stop: NmStop) -> Self {
        TerminationReason::SolverExit(stop.text().to_string())
    }
}

/// The Nelder–Mead solver (see the module documentation).
#[derive(Clone, Debug)]
pub struct NelderMead {
    /// Vertices and their F, best first once initialised.
    simplex: Vec<(DVector<f64>, f64)>,
    /// The starting simplex's extent along each coordinate (1 where it has none).
    scale: DVector<f64>,
    target: f64,
    xtol: f64,
    ftol: f64,
}

fn invalid(message: impl Into<String>) -> Error {
    argmin::core::ArgminError::InvalidParameter {
        text: message.into(),
    }
    .into()
}

impl NelderMead {
    /// A solver starting from `vertices` (n + 1 points in n dimensions, the
    /// first the start). No target; both tolerances 0.
    pub fn new(vertices: Vec<DVector<f64>>) -> Result<Self, Error> {
        let Some(first) = vertices.first() else {
            return Err(invalid("NelderMead: the simplex has no vertices"));
        };
        let n = first.len();
        if vertices.len() != n + 1 || vertices.iter().any(|v| v.len() != n) {
            return Err(invalid(format!(
                "NelderMead: a simplex in {n} dimensions needs {} vertices of length {n}",
                n + 1
            )));
        }
        if vertices.iter().any(|v| v.iter().any(|c| !c.is_finite())) {
            return Err(invalid("NelderMead: a vertex is not finite"));
        }
        let scale = DVector::from_fn(n, |k, _| {
            let extent = vertices
                .iter()
                .map(|v| (v[k] - first[k]).abs())
                .fold(0.0, f64::max);
            if extent > 0.0 { extent } else { 1.0 }
        });
        Ok(NelderMead {
            simplex: vertices.into_iter().map(|v| (v, f64::INFINITY)).collect(),
            scale,
            target: f64::NEG_INFINITY,
            xtol: 0.0,
            ftol: 0.0,
        })
    }

    /// Stop once the best F is at or below `target` (m²; −∞ for never).
    pub fn with_target(mut self, target: f64) -> Result<Self, Error> {
        if target.is_nan() {
            return Err(invalid("NelderMead: the target is not a number"));
        }
        self.target = target;
        Ok(self)
    }

    /// Stop once the simplex is within `xtol` of its starting size (finite, ≥ 0).
    pub fn with_xtol(mut self, xtol: f64) -> Result<Self, Error> {
        self.xtol = tolerance("xtol", xtol)?;
        Ok(self)
    }

    /// Stop once F varies over the simplex by less than `ftol` relative
    /// (finite, ≥ 0).
    pub fn with_ftol(mut self, ftol: f64) -> Result<Self, Error> {
        self.ftol = tolerance("ftol", ftol)?;
        Ok(self)
    }

    /// The simplex's size: the largest distance of a vertex from the best
    /// along any coordinate, in units of the starting simplex's extent there.
    pub fn size(&self) -> f64 {
        let best = &self.simplex[0].0;
        self.simplex
            .iter()
            .skip(1)
            .flat_map(|(v, _)| {
                v.iter()
                    .zip(best.iter())
                    .zip(self.scale.iter())
                    .map(|((a, b), s)| (a - b).abs() / s)
            })
            .fold(0.0, f64::max)
    }

    /// F at the worst vertex minus F at the best.
    pub fn spread(&self) -> f64 {
        let worst = self.simplex[self.simplex.len() - 1].1;
        worst - self.simplex[0].1
    }

    fn sort(&mut self) {
        // Stable, so ties keep their order and runs are reproducible.
        self.simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
    }

    /// The centroid of every vertex but the worst.
    fn centroid(&self) -> DVector<f64> {
        let m = self.simplex.len() - 1;
        let mut c = DVector::zeros(self.scale.len());
        for (v, _) in &self.simplex[..m] {
            c += v;
        }
        c / m as f64
    }
}

fn tolerance(name: &str, v: f64) -> Result<f64, Error> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(invalid(format!(
            "NelderMead: {name} must be finite and ≥ 0, got {v}"
        )))
    }
}

/// F at `x`, a non-finite value read as +∞.
fn cost<O>(problem: &mut Problem<O>, x: &DVector<f64>) -> Result<f64, Error>
where
    O: CostFunction<Param = DVector<f64>, Output = f64>,
{
    let f = problem.cost(x)?;
    Ok(if f.is_finite() { f } else { f64::INFINITY })
}

impl<O> Solver<O, NmState> for NelderMead
where
    O: CostFunction<Param = DVector<f64>, Output = f64>,
{
    fn name(&self) -> &str {
        "Nelder-Mead"
    }

    fn init(
        &mut self,
        problem: &mut Problem<O>,
        state: NmState,
    ) -> Result<(NmState, Option<KV>), Error> {
        for k in 0..self.simplex.len() {
            let f = cost(problem, &self.simplex[k].0)?;
            self.simplex[k].1 = f;
        }
        self.sort();
        let (best, f) = self.simplex[0].clone();
        Ok((state.param(best).cost(f), None))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<O>,
        state: NmState,
    ) -> Result<(NmState, Option<KV>), Error> {
        let (alpha, gamma, rho, sigma) = (1.0, 2.0, 0.5, 0.5);
        let last = self.simplex.len() - 1;
        if last == 0 {
            // No free parameter: nothing to move (the size test stops first).
            let (best, f) = self.simplex[0].clone();
            return Ok((state.param(best).cost(f), None));
        }
        let c = self.centroid();
        let f_best = self.simplex[0].1;
        let f_second_worst = self.simplex[last - 1].1;
        let (worst, f_worst) = self.simplex[last].clone();
        let xr = &c + (&c - &worst) * alpha;
        let fr = cost(problem, &xr)?;
        let replacement = if fr < f_best {
            let xe = &c + (&xr - &c) * gamma;
            let fe = cost(problem, &xe)?;
            Some(if fe < fr { (xe, fe) } else { (xr, fr) })
        } else if fr < f_second_worst {
            Some((xr, fr))
        } else if fr < f_worst {
            let xc = &c + (&xr - &c) * rho;
            let fc = cost(problem, &xc)?;
            (fc <= fr).then_some((xc, fc))
        } else {
            let xc = &c + (&worst - &c) * rho;
            let fc = cost(problem, &xc)?;
            (fc < f_worst).then_some((xc, fc))
        };
        match replacement {
            Some(vertex) => self.simplex[last] = vertex,
            None => {
                let best = self.simplex[0].0.clone();
                for k in 1..=last {
                    let v = &best + (&self.simplex[k].0 - &best) * sigma;
                    let f = cost(problem, &v)?;
                    self.simplex[k] = (v, f);
                }
            }
        }
        self.sort();
        let (best, f) = self.simplex[0].clone();
        Ok((state.param(best).cost(f), None))
    }

    fn terminate(&mut self, _state: &NmState) -> TerminationStatus {
        let f_best = self.simplex[0].1;
        let stop = if f_best <= self.target {
            Some(NmStop::Target)
        } else if self.size() <= self.xtol {
            Some(NmStop::SimplexSize)
        } else if self.spread() <= self.ftol * f_best {
            Some(NmStop::FSpread)
        } else {
            None
        };
        match stop {
            Some(s) => TerminationStatus::Terminated(s.into()),
            None => TerminationStatus::NotTerminated,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use argmin::core::{Executor, State};

    /// F = offset + Σ wₖ (xₖ − aₖ)²: a minimum of `offset` at `a`.
    struct Bowl {
        a: Vec<f64>,
        w: Vec<f64>,
        offset: f64,
    }

    impl CostFunction for Bowl {
        type Param = DVector<f64>;
        type Output = f64;
        fn cost(&self, x: &DVector<f64>) -> Result<f64, Error> {
            Ok(self.offset
                + x.iter()
                    .zip(&self.a)
                    .zip(&self.w)
                    .map(|((x, a), w)| w * (x - a).powi(2))
                    .sum::<f64>())
        }
    }

    fn bowl(offset: f64) -> Bowl {
        Bowl {
            a: vec![1.5, -2.0, 0.25],
            w: vec![1.0, 30.0, 0.2],
            offset,
        }
    }

    fn simplex(x0: &[f64], step: f64) -> Vec<DVector<f64>> {
        let mut s = vec![DVector::from_column_slice(x0)];
        for k in 0..x0.len() {
            let mut v = DVector::from_column_slice(x0);
            v[k] += step;
            s.push(v);
        }
        s
    }

    fn run(
        problem: Bowl,
        solver: NelderMead,
        max_iters: u64,
    ) -> (NmState, Option<NmStop>, TerminationReason) {
        let result = Executor::new(problem, solver)
            .configure(|s| s.max_iters(max_iters))
            .timer(false)
            .run()
            .unwrap();
        let state = result.state().clone();
        let reason = state.get_termination_reason().cloned().unwrap();
        (state, NmStop::from_reason(&reason), reason)
    }

    fn solver(target: f64, xtol: f64, ftol: f64) -> NelderMead {
        NelderMead::new(simplex(&[0.0, 0.0, 0.0], 0.5))
            .and_then(|s| s.with_target(target))
            .and_then(|s| s.with_xtol(xtol))
            .and_then(|s| s.with_ftol(ftol))
            .unwrap()
    }

    #[test]
    fn stops_at_the_target() {
        let (state, stop, _) = run(bowl(0.0), solver(1e-6, 0.0, 0.0), 10_000);
        assert_eq!(stop, Some(NmStop::Target));
        assert!(state.get_best_cost() <= 1e-6);
        // Not long after: the previous F was above the target.
        assert!(state.get_best_cost() > 1e-9, "{}", state.get_best_cost());
    }

    #[test]
    fn a_start_at_the_target_makes_no_iteration() {
        let nm = NelderMead::new(simplex(&[1.5, -2.0, 0.25], 0.5))
            .and_then(|s| s.with_target(0.0))
            .unwrap();
        let (state, stop, _) = run(bowl(0.0), nm, 10_000);
        assert_eq!(stop, Some(NmStop::Target));
        assert_eq!(state.get_iter(), 0);
    }

    #[test]
    fn stops_when_the_simplex_has_collapsed() {
        // A minimum of 0 that the target never reaches: F's relative spread
        // stays of order one while the simplex shrinks, so the size test stops it.
        let (state, stop, _) = run(bowl(0.0), solver(f64::NEG_INFINITY, 1e-9, 1e-12), 100_000);
        assert_eq!(stop, Some(NmStop::SimplexSize));
        let x = state.get_best_param().unwrap();
        for (x, a) in x.iter().zip([1.5, -2.0, 0.25]) {
            assert!((x - a).abs() < 1e-8, "{x} vs {a}");
        }
    }

    #[test]
    fn stops_when_the_spread_of_f_has_collapsed() {
        // A minimum of 1: F levels off long before the simplex is small.
        let nm = solver(0.0, 1e-12, 1e-10);
        let (state, stop, _) = run(bowl(1.0), nm, 100_000);
        assert_eq!(stop, Some(NmStop::FSpread));
        assert!((state.get_best_cost() - 1.0).abs() < 1e-9);
    }

    #[test]
    fn stops_at_the_iteration_limit() {
        let (state, stop, reason) = run(bowl(0.0), solver(0.0, 0.0, 0.0), 25);
        assert_eq!(stop, None);
        assert_eq!(reason, TerminationReason::MaxItersReached);
        assert_eq!(state.get_iter(), 25);
    }

    #[test]
    fn a_simplex_that_is_not_one_is_refused() {
        assert!(NelderMead::new(vec![]).is_err());
        assert!(NelderMead::new(simplex(&[0.0, 0.0], 1.0)[..2].to_vec()).is_err());
        let nan = vec![
            DVector::from_vec(vec![f64::NAN]),
            DVector::from_vec(vec![1.0]),
        ];
        assert!(NelderMead::new(nan).is_err());
        let nm = NelderMead::new(simplex(&[0.0], 1.0)).unwrap();
        assert!(nm.clone().with_xtol(-1.0).is_err());
        assert!(nm.clone().with_ftol(f64::INFINITY).is_err());
        assert!(nm.with_target(f64::NAN).is_err());
    }

    #[test]
    fn reasons_round_trip() {
        for stop in NmStop::ALL {
            assert_eq!(NmStop::from_reason(&stop.into()), Some(stop));
        }
        assert_eq!(
            NmStop::from_reason(&TerminationReason::MaxItersReached),
            None
        );
    }
}
