//! `mirage fit --grow` (`src/fit/grow/`): on the bundled problems made from
//! known air (no term, an inversion, one and two hot spots) with noisy
//! targets, started from the background alone, growing finds exactly the true
//! terms, at the noise floor; and the grown model is the same bit for bit on
//! one thread and two.
//!
//! `cargo test --test grow -- --ignored regenerate` rewrites the problems in
//! `problems/grow/` from the truths below.

use mirage::fit::synthetic::retarget;
use mirage::math::SplitMix64;
use mirage::medium::{LogisticMedium, Medium};
use mirage::pair::PointPair;
use mirage::problem::Problem;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::process::Command;

/// The starting medium of every example: the background alone.
const BACKGROUND: &str = r#"{"scale": 0.02, "background": {"n": 1.0, "a": 150.0}}"#;

/// One bundled example: its truth and how its targets were made.
struct Example {
    name: &'static str,
    description: &'static str,
    /// The air the targets were traced through.
    truth: &'static str,
    /// Endpoint noise σ (m) added to each target, in its plane.
    noise: f64,
    seed: u64,
}

const EXAMPLES: [Example; 4] = [
    Example {
        name: "none",
        description: "Nothing to add: the targets were traced through the background alone (plus 5 mm of noise). Growing must keep the background and add no term.",
        truth: BACKGROUND,
        noise: 0.005,
        seed: 1,
    },
    Example {
        name: "inversion",
        description: "A warm layer at 3 m over cold ground: the targets were traced through the background plus an inversion (n 0.6, a 0.4 m, height 3 m), then moved by 5 mm of noise. Growing from the background alone must add the inversion and nothing else.",
        truth: r#"{"scale": 0.032, "background": {"n": 1.0, "a": 150.0}, "inversion": {"n": 0.6, "a": 0.4, "height": 3.0}}"#,
        noise: 0.005,
        seed: 2,
    },
    Example {
        name: "one-hot-spot",
        description: "A hot patch of road 40 m across, 190 m ahead and 30 m to the left: the targets were traced through the background plus that hot spot (n -2, a -0.4 m, edge 0.5 /m), then moved by 8 mm of noise. Growing from the background alone must add one hot spot there and nothing else.",
        truth: r#"{"scale": 0.06, "background": {"n": 1.0, "a": 150.0}, "hotspots": [{"x": -30.0, "z": 190.0, "radius": 40.0, "n": -2.0, "a": -0.4, "edge": 0.5}]}"#,
        noise: 0.008,
        seed: 3,
    },
    Example {
        name: "two-hot-spots",
        description: "Two hot patches, one 190 m ahead on the left and one 260 m ahead on the right: the targets were traced through the background plus both hot spots, then moved by 10 mm of noise. Growing from the background alone must add two hot spots, one at each patch, and nothing else.",
        truth: r#"{"scale": 0.09, "background": {"n": 1.0, "a": 150.0}, "hotspots": [{"x": -30.0, "z": 190.0, "radius": 40.0, "n": -2.0, "a": -0.4, "edge": 0.5}, {"x": 35.0, "z": 260.0, "radius": 45.0, "n": -1.5, "a": -0.5, "edge": 0.5}]}"#,
        noise: 0.01,
        seed: 4,
    },
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

fn file_of(name: &str) -> PathBuf {
    root().join("problems/grow").join(format!("{name}.json"))
}

fn medium(text: &str) -> LogisticMedium {
    serde_json::from_str(text).unwrap()
}

/// The pairs of every example: three observers 1.4–2 m up, each looking
/// toward four places 400 m ahead (from 90 m left to 90 m right) along five
/// lines: three into the ground 150, 220 and 300 m out (the rays a hot patch
/// there turns up) and two rising to 3.5 and 6 m (the rays a layer bends).
fn pairs() -> Vec<PointPair> {
    let mut out = Vec::new();
    for origin in [[-30.0f64, 1.4, 0.0], [0.0, 2.0, 0.0], [30.0, 1.6, 0.0]] {
        for x in [-90.0f64, -30.0, 30.0, 90.0] {
            let far = [x, 0.0, 400.0];
            let (dx, dz) = (far[0] - origin[0], far[2] - origin[2]);
            let reach = dx.hypot(dz);
            // The point `s` metres out along the line toward `far`, at height `y`.
            let at = |s: f64, y: f64| [origin[0] + dx * s / reach, y, origin[2] + dz * s / reach];
            let mut lines: Vec<([f64; 3], [f64; 3])> = [150.0, 220.0, 300.0]
                .iter()
                .map(|&g| {
                    // Through the ground g metres out; the target where the
                    // line is at the far distance (below ground: retargeting
                    // moves it to where the ray ends).
                    (at(g, 0.0), at(reach, origin[1] * (1.0 - reach / g)))
                })
                .collect();
            for y in [3.5, 6.0] {
                lines.push((at(reach, y), at(reach, y)));
            }
            for (through, target) in lines {
                out.push(PointPair {
                    origin,
                    through,
                    target,
                    weight: 1.0,
                    wavelength: None,
                });
            }
        }
    }
    out
}

/// A standard normal number (Box–Muller).
fn normal(rng: &mut SplitMix64) -> f64 {
    let u = 1.0 - rng.next_f64();
    let v = rng.next_f64();
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

fn problem_json(ex: &Example, pairs: &[PointPair]) -> Value {
    json!({
        "name": format!("grow-{}", ex.name),
        "description": ex.description,
        "medium": serde_json::from_str::<Value>(BACKGROUND).unwrap(),
        "pairs": pairs,
        "trace": { "method": "dopri5", "tolerance": 1e-8 },
        "solver": { "method": "lm", "grow": true, "noise": ex.noise, "max_terms": 3 }
    })
}

/// Rewrites `problems/grow/*.json`: the pairs' targets traced through each
/// truth, then moved by Gaussian noise of σ in the two directions of the
/// target's plane (up, and across the line of sight).
#[test]
#[ignore = "rewrites the bundled problems"]
fn regenerate() {
    for ex in &EXAMPLES {
        let path = file_of(ex.name);
        let draft = problem_json(ex, &pairs());
        let problem = Problem::parse(&draft.to_string(), &path).unwrap();
        let truth = Medium::Logistic(medium(ex.truth));
        let (mut traced, failed) = retarget(&problem.pairs, &truth.field(), &problem.trace);
        assert!(
            failed.is_empty(),
            "{}: pairs {failed:?} unreachable",
            ex.name
        );
        let mut rng = SplitMix64(ex.seed);
        for p in &mut traced {
            let (dx, dz) = (p.target[0] - p.origin[0], p.target[2] - p.origin[2]);
            let h = dx.hypot(dz);
            let (across_x, across_z) = (-dz / h, dx / h);
            let (a, b) = (normal(&mut rng), normal(&mut rng));
            p.target[0] += ex.noise * a * across_x;
            p.target[1] += ex.noise * b;
            p.target[2] += ex.noise * a * across_z;
        }
        let text = serde_json::to_string_pretty(&problem_json(ex, &traced)).unwrap();
        std::fs::write(&path, text + "\n").unwrap();
    }
}
