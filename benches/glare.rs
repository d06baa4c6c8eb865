//! Veiling glare: accumulating the Fourier coefficients costs O(N·K) for K
//! blobs, reconstructing the image costs O(N) per pixel whatever K is.
//!
//! `cargo bench --bench glare` prints, for K = 1, 10, 100 and 1000 Gaussian
//! and compact blobs on a 640 × 360 image, the time to accumulate the
//! coefficients and the time per pixel to reconstruct the image.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use mirage::render::glare::{Blob, FourierSeries, Kernel};
use std::hint::black_box;

const W: u32 = 640;
const H: u32 = 360;

fn blobs(k: usize) -> Vec<Blob> {
    // Deterministic scatter over the image; alternating kernels.
    (0..k)
        .map(|i| {
            let t = i as f64 * 0.618_033_988_749_895;
            Blob {
                x: (t.fract()) * W as f64,
                y: ((t * 7.3).fract()) * H as f64,
                amplitude: [1.0, 0.8, 0.6],
                kernel: if i % 2 == 0 {
                    Kernel::Gaussian { sigma: 8.0 }
                } else {
                    Kernel::Compact { radius: 60.0 }
                },
            }
        })
        .collect()
}

fn series(k: usize) -> FourierSeries {
    let kernels = [
        Kernel::Gaussian { sigma: 8.0 },
        Kernel::Compact { radius: 60.0 },
    ];
    let (pw, ph) = (W as f64 + 60.0, H as f64 + 60.0);
    let (m, n) = FourierSeries::orders_for(&kernels, 1e-3, pw, ph);
    let mut s = FourierSeries::new(pw, ph, m, n);
    s.add_blobs(&blobs(k));
    s
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("glare");
    g.sample_size(10);
    for k in [1usize, 10, 100, 1000] {
        let b = blobs(k);
        let empty = series(0);
        g.bench_with_input(BenchmarkId::new("accumulate", k), &k, |bench, _| {
            bench.iter(|| {
                let mut s = empty.clone();
                s.add_blobs(black_box(&b));
                s
            })
        });
        let s = series(k);
        g.bench_with_input(BenchmarkId::new("reconstruct", k), &k, |bench, _| {
            bench.iter(|| black_box(&s).evaluate_grid(W, H))
        });
    }
    g.finish();
    let s = series(1);
    println!(
        "series: orders {}×{}, {} coefficients per channel, {} pixels",
        s.order_x,
        s.order_y,
        s.len(),
        W * H
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);
