//! Problem files (`docs/problem-format.md`): load, validate, and turn into a
//! [`Problem`] the rest of mirage can trust.
//!
//! ```json
//! {
//!   "name": "desert-road",
//!   "description": "Hot asphalt: the sky appears as water below the horizon.",
//!   "medium": { "scale": 1.0, "background": { "n": 1.0, "a": 40.0 },
//!               "hotspots": [ { "x": 0, "z": 600, "radius": 120, "n": -2, "a": -0.4 } ] },
//!   "free": ["hotspots[0].n", "hotspots[0].radius"],
//!   "bounds": { "hotspots[0].radius": [1.0, 500.0] },
//!   "pairs": [ { "origin": [0, 1.6, 0], "through": [0, -1.2, 900], "target": [0, 30, 900] } ],
//!   "trace":  { "method": "rk4", "step": 1.0 },
//!   "solver": { "method": "lm", "max_iterations": 200 }
//! }
//! ```
//!
//! | field | meaning |
//! | --- | --- |
//! | `medium` | the starting medium ([`Medium`]: the logistic model of `docs/model.md`); a term left out is not modelled |
//! | `free` | parameters the fit may change, by path name; absent: trace and report only |
//! | `bounds` | optional `[low, high]` per free parameter |
//! | `pairs` | point pairs: `origin`, `through`, `target` (metres), optional `weight`, optional `wavelength` (nm, real air only: the pair is traced with `air.wavelength` replaced by it), optional `noise` (σᵢ, m: the grown model's criterion) |
//! | `trace` | `method`: `rk4` (with `step`, metres) or `dopri5` (alias `adaptive`, with `tolerance`); optional `max_length` |
//! | `solver` | `method`: `lm`, `nelder-mead` or `auto` (LM, restarts, Nelder–Mead fallback); `max_iterations`, `starts`, `ftol`, `xtol`, `gtol`, `seed`, `target_objective` (m², default 1e-12), `simplex_xtol`, `simplex_ftol`; `grow`, `noise`, `max_terms` (`crate::fit::grow`) |

mod photo;
mod solver;
mod trace;

pub use solver::{
    DEFAULT_MAX_TERMS, DEFAULT_SIMPLEX_FTOL, DEFAULT_SIMPLEX_XTOL, GrowSettings, SolverMethod,
    SolverSettings, SolverSpec, check_max_terms, check_noise, grow_unsupported, solver_settings,
};
pub use trace::{DEFAULT_STEP, DEFAULT_TOLERANCE, TraceSpec, trace_options};

use crate::error::{Error, Result};
use crate::geo::Site;
use crate::io::json::{parse_json, read_input};
use crate::medium::{Medium, Param};
use crate::pair::{PairEntry, PointPair};
use crate::photo::spec::{MarkEntry, PhotoSetup, PhotoSpec};
use crate::trace::{EarthSpec, TraceOptions};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The problem file exactly as written.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ProblemFile {
    /// Short name.
    #[serde(default)]
    pub name: Option<String>,
    /// What a user would see.
    #[serde(default)]
    pub description: Option<String>,
    /// Starting medium.
    pub medium: Medium,
    /// Free parameters by path name.
    #[serde(default)]
    pub free: Vec<String>,
    /// Bounds per free parameter.
    #[serde(default)]
    pub bounds: BTreeMap<String, [f64; 2]>,
    /// The point pairs, each with its optional endpoint noise (none in a
    /// photo problem: its marks are its observations).
    #[serde(default)]
    pub pairs: Vec<PairEntry>,
    /// The photograph and its camera (`docs/photo.md`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub photo: Option<PhotoSpec>,
    /// The marks on the photograph.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub marks: Vec<MarkEntry>,
    /// The marks' noise σ (pixels).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise: Option<f64>,
    /// Integration settings.
    #[serde(default)]
    pub trace: TraceSpec,
    /// Solver settings.
    #[serde(default)]
    pub solver: SolverSpec,
    /// The round earth (`{"radius": R}`); absent: the flat ground, or with
    /// a `site` the sphere of WGS 84's Gaussian mean radius there.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub earth: Option<EarthSpec>,
    /// Where the local frame stands on the earth (`docs/geo.md`): needed by
    /// geographic points.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub site: Option<Site>,
    /// What a pair's residual measures: the miss in metres (`distance`, the
    /// default) or in angle (`angle`: the miss over the pair's range).
    #[serde(default, skip_serializing_if = "Residual::is_distance")]
    pub residual: Residual,
}

/// What a pair's residual measures (`docs/geo.md`, "Residuals in angle").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Residual {
    /// r = w·(endpoint − target), metres.
    #[default]
    Distance,
    /// r = w·(endpoint − target) / |target − origin|, radians inside
    /// (arcseconds in reports and in `noise`).
    Angle,
}

impl Residual {
    /// Whether it is the default, [`Residual::Distance`].
    pub fn is_distance(&self) -> bool {
        *self == Residual::Distance
    }

    /// A noise σ as files and flags give it (metres; arcseconds for angle
    /// residuals) in the residual's own unit (metres; radians).
    pub fn noise_in_residual_units(self, sigma: f64) -> f64 {
        match self {
            Residual::Distance => sigma,
            Residual::Angle => sigma / crate::sightline::ARCSEC_PER_RADIAN,
        }
    }
}

/// A validated problem.
#[derive(Clone, Debug)]
pub struct Problem {
    /// Where it was read from (for messages).
    pub source: PathBuf,
    /// Short name (the file stem if the file has none).
    pub name: String,
    /// What a user would see.
    pub description: String,
    /// Starting medium (valid per `docs/model.md`).
    pub medium: Medium,
    /// Free parameters, in the order of the file.
    pub free: Vec<Param>,
    /// `[low, high]` per free parameter (±∞ where unbounded).
    pub bounds: Vec<(f64, f64)>,
    /// The point pairs.
    pub pairs: Vec<PointPair>,
    /// Per pair, its endpoint noise σᵢ (m) when the file gives one
    /// (`pairs[i].noise`; the grown model's criterion, `crate::fit::grow`).
    pub pair_noise: Vec<Option<f64>>,
    /// Integration settings, the ground (`earth`) included.
    pub trace: TraceOptions,
    /// The `trace` section, normalised (echoed in results).
    pub trace_spec: TraceSpec,
    /// Solver settings.
    pub solver: SolverSettings,
    /// What a residual measures; with [`Residual::Angle`] each pair's
    /// weight was divided by its range |target − origin| at load.
    pub residual: Residual,
    /// The photograph, its camera and marks (`docs/photo.md`): the pairs
    /// are then its target marks', in order, with residuals in pixels.
    pub photo: Option<PhotoSetup>,
}

pub use crate::geo::earth_of;

impl Problem {
    /// The bounds of every fitted number: the medium's free parameters',
    /// then a photo's camera's (the order of the fit's x).
    pub fn all_bounds(&self) -> Vec<(f64, f64)> {
        let mut b = self.bounds.clone();
        if let Some(p) = &self.photo {
            b.extend(&p.bounds);
        }
        b
    }

    /// Reads and validates a problem file.
    pub fn load(path: &Path) -> Result<Problem> {
        Problem::parse(&read_input(path)?, path)
    }

    /// Parses and validates the text of a problem file; `path` is only used in
    /// messages.
    pub fn parse(text: &str, path: &Path) -> Result<Problem> {
        let file: ProblemFile = parse_json(text, path, "problem")?;
        Problem::from_file(file, path)
    }

    /// Validates a parsed problem file.
    pub fn from_file(file: ProblemFile, path: &Path) -> Result<Problem> {
        let bad = |field: String, message: String| Error::input(path, field, message);
        file.medium
            .validate()
            .map_err(|e| e.within("medium").in_file(path))?;

        if let Some(e) = &file.earth {
            e.validate().map_err(|e| e.within("earth").in_file(path))?;
        }
        if let Some(s) = &file.site {
            s.validate().map_err(|e| e.within("site").in_file(path))?;
        }
        let earth = earth_of(file.earth, file.site.as_ref());
        let mut pairs = Vec::with_capacity(file.pairs.len());
        for (i, pair) in file.pairs.iter().enumerate() {
            let resolved = pair
                .validate()
                .and_then(|()| pair.resolve(file.site.as_ref(), earth))
                .and_then(|p| p.validate().map(|()| p))
                .and_then(|p| p.validate_on(earth).map(|()| p))
                .map_err(|e| e.within(&format!("pairs[{i}]")).in_file(path))?;
            let mut resolved = resolved;
            if file.residual == Residual::Angle {
                // r = w·(e − t)/|t − o|: the miss as an angle seen from the origin.
                resolved.weight /= (resolved.target() - resolved.origin()).norm();
            }
            pairs.push(resolved);
            if pair.wavelength.is_some() && !file.medium.is_dispersive() {
                return Err(bad(
                    format!("pairs[{i}].wavelength"),
                    format!(
                        "a per-pair wavelength needs real air (`medium.air`), but this medium is the {} model, which has no wavelength",
                        file.medium.kind_name()
                    ),
                ));
            }
        }

        let mut free = Vec::with_capacity(file.free.len());
        let is_camera = |name: &str| name.starts_with("camera.");
        for (i, name) in file.free.iter().enumerate() {
            if is_camera(name) {
                continue;
            }
            let p: Param = name.parse().map_err(|e: crate::medium::ParamParseError| {
                bad(format!("free[{i}]"), e.to_string())
            })?;
            if file.medium.get(p).is_none() {
                return Err(bad(
                    format!("free[{i}]"),
                    format!(
                        "`{name}` is not a parameter of this medium: {}",
                        file.medium.absent_reason(p)
                    ),
                ));
            }
            if free.contains(&p) {
                return Err(bad(
                    format!("free[{i}]"),
                    format!("`{name}` is listed twice"),
                ));
            }
            free.push(p);
        }
        let photo = photo::load(
            photo::PhotoFields {
                photo: file.photo.as_ref(),
                marks: &file.marks,
                noise: file.noise,
                free: (file.free.iter().enumerate())
                    .filter(|(_, n)| is_camera(n))
                    .map(|(i, n)| (i, n.as_str()))
                    .collect(),
                bounds: (file.bounds.iter())
                    .filter(|(n, _)| is_camera(n))
                    .map(|(n, b)| (n.as_str(), *b))
                    .collect(),
            },
            path,
            file.site.as_ref(),
            earth,
        )?;
        let photo = match photo {
            None => None,
            Some((setup, mark_pairs)) => {
                if !file.pairs.is_empty() {
                    return Err(bad(
                        "pairs".into(),
                        "a photo problem's observations are its `marks`: give no `pairs` beside them".into(),
                    ));
                }
                if file.residual != Residual::Distance {
                    return Err(bad(
                        "residual".into(),
                        "a photo problem's residuals are in pixels: leave `residual` out".into(),
                    ));
                }
                if setup.marks.iter().any(|m| m.target.is_none())
                    && !crate::medium::IndexField::is_stratified(&file.medium.field())
                {
                    return Err(bad(
                        "marks".into(),
                        format!(
                            "horizon marks need air that depends on height alone; this medium ({}) has areal terms (hot spots)",
                            file.medium.kind_name()
                        ),
                    ));
                }
                pairs = mark_pairs;
                Some(setup)
            }
        };
        let observations = pairs.len() + photo.as_ref().map_or(0, |p| p.marks.len() - pairs.len());
        let camera_free = photo.as_ref().map_or(0, |p| p.free.len());
        if free.len() + camera_free > 0 && observations == 0 {
            return Err(bad(
                "pairs".into(),
                format!(
                    "{} free parameter(s) but no point pairs to fit them to",
                    free.len() + camera_free
                ),
            ));
        }

        let mut bounds = vec![(f64::NEG_INFINITY, f64::INFINITY); free.len()];
        for (name, &[low, high]) in &file.bounds {
            if is_camera(name) {
                continue;
            }
            let field = format!("bounds.{name}");
            let p: Param = name
                .parse()
                .map_err(|e: crate::medium::ParamParseError| bad(field.clone(), e.to_string()))?;
            let Some(k) = free.iter().position(|q| *q == p) else {
                return Err(bad(
                    field,
                    format!(
                        "`{name}` is not a free parameter; bounds apply only to parameters listed in `free`"
                    ),
                ));
            };
            if low.is_nan() || high.is_nan() {
                return Err(bad(field, "bounds must be numbers".into()));
            }
            if low > high {
                return Err(bad(
                    field,
                    format!("low bound {low} is above high bound {high}"),
                ));
            }
            let start = file.medium.get(p).unwrap_or(f64::NAN);
            if !(low..=high).contains(&start) {
                return Err(bad(
                    field,
                    format!(
                        "the starting value {start} of `{name}` lies outside its bounds [{low}, {high}]"
                    ),
                ));
            }
            bounds[k] = (low, high);
        }

        let (mut trace, trace_spec) = trace_options(&file.trace, path)?;
        trace.earth = earth;
        let solver = solver_settings(&file.solver, path)?;
        if solver.grow.is_some()
            && let Some(why) = grow_unsupported(&file.medium)
        {
            return Err(bad("solver.grow".into(), why));
        }
        let name = file.name.clone().unwrap_or_else(|| {
            path.file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "problem".into())
        });
        let pair_noise = match &photo {
            Some(p) => vec![p.noise; pairs.len()],
            None => file.pairs.iter().map(|p| p.noise).collect(),
        };
        Ok(Problem {
            source: path.to_path_buf(),
            name,
            description: file.description.clone().unwrap_or_default(),
            medium: file.medium,
            free,
            bounds,
            pairs,
            pair_noise,
            trace,
            trace_spec,
            solver,
            residual: file.residual,
            photo,
        })
    }
}
