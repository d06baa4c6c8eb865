//! The exact Jacobian (dual numbers through the tracer) against central finite
//! differences of the same discrete map.

use mirage::fit::objective::Objective;
use mirage::medium::{Background, HotSpot, Inversion, LogisticMedium, Param};
use mirage::pair::PointPair;
use mirage::trace::{Method, TraceOptions};

fn medium() -> LogisticMedium {
    LogisticMedium {
        scale: 1.0,
        background: Some(Background { n: 1.0, a: 40.0 }),
        inversion: Some(Inversion {
            n: 0.3,
            a: 2.0,
            height: 25.0,
        }),
        hotspots: vec![HotSpot {
            x: 10.0,
            z: 500.0,
            radius: 150.0,
            n: -2.0,
            a: -0.8,
            edge: 0.2,
        }],
    }
}

fn pairs() -> Vec<PointPair> {
    let mk = |tx: f64, ty: f64, ey: f64| PointPair {
        origin: [0.0, 1.6, 0.0],
        through: [tx, ty, 900.0],
        target: [tx, ey, 900.0],
        weight: 1.0,
        wavelength: None,
    };
    vec![
        mk(0.0, -1.0, 20.0),
        mk(40.0, -0.5, 15.0),
        mk(-30.0, 0.5, 8.0),
        mk(15.0, 3.0, 5.0),
    ]
}

fn all_free(m: &LogisticMedium) -> Vec<Param> {
    // Every parameter but the scale (which is in gauge with nothing here but is
    // a plain multiplier) — eleven columns, so two dual chunks (8 + 3).
    m.params()
        .into_iter()
        .map(|(p, _)| p)
        .filter(|p| *p != Param::Scale)
        .collect()
}

fn check(method: Method, rel: f64) {
    let m = medium();
    let free = all_free(&m);
    assert!(free.len() > 8, "exercise more than one dual chunk");
    let obj = Objective::new(m, free.clone(), pairs(), TraceOptions::new(method));
    let x = obj.start();
    let (r, jac) = obj.jacobian(x.as_slice());
    let (r_plain, _) = obj.residuals(x.as_slice());
    assert!(
        (&r - &r_plain).norm() <= 1e-12 * r.norm(),
        "dual real parts equal the f64 map"
    );
    for (k, p) in free.iter().enumerate() {
        // Endpoints ~1 km from the origin carry rounding of ~1e-13 m, so the step
        // must be large enough that noise/h stays far below 1e-6 relative; the
        // truncation error O(h²) is then still negligible.
        let h = 1e-4 * x[k].abs().max(1e-2);
        let mut xp = x.clone();
        xp[k] += h;
        let mut xm = x.clone();
        xm[k] -= h;
        let fd = (obj.residuals(xp.as_slice()).0 - obj.residuals(xm.as_slice()).0) / (2.0 * h);
        let col = jac.column(k);
        let err = (&fd - col).norm() / col.norm().max(1e-12);
        eprintln!("{p}: |J| = {:.3e}, relative error {err:.2e}", col.norm());
        assert!(
            err < rel,
            "{method:?} {p}: exact {col:?} vs finite differences {fd:?}"
        );
    }
}

#[test]
fn jacobian_matches_finite_differences_of_a_fixed_step_trace() {
    check(Method::Rk4 { step: 2.0 }, 1e-6);
}

#[test]
fn jacobian_of_the_adaptive_trace_is_that_of_its_frozen_step_map() {
    // Finite differences of an adaptive trace see step-control noise; at a tight
    // tolerance that noise is small enough to compare with.
    check(Method::Dopri5 { tolerance: 1e-12 }, 1e-5);
}
