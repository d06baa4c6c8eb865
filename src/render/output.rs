//! Image files: tone-mapped sRGB PNG and linear OpenEXR, encoded in memory so
//! that they can be written atomically.

use crate::error::{Error, Result};

/// Narkowicz's fit of the ACES filmic curve: highlights roll off instead of
/// clipping, so a bright sky and a sunlit wall both keep their detail.
#[inline]
fn aces(x: f64) -> f64 {
    let x = x.max(0.0);
    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

/// The sRGB transfer function of a linear value in [0, 1].
#[inline]
pub fn srgb_encode(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// How linear values become 8-bit sRGB.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ToneMap {
    /// Exposure, then the filmic curve (for shaded images).
    Filmic {
        /// Multiplies the radiance first.
        exposure: f64,
    },
    /// Clamp to [0, 1] only (albedo images keep their exact colours).
    Clamp,
}

impl ToneMap {
    /// The 8-bit sRGB value of one linear channel.
    #[inline]
    pub fn apply(self, x: f32) -> u8 {
        let v = match self {
            ToneMap::Filmic { exposure } => aces(x as f64 * exposure),
            ToneMap::Clamp => x as f64,
        };
        (srgb_encode(v) * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
    }
}

/// A tone map as 255 thresholds: the 8-bit value of x is the number of
/// thresholds at or below it, which is [`ToneMap::apply`]'s value exactly,
/// since that is a non-decreasing function of x (the filmic curve and the
/// sRGB transfer both rise; tests compare the two over the whole f32 range).
/// A table lookup and a step or two up the thresholds instead of a `powf`
/// per channel.
#[derive(Clone, Debug)]
struct Quantizer {
    /// `thresholds[k]`: the least finite x ≥ 0 that maps to k + 1 or more;
    /// +∞ where none does.
    thresholds: [f32; 255],
    /// `start[b]`: the number of thresholds at or below the float whose bits
    /// are `b << 16`, for every non-negative finite `b`. A float's level is
    /// at least that of its bucket's start; the buckets are 2⁻⁷ wide in
    /// relative terms, across which the curve climbs a level or two at most,
    /// so the walk up from there is short (and exact whatever its length).
    start: Box<[u8]>,
    /// For what is not finite (the filmic curve of +∞ is NaN, hence 0).
    tone: ToneMap,
}

/// The number of 2¹⁶-float buckets below +∞ (whose bits are 0x7F80_0000).
const FINITE_BUCKETS: u32 = 0x7F80;

impl Quantizer {
    fn new(tone: ToneMap) -> Self {
        let mut thresholds = [f32::INFINITY; 255];
        for (k, t) in thresholds.iter_mut().enumerate() {
            let level = k as u8 + 1;
            // Non-negative floats are ordered as their bit patterns; search
            // [0, f32::MAX] for the first one that reaches `level`.
            let (mut lo, mut hi) = (0u32, f32::MAX.to_bits());
            if tone.apply(f32::from_bits(hi)) < level {
                continue;
            }
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if tone.apply(f32::from_bits(mid)) >= level {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            *t = f32::from_bits(lo);
        }
        let start = (0..FINITE_BUCKETS)
            .map(|b| thresholds.partition_point(|&t| t <= f32::from_bits(b << 16)) as u8)
            .collect();
        Quantizer {
            thresholds,
            start,
            tone,
        }
    }

    /// The 8-bit value of `x`, as [`ToneMap::apply`] gives it.
    #[inline]
    fn apply(&self, x: f32) -> u8 {
        let bits = x.to_bits();
        if bits >> 16 < FINITE_BUCKETS {
            // Non-negative and finite: non-negative floats are ordered as
            // their bits, so the bucket's start is a lower bound.
            let mut k = self.start[(bits >> 16) as usize] as usize;
            while k < self.thresholds.len() && self.thresholds[k] <= x {
                k += 1;
            }
            k as u8
        } else if x.is_finite() {
            self.thresholds.partition_point(|&t| t <= x) as u8
        } else {
            self.tone.apply(x)
        }
    }
}

/// The 8-bit sRGB values of linear RGB pixels, three per pixel in their
/// order: what [`encode_png`] writes.
pub fn to_srgb8(pixels: &[[f32; 3]], tone: ToneMap) -> Vec<u8> {
    use rayon::prelude::*;
    // On all threads, the same bytes in any order.
    let quantizer = Quantizer::new(tone);
    let mut raw = vec![0u8; pixels.len() * 3];
    raw.par_chunks_mut(3)
        .zip(pixels.par_iter())
        .for_each(|(out, p)| {
            for k in 0..3 {
                out[k] = quantizer.apply(p[k]);
            }
        });
    raw
}

/// PNG bytes of a linear RGB image (row-major, top row first).
pub fn encode_png(width: u32, height: u32, pixels: &[[f32; 3]], tone: ToneMap) -> Result<Vec<u8>> {
    use image::ImageEncoder;
    use image::codecs::png::PngEncoder;
    if pixels.len() != width as usize * height as usize {
        return Err(Error::encode(
            "the PNG",
            "the image buffer has the wrong size",
        ));
    }
    let raw = to_srgb8(pixels, tone);
    let mut bytes = Vec::new();
    PngEncoder::new(&mut bytes)
        .write_image(&raw, width, height, image::ExtendedColorType::Rgb8)
        .map_err(|e| Error::encode("the PNG", e))?;
    Ok(bytes)
}

/// OpenEXR bytes (32-bit float R, G, B, linear) of an image.
pub fn encode_exr(width: u32, height: u32, pixels: &[[f32; 3]]) -> Result<Vec<u8>> {
    use exr::prelude::*;
    let w = width as usize;
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let p = pixels[y * w + x];
        (p[0], p[1], p[2])
    });
    let image = Image::from_channels((w, height as usize), channels);
    let mut bytes = std::io::Cursor::new(Vec::new());
    image
        .write()
        .to_buffered(&mut bytes)
        .map_err(|e| crate::error::Error::encode("the EXR", e))?;
    Ok(bytes.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The thresholds give `apply`'s value for every f32 tried: a stride
    /// through all non-negative floats, every float within 64 ulps of each
    /// threshold, both sides of every bucket edge, the negatives, ±∞ and
    /// NaN, for both tone maps.
    #[test]
    fn quantizer_equals_apply() {
        for tone in [
            ToneMap::Filmic { exposure: 1.0 },
            ToneMap::Filmic { exposure: 3.7 },
            ToneMap::Clamp,
        ] {
            let q = Quantizer::new(tone);
            let mut xs: Vec<f32> = (0..=f32::MAX.to_bits())
                .step_by(2039)
                .map(f32::from_bits)
                .collect();
            for t in q.thresholds.iter().filter(|t| t.is_finite()) {
                let b = t.to_bits();
                xs.extend((b.saturating_sub(64)..b + 64).map(f32::from_bits));
            }
            // Both sides of every bucket edge of the lookup table.
            for b in 1..FINITE_BUCKETS {
                xs.extend([b << 16, (b << 16) - 1].map(f32::from_bits));
            }
            xs.extend([
                -1.0,
                -0.0,
                -1e30,
                f32::NEG_INFINITY,
                f32::INFINITY,
                f32::NAN,
            ]);
            for x in xs {
                assert_eq!(q.apply(x), tone.apply(x), "{tone:?} at {x:e}");
            }
            // Every level is reached (the curve spans 0..=255).
            assert!(q.thresholds.iter().all(|t| t.is_finite()), "{tone:?}");
            assert!(q.thresholds.windows(2).all(|w| w[0] < w[1]));
        }
    }
}
