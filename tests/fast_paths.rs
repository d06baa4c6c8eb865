//! The batch tracers against the scalar tracer: the 3-D lanes kernel and the
//! stratified 2-D kernel must give the scalar tracer's endpoints (to 10⁻⁹ m),
//! flags, ends and statistics, with RK4 and with Dormand–Prince (each lane's
//! own adaptive steps), through the logistic model and real air, for every
//! instruction set this CPU runs; and the polynomial exponential they use
//! must be within its documented error.
//!
//! Run with `cargo test --release --test fast_paths -- --nocapture` to see the
//! largest differences.

use mirage::math::{SplitMix64, V3};
use mirage::medium::{
    Background, Field, HotSpot, IndexField, Inversion, LogisticField, LogisticMedium, Medium,
};
use mirage::trace::batch::{
    BatchOptions, Isa, LANES, NotStratified, RayJob, exp_in_place, trace_air_2d, trace_air_3d,
    trace_batch, trace_batch_2d, trace_batch_3d,
};
use mirage::trace::{End, GroundMode, Method, TargetPlane, Trace, TraceOptions, fastexp, trace};

/// Endpoints (and arc lengths) must agree to this, in metres.
const TOLERANCE: f64 = 1e-9;

/// A small deterministic generator (SplitMix64): the tests need reproducible
/// rays, not statistical quality.
struct Rng(u64);

impl Rng {
    /// Uniform in [a, b).
    fn uniform(&mut self, a: f64, b: f64) -> f64 {
        let mut g = SplitMix64(self.0);
        let u = g.next_f64();
        self.0 = g.0;
        a + (b - a) * u
    }
}

/// Writes to the process's stderr directly, past the test harness's capture,
/// so that the message is seen in a plain `cargo test`.
fn loud(message: &str) {
    use std::io::Write;
    let _ = writeln!(std::io::stderr(), "\n{message}\n");
}

/// The instruction sets this CPU runs. The builds of [`Isa::ALL`] that it
/// cannot run go untested here, and that is said loudly (once per run), so
/// that a pass on a CPU without, say, AVX-512 is not taken for a pass of the
/// AVX-512 kernels.
fn testable_isas() -> Vec<Isa> {
    static REPORTED: std::sync::Once = std::sync::Once::new();
    let untested: Vec<&str> = Isa::ALL
        .into_iter()
        .filter(|isa| !isa.is_available())
        .map(Isa::name)
        .collect();
    if !untested.is_empty() {
        REPORTED.call_once(|| {
            loud(&format!(
                "fast_paths: NOT TESTED on this CPU (it cannot run them): the {} build(s) of the batch kernels",
                untested.join(", ")
            ))
        });
    }
    Isa::available()
}

fn background() -> Background {
    Background { n: 1.0, a: 40.0 }
}

fn inversion() -> Inversion {
    Inversion {
        n: 0.3,
        a: 2.0,
        height: 25.0,
    }
}

fn hot_spot(rng: &mut Rng) -> HotSpot {
    HotSpot {
        x: rng.uniform(-300.0, 300.0),
        z: rng.uniform(100.0, 1500.0),
        radius: rng.uniform(0.0, 300.0),
        n: rng.uniform(-3.0, 1.0),
        a: rng.uniform(-1.5, -0.2),
        edge: rng.uniform(0.02, 10.0),
    }
}

/// The four media of the benchmarks: background only, background and
/// inversion, and the full medium with one and with eight hot spots. The
/// scale is large enough to bend rays visibly over a kilometre.
fn media() -> Vec<(&'static str, LogisticMedium)> {
    let mut rng = Rng(7);
    let base = LogisticMedium {
        scale: 1.3,
        background: Some(background()),
        ..LogisticMedium::vacuum()
    };
    let inv = LogisticMedium {
        inversion: Some(inversion()),
        ..base.clone()
    };
    let hot1 = LogisticMedium {
        hotspots: vec![HotSpot {
            x: 0.0,
            z: 600.0,
            radius: 200.0,
            n: -2.0,
            a: -0.8,
            edge: 0.05,
        }],
        ..inv.clone()
    };
    let hot8 = LogisticMedium {
        hotspots: (0..8).map(|_| hot_spot(&mut rng)).collect(),
        ..inv.clone()
    };
    vec![
        ("background", base),
        ("inversion", inv),
        ("hot spot", hot1),
        ("8 hot spots", hot8),
    ]
}

/// Random rays of every kind: grazing rays that hit the ground or are bent
/// back up, rays aimed above and below the horizon, rays aimed away from their
/// plane (never reach it), and rays whose plane is nearly edge-on.
fn random_jobs(rng: &mut Rng, count: usize) -> Vec<RayJob> {
    random_jobs_within(rng, count, 150.0, 1500.0)
}

/// [`random_jobs`] with targets between `near` and `far` metres away.
fn random_jobs_within(rng: &mut Rng, count: usize, near: f64, far: f64) -> Vec<RayJob> {
    (0..count)
        .map(|k| {
            let origin = V3::new(
                rng.uniform(-50.0, 50.0),
                rng.uniform(0.2, 20.0),
                rng.uniform(-50.0, 50.0),
            );
            let azimuth = rng.uniform(-0.6, 0.6);
            let elevation = rng.uniform(-0.02, 0.01);
            let mut direction = V3::new(
                azimuth.sin() * elevation.cos(),
                elevation.sin(),
                azimuth.cos() * elevation.cos(),
            );
            let distance = rng.uniform(near, far);
            let target = origin + direction * distance + V3::new(0.0, rng.uniform(-3.0, 3.0), 0.0);
            let d = target - origin;
            let mut normal = V3::new(d.x, 0.0, d.z).normalized();
            match k % 11 {
                // Aimed away from the plane.
                3 => direction = -direction,
                // A plane almost parallel to the ray.
                7 => normal = V3::new(normal.z, 0.0, -normal.x) + normal * 0.05,
                _ => {}
            }
            RayJob {
                origin,
                direction,
                target: TargetPlane {
                    point: target,
                    normal: normal.normalized(),
                },
            }
        })
        .collect()
}

fn scalar<F: IndexField>(field: &F, jobs: &[RayJob], options: &TraceOptions) -> Vec<Trace> {
    jobs.iter()
        .map(|j| trace::<f64, _>(field, j.origin, j.direction, Some(&j.target), options, None))
        .collect()
}

/// Largest endpoint difference; panics on any difference in the discrete
/// outcome (end, flags, statistics) or an endpoint beyond what `method`
/// allows (see [`allowed`]).
fn compare(
    what: &str,
    method: Method,
    reference: &[Trace],
    got: &[Trace],
    sensitivity: &[Sensitivity],
) -> f64 {
    assert_eq!(reference.len(), got.len());
    let mut worst = 0.0f64;
    for (i, (r, g)) in reference.iter().zip(got).enumerate() {
        let ctx = || format!("{what}, ray {i}: scalar {r:?}\n batch {g:?}");
        let sens = sensitivity.get(i).copied().unwrap_or_default();
        if sens.unstable {
            // A step decided by rounding: the two may take different steps,
            // to the same curve at the same tolerance.
            assert_eq!(r.unreachable, g.unreachable, "{}", ctx());
            continue;
        }
        assert_eq!(r.end, g.end, "{}", ctx());
        assert_eq!(r.occluded, g.occluded, "{}", ctx());
        assert_eq!(r.unreachable, g.unreachable, "{}", ctx());
        assert_eq!(r.stats, g.stats, "{}", ctx());
        let (across, along) = allowed(method, r);
        // A ray whose endpoint moves far with its steps' rounding.
        let across = across + 4.0 * sens.moved;
        let along = along + 4.0 * sens.stretched;
        let delta = g.endpoint - r.endpoint;
        let d = delta.norm();
        let on_ray = delta.dot(r.direction);
        let off_ray = (delta - r.direction * on_ray).norm();
        let d_s = g.arc_length - r.arc_length;
        if r.end == End::Plane {
            assert!(d <= across, "endpoint differs by {d:e} m: {}", ctx());
        } else {
            // Ends at a step's end: on the same curve, moved along it by
            // about the difference in arc length.
            assert!(
                off_ray <= across,
                "endpoint off the ray by {off_ray:e} m: {}",
                ctx()
            );
            assert!(
                (on_ray - d_s).abs() <= across,
                "along the ray by {on_ray:e} m for {d_s:e} m of arc: {}",
                ctx()
            );
        }
        assert!(
            d_s.abs() <= along,
            "arc length differs by {d_s:e} m: {}",
            ctx()
        );
        let turned = (r.direction - g.direction).norm();
        assert!(
            turned <= 1e-9 + 4.0 * sens.turned,
            "direction differs by {turned:e}: {}",
            ctx()
        );
        worst = worst.max(d);
    }
    worst
}

/// How far a batch endpoint may lie from the scalar tracer's (metres), and
/// how far its arc length. RK4: the same steps, so [`TOLERANCE`] both ways.
/// Dormand–Prince: the same steps accepted and rejected (the statistics are
/// compared exactly), but each step's length comes from an error estimate
/// that cancels to ~10⁻⁹ of the rates it is summed from, so the exponential's
/// last-bit differences move a step's length by ~10⁻¹⁰ relative and more:
/// two integrations of the same curve to the same tolerance, which agree to
/// the integrator's global error, bounded by the tolerance per accepted step.
/// The arc length, integrated along but not error-controlled, agrees to
/// 10⁻¹⁰ of itself more; a ray that ends at a step's end (its maximum length,
/// the step limit, the ceiling) ends on the same curve, up to 10⁻⁷ of its arc
/// length further on or short of it.
fn allowed(method: Method, scalar: &Trace) -> (f64, f64) {
    match method {
        Method::Rk4 { .. } => (TOLERANCE, TOLERANCE),
        Method::Dopri5 { tolerance } => {
            let across = TOLERANCE + (scalar.stats.accepted_steps + 4) as f64 * tolerance;
            let drift = if scalar.end == End::Plane {
                1e-10
            } else {
                1e-7
            };
            (across, across + drift * scalar.arc_length)
        }
    }
}

/// Every batch path this CPU runs for `field`: (label, traces).
fn batch_paths(
    field: &Field,
    jobs: &[RayJob],
    options: &BatchOptions,
) -> Vec<(String, Vec<Trace>)> {
    let mut out = Vec::new();
    for isa in testable_isas() {
        let mut t = vec![dummy(); jobs.len()];
        let flat = match field {
            Field::Logistic(f) => {
                trace_batch_3d(isa, f, jobs, options, &mut t);
                out.push((format!("lanes 3-D {}", isa.name()), t.clone()));
                trace_batch_2d(isa, f, jobs, options, &mut t)
            }
            Field::Air(f) => {
                trace_air_3d(isa, f, jobs, options, &mut t);
                out.push((format!("air lanes 3-D {}", isa.name()), t.clone()));
                trace_air_2d(isa, f, jobs, options, &mut t)
            }
            Field::LinearSquare(_) => panic!("no lanes for the analytic medium"),
        };
        match flat {
            Ok(()) => out.push((format!("stratified {}", isa.name()), t)),
            Err(NotStratified) => assert!(!field.is_stratified() || !options.earth.is_flat()),
        }
    }
    out.push(("auto".to_string(), trace_batch(field, jobs, options)));
    out
}

fn dummy() -> Trace {
    Trace {
        endpoint: V3::ZERO,
        direction: V3::ZERO,
        arc_length: 0.0,
        end: End::StepLimit,
        occluded: false,
        unreachable: true,
        stats: Default::default(),
    }
}

/// Traces `jobs` every way and checks every batch path against the scalar
/// tracer; returns the largest endpoint difference.
fn check_all(label: &str, field: &Field, jobs: &[RayJob], options: &TraceOptions) -> f64 {
    let reference = scalar(field, jobs, options);
    let sensitivity = sensitivity(field, jobs, options, &reference);
    let unstable = sensitivity.iter().filter(|s| s.unstable).count();
    // The skipped rays stay the exception, or the test would test nothing.
    assert!(
        unstable * 10 <= jobs.len().max(10),
        "{label}: {unstable} of {} rays change their steps with rounding",
        jobs.len()
    );
    if unstable > 0 {
        eprintln!(
            "{label}: {unstable} of {} rays change their steps with rounding",
            jobs.len()
        );
    }
    let batch = BatchOptions::from_trace_options(options);
    let mut worst = 0.0f64;
    for (path, traces) in batch_paths(field, jobs, &batch) {
        let d = compare(
            &format!("{label}, {path}"),
            options.method,
            &reference,
            &traces,
            &sensitivity,
        );
        eprintln!("{label:>40} | {path:<20} | max endpoint diff {d:.2e} m");
        worst = worst.max(d);
    }
    worst
}

/// How far a ray's scalar endpoint moves, and whether its statistics change,
/// when its steps are perturbed at the level the lanes' rounding perturbs
/// them: Dormand–Prince at tolerances 10⁻⁹ relative above and below the
/// given one (which moves each step by ~2·10⁻¹⁰ of itself). Most rays move by
/// 10⁻¹³ m; a ray that grazes a duct or dives below the ground through steep
/// air can move by 10⁻⁷ m or more, and where an error estimate lies within
/// rounding of the tolerance a step is accepted one way and rejected the
/// other. The lanes may differ from the scalar tracer there, and only there.
/// Empty for RK4, whose batch and scalar steps are the same.
#[derive(Clone, Copy, Default)]
struct Sensitivity {
    /// How far the endpoint moved (m), its direction turned, its arc length
    /// changed (m).
    moved: f64,
    turned: f64,
    stretched: f64,
    unstable: bool,
}

fn sensitivity(
    field: &Field,
    jobs: &[RayJob],
    options: &TraceOptions,
    traces: &[Trace],
) -> Vec<Sensitivity> {
    let Method::Dopri5 { tolerance } = options.method else {
        return Vec::new();
    };
    let mut out = vec![Sensitivity::default(); traces.len()];
    for factor in [1.0 + 1e-9, 1.0 - 1e-9] {
        let perturbed = TraceOptions {
            method: Method::Dopri5 {
                tolerance: tolerance * factor,
            },
            ..*options
        };
        for ((o, p), t) in out
            .iter_mut()
            .zip(scalar(field, jobs, &perturbed))
            .zip(traces)
        {
            o.moved = o.moved.max((p.endpoint - t.endpoint).norm());
            o.turned = o.turned.max((p.direction - t.direction).norm());
            o.stretched = o.stretched.max((p.arc_length - t.arc_length).abs());
            o.unstable |= p.stats != t.stats || p.end != t.end;
        }
    }
    out
}

/// [`check_all`] of a logistic field.
fn check_logistic(
    label: &str,
    field: &LogisticField,
    jobs: &[RayJob],
    options: &TraceOptions,
) -> f64 {
    check_all(label, &Field::Logistic(field.clone()), jobs, options)
}

#[test]
fn lanes_and_stratified_endpoints_equal_the_scalar_tracers() {
    let mut rng = Rng(42);
    let mut worst = 0.0f64;
    let mut kinds = [0usize; 4]; // plane, occluded, unreachable, dips between steps
    for (name, medium) in media() {
        let field = medium.field();
        // Batch sizes around the lane count, none of them a multiple of it
        // except one, and steps from fine to coarse.
        for (count, step) in [(3 * LANES + 5, 1.0), (LANES, 4.0), (7, 13.7), (1, 2.5)] {
            let jobs = random_jobs(&mut rng, count);
            let options = TraceOptions::new(Method::Rk4 { step });
            let reference = scalar(&field, &jobs, &options);
            for r in &reference {
                kinds[0] += usize::from(r.end == End::Plane);
                kinds[1] += usize::from(r.occluded);
                kinds[2] += usize::from(r.unreachable);
            }
            worst = worst.max(check_logistic(
                &format!("{name}, {count} rays, step {step}"),
                &field,
                &jobs,
                &options,
            ));
        }
        // Long rays (a Fata Morgana's 6 to 12 km at 1 m steps): the rounding of
        // the horizontal position drifts over 10⁴ steps, the same way in all.
        let jobs = random_jobs_within(&mut rng, LANES + 3, 6000.0, 12000.0);
        let options = TraceOptions::new(Method::Rk4 { step: 1.0 });
        worst = worst.max(check_logistic(
            &format!("{name}, long rays"),
            &field,
            &jobs,
            &options,
        ));
    }
    // Dips: steps far longer than the dive below the ground (as in
    // rays_analytic.rs, with a logistic background that is nearly linear
    // near the ground, so a grazing ray follows a parabola).
    let dip = LogisticMedium {
        scale: 3.0,
        background: Some(Background { n: 1.0, a: 100.0 }),
        ..LogisticMedium::vacuum()
    };
    let dips_hot = LogisticMedium {
        hotspots: vec![HotSpot {
            x: 0.0,
            z: 2000.0,
            radius: 50.0,
            n: 0.01,
            a: 30.0,
            edge: 1.0,
        }],
        ..dip.clone()
    };
    for medium in [dip, dips_hot] {
        let field = medium.field();
        let options = TraceOptions::new(Method::Rk4 { step: 600.0 });
        let jobs: Vec<RayJob> = (0..2 * LANES + 3)
            .map(|k| {
                let origin = V3::new(0.0, 0.3 + 0.06 * k as f64, 0.0);
                RayJob {
                    origin,
                    direction: V3::new(0.001 * k as f64, -0.006, 1.0).normalized(),
                    target: TargetPlane {
                        point: V3::new(0.0, 0.0, 1000.0),
                        normal: V3::new(0.0, 0.0, 1.0),
                    },
                }
            })
            .collect();
        for j in &jobs {
            let mut path = Vec::new();
            let r = trace::<f64, _>(
                &field,
                j.origin,
                j.direction,
                Some(&j.target),
                &options,
                Some(&mut path),
            );
            if r.occluded && path.iter().all(|p| p.x.y >= 0.0) {
                kinds[3] += 1;
            }
        }
        worst = worst.max(check_logistic("dips, step 600", &field, &jobs, &options));
    }
    eprintln!(
        "rays: {} on their plane, {} occluded, {} unreachable, {} dips between steps; max endpoint diff {worst:.2e} m",
        kinds[0], kinds[1], kinds[2], kinds[3]
    );
    assert!(
        kinds.iter().all(|&k| k > 0),
        "every kind of ray is exercised: {kinds:?}"
    );
}

#[test]
fn ground_stop_mode_step_limit_and_explicit_max_length_match_the_scalar_tracer() {
    let mut rng = Rng(3);
    for (name, medium) in media() {
        let field = medium.field();
        let jobs = random_jobs(&mut rng, LANES + 9);
        let mut options = TraceOptions::new(Method::Rk4 { step: 3.0 });
        options.ground = GroundMode::Stop;
        check_logistic(&format!("{name}, ground stop"), &field, &jobs, &options);
        let mut options = TraceOptions::new(Method::Rk4 { step: 3.0 });
        options.max_steps = 150;
        check_logistic(&format!("{name}, 150 steps"), &field, &jobs, &options);
        options.max_steps = 0;
        check_logistic(&format!("{name}, 0 steps"), &field, &jobs, &options);
        let mut options = TraceOptions::new(Method::Rk4 { step: 3.0 });
        options.max_length = Some(700.0);
        check_logistic(&format!("{name}, max length 700"), &field, &jobs, &options);
    }
}

#[test]
fn stratified_path_equals_the_general_3d_path() {
    // The acceptance check of the 2-D path: same endpoints as the 3-D lanes
    // kernel (and the scalar tracer, above) on media without hot spots.
    let mut rng = Rng(11);
    let batch = BatchOptions::from_trace_options(&TraceOptions::new(Method::Rk4 { step: 1.0 }));
    let mut worst = 0.0f64;
    for (name, medium) in media().into_iter().take(2) {
        let field = medium.field();
        let jobs = random_jobs(&mut rng, 4 * LANES + 1);
        for isa in testable_isas() {
            let mut general = vec![dummy(); jobs.len()];
            trace_batch_3d(isa, &field, &jobs, &batch, &mut general);
            let mut flat = vec![dummy(); jobs.len()];
            trace_batch_2d(isa, &field, &jobs, &batch, &mut flat).unwrap();
            worst = worst.max(compare(
                &format!("{name}, {isa:?}"),
                batch.method,
                &general,
                &flat,
                &[],
            ));
        }
    }
    eprintln!("stratified vs 3-D: max endpoint diff {worst:.2e} m");
    // Hot spots: the 2-D path declines.
    let hot = &media()[2].1;
    let mut out = vec![dummy(); 1];
    assert_eq!(
        trace_batch_2d(
            Isa::Baseline,
            &hot.field(),
            &random_jobs(&mut rng, 1),
            &batch,
            &mut out
        ),
        Err(NotStratified)
    );
}

#[test]
fn empty_batch_is_fine() {
    for method in [
        Method::Rk4 { step: 1.0 },
        Method::Dopri5 { tolerance: 1e-9 },
    ] {
        let batch = BatchOptions::from_trace_options(&TraceOptions::new(method));
        for (_, m) in media() {
            assert!(trace_batch(&Field::Logistic(m.field()), &[], &batch).is_empty());
        }
        for (_, m) in air_media() {
            assert!(trace_batch(&m.field(), &[], &batch).is_empty());
        }
    }
}

#[test]
fn adaptive_lanes_equal_the_scalar_tracer() {
    // Dormand–Prince: every lane with its own step sequence, rejections
    // included, must be the scalar stepper's (same statistics) and end where
    // it ends, through every logistic medium, on short and long rays.
    let mut rng = Rng(17);
    let mut worst = 0.0f64;
    let mut rejected = 0u64;
    for (name, medium) in media() {
        let field = medium.field();
        for (count, tolerance) in [(3 * LANES + 5, 1e-9), (LANES, 1e-6), (5, 1e-11)] {
            let jobs = random_jobs(&mut rng, count);
            let options = TraceOptions::new(Method::Dopri5 { tolerance });
            rejected += scalar(&field, &jobs, &options)
                .iter()
                .map(|t| t.stats.rejected_steps)
                .sum::<u64>();
            worst = worst.max(check_logistic(
                &format!("{name}, {count} rays, dopri5 {tolerance:e}"),
                &field,
                &jobs,
                &options,
            ));
        }
        let jobs = random_jobs_within(&mut rng, LANES + 3, 6000.0, 12000.0);
        let options = TraceOptions::new(Method::Dopri5 { tolerance: 1e-9 });
        worst = worst.max(check_logistic(
            &format!("{name}, long rays, dopri5"),
            &field,
            &jobs,
            &options,
        ));
        // The options that end rays early.
        let jobs = random_jobs(&mut rng, LANES + 9);
        let base = TraceOptions::new(Method::Dopri5 { tolerance: 1e-8 });
        for (what, options) in [
            (
                "ground stop",
                TraceOptions {
                    ground: GroundMode::Stop,
                    ..base
                },
            ),
            (
                "12 steps",
                TraceOptions {
                    max_steps: 12,
                    ..base
                },
            ),
            (
                "0 steps",
                TraceOptions {
                    max_steps: 0,
                    ..base
                },
            ),
            (
                "max length 700",
                TraceOptions {
                    max_length: Some(700.0),
                    ..base
                },
            ),
        ] {
            check_logistic(&format!("{name}, dopri5, {what}"), &field, &jobs, &options);
        }
    }
    eprintln!("adaptive lanes: {rejected} rejected steps checked, max endpoint diff {worst:.2e} m");
    assert!(rejected > 100, "the rays exercise rejections: {rejected}");
}

/// Real air of every kind the lanes evaluate differently: Gladstone–Dale at
/// a constant pressure (the all-vector path), Ciddor with hydrostatic
/// pressure and humidity (the formula per lane), Edlén over the US 1976
/// layers, a measured table, and hot spots over each (the 3-D kernel).
fn air_media() -> Vec<(&'static str, Medium)> {
    let parse = |text: &str| -> Medium { serde_json::from_str(text).expect("a valid medium") };
    let hot = r#"[{"x": 0.0, "z": 600.0, "radius": 200.0, "edge": 0.05, "delta": 25.0, "scale_height": 0.4},
                  {"x": 150.0, "z": 900.0, "radius": 80.0, "edge": 2.0, "delta": -8.0, "scale_height": 3.0}]"#;
    let kinds = [
        (
            "gladstone-dale",
            r#""temperature": {"base": 10.033, "exponential": {"delta": 3.15, "scale_height": 0.0497512}},
               "pressure": 101325.0, "hydrostatic": false, "refractivity": {"gladstone_dale": 0.079386}"#,
        ),
        (
            "ciddor",
            r#""temperature": {"base": 10.0, "lapse": -0.0065,
                  "exponential": {"delta": 4.0, "scale_height": 0.3},
                  "inversion": {"delta": 6.0, "height": 12.0, "thickness": 1.5}},
               "humidity": 0.6, "refractivity": "ciddor""#,
        ),
        (
            "edlen, standard",
            r#""temperature": {"base": 20.0, "lapse": "standard",
                  "inversion": {"delta": -3.0, "height": 8.0, "thickness": 2.0}},
               "humidity": 0.3, "wavelength": 633.0, "refractivity": "edlen""#,
        ),
        (
            "ciddor, humidity table",
            r#""temperature": {"base": 12.0, "lapse": -0.0065,
                  "inversion": {"delta": 5.0, "height": 10.0, "thickness": 2.0}},
               "humidity": {"table": [[0.0, 0.95], [2.0, 0.8], [12.0, 0.5], [60.0, 0.3]]},
               "refractivity": "ciddor""#,
        ),
        (
            "table",
            r#""temperature": {"table": [[0.0, 35.0], [0.5, 28.0], [2.0, 24.0], [10.0, 22.0], [40.0, 21.0]]},
               "refractivity": {"gladstone_dale": 0.0787}"#,
        ),
    ];
    let mut out = Vec::new();
    for (name, air) in kinds {
        out.push((name, parse(&format!(r#"{{"air": {{{air}}}}}"#))));
        out.push((
            name,
            parse(&format!(r#"{{"air": {{{air}}}, "hotspots": {hot}}}"#)),
        ));
    }
    out
}

#[test]
fn real_air_lanes_equal_the_scalar_tracer() {
    let mut rng = Rng(23);
    let mut worst = 0.0f64;
    let mut kinds = [0usize; 3]; // plane, occluded, unreachable
    for (name, medium) in air_media() {
        let field = medium.field();
        let name = if field.is_stratified() {
            name.to_string()
        } else {
            format!("{name} + hot spots")
        };
        for method in [
            Method::Rk4 { step: 2.0 },
            Method::Dopri5 { tolerance: 1e-9 },
            Method::Dopri5 { tolerance: 1e-6 },
        ] {
            let jobs = random_jobs(&mut rng, 2 * LANES + 3);
            let options = TraceOptions::new(method);
            for r in scalar(&field, &jobs, &options) {
                kinds[0] += usize::from(r.end == End::Plane);
                kinds[1] += usize::from(r.occluded);
                kinds[2] += usize::from(r.unreachable);
            }
            worst = worst.max(check_all(
                &format!("{name}, {method:?}"),
                &field,
                &jobs,
                &options,
            ));
        }
    }
    eprintln!(
        "real air: rays {kinds:?} (plane, occluded, unreachable); max endpoint diff {worst:.2e} m"
    );
    assert!(kinds.iter().all(|&k| k > 0), "every kind of ray: {kinds:?}");
}

#[test]
fn rays_that_leave_the_air_end_there_in_the_lanes_too() {
    // A lapse steep enough that air 1.2 km up is colder than −150 °C: rays
    // aimed upward stop at the ceiling (`End::LeftAir`) in every tracer.
    let medium: Medium = serde_json::from_str(
        r#"{"air": {"temperature": {"base": 15.0, "lapse": -0.14}, "hydrostatic": false,
                    "refractivity": {"gladstone_dale": 0.0787}}}"#,
    )
    .unwrap();
    let field = medium.field();
    assert!(field.ceiling() < 1200.0);
    let jobs: Vec<RayJob> = (0..LANES + 2)
        .map(|k| {
            let origin = V3::new(0.0, 2.0, 0.0);
            let direction = V3::new(0.0, 0.2 + 0.05 * k as f64, 1.0).normalized();
            RayJob {
                origin,
                direction,
                target: TargetPlane {
                    point: V3::new(0.0, 0.0, 20_000.0),
                    normal: V3::new(0.0, 0.0, 1.0),
                },
            }
        })
        .collect();
    for method in [
        Method::Rk4 { step: 5.0 },
        Method::Dopri5 { tolerance: 1e-9 },
    ] {
        let options = TraceOptions::new(method);
        for t in scalar(&field, &jobs, &options) {
            assert_eq!(t.end, End::LeftAir);
        }
        check_all(&format!("ceiling, {method:?}"), &field, &jobs, &options);
    }
}

/// Distance in units in the last place between two finite non-negative
/// doubles.
fn ulps(a: f64, b: f64) -> u64 {
    a.to_bits().abs_diff(b.to_bits())
}

#[test]
fn polynomial_exp_is_within_its_documented_error() {
    let mut rng = Rng(5);
    // The tracer's arguments are −|t| for any t; cover the whole normal range
    // uniformly, and [−40, 0] (where σ is not saturated) densely.
    let mut xs: Vec<f64> = (0..2_000_000).map(|_| rng.uniform(-708.0, 709.0)).collect();
    xs.extend((0..8_000_000).map(|_| rng.uniform(-40.0, 0.0)));
    xs.extend([
        0.0,
        -0.0,
        -708.0,
        709.0,
        1e-300,
        -1e-300,
        -0.5 * std::f64::consts::LN_2,
    ]);
    for isa in testable_isas() {
        let mut ys = xs.clone();
        exp_in_place(isa, &mut ys);
        let worst = xs
            .iter()
            .zip(&ys)
            .map(|(x, y)| ulps(*y, x.exp()))
            .max()
            .unwrap();
        eprintln!(
            "exp {isa:?}: max error {worst} ulp over {} arguments",
            xs.len()
        );
        let bound = if isa == Isa::Baseline { 2 } else { 1 };
        assert!(worst <= bound, "{isa:?}: {worst} ulp");
        // Below −708: exactly 0, never NaN, also for huge negative arguments.
        let mut tail = vec![
            -708.0001,
            -709.0,
            -745.2,
            -800.0,
            -1e300,
            f64::MIN,
            f64::NEG_INFINITY,
        ];
        let reference: Vec<f64> = tail.iter().map(|x| x.exp()).collect();
        exp_in_place(isa, &mut tail);
        for (y, r) in tail.iter().zip(reference) {
            assert_eq!(*y, 0.0);
            assert!((y - r).abs() <= (-708.0f64).exp());
        }
        let mut big = vec![709.8, 1e300, f64::INFINITY];
        exp_in_place(isa, &mut big);
        assert!(big.iter().all(|y| *y == f64::INFINITY));
    }
    // The public scalar entry point.
    assert_eq!(fastexp::exp(-1e300), 0.0);
    assert!(ulps(fastexp::exp(-1.0), (-1.0f64).exp()) <= 2);
}

#[test]
fn lanes_over_the_round_earth_equal_the_scalar_tracer() {
    // The 3-D kernels with heights above the sphere (a real earth, and a
    // 20 km one whose curvature shows within the rays' kilometre), RK4 and
    // Dormand–Prince, through the logistic model and real air.
    let mut rng = Rng(31);
    let mut worst = 0.0f64;
    let mut occluded = 0;
    let mut fields: Vec<(String, Field)> = media()
        .into_iter()
        .take(3)
        .map(|(n, m)| (n.to_string(), Field::Logistic(m.field())))
        .collect();
    fields.extend(
        air_media()
            .into_iter()
            .take(4)
            .map(|(n, m)| (n.to_string(), m.field())),
    );
    for radius in [6_371_000.0, 20_000.0] {
        let earth = mirage::trace::Earth::Round { radius };
        for (name, field) in &fields {
            for method in [
                Method::Rk4 { step: 3.0 },
                Method::Dopri5 { tolerance: 1e-9 },
            ] {
                let jobs = random_jobs(&mut rng, LANES + 5);
                let options = TraceOptions {
                    earth,
                    ..TraceOptions::new(method)
                };
                occluded += scalar(field, &jobs, &options)
                    .iter()
                    .filter(|t| t.occluded)
                    .count();
                worst = worst.max(check_all(
                    &format!("{name}, R = {radius}, {method:?}"),
                    field,
                    &jobs,
                    &options,
                ));
            }
        }
    }
    eprintln!("round earth: {occluded} occluded rays; max endpoint diff {worst:.2e} m");
    assert!(occluded > 20, "rays that meet the sphere: {occluded}");
}
