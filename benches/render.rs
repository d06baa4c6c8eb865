//! Render benchmarks: the 1280×720 render time of a stratified scene (the sea,
//! with path reuse) and of a hot-spot scene (the road); the three sphere
//! tracers on the road at 320×180 (time, distance queries and SDF evaluations
//! per pixel: the plain tracer evaluates all 57 objects at every query); and
//! what path reuse buys on the sea at 640×360.
//!
//! Run with `cargo bench --bench render`; the targets are for 2 cores:
//! `RAYON_NUM_THREADS=2 cargo bench --bench render`.

use criterion::{Criterion, criterion_group, criterion_main};
use mirage::render::march::TracerKind;
use mirage::render::{RenderOptions, Renderer, summary};
use mirage::scene::Scene;
use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

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

criterion_group!(benches, full_hd_720, tracers, path_reuse);
criterion_main!(benches);
