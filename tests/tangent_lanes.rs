//! The tangent lanes' Jacobian (`Objective::jacobian` for the logistic
//! model) against the dual-number reference (`Objective::jacobian_dual`):
//! the same derivative of the same discrete map, so equal to rounding, on
//! every bundled logistic problem and on media that exercise each part of
//! the kernel (RK4 and Dormand–Prince, the flat ground and the sphere,
//! culled hot spots, two parameter passes, rays that miss their plane).

use mirage::fit::objective::Objective;
use mirage::medium::{Background, HotSpot, Inversion, LogisticMedium, Medium, Param};
use mirage::pair::PointPair;
use mirage::problem::Problem;
use mirage::trace::{Earth, Method, TraceOptions};
use nalgebra::{DMatrix, DVector};

/// Largest column-wise difference between the two Jacobians, relative to
/// the column's size, and the residuals' difference relative to theirs.
fn compare(obj: &Objective, x: &[f64]) -> (f64, f64) {
    let (r, jac) = obj.jacobian(x);
    let (r_ref, jac_ref) = obj.jacobian_dual(x);
    assert!(jac.iter().all(|v| v.is_finite()), "a finite Jacobian");
    let residual = (&r - &r_ref).norm() / r_ref.norm().max(1e-9);
    (column_error(&jac, &jac_ref), residual)
}

fn column_error(jac: &DMatrix<f64>, reference: &DMatrix<f64>) -> f64 {
    let mut worst: f64 = 0.0;
    for k in 0..reference.ncols() {
        let size = reference.column(k).norm();
        let diff = (jac.column(k) - reference.column(k)).norm();
        worst = worst.max(if size > 0.0 { diff / size } else { diff });
    }
    worst
}

/// Every bundled problem file with a logistic medium.
fn bundled() -> Vec<Problem> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<_> = ["problems", "benches/baseline/problems"]
        .iter()
        .flat_map(|d| std::fs::read_dir(root.join(d)).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    files
        .iter()
        .map(|f| Problem::load(f).unwrap_or_else(|e| panic!("{}: {e}", f.display())))
        .filter(|p| matches!(p.medium, Medium::Logistic(_)))
        .collect()
}

#[test]
fn every_bundled_logistic_problem_gets_the_dual_jacobian() {
    let problems = bundled();
    assert!(problems.len() >= 6, "the bundled logistic problems");
    for p in problems {
        let obj = Objective::from_problem(&p);
        let start = obj.start();
        // The start, and a point 2 % away from it (every parameter moved).
        let moved = DVector::from_iterator(start.len(), start.iter().map(|v| v * 1.02 + 1e-3));
        for x in [start, moved] {
            let (jac, res) = compare(&obj, x.as_slice());
            eprintln!("{}: Jacobian {jac:.2e}, residuals {res:.2e}", p.name);
            assert!(jac < 1e-8, "{}: Jacobian differs by {jac:e}", p.name);
            assert!(res < 1e-9, "{}: residuals differ by {res:e}", p.name);
        }
    }
}

fn medium(hotspots: usize) -> LogisticMedium {
    LogisticMedium {
        scale: 1.2,
        background: Some(Background { n: 1.0, a: 40.0 }),
        inversion: Some(Inversion {
            n: 0.3,
            a: 2.0,
            height: 25.0,
        }),
        hotspots: (0..hotspots)
            .map(|j| HotSpot {
                x: 10.0 + 30.0 * j as f64,
                z: 500.0 + 150.0 * j as f64,
                radius: 150.0,
                n: -2.0 + 0.3 * j as f64,
                a: -0.8,
                edge: 0.2,
            })
            .collect(),
    }
}

fn pairs(distance: f64) -> Vec<PointPair> {
    let mk = |tx: f64, ty: f64, ey: f64| PointPair {
        origin: [0.0, 1.6, 0.0],
        through: [tx, ty, distance],
        target: [tx, ey, distance],
        weight: 1.5,
        wavelength: None,
    };
    (0..11)
        .map(|i| {
            let f = i as f64;
            mk(-50.0 + 10.0 * f, -1.0 + 0.4 * f, 3.0 + 1.5 * f)
        })
        .collect()
}

/// Every parameter free: 11 with one hot spot (two passes, 8 + 3), more
/// with several.
fn all_free(m: &LogisticMedium) -> Vec<Param> {
    m.params().into_iter().map(|(p, _)| p).collect()
}

fn check(hotspots: usize, method: Method, earth: Earth, distance: f64) {
    let m = medium(hotspots);
    let free = all_free(&m);
    let mut options = TraceOptions::new(method);
    options.earth = earth;
    let obj = Objective::new(m, free, pairs(distance), options);
    let x = obj.start();
    let (jac, res) = compare(&obj, x.as_slice());
    eprintln!("{hotspots} hot spot(s), {method:?}, {earth:?}: {jac:.2e}, {res:.2e}");
    assert!(jac < 1e-8, "Jacobian differs by {jac:e}");
    assert!(res < 1e-9, "residuals differ by {res:e}");
}

#[test]
fn fixed_steps_over_the_flat_ground() {
    check(1, Method::Rk4 { step: 2.0 }, Earth::Flat, 900.0);
}

#[test]
fn adaptive_steps_over_the_flat_ground() {
    check(1, Method::Dopri5 { tolerance: 1e-10 }, Earth::Flat, 900.0);
}

#[test]
fn over_the_round_earth() {
    let earth = Earth::Round {
        radius: 6_371_000.0,
    };
    check(1, Method::Rk4 { step: 5.0 }, earth, 3000.0);
    check(1, Method::Dopri5 { tolerance: 1e-9 }, earth, 3000.0);
}

#[test]
fn culled_hot_spots() {
    // Three hot spots: the field has a culling grid, and each lane takes its
    // own cell's list.
    check(3, Method::Rk4 { step: 2.0 }, Earth::Flat, 900.0);
    check(3, Method::Dopri5 { tolerance: 1e-10 }, Earth::Flat, 900.0);
}

#[test]
fn a_stratified_medium() {
    // No hot spots: the residuals take the 2-D kernel, the Jacobian the 3-D
    // tangent kernel.
    check(0, Method::Dopri5 { tolerance: 1e-10 }, Earth::Flat, 900.0);
}

#[test]
fn rays_that_miss_their_plane_take_the_dual_path() {
    let m = medium(1);
    let free = all_free(&m);
    let mut options = TraceOptions::new(Method::Rk4 { step: 2.0 });
    // Shorter than the rays' way to their planes: every ray is unreachable.
    options.max_length = Some(400.0);
    let mut pp = pairs(900.0);
    // One ray that reaches its plane among them.
    pp.push(PointPair {
        origin: [0.0, 1.6, 0.0],
        through: [0.0, 1.0, 300.0],
        target: [0.0, 1.2, 300.0],
        weight: 1.0,
        wavelength: None,
    });
    let obj = Objective::new(m, free, pp, options);
    let x = obj.start();
    let (jac, res) = compare(&obj, x.as_slice());
    assert!(jac < 1e-8, "Jacobian differs by {jac:e}");
    assert!(res < 1e-9, "residuals differ by {res:e}");
}
