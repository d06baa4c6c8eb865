//! Editing the air in the previewer, apart from any window: slider ranges for
//! the medium's parameters, hot spots picked and dragged on the ground, the
//! pairs' current endpoint distances, the fit run in the background, and
//! saving the edited medium into a copy of the input file.

use crate::error::{Error, Result};
use crate::evaluate::trace_pairs;
use crate::fit::IterationRecord;
use crate::io::write_atomic;
use crate::medium::{HotField, HotSpot, LogisticMedium, Medium, Param};
use crate::problem::Problem;
use crate::render::camera::Camera;
use glam::{DVec2, DVec3};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// The range of a parameter's slider, from its value when the editor opened
/// (and the problem's bounds for a free parameter): wide enough to explore,
/// fixed while dragging.
pub fn slider_range(p: Param, start: f64, bounds: Option<(f64, f64)>) -> (f64, f64) {
    if let Some((lo, hi)) = bounds
        && lo.is_finite()
        && hi.is_finite()
    {
        return (lo, hi);
    }
    let m = start.abs();
    let (lo, hi) = match p {
        Param::Scale => (0.0, (4.0 * m).max(0.1)),
        Param::BackgroundN | Param::InversionN | Param::Hot(_, HotField::N) => {
            let r = (2.0 * m).max(5.0);
            (-r, r)
        }
        Param::BackgroundA | Param::InversionA | Param::Hot(_, HotField::A) => {
            let r = (4.0 * m).max(1.0);
            (-r, r)
        }
        Param::InversionHeight => (0.0, (4.0 * m).max(100.0)),
        Param::Hot(_, HotField::X) | Param::Hot(_, HotField::Z) => {
            let r = (2.0 * m).max(1000.0);
            (start - r, start + r)
        }
        Param::Hot(_, HotField::Radius) => (0.0, (4.0 * m).max(100.0)),
        Param::Hot(_, HotField::Edge) => (0.01, (4.0 * m).max(20.0)),
        Param::LinearN0
        | Param::LinearG
        | Param::Air(_)
        | Param::Hot(_, HotField::Delta | HotField::ScaleHeight) => {
            (start - (m.max(1e-6)), start + m.max(1e-6))
        }
    };
    (lo.min(start), hi.max(start))
}

/// Where the straight camera ray through pixel (px, py) meets the ground
/// y = 0 (the editor picks with straight rays: a hot spot is placed on the
/// ground, not on its mirage).
pub fn ground_point(camera: &Camera, px: f64, py: f64) -> Option<DVec3> {
    let d = camera.direction(px, py);
    if d.y >= 0.0 || camera.origin.y <= 0.0 {
        return None;
    }
    let t = -camera.origin.y / d.y;
    Some(camera.origin + d * t)
}

/// What a drag on the ground does to a hot spot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Drag {
    /// Moves hot spot `index`, keeping the grab point's offset from its centre.
    Move {
        /// The hot spot.
        index: usize,
        /// Centre minus the grab point (x, z).
        offset: DVec2,
    },
    /// Resizes hot spot `index` (its rim follows the pointer).
    Resize {
        /// The hot spot.
        index: usize,
    },
}

/// The drag that starts at ground point (x, z): on a hot spot's rim (within
/// 15 % of its radius) resizes it, inside it moves it; the smallest hot spot
/// under the point wins.
pub fn pick(medium: &LogisticMedium, at: DVec2) -> Option<Drag> {
    let mut best: Option<(f64, Drag)> = None;
    for (index, h) in medium.hotspots.iter().enumerate() {
        let centre = DVec2::new(h.x, h.z);
        let rho = (at - centre).length();
        let rim = 0.15 * h.radius.max(1.0);
        let drag = if (rho - h.radius).abs() <= rim {
            Drag::Resize { index }
        } else if rho < h.radius {
            Drag::Move {
                index,
                offset: centre - at,
            }
        } else {
            continue;
        };
        if best.is_none_or(|(r, _)| h.radius < r) {
            best = Some((h.radius, drag));
        }
    }
    best.map(|(_, d)| d)
}

/// Applies a drag with the pointer now at ground point (x, z).
pub fn apply_drag(medium: &mut LogisticMedium, drag: Drag, at: DVec2) {
    match drag {
        Drag::Move { index, offset } => {
            if let Some(h) = medium.hotspots.get_mut(index) {
                let c = at + offset;
                h.x = c.x;
                h.z = c.y;
            }
        }
        Drag::Resize { index } => {
            if let Some(h) = medium.hotspots.get_mut(index) {
                h.radius = (at - DVec2::new(h.x, h.z)).length().max(0.5);
            }
        }
    }
}

/// A new hot spot at ground point (x, z): the first one's vertical profile
/// and strength if there is one, else a typical road hot spot.
pub fn new_hot_spot(medium: &LogisticMedium, at: DVec2) -> HotSpot {
    match medium.hotspots.first() {
        Some(h) => HotSpot {
            x: at.x,
            z: at.y,
            ..*h
        },
        None => HotSpot {
            x: at.x,
            z: at.y,
            radius: 50.0,
            n: -1.0,
            a: -0.4,
            edge: 0.5,
        },
    }
}

/// The current distance of every pair's endpoint from its target (metres;
/// infinite for a ray that never reaches its target plane).
pub fn pair_distances(problem: &Problem, medium: &LogisticMedium) -> Vec<f64> {
    trace_pairs(problem, &Medium::Logistic(medium.clone()))
        .pairs
        .iter()
        .map(|p| {
            if p.unreachable {
                f64::INFINITY
            } else {
                p.distance
            }
        })
        .collect()
}

/// The input file's text with its `medium` replaced by `medium` (and a
/// scene's `medium_from` dropped), pretty-printed. Every other field is kept
/// as written.
pub fn with_medium(text: &str, path: &Path, medium: &LogisticMedium) -> Result<String> {
    let mut value: serde_json::Value = serde_json::from_str(text)
        .map_err(|e| Error::input(path, "-", format!("not valid JSON: {e}")))?;
    let obj = value
        .as_object_mut()
        .ok_or_else(|| Error::input(path, "-", "the file is not a JSON object"))?;
    obj.remove("medium_from");
    obj.insert(
        "medium".to_string(),
        serde_json::to_value(medium).map_err(|e| Error::encode("the medium as JSON", e))?,
    );
    let mut out =
        serde_json::to_string_pretty(&value).map_err(|e| Error::encode("the file as JSON", e))?;
    out.push('\n');
    Ok(out)
}

/// The default name of the edited copy: `road.json` → `road-edited.json`,
/// next to the input.
pub fn edited_path(input: &Path) -> PathBuf {
    let stem = input
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "medium".to_string());
    input.with_file_name(format!("{stem}-edited.json"))
}

/// Saves the input file with the edited medium to `out`, atomically: the
/// medium is checked first, and a failed write leaves `out` as it was.
pub fn save(input: &Path, medium: &LogisticMedium, out: &Path) -> Result<()> {
    medium
        .validate()
        .map_err(|e| e.within("medium").in_file(out))?;
    let text = crate::io::json::read_input(input)?;
    let edited = with_medium(&text, input, medium)?;
    write_atomic(out, edited.as_bytes())
}

/// A fit's progress as the window shows it.
#[derive(Clone, Debug, Default)]
pub struct FitProgress {
    /// Iterates seen so far (all runs).
    pub iterations: u64,
    /// The best objective seen.
    pub best_objective: f64,
    /// The run now iterating.
    pub run: String,
    /// The result, once done: the fitted medium, or the error (shared: the
    /// progress is copied out to whoever asks).
    pub done: Option<std::result::Result<LogisticMedium, Arc<Error>>>,
}

/// A fit running on a background thread from the editor's current medium.
#[derive(Clone, Debug)]
pub struct FitJob {
    progress: Arc<Mutex<FitProgress>>,
}

impl FitJob {
    /// Starts fitting `problem`'s free parameters from `medium`.
    pub fn start(problem: &Problem, medium: &LogisticMedium) -> FitJob {
        let progress = Arc::new(Mutex::new(FitProgress {
            best_objective: f64::INFINITY,
            ..FitProgress::default()
        }));
        let mut problem = problem.clone();
        problem.medium = Medium::Logistic(medium.clone());
        let seen = Arc::clone(&progress);
        let done = Arc::clone(&progress);
        std::thread::spawn(move || {
            let hook: crate::fit::solve::IterateHook =
                Arc::new(move |label: &str, r: &IterationRecord| {
                    if let Ok(mut p) = seen.lock() {
                        p.iterations += 1;
                        p.best_objective = p.best_objective.min(r.objective);
                        if p.run != label {
                            p.run = label.to_string();
                        }
                    }
                });
            let result = crate::fit::fit(&problem, Some(hook))
                .and_then(|report| super::input::logistic(&report.medium, &problem.source).cloned())
                .map_err(Arc::new);
            if let Ok(mut p) = done.lock() {
                p.done = Some(result);
            }
        });
        FitJob { progress }
    }

    /// The progress so far.
    pub fn progress(&self) -> FitProgress {
        self.progress.lock().map(|p| p.clone()).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::description::CameraSettings;

    fn road_medium() -> LogisticMedium {
        serde_json::from_str(
            r#"{"scale": 0.02, "background": {"n": 1.0, "a": 150.0},
                "hotspots": [{"x": 0.0, "z": 160.0, "radius": 110.0, "n": -3.0, "a": -0.35, "edge": 0.5},
                             {"x": 5.0, "z": 170.0, "radius": 10.0, "n": -1.0, "a": -0.35}]}"#,
        )
        .unwrap()
    }

    #[test]
    fn ranges_hold_the_start_and_respect_bounds() {
        for (p, v) in road_medium().params() {
            let (lo, hi) = slider_range(p, v, None);
            assert!(
                lo <= v && v <= hi && lo < hi,
                "{p}: {v} not in [{lo}, {hi}]"
            );
        }
        assert_eq!(
            slider_range(Param::Scale, 0.02, Some((0.0, 0.05))),
            (0.0, 0.05)
        );
    }

    #[test]
    fn drags_pick_the_smallest_hot_spot_and_move_or_resize_it() {
        let mut m = road_medium();
        // Inside both: the small one wins.
        let d = pick(&m, DVec2::new(5.0, 171.0)).unwrap();
        assert_eq!(
            d,
            Drag::Move {
                index: 1,
                offset: DVec2::new(0.0, -1.0)
            }
        );
        apply_drag(&mut m, d, DVec2::new(25.0, 201.0));
        assert_eq!((m.hotspots[1].x, m.hotspots[1].z), (25.0, 200.0));
        // On the big one's rim: resize.
        let d = pick(&m, DVec2::new(0.0, 160.0 + 105.0)).unwrap();
        assert_eq!(d, Drag::Resize { index: 0 });
        apply_drag(&mut m, d, DVec2::new(0.0, 160.0 + 80.0));
        assert_eq!(m.hotspots[0].radius, 80.0);
        assert!(pick(&m, DVec2::new(500.0, 0.0)).is_none());
    }

    #[test]
    fn the_ground_point_is_under_the_image_centre() {
        let cam = Camera::new(&CameraSettings {
            position: DVec3::new(0.0, 1.2, 0.0),
            look_at: DVec3::new(0.0, 0.0, 12.0),
            up: DVec3::Y,
            vertical_fov: 30.0,
            width: 100,
            height: 50,
            lens: Default::default(),
        });
        let p = ground_point(&cam, 50.0, 25.0).unwrap();
        assert!((p - DVec3::new(0.0, 0.0, 12.0)).length() < 1e-9, "{p}");
        // Above the horizon there is no ground.
        assert!(ground_point(&cam, 50.0, 0.0).is_none());
    }

    #[test]
    fn the_background_fit_reports_progress_and_lands_the_pairs() {
        let input = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/hot-road.json");
        let problem = Problem::load(&input).unwrap();
        let start_medium = problem.medium.as_logistic().unwrap().clone();
        let before = pair_distances(&problem, &start_medium);
        let job = FitJob::start(&problem, &start_medium);
        let start = std::time::Instant::now();
        let progress = loop {
            let p = job.progress();
            if p.done.is_some() {
                break p;
            }
            assert!(start.elapsed().as_secs() < 120, "the fit did not finish");
            std::thread::sleep(std::time::Duration::from_millis(20));
        };
        assert!(progress.iterations > 0);
        let fitted = progress.done.unwrap().unwrap();
        let after = pair_distances(&problem, &fitted);
        let worst = after.iter().cloned().fold(0.0, f64::max);
        assert!(
            worst < 1e-6 && before.iter().cloned().fold(0.0, f64::max) > 1e-3,
            "before {before:?}, after {after:?}"
        );
    }

    #[test]
    fn saving_replaces_the_medium_and_keeps_the_rest() {
        let dir = tempfile::tempdir().unwrap();
        let input = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/hot-road.json");
        let out = dir.path().join("edited.json");
        let mut m = Problem::load(&input)
            .unwrap()
            .medium
            .as_logistic()
            .unwrap()
            .clone();
        m.scale *= 1.5;
        save(&input, &m, &out).unwrap();
        let back = Problem::load(&out).unwrap();
        assert_eq!(back.medium, Medium::Logistic(m.clone()));
        assert_eq!(back.pairs, Problem::load(&input).unwrap().pairs);
        // An invalid medium is refused and nothing is written.
        let bad_out = dir.path().join("bad.json");
        m.scale = 1e6;
        let err = save(&input, &m, &bad_out).unwrap_err();
        assert!(err.to_string().contains("medium.scale"), "{err}");
        assert!(!bad_out.exists());
        assert_eq!(
            edited_path(Path::new("a/road.json")),
            Path::new("a/road-edited.json")
        );
    }
}
