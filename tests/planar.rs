//! The planar stepper against the 3-D one.
//!
//! In a stratified medium (δ a function of the height alone) the general
//! tracer steps only the vertical part of the ray (`trace/stepper.rs`,
//! `Stepper::attempt_planar`) and advances x and z by the constant v_x, v_z.
//! That is meant to be the 3-D step's own arithmetic on the components that
//! change, so the results must be the 3-D tracer's bit for bit: endpoints,
//! directions, arc lengths, ends, flags and statistics, for RK4 and
//! Dormand–Prince, for every stratified kind (logistic, linear n², real air
//! with Gladstone–Dale, Ciddor and a table), for rays in any azimuth, for dual
//! numbers (the fit's Jacobians) as for plain ones.
//!
//! The 3-D path is reached by hiding the field's stratification behind a
//! wrapper that forwards δ and ∇δ but answers `is_stratified() == false`.

use mirage::math::{Real, V3};
use mirage::medium::analytic::LinearSquare;
use mirage::medium::{Field, IndexField, Medium};
use mirage::trace::{GroundMode, Method, TargetPlane, Trace, TraceOptions, trace};
use num_dual::{DualSVec64, DualStruct};

/// A field seen as not stratified: the tracer takes its 3-D path.
struct ThreeD<'a, F: ?Sized>(&'a F);

impl<T: Real, F: IndexField<T> + ?Sized> IndexField<T> for ThreeD<'_, F> {
    fn delta_gradient(&self, p: V3<T>) -> (T, V3<T>) {
        self.0.delta_gradient(p)
    }
    fn ceiling(&self) -> f64 {
        self.0.ceiling()
    }
    fn step_limit(&self, y: f64, vy: f64) -> f64 {
        self.0.step_limit(y, vy)
    }
}

fn medium(json: &str) -> Medium {
    serde_json::from_str(json).expect("a valid medium")
}

/// Stratified media of every kind.
fn media() -> Vec<(&'static str, Medium)> {
    vec![
        (
            "logistic background and inversion",
            medium(
                r#"{"scale": 0.015, "background": {"n": 1.0, "a": 300.0},
                    "inversion": {"n": 0.9, "a": 2.0, "height": 6.0}}"#,
            ),
        ),
        (
            "the Wigner water air (Gladstone–Dale, constant pressure)",
            medium(
                r#"{"air": {"temperature": {"base": 10.033,
                      "exponential": {"delta": 3.15, "scale_height": 0.04975}},
                    "pressure": 101325.0, "hydrostatic": false,
                    "refractivity": {"gladstone_dale": 0.079386}}}"#,
            ),
        ),
        (
            "a cold sea in Ciddor air (hydrostatic, humid)",
            medium(
                r#"{"air": {"temperature": {"base": 12.0, "lapse": -0.0065,
                      "inversion": {"delta": 6.0, "height": 12.0, "thickness": 1.5}},
                    "humidity": 0.8}}"#,
            ),
        ),
        (
            "a measured table",
            medium(
                r#"{"air": {"temperature": {"table": [[0.0, 30.0], [0.5, 24.0],
                      [2.0, 21.0], [10.0, 20.0], [100.0, 19.5]]}}}"#,
            ),
        ),
    ]
}

/// Rays from low observers, in several azimuths, grazing and steeper, up and
/// down, some of which reach the ground before their plane.
fn rays() -> Vec<(V3, V3, TargetPlane)> {
    let mut out = Vec::new();
    for (k, azimuth) in [0.0_f64, 0.4, 1.3, 2.9, -2.2].into_iter().enumerate() {
        for elevation_deg in [-0.9, -0.3, -0.05, 0.02, 0.4] {
            let e = f64::to_radians(elevation_deg);
            let d = V3::new(e.cos() * azimuth.sin(), e.sin(), e.cos() * azimuth.cos());
            let origin = V3::new(3.0 * k as f64, 1.7 + 0.5 * k as f64, -2.0);
            let distance = 400.0 + 150.0 * k as f64;
            let horizontal = V3::new(d.x, 0.0, d.z).normalized();
            let target = TargetPlane {
                point: origin + horizontal.scale(distance),
                normal: horizontal,
            };
            out.push((origin, d, target));
        }
    }
    out
}

fn methods() -> Vec<TraceOptions> {
    let mut out = Vec::new();
    for method in [
        Method::Rk4 { step: 1.5 },
        Method::Dopri5 { tolerance: 1e-9 },
        Method::Dopri5 { tolerance: 1e-5 },
    ] {
        for ground in [GroundMode::Stop, GroundMode::Flag] {
            let mut o = TraceOptions::new(method);
            o.ground = ground;
            out.push(o);
        }
    }
    out
}

fn same<T: Real + PartialEq + std::fmt::Debug>(a: &Trace<T>, b: &Trace<T>, what: &str) {
    assert_eq!(a.endpoint, b.endpoint, "{what}: endpoint");
    assert_eq!(a.direction, b.direction, "{what}: direction");
    assert_eq!(
        a.arc_length.to_bits(),
        b.arc_length.to_bits(),
        "{what}: arc length"
    );
    assert_eq!(a.end, b.end, "{what}: end");
    assert_eq!(a.occluded, b.occluded, "{what}: occluded");
    assert_eq!(a.unreachable, b.unreachable, "{what}: unreachable");
    assert_eq!(a.stats, b.stats, "{what}: statistics");
}

#[test]
fn the_planar_stepper_gives_the_3d_steps_bit_for_bit() {
    let mut compared = 0;
    let mut fields: Vec<(&str, Field)> = media()
        .into_iter()
        .map(|(name, m)| (name, m.field()))
        .collect();
    fields.push((
        "linear n²",
        Field::LinearSquare(LinearSquare {
            n0: 1.0003,
            g: -2.0e-5,
        }),
    ));
    for (name, field) in fields {
        assert!(
            IndexField::<f64>::is_stratified(&field),
            "{name} is stratified"
        );
        for options in methods() {
            for (i, (origin, d, target)) in rays().into_iter().enumerate() {
                let planar = trace::<f64, _>(&field, origin, d, Some(&target), &options, None);
                let full =
                    trace::<f64, _>(&ThreeD(&field), origin, d, Some(&target), &options, None);
                same(&planar, &full, &format!("{name}, ray {i}, {options:?}"));
                compared += 1;
            }
        }
    }
    assert_eq!(compared, 5 * 6 * 25);
}

#[test]
fn dual_numbers_take_the_same_planar_steps() {
    type D = DualSVec64<2>;
    for (name, m) in media() {
        // Seed the first two parameters of each medium.
        let params: Vec<_> = m.params().into_iter().map(|(p, _)| p).collect();
        let seeded: Medium<D> = m.map(|p, v| match params.iter().position(|q| *q == p) {
            Some(k) if k < 2 => D::from_re(v).derivative(k),
            _ => D::from_re(v),
        });
        let field = seeded.field();
        for options in methods() {
            for (i, (origin, d, target)) in rays().into_iter().enumerate().step_by(3) {
                let planar = trace::<D, _>(&field, origin, d, Some(&target), &options, None);
                let full = trace::<D, _>(&ThreeD(&field), origin, d, Some(&target), &options, None);
                let what = format!("{name}, ray {i}, {options:?}");
                same(&planar, &full, &what);
                // The derivative parts too, not only the values.
                for (a, b) in [
                    (planar.endpoint.x, full.endpoint.x),
                    (planar.endpoint.y, full.endpoint.y),
                    (planar.endpoint.z, full.endpoint.z),
                ] {
                    assert_eq!(a.re(), b.re(), "{what}");
                    assert_eq!(a.eps, b.eps, "{what}: derivatives");
                }
            }
        }
    }
}
