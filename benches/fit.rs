//! Fit time of every bundled problem, and of a 15-pair, 4-parameter hot-spot fit
//! (the target: under 0.2 s on one core). Run with `cargo bench --bench fit`;
//! pin to one core with `RAYON_NUM_THREADS=1`.

use criterion::{Criterion, criterion_group, criterion_main};
use mirage::fit::fit;
use mirage::fit::synthetic::retarget;
use mirage::pair::PointPair;
use mirage::problem::Problem;
use std::path::Path;
use std::time::Duration;

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

fn bench_fits(c: &mut Criterion) {
    let mut group = c.benchmark_group("fit");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(5));
    let mut files: Vec<_> = std::fs::read_dir(problems_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        // Problem files only: `problems/scenes/` holds scenes.
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    files.sort();
    for f in files {
        let p = Problem::load(&f).unwrap();
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
    group.finish();
}

criterion_group!(benches, bench_fits);
criterion_main!(benches);
