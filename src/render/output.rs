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

/// PNG bytes of a linear RGB image (row-major, top row first).
pub fn encode_png(width: u32, height: u32, pixels: &[[f32; 3]], tone: ToneMap) -> Result<Vec<u8>> {
    use image::ImageEncoder;
    use image::codecs::png::PngEncoder;
    use rayon::prelude::*;
    if pixels.len() != width as usize * height as usize {
        return Err(Error::encode(
            "the PNG",
            "the image buffer has the wrong size",
        ));
    }
    // Per channel a `powf`: on all threads, the same bytes in any order.
    let mut raw = vec![0u8; pixels.len() * 3];
    raw.par_chunks_mut(3)
        .zip(pixels.par_iter())
        .for_each(|(out, p)| {
            for k in 0..3 {
                out[k] = tone.apply(p[k]);
            }
        });
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
