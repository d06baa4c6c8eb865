//! What every fuzz target checks: an input is either accepted, and then
//! everything computed from it is finite, or refused with an input error that
//! names a field (exit code 2), never a panic.

#![allow(dead_code)]

use mirage::error::Error;
use mirage::evaluate::trace_pairs;
use mirage::math::V3;
use mirage::medium::{IndexField, Medium};
use mirage::problem::Problem;
use mirage::trace::{Earth, Method, TargetPlane, TraceOptions, trace};
use std::path::PathBuf;
use std::sync::OnceLock;

/// A step cap that keeps one fuzz input well under a second: a runaway trace
/// is what the cap is for, and hitting it is a valid end (`step_limit`).
pub const MAX_STEPS: u64 = 20_000;

/// An error from parsing or validating an input: an input error with a
/// field path and a message, so that `mirage` exits 2 and says where.
pub fn check_error(e: &Error) {
    let field = e
        .field()
        .unwrap_or_else(|| panic!("not an input error (exit {}): {e}", e.exit_code()));
    assert_eq!(e.exit_code(), 2, "{e}");
    assert!(!field.path.is_empty(), "no field named: {e}");
    assert!(!field.message.is_empty(), "no message: {e}");
}

/// A scratch folder for this process (the scene targets write a sibling file).
pub fn scratch() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = std::env::temp_dir().join(format!("mirage-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    })
}

/// Traces a loaded problem (at most four pairs, capped steps) and checks that
/// every number of the report is finite.
pub fn check_problem(mut p: Problem) {
    p.pairs.truncate(4);
    p.trace.max_steps = MAX_STEPS;
    let r = trace_pairs(&p, &p.medium);
    for (i, pr) in r.pairs.iter().enumerate() {
        let all = pr
            .endpoint
            .iter()
            .chain(&pr.direction)
            .chain(&pr.residual)
            .chain([&pr.distance, &pr.arc_length]);
        for v in all {
            assert!(v.is_finite(), "pair {i}: non-finite output {pr:?}");
        }
    }
    assert!(!r.totals.objective.is_nan(), "objective NaN");
}

/// Checks a valid medium: δ and ∇δ finite at a few heights, and rays from
/// grazing to vertical (flat and round earth) end at finite points.
pub fn check_medium(m: &Medium) {
    let field = m.field();
    let ceiling = IndexField::<f64>::ceiling(&field);
    for h in [0.0, 1e-3, 0.05, 1.0, 10.0, 100.0, 1e3, 1e4] {
        if h > ceiling {
            continue;
        }
        let (d, g) = field.delta_gradient(V3::new(3.0, h, 500.0));
        assert!(d.is_finite() && g.is_finite(), "δ({h}) = {d}, ∇δ = {g:?}");
    }
    for earth in [Earth::Flat, Earth::Round { radius: 6.371e6 }] {
        for elevation in [-0.01_f64, 0.0, 0.003, 0.1, 1.0, 89.0, 90.0] {
            let e = elevation.to_radians();
            let d = V3::new(0.0, e.sin(), e.cos()).normalized();
            check_ray(
                &field,
                V3::new(0.0, 1.5, 0.0),
                d,
                earth,
                300.0,
                Method::Rk4 { step: 5.0 },
                m,
            );
        }
    }
}

/// One ray, capped; its endpoint, direction and length must be finite.
/// `medium` is shown when it fails, so that a crash report says which air.
#[allow(clippy::too_many_arguments)]
pub fn check_ray(
    field: &mirage::medium::Field,
    origin: V3,
    direction: V3,
    earth: Earth,
    distance: f64,
    method: Method,
    medium: &Medium,
) {
    let mut o = TraceOptions::new(method);
    o.max_steps = MAX_STEPS;
    o.earth = earth;
    o.max_length = Some(4.0 * distance);
    let plane = TargetPlane {
        point: origin + V3::new(0.0, 0.0, distance),
        normal: V3::new(0.0, 0.0, 1.0),
    };
    let t = trace::<f64, _>(field, origin, direction, Some(&plane), &o, None);
    assert!(
        t.endpoint.is_finite() && t.direction.is_finite() && t.arc_length.is_finite(),
        "ray from {origin:?} along {direction:?} over {earth:?} by {method:?} through {medium:?}: {t:?}"
    );
}
