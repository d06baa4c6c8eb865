//! Ray-tracing throughput on one core: the scalar generic tracer, the 3-D
//! lanes kernel and the stratified 2-D kernel (for every instruction set this
//! CPU runs), through six media: background only, background + inversion,
//! and the full medium with one and with eight hot spots (large, soft rims
//! that all cover the rays: nothing to cull), and with 64 and 1,024 small hot
//! spots scattered over 20 km² (rays crossing a few: culled, see
//! `src/medium/cull.rs`). Where a medium is culled, the scalar tracer and the
//! widest lanes build also run unculled (every hot spot at every step, the
//! code before culling) on the first 16 rays. Criterion's
//! throughput is RK4 steps per second (`Throughput::Elements(steps)`); a table
//! of rays/s and steps/s per path follows at the end. Then Dormand–Prince
//! (adaptive steps, each lane its own) through the logistic model and real
//! air, scalar against lanes, in right-hand-side evaluations per second: the
//! Wigner lab's 1000-ray fan over warm water (Gladstone–Dale, tolerance
//! 1e-6), Ciddor air with hydrostatic pressure, and hot spots. Then the cost
//! of one exact Jacobian of `problems/desert-lake.json` relative to one
//! residual evaluation, on one thread.
//!
//! Run with `cargo bench --bench trace`; a filter such as
//! `cargo bench --bench trace -- "hot spot/"` runs a subset (the table is
//! printed unless `MIRAGE_BENCH_NO_TABLE` is set; `MIRAGE_BENCH_TABLE_ONLY=1`
//! prints the table alone, as `benches/tables.sh` does).

use criterion::{BenchmarkId, Criterion, SamplingMode, Throughput};
use mirage::fit::objective::Objective;
use mirage::math::V3;
use mirage::medium::{
    Background, Field, HotSpot, IndexField, Inversion, LogisticField, LogisticMedium, Medium,
};
use mirage::pair::PointPair;
use mirage::problem::Problem;
use mirage::trace::batch::{
    BatchOptions, Isa, LANES, RayJob, trace_batch, trace_batch_2d, trace_batch_3d, trace_batch_into,
};
use mirage::trace::{End, Method, TargetPlane, Trace, TraceOptions, trace};
use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, Instant};

/// RK4 step of the benchmarks (the problem files' default).
const STEP: f64 = 1.0;

/// The four media, as in `tests/fast_paths.rs`.
fn media() -> Vec<(&'static str, LogisticMedium)> {
    let base = LogisticMedium {
        scale: 1.3,
        background: Some(Background { n: 1.0, a: 40.0 }),
        ..LogisticMedium::vacuum()
    };
    let inv = LogisticMedium {
        inversion: Some(Inversion {
            n: 0.3,
            a: 2.0,
            height: 25.0,
        }),
        ..base.clone()
    };
    let spot = |j: usize| HotSpot {
        x: -300.0 + 80.0 * j as f64,
        z: 400.0 + 90.0 * j as f64,
        radius: 150.0,
        n: -2.0,
        a: -0.8,
        edge: 0.05,
    };
    let hot1 = LogisticMedium {
        hotspots: vec![spot(3)],
        ..inv.clone()
    };
    let hot8 = LogisticMedium {
        hotspots: (0..8).map(spot).collect(),
        ..inv.clone()
    };
    vec![
        ("background", base),
        ("inversion", inv.clone()),
        ("hot spot", hot1),
        ("8 hot spots", hot8),
        ("64 hot spots", scattered(&inv, 64)),
        ("1024 hot spots", scattered(&inv, 1024)),
    ]
}

/// `count` hot spots scattered uniformly over 20 km² (x in ±2 km, z from −1 to
/// 4 km) around the rays of [`jobs`], radius 10–40 m, rims of 1/m (their
/// reach, R + 40 m, is what culling keeps), on `layers`: a desert of
/// patches. A ray of 1–1.5 km crosses a few of the 1,024.
fn scattered(layers: &LogisticMedium, count: usize) -> LogisticMedium {
    let mut seed = 0x5eed_u64;
    let mut uniform = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    LogisticMedium {
        hotspots: (0..count)
            .map(|_| HotSpot {
                x: -2000.0 + 4000.0 * uniform(),
                z: -1000.0 + 5000.0 * uniform(),
                radius: 10.0 + 30.0 * uniform(),
                n: -2.0,
                a: -0.8,
                edge: 1.0,
            })
            .collect(),
        ..layers.clone()
    }
}

/// Rays the unculled paths trace (every hot spot at every step is slow).
const UNCULLED_RAYS: usize = 16;

/// 64 mirage-like rays: an observer 2.5 m up looking 1–1.5 km ahead, within a
/// few tenths of a degree of the horizon (as in desert-lake).
fn jobs() -> Vec<RayJob> {
    let origin = V3::new(0.0, 2.5, 0.0);
    (0..4 * LANES)
        .map(|k| {
            let f = k as f64 / (4 * LANES) as f64;
            let azimuth = (-15.0 + 30.0 * f).to_radians();
            let elevation = (-0.2 + 0.3 * ((7 * k) % 11) as f64 / 10.0).to_radians();
            let distance = 1000.0 + 500.0 * ((5 * k) % 13) as f64 / 12.0;
            let direction = V3::new(
                azimuth.sin() * elevation.cos(),
                elevation.sin(),
                azimuth.cos() * elevation.cos(),
            );
            let target = origin + direction * distance;
            RayJob {
                origin,
                direction,
                target: TargetPlane {
                    point: target,
                    normal: V3::new(target.x, 0.0, target.z).normalized(),
                },
            }
        })
        .collect()
}

fn options() -> TraceOptions {
    TraceOptions::new(Method::Rk4 { step: STEP })
}

fn scalar(field: &LogisticField, jobs: &[RayJob], out: &mut [Trace]) {
    for (j, o) in jobs.iter().zip(out) {
        *o = trace::<f64, _>(
            field,
            j.origin,
            j.direction,
            Some(&j.target),
            &options(),
            None,
        );
    }
}

/// A named way to trace a batch.
type Path_ = (String, Box<dyn Fn(&LogisticField, &[RayJob], &mut [Trace])>);

/// Every path that applies to `field`.
fn paths(field: &LogisticField) -> Vec<Path_> {
    let batch = BatchOptions::from_trace_options(&options());
    let mut out: Vec<Path_> = vec![("scalar".to_string(), Box::new(scalar))];
    for isa in Isa::available() {
        out.push((
            format!("lanes-{}", isa.name()),
            Box::new(move |f, j, o| trace_batch_3d(isa, f, j, &batch, o)),
        ));
    }
    if field.is_stratified() {
        for isa in Isa::available() {
            out.push((
                format!("stratified-{}", isa.name()),
                Box::new(move |f, j, o| trace_batch_2d(isa, f, j, &batch, o).unwrap()),
            ));
        }
    }
    out
}

/// The scalar tracer and the widest lanes build without culling, for a field
/// that culls (none otherwise).
fn unculled_paths(field: &LogisticField) -> Vec<Path_> {
    if field.grid().is_none() {
        return Vec::new();
    }
    let batch = BatchOptions::from_trace_options(&options());
    let isa = Isa::detect();
    vec![
        (
            "scalar unculled".to_string(),
            Box::new(|f: &LogisticField, j: &[RayJob], o: &mut [Trace]| {
                scalar(&f.clone().unculled(), j, o)
            }),
        ),
        (
            format!("lanes-{} unculled", isa.name()),
            Box::new(move |f: &LogisticField, j: &[RayJob], o: &mut [Trace]| {
                trace_batch_3d(isa, &f.clone().unculled(), j, &batch, o)
            }),
        ),
    ]
}

fn placeholder() -> Trace {
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

/// Total RK4 steps to trace `jobs` (the same for every path).
fn total_steps(field: &LogisticField, jobs: &[RayJob]) -> u64 {
    let mut out = vec![placeholder(); jobs.len()];
    scalar(field, jobs, &mut out);
    out.iter().map(|t| t.stats.accepted_steps).sum()
}

fn bench_trace(c: &mut Criterion) {
    let jobs = jobs();
    for (name, medium) in media() {
        let field = medium.field();
        let steps = total_steps(&field, &jobs);
        let mut group = c.benchmark_group(name);
        group
            .throughput(Throughput::Elements(steps))
            .sample_size(20)
            .warm_up_time(Duration::from_millis(500))
            .measurement_time(Duration::from_secs(3));
        let mut out = vec![placeholder(); jobs.len()];
        for (path, run) in paths(&field) {
            group.bench_function(BenchmarkId::from_parameter(&path), |b| {
                b.iter(|| run(black_box(&field), black_box(&jobs), &mut out))
            });
        }
        group.finish();
        let unculled = unculled_paths(&field);
        if unculled.is_empty() {
            continue;
        }
        let few = &jobs[..UNCULLED_RAYS];
        let mut group = c.benchmark_group(format!("{name}, {UNCULLED_RAYS} rays"));
        group
            .throughput(Throughput::Elements(total_steps(&field, few)))
            .sampling_mode(SamplingMode::Flat)
            .sample_size(10)
            .warm_up_time(Duration::from_millis(100))
            .measurement_time(Duration::from_secs(3));
        for (path, run) in paths(&field).into_iter().take(1).chain(unculled) {
            group.bench_function(BenchmarkId::from_parameter(&path), |b| {
                b.iter(|| run(black_box(&field), black_box(few), &mut out[..UNCULLED_RAYS]))
            });
        }
        group.finish();
    }
}

/// Dormand–Prince cases: (name, field, rays, tolerance).
fn adaptive_cases() -> Vec<(String, Field, Vec<RayJob>, f64)> {
    let air = |text: &str| -> Field {
        serde_json::from_str::<Medium>(text)
            .expect("a valid medium")
            .field()
    };
    let wigner = air(
        r#"{"air": {"temperature": {"base": 10.033, "exponential": {"delta": 3.15, "scale_height": 0.04975124378109452}},
                     "pressure": 101325.0, "hydrostatic": false, "refractivity": {"gladstone_dale": 0.079386}}}"#,
    );
    let ciddor = air(r#"{"air": {"temperature": {"base": 10.0, "lapse": -0.0065,
              "exponential": {"delta": 3.0, "scale_height": 0.3},
              "inversion": {"delta": 6.0, "height": 12.0, "thickness": 1.5}}, "humidity": 0.6}}"#);
    let road = air(
        r#"{"air": {"temperature": {"base": 30.0, "lapse": -0.0065}, "humidity": 0.3,
                     "refractivity": {"gladstone_dale": 0.0787}},
            "hotspots": [{"x": 0.0, "z": 1000.0, "radius": 400.0, "edge": 0.05, "delta": 30.0, "scale_height": 0.35}]}"#,
    );
    let media = media();
    vec![
        (
            "fan: real air, Gladstone–Dale".to_string(),
            wigner,
            fan(),
            1e-6,
        ),
        (
            "logistic inversion".to_string(),
            Field::Logistic(media[1].1.field()),
            jobs(),
            1e-9,
        ),
        (
            "logistic hot spot".to_string(),
            Field::Logistic(media[2].1.field()),
            jobs(),
            1e-9,
        ),
        ("real air, Ciddor".to_string(), ciddor, jobs(), 1e-9),
        ("real air, hot spot".to_string(), road, jobs(), 1e-9),
    ]
}

/// The Wigner lab's fan: 1000 rays from 1.1 m, −0.04° … −0.14°, to 3 km.
fn fan() -> Vec<RayJob> {
    (0..1000)
        .map(|k| {
            let angle = (-0.04 - 0.1 * k as f64 / 999.0).to_radians();
            RayJob {
                origin: V3::new(0.0, 1.1, 0.0),
                direction: V3::new(0.0, angle.sin(), angle.cos()),
                target: TargetPlane {
                    point: V3::new(0.0, 0.0, 3000.0),
                    normal: V3::new(0.0, 0.0, 1.0),
                },
            }
        })
        .collect()
}

/// Scalar and lanes (the batch entry, on this CPU's widest build) for one
/// Dormand–Prince case.
fn adaptive_paths(tolerance: f64) -> Vec<Path2> {
    let options = TraceOptions::new(Method::Dopri5 { tolerance });
    let batch = BatchOptions::from_trace_options(&options);
    vec![
        (
            "scalar".to_string(),
            Box::new(move |f: &Field, jobs: &[RayJob], out: &mut [Trace]| {
                for (j, o) in jobs.iter().zip(out) {
                    *o = trace::<f64, _>(f, j.origin, j.direction, Some(&j.target), &options, None);
                }
            }),
        ),
        (
            format!("lanes-{}", Isa::detect().name()),
            Box::new(move |f: &Field, jobs: &[RayJob], out: &mut [Trace]| {
                trace_batch_into(f, jobs, &batch, out)
            }),
        ),
    ]
}

/// A named way to trace a batch through any field.
type Path2 = (String, Box<dyn Fn(&Field, &[RayJob], &mut [Trace])>);

fn bench_adaptive(c: &mut Criterion) {
    for (name, field, jobs, tolerance) in adaptive_cases() {
        let mut out = vec![placeholder(); jobs.len()];
        let paths = adaptive_paths(tolerance);
        (paths[0].1)(&field, &jobs, &mut out);
        let rhs: u64 = out.iter().map(|t| t.stats.rhs_evaluations).sum();
        let mut group = c.benchmark_group(format!("dopri5 {name}"));
        group
            .throughput(Throughput::Elements(rhs))
            .sample_size(20)
            .warm_up_time(Duration::from_millis(500))
            .measurement_time(Duration::from_secs(3));
        for (path, run) in &paths {
            group.bench_function(BenchmarkId::from_parameter(path), |b| {
                b.iter(|| run(black_box(&field), black_box(&jobs), &mut out))
            });
        }
        group.finish();
    }
}

/// The cost of one Jacobian against one residual evaluation, on one thread.
fn bench_objective(c: &mut Criterion) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    for (label, objective) in objectives() {
        let x: Vec<f64> = objective.start().iter().copied().collect();
        let mut group = c.benchmark_group(format!("objective {label}"));
        group
            .sample_size(10)
            .measurement_time(Duration::from_secs(3));
        group.bench_function("residuals", |b| {
            b.iter(|| pool.install(|| objective.residuals(black_box(&x))))
        });
        group.bench_function("jacobian", |b| {
            b.iter(|| pool.install(|| objective.jacobian(black_box(&x))))
        });
        group.bench_function("jacobian dual", |b| {
            b.iter(|| pool.install(|| objective.jacobian_dual(black_box(&x))))
        });
        group.finish();
    }
}

/// desert-lake as written (Dormand–Prince), the 36-pair, 6-parameter sweep
/// problem (Dormand–Prince, and RK4 at 0.5 m over 2.5 km), and desert-lake
/// with RK4 at 1 m steps (last: the table's batch comparison takes it).
fn objectives() -> Vec<(String, Objective)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let p = Problem::load(&root.join("problems/desert-lake.json")).unwrap();
    let rk4 = Objective::new(p.medium.clone(), p.free.clone(), p.pairs.clone(), options());
    let sweep = |name: &str| {
        let path = root
            .join("benches/baseline/problems")
            .join(format!("{name}.json"));
        let q = Problem::load(&path).unwrap();
        let label = format!("{name} ({})", q.trace.method.name());
        (label, Objective::from_problem(&q))
    };
    vec![
        (
            format!("desert-lake ({})", p.trace.method.name()),
            Objective::from_problem(&p),
        ),
        sweep("sweep-36x6"),
        sweep("sweep-36x6-rk4"),
        ("desert-lake (rk4 1 m)".to_string(), rk4),
    ]
}

/// Seconds this thread has run on a CPU. The machine is shared, so wall time
/// counts the time other processes held the core; CPU time does not.
#[cfg(target_os = "linux")]
fn cpu_seconds() -> f64 {
    #[repr(C)]
    struct Timespec {
        sec: i64,
        nsec: i64,
    }
    unsafe extern "C" {
        fn clock_gettime(clock: i32, ts: *mut Timespec) -> i32;
    }
    const CLOCK_THREAD_CPUTIME_ID: i32 = 3;
    let mut ts = Timespec { sec: 0, nsec: 0 };
    // SAFETY: clock_gettime writes one timespec (two 64-bit fields on
    // x86-64 and aarch64 Linux) into the pointer it is given.
    let rc = unsafe { clock_gettime(CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    assert_eq!(rc, 0, "clock_gettime");
    ts.sec as f64 + ts.nsec as f64 * 1e-9
}

/// Wall time where thread CPU time is not at hand.
#[cfg(not(target_os = "linux"))]
fn cpu_seconds() -> f64 {
    use std::sync::OnceLock;
    static START: OnceLock<Instant> = OnceLock::new();
    START.get_or_init(Instant::now).elapsed().as_secs_f64()
}

/// Best of a few runs of `f`, in seconds of CPU time of this thread.
fn best_time(f: impl FnMut()) -> f64 {
    best_of(f, cpu_seconds)
}

/// Best of a few runs of `f`, in seconds of wall time (for work on a rayon
/// pool's thread, which this thread's CPU time does not see).
fn best_wall_time(f: impl FnMut()) -> f64 {
    let start = Instant::now();
    best_of(f, || start.elapsed().as_secs_f64())
}

fn best_of(mut f: impl FnMut(), clock: impl Fn() -> f64) -> f64 {
    f();
    let mut best = f64::INFINITY;
    let started = Instant::now();
    while started.elapsed() < Duration::from_millis(400) {
        let t = clock();
        f();
        best = best.min(clock() - t);
    }
    best
}

/// The table: rays/s and M steps/s per core for every medium and path, and the
/// Jacobian/residual cost ratio.
fn table() {
    let jobs = jobs();
    println!(
        "\nRK4 through the logistic model: one core (best CPU time of this thread), rays of 1–1.5 km, step {STEP} m; CPU: {}\n",
        cpu_features()
    );
    println!("| medium | path | rays | rays/s | M steps/s |");
    println!("| --- | --- | --- | --- | --- |");
    for (name, medium) in media() {
        let field = medium.field();
        let mut out = vec![placeholder(); jobs.len()];
        let all = paths(&field).into_iter().map(|p| (p, &jobs[..]));
        let few = unculled_paths(&field)
            .into_iter()
            .map(|p| (p, &jobs[..UNCULLED_RAYS]));
        for ((path, run), jobs) in all.chain(few) {
            let steps = total_steps(&field, jobs) as f64;
            let out = &mut out[..jobs.len()];
            let t = best_time(|| run(&field, jobs, out));
            println!(
                "| {name} | {path} | {} | {:.0} | {:.2} |",
                jobs.len(),
                jobs.len() as f64 / t,
                steps / t / 1e6
            );
        }
    }
    println!(
        "\nDormand–Prince, one core (best CPU time of this thread): rays/s and million right-hand sides/s\n"
    );
    println!("| case | rays | path | rays/s | M RHS/s | RHS/ray |");
    println!("| --- | --- | --- | --- | --- | --- |");
    for (name, field, jobs, tolerance) in adaptive_cases() {
        let mut out = vec![placeholder(); jobs.len()];
        for (path, run) in adaptive_paths(tolerance) {
            let t = best_time(|| run(&field, &jobs, &mut out));
            let rhs: u64 = out.iter().map(|t| t.stats.rhs_evaluations).sum();
            println!(
                "| {name} | {} | {path} | {:.0} | {:.2} | {:.1} |",
                jobs.len(),
                jobs.len() as f64 / t,
                rhs as f64 / t / 1e6,
                rhs as f64 / jobs.len() as f64
            );
        }
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    println!(
        "\nOne exact Jacobian against one residual evaluation, one thread (best wall time): the tangent lanes and the dual-number reference\n"
    );
    println!(
        "| problem | pairs | free | residuals | Jacobian, tangent lanes | Jacobians/s | in residuals | Jacobian, dual numbers | in residuals | lanes speed-up |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for (label, objective) in objectives() {
        let x: Vec<f64> = objective.start().iter().copied().collect();
        let r = best_wall_time(|| {
            pool.install(|| black_box(objective.residuals(&x)));
        });
        let j = best_wall_time(|| {
            pool.install(|| black_box(objective.jacobian(&x)));
        });
        let d = best_wall_time(|| {
            pool.install(|| black_box(objective.jacobian_dual(&x)));
        });
        println!(
            "| {label} | {} | {} | {:.2} ms | {:.2} ms | {:.0} | {:.1} | {:.2} ms | {:.1} | {:.1}× |",
            objective.pairs().len(),
            objective.free().len(),
            r * 1e3,
            j * 1e3,
            1.0 / j,
            j / r,
            d * 1e3,
            d / r,
            d / j
        );
    }
    // What wiring the kernel into the fitter would give: the same residuals
    // (RK4 1 m) from one batch call.
    let (_, objective) = objectives().pop().unwrap();
    let x: Vec<f64> = objective.start().iter().copied().collect();
    let field = objective.medium(&x).field();
    let pairs = objective.pairs();
    let batch_jobs: Vec<RayJob> = pairs.iter().map(PointPair::ray_job).collect();
    let batch = BatchOptions::from_trace_options(objective.options());
    // Wall time for both: the objective traces on the pool's thread.
    let lanes = best_wall_time(|| {
        let traces = trace_batch(&field, &batch_jobs, &batch);
        let r: Vec<V3> = traces
            .iter()
            .zip(pairs)
            .map(|(t, p)| (t.endpoint - p.target()) * p.weight)
            .collect();
        black_box(r);
    });
    let scalar = best_wall_time(|| {
        pool.install(|| black_box(objective.residuals(&x)));
    });
    println!(
        "- desert-lake (rk4 1 m) residuals, {} pairs: objective {:.3} ms, one lanes batch {:.3} ms ({:.1}×)",
        pairs.len(),
        scalar * 1e3,
        lanes * 1e3,
        scalar / lanes
    );
}

fn cpu_features() -> String {
    let isas: Vec<&str> = Isa::available().iter().map(|i| i.name()).collect();
    format!("{} (kernels use {})", isas.join(", "), Isa::detect().name())
}

fn main() {
    // `benches/tables.sh` wants the table alone (a minute, not criterion's ten).
    if std::env::var_os("MIRAGE_BENCH_TABLE_ONLY").is_some() {
        table();
        return;
    }
    let mut c = Criterion::default().configure_from_args();
    bench_trace(&mut c);
    bench_adaptive(&mut c);
    bench_objective(&mut c);
    c.final_summary();
    // Not in `cargo test --benches` (which passes --test) or when listing.
    let quick = std::env::args().any(|a| a == "--test" || a == "--list");
    if !quick && std::env::var_os("MIRAGE_BENCH_NO_TABLE").is_none() {
        table();
    }
}
