//! Image comparison: how far one render is from a reference (`mirage compare`).
//!
//! Both images are read as linear RGB:
//!
//! | file | read as |
//! | --- | --- |
//! | `.exr` | the R, G, B channels as stored (linear; alpha ignored) |
//! | `.png` | 8- or 16-bit sRGB, decoded to linear with the sRGB transfer function, so that a PNG and an EXR of the same albedo render compare like with like (mirage's albedo PNG is the clamped linear value, sRGB-encoded) |
//! | `.npy` | `float32`, `float64` or `uint8` (÷ 255, no decoding), C order, shape (H, W), (H, W, 3) or (H, W, 4) (alpha dropped; a grey image is used for all three channels) |
//!
//! Metrics, over all pixels and channels:
//!
//! - **RMSE**: √(mean of the squared channel differences).
//! - **PSNR**: 20·log10(peak / RMSE) dB with peak 1 (linear albedo and sky
//!   radiance live in [0, 1]); infinite for identical images (`null` in JSON).
//! - **SSIM** (Wang, Bovik, Sheikh & Simoncelli 2004): on the luminance
//!   Y = 0.2126 R + 0.7152 G + 0.0722 B, an 11 × 11 Gaussian window with σ = 1.5,
//!   K1 = 0.01, K2 = 0.03, dynamic range 1; the mean of the SSIM map over every
//!   pixel, where near the border the window is cut to the image and its weights
//!   renormalised (so that images smaller than the window still get a value).
//! - **share over threshold**: the fraction of pixels whose largest channel
//!   difference exceeds the threshold (default 0.05).
//!
//! The heat map shows each pixel's largest channel difference on a black → red →
//! yellow → white ramp from 0 to twice the threshold (clipped there): a pixel is
//! over the threshold exactly when it is past the orange at the middle of the ramp.

use crate::error::{Error, FieldError, Result};
use crate::io::{Output, OutputKind, check_outputs, write_atomic, write_json};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Default per-pixel threshold (largest channel difference).
pub const DEFAULT_THRESHOLD: f64 = 0.05;

/// A linear RGB image, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearImage {
    /// Width (pixels).
    pub width: usize,
    /// Height (pixels).
    pub height: usize,
    /// Linear RGB per pixel.
    pub pixels: Vec<[f64; 3]>,
}

/// The numbers `mirage compare` reports.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Metrics {
    /// Width (pixels).
    pub width: usize,
    /// Height (pixels).
    pub height: usize,
    /// Root-mean-square channel difference.
    pub rmse: f64,
    /// Peak signal-to-noise ratio (dB, peak 1); `None` for identical images.
    pub psnr_db: Option<f64>,
    /// Mean structural similarity of the luminance.
    pub ssim: f64,
    /// The largest channel difference of any pixel.
    pub max_difference: f64,
    /// The per-pixel threshold used for `share_over`.
    pub threshold: f64,
    /// Fraction of pixels whose largest channel difference exceeds `threshold`.
    pub share_over: f64,
}

/// Limits that make `mirage compare` fail (exit code 1) when missed.
#[derive(Clone, Copy, Debug, Default, PartialEq, clap::Args)]
pub struct Limits {
    /// Fail (exit code 1) if the RMSE is above this.
    #[arg(long, value_parser = finite)]
    pub max_rmse: Option<f64>,
    /// Fail if the PSNR (dB) is below this.
    #[arg(long, value_parser = finite)]
    pub min_psnr: Option<f64>,
    /// Fail if the SSIM is below this.
    #[arg(long, value_parser = finite)]
    pub min_ssim: Option<f64>,
    /// Fail if the share of pixels over the threshold (0 to 1) is above this.
    #[arg(long, value_parser = finite)]
    pub max_share_over: Option<f64>,
}

/// A limit: any finite number.
fn finite(s: &str) -> std::result::Result<f64, crate::error::ValueError> {
    match s
        .parse::<f64>()
        .map_err(|_| crate::error::ValueError::NotANumber {
            value: s.to_string(),
        })? {
        v if v.is_finite() => Ok(v),
        v => Err(crate::error::ValueError::OutOfRange {
            rule: format!("must be a finite number, got {v}"),
        }),
    }
}

/// `--threshold`: a finite number > 0.
fn threshold(s: &str) -> std::result::Result<f64, crate::error::ValueError> {
    match s
        .parse::<f64>()
        .map_err(|_| crate::error::ValueError::NotANumber {
            value: s.to_string(),
        })? {
        v if v.is_finite() && v > 0.0 => Ok(v),
        v => Err(crate::error::ValueError::OutOfRange {
            rule: format!("must be a finite number > 0, got {v}"),
        }),
    }
}

impl Limits {
    /// The limits `m` misses, in words (empty: all met).
    pub fn missed(&self, m: &Metrics) -> Vec<String> {
        let mut out = Vec::new();
        if let Some(l) = self.max_rmse
            && m.rmse > l
        {
            out.push(format!("RMSE {:.5} > {l}", m.rmse));
        }
        if let Some(l) = self.min_psnr
            && m.psnr_db.is_some_and(|p| p < l)
        {
            out.push(format!("PSNR {:.2} dB < {l} dB", m.psnr_db.unwrap_or(0.0)));
        }
        if let Some(l) = self.min_ssim
            && m.ssim < l
        {
            out.push(format!("SSIM {:.5} < {l}", m.ssim));
        }
        if let Some(l) = self.max_share_over
            && m.share_over > l
        {
            out.push(format!(
                "{:.3} % of pixels over {} > {:.3} %",
                100.0 * m.share_over,
                m.threshold,
                100.0 * l
            ));
        }
        out
    }
}

/// The sRGB transfer function inverted: an encoded value in [0, 1] to linear.
#[inline]
pub fn srgb_decode(x: f64) -> f64 {
    if x <= 0.040_45 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// Reads a PNG, EXR or NPY image as linear RGB (see the module documentation).
/// Any failure is an input error naming the file.
pub fn load(path: &Path) -> Result<LinearImage> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let image = match ext.as_deref() {
        Some("png") => load_png(path)?,
        Some("exr") => load_exr(path)?,
        Some("npy") => {
            let bytes = std::fs::read(path)
                .map_err(|e| Error::input(path, "-", format!("cannot read the file: {e}")))?;
            parse_npy(&bytes).map_err(|e| e.in_file(path))?
        }
        _ => {
            return Err(Error::input(
                path,
                "-",
                "unsupported image format: expected .png, .exr or .npy",
            ));
        }
    };
    if image.width == 0 || image.height == 0 {
        return Err(Error::input(path, "-", "the image is empty"));
    }
    if let Some(i) = image
        .pixels
        .iter()
        .position(|p| p.iter().any(|c| !c.is_finite()))
    {
        return Err(Error::input(
            path,
            "-",
            format!(
                "pixel ({}, {}) is not finite",
                i % image.width,
                i / image.width
            ),
        ));
    }
    Ok(image)
}

fn load_png(path: &Path) -> Result<LinearImage> {
    let bytes = std::fs::read(path)
        .map_err(|e| Error::input(path, "-", format!("cannot read the file: {e}")))?;
    let img = image::load_from_memory_with_format(&bytes, image::ImageFormat::Png)
        .map_err(|e| Error::input(path, "-", format!("not a readable PNG: {e}")))?
        .to_rgb32f();
    let (w, h) = img.dimensions();
    let pixels = img
        .pixels()
        .map(|p| p.0.map(|c| srgb_decode(c as f64)))
        .collect();
    Ok(LinearImage {
        width: w as usize,
        height: h as usize,
        pixels,
    })
}

fn load_exr(path: &Path) -> Result<LinearImage> {
    use exr::prelude::*;
    let read = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |size: Vec2<usize>, _: &RgbaChannels| {
                (size.0, size.1, vec![[0.0f64; 3]; size.0 * size.1])
            },
            |(w, _, px): &mut (usize, usize, Vec<[f64; 3]>),
             pos: Vec2<usize>,
             (r, g, b, _a): (f32, f32, f32, f32)| {
                px[pos.1 * *w + pos.0] = [r as f64, g as f64, b as f64];
            },
        )
        .first_valid_layer()
        .all_attributes()
        .non_parallel()
        .from_file(path)
        .map_err(|e| {
            crate::error::Error::input(path, "-", format!("not a readable RGB EXR: {e}"))
        })?;
    let (width, height, pixels) = read.layer_data.channel_data.pixels;
    Ok(LinearImage {
        width,
        height,
        pixels,
    })
}

/// Parses the bytes of a NumPy `.npy` file (read by the `npyz` crate) holding
/// a C-ordered (H, W), (H, W, 3) or (H, W, 4) array of `f4`, `f8` or `u1`
/// (either byte order).
pub fn parse_npy(bytes: &[u8]) -> std::result::Result<LinearImage, FieldError> {
    use npyz::{DType, Order, TypeChar};
    let npy = npyz::NpyFile::new(bytes)
        .map_err(|e| FieldError::whole(format!("not a readable .npy file: {e}")))?;
    if npy.order() == Order::Fortran {
        return Err(FieldError::whole(
            "Fortran-ordered arrays are not supported (save a C-ordered array)",
        ));
    }
    let shape: Vec<usize> = npy.shape().iter().map(|&d| d as usize).collect();
    let (h, w, c) = match shape[..] {
        [h, w] => (h, w, 1),
        [h, w, c] if c == 3 || c == 4 => (h, w, c),
        _ => {
            return Err(FieldError::whole(format!(
                "shape {shape:?}: expected (H, W), (H, W, 3) or (H, W, 4)"
            )));
        }
    };
    let bad = |e: std::io::Error| match e.kind() {
        std::io::ErrorKind::UnexpectedEof => FieldError::whole(format!(
            "truncated data: fewer values than the shape {shape:?} holds"
        )),
        _ => FieldError::whole(format!("cannot read the .npy data: {e}")),
    };
    let values: Vec<f64> = match npy.dtype() {
        DType::Plain(t) => match (t.type_char(), t.size_field()) {
            (TypeChar::Float, 4) => npy
                .into_vec::<f32>()
                .map_err(bad)?
                .into_iter()
                .map(f64::from)
                .collect(),
            (TypeChar::Float, 8) => npy.into_vec::<f64>().map_err(bad)?,
            (TypeChar::Uint, 1) => npy
                .into_vec::<u8>()
                .map_err(bad)?
                .into_iter()
                .map(|v| v as f64 / 255.0)
                .collect(),
            _ => {
                return Err(FieldError::whole(format!(
                    "dtype `{t}`: expected float32 (<f4), float64 (<f8) or uint8 (|u1)"
                )));
            }
        },
        other => {
            return Err(FieldError::whole(format!(
                "dtype {other:?}: expected a plain float32, float64 or uint8 array"
            )));
        }
    };
    if values.len() != h * w * c {
        return Err(FieldError::whole(format!(
            "{} values for shape {shape:?}",
            values.len()
        )));
    }
    let pixels = values
        .chunks_exact(c)
        .map(|v| {
            if c == 1 {
                [v[0]; 3]
            } else {
                [v[0], v[1], v[2]]
            }
        })
        .collect();
    Ok(LinearImage {
        width: w,
        height: h,
        pixels,
    })
}

fn luminance(p: &[f64; 3]) -> f64 {
    0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]
}

/// Mean SSIM of the luminance of two images of the same size (see the module
/// documentation for the window and constants).
pub fn ssim(a: &LinearImage, b: &LinearImage) -> f64 {
    const RADIUS: isize = 5;
    const SIGMA: f64 = 1.5;
    let (c1, c2) = ((0.01f64).powi(2), (0.03f64).powi(2));
    let kernel: Vec<f64> = (-RADIUS..=RADIUS)
        .map(|i| (-((i * i) as f64) / (2.0 * SIGMA * SIGMA)).exp())
        .collect();
    let (w, h) = (a.width as isize, a.height as isize);
    let ya: Vec<f64> = a.pixels.iter().map(luminance).collect();
    let yb: Vec<f64> = b.pixels.iter().map(luminance).collect();
    let mut total = 0.0;
    for y in 0..h {
        for x in 0..w {
            let (mut sw, mut ma, mut mb, mut aa, mut bb, mut ab) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
            for dy in -RADIUS..=RADIUS {
                let yy = y + dy;
                if yy < 0 || yy >= h {
                    continue;
                }
                for dx in -RADIUS..=RADIUS {
                    let xx = x + dx;
                    if xx < 0 || xx >= w {
                        continue;
                    }
                    let k = kernel[(dy + RADIUS) as usize] * kernel[(dx + RADIUS) as usize];
                    let i = (yy * w + xx) as usize;
                    let (p, q) = (ya[i], yb[i]);
                    sw += k;
                    ma += k * p;
                    mb += k * q;
                    aa += k * p * p;
                    bb += k * q * q;
                    ab += k * p * q;
                }
            }
            let (ma, mb) = (ma / sw, mb / sw);
            let va = (aa / sw - ma * ma).max(0.0);
            let vb = (bb / sw - mb * mb).max(0.0);
            let cov = ab / sw - ma * mb;
            total += ((2.0 * ma * mb + c1) * (2.0 * cov + c2))
                / ((ma * ma + mb * mb + c1) * (va + vb + c2));
        }
    }
    total / (w * h) as f64
}

/// Each pixel's largest channel difference.
fn pixel_differences(a: &LinearImage, b: &LinearImage) -> Vec<f64> {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| (0..3).map(|c| (p[c] - q[c]).abs()).fold(0.0, f64::max))
        .collect()
}

/// The metrics of `ours` against `reference` (same size; checked by the caller).
pub fn metrics(ours: &LinearImage, reference: &LinearImage, threshold: f64) -> Metrics {
    let n = ours.pixels.len();
    let sq: f64 = ours
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(p, q)| (0..3).map(|c| (p[c] - q[c]).powi(2)).sum::<f64>())
        .sum();
    let rmse = (sq / (3 * n) as f64).sqrt();
    let diffs = pixel_differences(ours, reference);
    Metrics {
        width: ours.width,
        height: ours.height,
        rmse,
        psnr_db: (rmse > 0.0).then(|| -20.0 * rmse.log10()),
        ssim: ssim(ours, reference),
        max_difference: diffs.iter().copied().fold(0.0, f64::max),
        threshold,
        share_over: diffs.iter().filter(|&&d| d > threshold).count() as f64 / n as f64,
    }
}

/// The heat-map colour of a difference `d` on a ramp ending at `top`.
fn heat(d: f64, top: f64) -> [u8; 3] {
    let t = (d / top).clamp(0.0, 1.0) * 3.0;
    let ch = |v: f64| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    [ch(t), ch(t - 1.0), ch(t - 2.0)]
}

/// PNG bytes of the difference heat map (see the module documentation).
pub fn heat_map_png(
    ours: &LinearImage,
    reference: &LinearImage,
    threshold: f64,
) -> Result<Vec<u8>> {
    let raw: Vec<u8> = pixel_differences(ours, reference)
        .into_iter()
        .flat_map(|d| heat(d, 2.0 * threshold))
        .collect();
    let img = image::RgbImage::from_raw(ours.width as u32, ours.height as u32, raw)
        .ok_or_else(|| Error::encode("the heat map", "the image buffer has the wrong size"))?;
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, image::ImageFormat::Png)
        .map_err(|e| Error::encode("the heat map", e))?;
    Ok(bytes.into_inner())
}

/// Compare an image with a reference: RMSE, PSNR, SSIM, share of pixels over a threshold.
#[derive(Clone, Debug, Default, PartialEq, clap::Args)]
pub struct CompareOptions {
    /// Our image (.png, .exr or .npy).
    pub ours: PathBuf,
    /// The reference image (.png, .exr or .npy).
    pub reference: PathBuf,
    /// A pixel differs when its largest channel difference exceeds this.
    #[arg(long, value_parser = threshold)]
    pub threshold: Option<f64>,
    /// Write the difference heat map here (.png).
    #[arg(long)]
    pub diff: Option<PathBuf>,
    /// Write the metrics as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Limits that fail the command when missed.
    #[command(flatten)]
    pub limits: Limits,
}

/// The terminal lines of a comparison.
pub fn table(m: &Metrics) -> String {
    let psnr = match m.psnr_db {
        Some(p) => format!("{p:.2} dB"),
        None => "inf (identical)".into(),
    };
    format!(
        "{}×{} px   RMSE {:.5}   PSNR {psnr}   SSIM {:.5}   max difference {:.4}   over {}: {:.3} % of pixels\n",
        m.width,
        m.height,
        m.rmse,
        m.ssim,
        m.max_difference,
        m.threshold,
        100.0 * m.share_over
    )
}

/// `mirage compare`: reads both images, prints the metrics, writes the heat map
/// and JSON if asked, and fails (exit code 1) when a limit is missed; the
/// outputs are written first, so a failed comparison still leaves its evidence.
pub fn compare_command(o: &CompareOptions) -> Result<Metrics> {
    let threshold = o.threshold.unwrap_or(DEFAULT_THRESHOLD);
    let inputs = [o.ours.as_path(), o.reference.as_path()];
    check_outputs(
        [
            Output::optional("--diff", o.diff.as_ref(), OutputKind::Png("the heat map")),
            Output::optional("--json", o.json.as_ref(), OutputKind::Any),
        ]
        .into_iter()
        .flatten(),
        &inputs,
    )?;
    let ours = load(&o.ours)?;
    let reference = load(&o.reference)?;
    if (ours.width, ours.height) != (reference.width, reference.height) {
        return Err(Error::input(
            &o.reference,
            "-",
            format!(
                "size {}×{} differs from {} ({}×{})",
                reference.width,
                reference.height,
                o.ours.display(),
                ours.width,
                ours.height
            ),
        ));
    }
    let m = metrics(&ours, &reference, threshold);
    if let Some(d) = &o.diff {
        write_atomic(d, &heat_map_png(&ours, &reference, threshold)?)?;
    }
    if let Some(j) = &o.json {
        write_json(j, &m)?;
    }
    print!("{}", table(&m));
    let missed = o.limits.missed(&m);
    if !missed.is_empty() {
        return Err(Error::LimitsMissed {
            subject: format!("{} vs {}", o.ours.display(), o.reference.display()),
            missed,
        });
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn constant(w: usize, h: usize, v: [f64; 3]) -> LinearImage {
        LinearImage {
            width: w,
            height: h,
            pixels: vec![v; w * h],
        }
    }

    fn ramp(w: usize, h: usize) -> LinearImage {
        LinearImage {
            width: w,
            height: h,
            pixels: (0..w * h)
                .map(|i| {
                    let (x, y) = ((i % w) as f64, (i / w) as f64);
                    [
                        x / w as f64,
                        y / h as f64,
                        ((x * 7.0 + y * 3.0) % 5.0) / 5.0,
                    ]
                })
                .collect(),
        }
    }

    #[test]
    fn identical_images_are_perfect() {
        let a = ramp(23, 17);
        let m = metrics(&a, &a, 0.05);
        assert_eq!(m.rmse, 0.0);
        assert_eq!(m.psnr_db, None);
        assert!((m.ssim - 1.0).abs() < 1e-12, "{}", m.ssim);
        assert_eq!(m.share_over, 0.0);
        assert!(table(&m).contains("inf (identical)"));
    }

    #[test]
    fn constant_offset_gives_known_rmse_and_psnr() {
        let a = constant(16, 12, [0.2, 0.4, 0.6]);
        let b = constant(16, 12, [0.3, 0.5, 0.7]);
        let m = metrics(&a, &b, 0.05);
        assert!((m.rmse - 0.1).abs() < 1e-12);
        assert!((m.psnr_db.unwrap() - 20.0).abs() < 1e-9);
        assert_eq!(m.share_over, 1.0);
        assert!((m.max_difference - 0.1).abs() < 1e-12);
        // Below the threshold: no pixel counts.
        assert_eq!(metrics(&a, &b, 0.11).share_over, 0.0);
    }

    #[test]
    fn one_channel_offset_averages_over_channels() {
        let a = constant(8, 8, [0.5, 0.5, 0.5]);
        let b = constant(8, 8, [0.5, 0.5, 0.5 + 0.03]);
        let m = metrics(&a, &b, 0.05);
        assert!((m.rmse - 0.03 / 3f64.sqrt()).abs() < 1e-12);
        assert_eq!(m.share_over, 0.0);
    }

    #[test]
    fn ssim_of_constant_images_follows_the_luminance_term() {
        // Flat windows: variances and covariance vanish, SSIM is the luminance
        // term (2·μa·μb + C1) / (μa² + μb² + C1).
        let a = constant(12, 12, [0.5; 3]);
        let b = constant(12, 12, [0.25; 3]);
        let c1 = 0.0001;
        let expect = (2.0 * 0.5 * 0.25 + c1) / (0.25 + 0.0625 + c1);
        assert!((ssim(&a, &b) - expect).abs() < 1e-12);
    }

    #[test]
    fn ssim_falls_with_noise_and_is_symmetric() {
        let a = ramp(32, 24);
        let mut b = a.clone();
        for (i, p) in b.pixels.iter_mut().enumerate() {
            let s = if (i * 7919) % 3 == 0 { 0.2 } else { -0.1 };
            p.iter_mut().for_each(|c| *c += s);
        }
        let s = ssim(&a, &b);
        assert!(s < 0.95 && s > 0.0, "{s}");
        assert!((s - ssim(&b, &a)).abs() < 1e-12);
    }

    #[test]
    fn share_over_counts_pixels_not_channels() {
        let a = constant(10, 10, [0.0; 3]);
        let mut b = a.clone();
        b.pixels[3] = [0.0, 0.2, 0.0];
        b.pixels[7] = [0.06, 0.06, 0.06];
        let m = metrics(&a, &b, 0.05);
        assert!((m.share_over - 0.02).abs() < 1e-12);
    }

    #[test]
    fn limits_report_what_is_missed() {
        let m = metrics(&constant(4, 4, [0.0; 3]), &constant(4, 4, [0.1; 3]), 0.05);
        let ok = Limits {
            max_rmse: Some(0.2),
            min_psnr: Some(15.0),
            min_ssim: None,
            max_share_over: Some(1.0),
        };
        assert!(ok.missed(&m).is_empty());
        let strict = Limits {
            max_rmse: Some(0.01),
            min_psnr: Some(35.0),
            min_ssim: None,
            max_share_over: Some(0.01),
        };
        assert_eq!(strict.missed(&m).len(), 3);
    }

    #[test]
    fn srgb_round_trip() {
        for i in 0..=100 {
            let x = i as f64 / 100.0;
            let back = srgb_decode(crate::render::output::srgb_encode(x));
            assert!((back - x).abs() < 1e-12, "{x} {back}");
        }
    }

    fn npy(descr: &str, shape: &str, data: &[u8]) -> Vec<u8> {
        let mut header =
            format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
        while (10 + header.len() + 1) % 64 != 0 {
            header.push(' ');
        }
        header.push('\n');
        let mut out = b"\x93NUMPY\x01\x00".to_vec();
        out.extend((header.len() as u16).to_le_bytes());
        out.extend(header.as_bytes());
        out.extend(data);
        out
    }

    #[test]
    fn npy_float32_rgb_and_grey_uint8() {
        let vals: Vec<u8> = [0.1f32, 0.2, 0.3, 0.4, 0.5, 0.6]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        let img = parse_npy(&npy("<f4", "(1, 2, 3)", &vals)).unwrap();
        assert_eq!((img.width, img.height), (2, 1));
        assert!((img.pixels[1][2] - 0.6).abs() < 1e-7);
        let grey = parse_npy(&npy("|u1", "(2, 1)", &[0, 255])).unwrap();
        assert_eq!(grey.pixels, vec![[0.0; 3], [1.0; 3]]);
    }

    #[test]
    fn npy_errors_are_clear() {
        assert!(parse_npy(b"hello").unwrap_err().message.contains("magic"));
        let e = parse_npy(&npy("<i8", "(1, 1)", &[0; 8])).unwrap_err();
        assert!(e.message.contains("dtype"), "{e}");
        let e = parse_npy(&npy("<f8", "(2, 2, 2)", &[0; 64])).unwrap_err();
        assert!(e.message.contains("shape"), "{e}");
        let e = parse_npy(&npy("<f8", "(2, 2)", &[0; 8])).unwrap_err();
        assert!(e.message.contains("truncated"), "{e}");
    }

    #[test]
    fn heat_map_is_red_at_the_threshold() {
        assert_eq!(heat(0.0, 0.1), [0, 0, 0]);
        assert_eq!(heat(0.05, 0.1), [255, 128, 0]);
        assert_eq!(heat(1.0, 0.1), [255, 255, 255]);
    }
}
