//! What the previewer shows: a scene file, or a problem file seen as a scene
//! (its medium over a plain ground, from the first pair's origin); the medium
//! must be of a kind the shader evaluates: the logistic model (which the
//! editor also edits) or real air.

use crate::error::{Error, FieldError, Result};
use crate::io::json::{parse_json, read_input};
use crate::medium::{LogisticMedium, Medium};
use crate::problem::Problem;
use crate::scene::Scene;
use crate::scene::description::{CameraSpec, SceneFile};
use std::path::{Path, PathBuf};

/// Default size of a headless frame when the input does not fix one (a problem
/// file) and for `--bench`.
pub const BENCH_SIZE: (u32, u32) = (1280, 720);

/// What the previewer shows: a scene, and for a problem file its pairs.
#[derive(Clone, Debug)]
pub struct Input {
    /// The file given.
    pub path: PathBuf,
    /// The scene (for a problem: its medium over a plain ground, seen from
    /// the first pair's origin).
    pub scene: Scene,
    /// The problem, when the input is one.
    pub problem: Option<Problem>,
}

/// Whether the previewer's shader evaluates `medium`'s kind (the logistic
/// model, real air), else the error naming the kind.
pub fn previewable(medium: &Medium) -> std::result::Result<(), FieldError> {
    match medium {
        Medium::Air(m) if m.air.humidity.table().is_some() => Err(FieldError::new(
            "medium.air.humidity",
            "the previewer's tables take one relative humidity; this air has a humidity table (use `mirage render`, or give one number)",
        )),
        Medium::Logistic(_) | Medium::Air(_) => Ok(()),
        other => Err(FieldError::new(
            "medium",
            format!(
                "the previewer shows the logistic model and real air; this medium is of kind `{}` (use `mirage render`)",
                other.kind_name()
            ),
        )),
    }
}

/// The logistic parameters of `medium`, or the error that the previewer's
/// editor (its sliders, drags and fit edit logistic parameters) cannot edit
/// this kind.
pub fn logistic<'a>(medium: &'a Medium, file: &Path) -> Result<&'a LogisticMedium> {
    medium.as_logistic().ok_or_else(|| {
        FieldError::new(
            "medium",
            format!(
                "the previewer edits the logistic model only; this medium is of kind `{}` (edit the file, or use `mirage fit`)",
                medium.kind_name()
            ),
        )
        .in_file(file)
    })
}

/// Reads a scene or a problem file (a scene has a `camera`, a problem `pairs`);
/// its medium must be of a kind the shader evaluates ([`previewable`]).
pub fn load_input(path: &Path) -> Result<Input> {
    let input = load_any_input(path)?;
    previewable(&input.scene.medium).map_err(|e| e.in_file(path))?;
    Ok(input)
}

fn load_any_input(path: &Path) -> Result<Input> {
    let text = read_input(path)?;
    let value: serde_json::Value = parse_json(&text, path, "scene or problem")?;
    let is_scene = value.get("camera").is_some();
    let is_problem = value.get("pairs").is_some();
    match (is_scene, is_problem) {
        (true, _) => Ok(Input {
            path: path.to_path_buf(),
            scene: Scene::parse(&text, path)?,
            problem: None,
        }),
        (false, true) => {
            let problem = Problem::parse(&text, path)?;
            let scene = problem_scene(&problem, path)?;
            Ok(Input {
                path: path.to_path_buf(),
                scene,
                problem: Some(problem),
            })
        }
        (false, false) => Err(Error::input(
            path,
            "-",
            "neither a scene (no `camera`) nor a problem (no `pairs`)",
        )),
    }
}

/// The scene a problem is previewed in: its medium over a grey ground, seen
/// from the first pair's origin toward its `through` point with a 2° field of
/// view, and the sky behind.
pub fn problem_scene(problem: &Problem, path: &Path) -> Result<Scene> {
    let (position, look_at) = match problem.pairs.first() {
        Some(p) => (p.origin, p.through),
        None => ([0.0, 2.0, 0.0], [0.0, 2.0, 1000.0]),
    };
    let file = SceneFile {
        name: Some(problem.name.clone()),
        description: Some(problem.description.clone()),
        site: None,
        camera: CameraSpec {
            position: position.into(),
            look_at: Some(look_at.into()),
            elevation: None,
            azimuth: None,
            up: Some([0.0, 1.0, 0.0]),
            vertical_fov: 2.0,
            width: BENCH_SIZE.0,
            height: BENCH_SIZE.1,
            roll: None,
            distortion: None,
        },
        medium: Some(problem.medium.clone()),
        medium_from: None,
        ground: Some(crate::scene::description::GroundSpec {
            albedo: None,
            checker: Some(crate::scene::description::CheckerSpec {
                size: 10.0,
                colors: [[0.10, 0.10, 0.10], [0.16, 0.15, 0.13]],
            }),
        }),
        earth: problem.trace.earth.spec(),
        objects: Vec::new(),
        sun: Default::default(),
        sky: None,
        samples_per_pixel: None,
        trace: Default::default(),
        exposure: None,
        glare: None,
        dispersion: None,
    };
    Scene::from_file(file, path)
}
