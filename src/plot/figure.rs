//! A figure: the image formats, the [`Figure`] interface every plot
//! implements, rendering to PNG or SVG in memory and saving atomically, and
//! the header and placeholder every figure draws.

use super::style::{
    AXIS_LABEL_SIZE, DrawResult, INK, MUTED, SUBTITLE_SIZE, TITLE_SIZE, anchored, ensure_font, text,
};
use super::text::{TextMode, draw_label};
use crate::error::{Error, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};
use std::path::Path;

/// The image formats plots are written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// Portable Network Graphics (raster).
    Png,
    /// Scalable Vector Graphics (text stays text).
    Svg,
}

impl ImageFormat {
    /// The format named by the extension of `path` (`.png` or `.svg`, any
    /// case); anything else is an input error.
    pub fn from_path(path: &Path) -> Result<ImageFormat> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            Some("png") => Ok(ImageFormat::Png),
            Some("svg") => Ok(ImageFormat::Svg),
            Some(other) => Err(Error::input(
                path,
                "-",
                format!("unsupported image format `.{other}`: expected .png or .svg"),
            )),
            None => Err(Error::input(
                path,
                "-",
                "the output has no file extension: expected .png or .svg",
            )),
        }
    }
}

/// A figure that can be drawn on any plotters backend, so one drawing routine
/// serves both PNG and SVG.
pub(super) trait Figure {
    /// Size in pixels (width, height).
    fn size(&self) -> (u32, u32);
    /// Draws the whole figure on `root` (already filled white), with text drawn
    /// the way `mode` says.
    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        mode: TextMode,
    ) -> DrawResult<DB>;
}

pub(super) fn draw_failed(e: impl std::fmt::Display) -> Error {
    Error::encode("the plot", e)
}

/// Renders `figure` to the bytes of an image file.
pub(super) fn render(figure: &impl Figure, format: ImageFormat) -> Result<Vec<u8>> {
    ensure_font();
    let (w, h) = figure.size();
    match format {
        ImageFormat::Png => {
            let mut pixels = vec![0u8; w as usize * h as usize * 3];
            {
                let root = BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area();
                root.fill(&WHITE).map_err(draw_failed)?;
                figure
                    .draw(&root, TextMode::PerGlyph)
                    .map_err(draw_failed)?;
                root.present().map_err(draw_failed)?;
            }
            let mut bytes = Vec::new();
            image::ImageEncoder::write_image(
                image::codecs::png::PngEncoder::new(&mut bytes),
                &pixels,
                w,
                h,
                image::ExtendedColorType::Rgb8,
            )
            .map_err(|e| Error::encode("the PNG", e))?;
            Ok(bytes)
        }
        ImageFormat::Svg => {
            let mut text = String::new();
            {
                let root = SVGBackend::with_string(&mut text, (w, h)).into_drawing_area();
                root.fill(&WHITE).map_err(draw_failed)?;
                figure.draw(&root, TextMode::Whole).map_err(draw_failed)?;
                root.present().map_err(draw_failed)?;
            }
            Ok(text.into_bytes())
        }
    }
}

/// Renders `figure` in the format `output` names and writes it atomically.
pub(super) fn save(figure: &impl Figure, output: &Path) -> Result<()> {
    let format = ImageFormat::from_path(output)?;
    let bytes = render(figure, format)?;
    crate::io::write_atomic(output, &bytes)
}

/// Draws the title and a subtitle line centred at the top of `header`.
pub(super) fn draw_header<DB: DrawingBackend>(
    header: &DrawingArea<DB, Shift>,
    title: &str,
    subtitle: &str,
    mode: TextMode,
) -> DrawResult<DB> {
    let (w, _) = header.dim_in_pixel();
    let centre = (w / 2) as i32;
    let style = anchored(text(TITLE_SIZE, INK), HPos::Center, VPos::Top);
    draw_label(header, title, (centre, 12), &style, mode)?;
    let style = anchored(text(SUBTITLE_SIZE, MUTED), HPos::Center, VPos::Top);
    draw_label(header, subtitle, (centre, 46), &style, mode)
}

/// Draws a message in the middle of an area that has no data to show.
pub(super) fn draw_placeholder<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    message: &str,
    mode: TextMode,
) -> DrawResult<DB> {
    let (w, h) = area.dim_in_pixel();
    let style = anchored(text(AXIS_LABEL_SIZE, MUTED), HPos::Center, VPos::Center);
    draw_label(
        area,
        message,
        ((w / 2) as i32, (h / 2) as i32),
        &style,
        mode,
    )
}
