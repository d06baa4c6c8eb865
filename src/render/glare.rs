//! Veiling glare: light from the brightest parts of the image (the sun and
//! its mirage images) scattered over the rest of it by the eye or the lens.
//!
//! The glare is a sum of K bell-shaped ghosts ("blobs"), each a kernel of
//! peak `A_k` centred on (x_k, y_k). Instead of adding K kernels to every
//! pixel (O(pixels·K)), the sum is represented by a truncated 2-D Fourier
//! series over a period W × H (the image plus a margin, so that ghosts do not
//! wrap around onto the far edge):
//!
//! ```text
//! f(x, y) = Σ_{|m|≤M, |n|≤N} c_mn · e^{i(ω_m x + ν_n y)},  ω_m = 2πm/W, ν_n = 2πn/H
//! c_mn    = (1/(W·H)) Σ_k A_k · K̂_k(|(ω_m, ν_n)|) · e^{−i(ω_m x_k + ν_n y_k)}
//! ```
//!
//! The coefficients are accumulated once, in O(N·K) for N = (2M+1)(2N+1)
//! coefficients; reconstructing a pixel costs O(N) (in practice O(M) per
//! pixel plus O(N) per row, by summing over n first), independent of K.
//!
//! Kernels ([`Kernel`]), with their Fourier transforms in closed form:
//!
//! | kernel | profile (peak 1) | K̂(k) | truncation for ε |
//! | --- | --- | --- | --- |
//! | Gaussian σ | e^(−u²/2σ²) | 2πσ²·e^(−σ²k²/2) | k ≤ √(2 ln(1/ε))/σ |
//! | compact r | (1 − u²/r²)₊³ | 2πr²·48·J₄(kr)/(kr)⁴ | k ≤ (15.3/ε)^0.4/r |
//!
//! Truncating at those k leaves a pointwise error of at most ε·Σ_k A_k: for
//! the Gaussian the dropped coefficients sum to A·e^(−σ²k²/2) = ε·A; for the
//! compact kernel |J₄(a)| ≤ √(2/(πa)) bounds their sum by 15.3·A·(kr)^−2.5.
//! The order is set by the narrowest kernel.
//!
//! In a render ([`apply`]), every pixel brighter than a threshold is a source;
//! each source spreads a fraction `weight` of its light through each kernel
//! of the scene's glare, normalised to unit integral, and keeps the rest.
//! Sources lie on the pixel grid, so their phase sums are a row-separable
//! discrete Fourier transform.
//!
//! ```json
//! "glare": { "strength": 1.0, "threshold": 20.0, "epsilon": 1e-3,
//!            "kernels": [ { "type": "gaussian", "sigma": 0.08, "weight": 0.004 },
//!                         { "type": "compact", "radius": 2.0, "weight": 0.0005 } ] }
//! ```
//!
//! | field | meaning | default |
//! | --- | --- | --- |
//! | `enabled` | glare on/off | true |
//! | `strength` | multiplies every kernel's weight | 1 |
//! | `threshold` | luminance above which a pixel is a source (linear units) | 20 |
//! | `epsilon` | truncation error, relative to the sources' peaks | 1e-3 |
//! | `kernels` | `gaussian` (`sigma`, degrees) or `compact` (`radius`, degrees), each with the `weight` of light it spreads | Gaussian 0.08° (0.004), Gaussian 0.5° (0.0015), compact 2° (0.0005) |

pub use crate::scene::glare::{
    AngularGlare, DEFAULT_EPSILON, DEFAULT_THRESHOLD, Kernel, WeightedKernel, default_kernels,
};

use nalgebra::Complex;
use rayon::prelude::*;
use std::f64::consts::PI;

/// A complex number.
pub type C64 = Complex<f64>;

/// The narrowest kernel drawn (pixels): narrower glare is no wider than the
/// source pixel itself, and would only inflate the series' order.
pub const MIN_KERNEL_PIXELS: f64 = 1.5;

impl Kernel {
    /// The kernel's value at squared distance `u2` from its centre.
    #[inline]
    pub fn value(&self, u2: f64) -> f64 {
        match *self {
            Kernel::Gaussian { sigma } => (-0.5 * u2 / (sigma * sigma)).exp(),
            Kernel::Compact { radius } => {
                let t = 1.0 - u2 / (radius * radius);
                if t > 0.0 { t * t * t } else { 0.0 }
            }
        }
    }

    /// The kernel's integral over the plane (its Fourier transform at 0).
    pub fn integral(&self) -> f64 {
        match *self {
            Kernel::Gaussian { sigma } => 2.0 * PI * sigma * sigma,
            Kernel::Compact { radius } => PI * radius * radius / 4.0,
        }
    }

    /// The 2-D Fourier transform at angular frequency magnitude `k`.
    pub fn spectrum(&self, k: f64) -> f64 {
        match *self {
            Kernel::Gaussian { sigma } => {
                2.0 * PI * sigma * sigma * (-0.5 * sigma * sigma * k * k).exp()
            }
            Kernel::Compact { radius } => {
                let a = k * radius;
                2.0 * PI * radius * radius * 48.0 * bessel_j4_over_a4(a)
            }
        }
    }

    /// The frequency beyond which the dropped part of the series is below
    /// `epsilon` times the peak (see the module's table).
    pub fn cutoff(&self, epsilon: f64) -> f64 {
        match *self {
            Kernel::Gaussian { sigma } => (2.0 * (1.0 / epsilon).ln()).sqrt() / sigma,
            Kernel::Compact { radius } => (15.3 / epsilon).powf(0.4) / radius,
        }
    }

    /// How far from its centre the kernel is above `epsilon` of its peak.
    pub fn reach(&self, epsilon: f64) -> f64 {
        match *self {
            Kernel::Gaussian { sigma } => sigma * (2.0 * (1.0 / epsilon).ln()).sqrt(),
            Kernel::Compact { radius } => radius,
        }
    }
}

/// J₄(a)/a⁴: the power series near 0 (where the quotient cancels), else the
/// trapezoid rule on Bessel's integral J_n(a) = (1/2π)∫cos(nθ − a sin θ) dθ,
/// which converges exponentially for a periodic analytic integrand once the
/// number of points exceeds a + n by a margin.
pub fn bessel_j4_over_a4(a: f64) -> f64 {
    let a = a.abs();
    if a < 1.0 {
        // J₄(a) = Σ_k (−1)^k (a/2)^{2k+4} / (k!(k+4)!)
        let q = 0.25 * a * a;
        let mut term = 1.0 / (16.0 * 24.0);
        let mut sum = term;
        for k in 1..12 {
            term *= -q / (k as f64 * (k + 4) as f64);
            sum += term;
        }
        return sum;
    }
    let points = (a.ceil() as usize + 48).next_multiple_of(8);
    let mut s = 0.0;
    for j in 0..points {
        let th = 2.0 * PI * j as f64 / points as f64;
        s += (4.0 * th - a * th.sin()).cos();
    }
    s / points as f64 / a.powi(4)
}

/// One ghost: a kernel of peak `amplitude` (per channel) at (x, y) pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Blob {
    /// Centre, pixels from the left edge.
    pub x: f64,
    /// Centre, pixels from the top edge.
    pub y: f64,
    /// Peak value per channel.
    pub amplitude: [f64; 3],
    /// Shape.
    pub kernel: Kernel,
}

/// A truncated 2-D Fourier series of RGB values over a W × H period.
#[derive(Clone, Debug)]
pub struct FourierSeries {
    /// Period along x (pixels).
    pub period_x: f64,
    /// Period along y (pixels).
    pub period_y: f64,
    /// Highest |m|.
    pub order_x: usize,
    /// Highest |n|.
    pub order_y: usize,
    /// c_mn per channel, row-major over n (−N…N) then m (−M…M).
    coefficients: Vec<[C64; 3]>,
}

impl FourierSeries {
    /// A zero series.
    pub fn new(period_x: f64, period_y: f64, order_x: usize, order_y: usize) -> FourierSeries {
        FourierSeries {
            period_x,
            period_y,
            order_x,
            order_y,
            coefficients: vec![[C64::new(0.0, 0.0); 3]; (2 * order_x + 1) * (2 * order_y + 1)],
        }
    }

    /// The orders (M, N) that represent `kernels` to within `epsilon` of
    /// their peaks over the period: set by the narrowest kernel.
    pub fn orders_for(
        kernels: &[Kernel],
        epsilon: f64,
        period_x: f64,
        period_y: f64,
    ) -> (usize, usize) {
        let k = kernels
            .iter()
            .map(|k| k.cutoff(epsilon))
            .fold(0.0, f64::max);
        (
            (k * period_x / (2.0 * PI)).ceil() as usize,
            (k * period_y / (2.0 * PI)).ceil() as usize,
        )
    }

    /// The number of coefficients.
    pub fn len(&self) -> usize {
        self.coefficients.len()
    }

    /// Whether the series has no coefficients (never: c₀₀ always exists).
    pub fn is_empty(&self) -> bool {
        self.coefficients.is_empty()
    }

    fn index(&self, m: i64, n: i64) -> usize {
        let w = 2 * self.order_x + 1;
        (n + self.order_y as i64) as usize * w + (m + self.order_x as i64) as usize
    }

    /// c_mn (all three channels).
    pub fn coefficient(&self, m: i64, n: i64) -> [C64; 3] {
        self.coefficients[self.index(m, n)]
    }

    fn omega(&self, m: i64) -> f64 {
        2.0 * PI * m as f64 / self.period_x
    }

    fn nu(&self, n: i64) -> f64 {
        2.0 * PI * n as f64 / self.period_y
    }

    /// The kernel's transform over the coefficient grid (row-major like the
    /// coefficients), divided by the period's area.
    fn spectrum_grid(&self, kernel: &Kernel) -> Vec<f64> {
        let (mm, nn) = (self.order_x as i64, self.order_y as i64);
        let area = self.period_x * self.period_y;
        // The transform is radial: compute one quadrant and mirror it.
        let quad: Vec<f64> = (0..=nn)
            .into_par_iter()
            .flat_map_iter(|n| {
                (0..=mm).map(move |m| {
                    let k = self.omega(m).hypot(self.nu(n));
                    kernel.spectrum(k) / area
                })
            })
            .collect();
        let mut out = Vec::with_capacity(self.len());
        for n in -nn..=nn {
            for m in -mm..=mm {
                out.push(
                    quad[n.unsigned_abs() as usize * (mm as usize + 1) + m.unsigned_abs() as usize],
                );
            }
        }
        out
    }

    /// Adds blobs to the series: O(N) each.
    pub fn add_blobs(&mut self, blobs: &[Blob]) {
        let (mm, nn) = (self.order_x as i64, self.order_y as i64);
        let mut spectra: Vec<(Kernel, Vec<f64>)> = Vec::new();
        for b in blobs {
            let kernel = b.kernel;
            let pos = match spectra.iter().position(|(k, _)| *k == kernel) {
                Some(p) => p,
                None => {
                    spectra.push((kernel, self.spectrum_grid(&kernel)));
                    spectra.len() - 1
                }
            };
            let spectrum = &spectra[pos].1;
            // The phase e^{−i(ω_m x + ν_n y)} factors into a row and a column.
            let px: Vec<C64> = (-mm..=mm)
                .map(|m| C64::from_polar(1.0, -self.omega(m) * b.x))
                .collect();
            let w = px.len();
            for (row, n) in (-nn..=nn).enumerate() {
                let py = C64::from_polar(1.0, -self.nu(n) * b.y);
                for (col, pxm) in px.iter().enumerate() {
                    let idx = row * w + col;
                    let phase = pxm * py * spectrum[idx];
                    for c in 0..3 {
                        self.coefficients[idx][c] += phase * b.amplitude[c];
                    }
                }
            }
        }
    }

    /// The series' value at (x, y): O(N).
    pub fn evaluate(&self, x: f64, y: f64) -> [f64; 3] {
        let (mm, nn) = (self.order_x as i64, self.order_y as i64);
        let mut sum = [C64::new(0.0, 0.0); 3];
        for n in -nn..=nn {
            let py = C64::from_polar(1.0, self.nu(n) * y);
            for m in -mm..=mm {
                let p = C64::from_polar(1.0, self.omega(m) * x) * py;
                let c = self.coefficient(m, n);
                for k in 0..3 {
                    sum[k] += c[k] * p;
                }
            }
        }
        sum.map(|s| s.re)
    }

    /// The series at the centres of a width × height pixel grid (row-major):
    /// per row, the sum over n first (O(N)), then per pixel a sum over
    /// m ≥ 0 only, since the series is real (c₋ₘ₋ₙ = conj cₘₙ): O(M).
    pub fn evaluate_grid(&self, width: u32, height: u32) -> Vec<[f64; 3]> {
        let (mm, nn) = (self.order_x as i64, self.order_y as i64);
        let columns: Vec<Vec<C64>> = (0..width)
            .map(|x| {
                let xc = x as f64 + 0.5;
                (0..=mm)
                    .map(|m| C64::from_polar(1.0, self.omega(m) * xc))
                    .collect()
            })
            .collect();
        (0..height)
            .into_par_iter()
            .flat_map_iter(|y| {
                let yc = y as f64 + 0.5;
                let mut d = vec![[C64::new(0.0, 0.0); 3]; mm as usize + 1];
                for n in -nn..=nn {
                    let py = C64::from_polar(1.0, self.nu(n) * yc);
                    for m in 0..=mm {
                        let c = self.coefficient(m, n);
                        for k in 0..3 {
                            d[m as usize][k] += c[k] * py;
                        }
                    }
                }
                let columns = &columns;
                (0..width as usize).map(move |x| {
                    let col = &columns[x];
                    let mut s = [d[0][0].re, d[0][1].re, d[0][2].re];
                    for m in 1..=mm as usize {
                        let p = col[m];
                        for k in 0..3 {
                            s[k] += 2.0 * (d[m][k] * p).re;
                        }
                    }
                    s
                })
            })
            .collect()
    }
}

/// What [`apply`] needs: kernels in pixels, the source threshold and ε.
#[derive(Clone, Debug, PartialEq)]
pub struct GlareSettings {
    /// The kernels (already scaled by the strength).
    pub kernels: Vec<WeightedKernel>,
    /// Pixels whose luminance exceeds this are sources.
    pub threshold: f64,
    /// Truncation error relative to the sources' peaks.
    pub epsilon: f64,
}

impl AngularGlare {
    /// The settings for a camera whose pixels subtend `pixel_angle` radians;
    /// kernels narrower than [`MIN_KERNEL_PIXELS`] are widened to it.
    pub fn in_pixels(&self, pixel_angle: f64) -> GlareSettings {
        let px = |deg: f64| (deg.to_radians() / pixel_angle).max(MIN_KERNEL_PIXELS);
        GlareSettings {
            kernels: self
                .kernels
                .iter()
                .map(|k| WeightedKernel {
                    kernel: match k.kernel {
                        Kernel::Gaussian { sigma } => Kernel::Gaussian { sigma: px(sigma) },
                        Kernel::Compact { radius } => Kernel::Compact { radius: px(radius) },
                    },
                    weight: k.weight,
                })
                .collect(),
            threshold: self.threshold,
            epsilon: self.epsilon,
        }
    }
}

/// What the glare cost and found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GlareStats {
    /// Source pixels.
    pub sources: usize,
    /// Fourier coefficients per channel.
    pub coefficients: usize,
    /// Orders (M, N).
    pub orders: (usize, usize),
    /// Seconds spent.
    pub seconds: f64,
}

/// Rec. 709 luminance of linear RGB.
#[inline]
pub fn luminance(c: [f32; 3]) -> f64 {
    0.2126 * c[0] as f64 + 0.7152 * c[1] as f64 + 0.0722 * c[2] as f64
}

/// Adds the veiling glare of the image's bright pixels to the image (linear
/// RGB, row-major), taking the spread light out of the sources.
pub fn apply(
    pixels: &mut [[f32; 3]],
    width: u32,
    height: u32,
    settings: &GlareSettings,
) -> GlareStats {
    let start = std::time::Instant::now();
    let kernels: Vec<WeightedKernel> = settings
        .kernels
        .iter()
        .copied()
        .filter(|k| k.weight > 0.0)
        .collect();
    let sources: Vec<usize> = (0..pixels.len())
        .filter(|&i| luminance(pixels[i]) > settings.threshold)
        .collect();
    if sources.is_empty() || kernels.is_empty() {
        return GlareStats {
            seconds: start.elapsed().as_secs_f64(),
            ..GlareStats::default()
        };
    }
    let eps = settings.epsilon;
    let margin = kernels
        .iter()
        .map(|k| k.kernel.reach(eps))
        .fold(0.0, f64::max)
        .ceil();
    let (pw, ph) = (width as f64 + margin, height as f64 + margin);
    let shapes: Vec<Kernel> = kernels.iter().map(|k| k.kernel).collect();
    let (mm, nn) = FourierSeries::orders_for(&shapes, eps, pw, ph);
    let mut series = FourierSeries::new(pw, ph, mm, nn);

    // S_mn = Σ_sources L_s e^{−i(ω_m x_s + ν_n y_s)}, by rows: the sum over
    // a row's sources for every m, then each row's contribution for every n.
    let w = width as usize;
    let mut rows: Vec<(usize, Vec<usize>)> = Vec::new();
    for &i in &sources {
        let y = i / w;
        match rows.last_mut() {
            Some((ry, xs)) if *ry == y => xs.push(i % w),
            _ => rows.push((y, vec![i % w])),
        }
    }
    let row_sums: Vec<(usize, Vec<[C64; 3]>)> = rows
        .par_iter()
        .map(|(y, xs)| {
            let mut t = vec![[C64::new(0.0, 0.0); 3]; 2 * mm + 1];
            for &x in xs {
                let l = pixels[y * w + x];
                let xc = x as f64 + 0.5;
                for (j, m) in (-(mm as i64)..=mm as i64).enumerate() {
                    let p = C64::from_polar(1.0, -series.omega(m) * xc);
                    for c in 0..3 {
                        t[j][c] += p * l[c] as f64;
                    }
                }
            }
            (*y, t)
        })
        .collect();
    let mut transfer = vec![0.0; series.len()];
    for k in &kernels {
        let g = series.spectrum_grid(&k.kernel);
        let norm = k.weight / k.kernel.integral();
        for (t, v) in transfer.iter_mut().zip(g) {
            *t += norm * v;
        }
    }
    let width_m = 2 * mm + 1;
    let nu: Vec<f64> = (-(nn as i64)..=nn as i64).map(|n| series.nu(n)).collect();
    series
        .coefficients
        .par_chunks_mut(width_m)
        .enumerate()
        .for_each(|(row, chunk)| {
            for (y, t) in &row_sums {
                let py = C64::from_polar(1.0, -nu[row] * (*y as f64 + 0.5));
                for (j, c) in chunk.iter_mut().enumerate() {
                    for k in 0..3 {
                        c[k] += t[j][k] * py;
                    }
                }
            }
            for (j, c) in chunk.iter_mut().enumerate() {
                let f = transfer[row * width_m + j];
                for v in c.iter_mut() {
                    *v *= f;
                }
            }
        });
    let glare = series.evaluate_grid(width, height);
    let kept = 1.0 - kernels.iter().map(|k| k.weight).sum::<f64>();
    for &i in &sources {
        for v in pixels[i].iter_mut() {
            *v *= kept.max(0.0) as f32;
        }
    }
    for (p, g) in pixels.iter_mut().zip(glare) {
        for c in 0..3 {
            // The truncated series rings slightly below zero far from the
            // sources; light is never negative.
            p[c] = (p[c] as f64 + g[c]).max(0.0) as f32;
        }
    }
    GlareStats {
        sources: sources.len(),
        coefficients: series.len(),
        orders: (mm, nn),
        seconds: start.elapsed().as_secs_f64(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gaussian(x: f64, y: f64, a: f64, sigma: f64) -> Blob {
        Blob {
            x,
            y,
            amplitude: [a; 3],
            kernel: Kernel::Gaussian { sigma },
        }
    }

    fn series_of(blobs: &[Blob], eps: f64) -> FourierSeries {
        let (w, h) = (200.0, 120.0);
        let kernels: Vec<Kernel> = blobs.iter().map(|b| b.kernel).collect();
        let (m, n) = FourierSeries::orders_for(&kernels, eps, w, h);
        let mut s = FourierSeries::new(w, h, m, n);
        s.add_blobs(blobs);
        s
    }

    #[test]
    fn dc_coefficient_is_total_energy_over_area() {
        let blobs = [
            gaussian(50.0, 40.0, 2.0, 5.0),
            gaussian(120.0, 70.0, 0.5, 9.0),
        ];
        let s = series_of(&blobs, 1e-3);
        let want = (2.0 * 2.0 * PI * 25.0 + 0.5 * 2.0 * PI * 81.0) / (200.0 * 120.0);
        let c = s.coefficient(0, 0)[0];
        assert!(
            (c.re - want).abs() < 1e-14 && c.im.abs() < 1e-14,
            "{c} vs {want}"
        );
    }

    #[test]
    fn moving_a_blob_changes_only_phases() {
        let a = series_of(&[gaussian(50.0, 40.0, 1.0, 6.0)], 1e-3);
        let b = series_of(&[gaussian(131.3, 77.7, 1.0, 6.0)], 1e-3);
        let (mm, nn) = (a.order_x as i64, a.order_y as i64);
        for n in -nn..=nn {
            for m in -mm..=mm {
                let (ca, cb) = (a.coefficient(m, n)[0], b.coefficient(m, n)[0]);
                assert!((ca.norm() - cb.norm()).abs() < 1e-15);
                // …and by exactly the shift's phase.
                let shift = C64::from_polar(
                    1.0,
                    -(a.omega(m) * (131.3 - 50.0) + a.nu(n) * (77.7 - 40.0)),
                );
                assert!((ca * shift - cb).norm() < 1e-15);
            }
        }
    }

    #[test]
    fn coefficients_are_linear_in_blobs() {
        let blobs = [
            gaussian(30.0, 30.0, 1.0, 4.0),
            gaussian(100.0, 60.0, 3.0, 7.0),
            Blob {
                x: 150.0,
                y: 50.0,
                amplitude: [0.5, 1.0, 2.0],
                kernel: Kernel::Compact { radius: 25.0 },
            },
        ];
        let all = series_of(&blobs, 1e-3);
        let (m, n) = (all.order_x, all.order_y);
        let mut sum = FourierSeries::new(200.0, 120.0, m, n);
        for b in &blobs {
            let mut one = FourierSeries::new(200.0, 120.0, m, n);
            one.add_blobs(std::slice::from_ref(b));
            for (s, o) in sum.coefficients.iter_mut().zip(&one.coefficients) {
                for c in 0..3 {
                    s[c] += o[c];
                }
            }
        }
        for (a, b) in all.coefficients.iter().zip(&sum.coefficients) {
            for c in 0..3 {
                assert!((a[c] - b[c]).norm() < 1e-15);
            }
        }
    }

    #[test]
    fn parseval_for_one_gaussian() {
        let (a, sigma) = (1.7, 6.0);
        let s = series_of(&[gaussian(100.0, 60.0, a, sigma)], 1e-8);
        let energy: f64 = s.coefficients.iter().map(|c| c[0].norm_sqr()).sum();
        let lhs = 200.0 * 120.0 * energy;
        let rhs = a * a * PI * sigma * sigma;
        assert!((lhs / rhs - 1.0).abs() < 1e-6, "{lhs} vs {rhs}");
    }

    #[test]
    fn compact_kernel_transform_matches_quadrature() {
        // K̂(k) = 2π ∫₀^r K(u) J₀(ku) u du, with J₀ by its own integral.
        let r = 10.0;
        let kernel = Kernel::Compact { radius: r };
        for k in [0.0, 0.05, 0.3, 1.0, 2.5] {
            let n = 4000;
            let mut s = 0.0;
            for i in 0..n {
                let u = r * (i as f64 + 0.5) / n as f64;
                let mut j0 = 0.0;
                for t in 0..64 {
                    let th = 2.0 * PI * t as f64 / 64.0;
                    j0 += (k * u * th.sin()).cos();
                }
                j0 /= 64.0;
                s += kernel.value(u * u) * j0 * u;
            }
            let quad = 2.0 * PI * s * r / n as f64;
            let closed = kernel.spectrum(k);
            assert!(
                (quad - closed).abs() < 1e-6 * kernel.integral(),
                "k {k}: {quad} vs {closed}"
            );
        }
        assert!((kernel.spectrum(0.0) - kernel.integral()).abs() < 1e-12);
    }

    #[test]
    fn reconstruction_matches_brute_force_within_epsilon() {
        for eps in [1e-2, 1e-3, 1e-4] {
            let blobs = [
                gaussian(70.0, 50.0, 1.0, 4.0),
                gaussian(120.0, 65.0, 2.0, 8.0),
                Blob {
                    x: 100.0,
                    y: 60.0,
                    amplitude: [0.7; 3],
                    kernel: Kernel::Compact { radius: 30.0 },
                },
            ];
            let s = series_of(&blobs, eps);
            let peaks: f64 = blobs.iter().map(|b| b.amplitude[0]).sum();
            let grid = s.evaluate_grid(200, 120);
            let mut worst: f64 = 0.0;
            for y in 0..120 {
                for x in 0..200 {
                    let (xc, yc) = (x as f64 + 0.5, y as f64 + 0.5);
                    let brute: f64 = blobs
                        .iter()
                        .map(|b| {
                            b.amplitude[0] * b.kernel.value((xc - b.x).powi(2) + (yc - b.y).powi(2))
                        })
                        .sum();
                    worst = worst.max((grid[y * 200 + x][0] - brute).abs());
                }
            }
            // The single-point evaluation agrees with the grid.
            let p = s.evaluate(70.5, 50.5);
            assert!((p[0] - grid[50 * 200 + 70][0]).abs() < 1e-12);
            eprintln!("ε {eps:.0e}: worst error {worst:.2e} of Σ peaks {peaks}");
            assert!(worst <= eps * peaks, "ε {eps}: worst error {worst}");
        }
    }

    #[test]
    fn apply_spreads_light_and_conserves_it() {
        let (w, h) = (160u32, 100u32);
        let mut px = vec![[0.1f32; 3]; (w * h) as usize];
        px[(50 * w + 80) as usize] = [1000.0, 800.0, 600.0];
        let before: f64 = px.iter().map(|p| p[0] as f64).sum();
        let settings = GlareSettings {
            kernels: vec![
                WeightedKernel {
                    kernel: Kernel::Gaussian { sigma: 3.0 },
                    weight: 0.05,
                },
                WeightedKernel {
                    kernel: Kernel::Compact { radius: 20.0 },
                    weight: 0.02,
                },
            ],
            threshold: 50.0,
            epsilon: 1e-4,
        };
        let stats = apply(&mut px, w, h, &settings);
        assert_eq!(stats.sources, 1);
        let after: f64 = px.iter().map(|p| p[0] as f64).sum();
        assert!((after / before - 1.0).abs() < 1e-3, "{before} → {after}");
        // Brighter near the source, fading with distance, symmetric.
        let at = |x: u32, y: u32| px[(y * w + x) as usize][0];
        assert!(at(83, 50) > at(90, 50) && at(90, 50) > at(110, 50));
        assert!((at(83, 50) - at(77, 50)).abs() < 1e-3 * at(83, 50));
        assert!(at(150, 5) >= 0.1 - 1e-3 && at(150, 5) < 0.1 + 1e-3);
    }
}
