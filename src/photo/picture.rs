//! Reading a photograph: its bytes, its format and its size.
//!
//! [`Picture::read`] reads the whole file once, tells PNG and JPEG from
//! anything else by the file's content (its magic bytes, never its
//! extension), and reads the width and height from the header without
//! decoding a pixel, so that checking a problem (marks inside the image, the
//! principal point, the focal length from EXIF, which needs the bytes) costs
//! the size of the file and not the size of the image. [`Picture::decode`]
//! decodes the pixels, as 8-bit RGB, only for the commands that draw on the
//! photo.
//!
//! The pixels are those of the image **as displayed**: an EXIF `Orientation`
//! tag (a phone held upright stores its picture turned and says so) is
//! applied, as every viewer applies it, so the width, the height and the
//! marks' pixels are those a user sees and measures; a file without the tag
//! is as stored. 16-bit channels are reduced to 8 bits, grey becomes RGB and an alpha
//! channel is dropped without compositing. Decoding is bounded by the `image`
//! crate's default memory limit (512 MiB), so a file whose header claims an
//! absurd size is refused with [`PictureError::TooLarge`] instead of
//! exhausting memory.

use image::metadata::Orientation;
use image::{DynamicImage, ImageDecoder, ImageError, ImageFormat, ImageReader, RgbImage};
use std::io::Cursor;
use std::path::{Path, PathBuf};

/// A photograph as read from its file: its size in pixels and the file's
/// bytes (kept for the EXIF and for decoding later).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Picture {
    /// Width W in pixels as displayed (u runs over 0 … W − 1).
    pub width: u32,
    /// Height H in pixels as displayed (v runs over 0 … H − 1).
    pub height: u32,
    /// The EXIF orientation that turns the stored pixels into the displayed
    /// ones (`NoTransforms` without the tag).
    pub orientation: Orientation,
    /// The whole file, as read.
    pub bytes: Vec<u8>,
}

/// Why a photograph cannot be used, in words a user understands. Every
/// variant but [`PictureError::Undecodable`] and [`PictureError::TooLarge`]
/// (which come from [`Picture::decode`], which has no path) names the file.
#[derive(Debug, thiserror::Error)]
pub enum PictureError {
    /// There is no file at the path.
    #[error("the photo {} does not exist", path.display())]
    Missing {
        /// The path as given.
        path: PathBuf,
    },
    /// The file exists but cannot be read (a folder, no permission, …).
    #[error("cannot read the photo {}: {source}", path.display())]
    Unreadable {
        /// The path as given.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The file has no bytes.
    #[error("the photo {} is an empty file", path.display())]
    Empty {
        /// The path as given.
        path: PathBuf,
    },
    /// The file is not a PNG or JPEG image.
    #[error(
        "the photo {} is not a PNG or JPEG image{}",
        path.display(),
        found.as_deref().map(|f| format!(": it is {f}")).unwrap_or_else(|| ": its format is not recognised".to_string())
    )]
    NotPngOrJpeg {
        /// The path as given.
        path: PathBuf,
        /// What the file appears to be ("a GIF image", "a text file"), when
        /// that can be told.
        found: Option<String>,
    },
    /// The file starts as a PNG or JPEG but its header cannot be read.
    #[error("the photo {} is a {format} file but is corrupt or truncated: {source}", path.display())]
    Corrupt {
        /// The path as given.
        path: PathBuf,
        /// "PNG" or "JPEG".
        format: &'static str,
        /// What the decoder said.
        source: ImageError,
    },
    /// The header says the image has no pixels.
    #[error("the photo {} has zero size ({width} × {height} pixels)", path.display())]
    ZeroSize {
        /// The path as given.
        path: PathBuf,
        /// Width from the header.
        width: u32,
        /// Height from the header.
        height: u32,
    },
    /// The pixels cannot be decoded (the data after the header is corrupt or
    /// truncated).
    #[error("the photo's pixels cannot be decoded (the file is corrupt or truncated): {source}")]
    Undecodable {
        /// What the decoder said.
        source: ImageError,
    },
    /// Decoding the pixels would take more memory than allowed.
    #[error(
        "the photo is too large to decode ({width} × {height} pixels, more than the 512 MiB allowed)"
    )]
    TooLarge {
        /// Width from the header.
        width: u32,
        /// Height from the header.
        height: u32,
    },
}

/// The name of a format this module accepts, or `None` for any other.
fn accepted(format: ImageFormat) -> Option<&'static str> {
    match format {
        ImageFormat::Png => Some("PNG"),
        ImageFormat::Jpeg => Some("JPEG"),
        _ => None,
    }
}

/// What a file that is not PNG or JPEG appears to be, in words, when its
/// first bytes tell.
fn describe(bytes: &[u8]) -> Option<String> {
    if let Ok(format) = image::guess_format(bytes) {
        let name = match format {
            ImageFormat::Gif => "GIF",
            ImageFormat::WebP => "WebP",
            ImageFormat::Tiff => "TIFF (or a camera RAW file)",
            ImageFormat::Bmp => "BMP",
            ImageFormat::Ico => "ICO",
            ImageFormat::Avif => "AVIF",
            ImageFormat::OpenExr => "OpenEXR",
            ImageFormat::Hdr => "Radiance HDR",
            ImageFormat::Qoi => "QOI",
            ImageFormat::Pnm => "PNM",
            ImageFormat::Tga => "TGA",
            ImageFormat::Dds => "DDS",
            ImageFormat::Farbfeld => "farbfeld",
            _ => "an image format other than PNG or JPEG",
        };
        return Some(if name.starts_with("an ") {
            name.to_string()
        } else {
            format!("a {name} image; convert it to PNG or JPEG")
        });
    }
    // HEIF/HEIC (what phones save), which `image` does not recognise: an ISO
    // BMFF `ftyp` box with a HEIF brand.
    if bytes.len() >= 12 && &bytes[4..8] == b"ftyp" {
        let brand = &bytes[8..12];
        let heif: [&[u8]; 7] = [
            b"heic", b"heix", b"hevc", b"heim", b"heis", b"mif1", b"msf1",
        ];
        if heif.contains(&brand) {
            return Some("a HEIF/HEIC image; convert it to JPEG".to_string());
        }
    }
    let head = &bytes[..bytes.len().min(1024)];
    if head.starts_with(b"%PDF") {
        return Some("a PDF document".to_string());
    }
    // Text: valid UTF-8 (allowing a character cut at the end of the sample)
    // without control bytes other than whitespace.
    let text = match std::str::from_utf8(head) {
        Ok(t) => Some(t),
        Err(e) if e.error_len().is_none() => std::str::from_utf8(&head[..e.valid_up_to()]).ok(),
        Err(_) => None,
    };
    if let Some(t) = text
        && !t.is_empty()
        && t.chars()
            .all(|c| !c.is_control() || matches!(c, '\n' | '\r' | '\t'))
    {
        return Some("a text file".to_string());
    }
    None
}

impl Picture {
    /// Reads the photo at `path`: its bytes, its format (PNG or JPEG, by
    /// content) and its width and height (from the header, without decoding
    /// the pixels).
    pub fn read(path: &Path) -> Result<Picture, PictureError> {
        let bytes = std::fs::read(path).map_err(|source| {
            if source.kind() == std::io::ErrorKind::NotFound {
                PictureError::Missing {
                    path: path.to_path_buf(),
                }
            } else {
                PictureError::Unreadable {
                    path: path.to_path_buf(),
                    source,
                }
            }
        })?;
        Picture::from_bytes(bytes, path)
    }

    /// The same checks as [`Picture::read`] on bytes already in memory;
    /// `path` is only for the messages.
    pub fn from_bytes(bytes: Vec<u8>, path: &Path) -> Result<Picture, PictureError> {
        let path_buf = || path.to_path_buf();
        if bytes.is_empty() {
            return Err(PictureError::Empty { path: path_buf() });
        }
        let format = image::guess_format(&bytes)
            .ok()
            .and_then(accepted)
            .ok_or_else(|| PictureError::NotPngOrJpeg {
                path: path_buf(),
                found: describe(&bytes),
            })?;
        let corrupt = |source| PictureError::Corrupt {
            path: path_buf(),
            format,
            source,
        };
        let (stored_w, stored_h, orientation) = {
            let mut decoder = reader(&bytes).into_decoder().map_err(corrupt)?;
            let (w, h) = decoder.dimensions();
            // A broken EXIF block is no reason to refuse a readable image: it
            // is read as no orientation, as viewers do.
            let o = decoder.orientation().unwrap_or(Orientation::NoTransforms);
            (w, h, o)
        };
        let (width, height) = if turns(orientation) {
            (stored_h, stored_w)
        } else {
            (stored_w, stored_h)
        };
        if width == 0 || height == 0 {
            return Err(PictureError::ZeroSize {
                path: path_buf(),
                width,
                height,
            });
        }
        Ok(Picture {
            width,
            height,
            orientation,
            bytes,
        })
    }

    /// Decodes the pixels as 8-bit RGB (see the module's notes on
    /// orientation, depth and alpha). The result is `width` × `height`.
    pub fn decode(&self) -> Result<RgbImage, PictureError> {
        let too_large_or_undecodable = |source| match source {
            ImageError::Limits(_) => PictureError::TooLarge {
                width: self.width,
                height: self.height,
            },
            source => PictureError::Undecodable { source },
        };
        let mut decoder = reader(&self.bytes)
            .into_decoder()
            .map_err(too_large_or_undecodable)?;
        // What `ImageReader::decode` does before allocating: the whole
        // buffer counts against the limit, so that a header claiming an
        // absurd size is refused instead of exhausting memory.
        let mut limits = image::Limits::default();
        limits
            .reserve(decoder.total_bytes())
            .and_then(|()| decoder.set_limits(limits))
            .map_err(too_large_or_undecodable)?;
        let mut image = DynamicImage::from_decoder(decoder).map_err(too_large_or_undecodable)?;
        image.apply_orientation(self.orientation);
        Ok(image.into_rgb8())
    }
}

/// Whether `o` swaps width and height (a quarter turn, with or without a flip).
fn turns(o: Orientation) -> bool {
    matches!(
        o,
        Orientation::Rotate90
            | Orientation::Rotate270
            | Orientation::Rotate90FlipH
            | Orientation::Rotate270FlipH
    )
}

/// A reader of `bytes` whose format is told by their content (falling back
/// to "unknown", which then fails as an unsupported format).
fn reader(bytes: &[u8]) -> ImageReader<Cursor<&[u8]>> {
    let plain = || ImageReader::new(Cursor::new(bytes));
    // Guessing reads only the in-memory cursor, which cannot fail.
    plain().with_guessed_format().unwrap_or_else(|_| plain())
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::{ExtendedColorType, ImageEncoder, Rgb};

    fn gradient(w: u32, h: u32) -> RgbImage {
        RgbImage::from_fn(w, h, |x, y| {
            Rgb([(x * 7) as u8, (y * 5) as u8, ((x + y) * 3) as u8])
        })
    }

    fn png_bytes(img: &RgbImage) -> Vec<u8> {
        let mut out = Vec::new();
        image::codecs::png::PngEncoder::new(&mut out)
            .write_image(
                img.as_raw(),
                img.width(),
                img.height(),
                ExtendedColorType::Rgb8,
            )
            .unwrap();
        out
    }

    fn jpeg_bytes(img: &RgbImage) -> Vec<u8> {
        jpeg_with(img, 95, None)
    }

    /// A JPEG of `img` at `quality`, with `exif` (a TIFF block) when given.
    fn jpeg_with(img: &RgbImage, quality: u8, exif: Option<Vec<u8>>) -> Vec<u8> {
        let mut out = Vec::new();
        let mut enc = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, quality);
        if let Some(tiff) = exif {
            enc.set_exif_metadata(tiff).unwrap();
        }
        enc.write_image(
            img.as_raw(),
            img.width(),
            img.height(),
            ExtendedColorType::Rgb8,
        )
        .unwrap();
        out
    }

    fn write(dir: &tempfile::TempDir, name: &str, bytes: &[u8]) -> PathBuf {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        path
    }

    #[test]
    fn reads_png_size_and_pixels() {
        let dir = tempfile::tempdir().unwrap();
        let img = gradient(37, 21);
        let path = write(&dir, "a.png", &png_bytes(&img));
        let pic = Picture::read(&path).unwrap();
        assert_eq!((pic.width, pic.height), (37, 21));
        assert_eq!(pic.decode().unwrap(), img);
    }

    /// A JPEG of `img` whose EXIF says `Orientation` = `code`.
    fn jpeg_oriented(img: &RgbImage, code: u16) -> Vec<u8> {
        let field = exif::Field {
            tag: exif::Tag::Orientation,
            ifd_num: exif::In::PRIMARY,
            value: exif::Value::Short(vec![code]),
        };
        let mut writer = exif::experimental::Writer::new();
        writer.push_field(&field);
        let mut tiff = Cursor::new(Vec::new());
        writer.write(&mut tiff, false).unwrap();
        jpeg_with(img, 100, Some(tiff.into_inner()))
    }

    #[test]
    fn exif_orientation_gives_the_image_as_displayed() {
        // Two flat halves (left dark, right bright), so that JPEG's loss
        // cannot hide which way the picture was turned.
        let img = RgbImage::from_fn(40, 24, |x, _| {
            if x < 20 {
                Rgb([20, 20, 20])
            } else {
                Rgb([230, 230, 230])
            }
        });
        let dir = tempfile::tempdir().unwrap();
        let bright = |p: &Rgb<u8>| p.0[0] > 128;
        // 1: as stored; 6: turn 90° clockwise (the left half goes on top);
        // 8: 90° anticlockwise (the left half at the bottom); 3: 180°.
        for (code, size, top_left_bright, bottom_left_bright) in [
            (1u16, (40, 24), false, false),
            (6, (24, 40), false, true),
            (8, (24, 40), true, false),
            (3, (40, 24), true, true),
            (2, (40, 24), true, true),
        ] {
            let path = write(&dir, &format!("o{code}.jpg"), &jpeg_oriented(&img, code));
            let pic = Picture::read(&path).unwrap();
            assert_eq!((pic.width, pic.height), size, "orientation {code}");
            let shown = pic.decode().unwrap();
            assert_eq!(shown.dimensions(), size, "orientation {code}");
            let (w, h) = size;
            assert_eq!(
                bright(shown.get_pixel(2, 2)),
                top_left_bright,
                "orientation {code}"
            );
            assert_eq!(
                bright(shown.get_pixel(2, h - 3)),
                bottom_left_bright,
                "orientation {code}"
            );
            assert!(w > 3);
        }
    }

    #[test]
    fn reads_jpeg_by_content_whatever_the_extension() {
        let dir = tempfile::tempdir().unwrap();
        let img = gradient(64, 48);
        // A JPEG named .png: the content decides.
        let path = write(&dir, "looks-like.png", &jpeg_bytes(&img));
        let pic = Picture::read(&path).unwrap();
        assert_eq!((pic.width, pic.height), (64, 48));
        let decoded = pic.decode().unwrap();
        assert_eq!(decoded.dimensions(), (64, 48));
        // Lossy, but close: quality 95 on a smooth gradient.
        let err: f64 = decoded
            .as_raw()
            .iter()
            .zip(img.as_raw())
            .map(|(a, b)| (*a as f64 - *b as f64).abs())
            .sum::<f64>()
            / img.as_raw().len() as f64;
        assert!(err < 4.0, "mean error {err}");
    }

    #[test]
    fn reads_size_without_decoding() {
        // A JPEG whose scan data is cut off still has its size in the header:
        // read succeeds, decode fails.
        let dir = tempfile::tempdir().unwrap();
        let full = jpeg_bytes(&gradient(200, 120));
        let cut = &full[..full.len() / 2];
        let path = write(&dir, "cut.jpg", cut);
        let pic = Picture::read(&path).unwrap();
        assert_eq!((pic.width, pic.height), (200, 120));
        // The same for a PNG cut in its image data.
        let full = png_bytes(&gradient(200, 120));
        let path = write(&dir, "cut.png", &full[..full.len() / 2]);
        let pic = Picture::read(&path).unwrap();
        assert_eq!((pic.width, pic.height), (200, 120));
        let e = pic.decode().unwrap_err();
        assert!(matches!(e, PictureError::Undecodable { .. }), "{e}");
        assert!(e.to_string().contains("corrupt or truncated"), "{e}");
    }

    #[test]
    fn a_missing_file_names_its_path() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("nowhere/harbour.jpg");
        let e = Picture::read(&path).unwrap_err();
        assert!(matches!(e, PictureError::Missing { .. }));
        let msg = e.to_string();
        assert!(msg.contains("does not exist"), "{msg}");
        assert!(msg.contains("harbour.jpg"), "{msg}");
    }

    #[test]
    fn a_folder_is_unreadable() {
        let dir = tempfile::tempdir().unwrap();
        let e = Picture::read(dir.path()).unwrap_err();
        assert!(matches!(e, PictureError::Unreadable { .. }), "{e}");
        assert!(e.to_string().starts_with("cannot read the photo"), "{e}");
    }

    #[test]
    fn other_formats_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let cases: Vec<(&str, Vec<u8>, &str)> = vec![
            (
                "a.gif",
                b"GIF89a\x01\x00\x01\x00\x00\x00\x00;".to_vec(),
                "a GIF image",
            ),
            (
                "a.webp",
                b"RIFF\x1a\x00\x00\x00WEBPVP8 ".to_vec(),
                "a WebP image",
            ),
            ("a.tif", b"II*\x00\x08\x00\x00\x00\x00\x00".to_vec(), "TIFF"),
            (
                "a.heic",
                b"\x00\x00\x00\x18ftypheic\x00\x00\x00\x00mif1heic".to_vec(),
                "HEIF/HEIC",
            ),
            (
                "a.json",
                b"{ \"name\": \"not a photo\" }\n".to_vec(),
                "a text file",
            ),
            (
                "a.pdf",
                b"%PDF-1.7\n\xe2\xe3\xcf\xd3".to_vec(),
                "a PDF document",
            ),
        ];
        for (name, bytes, says) in cases {
            let path = write(&dir, name, &bytes);
            let e = Picture::read(&path).unwrap_err();
            assert!(
                matches!(e, PictureError::NotPngOrJpeg { .. }),
                "{name}: {e}"
            );
            let msg = e.to_string();
            assert!(msg.contains("is not a PNG or JPEG image"), "{msg}");
            assert!(msg.contains(says), "{name}: {msg}");
        }
        // Unrecognisable bytes say so.
        let path = write(&dir, "noise.jpg", &[0x00, 0x9f, 0x13, 0xfe, 0x00, 0x01]);
        let msg = Picture::read(&path).unwrap_err().to_string();
        assert!(msg.ends_with("its format is not recognised"), "{msg}");
    }

    #[test]
    fn empty_and_corrupt_headers() {
        let dir = tempfile::tempdir().unwrap();
        let path = write(&dir, "empty.jpg", b"");
        let e = Picture::read(&path).unwrap_err();
        assert!(matches!(e, PictureError::Empty { .. }), "{e}");
        assert!(e.to_string().contains("empty file"));
        // The magic bytes and nothing else.
        for (name, bytes, format) in [
            ("sig.jpg", &b"\xff\xd8\xff"[..], "JPEG"),
            ("sig.png", &b"\x89PNG\r\n\x1a\n"[..], "PNG"),
        ] {
            let path = write(&dir, name, bytes);
            let e = Picture::read(&path).unwrap_err();
            assert!(matches!(e, PictureError::Corrupt { .. }), "{name}: {e}");
            let msg = e.to_string();
            assert!(
                msg.contains(&format!("is a {format} file but is corrupt or truncated")),
                "{msg}"
            );
        }
    }

    #[test]
    fn zero_size_is_refused() {
        // A PNG header (IHDR) declaring 0 × 5 pixels, with a valid CRC.
        let mut ihdr = b"IHDR".to_vec();
        ihdr.extend_from_slice(&0u32.to_be_bytes());
        ihdr.extend_from_slice(&5u32.to_be_bytes());
        ihdr.extend_from_slice(&[8, 2, 0, 0, 0]);
        let crc = crc32(&ihdr);
        let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
        png.extend_from_slice(&13u32.to_be_bytes());
        png.extend_from_slice(&ihdr);
        png.extend_from_slice(&crc.to_be_bytes());
        let e = Picture::from_bytes(png, Path::new("zero.png")).unwrap_err();
        // The png crate itself may refuse a zero dimension as corrupt; either
        // way the photo is refused with a message naming it.
        assert!(
            matches!(
                e,
                PictureError::ZeroSize { .. } | PictureError::Corrupt { .. }
            ),
            "{e}"
        );
        assert!(e.to_string().contains("zero.png"), "{e}");
    }

    /// CRC-32 (IEEE), for building a PNG chunk by hand.
    fn crc32(data: &[u8]) -> u32 {
        let mut crc = 0xffff_ffffu32;
        for &b in data {
            crc ^= b as u32;
            for _ in 0..8 {
                crc = if crc & 1 != 0 {
                    (crc >> 1) ^ 0xedb8_8320
                } else {
                    crc >> 1
                };
            }
        }
        !crc
    }

    #[test]
    fn absurd_sizes_are_refused_on_decode() {
        // A JPEG whose SOF claims 65000 × 65000 pixels: the header reads, the
        // decoder refuses instead of allocating 12 GB.
        let mut bytes = jpeg_bytes(&gradient(16, 16));
        let sof = bytes
            .windows(2)
            .position(|w| w == [0xff, 0xc0])
            .expect("a baseline SOF0");
        // SOF0: marker, length (2), precision (1), height (2), width (2).
        bytes[sof + 5..sof + 7].copy_from_slice(&65000u16.to_be_bytes());
        bytes[sof + 7..sof + 9].copy_from_slice(&65000u16.to_be_bytes());
        let pic = Picture::from_bytes(bytes, Path::new("huge.jpg")).unwrap();
        assert_eq!((pic.width, pic.height), (65000, 65000));
        let e = pic.decode().unwrap_err();
        assert!(matches!(e, PictureError::TooLarge { .. }), "{e}");
        assert!(e.to_string().contains("65000 × 65000"), "{e}");
    }

    #[test]
    fn never_panics_on_garbage() {
        // Random bytes, and every prefix of a valid PNG and JPEG, with the
        // magic bytes kept in front: read and decode return, whatever they say.
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let jpeg = jpeg_bytes(&gradient(24, 16));
        let png = png_bytes(&gradient(24, 16));
        let mut inputs: Vec<Vec<u8>> = Vec::new();
        for n in (0..jpeg.len()).step_by(7) {
            inputs.push(jpeg[..n].to_vec());
        }
        for n in (0..png.len()).step_by(5) {
            inputs.push(png[..n].to_vec());
        }
        for _ in 0..300 {
            let len = (next() % 400) as usize;
            let mut b: Vec<u8> = (0..len).map(|_| next() as u8).collect();
            let head: &[u8] = match next() % 3 {
                0 => &[0xff, 0xd8, 0xff],
                1 => b"\x89PNG\r\n\x1a\n",
                _ => &[],
            };
            b.splice(0..0, head.iter().copied());
            inputs.push(b);
        }
        // Flipped bytes inside a valid JPEG.
        for _ in 0..200 {
            let mut b = jpeg.clone();
            let i = (next() as usize) % b.len();
            b[i] = next() as u8;
            inputs.push(b);
        }
        let mut decoded = 0;
        for bytes in inputs {
            if let Ok(pic) = Picture::from_bytes(bytes, Path::new("x")) {
                if let Ok(img) = pic.decode() {
                    assert_eq!(img.dimensions(), (pic.width, pic.height));
                    decoded += 1;
                }
            }
        }
        assert!(decoded > 0);
    }
}
