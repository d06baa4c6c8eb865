//! Fit time of every bundled problem, of a 15-pair, 4-parameter hot-spot fit
//! (the target: under 0.2 s on one core), and of the 36-pair, 6-parameter
//! sweep problem at 0.5 m RK4 steps with the surrogate tracer and without it
//! (issue #14's target: under 0.3 s on one core; the ratio of the two is
//! what the surrogate buys, measured in one run). Run with `cargo bench --bench fit`;
//! pin to one core with `RAYON_NUM_THREADS=1`. With `MIRAGE_BENCH_TABLE_ONLY=1`
//! it prints the README's table instead (median of 7 fits each, as
//! `benches/tables.sh` runs it).

use criterion::Criterion;
use mirage::fit::fit;
use mirage::fit::synthetic::retarget;
use mirage::pair::PointPair;
use mirage::problem::Problem;
use mirage::trace::Method;
use std::path::Path;
use std::time::{Duration, Instant};

fn problems_dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("problems")
}

/// desert-lake with three more pairs, traced through its fitted air: 15 pairs,
/// 4 free parameters (hot spot centre, radius, strength).
fn fifteen_pair_problem() -> Problem {
    let mut p = Problem::load(&problems_dir().join("desert-lake.json")).unwrap();
    let fitted = fit(&p, None).unwrap().medium;
    let o = p.pairs[0].origin;
    let extra: Vec<PointPair> = [
        (-15.0f64, -0.12f64, 1250.0f64),
        (14.0, -0.17, 1400.0),
        (3.0, -0.22, 1300.0),
    ]
    .iter()
    .map(|&(az, el, d)| {
        let (a, e) = (az.to_radians(), el.to_radians());
        let t = [o[0] + d * a.sin(), o[1] + d * e.tan(), o[2] + d * a.cos()];
        PointPair {
            origin: o,
            through: t,
            target: t,
            weight: 1.0,
            wavelength: None,
        }
    })
    .collect();
    let (extra, failed) = retarget(&extra, &fitted.field(), &p.trace);
    assert!(failed.is_empty());
    p.pairs.extend(extra);
    assert_eq!(p.pairs.len(), 15);
    p
}

/// `benches/baseline/problems/sweep-36x6-rk4.json` (36 pairs over 2.5 km, 6
/// free parameters, RK4 at 0.5 m), the surrogate tracer on or off.
fn rk4_sweep(surrogate: bool) -> Problem {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/baseline/problems/sweep-36x6-rk4.json");
    let mut p = Problem::load(&path).unwrap();
    p.solver.surrogate = surrogate;
    p.name = format!(
        "{}, {}",
        p.name,
        if surrogate {
            "surrogate"
        } else {
            "no surrogate"
        }
    );
    p
}

/// Every bundled problem (`problems/*.json`; `problems/scenes/` holds scenes).
fn bundled() -> Vec<Problem> {
    let mut files: Vec<_> = std::fs::read_dir(problems_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    files.sort();
    files.iter().map(|f| Problem::load(f).unwrap()).collect()
}

fn bench_fits(c: &mut Criterion) {
    let mut group = c.benchmark_group("fit");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(5));
    for p in bundled() {
        group.bench_function(p.name.clone(), |b| b.iter(|| fit(&p, None).unwrap()));
    }
    let p = fifteen_pair_problem();
    group.bench_function("desert-lake-15-pairs-4-params", |b| {
        b.iter(|| {
            let r = fit(&p, None).unwrap();
            assert!(r.totals.objective < 1e-12);
            r
        })
    });
    for surrogate in [true, false] {
        let p = rk4_sweep(surrogate);
        group.bench_function(p.name.clone(), |b| b.iter(|| fit(&p, None).unwrap()));
    }
    group.finish();
}

/// The README's table: per problem, the median wall time of 7 fits (after
/// one unmeasured), its fitted F and the fit's size.
fn table() {
    println!(
        "Fit time, in process (`mirage::fit::fit`, the solver and identifiability analysis), median of 7, rayon threads: {}\n",
        rayon::current_num_threads()
    );
    println!("| problem | pairs | free | trace | fitted F (m²) | fit time |");
    println!("| --- | --- | --- | --- | --- | --- |");
    let mut all = bundled();
    all.push(fifteen_pair_problem());
    all.push(rk4_sweep(true));
    all.push(rk4_sweep(false));
    let mut sweep = Vec::new();
    for p in all {
        let r = fit(&p, None).unwrap();
        let mut times: Vec<f64> = (0..7)
            .map(|_| {
                let t = Instant::now();
                std::hint::black_box(fit(&p, None).unwrap());
                t.elapsed().as_secs_f64()
            })
            .collect();
        times.sort_by(f64::total_cmp);
        let name = if p.pairs.len() == 15 && p.name == "desert-lake" {
            "desert-lake, 15 pairs".to_string()
        } else {
            p.name.clone()
        };
        println!(
            "| {name} | {} | {} | {} | {:.1e} | {:.1} ms |",
            p.pairs.len(),
            p.free.len(),
            match p.trace.method {
                Method::Rk4 { step } => format!("RK4 {step} m"),
                Method::Dopri5 { tolerance } => format!("dopri5 {tolerance:e}"),
            },
            r.totals.objective,
            times[3] * 1e3
        );
        if p.name.starts_with("sweep-36x6-rk4") {
            sweep.push(times[3]);
        }
    }
    if let [with, without] = sweep[..] {
        println!(
            "\nThe surrogate tracer on sweep-36x6-rk4: {:.1}× faster than RK4 alone, same run.",
            without / with
        );
    }
}

fn main() {
    if std::env::var_os("MIRAGE_BENCH_TABLE_ONLY").is_some() {
        table();
        return;
    }
    let mut c = Criterion::default().configure_from_args();
    bench_fits(&mut c);
    c.final_summary();
}
