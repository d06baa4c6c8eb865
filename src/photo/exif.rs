//! The focal length in pixels from a photo's EXIF, and writing such EXIF.
//!
//! [`focal_from_exif`] reads the EXIF of a JPEG (APP1 segment) or PNG
//! (`eXIf` chunk) with the `kamadak-exif` crate and turns it into a focal
//! length f in pixels of the stored image (W × H), by the first route that
//! has usable tags:
//!
//! 1. `FocalLengthIn35mmFilm` f35 (mm): f = f35 · √(W² + H²) / 43.2666, the
//!    35 mm frame's diagonal being 43.2666 mm. This assumes the photo is the
//!    camera's whole frame (a cropped photo gives too short a focal length).
//! 2. `FocalLength` F (mm) with `FocalPlaneXResolution` R (sensor pixels per
//!    unit) and `FocalPlaneResolutionUnit` (2 = inch, the default when
//!    absent; 3 = cm; 4 = mm; 5 = µm): f = F · R / (mm per unit). R counts the
//!    camera's pixels, so when the stored image was resized without its EXIF
//!    being updated (its `PixelXDimension` differs from W), f is scaled by
//!    W / `PixelXDimension`; a stored image turned by 90° (W and H equal to
//!    `PixelYDimension` and `PixelXDimension`) is not scaled.
//!
//! The result is exact arithmetic on the stored rationals (f64 rounding
//! only); how well it matches the lens is the camera's business (focal
//! lengths in EXIF are often rounded to a millimetre, and zooms and focus
//! breathing change the true value by a few per cent).
//!
//! A tag is *unusable* when it is missing, of a non-numeric type, zero,
//! negative or not finite (a rational over 0); an unusable tag sends the
//! reader to the next route, and when no route is usable the answer is
//! `Ok(None)`, as it is for a file without EXIF or for bytes that are not a
//! JPEG or PNG. `Err` is kept for EXIF that is there but cannot be read (a
//! broken TIFF structure, a JPEG cut before its end, or an EXIF read only in
//! part whose readable part has no usable tags), so that the user can be told
//! why the photo's own focal length was not used. No input panics: the
//! function is meant to be fuzzed.
//!
//! [`write_focal_exif`] does the reverse for test photos and the bundled
//! example: it encodes the tags of a [`FocalTags`] as an EXIF block
//! (`kamadak-exif`'s writer) and inserts it as an APP1 segment right after a
//! JPEG's SOI marker.

use exif::experimental::Writer;
use exif::{Field, In, Rational, Reader, Tag, Value};
use std::io::Cursor;

/// A focal length in pixels read from EXIF, and where it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct ExifFocal {
    /// Focal length f in pixels of the stored image.
    pub pixels: f64,
    /// The tags it was computed from, for messages and the result file
    /// (`EXIF FocalLengthIn35mmFilm = 200 mm`).
    pub source: String,
}

/// EXIF that cannot be read, or written.
#[derive(Debug, thiserror::Error)]
pub enum ExifError {
    /// The file has EXIF (or claims to) that cannot be read.
    #[error("its EXIF cannot be read: {0}")]
    Unreadable(#[source] exif::Error),
    /// [`write_focal_exif`] was given bytes that do not start with a JPEG SOI
    /// marker.
    #[error("cannot embed EXIF: the bytes are not a JPEG (no SOI marker)")]
    NotJpeg,
    /// [`write_focal_exif`] was given a value that no EXIF type holds.
    #[error("cannot write EXIF {tag} = {value}: not a finite number in 0 … 4294967295")]
    Unrepresentable {
        /// The tag's name.
        tag: &'static str,
        /// The value given.
        value: f64,
    },
    /// The EXIF encoder failed.
    #[error("cannot encode the EXIF block: {0}")]
    Encode(#[source] exif::Error),
}

/// JPEG's start-of-image marker.
const JPEG_SOI: [u8; 2] = [0xff, 0xd8];
/// PNG's signature.
const PNG_SIG: [u8; 8] = *b"\x89PNG\r\n\x1a\n";
/// The diagonal of the 35 mm frame (36 × 24 mm), mm.
const FRAME_35MM_DIAGONAL: f64 = 43.2666;
/// The most bytes an APP1 segment holds after its length field.
const APP1_MAX: usize = 65533;

/// Reads the focal length in pixels of a W × H photo from the EXIF in its
/// file's `bytes` (the routes and what counts as usable are in the module
/// notes). `Ok(None)`: no EXIF or no usable tags; `Err`: EXIF that is there
/// but unreadable.
pub fn focal_from_exif(
    bytes: &[u8],
    width: u32,
    height: u32,
) -> Result<Option<ExifFocal>, ExifError> {
    if !(bytes.starts_with(&JPEG_SOI) || bytes.starts_with(&PNG_SIG)) {
        return Ok(None);
    }
    let mut reader = Reader::new();
    reader.continue_on_error(true);
    let (exif, damage) = match reader.read_from_container(&mut Cursor::new(bytes)) {
        Ok(exif) => (exif, None),
        Err(exif::Error::NotFound(_)) => return Ok(None),
        Err(exif::Error::PartialResult(partial)) => {
            let (exif, errors) = partial.into_inner();
            (exif, errors.into_iter().next())
        }
        Err(e) => return Err(ExifError::Unreadable(e)),
    };
    let tags = Tags::from_exif(&exif);
    match (focal_from_tags(&tags, width, height), damage) {
        (Some(mut focal), Some(_)) => {
            focal.source.push_str(" (from an EXIF read only in part)");
            Ok(Some(focal))
        }
        (Some(focal), None) => Ok(Some(focal)),
        (None, Some(e)) => Err(ExifError::Unreadable(e)),
        (None, None) => Ok(None),
    }
}

/// The tags the routes use, as numbers (`None` where missing or not
/// numeric).
#[derive(Clone, Copy, Debug, Default)]
struct Tags {
    focal_35mm: Option<f64>,
    focal_length: Option<f64>,
    x_resolution: Option<f64>,
    resolution_unit: Option<f64>,
    pixel_x: Option<f64>,
    pixel_y: Option<f64>,
}

impl Tags {
    fn from_exif(exif: &exif::Exif) -> Tags {
        let get = |tag| {
            exif.get_field(tag, In::PRIMARY)
                .and_then(|f| first_number(&f.value))
        };
        Tags {
            focal_35mm: get(Tag::FocalLengthIn35mmFilm),
            focal_length: get(Tag::FocalLength),
            x_resolution: get(Tag::FocalPlaneXResolution),
            resolution_unit: get(Tag::FocalPlaneResolutionUnit),
            pixel_x: get(Tag::PixelXDimension),
            pixel_y: get(Tag::PixelYDimension),
        }
    }
}

/// The first element of a numeric value, as f64 (a rational over zero gives
/// an infinity or NaN, which [`usable`] refuses).
fn first_number(value: &Value) -> Option<f64> {
    match value {
        Value::Byte(v) => v.first().map(|&x| f64::from(x)),
        Value::Short(v) => v.first().map(|&x| f64::from(x)),
        Value::Long(v) => v.first().map(|&x| f64::from(x)),
        Value::SByte(v) => v.first().map(|&x| f64::from(x)),
        Value::SShort(v) => v.first().map(|&x| f64::from(x)),
        Value::SLong(v) => v.first().map(|&x| f64::from(x)),
        Value::Rational(v) => v.first().map(|r| r.to_f64()),
        Value::SRational(v) => v.first().map(|r| r.to_f64()),
        Value::Float(v) => v.first().map(|&x| f64::from(x)),
        Value::Double(v) => v.first().copied(),
        Value::Ascii(_) | Value::Undefined(..) | Value::Unknown(..) => None,
    }
}

/// `x` if it is a finite positive number.
fn usable(x: Option<f64>) -> Option<f64> {
    x.filter(|x| x.is_finite() && *x > 0.0)
}

/// Millimetres per unit of `FocalPlaneResolutionUnit`, and the unit's name.
fn unit_mm(code: f64) -> Option<(f64, &'static str)> {
    match code {
        2.0 => Some((25.4, "inch")),
        3.0 => Some((10.0, "cm")),
        4.0 => Some((1.0, "mm")),
        5.0 => Some((0.001, "µm")),
        _ => None,
    }
}

/// The first usable route (see the module notes).
fn focal_from_tags(tags: &Tags, width: u32, height: u32) -> Option<ExifFocal> {
    let (w, h) = (f64::from(width), f64::from(height));
    if let Some(f35) = usable(tags.focal_35mm) {
        let pixels = f35 * w.hypot(h) / FRAME_35MM_DIAGONAL;
        if usable(Some(pixels)).is_some() {
            return Some(ExifFocal {
                pixels,
                source: format!("EXIF FocalLengthIn35mmFilm = {f35} mm"),
            });
        }
    }
    let focal = usable(tags.focal_length)?;
    let resolution = usable(tags.x_resolution)?;
    let (mm, unit) = unit_mm(tags.resolution_unit.unwrap_or(2.0))?;
    let mut pixels = focal * resolution / mm;
    let mut source = format!(
        "EXIF FocalLength = {focal} mm, FocalPlaneXResolution = {resolution} px per {unit}"
    );
    if let Some(px) = usable(tags.pixel_x) {
        let turned = usable(tags.pixel_y) == Some(w) && px == h && px != w;
        if turned {
            source.push_str(&format!(
                " (the image is stored turned by 90°: {width} × {height} of the camera's {px} × {w})"
            ));
        } else if px != w {
            pixels *= w / px;
            source.push_str(&format!(
                ", scaled by {width}/{px} (the image is {width} px wide, the camera's PixelXDimension {px})"
            ));
        }
    }
    usable(Some(pixels)).map(|pixels| ExifFocal { pixels, source })
}

/// The focal-length tags [`write_focal_exif`] writes; each is written when
/// `Some`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FocalTags {
    /// `FocalLength`, mm (a rational).
    pub focal_length: Option<f64>,
    /// `FocalLengthIn35mmFilm`, mm (a whole number).
    pub focal_length_35mm: Option<u16>,
    /// `FocalPlaneXResolution`, sensor pixels per unit (a rational).
    pub focal_plane_x_resolution: Option<f64>,
    /// `FocalPlaneResolutionUnit` (2 = inch, 3 = cm, 4 = mm, 5 = µm).
    pub focal_plane_resolution_unit: Option<u16>,
    /// `PixelXDimension`: the width the camera recorded.
    pub pixel_x_dimension: Option<u32>,
    /// `PixelYDimension`: the height the camera recorded.
    pub pixel_y_dimension: Option<u32>,
}

/// The closest rational to `x` with numerator and denominator in u32 (the
/// last convergent of its continued fraction that fits), or `None` for a
/// value no unsigned rational holds. Exact for every x = n / d that fits;
/// otherwise within 1/d² of x.
fn rational(x: f64) -> Option<Rational> {
    if !(x.is_finite() && (0.0..=f64::from(u32::MAX)).contains(&x)) {
        return None;
    }
    let max = u64::from(u32::MAX);
    // Convergents h/k, starting from h₋₂/k₋₂ = 0/1 and h₋₁/k₋₁ = 1/0.
    let (mut h0, mut h1, mut k0, mut k1) = (0u64, 1u64, 1u64, 0u64);
    let mut r = x;
    for _ in 0..64 {
        let a = r.floor();
        if !(a.is_finite() && a <= max as f64) {
            break;
        }
        let a = a as u64;
        let h = a.checked_mul(h1).and_then(|v| v.checked_add(h0));
        let k = a.checked_mul(k1).and_then(|v| v.checked_add(k0));
        match (h, k) {
            (Some(h), Some(k)) if h <= max && k <= max => {
                (h0, h1, k0, k1) = (h1, h, k1, k);
            }
            _ => break,
        }
        let frac = r - r.floor();
        if h1 as f64 / k1 as f64 == x || frac == 0.0 {
            break;
        }
        r = 1.0 / frac;
    }
    // The first step always fits (a = ⌊x⌋ ≤ u32::MAX, k = 1).
    Some(Rational {
        num: h1 as u32,
        denom: k1.max(1) as u32,
    })
}

/// `jpeg` with an EXIF block holding `tags` (and `Software = mirage`)
/// inserted as an APP1 segment right after its SOI marker. Any EXIF already
/// in the file stays after it; readers take the first.
pub fn write_focal_exif(jpeg: &[u8], tags: &FocalTags) -> Result<Vec<u8>, ExifError> {
    let rational_field = |tag: Tag, name: &'static str, value: f64| {
        let r = rational(value).ok_or(ExifError::Unrepresentable { tag: name, value })?;
        Ok::<_, ExifError>(field(tag, Value::Rational(vec![r])))
    };
    let mut fields = vec![field(Tag::Software, Value::Ascii(vec![b"mirage".to_vec()]))];
    let mut exif_fields = Vec::new();
    if let Some(f) = tags.focal_length {
        exif_fields.push(rational_field(Tag::FocalLength, "FocalLength", f)?);
    }
    if let Some(f) = tags.focal_length_35mm {
        exif_fields.push(field(Tag::FocalLengthIn35mmFilm, Value::Short(vec![f])));
    }
    if let Some(r) = tags.focal_plane_x_resolution {
        exif_fields.push(rational_field(
            Tag::FocalPlaneXResolution,
            "FocalPlaneXResolution",
            r,
        )?);
    }
    if let Some(u) = tags.focal_plane_resolution_unit {
        exif_fields.push(field(Tag::FocalPlaneResolutionUnit, Value::Short(vec![u])));
    }
    if let Some(p) = tags.pixel_x_dimension {
        exif_fields.push(field(Tag::PixelXDimension, Value::Long(vec![p])));
    }
    if let Some(p) = tags.pixel_y_dimension {
        exif_fields.push(field(Tag::PixelYDimension, Value::Long(vec![p])));
    }
    if !exif_fields.is_empty() {
        // Required in every Exif IFD: the version of the standard (2.32).
        fields.push(field(
            Tag::ExifVersion,
            Value::Undefined(b"0232".to_vec(), 0),
        ));
    }
    fields.extend(exif_fields);
    embed_exif(jpeg, &fields)
}

/// A field of the primary image.
fn field(tag: Tag, value: Value) -> Field {
    Field {
        tag,
        ifd_num: In::PRIMARY,
        value,
    }
}

/// `jpeg` with `fields` encoded as EXIF (big-endian TIFF) in an APP1
/// segment right after SOI.
fn embed_exif(jpeg: &[u8], fields: &[Field]) -> Result<Vec<u8>, ExifError> {
    if !jpeg.starts_with(&JPEG_SOI) {
        return Err(ExifError::NotJpeg);
    }
    let mut writer = Writer::new();
    for f in fields {
        writer.push_field(f);
    }
    let mut tiff = Cursor::new(Vec::new());
    writer.write(&mut tiff, false).map_err(ExifError::Encode)?;
    let tiff = tiff.into_inner();
    let mut body = b"Exif\0\0".to_vec();
    body.extend_from_slice(&tiff);
    if body.len() > APP1_MAX {
        return Err(ExifError::Encode(exif::Error::TooBig(
            "the EXIF block is larger than a JPEG APP1 segment holds",
        )));
    }
    let mut out = Vec::with_capacity(jpeg.len() + body.len() + 4);
    out.extend_from_slice(&JPEG_SOI);
    out.extend_from_slice(&[0xff, 0xe1]);
    // The length counts itself (2 bytes) and the body; at most 65535.
    out.extend_from_slice(&((body.len() + 2) as u16).to_be_bytes());
    out.extend_from_slice(&body);
    out.extend_from_slice(&jpeg[JPEG_SOI.len()..]);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use exif::SRational;
    use image::{ExtendedColorType, ImageEncoder, RgbImage};

    fn jpeg(w: u32, h: u32) -> Vec<u8> {
        let img = RgbImage::from_fn(w, h, |x, y| image::Rgb([x as u8, y as u8, 128]));
        let mut out = Vec::new();
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, 90)
            .write_image(img.as_raw(), w, h, ExtendedColorType::Rgb8)
            .unwrap();
        out
    }

    fn png(w: u32, h: u32) -> Vec<u8> {
        let img = RgbImage::new(w, h);
        let mut out = Vec::new();
        image::codecs::png::PngEncoder::new(&mut out)
            .write_image(img.as_raw(), w, h, ExtendedColorType::Rgb8)
            .unwrap();
        out
    }

    fn close(a: f64, b: f64) -> bool {
        ((a - b) / b).abs() < 1e-9
    }

    /// The focal length read back from `tags` embedded in a W × H JPEG, which
    /// must still decode as that image.
    fn round_trip(w: u32, h: u32, tags: &FocalTags) -> Option<ExifFocal> {
        let bytes = write_focal_exif(&jpeg(w, h), tags).unwrap();
        let decoded = image::load_from_memory(&bytes).unwrap();
        assert_eq!((decoded.width(), decoded.height()), (w, h));
        focal_from_exif(&bytes, w, h).unwrap()
    }

    #[test]
    fn focal_length_in_35mm_film() {
        let tags = FocalTags {
            focal_length_35mm: Some(200),
            // The 35 mm route comes first even when the other is there.
            focal_length: Some(133.0),
            focal_plane_x_resolution: Some(4000.0),
            ..FocalTags::default()
        };
        let got = round_trip(640, 480, &tags).unwrap();
        let want = 200.0 * 800.0 / 43.2666;
        assert!(close(got.pixels, want), "{} vs {want}", got.pixels);
        assert_eq!(got.source, "EXIF FocalLengthIn35mmFilm = 200 mm");
    }

    #[test]
    fn focal_length_and_focal_plane_resolution_in_mm_and_inch() {
        // 300 mm on a sensor of 4.2 µm pixels: 238.095… px per mm.
        let per_mm = 1000.0 / 4.2;
        let tags = FocalTags {
            focal_length: Some(300.0),
            focal_plane_x_resolution: Some(per_mm),
            focal_plane_resolution_unit: Some(4),
            pixel_x_dimension: Some(320),
            ..FocalTags::default()
        };
        let got = round_trip(320, 200, &tags).unwrap();
        assert!(close(got.pixels, 300.0 * per_mm), "{}", got.pixels);
        assert!(got.source.contains("px per mm"), "{}", got.source);
        assert!(!got.source.contains("scaled"), "{}", got.source);

        // The same sensor in pixels per inch, 24.5 mm lens; and in cm and µm.
        for (unit, per_unit, name) in [
            (2, per_mm * 25.4, "inch"),
            (3, per_mm * 10.0, "cm"),
            (5, per_mm / 1000.0, "µm"),
        ] {
            let tags = FocalTags {
                focal_length: Some(24.5),
                focal_plane_x_resolution: Some(per_unit),
                focal_plane_resolution_unit: Some(unit),
                ..FocalTags::default()
            };
            let got = round_trip(320, 200, &tags).unwrap();
            assert!(close(got.pixels, 24.5 * per_mm), "{name}: {}", got.pixels);
            assert!(
                got.source.contains(&format!("px per {name}")),
                "{}",
                got.source
            );
        }
        // No unit: inches, as EXIF says.
        let tags = FocalTags {
            focal_length: Some(50.0),
            focal_plane_x_resolution: Some(5000.0),
            ..FocalTags::default()
        };
        let got = round_trip(320, 200, &tags).unwrap();
        assert!(close(got.pixels, 50.0 * 5000.0 / 25.4), "{}", got.pixels);
    }

    #[test]
    fn a_downscaled_image_scales_the_focal_plane_route() {
        // The camera recorded 6000 px; the file was resized to 600 px wide
        // without updating the EXIF.
        let tags = FocalTags {
            focal_length: Some(200.0),
            focal_plane_x_resolution: Some(6000.0 / 23.5),
            focal_plane_resolution_unit: Some(4),
            pixel_x_dimension: Some(6000),
            pixel_y_dimension: Some(4000),
            ..FocalTags::default()
        };
        let got = round_trip(600, 400, &tags).unwrap();
        let want = 200.0 * 600.0 / 23.5;
        assert!(close(got.pixels, want), "{} vs {want}", got.pixels);
        assert!(got.source.contains("scaled by 600/6000"), "{}", got.source);
        // Stored turned by 90° (400 × 600 of a 600 × 400 capture): no scaling.
        let tags = FocalTags {
            pixel_x_dimension: Some(600),
            pixel_y_dimension: Some(400),
            ..tags
        };
        let got = round_trip(400, 600, &tags).unwrap();
        assert!(close(got.pixels, 200.0 * 6000.0 / 23.5), "{}", got.pixels);
        assert!(got.source.contains("turned by 90°"), "{}", got.source);
    }

    #[test]
    fn png_exif_is_read_too() {
        // An eXIf chunk (the TIFF block as written for a JPEG) after IHDR.
        let tagged = write_focal_exif(
            &jpeg(8, 8),
            &FocalTags {
                focal_length_35mm: Some(50),
                ..FocalTags::default()
            },
        )
        .unwrap();
        let tiff_at = tagged.windows(6).position(|w| w == b"Exif\0\0").unwrap() + 6;
        let len = u16::from_be_bytes([tagged[4], tagged[5]]) as usize - 8;
        let tiff = &tagged[tiff_at..tiff_at + len];
        let plain = png(30, 40);
        let ihdr_end = 8 + 8 + 13 + 4;
        let mut bytes = plain[..ihdr_end].to_vec();
        bytes.extend_from_slice(&(tiff.len() as u32).to_be_bytes());
        bytes.extend_from_slice(b"eXIf");
        bytes.extend_from_slice(tiff);
        bytes.extend_from_slice(&[0, 0, 0, 0]); // CRC, not checked by the reader
        bytes.extend_from_slice(&plain[ihdr_end..]);
        let got = focal_from_exif(&bytes, 30, 40).unwrap().unwrap();
        assert!(close(got.pixels, 50.0 * 50.0 / 43.2666), "{}", got.pixels);
        // The plain PNG has none.
        assert_eq!(focal_from_exif(&plain, 30, 40).unwrap(), None);
    }

    #[test]
    fn no_exif_is_none() {
        assert_eq!(focal_from_exif(&jpeg(16, 16), 16, 16).unwrap(), None);
        assert_eq!(focal_from_exif(b"", 16, 16).unwrap(), None);
        assert_eq!(focal_from_exif(b"GIF89a", 16, 16).unwrap(), None);
        // EXIF without focal tags.
        let bytes = write_focal_exif(&jpeg(16, 16), &FocalTags::default()).unwrap();
        assert_eq!(focal_from_exif(&bytes, 16, 16).unwrap(), None);
        // FocalLength without a resolution, a resolution without FocalLength,
        // and an unknown unit.
        for tags in [
            FocalTags {
                focal_length: Some(50.0),
                ..FocalTags::default()
            },
            FocalTags {
                focal_plane_x_resolution: Some(5000.0),
                ..FocalTags::default()
            },
            FocalTags {
                focal_length: Some(50.0),
                focal_plane_x_resolution: Some(5000.0),
                focal_plane_resolution_unit: Some(1),
                ..FocalTags::default()
            },
        ] {
            assert_eq!(round_trip(16, 16, &tags), None, "{tags:?}");
        }
    }

    #[test]
    fn unusable_values_fall_through_or_give_none() {
        let base = jpeg(64, 48);
        let rational = |num, denom| Value::Rational(vec![Rational { num, denom }]);
        let good_plane = || {
            vec![
                field(Tag::FocalLength, rational(50, 1)),
                field(Tag::FocalPlaneXResolution, rational(5000, 1)),
                field(Tag::FocalPlaneResolutionUnit, Value::Short(vec![2])),
            ]
        };
        let read_at = |bytes: &[u8], w, h| focal_from_exif(bytes, w, h).unwrap();
        let read = |fields: Vec<Field>| {
            let bytes = embed_exif(&base, &fields).unwrap();
            focal_from_exif(&bytes, 64, 48).unwrap()
        };
        // A zero 35 mm focal length falls through to the focal plane.
        let mut fields = good_plane();
        fields.push(field(Tag::FocalLengthIn35mmFilm, Value::Short(vec![0])));
        let got = read(fields).unwrap();
        assert!(close(got.pixels, 50.0 * 5000.0 / 25.4));
        // Zero, infinite (x/0), NaN (0/0) and negative focal lengths.
        for bad in [
            rational(0, 1),
            rational(50, 0),
            rational(0, 0),
            Value::SRational(vec![SRational { num: -50, denom: 1 }]),
            Value::Ascii(vec![b"50".to_vec()]),
            Value::Rational(vec![]),
        ] {
            let mut fields = good_plane();
            fields[0] = field(Tag::FocalLength, bad.clone());
            assert_eq!(read(fields), None, "{bad:?}");
            let mut fields = good_plane();
            fields[1] = field(Tag::FocalPlaneXResolution, bad.clone());
            assert_eq!(read(fields), None, "{bad:?}");
        }
        // A zero PixelXDimension is ignored (no scaling by infinity).
        let mut fields = good_plane();
        fields.push(field(Tag::PixelXDimension, Value::Long(vec![0])));
        let got = read(fields).unwrap();
        assert!(close(got.pixels, 50.0 * 5000.0 / 25.4));
        // A zero-size image: the 35 mm route would give f = 0, so it is
        // passed over for the focal plane's, which does not depend on W and H
        // (without PixelXDimension); with only the 35 mm tag, none.
        let mut fields = good_plane();
        fields.push(field(Tag::FocalLengthIn35mmFilm, Value::Short(vec![85])));
        let got = read_at(&embed_exif(&base, &fields).unwrap(), 0, 0).unwrap();
        assert!(
            got.source.starts_with("EXIF FocalLength = 50 mm"),
            "{}",
            got.source
        );
        let only_35mm = [field(Tag::FocalLengthIn35mmFilm, Value::Short(vec![85]))];
        let bytes = embed_exif(&base, &only_35mm).unwrap();
        assert_eq!(read_at(&bytes, 0, 0), None);
        assert!(read_at(&bytes, 64, 48).is_some());
    }

    #[test]
    fn broken_exif_is_an_error_or_none_never_a_panic() {
        let tagged = write_focal_exif(
            &jpeg(32, 24),
            &FocalTags {
                focal_length_35mm: Some(85),
                focal_length: Some(50.0),
                focal_plane_x_resolution: Some(5000.0),
                pixel_x_dimension: Some(3000),
                ..FocalTags::default()
            },
        )
        .unwrap();
        // Every truncation: the EXIF cut inside its block is an error; a cut
        // after it still reads; no prefix panics.
        let mut errors = 0;
        for n in 0..tagged.len() {
            match focal_from_exif(&tagged[..n], 32, 24) {
                Err(e) => {
                    errors += 1;
                    assert!(e.to_string().starts_with("its EXIF cannot be read"), "{e}");
                }
                Ok(Some(f)) => assert!(f.pixels.is_finite() && f.pixels > 0.0),
                Ok(None) => {}
            }
        }
        assert!(errors > 0);
        assert!(focal_from_exif(&tagged, 32, 24).unwrap().is_some());

        // Random bytes, alone and behind a JPEG SOI, a PNG signature and a
        // well-formed APP1 header; and random flips inside the EXIF block.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let exif_end = 6 + u16::from_be_bytes([tagged[4], tagged[5]]) as usize;
        for i in 0..4000 {
            let bytes: Vec<u8> = if i % 2 == 0 {
                let mut b = tagged.clone();
                for _ in 0..1 + next() % 4 {
                    let at = 4 + (next() as usize) % (exif_end - 4);
                    b[at] = next() as u8;
                }
                b
            } else {
                let len = (next() % 300) as usize;
                let mut b: Vec<u8> = (0..len).map(|_| next() as u8).collect();
                match next() % 4 {
                    0 => {
                        b.splice(0..0, [0xff, 0xd8]);
                    }
                    1 => {
                        b.splice(0..0, PNG_SIG);
                    }
                    2 => {
                        let n = (len + 8).min(65535) as u16;
                        let mut head = vec![0xff, 0xd8, 0xff, 0xe1];
                        head.extend_from_slice(&n.to_be_bytes());
                        head.extend_from_slice(b"Exif\0\0");
                        head.extend_from_slice(if next() % 2 == 0 { b"MM\0*" } else { b"II*\0" });
                        b.splice(0..0, head);
                    }
                    _ => {}
                }
                b
            };
            let (w, h) = ((next() % 10_000) as u32, (next() % 10_000) as u32);
            if let Ok(Some(f)) = focal_from_exif(&bytes, w, h) {
                assert!(f.pixels.is_finite() && f.pixels > 0.0, "{f:?}");
            }
        }
    }

    #[test]
    fn rationals_are_exact_or_within_rounding() {
        for x in [
            0.0,
            1.0,
            200.0,
            23.5,
            0.1,
            1000.0 / 4.2,
            6000.0 / 23.5,
            5000.0 * 25.4,
            1.0 / 3.0,
            std::f64::consts::PI,
            4294967295.0,
            1e-7,
        ] {
            let r = rational(x).unwrap();
            let back = r.to_f64();
            assert!(
                (back - x).abs() <= 1e-12 * x.max(1e-3),
                "{x}: {}/{} = {back}",
                r.num,
                r.denom
            );
        }
        let r = rational(23.5).unwrap();
        assert_eq!((r.num, r.denom), (47, 2));
        for bad in [-1.0, f64::NAN, f64::INFINITY, 5e9] {
            assert!(rational(bad).is_none(), "{bad}");
        }
        let e = write_focal_exif(
            &jpeg(8, 8),
            &FocalTags {
                focal_length: Some(-3.0),
                ..FocalTags::default()
            },
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "cannot write EXIF FocalLength = -3: not a finite number in 0 … 4294967295"
        );
        assert!(matches!(
            write_focal_exif(b"\x89PNG", &FocalTags::default()),
            Err(ExifError::NotJpeg)
        ));
    }
}
