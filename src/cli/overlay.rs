//! `mirage overlay PROBLEM.json -o OVERLAY.png`: a photo problem's marks
//! drawn on its photo where its starting air and camera put them (no fit),
//! and the overlay `mirage fit --overlay` writes for the fitted ones
//! (`docs/photo.md`, "What comes out").

use crate::error::{Error, Result};
use crate::fit::objective::Objective;
use crate::fit::photo::{PhotoReport, photo_report};
use crate::io::{Output, OutputKind, check_outputs};
use crate::photo::picture::Picture;
use crate::plot::{Overlay, OverlayMark, draw_overlay};
use crate::problem::Problem;
use std::fmt::Write;
use std::path::{Path, PathBuf};

/// `mirage overlay`'s arguments.
#[derive(Debug, clap::Args)]
pub struct OverlayOptions {
    /// Photo problem file (JSON, with a `photo` section and `marks`).
    pub problem: PathBuf,
    /// The overlay to write (.png).
    #[arg(short, long)]
    pub output: PathBuf,
}

/// The problem's photo report at its starting numbers.
pub fn starting_report(problem: &Problem) -> Result<PhotoReport> {
    let Some(setup) = &problem.photo else {
        return Err(Error::input(
            &problem.source,
            "photo",
            "missing: an overlay draws a photo problem's marks on its photo; this problem has no `photo` section",
        ));
    };
    let objective = Objective::from_problem(problem);
    let x = objective.start();
    photo_report(&objective, x.as_slice(), &setup.image.display().to_string()).ok_or_else(|| {
        Error::input(
            &problem.source,
            "photo",
            "the photo's report could not be made",
        )
    })
}

/// The overlay's title: the problem's name, and whether the air and the
/// camera drawn are fitted or the problem's starting ones.
pub fn overlay_title(problem: &Problem, fitted: bool) -> String {
    if fitted {
        format!("{}: fitted", problem.name)
    } else {
        format!("{}: starting air and camera (not fitted)", problem.name)
    }
}

/// Draws `report` over the problem's photo and writes it to `path` (PNG,
/// atomically).
pub fn write_overlay(
    problem: &Problem,
    report: &PhotoReport,
    title: &str,
    path: &Path,
) -> Result<()> {
    if problem.photo.is_none() {
        return Ok(());
    }
    let image = overlay_image(problem, report, title)?;
    let mut bytes = Vec::new();
    image::ImageEncoder::write_image(
        image::codecs::png::PngEncoder::new(&mut bytes),
        image.as_raw(),
        image.width(),
        image.height(),
        image::ExtendedColorType::Rgb8,
    )
    .map_err(|e| Error::encode("the overlay PNG", e))?;
    crate::io::write_atomic(path, &bytes)
}

/// The overlay of `report` on the problem's photo, as pixels (what
/// [`write_overlay`] writes as a PNG).
pub fn overlay_image(
    problem: &Problem,
    report: &PhotoReport,
    title: &str,
) -> Result<image::RgbImage> {
    let Some(setup) = &problem.photo else {
        return Err(Error::input(
            &problem.source,
            "photo",
            "missing: an overlay draws a photo problem's marks on its photo; this problem has no `photo` section",
        ));
    };
    let picture = Picture::read(&setup.image)
        .and_then(|p| p.decode())
        .map_err(|e| Error::input(&problem.source, "photo.image", e.to_string()))?;
    let overlay = Overlay {
        marks: report
            .marks
            .iter()
            .map(|m| OverlayMark {
                name: m.name.clone(),
                marked: m.pixel,
                fitted: m.predicted,
                straight: m.straight,
                horizon: m.horizon,
            })
            .collect(),
        horizon: report.horizon_line.clone(),
        title: title.to_string(),
        rms_pixels: Some(report.rms_pixels),
    };
    Ok(draw_overlay(&picture, &overlay))
}

/// Runs `mirage overlay`.
pub fn run(o: &OverlayOptions) -> Result<PhotoReport> {
    let problem = Problem::load(&o.problem)?;
    check_outputs(
        [Output::new("-o", &o.output, OutputKind::Png("an overlay"))],
        &[o.problem.as_path()],
    )?;
    let report = starting_report(&problem)?;
    write_overlay(
        &problem,
        &report,
        &overlay_title(&problem, false),
        &o.output,
    )?;
    print!("{}", photo_summary(&report));
    Ok(report)
}

/// A photo fit's marks: residual and predicted pixel per mark, the RMS.
pub fn photo_summary(p: &crate::fit::photo::PhotoReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "photo {} ({} × {} px, f = {:.2} px from {}): RMS residual {:.3} px",
        p.image, p.size[0], p.size[1], p.focal_pixels, p.focal_source, p.rms_pixels
    );
    if let Some(e) = p.horizon_elevation {
        let _ = writeln!(s, "  apparent horizon at {e:.5}° elevation");
    }
    let w = p
        .marks
        .iter()
        .map(|m| m.name.chars().count())
        .max()
        .unwrap_or(0)
        .max(12);
    let _ = writeln!(
        s,
        "  {:<w$} {:>22} {:>22} {:>10}",
        "mark", "marked (u, v)", "fitted air (u, v)", "residual"
    );
    for m in &p.marks {
        let at = |q: Option<[f64; 2]>| match q {
            Some([u, v]) => format!("({u:.2}, {v:.2})"),
            None => "none".into(),
        };
        let _ = writeln!(
            s,
            "  {:<w$} {:>22} {:>22} {:>7.3} px{}",
            m.name,
            at(Some(m.pixel)),
            at(m.predicted),
            m.residual,
            if m.horizon { "  (horizon)" } else { "" }
        );
    }
    s
}
