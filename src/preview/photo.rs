//! The previewer's photo mode apart from any window: a photo problem's marks
//! being edited (added on a click with a target picked or typed, dragged,
//! deleted), the predictions of the current air and camera for them, the
//! fit run in the background, and the marks saved back into the file.
//!
//! # Invariants
//!
//! - The marks always make a valid problem: every edit re-validates the
//!   problem file with the edited `marks` ([`Problem::parse`], the same
//!   checks as `mirage fit`), and an edit that makes it invalid (a pixel
//!   outside the image, a target behind the camera, no mark left) is undone
//!   and returns that error.
//! - The predictions ([`PhotoSession::report`]) are
//!   [`crate::fit::photo::photo_report`]'s (each target shot through the air
//!   to 1e-12 of its range) for the current marks, at the fitted numbers
//!   after a fit, else at the file's starting numbers. Mark edits keep the
//!   fitted numbers (the free parameters do not change with the marks).
//! - Saving replaces the file's `marks` array and nothing else: the file is
//!   read as a JSON value, its `marks` replaced, and written atomically
//!   ([`crate::io::write_atomic`]); unknown fields, key order and the
//!   starting numbers are kept (the fitted numbers are the result's, as for
//!   `mirage fit`).
//!
//! # Pixels on the screen
//!
//! [`PhotoFrame`] places the image in a rectangle of the window with its
//! aspect ratio kept: the pixel (u, v) (OpenCV's convention, the centre of
//! the top-left pixel at (0, 0)) is drawn at origin + (u + ½, v + ½)·scale,
//! exactly invertible.

use crate::error::{Error, Result};
use crate::fit::objective::Objective;
use crate::fit::photo::{PhotoReport, photo_report};
use crate::fit::report::FitReport;
use crate::geo::{GeoPoint, Point};
use crate::io::json::{parse_json, read_input};
use crate::photo::spec::MarkEntry;
use crate::problem::Problem;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// Where a new mark's target comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum NewTarget {
    /// The `k`-th of [`PhotoSession::named_targets`].
    Named(usize),
    /// A point typed in (local `[x, y, z]` or geographic).
    Point(Point),
    /// A mark on the apparent sea horizon.
    Horizon,
}

/// A photo problem being marked.
#[derive(Clone, Debug)]
pub struct PhotoSession {
    /// The problem file.
    pub path: PathBuf,
    /// The file as read, as a JSON value.
    original: Value,
    /// The marks as edited.
    pub marks: Vec<MarkEntry>,
    /// The problem with the edited marks.
    pub problem: Problem,
    /// The fitted parameters (the fit's x), once fitted.
    pub fitted: Option<Vec<f64>>,
    /// The predictions for the current marks.
    pub report: PhotoReport,
}

impl PhotoSession {
    /// Opens the photo problem at `path` (validated as `mirage fit` does).
    pub fn open(path: &Path) -> Result<PhotoSession> {
        let text = read_input(path)?;
        let original: Value = parse_json(&text, path, "photo problem")?;
        let problem = Problem::parse(&text, path)?;
        if problem.photo.is_none() {
            return Err(Error::input(
                path,
                "photo",
                "missing: the photo mode shows a photo problem (a `photo` section and `marks`)",
            ));
        }
        let marks: Vec<MarkEntry> = serde_json::from_value(original["marks"].clone())
            .map_err(|e| Error::input(path, "marks", e.to_string()))?;
        let report = report_of(&problem, None)?;
        Ok(PhotoSession {
            path: path.to_path_buf(),
            original,
            marks,
            problem,
            fitted: None,
            report,
        })
    }

    /// The image's width and height (pixels).
    pub fn size(&self) -> [u32; 2] {
        self.report.size
    }

    /// The file with the edited marks in place of its own.
    pub fn edited_value(&self) -> Value {
        let mut v = self.original.clone();
        v["marks"] = serde_json::to_value(&self.marks).unwrap_or(Value::Null);
        v
    }

    /// The edited file's text (pretty JSON, a final newline).
    pub fn edited_text(&self) -> String {
        let mut s = serde_json::to_string_pretty(&self.edited_value()).unwrap_or_default();
        s.push('\n');
        s
    }

    /// Re-validates the problem with `marks` and recomputes the predictions;
    /// on an error nothing changes.
    fn apply(&mut self, marks: Vec<MarkEntry>) -> Result<()> {
        let old = std::mem::replace(&mut self.marks, marks);
        let outcome = Problem::parse(&self.edited_text(), &self.path).and_then(|problem| {
            let report = report_of(&problem, self.fitted.as_deref())?;
            Ok((problem, report))
        });
        match outcome {
            Ok((problem, report)) => {
                self.problem = problem;
                self.report = report;
                Ok(())
            }
            Err(e) => {
                self.marks = old;
                Err(e)
            }
        }
    }

    /// The points the problem names: each named mark's target, once, in
    /// file order.
    pub fn named_targets(&self) -> Vec<(String, Point)> {
        let mut out: Vec<(String, Point)> = Vec::new();
        for (i, m) in self.marks.iter().enumerate() {
            if let Some(t) = m.target
                && !out.iter().any(|(_, p)| *p == t)
            {
                out.push((m.name.clone().unwrap_or(format!("mark {i}")), t));
            }
        }
        out
    }

    /// Whether the problem has a site (typed targets may be geographic).
    pub fn has_site(&self) -> bool {
        self.original.get("site").is_some_and(|s| !s.is_null())
    }

    /// Adds a mark at `pixel` seen on `target`; returns its index.
    pub fn add_mark(&mut self, pixel: [f64; 2], target: NewTarget) -> Result<usize> {
        let n = self.marks.len();
        let (name, target, horizon) = match target {
            NewTarget::Named(k) => {
                let named = self.named_targets();
                let Some((name, p)) = named.get(k) else {
                    return Err(Error::input(
                        &self.path,
                        format!("marks[{n}].target"),
                        format!("no named point {k} (the problem names {})", named.len()),
                    ));
                };
                (name.clone(), Some(*p), false)
            }
            NewTarget::Point(p) => (format!("mark {n}"), Some(p), false),
            NewTarget::Horizon => (format!("horizon {n}"), None, true),
        };
        let mut marks = self.marks.clone();
        marks.push(MarkEntry {
            name: Some(name),
            pixel,
            target,
            horizon,
        });
        self.apply(marks)?;
        Ok(n)
    }

    /// Moves mark `i` to `pixel`.
    pub fn move_mark(&mut self, i: usize, pixel: [f64; 2]) -> Result<()> {
        let mut marks = self.marks.clone();
        if let Some(m) = marks.get_mut(i) {
            m.pixel = pixel;
        }
        self.apply(marks)
    }

    /// Deletes mark `i` (a photo problem keeps at least one).
    pub fn delete_mark(&mut self, i: usize) -> Result<()> {
        let mut marks = self.marks.clone();
        if i < marks.len() {
            marks.remove(i);
        }
        self.apply(marks)
    }

    /// The mark whose marked pixel is nearest `pixel`, within `radius`
    /// pixels.
    pub fn hit(&self, pixel: [f64; 2], radius: f64) -> Option<usize> {
        self.marks
            .iter()
            .enumerate()
            .map(|(i, m)| (i, (m.pixel[0] - pixel[0]).hypot(m.pixel[1] - pixel[1])))
            .filter(|&(_, d)| d <= radius)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(i, _)| i)
    }

    /// Takes a finished fit: its numbers and predictions become the view's.
    pub fn take_fit(&mut self, report: &FitReport) -> Result<()> {
        let x: Vec<f64> = report.parameters.iter().map(|p| p.value).collect();
        self.report = report_of(&self.problem, Some(&x))?;
        self.fitted = Some(x);
        Ok(())
    }

    /// Writes the file with the edited marks to `out`, atomically.
    pub fn save(&self, out: &Path) -> Result<()> {
        crate::io::write_atomic(out, self.edited_text().as_bytes())
    }
}

/// The photo report of `problem` at `x` (else its start).
fn report_of(problem: &Problem, x: Option<&[f64]>) -> Result<PhotoReport> {
    let objective = Objective::from_problem(problem);
    let start = objective.start();
    let x = x
        .filter(|x| x.len() == start.len())
        .unwrap_or(start.as_slice());
    let image = problem
        .photo
        .as_ref()
        .map(|s| s.image.display().to_string())
        .unwrap_or_default();
    photo_report(&objective, x, &image).ok_or_else(|| {
        Error::input(
            &problem.source,
            "photo",
            "the marks' predictions could not be made",
        )
    })
}

/// Whether the file at `path` is a photo problem (a JSON object with a
/// `photo` section).
pub fn is_photo_problem(path: &Path) -> Result<bool> {
    let text = read_input(path)?;
    let value: Value = parse_json(&text, path, "scene or problem")?;
    Ok(value.get("photo").is_some())
}

/// A point typed in the new mark's popup: geographic with a site, else
/// local; the fields as typed.
pub fn typed_point(fields: &[String; 3], geographic: bool) -> Option<Point> {
    let v: Vec<f64> = fields
        .iter()
        .map(|s| s.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .ok()?;
    if v.iter().any(|c| !c.is_finite()) {
        return None;
    }
    Some(if geographic {
        Point::Geo(GeoPoint {
            latitude: v[0],
            longitude: v[1],
            height: v[2],
        })
    } else {
        Point::Local([v[0], v[1], v[2]])
    })
}

/// The image placed in a rectangle of the window (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotoFrame {
    /// The screen point of the image's top-left edge.
    pub origin: [f64; 2],
    /// Screen units per image pixel.
    pub scale: f64,
}

impl PhotoFrame {
    /// The largest placement of a `size` image in the rectangle at `min`
    /// of `extent`, centred.
    pub fn fit(min: [f64; 2], extent: [f64; 2], size: [u32; 2]) -> PhotoFrame {
        let (w, h) = (size[0].max(1) as f64, size[1].max(1) as f64);
        let scale = (extent[0] / w).min(extent[1] / h).max(1e-9);
        PhotoFrame {
            origin: [
                min[0] + 0.5 * (extent[0] - w * scale),
                min[1] + 0.5 * (extent[1] - h * scale),
            ],
            scale,
        }
    }

    /// The screen point of image pixel `p`.
    pub fn to_screen(&self, p: [f64; 2]) -> [f64; 2] {
        [
            self.origin[0] + (p[0] + 0.5) * self.scale,
            self.origin[1] + (p[1] + 0.5) * self.scale,
        ]
    }

    /// The image pixel at screen point `s`.
    pub fn to_pixel(&self, s: [f64; 2]) -> [f64; 2] {
        [
            (s[0] - self.origin[0]) / self.scale - 0.5,
            (s[1] - self.origin[1]) / self.scale - 0.5,
        ]
    }
}

/// A photo fit on a background thread.
#[derive(Clone, Debug)]
pub struct PhotoFitJob {
    state: Arc<Mutex<FitState>>,
}

/// What a [`PhotoFitJob`] has done so far.
#[derive(Clone, Debug, Default)]
pub struct FitState {
    /// Iterates seen.
    pub iterations: u64,
    /// The result once done (shared: the state is copied out).
    pub done: Option<std::result::Result<Arc<FitReport>, Arc<Error>>>,
}

impl PhotoFitJob {
    /// Starts fitting `problem` (its marks as edited, from its starting
    /// numbers).
    pub fn start(problem: &Problem) -> PhotoFitJob {
        let state = Arc::new(Mutex::new(FitState::default()));
        let problem = problem.clone();
        let (seen, done) = (Arc::clone(&state), Arc::clone(&state));
        std::thread::spawn(move || {
            let hook: crate::fit::solve::IterateHook =
                Arc::new(move |_: &str, _: &crate::fit::IterationRecord| {
                    if let Ok(mut s) = seen.lock() {
                        s.iterations += 1;
                    }
                });
            let result = crate::fit::fit(&problem, Some(hook))
                .map(Arc::new)
                .map_err(Arc::new);
            if let Ok(mut s) = done.lock() {
                s.done = Some(result);
            }
        });
        PhotoFitJob { state }
    }

    /// The state so far.
    pub fn state(&self) -> FitState {
        self.state.lock().map(|s| s.clone()).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// A flat-earth photo problem in `dir` (a 480 × 320 PNG): six targets
    /// at 0.5–8 km marked where the true air and camera put them, the file
    /// starting with the camera turned `off` degrees (azimuth and tilt) and
    /// the air's strength `scale`.
    fn fixture(dir: &Path, off: f64, scale: f64) -> PathBuf {
        image::RgbImage::from_pixel(480, 320, image::Rgb([90, 120, 160]))
            .save(dir.join("photo.png"))
            .unwrap();
        let targets: Vec<Value> = (0..6)
            .map(|k| {
                let d = 500.0 * 16f64.powf(k as f64 / 5.0);
                let a = (-3.0 + 1.2 * k as f64).to_radians();
                json!({"name": format!("target {k}"), "pixel": [240.0, 160.0],
                       "target": [d * a.sin(), 2.0 + 5.0 * k as f64, d * a.cos()]})
            })
            .collect();
        let mut v = json!({
            "name": "photo-mode", "description": "kept as written",
            "photo": {"image": "photo.png", "camera": {"horizontal_fov": 8.0,
                "azimuth": 0.0, "tilt": 0.0, "position": [0.0, 10.0, 0.0]}},
            "medium": {"scale": 0.0025, "background": {"n": 1.0, "a": 300.0},
                       "inversion": {"n": 0.9, "a": 5.0, "height": 6.0}},
            "marks": targets,
            "free": ["scale", "camera.azimuth", "camera.tilt"],
            "trace": {"method": "dopri5", "tolerance": 1e-10},
        });
        let path = dir.join("p.json");
        std::fs::write(&path, v.to_string()).unwrap();
        let truth = PhotoSession::open(&path).unwrap();
        for (m, r) in v["marks"]
            .as_array_mut()
            .unwrap()
            .iter_mut()
            .zip(&truth.report.marks)
        {
            m["pixel"] = json!(r.predicted.unwrap());
        }
        v["photo"]["camera"]["azimuth"] = json!(off);
        v["photo"]["camera"]["tilt"] = json!(off);
        v["medium"]["scale"] = json!(scale);
        std::fs::write(&path, serde_json::to_string_pretty(&v).unwrap()).unwrap();
        path
    }

    #[test]
    fn edits_are_validated_undone_when_bad_and_saved_into_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = fixture(dir.path(), 0.0, 0.0025);
        let mut s = PhotoSession::open(&path).unwrap();
        // At the truth every prediction is its mark.
        assert!(s.report.rms_pixels < 1e-6, "{}", s.report.rms_pixels);
        assert_eq!(s.named_targets().len(), 6);
        let i = s.add_mark([100.25, 80.5], NewTarget::Named(2)).unwrap();
        assert_eq!(i, 6);
        assert_eq!(s.marks[6].target, s.marks[2].target);
        assert_eq!(s.report.marks.len(), 7);
        // Its residual is its distance from target 2's pixel.
        let p2 = s.marks[2].pixel;
        let miss = (p2[0] - 100.25).hypot(p2[1] - 80.5);
        assert!(
            (s.report.marks[6].residual - miss).abs() < 1e-3 * miss,
            "{} {miss}",
            s.report.marks[6].residual
        );
        // A typed point; a pixel outside the image is refused and undone.
        s.add_mark(
            [10.0, 10.0],
            NewTarget::Point(Point::Local([50.0, 12.0, 900.0])),
        )
        .unwrap();
        let before = s.marks.clone();
        let err = s.add_mark([900.0, 10.0], NewTarget::Named(0)).unwrap_err();
        assert!(err.to_string().contains("marks[8].pixel"), "{err}");
        let err = s.move_mark(0, [10.0, -40.0]).unwrap_err();
        assert!(err.to_string().contains("marks[0].pixel"), "{err}");
        assert_eq!(s.marks, before);
        // A horizon mark needs the round earth: refused here.
        assert!(s.add_mark([5.0, 5.0], NewTarget::Horizon).is_err());
        assert!(s.add_mark([5.0, 5.0], NewTarget::Named(17)).is_err());
        // Hit-testing picks the nearest mark within the radius.
        assert_eq!(s.hit([100.0, 81.0], 3.0), Some(6));
        assert_eq!(s.hit([100.0, 90.0], 3.0), None);
        s.move_mark(6, [p2[0], p2[1]]).unwrap();
        assert!(s.report.marks[6].residual < 1e-6);
        s.delete_mark(7).unwrap();
        assert_eq!(s.marks.len(), 7);
        // Saving: the marks replaced, the rest as it was (key order too).
        let out = dir.path().join("saved.json");
        s.save(&out).unwrap();
        let saved: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        let original: Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        let keys = |v: &Value| v.as_object().unwrap().keys().cloned().collect::<Vec<_>>();
        assert_eq!(keys(&saved), keys(&original));
        for k in keys(&original).iter().filter(|k| *k != "marks") {
            assert_eq!(saved[k], original[k], "{k}");
        }
        let back = PhotoSession::open(&out).unwrap();
        assert_eq!(back.marks, s.marks);
        assert!(PhotoSession::open(&path).unwrap().marks.len() == 6);
        // The last mark cannot go.
        let mut one = back;
        while one.marks.len() > 1 {
            one.delete_mark(0).unwrap();
        }
        let err = one.delete_mark(0).unwrap_err();
        assert!(err.to_string().contains("marks"), "{err}");
        assert_eq!(one.marks.len(), 1);
    }

    #[test]
    fn the_background_fit_brings_the_marks_home() {
        let dir = tempfile::tempdir().unwrap();
        let path = fixture(dir.path(), 0.03, 0.002);
        let mut s = PhotoSession::open(&path).unwrap();
        let before = s.report.rms_pixels;
        assert!(before > 1.0, "{before}");
        let job = PhotoFitJob::start(&s.problem);
        let start = std::time::Instant::now();
        let state = loop {
            let st = job.state();
            if st.done.is_some() {
                break st;
            }
            assert!(start.elapsed().as_secs() < 120, "the fit did not finish");
            std::thread::sleep(std::time::Duration::from_millis(20));
        };
        assert!(state.iterations > 0);
        let report = state.done.unwrap().unwrap();
        s.take_fit(&report).unwrap();
        assert!(
            s.report.rms_pixels < 1e-3,
            "{before} → {}",
            s.report.rms_pixels
        );
        for (p, truth) in report.parameters.iter().zip([0.0025, 0.0, 0.0]) {
            assert!((p.value - truth).abs() < 1e-4, "{}: {}", p.name, p.value);
        }
        // A mark edited after the fit keeps the fitted numbers.
        let p = s.marks[0].pixel;
        s.move_mark(0, [p[0] + 3.0, p[1] + 4.0]).unwrap();
        assert!((s.report.marks[0].residual - 5.0).abs() < 0.01);
    }

    #[test]
    fn the_frame_centres_the_photo_and_maps_pixels_both_ways() {
        let f = PhotoFrame::fit([10.0, 20.0], [800.0, 600.0], [400, 100]);
        assert_eq!(f.scale, 2.0);
        assert_eq!(f.origin, [10.0, 20.0 + 200.0]);
        // The top-left pixel's centre is half a pixel in from the corner.
        assert_eq!(f.to_screen([0.0, 0.0]), [11.0, 221.0]);
        for p in [[0.0, 0.0], [123.25, 77.5], [399.5, 99.5]] {
            let q = f.to_pixel(f.to_screen(p));
            assert!((q[0] - p[0]).abs() < 1e-12 && (q[1] - p[1]).abs() < 1e-12);
        }
        let fields = ["43.2".to_string(), "5.3".into(), " 48 ".into()];
        assert_eq!(
            typed_point(&fields, true),
            Some(Point::Geo(GeoPoint {
                latitude: 43.2,
                longitude: 5.3,
                height: 48.0
            }))
        );
        assert_eq!(
            typed_point(&fields, false),
            Some(Point::Local([43.2, 5.3, 48.0]))
        );
        let bad = ["1".to_string(), "x".into(), "2".into()];
        assert_eq!(typed_point(&bad, false), None);
        let inf = ["1".to_string(), "inf".into(), "2".into()];
        assert_eq!(typed_point(&inf, false), None);
    }
}
