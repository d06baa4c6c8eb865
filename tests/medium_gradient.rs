//! The logistic medium: analytic gradient against finite differences, the model's
//! structural rules, and no NaN or inf anywhere for extreme but finite input.

use mirage::math::V3;
use mirage::medium::{Background, HotSpot, IndexField, Inversion, LogisticMedium, Param};
use mirage::trace::{Method, TargetPlane, TraceOptions, trace};
use proptest::prelude::*;

fn full_medium() -> LogisticMedium {
    LogisticMedium {
        scale: 1.3,
        background: Some(Background { n: 1.0, a: 40.0 }),
        inversion: Some(Inversion {
            n: 0.3,
            a: 2.0,
            height: 25.0,
        }),
        hotspots: vec![
            HotSpot {
                x: 0.0,
                z: 600.0,
                radius: 120.0,
                n: -2.0,
                a: -0.4,
                edge: 10.0,
            },
            HotSpot {
                x: 30.0,
                z: 200.0,
                radius: 0.0,
                n: 0.7,
                a: 1.5,
                edge: 0.5,
            },
        ],
    }
}

fn central_difference(field: &impl IndexField, p: V3, h: f64) -> V3 {
    let d = |e: V3| (field.delta(p + e * h) - field.delta(p - e * h)) / (2.0 * h);
    V3::new(
        d(V3::new(1.0, 0.0, 0.0)),
        d(V3::new(0.0, 1.0, 0.0)),
        d(V3::new(0.0, 0.0, 1.0)),
    )
}

/// Points where the model changes fastest: hot-spot centres, rims, layer heights.
fn probe_points() -> Vec<V3> {
    let mut pts = vec![
        V3::new(0.0, 0.7, 600.0),   // hot spot 0 centre
        V3::new(30.0, 1.0, 200.0),  // hot spot 1 centre (radius 0: a cone tip)
        V3::new(120.0, 0.3, 600.0), // on the rim
        V3::new(0.0, 0.3, 480.05),  // just inside the rim
        V3::new(84.9, -0.2, 684.9), // rim, diagonal, below ground
        V3::new(5.0, 25.0, 100.0),  // inversion height
        V3::new(5.0, 23.0, 700.0),  // inversion flank
        V3::new(-40.0, 0.0, 0.0),   // ground level
        V3::new(2.0, 60.0, 1500.0), // high up
    ];
    // A deterministic scatter over the scene (a simple LCG: no test randomness).
    let mut s = 12345u64;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    for _ in 0..200 {
        pts.push(V3::new(
            -200.0 + 400.0 * next(),
            -3.0 + 40.0 * next(),
            -100.0 + 900.0 * next(),
        ));
    }
    pts
}

#[test]
fn gradient_matches_central_differences() {
    let field = full_medium().field();
    let mut worst = 0.0f64;
    for p in probe_points() {
        let (_, g) = field.delta_gradient(p);
        let fd = central_difference(&field, p, 1e-5);
        // Relative to the gradient's size; an absolute floor for components that
        // are zero by symmetry (centres, far from rims).
        let err = (fd - g).norm() / g.norm().max(1e-7);
        worst = worst.max(err);
        assert!(
            err < 1e-6,
            "at {p:?}: analytic {g:?}, finite differences {fd:?}"
        );
    }
    eprintln!("worst relative gradient error {worst:e}");
}

#[test]
fn an_absent_term_has_no_parameters_and_no_part_in_s() {
    let mut m = full_medium();
    m.inversion = None;
    assert!(m.get(Param::InversionHeight).is_none());
    assert!(m.set(Param::InversionN, 1.0).is_err());
    assert!(
        !m.params()
            .iter()
            .any(|(p, _)| matches!(p, Param::InversionN))
    );
    // S = |1| + |−2| + |0.7| without the inversion's 0.3.
    assert_eq!(m.amplitude_sum(), 3.7);
    // Background only: δ is exactly C·|k|·σ(y/a) since n_bg/S = 1.
    let bg = LogisticMedium {
        scale: 2.0,
        background: Some(Background { n: 5.0, a: 10.0 }),
        inversion: None,
        hotspots: vec![],
    };
    let y: f64 = 7.0;
    let expected = 0.003 * 2.0 / (1.0 + (-y / 10.0).exp());
    assert!((bg.field().delta(V3::new(0.0, y, 0.0)) - expected).abs() < 1e-18);
}

#[test]
fn amplitudes_have_a_gauge_freedom() {
    let m = full_medium();
    let scaled = m.map(|p, v| if p.is_amplitude() { 7.5 * v } else { v });
    for p in probe_points().into_iter().take(40) {
        let (a, ga) = m.field().delta_gradient(p);
        let (b, gb) = scaled.field().delta_gradient(p);
        assert!((a - b).abs() <= 1e-15 * a.abs().max(1e-6));
        assert!((ga - gb).norm() <= 1e-13 * ga.norm().max(1e-9));
    }
}

fn extreme_medium() -> impl Strategy<Value = LogisticMedium> {
    let rate = (prop::bool::ANY, -6.0f64..6.0).prop_map(|(neg, e)| {
        let a = 10f64.powf(e);
        if neg { -a } else { a }
    });
    let amp = (prop::bool::ANY, -3.0f64..300.0).prop_map(|(neg, e)| {
        let a = 10f64.powf(e);
        if neg { -a } else { a }
    });
    let hot = (
        -1e4f64..1e4,
        -1e4f64..1e4,
        prop_oneof![Just(0.0), 0.0f64..1e4],
        amp.clone(),
        rate.clone(),
        prop_oneof![Just(1e-6), 1e-3f64..1e3, Just(1e6)],
    )
        .prop_map(|(x, z, radius, n, a, edge)| HotSpot {
            x,
            z,
            radius,
            n,
            a,
            edge,
        });
    (
        -333.0f64..333.0,
        prop::option::of((amp.clone(), rate.clone())),
        prop::option::of((amp.clone(), rate.clone(), -1e4f64..1e4)),
        prop::collection::vec(hot, 0..3),
    )
        .prop_map(|(scale, bg, inv, hotspots)| LogisticMedium {
            scale,
            background: bg.map(|(n, a)| Background { n, a }),
            inversion: inv.map(|(n, a, height)| Inversion { n, a, height }),
            hotspots,
        })
}

fn point() -> impl Strategy<Value = V3> {
    let c = prop_oneof![-1e4f64..1e4, -10.0f64..10.0, Just(0.0), -1e300f64..1e300];
    (c.clone(), c.clone(), c).prop_map(|(x, y, z)| V3::new(x, y, z))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn delta_and_gradient_are_finite_for_extreme_parameters(m in extreme_medium(), p in point()) {
        prop_assume!(m.validate().is_ok());
        let field = m.field();
        let (d, g) = field.delta_gradient(p);
        prop_assert!(d.is_finite() && g.is_finite(), "δ = {d}, ∇δ = {g:?} at {p:?} for {m:?}");
        // |δ| ≤ C·|k_s| always holds: every σ and w lies in [0, 1] and Σ|n|/S = 1.
        prop_assert!(d.abs() <= 0.003 * m.scale.abs() * (1.0 + 1e-12));
        // The centre of each hot spot, exactly (the cone tip).
        for h in &m.hotspots {
            let (d, g) = field.delta_gradient(V3::new(h.x, p.y, h.z));
            prop_assert!(d.is_finite() && g.is_finite());
        }
    }

    #[test]
    fn traces_stay_finite_for_extreme_parameters(
        m in extreme_medium(),
        elevation in -0.2f64..0.2,
        adaptive in prop::bool::ANY,
    ) {
        prop_assume!(m.validate().is_ok());
        let field = m.field();
        let origin = V3::new(0.0, 1.6, 0.0);
        let dir = V3::new(0.0, elevation.tan(), 1.0).normalized();
        let plane = TargetPlane { point: V3::new(0.0, 0.0, 300.0), normal: V3::new(0.0, 0.0, 1.0) };
        let method = if adaptive { Method::Dopri5 { tolerance: 1e-6 } } else { Method::Rk4 { step: 2.0 } };
        let mut opts = TraceOptions::new(method);
        opts.max_steps = 20_000;
        let t = trace::<f64, _>(&field, origin, dir, Some(&plane), &opts, None);
        prop_assert!(t.endpoint.is_finite() && t.direction.is_finite() && t.arc_length.is_finite(),
            "{t:?} for {m:?}");
    }
}
