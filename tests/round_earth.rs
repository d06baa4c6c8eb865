//! The round earth (`docs/air.md`): straight rays over the sphere land where
//! geometry says and are occluded exactly when the line meets the sphere
//! first; a stratified medium over the sphere gives the rays of the exactly
//! transformed flat problem (the earth-flattening transformation, a conformal
//! map); a superior mirage 8 km out, made on the sphere, is fitted back to its
//! true inversion over the sphere and not over the flat ground; the flat
//! ground's traces are what they always were.

use mirage::fit::objective::Objective;
use mirage::fit::solve::solve;
use mirage::fit::synthetic::retarget;
use mirage::math::V3;
use mirage::medium::{Background, IndexField, Inversion, LogisticMedium, Medium, Param};
use mirage::pair::PointPair;
use mirage::problem::{SolverSpec, solver_settings};
use mirage::trace::{Earth, End, Method, TargetPlane, TraceOptions, trace};
use std::path::Path;

const R: f64 = 6_371_000.0;

fn on(earth: Earth, tolerance: f64) -> TraceOptions {
    TraceOptions {
        earth,
        ..TraceOptions::new(Method::Dopri5 { tolerance })
    }
}

/// The first t > 0 where the line o + t·d (|d| = 1) meets the sphere of
/// radius `r` centred at (0, −r, 0), if it does.
fn line_meets_sphere(o: V3, d: V3, r: f64) -> Option<f64> {
    let q = o - V3::new(0.0, -r, 0.0);
    let b = q.dot(d);
    // |q|² − r², without cancellation (as `Earth::height` forms it).
    let c = o.x * o.x + o.z * o.z + o.y * (o.y + 2.0 * r);
    let disc = b * b - c;
    if disc < 0.0 {
        return None;
    }
    let t = -b - disc.sqrt();
    (t > 0.0).then_some(t)
}

#[test]
fn straight_rays_over_the_sphere_land_where_geometry_says() {
    // δ ≡ 0: every ray is a straight line. Its endpoint is the line's
    // crossing of the target plane, and it is occluded exactly when the line
    // meets the sphere before that plane.
    let vacuum = Medium::Logistic(LogisticMedium::vacuum()).field();
    for radius in [R, 20_000.0] {
        let earth = Earth::Round { radius };
        // The dip of the horizon from the highest observer: rays below it
        // meet the sphere, rays above it clear it.
        let dip = (2.0 * 30.0 / radius).sqrt();
        let (mut occluded, mut clear, mut worst) = (0, 0, 0.0f64);
        for k in 0..400 {
            let f = k as f64 / 400.0;
            let azimuth = (-40.0 + 80.0 * f).to_radians();
            let distance = 1000.0 + 7000.0 * ((7 * k) % 17) as f64 / 16.0;
            let elevation = dip * (-1.5 + 2.0 * ((11 * k) % 13) as f64 / 12.0);
            let origin = V3::new(0.0, [2.0, 6.0, 30.0][k % 3], 0.0);
            let d = V3::new(
                azimuth.sin() * elevation.cos(),
                elevation.sin(),
                azimuth.cos() * elevation.cos(),
            );
            let pair = PointPair {
                origin: origin.to_array(),
                through: (origin + d * distance).to_array(),
                target: (origin + d * distance + V3::new(0.0, 3.0, 0.0)).to_array(),
                weight: 1.0,
                wavelength: None,
            };
            let plane: TargetPlane = pair.plane_on(earth);
            let to_plane = (plane.point - origin).dot(plane.normal) / d.dot(plane.normal);
            let exact = origin + d * to_plane;
            let hits = line_meets_sphere(origin, d, radius).filter(|&t| t < to_plane);
            // Lines that touch the sphere within a micrometre are left out:
            // which side they fall on is rounding.
            let lowest = {
                let q = origin - V3::new(0.0, -radius, 0.0);
                let t = (-q.dot(d)).clamp(0.0, to_plane);
                earth.height(origin + d * t)
            };
            if lowest.abs() < 1e-6 {
                continue;
            }
            let (t, _) = pair.evaluate::<f64, _>(&vacuum, &on(earth, 1e-9), None);
            assert_eq!(t.end, End::Plane);
            assert_eq!(
                t.occluded,
                hits.is_some(),
                "ray {k}: lowest height {lowest} m"
            );
            if t.occluded {
                occluded += 1;
            } else {
                clear += 1;
            }
            worst = worst.max((t.endpoint - exact).norm());
        }
        eprintln!(
            "radius {radius} m: {occluded} occluded, {clear} clear, worst endpoint {worst:.2e} m"
        );
        assert!(worst < 1e-6, "straight rays {worst} m off the line");
        assert!(occluded > 20 && clear > 20);
    }
}

/// A stratified medium given by δ(h), evaluated at the height `y` of a flat
/// problem (δ of `field` at (0, y, 0)).
fn profile(field: &impl IndexField, h: f64) -> (f64, f64) {
    let (d, g) = field.delta_gradient(V3::new(0.0, h, 0.0));
    (d, g.y)
}

/// The flat problem that is the sphere's under the conformal map
/// X = R·φ, Y = R·ln(r/R) of the ray's vertical plane: its index is
/// n(h)·r/R with r = R·e^(Y/R), h = r − R (rays are the same curves, mapped).
struct Flattened<'a, F> {
    field: &'a F,
    radius: f64,
}

impl<F: IndexField> IndexField for Flattened<'_, F> {
    fn delta_gradient(&self, p: V3) -> (f64, V3) {
        let e = (p.y / self.radius).exp();
        let h = self.radius * (p.y / self.radius).exp_m1();
        let (d, dd) = profile(self.field, h);
        let n = (1.0 + d) * e;
        let dn = dd * e * e + (1.0 + d) * e / self.radius;
        (n - 1.0, V3::new(0.0, dn, 0.0))
    }
    fn is_stratified(&self) -> bool {
        true
    }
}

#[test]
fn a_stratified_medium_over_the_sphere_is_the_flattened_flat_problem() {
    // A small earth (20 km) so that the curvature is large, and air with a
    // surface layer and an inversion.
    let radius = 20_000.0;
    let medium: Medium = serde_json::from_str(
        r#"{"air": {"temperature": {"base": 10.0, "lapse": -0.0065,
              "exponential": {"delta": 8.0, "scale_height": 0.8},
              "inversion": {"delta": 10.0, "height": 15.0, "thickness": 3.0}},
            "refractivity": {"gladstone_dale": 0.0787}}}"#,
    )
    .unwrap();
    let field = medium.field();
    let flat = Flattened {
        field: &field,
        radius,
    };
    let sphere = on(Earth::Round { radius }, 1e-12);
    let plane_options = on(Earth::Flat, 1e-12);
    let mut worst = 0.0f64;
    for k in 0..24 {
        let h0 = [2.0, 8.0, 14.0][k % 3];
        let elevation = (-0.25 + 0.5 * (k / 3) as f64 / 7.0).to_radians();
        let phi = 2500.0 / radius;
        // On the sphere: in the plane x = 0, to the radial plane at angle φ.
        let d = V3::new(0.0, elevation.sin(), elevation.cos());
        let normal = V3::new(0.0, -phi.sin(), phi.cos());
        let target = TargetPlane {
            point: V3::new(0.0, -radius, 0.0),
            normal,
        };
        let o = V3::new(0.0, h0, 0.0);
        let s = trace::<f64, _>(&field, o, d, Some(&target), &sphere, None);
        // Flat: X = R·φ, Y = R·ln(r/R); the same elevation (the map is
        // conformal).
        let y0 = radius * ((radius + h0) / radius).ln();
        let flat_target = TargetPlane {
            point: V3::new(0.0, 0.0, radius * phi),
            normal: V3::new(0.0, 0.0, 1.0),
        };
        let f = trace::<f64, _>(
            &flat,
            V3::new(0.0, y0, 0.0),
            d,
            Some(&flat_target),
            &plane_options,
            None,
        );
        if s.end != End::Plane || f.end != End::Plane {
            panic!("ray {k}: sphere {:?}, flat {:?}", s.end, f.end);
        }
        let h_sphere = Earth::Round { radius }.height(s.endpoint);
        let h_flat = radius * (f.endpoint.y / radius).exp_m1();
        assert_eq!(s.occluded, f.occluded, "ray {k}");
        worst = worst.max((h_sphere - h_flat).abs());
    }
    eprintln!("sphere against the flattened flat problem: worst height {worst:.2e} m");
    assert!(worst < 1e-7, "{worst} m");
}

fn cold_sea() -> LogisticMedium {
    LogisticMedium {
        scale: 0.015,
        background: Some(Background { n: 1.0, a: 300.0 }),
        inversion: Some(Inversion {
            n: 0.9,
            a: 2.0,
            height: 12.0,
        }),
        hotspots: vec![],
    }
}

/// A harbour wall 6 m up looking at ships 6–8 km out, 0.02–0.12° up.
fn ships() -> Vec<PointPair> {
    let mut pairs = Vec::new();
    for (k, (azimuth, distance)) in [
        (0.0f64, 8000.0),
        (5.0, 7000.0),
        (-3.0, 6000.0),
        (8.0, 7500.0),
    ]
    .into_iter()
    .enumerate()
    {
        for elevation in [0.02f64, 0.05, 0.08, 0.12] {
            let (a, e) = (
                azimuth.to_radians(),
                (elevation + 0.003 * k as f64).to_radians(),
            );
            let through = [
                distance * a.sin(),
                6.0 + distance * e.tan(),
                distance * a.cos(),
            ];
            pairs.push(PointPair {
                origin: [0.0, 6.0, 0.0],
                through,
                target: through,
                weight: 1.0,
                wavelength: None,
            });
        }
    }
    pairs
}

#[test]
fn a_superior_mirage_8_km_out_is_fitted_on_the_sphere_and_not_on_the_plane() {
    let earth = Earth::Round { radius: R };
    let truth = cold_sea();
    let (pairs, failed) = retarget(&ships(), &truth.field(), &on(earth, 1e-10));
    assert!(failed.is_empty(), "every ray reaches its ship: {failed:?}");
    let free = vec![Param::InversionHeight, Param::InversionA, Param::InversionN];
    let mut start = truth.clone();
    start.inversion = Some(Inversion {
        n: 1.3,
        a: 3.0,
        height: 9.0,
    });
    let settings = solver_settings(
        &SolverSpec {
            method: "auto".into(),
            max_iterations: Some(300),
            ..Default::default()
        },
        Path::new("test"),
    )
    .unwrap();
    let bounds = vec![(2.0, 60.0), (0.1, 20.0), (0.05, 5.0)];
    let fit = |earth: Earth| {
        let obj = Objective::new(start.clone(), free.clone(), pairs.clone(), on(earth, 1e-10));
        solve(&obj, &settings, &bounds, 1e-14, None).unwrap()
    };
    let round = fit(earth);
    let height = round.x[0];
    eprintln!(
        "over the sphere: inversion at {height} m (truth 12), F = {:.2e}",
        round.objective
    );
    for (v, t) in round.x.iter().zip([12.0, 2.0, 0.9]) {
        assert!(((v - t) / t).abs() < 1e-4, "fitted {v}, truth {t}");
    }
    let flat = fit(Earth::Flat);
    eprintln!(
        "over the flat ground: inversion at {} m, a {}, n {}; F = {:.2e}",
        flat.x[0], flat.x[1], flat.x[2], flat.objective
    );
    // The flat ground cannot explain pairs made on the sphere.
    assert!(flat.objective > 1e6 * round.objective.max(1e-20));
}

#[test]
fn the_flat_ground_traces_as_before() {
    // `Earth::Flat` is the default, and the origin-plane fields of a pair
    // are the ones the flat ground always had.
    let pair = PointPair {
        origin: [1.0, 2.0, 3.0],
        through: [40.0, 2.5, 900.0],
        target: [41.0, 1.0, 910.0],
        weight: 1.0,
        wavelength: None,
    };
    assert_eq!(pair.plane(), pair.plane_on(Earth::Flat));
    assert_eq!(
        TraceOptions::new(Method::Rk4 { step: 1.0 }).earth,
        Earth::Flat
    );
    let field = cold_sea().field();
    let a = pair
        .evaluate::<f64, _>(&field, &on(Earth::Flat, 1e-9), None)
        .0;
    let options = TraceOptions::new(Method::Dopri5 { tolerance: 1e-9 });
    let b = trace::<f64, _>(
        &field,
        pair.origin(),
        pair.direction(),
        Some(&pair.plane()),
        &options,
        None,
    );
    assert_eq!(a.endpoint, b.endpoint);
    assert_eq!(a.stats, b.stats);
}
