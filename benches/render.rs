//! Render benchmarks: the 1280×720 render time of a stratified scene (the sea,
//! with path reuse) and of a hot-spot scene (the road); the three sphere
//! tracers on the road at 320×180 (time, distance queries and SDF evaluations
//! per pixel: the plain tracer evaluates all 57 objects at every query);
//! what path reuse buys on the sea at 640×360; and what integrating camera
//! rays in packs of SIMD lanes buys on the road at 640×360.
//!
//! Run with `cargo bench --bench render`; the targets are for 2 cores:
//! `RAYON_NUM_THREADS=2 cargo bench --bench render`. With
//! `MIRAGE_BENCH_TABLE_ONLY=1` it prints the README's table instead: every
//! bundled flat-ground scene at 1280×720, median of 3 (`benches/tables.sh`).

use criterion::Criterion;
use mirage::medium::IndexField;
use mirage::render::march::TracerKind;
use mirage::render::{RenderOptions, Renderer, summary};
use mirage::scene::Scene;
use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, Instant};

fn scene(name: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("problems/scenes")
        .join(format!("{name}.json"));
    Scene::load(&path).unwrap()
}

fn options(width: u32, tracer: TracerKind, path_reuse: bool) -> RenderOptions {
    RenderOptions {
        width: Some(width),
        tracer,
        path_reuse,
        ..RenderOptions::default()
    }
}

/// The median of 3 timed renders after one unmeasured (setup included).
fn median_render(scene: &Scene, opts: &RenderOptions) -> f64 {
    black_box(Renderer::new(scene, opts).render());
    let mut times: Vec<f64> = (0..3)
        .map(|_| {
            let t = Instant::now();
            black_box(Renderer::new(scene, opts).render());
            t.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[1]
}

/// Renders once and prints the work per pixel (the numbers criterion does
/// not show).
fn report(label: &str, scene: &Scene, opts: &RenderOptions) {
    let r = Renderer::new(scene, opts);
    let img = r.render();
    println!("{label}:\n{}\n", summary(&r, &img));
}

fn full_hd_720(c: &mut Criterion) {
    let threads = rayon::current_num_threads();
    println!("rayon threads: {threads}");
    let mut g = c.benchmark_group("render 1280x720");
    g.sample_size(10).measurement_time(Duration::from_secs(60));
    for (name, label) in [
        ("sea", "stratified (sea, path reuse)"),
        ("road", "hot spot (road)"),
    ] {
        let s = scene(name);
        let opts = options(1280, TracerKind::Quadric, true);
        report(label, &s, &opts);
        // Setup (grid, path table) is part of a render.
        g.bench_function(label, |b| {
            b.iter(|| black_box(Renderer::new(&s, &opts).render()))
        });
    }
    g.finish();
}

fn tracers(c: &mut Criterion) {
    let s = scene("road");
    let mut g = c.benchmark_group("road 320x180 by tracer");
    g.sample_size(10).measurement_time(Duration::from_secs(30));
    for tracer in [TracerKind::Plain, TracerKind::Enhanced, TracerKind::Quadric] {
        let opts = options(320, tracer, true);
        report(&format!("road, {} tracer", tracer.name()), &s, &opts);
        g.bench_function(tracer.name(), |b| {
            b.iter(|| black_box(Renderer::new(&s, &opts).render()))
        });
    }
    g.finish();
}

fn path_reuse(c: &mut Criterion) {
    let s = scene("sea");
    let mut g = c.benchmark_group("sea 640x360 path reuse");
    g.sample_size(10).measurement_time(Duration::from_secs(30));
    for reuse in [true, false] {
        let opts = options(640, TracerKind::Quadric, reuse);
        let label = if reuse { "table" } else { "integrated" };
        report(&format!("sea, {label}"), &s, &opts);
        g.bench_function(label, |b| {
            b.iter(|| black_box(Renderer::new(&s, &opts).render()))
        });
    }
    g.finish();
}

fn packs(c: &mut Criterion) {
    let s = scene("road");
    let mut g = c.benchmark_group("road 640x360 packs");
    g.sample_size(10).measurement_time(Duration::from_secs(30));
    for packs in [true, false] {
        let opts = RenderOptions {
            packs,
            ..options(640, TracerKind::Quadric, true)
        };
        let label = if packs { "packs" } else { "one by one" };
        report(&format!("road, {label}"), &s, &opts);
        g.bench_function(label, |b| {
            b.iter(|| black_box(Renderer::new(&s, &opts).render()))
        });
    }
    g.finish();
}

/// The README's table: 1280×720 renders (setup included), median of 3 after
/// one unmeasured, on the rayon pool's threads; where the air has hot spots
/// also with every camera ray integrated on its own (`--no-packs`), in the
/// same run, and the ratio.
fn table() {
    println!(
        "1280×720 renders (setup, path table and image; not the PNG), median of 3, rayon threads: {}\n",
        rayon::current_num_threads()
    );
    println!("| scene | air | render time | rays one by one (`--no-packs`) | packs' speed-up |");
    println!("| --- | --- | --- | --- | --- |");
    for (name, air) in [
        ("sea", "stratified (path table)"),
        ("road", "one hot spot"),
        ("desert", "one large hot spot"),
        ("desert-patches", "400 hot patches (culled)"),
    ] {
        let s = scene(name);
        let opts = options(1280, TracerKind::Quadric, true);
        let t = median_render(&s, &opts);
        if s.medium.field().is_stratified() {
            println!("| {name} | {air} | {t:.2} s | – | – |");
        } else {
            let alone = median_render(
                &s,
                &RenderOptions {
                    packs: false,
                    ..opts
                },
            );
            println!(
                "| {name} | {air} | {t:.2} s | {alone:.2} s | {:.2}× |",
                alone / t
            );
        }
    }
}

fn main() {
    if std::env::var_os("MIRAGE_BENCH_TABLE_ONLY").is_some() {
        table();
        return;
    }
    let mut c = Criterion::default().configure_from_args();
    full_hd_720(&mut c);
    tracers(&mut c);
    path_reuse(&mut c);
    packs(&mut c);
    c.final_summary();
}
