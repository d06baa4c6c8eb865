//! Hot-spot culling (`docs/model.md`, "Culling"): a culled field equals the
//! unculled sum within the stated bounds, for δ, ∇δ and their parameter
//! derivatives (dual numbers), and rays traced through it (scalar tracer and
//! lanes kernel) end where unculled rays end.

use mirage::math::V3;
use mirage::medium::cull::CULL_UNITS;
use mirage::medium::{
    Background, C_SCALE, HotSpot, IndexField, Inversion, LogisticField, LogisticMedium,
};
use mirage::trace::batch::{BatchOptions, Isa, RayJob, trace_batch_3d};
use mirage::trace::{Method, TargetPlane, Trace, TraceOptions, trace};
use num_dual::Dual64;
use proptest::prelude::*;

/// e^(−40): the largest rim weight of a term left out.
fn w_max() -> f64 {
    (-CULL_UNITS).exp()
}

/// A hot spot's parameters, drawn from `u` (eight numbers in [0, 1)).
fn spot(u: &[f64], half_width: f64) -> HotSpot {
    HotSpot {
        x: half_width * (2.0 * u[0] - 1.0),
        z: half_width * (2.0 * u[1] - 1.0),
        radius: 80.0 * u[2],
        n: 6.0 * u[3] - 3.0,
        // |a| from 0.2 to 5 m, either sign.
        a: (0.2 + 4.8 * u[4]) * if u[5] < 0.5 { -1.0 } else { 1.0 },
        // Rims from 0.1 /m (a reach of R + 400 m) to 20 /m.
        edge: 0.1 * 200f64.powf(u[6]),
    }
}

prop_compose! {
    /// A medium of 2–300 hot spots scattered over a square of 2–8 km, with
    /// or without layers.
    fn scattered_medium()(
        count in 2usize..300,
        half_width in 1000.0f64..4000.0,
        scale in 0.05f64..2.0,
        layers in 0u8..3,
        seeds in prop::collection::vec(0.0f64..1.0, 300 * 8),
    ) -> LogisticMedium {
        LogisticMedium {
            scale,
            background: (layers > 0).then_some(Background { n: 1.0, a: 40.0 }),
            inversion: (layers > 1).then_some(Inversion { n: 0.3, a: 2.0, height: 25.0 }),
            hotspots: seeds.chunks(8).take(count).map(|u| spot(u, half_width)).collect(),
        }
    }
}

/// The points to compare at: anywhere over the square, and on and around
/// the hot spots' rims and reach circles (where culling starts).
fn probes(m: &LogisticMedium, u: &[f64]) -> Vec<V3> {
    let span = m
        .hotspots
        .iter()
        .map(|h| h.x.abs().max(h.z.abs()))
        .fold(0.0, f64::max)
        + 100.0;
    let mut out = Vec::new();
    for (k, c) in u.chunks(4).enumerate() {
        let y = -2.0 + 30.0 * c[3];
        let p = if k % 2 == 0 {
            V3::new(span * (2.0 * c[0] - 1.0), y, span * (2.0 * c[1] - 1.0))
        } else {
            let h = &m.hotspots[(c[0] * m.hotspots.len() as f64) as usize % m.hotspots.len()];
            // Between the rim and a little past the reach.
            let r = h.radius + (CULL_UNITS + 2.0) / h.edge * c[2];
            let angle = std::f64::consts::TAU * c[1];
            V3::new(h.x + r * angle.cos(), y, h.z + r * angle.sin())
        };
        out.push(p);
    }
    out
}

/// k = C·|k_s| and the normalised amplitudes |A_j| = k·|n_j|/S.
fn amplitudes(m: &LogisticMedium) -> (f64, Vec<f64>) {
    let k = C_SCALE * m.scale.abs();
    let s = m.amplitude_sum();
    (k, m.hotspots.iter().map(|h| k * h.n.abs() / s).collect())
}

/// Max of the rates a derivative of term j can carry (e, 1/e, 1/|a|, 1).
fn rate(h: &HotSpot) -> f64 {
    h.edge.max(1.0 / h.edge).max(1.0 / h.a.abs()).max(1.0)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// δ and ∇δ: the terms left out sum to at most k·e^(−40) (δ) and
    /// Σ|A_j|·e_j·e^(−40) + Σ|A_j|·e^(−40)/(4|a_j|) (∇δ), plus the
    /// rounding of sums of at most k (δ) and of the gradient bound (∇δ).
    #[test]
    fn delta_and_gradient_equal_the_unculled_sum(
        m in scattered_medium(),
        u in prop::collection::vec(0.0f64..1.0, 400 * 4),
    ) {
        let culled = m.field();
        // Too crowded to pay: nothing would be culled; draw another.
        prop_assume!(culled.grid().is_some());
        let grid = culled.grid().unwrap();
        prop_assert!(grid.longest() <= m.hotspots.len());
        let unculled = culled.clone().unculled();
        let (k, amps) = amplitudes(&m);
        let g_scale: f64 = m.hotspots.iter().zip(&amps)
            .map(|(h, a)| a * (h.edge + 0.25 / h.a.abs()))
            .sum::<f64>() + k / 40.0 + k / 2.0;
        let eps = f64::EPSILON;
        for p in probes(&m, &u) {
            let (d0, g0) = unculled.delta_gradient(p);
            let (d1, g1) = culled.delta_gradient(p);
            let tol_d = k * w_max() + 8.0 * eps * k;
            prop_assert!((d1 - d0).abs() <= tol_d, "δ at {p:?}: {d1:e} against {d0:e}");
            let tol_g = g_scale * (w_max() + 8.0 * eps);
            for (a, b) in [(g1.x, g0.x), (g1.y, g0.y), (g1.z, g0.z)] {
                prop_assert!((a - b).abs() <= tol_g, "∇δ at {p:?}: {g1:?} against {g0:?}");
            }
        }
    }

    /// The parameter derivatives that the exact Jacobians carry: δ and ∇δ
    /// with one parameter seeded as a dual number, culled against unculled,
    /// within (1 + 40)·e^(−40) times the terms' scale, plus rounding.
    #[test]
    fn parameter_derivatives_equal_the_unculled_ones(
        m in scattered_medium(),
        u in prop::collection::vec(0.0f64..1.0, 40 * 4),
        pick in 0.0f64..1.0,
    ) {
        prop_assume!(m.field().grid().is_some());
        let params = m.params();
        let (seeded, _) = params[((pick * params.len() as f64) as usize).min(params.len() - 1)];
        let dual = m.map(|p, v| if p == seeded { Dual64::new(v, 1.0) } else { Dual64::from_re(v) });
        let culled = LogisticField::<Dual64>::new(&dual);
        prop_assert!(culled.grid().is_some());
        let unculled = culled.clone().unculled();
        let (k, amps) = amplitudes(&m);
        let s = m.amplitude_sum();
        // Every term's derivative scale: |A_j| (and |∂A_j/∂θ| ≤ |A_j|/|k_s|
        // + 2k/S) times two of its rates.
        let scale: f64 = m.hotspots.iter().zip(&amps)
            .map(|(h, a)| (a * (1.0 + 1.0 / m.scale.abs()) + 2.0 * k / s) * rate(h).powi(2))
            .sum::<f64>() + k * (1.0 + 1.0 / m.scale.abs());
        let tol = scale * ((1.0 + CULL_UNITS) * w_max() + 64.0 * f64::EPSILON);
        for p in probes(&m, &u) {
            let q = V3::new(Dual64::from_re(p.x), Dual64::from_re(p.y), Dual64::from_re(p.z));
            let (d0, g0) = unculled.delta_gradient(q);
            let (d1, g1) = culled.delta_gradient(q);
            for (a, b, what) in [
                (d1, d0, "δ"), (g1.x, g0.x, "∂x δ"), (g1.y, g0.y, "∂y δ"), (g1.z, g0.z, "∂z δ"),
            ] {
                prop_assert!((a.re - b.re).abs() <= tol, "{what} at {p:?}");
                prop_assert!(
                    (a.eps - b.eps).abs() <= tol,
                    "∂/∂{seeded} of {what} at {p:?}: {:e} against {:e} (tolerance {tol:e})",
                    a.eps, b.eps
                );
            }
        }
    }
}

/// A desert of 400 patches over 4 km × 5 km (radius 10–60 m, rims of 0.5–4
/// /m) on a background and an inversion, seeded by `seed`.
fn desert(seed: u64) -> LogisticMedium {
    let mut s = seed;
    let mut next = move || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    LogisticMedium {
        scale: 1.3,
        background: Some(Background { n: 1.0, a: 40.0 }),
        inversion: Some(Inversion {
            n: 0.3,
            a: 2.0,
            height: 25.0,
        }),
        hotspots: (0..400)
            .map(|_| HotSpot {
                x: -2000.0 + 4000.0 * next(),
                z: -1000.0 + 5000.0 * next(),
                radius: 10.0 + 50.0 * next(),
                n: -1.0 - 40.0 * next(),
                a: -0.3 - next(),
                edge: 0.5 + 3.5 * next(),
            })
            .collect(),
    }
}

/// Mirage-like rays from 1–3 m up, 0.5–1.5 km, within a few tenths of a
/// degree of the horizon.
fn rays(u: &[f64]) -> Vec<RayJob> {
    u.chunks(4)
        .map(|c| {
            let origin = V3::new(-500.0 + 1000.0 * c[0], 1.0 + 2.0 * c[1], -200.0);
            let azimuth = (-20.0 + 40.0 * c[2]).to_radians();
            let elevation = (-0.3 + 0.4 * c[3]).to_radians();
            let direction = V3::new(
                azimuth.sin() * elevation.cos(),
                elevation.sin(),
                azimuth.cos() * elevation.cos(),
            );
            let target = origin + direction * (500.0 + 1000.0 * c[3]);
            let normal = V3::new(direction.x, 0.0, direction.z).normalized();
            RayJob {
                origin,
                direction,
                target: TargetPlane {
                    point: target,
                    normal,
                },
            }
        })
        .collect()
}

fn scalar(field: &LogisticField, jobs: &[RayJob], options: &TraceOptions) -> Vec<Trace> {
    jobs.iter()
        .map(|j| trace::<f64, _>(field, j.origin, j.direction, Some(&j.target), options, None))
        .collect()
}

fn assert_same_ends(a: &[Trace], b: &[Trace], what: &str) {
    for (i, (a, b)) in a.iter().zip(b).enumerate() {
        let d = (a.endpoint - b.endpoint).norm();
        assert!(
            d <= 1e-9,
            "{what}, ray {i}: endpoints {:?} and {:?} differ by {d:e} m",
            a.endpoint,
            b.endpoint
        );
        assert_eq!(
            (a.end, a.occluded, a.unreachable),
            (b.end, b.occluded, b.unreachable),
            "{what}, ray {i}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4))]

    /// Ray endpoints through a culled desert: the scalar tracer and the
    /// lanes kernel (every instruction set this CPU has), culled, against the
    /// unculled scalar tracer, all within 10⁻⁹ m (the lanes' own agreement
    /// with the scalar tracer, `tests/fast_paths.rs`). The unculled lanes are
    /// the same kernel with a list of every spot at every step; the unculled
    /// scalar sum is the reference, so comparing them too would only double
    /// the test's time (CI's budget).
    #[test]
    fn ray_endpoints_equal_unculled_ones(
        seed in 0u64..1_000_000,
        u in prop::collection::vec(0.0f64..1.0, 20 * 4),
    ) {
        let m = desert(seed);
        let culled = m.field();
        let grid = culled.grid().expect("a desert of patches is culled");
        prop_assert!(grid.longest() < m.hotspots.len() / 4);
        let unculled = culled.clone().unculled();
        let jobs = rays(&u);
        let options = TraceOptions::new(Method::Rk4 { step: 2.0 });
        let reference = scalar(&unculled, &jobs, &options);
        assert_same_ends(&scalar(&culled, &jobs, &options), &reference, "scalar culled");
        let batch = BatchOptions::from_trace_options(&options);
        for isa in Isa::available() {
            // 20 rays: the 16-lane kernel; 5: the 8-lane one.
            for jobs in [&jobs[..], &jobs[..5]] {
                let mut out = reference[..jobs.len()].to_vec();
                trace_batch_3d(isa, &culled, jobs, &batch, &mut out);
                assert_same_ends(&out, &reference[..jobs.len()], isa.name());
            }
        }
    }
}

/// Culling does cull: at a point of the desert far from most patches only a
/// few are listed, and those left out are beyond their reach.
#[test]
fn a_point_pays_for_the_hot_spots_in_reach_only() {
    let m = desert(1);
    let field = m.field();
    let grid = field.grid().expect("culled");
    let mut listed = 0usize;
    let points = 2000;
    let mut s = 9u64;
    for _ in 0..points {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let x = -2000.0 + 4000.0 * ((s >> 11) as f64 / (1u64 << 53) as f64);
        let z = -1000.0 + 5000.0 * ((s >> 20) as f64 / (1u64 << 44) as f64);
        let list = grid.candidates(x, z);
        listed += list.len();
        for (j, h) in m.hotspots.iter().enumerate() {
            let t = h.edge * ((x - h.x).hypot(z - h.z) - h.radius);
            if !list.contains(&(j as u32)) {
                assert!(t > CULL_UNITS, "hot spot {j} left out at t = {t}");
            }
        }
    }
    let mean = listed as f64 / points as f64;
    assert!(mean < 5.0, "{mean} hot spots per point of 400");
}
