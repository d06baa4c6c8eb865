use super::*;
use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{Executor, KvValue, OptimizationResult, State};
use nalgebra::{dmatrix, dvector};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

type Vector = DVector<f64>;
type Matrix = DMatrix<f64>;

/// Residual/Jacobian pair from two closures.
struct Fun<R, Jf> {
    r: R,
    j: Jf,
}

impl<R, Jf> Operator for Fun<R, Jf>
where
    R: Fn(&Vector) -> Vector,
{
    type Param = Vector;
    type Output = Vector;
    fn apply(&self, x: &Vector) -> Result<Vector, Error> {
        Ok((self.r)(x))
    }
}

impl<R, Jf> Jacobian for Fun<R, Jf>
where
    Jf: Fn(&Vector) -> Matrix,
{
    type Param = Vector;
    type Jacobian = Matrix;
    fn jacobian(&self, x: &Vector) -> Result<Matrix, Error> {
        Ok((self.j)(x))
    }
}

fn rosenbrock() -> Fun<impl Fn(&Vector) -> Vector, impl Fn(&Vector) -> Matrix> {
    Fun {
        r: |x: &Vector| dvector![10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]],
        j: |x: &Vector| dmatrix![-20.0 * x[0], 10.0; -1.0, 0.0],
    }
}

/// Panics if the wrapped problem is ever evaluated outside the box.
struct BoxChecked<P> {
    inner: P,
    lo: Vector,
    hi: Vector,
    evals: AtomicUsize,
}

impl<P> BoxChecked<P> {
    fn check(&self, x: &Vector) {
        for j in 0..x.len() {
            assert!(
                x[j] >= self.lo[j] && x[j] <= self.hi[j],
                "evaluated outside the box: x[{j}] = {} not in [{}, {}]",
                x[j],
                self.lo[j],
                self.hi[j]
            );
        }
        self.evals.fetch_add(1, Ordering::Relaxed);
    }
}

impl<P: Operator<Param = Vector, Output = Vector>> Operator for BoxChecked<P> {
    type Param = Vector;
    type Output = Vector;
    fn apply(&self, x: &Vector) -> Result<Vector, Error> {
        self.check(x);
        self.inner.apply(x)
    }
}

impl<P: Jacobian<Param = Vector, Jacobian = Matrix>> Jacobian for BoxChecked<P> {
    type Param = Vector;
    type Jacobian = Matrix;
    fn jacobian(&self, x: &Vector) -> Result<Matrix, Error> {
        self.check(x);
        self.inner.jacobian(x)
    }
}

/// Records every parameter vector and KV the executor reports.
#[derive(Clone, Default)]
struct Recorder {
    params: Arc<Mutex<Vec<Vector>>>,
    kvs: Arc<Mutex<Vec<KV>>>,
}

impl Observe<LmState> for Recorder {
    fn observe_init(&mut self, _name: &str, state: &LmState, kv: &KV) -> Result<(), Error> {
        self.params
            .lock()
            .unwrap()
            .push(state.get_param().unwrap().clone());
        self.kvs.lock().unwrap().push(kv.clone());
        Ok(())
    }
    fn observe_iter(&mut self, state: &LmState, kv: &KV) -> Result<(), Error> {
        self.params
            .lock()
            .unwrap()
            .push(state.get_param().unwrap().clone());
        self.kvs.lock().unwrap().push(kv.clone());
        Ok(())
    }
}

impl Recorder {
    /// Number of iterations whose step was accepted.
    fn accepted(&self) -> u64 {
        self.kvs
            .lock()
            .unwrap()
            .iter()
            .filter(|kv| kv.get("accepted") == Some(&KvValue::Bool(true)))
            .count() as u64
    }
}

type Res<P> = OptimizationResult<P, LevenbergMarquardt, LmState>;

fn solve<P>(p: P, solver: LevenbergMarquardt, x0: Vector, max_iters: u64) -> (Res<P>, Recorder)
where
    P: Operator<Param = Vector, Output = Vector> + Jacobian<Param = Vector, Jacobian = Matrix>,
{
    let rec = Recorder::default();
    let res = Executor::new(p, solver)
        .configure(|s| s.param(x0).max_iters(max_iters).counting(true))
        .add_observer(rec.clone(), ObserverMode::Always)
        .run()
        .unwrap();
    // LM is monotone: the current point must always be the best one.
    assert_eq!(res.state().get_param(), res.state().get_best_param());
    (res, rec)
}

fn reason<P>(res: &Res<P>) -> TerminationReason {
    res.state().get_termination_reason().unwrap().clone()
}

fn exit(stop: LmStop) -> TerminationReason {
    stop.into()
}

fn best<P>(res: &Res<P>) -> Vector {
    res.state().get_best_param().unwrap().clone()
}

fn assert_no_nan(rec: &Recorder) {
    for p in rec.params.lock().unwrap().iter() {
        assert!(all_finite(p.iter()), "non-finite iterate {p}");
    }
    for kv in rec.kvs.lock().unwrap().iter() {
        for (k, v) in kv.kv.iter() {
            if let KvValue::Float(f) = v {
                assert!(!f.is_nan(), "KV {k} is NaN");
            }
        }
    }
}

/// Largest cosine between r and a Jacobian column (MINPACK's gtol measure).
fn gradient_cosine(j: &Matrix, r: &Vector) -> f64 {
    let g = j.tr_mul(r);
    (0..j.ncols())
        .map(|c| g[c].abs() / (j.column(c).norm() * r.norm()))
        .fold(0.0, f64::max)
}

#[test]
fn rosenbrock_converges() {
    let (res, rec) = solve(
        rosenbrock(),
        LevenbergMarquardt::new(),
        dvector![-1.2, 1.0],
        200,
    );
    let x = best(&res);
    assert!(
        (x[0] - 1.0).abs() < 1e-10 && (x[1] - 1.0).abs() < 1e-10,
        "x = {x}"
    );
    assert!(res.state().get_best_cost() < 1e-20);
    assert!(
        LevenbergMarquardt::is_converged(&reason(&res)),
        "{:?}",
        reason(&res)
    );
    assert_no_nan(&rec);
    // Jacobian in the state belongs to the final accepted point.
    let j = res.state().get_jacobian().unwrap();
    assert_eq!(j, &dmatrix![-20.0 * x[0], 10.0; -1.0, 0.0]);
}

fn exp_model(t: Vector, y: Vector) -> Fun<impl Fn(&Vector) -> Vector, impl Fn(&Vector) -> Matrix> {
    let t2 = t.clone();
    Fun {
        r: move |p: &Vector| t.map(|ti| p[0] * (-p[1] * ti).exp() + p[2]) - &y,
        j: move |p: &Vector| {
            Matrix::from_fn(t2.len(), 3, |i, c| {
                let e = (-p[1] * t2[i]).exp();
                match c {
                    0 => e,
                    1 => -p[0] * t2[i] * e,
                    _ => 1.0,
                }
            })
        },
    }
}

fn exp_data(noise: f64) -> (Vector, Vector) {
    let t = Vector::from_fn(40, |i, _| 0.125 * i as f64);
    // Deterministic zero-mean-ish perturbation.
    let y = t.map(|ti| 2.5 * (-1.3 * ti).exp() + 0.5 + noise * (7.3 * ti + 0.4).sin());
    (t, y)
}

#[test]
fn exp_decay_noise_free_recovers_parameters() {
    let (t, y) = exp_data(0.0);
    let (res, rec) = solve(
        exp_model(t, y),
        LevenbergMarquardt::new(),
        dvector![1.0, 0.5, 0.0],
        200,
    );
    let p = best(&res);
    let truth = dvector![2.5, 1.3, 0.5];
    for k in 0..3 {
        assert!(((p[k] - truth[k]) / truth[k]).abs() < 1e-9, "p = {p}");
    }
    assert!(
        LevenbergMarquardt::is_converged(&reason(&res)),
        "{:?}",
        reason(&res)
    );
    assert_no_nan(&rec);
}

#[test]
fn exp_decay_noisy_satisfies_normal_equations() {
    let (t, y) = exp_data(0.05);
    let (res, _) = solve(
        exp_model(t.clone(), y.clone()),
        LevenbergMarquardt::new(),
        dvector![1.0, 0.5, 0.0],
        200,
    );
    assert!(
        LevenbergMarquardt::is_converged(&reason(&res)),
        "{:?}",
        reason(&res)
    );
    let p = best(&res);
    let model = exp_model(t.clone(), y.clone());
    let r = model.apply(&p).unwrap();
    let j = model.jacobian(&p).unwrap();
    assert!(r.norm() > 0.1, "noisy data must leave a residual");
    let cos = gradient_cosine(&j, &r);
    assert!(cos < 1e-7, "gradient cosine {cos}");
    // A different start lands on the same least-squares solution.
    let (res2, _) = solve(
        exp_model(t, y),
        LevenbergMarquardt::new(),
        dvector![5.0, 3.0, -1.0],
        200,
    );
    let p2 = best(&res2);
    assert!((&p - &p2).norm() < 1e-7 * p.norm(), "{p} vs {p2}");
}

/// y = A·exp(−k·t) with k ~ 1e-4 /s and A ~ 1e3 m, t up to 4e4 s.
fn badly_scaled(k_unit: f64) -> Fun<impl Fn(&Vector) -> Vector, impl Fn(&Vector) -> Matrix> {
    let t = Vector::from_fn(30, |i, _| 1500.0 * i as f64);
    let y = t.map(|ti| 1234.5 * (-1.7e-4 * ti).exp() + 3.0 * (0.001 * ti).cos());
    let t2 = t.clone();
    Fun {
        r: move |p: &Vector| t.map(|ti| p[1] * (-p[0] * k_unit * ti).exp()) - &y,
        j: move |p: &Vector| {
            Matrix::from_fn(t2.len(), 2, |i, c| {
                let e = (-p[0] * k_unit * t2[i]).exp();
                if c == 0 {
                    -p[1] * k_unit * t2[i] * e
                } else {
                    e
                }
            })
        },
    }
}

#[test]
fn badly_scaled_converges_and_is_unit_invariant() {
    let (res, rec) = solve(
        badly_scaled(1.0),
        LevenbergMarquardt::new(),
        dvector![3e-4, 500.0],
        100,
    );
    assert!(
        LevenbergMarquardt::is_converged(&reason(&res)),
        "{:?}",
        reason(&res)
    );
    let p = best(&res);
    let model = badly_scaled(1.0);
    let cos = gradient_cosine(&model.jacobian(&p).unwrap(), &model.apply(&p).unwrap());
    assert!(cos < 1e-7, "gradient cosine {cos}, p = {p}");
    assert!(
        (p[0] - 1.7e-4).abs() < 1e-5 && (p[1] - 1234.5).abs() < 10.0,
        "p = {p}"
    );

    // Same problem with k expressed in units of 1e-4: identical path.
    let (res2, rec2) = solve(
        badly_scaled(1e-4),
        LevenbergMarquardt::new(),
        dvector![3.0, 500.0],
        100,
    );
    assert_eq!(reason(&res), reason(&res2));
    assert_eq!(res.state().get_iter(), res2.state().get_iter());
    let p2 = best(&res2);
    assert!((p2[0] * 1e-4 - p[0]).abs() < 1e-10 * p[0] && (p2[1] - p[1]).abs() < 1e-10 * p[1]);
    let (a, b) = (rec.params.lock().unwrap(), rec2.params.lock().unwrap());
    assert_eq!(a.len(), b.len());
    for (u, v) in a.iter().zip(b.iter()) {
        assert!((v[0] * 1e-4 - u[0]).abs() <= 1e-9 * u[0].abs());
        assert!((v[1] - u[1]).abs() <= 1e-9 * u[1].abs());
    }
}

#[test]
fn powell_singular_converges_without_nan() {
    let s5 = 5f64.sqrt();
    let s10 = 10f64.sqrt();
    let p = Fun {
        r: move |x: &Vector| {
            dvector![
                x[0] + 10.0 * x[1],
                s5 * (x[2] - x[3]),
                (x[1] - 2.0 * x[2]).powi(2),
                s10 * (x[0] - x[3]).powi(2)
            ]
        },
        j: move |x: &Vector| {
            let a = 2.0 * (x[1] - 2.0 * x[2]);
            let b = 2.0 * s10 * (x[0] - x[3]);
            dmatrix![
                1.0, 10.0, 0.0, 0.0;
                0.0, 0.0, s5, -s5;
                0.0, a, -2.0 * a, 0.0;
                b, 0.0, 0.0, -b
            ]
        },
    };
    let (res, rec) = solve(
        p,
        LevenbergMarquardt::new(),
        dvector![3.0, -1.0, 0.0, 1.0],
        500,
    );
    let x = best(&res);
    assert!(x.norm() < 1e-6, "x = {x}, reason {:?}", reason(&res));
    assert!(res.state().get_best_cost() < 1e-20);
    assert!(
        LevenbergMarquardt::is_converged(&reason(&res)),
        "{:?}",
        reason(&res)
    );
    assert_no_nan(&rec);
}

#[test]
fn rank_deficient_converges_on_determined_part() {
    let p = Fun {
        r: |x: &Vector| dvector![x[0] + x[1] - 3.0, 2.0 * (x[0] + x[1]) - 6.0, x[2] - 1.0],
        j: |_: &Vector| dmatrix![1.0, 1.0, 0.0; 2.0, 2.0, 0.0; 0.0, 0.0, 1.0],
    };
    let x0 = dvector![0.5, -2.0, 7.0];
    let (res, rec) = solve(p, LevenbergMarquardt::new(), x0.clone(), 200);
    let x = best(&res);
    assert!((x[0] + x[1] - 3.0).abs() < 1e-10, "x = {x}");
    assert!((x[2] - 1.0).abs() < 1e-10, "x = {x}");
    // The flat direction x0 − x1 gets no step component at all.
    assert!(((x[0] - x[1]) - (x0[0] - x0[1])).abs() < 1e-12, "x = {x}");
    assert!(
        LevenbergMarquardt::is_converged(&reason(&res)),
        "{:?}",
        reason(&res)
    );
    assert_no_nan(&rec);
}

#[test]
fn underdetermined_problem_uses_direct_svd_path() {
    // m = 1 < n = 3: no QR pre-step; the step stays in the row space.
    let p = Fun {
        r: |x: &Vector| dvector![x[0] + 2.0 * x[1] - x[2] - 3.0],
        j: |_: &Vector| dmatrix![1.0, 2.0, -1.0],
    };
    let (res, rec) = solve(p, LevenbergMarquardt::new(), dvector![0.0, 0.0, 0.0], 100);
    assert!(
        LevenbergMarquardt::is_converged(&reason(&res)),
        "{:?}",
        reason(&res)
    );
    let x = best(&res);
    assert!((x[0] + 2.0 * x[1] - x[2] - 3.0).abs() < 1e-12, "x = {x}");
    // In the scaled variables y = D x (D = column norms 1, 2, 1) every
    // step lies in the row space of J D⁻¹ = (1, 1, −1).
    let d = dvector![1.0, 2.0, 1.0];
    let y = x.component_mul(&d);
    assert!(
        (y[0] - y[1]).abs() < 1e-12 && (y[0] + y[2]).abs() < 1e-12,
        "y = {y}"
    );
    assert_no_nan(&rec);
}

#[test]
fn bounded_rosenbrock_stays_in_box_and_reaches_kkt_point() {
    let lo = dvector![-2.0, f64::NEG_INFINITY];
    let hi = dvector![0.5, 3.0];
    let p = BoxChecked {
        inner: rosenbrock(),
        lo: lo.clone(),
        hi: hi.clone(),
        evals: AtomicUsize::new(0),
    };
    let solver = LevenbergMarquardt::new()
        .with_bounds(lo.clone(), hi.clone())
        .unwrap();
    let (res, rec) = solve(p, solver, dvector![-1.2, 1.0], 200);
    assert!(
        LevenbergMarquardt::is_converged(&reason(&res)),
        "{:?}",
        reason(&res)
    );
    let x = best(&res);
    assert_eq!(x[0], 0.5, "x = {x}");
    assert!((x[1] - 0.25).abs() < 1e-10, "x = {x}");
    // KKT: free component stationary, bound component's gradient points out.
    let prob = rosenbrock();
    let g = prob.jacobian(&x).unwrap().tr_mul(&prob.apply(&x).unwrap());
    assert!(g[1].abs() < 1e-8 && g[0] < 0.0, "g = {g}");
    let params = rec.params.lock().unwrap();
    assert!(params.len() > 2);
    for q in params.iter() {
        for j in 0..2 {
            assert!(q[j] >= lo[j] && q[j] <= hi[j], "iterate {q} left the box");
        }
    }
    let evals = res
        .problem()
        .problem
        .as_ref()
        .unwrap()
        .evals
        .load(Ordering::Relaxed);
    assert!(evals > 2);
    assert!(
        rec.kvs
            .lock()
            .unwrap()
            .iter()
            .any(|kv| kv.get("n_fixed") == Some(&KvValue::Uint(1)))
    );
}

#[test]
fn bounds_that_do_not_bind_leave_the_solution_alone() {
    let lo = dvector![-5.0, -5.0];
    let hi = dvector![5.0, 5.0];
    let p = BoxChecked {
        inner: rosenbrock(),
        lo: lo.clone(),
        hi: hi.clone(),
        evals: AtomicUsize::new(0),
    };
    let solver = LevenbergMarquardt::new().with_bounds(lo, hi).unwrap();
    let (res, _) = solve(p, solver, dvector![-1.2, 1.0], 200);
    let x = best(&res);
    assert!(
        (x[0] - 1.0).abs() < 1e-10 && (x[1] - 1.0).abs() < 1e-10,
        "x = {x}"
    );
}

#[test]
fn bounded_fit_with_start_on_bound_and_fixed_parameter() {
    // Offset c is forced to stay ≥ 0.8 (truth 0.5); amplitude fixed at 2.5.
    let (t, y) = exp_data(0.0);
    let lo = dvector![2.5, 0.0, 0.8];
    let hi = dvector![2.5, 10.0, f64::INFINITY];
    let p = BoxChecked {
        inner: exp_model(t.clone(), y.clone()),
        lo: lo.clone(),
        hi: hi.clone(),
        evals: AtomicUsize::new(0),
    };
    let solver = LevenbergMarquardt::new().with_bounds(lo, hi).unwrap();
    let (res, rec) = solve(p, solver, dvector![2.5, 0.0, 0.8], 300);
    assert!(
        LevenbergMarquardt::is_converged(&reason(&res)),
        "{:?}",
        reason(&res)
    );
    let x = best(&res);
    assert_eq!(x[0], 2.5);
    assert_eq!(x[2], 0.8);
    let model = exp_model(t, y);
    let g = model
        .jacobian(&x)
        .unwrap()
        .tr_mul(&model.apply(&x).unwrap());
    assert!(
        g[2] > 0.0,
        "c is held by its lower bound only if g_c > 0: g = {g}"
    );
    // Large-residual problem: Gauss–Newton converges linearly and ftol
    // stops at ~√ftol relative accuracy, so check the cosine, not 1e-12.
    let j = model.jacobian(&x).unwrap();
    let cos_b = g[1].abs() / (j.column(1).norm() * model.apply(&x).unwrap().norm());
    assert!(cos_b < 1e-6, "g = {g}, cos_b = {cos_b}");
    assert_no_nan(&rec);
}

#[test]
fn non_finite_residuals_are_rejected_not_accepted() {
    let nan_evals = Arc::new(AtomicUsize::new(0));
    let counter = nan_evals.clone();
    let p = Fun {
        r: move |x: &Vector| {
            if x.norm() > 2.0 {
                counter.fetch_add(1, Ordering::Relaxed);
                dvector![f64::NAN, 1.0]
            } else {
                dvector![10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]]
            }
        },
        j: |x: &Vector| dmatrix![-20.0 * x[0], 10.0; -1.0, 0.0],
    };
    let solver = LevenbergMarquardt::new()
        .with_initial_damping(1e-8)
        .unwrap();
    let (res, rec) = solve(p, solver, dvector![-1.2, 1.0], 300);
    assert!(
        nan_evals.load(Ordering::Relaxed) > 0,
        "test must hit the NaN region"
    );
    let x = best(&res);
    assert!(
        (x[0] - 1.0).abs() < 1e-10 && (x[1] - 1.0).abs() < 1e-10,
        "x = {x}"
    );
    assert!(res.state().get_best_cost().is_finite());
    for q in rec.params.lock().unwrap().iter() {
        assert!(q.norm() <= 2.0, "accepted a point in the NaN region: {q}");
    }
    assert_no_nan(&rec);
}

#[test]
fn max_iters_is_reported() {
    let (res, _) = solve(
        rosenbrock(),
        LevenbergMarquardt::new(),
        dvector![-1.2, 1.0],
        3,
    );
    assert_eq!(reason(&res), TerminationReason::MaxItersReached);
    assert_eq!(res.state().get_iter(), 3);
    assert!(!LevenbergMarquardt::is_converged(&reason(&res)));
}

#[test]
fn zero_residual_at_start_stops_immediately() {
    let (res, _) = solve(
        rosenbrock(),
        LevenbergMarquardt::new(),
        dvector![1.0, 1.0],
        100,
    );
    assert_eq!(reason(&res), exit(LmStop::ZeroResidual));
    assert_eq!(res.state().get_iter(), 0);
    assert_eq!(res.state().get_func_counts()["operator_count"], 1);
}

fn linear() -> Fun<impl Fn(&Vector) -> Vector, impl Fn(&Vector) -> Matrix> {
    Fun {
        r: |x: &Vector| dvector![x[0] - 1.0, 2.0 * x[1] + 3.0, x[0] + x[1] - 0.5],
        j: |_: &Vector| dmatrix![1.0, 0.0; 0.0, 2.0; 1.0, 1.0],
    }
}

#[test]
fn each_tolerance_path_is_reachable() {
    let x0 = dvector![-1.2, 1.0];
    let off = |s: LevenbergMarquardt| {
        s.with_ftol(0.0)
            .unwrap()
            .with_xtol(0.0)
            .unwrap()
            .with_gtol(0.0)
            .unwrap()
    };

    let xtol_only = off(LevenbergMarquardt::new()).with_xtol(1e-10).unwrap();
    let (res, _) = solve(rosenbrock(), xtol_only, x0.clone(), 200);
    assert_eq!(reason(&res), exit(LmStop::Xtol));
    let x = best(&res);
    assert!(
        (x[0] - 1.0).abs() < 1e-10 && (x[1] - 1.0).abs() < 1e-10,
        "x = {x}"
    );

    // Non-zero-residual linear problem: F* > 0, so ftol and gtol can fire.
    let ftol_only = off(LevenbergMarquardt::new()).with_ftol(1e-10).unwrap();
    let (res, _) = solve(linear(), ftol_only, dvector![10.0, 10.0], 200);
    assert_eq!(reason(&res), exit(LmStop::Ftol));

    let gtol_only = off(LevenbergMarquardt::new()).with_gtol(1e-10).unwrap();
    let (res, _) = solve(linear(), gtol_only, dvector![10.0, 10.0], 200);
    assert_eq!(reason(&res), exit(LmStop::Gtol));
    let p = best(&res);
    let prob = linear();
    assert!(gradient_cosine(&prob.jacobian(&p).unwrap(), &prob.apply(&p).unwrap()) <= 1e-10);
}

#[test]
fn target_cost_is_reported() {
    let res = Executor::new(rosenbrock(), LevenbergMarquardt::new())
        .configure(|s| {
            s.param(dvector![-1.2, 1.0])
                .max_iters(200)
                .target_cost(1e-6)
        })
        .run()
        .unwrap();
    assert_eq!(reason(&res), TerminationReason::TargetCostReached);
    assert!(res.state().get_best_cost() <= 1e-6);
}

/// Residual that is finite only at the exact starting point.
fn hostile() -> Fun<impl Fn(&Vector) -> Vector, impl Fn(&Vector) -> Matrix> {
    Fun {
        r: |x: &Vector| {
            if x[0] == 3.0 {
                dvector![x[0] - 1.0]
            } else {
                dvector![f64::INFINITY]
            }
        },
        j: |_: &Vector| dmatrix![1.0],
    }
}

#[test]
fn stalls_are_reported() {
    let solver = LevenbergMarquardt::new().with_xtol(0.0).unwrap();
    let (res, rec) = solve(hostile(), solver, dvector![3.0], 1000);
    assert_eq!(reason(&res), exit(LmStop::StallDamping));
    assert_eq!(best(&res)[0], 3.0);
    assert!(!LevenbergMarquardt::is_converged(&reason(&res)));
    assert_eq!(rec.accepted(), 0);
    assert_no_nan(&rec);

    let solver = LevenbergMarquardt::new()
        .with_xtol(0.0)
        .unwrap()
        .with_max_rejections(4)
        .unwrap();
    let (res, _) = solve(hostile(), solver, dvector![3.0], 1000);
    assert_eq!(reason(&res), exit(LmStop::StallRejections));
    assert_eq!(res.state().get_iter(), 4);
}

#[test]
fn counters_and_kv() {
    let (res, rec) = solve(
        rosenbrock(),
        LevenbergMarquardt::new(),
        dvector![-1.2, 1.0],
        200,
    );
    let counts = res.state().get_func_counts();
    let accepted = rec.accepted();
    assert!(accepted > 0);
    assert!(
        res.state().get_iter() > accepted,
        "run must contain rejected steps to test that they skip J"
    );
    // One Jacobian at the start plus one per accepted step, none for rejections.
    assert_eq!(counts["jacobian_count"], accepted + 1, "{counts:?}");
    assert!(
        counts["operator_count"] <= res.state().get_iter() + 1,
        "{counts:?}"
    );
    let kvs = rec.kvs.lock().unwrap();
    assert_eq!(kvs.len() as u64, res.state().get_iter() + 1);
    for kv in kvs.iter().skip(1) {
        for key in [
            "mu",
            "rho",
            "step_norm",
            "accepted",
            "cost_trial",
            "pred",
            "gnorm",
        ] {
            assert!(kv.get(key).is_some(), "missing {key}");
        }
        assert!(kv.get("mu").unwrap().get_float().unwrap() > 0.0);
    }
}

#[test]
fn setters_validate_input() {
    let s = LevenbergMarquardt::new;
    assert!(s().with_ftol(-1.0).is_err());
    assert!(s().with_xtol(f64::NAN).is_err());
    assert!(s().with_gtol(f64::INFINITY).is_err());
    assert!(s().with_initial_damping(0.0).is_err());
    assert!(s().with_initial_damping(f64::NAN).is_err());
    assert!(s().with_max_rejections(0).is_err());
    assert!(s().with_ftol(0.0).is_ok());
    assert!(s().with_bounds(dvector![0.0], dvector![1.0, 2.0]).is_err());
    assert!(s().with_bounds(dvector![2.0], dvector![1.0]).is_err());
    assert!(s().with_bounds(dvector![f64::NAN], dvector![1.0]).is_err());
    assert!(
        s().with_bounds(dvector![f64::INFINITY], dvector![f64::INFINITY])
            .is_err()
    );
    assert!(s().with_bounds(dvector![1.0], dvector![1.0]).is_ok());
}

#[test]
fn init_rejects_bad_start() {
    let run = |solver: LevenbergMarquardt, x0: Vector| {
        Executor::new(rosenbrock(), solver)
            .configure(|s| s.param(x0).max_iters(10))
            .run()
    };
    let boxed = || {
        LevenbergMarquardt::new()
            .with_bounds(dvector![0.0, 0.0], dvector![0.5, 1.0])
            .unwrap()
    };
    assert!(
        run(boxed(), dvector![-1.2, 1.0]).is_err(),
        "start outside the box"
    );
    assert!(
        run(boxed(), dvector![0.0, 0.0, 0.0]).is_err(),
        "length mismatch"
    );
    assert!(run(LevenbergMarquardt::new(), dvector![f64::NAN, 0.0]).is_err());
    assert!(run(boxed(), dvector![0.25, 1.0]).is_ok());
    let no_param = Executor::new(rosenbrock(), LevenbergMarquardt::new())
        .configure(|s| s.max_iters(10))
        .run();
    assert!(no_param.is_err());
}

#[test]
fn solver_can_be_reused() {
    let solver = LevenbergMarquardt::new();
    let (a, _) = solve(rosenbrock(), solver.clone(), dvector![-1.2, 1.0], 200);
    let (b, _) = solve(rosenbrock(), a.solver().clone(), dvector![-1.2, 1.0], 200);
    assert_eq!(a.state().get_iter(), b.state().get_iter());
    assert_eq!(best(&a), best(&b));
}

#[test]
fn module_doc_example() -> Result<(), Error> {
    struct Rosenbrock;

    impl Operator for Rosenbrock {
        type Param = DVector<f64>;
        type Output = DVector<f64>;
        fn apply(&self, x: &DVector<f64>) -> Result<DVector<f64>, Error> {
            Ok(dvector![10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]])
        }
    }

    impl Jacobian for Rosenbrock {
        type Param = DVector<f64>;
        type Jacobian = DMatrix<f64>;
        fn jacobian(&self, x: &DVector<f64>) -> Result<DMatrix<f64>, Error> {
            Ok(dmatrix![-20.0 * x[0], 10.0; -1.0, 0.0])
        }
    }

    let solver = LevenbergMarquardt::new().with_bounds(
        dvector![f64::NEG_INFINITY, -1.0],
        dvector![0.5, f64::INFINITY],
    )?;
    let res = Executor::new(Rosenbrock, solver)
        .configure(|s| s.param(dvector![-1.2, 1.0]).max_iters(200))
        .run()?;
    let x = res.state().get_best_param().unwrap();
    assert!((x[0] - 0.5).abs() < 1e-12 && (x[1] - 0.25).abs() < 1e-8);
    assert!(LevenbergMarquardt::is_converged(
        res.state().get_termination_reason().unwrap()
    ));
    Ok(())
}
