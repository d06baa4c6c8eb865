//! Scenes for growing, made from a known truth: the generator behind
//! `tests/grow_generator.rs` and the README's table of what `mirage fit
//! --grow` finds (`docs/problem-format.md`, "Growing").
//!
//! A case is drawn from a seed: a geometry (one to three observers 1.5–5.5 m
//! up, lines of sight to 0.3–4 km, 9–28 pairs, flat or round ground), a true
//! air of one family (nothing beyond the background, a layer, one hot spot,
//! two hot spots) of either kind (the logistic model or real air in kelvins),
//! the pairs' targets traced through that air, then moved by Gaussian noise
//! of σ = 3–10 mm in their target planes (up along the local vertical, and
//! across the line of sight). The start is the truth's background alone (the
//! logistic background, or the base air), with a free set drawn from what a
//! user would free there (none, `scale`, `scale` and `background.a`; none or
//! the lapse).
//!
//! **Every true term is visible.** Each term of the truth, taken out, moves
//! the endpoints by χ² ≥ [`MIN_TERM_CHI2`] (at the case's σ); a term drawn
//! weaker is drawn again (up to 40 times), so a case's right answer is the
//! truth's set of terms, not a matter of luck. A pair whose ray cannot be
//! traced through the truth (a cold layer that sends it into the ground, say)
//! is left out; a case keeps at least 9 pairs.
//!
//! Nothing here knows how growing works: the cases are only the truth, the
//! problem and the truth's own F on the noisy pairs.

use crate::error::Result;
use crate::evaluate::trace_pairs;
use crate::math::SplitMix64;
use crate::medium::Medium;
use crate::problem::Problem;
use serde_json::{Value, json};
use std::path::Path;

/// The least χ² by which every true term moves the endpoints.
pub const MIN_TERM_CHI2: f64 = 400.0;

/// The earth's radius of the round cases (m).
pub const EARTH_RADIUS: f64 = 6_371_000.0;

/// The terms of a true air, beyond its background.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// Nothing: growing must add no term.
    Nothing,
    /// A layer: the logistic inversion; in real air the surface layer or the
    /// step aloft.
    Layer,
    /// One hot spot.
    OneSpot,
    /// Two hot spots.
    TwoSpots,
}

impl Family {
    /// All four, in order.
    pub const ALL: [Family; 4] = [
        Family::Nothing,
        Family::Layer,
        Family::OneSpot,
        Family::TwoSpots,
    ];

    /// A short name.
    pub fn name(self) -> &'static str {
        match self {
            Family::Nothing => "nothing",
            Family::Layer => "layer",
            Family::OneSpot => "one-spot",
            Family::TwoSpots => "two-spots",
        }
    }
}

/// Which model the truth (and the start) is written in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// The logistic model (`docs/model.md`).
    Logistic,
    /// Real air in kelvins (`docs/air.md`).
    Air,
}

/// What to draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CaseSpec {
    /// The true terms.
    pub family: Family,
    /// The model.
    pub kind: Kind,
    /// Over the round earth (radius [`EARTH_RADIUS`]) or the flat ground.
    pub round: bool,
    /// The seed of everything else.
    pub seed: u64,
}

impl CaseSpec {
    /// The `i`-th case of the standard family: the four families, both
    /// kinds, flat and round ground, cycling so that any 8 consecutive
    /// indices from a multiple of 8 hold every (family, kind) pair once;
    /// indices 8–15 are over the round earth, the others alternate.
    pub fn standard(i: u64) -> CaseSpec {
        let family = Family::ALL[(i % 4) as usize];
        let kind = if (i / 4) % 2 == 0 {
            Kind::Logistic
        } else {
            Kind::Air
        };
        let block = i / 8;
        let round = block % 3 == 1 || (block % 3 == 2 && i % 2 == 1);
        CaseSpec {
            family,
            kind,
            round,
            seed: 0x6d69_7261_6765 ^ (i.wrapping_mul(0x9e37_79b9_7f4a_7c15)),
        }
    }
}

/// The true terms, as growing should find them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Terms {
    /// The logistic inversion or real air's step aloft.
    pub inversion: bool,
    /// Real air's surface layer (`air.temperature.exponential`).
    pub surface: bool,
    /// Hot spots.
    pub spots: usize,
}

impl Terms {
    /// The terms of `medium` beyond its background.
    pub fn of(medium: &Medium) -> Terms {
        match medium {
            Medium::Logistic(l) => Terms {
                inversion: l.inversion.is_some(),
                surface: false,
                spots: l.hotspots.len(),
            },
            Medium::Air(a) => Terms {
                inversion: a.air.temperature.inversion.is_some(),
                surface: a.air.temperature.exponential.is_some(),
                spots: a.hotspots.len(),
            },
            Medium::LinearSquare(_) => Terms {
                inversion: false,
                surface: false,
                spots: 0,
            },
        }
    }

    /// In words: `inversion + 2 hot spots`, `nothing`.
    pub fn describe(&self) -> String {
        let mut t = Vec::new();
        if self.surface {
            t.push("surface layer".to_string());
        }
        if self.inversion {
            t.push("inversion".to_string());
        }
        match self.spots {
            0 => {}
            1 => t.push("1 hot spot".into()),
            k => t.push(format!("{k} hot spots")),
        }
        if t.is_empty() {
            "nothing".into()
        } else {
            t.join(" + ")
        }
    }
}

/// A drawn case.
#[derive(Clone, Debug)]
pub struct GrowCase {
    /// `logistic-one-spot-round-3`.
    pub name: String,
    /// What it was drawn from.
    pub spec: CaseSpec,
    /// The endpoint noise σ (m) added to the targets and given to growing.
    pub noise: f64,
    /// The air the targets were traced through.
    pub truth: Medium,
    /// The problem file: the start, the noisy pairs, `solver.grow` with σ.
    pub file: Value,
    /// The problem, parsed from `file`.
    pub problem: Problem,
    /// F of the noisy pairs traced through the truth (m²).
    pub truth_objective: f64,
    /// Observers, the farthest target (m), for the table.
    pub observers: usize,
    /// The farthest target's horizontal distance (m).
    pub reach: f64,
}

impl GrowCase {
    /// The true terms.
    pub fn terms(&self) -> Terms {
        Terms::of(&self.truth)
    }
}

/// A uniform number in [lo, hi).
fn uniform(rng: &mut SplitMix64, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * rng.next_f64()
}

/// A standard normal number (Box–Muller).
fn normal(rng: &mut SplitMix64) -> f64 {
    let u = 1.0 - rng.next_f64();
    let v = rng.next_f64();
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// A line of sight: observer index, unit horizontal direction, the
/// `through` point's (horizontal distance, height) and the target's.
type Line = (usize, [f64; 2], [f64; 2], [f64; 2]);

/// The scene's lines of sight.
struct Geometry {
    /// Observers (x, eye height, z), all at z = 0.
    eyes: Vec<[f64; 3]>,
    /// The lines of sight.
    lines: Vec<Line>,
    /// The farthest horizontal distance (m).
    reach: f64,
    /// Heights the rays pass: the lowest eye and the highest target (m).
    heights: (f64, f64),
    /// Ground points of the falling lines: (x, z, distance from the eye).
    ground: Vec<(f64, f64, f64)>,
}

/// The point at horizontal (arc) distance `s` along `dir` from the foot of
/// `eye`, `h` above the ground: on the flat ground or the sphere.
fn point(eye: [f64; 3], dir: [f64; 2], s: f64, h: f64, round: bool) -> [f64; 3] {
    if !round {
        return [eye[0] + dir[0] * s, h, eye[2] + dir[1] * s];
    }
    // The sphere touches y = 0 at the origin; the eye's foot is (x₀, ·, 0),
    // near enough the touching point for these scenes (|x₀| ≤ 60 m) that the
    // small tilt of its vertical does not matter: points are placed exactly
    // on the sphere at the given height and horizontal position.
    let r = EARTH_RADIUS;
    let (x, z) = (eye[0] + dir[0] * s, eye[2] + dir[1] * s);
    let rho = x.hypot(z);
    let phi = rho / r;
    let (sx, sz) = if rho > 0.0 {
        (x / rho, z / rho)
    } else {
        (0.0, 0.0)
    };
    let horiz = (r + h) * phi.sin();
    [sx * horiz, (r + h) * phi.cos() - r, sz * horiz]
}

fn draw_geometry(rng: &mut SplitMix64) -> Geometry {
    let observers = 1 + (rng.next_u64() % 3) as usize;
    let reach = (uniform(rng, 300f64.ln(), 4000f64.ln())).exp();
    let eyes: Vec<[f64; 3]> = (0..observers)
        .map(|k| {
            let x = if observers == 1 {
                0.0
            } else {
                -50.0 + 100.0 * k as f64 / (observers - 1) as f64
            };
            [x, uniform(rng, 1.5, 5.5), 0.0]
        })
        .collect();
    let pairs_wanted = 9 + (rng.next_u64() % 20) as usize;
    let per_direction = 3 + (rng.next_u64() % 2) as usize;
    let per_observer = observers * per_direction;
    // At least three directions from a lone observer, two from each of
    // several: a hot spot's place is seen from more than one line.
    let mut directions = (pairs_wanted / per_observer).max(if observers == 1 { 3 } else { 2 });
    while observers * per_direction * directions < 9 {
        directions += 1;
    }
    let half_angle = uniform(rng, 8f64, 30f64).to_radians();
    let low = eyes.iter().map(|e| e[1]).fold(f64::INFINITY, f64::min);
    let mut lines = Vec::new();
    let mut ground = Vec::new();
    let mut top: f64 = 0.0;
    for (k, eye) in eyes.iter().enumerate() {
        for j in 0..directions {
            let t = if directions == 1 {
                0.0
            } else {
                -1.0 + 2.0 * j as f64 / (directions - 1) as f64
            };
            let a = t * half_angle + uniform(rng, -0.02, 0.02);
            let dir = [a.sin(), a.cos()];
            let d = reach * uniform(rng, 0.85, 1.0);
            for m in 0..per_direction {
                if m < 2 {
                    // Falling: through the ground at a share of the distance.
                    let share = if m == 0 {
                        uniform(rng, 0.2, 0.45)
                    } else {
                        uniform(rng, 0.5, 0.85)
                    };
                    let g = share * d;
                    // On the line, where it is at the far distance.
                    let far_h = eye[1] * (1.0 - d / g);
                    lines.push((k, dir, [g, 0.0], [d, far_h]));
                    ground.push((eye[0] + dir[0] * g, eye[2] + dir[1] * g, g));
                } else {
                    let h = eye[1] * uniform(rng, 1.2, 3.5) + uniform(rng, 0.0, 2.0);
                    top = top.max(h);
                    lines.push((k, dir, [d, h], [d, h]));
                }
            }
        }
    }
    Geometry {
        eyes,
        lines,
        reach,
        heights: (low, top.max(low)),
        ground,
    }
}

/// Two true hot spots are apart: no line of sight passes within this many
/// metres of both rims, so that one spot cannot stand for two.
const SPOT_GAP: f64 = 20.0;

/// The horizontal distance from (x, z) to `line`'s way from its observer to
/// its target.
fn line_gap(eyes: &[[f64; 3]], line: &Line, (x, z): (f64, f64)) -> f64 {
    let (k, dir, _, target) = *line;
    let (ox, oz) = (eyes[k][0], eyes[k][2]);
    let t = ((x - ox) * dir[0] + (z - oz) * dir[1]).clamp(0.0, target[0]);
    (ox + t * dir[0] - x).hypot(oz + t * dir[1] - z)
}

/// The truth's background and its terms, drawn.
fn draw_truth(spec: &CaseSpec, g: &Geometry, rng: &mut SplitMix64) -> Option<Value> {
    let (low, top) = g.heights;
    let spot_at = |rng: &mut SplitMix64, avoid: Option<(f64, f64, f64)>| {
        // Under one of the falling lines' ground points, away from `avoid`.
        for _ in 0..64 {
            let (x, z, dist) = g.ground[(rng.next_u64() % g.ground.len() as u64) as usize];
            let radius = (uniform(rng, 0.05, 0.12) * dist).clamp(10.0, 250.0);
            let (x, z) = (
                x + uniform(rng, -0.3, 0.3) * radius,
                z + uniform(rng, -0.3, 0.3) * radius,
            );
            match avoid {
                Some((ax, az, ar))
                    if (x - ax).hypot(z - az) < 1.3 * (radius + ar)
                        || g.lines.iter().any(|l| {
                            line_gap(&g.eyes, l, (ax, az)) < ar + SPOT_GAP
                                && line_gap(&g.eyes, l, (x, z)) < radius + SPOT_GAP
                        }) =>
                {
                    continue;
                }
                _ => return Some((x, z, radius)),
            }
        }
        None
    };
    let edge = |rng: &mut SplitMix64| if rng.next_f64() < 0.5 { 0.5 } else { 10.0 };
    let spots = match spec.family {
        Family::OneSpot => 1,
        Family::TwoSpots => 2,
        _ => 0,
    };
    let mut placed: Vec<(f64, f64, f64)> = Vec::new();
    for _ in 0..spots {
        // No place for a second spot apart from the first: draw again.
        placed.push(spot_at(rng, placed.first().copied())?);
    }
    match spec.kind {
        Kind::Logistic => {
            let bg_a = uniform(rng, 100.0, 300.0);
            let base_scale = uniform(rng, 0.01, 0.03);
            let mut sum = 1.0;
            let mut m = json!({"background": {"n": 1.0, "a": bg_a}});
            if spec.family == Family::Layer {
                let n = uniform(rng, 0.3, 1.0) * if rng.next_f64() < 0.75 { 1.0 } else { -1.0 };
                let height = uniform(rng, low, top);
                m["inversion"] = json!({"n": n, "a": uniform(rng, 0.15, 0.8), "height": height});
                sum += n.abs();
            }
            let mut hs = Vec::new();
            for &(x, z, radius) in &placed {
                // δ of 0.4–1.2 times the background's (C·k/S = 3–9·10⁻⁵):
                // 1.2–11·10⁻⁵ at the ground, a road 10–100 K hotter than the
                // air above it.
                let n = -uniform(rng, 0.4, 1.2);
                sum += n.abs();
                hs.push(json!({"x": x, "z": z, "radius": radius, "n": n,
                    "a": -uniform(rng, 0.1, 0.3) * low, "edge": edge(rng)}));
            }
            if !hs.is_empty() {
                m["hotspots"] = Value::Array(hs);
            }
            // The background keeps its strength: scale grows with S.
            m["scale"] = json!(base_scale * sum);
            Some(m)
        }
        Kind::Air => {
            let mut t = json!({"base": uniform(rng, 5.0, 30.0)});
            if spec.family == Family::Layer {
                if rng.next_f64() < 0.5 {
                    let delta = if rng.next_f64() < 0.6 {
                        uniform(rng, 3.0, 15.0)
                    } else {
                        -uniform(rng, 2.0, 6.0)
                    };
                    t["exponential"] =
                        json!({"delta": delta, "scale_height": uniform(rng, 0.1, 0.35) * low});
                } else {
                    let delta =
                        uniform(rng, 1.0, 6.0) * if rng.next_f64() < 0.7 { 1.0 } else { -1.0 };
                    t["inversion"] = json!({"delta": delta, "height": uniform(rng, low, top),
                        "thickness": uniform(rng, 0.2, 1.2)});
                }
            }
            let mut m = json!({"air": {"temperature": t, "hydrostatic": false,
                "refractivity": {"gladstone_dale": 0.0801}}});
            let hs: Vec<Value> = placed
                .iter()
                .map(|&(x, z, radius)| {
                    json!({"x": x, "z": z, "radius": radius, "edge": edge(rng),
                        "delta": uniform(rng, 5.0, 20.0),
                        "scale_height": uniform(rng, 0.08, 0.25) * low})
                })
                .collect();
            if !hs.is_empty() {
                m["hotspots"] = Value::Array(hs);
            }
            Some(m)
        }
    }
}

/// The truth without its terms: the start's medium.
fn background_of(truth: &Value, kind: Kind) -> Value {
    let mut m = truth.clone();
    match kind {
        Kind::Logistic => {
            let o = m.as_object_mut().unwrap();
            let n_bg = 1.0;
            let sum: f64 = n_bg
                + o.get("inversion")
                    .map_or(0.0, |i| i["n"].as_f64().unwrap().abs())
                + o.get("hotspots").map_or(0.0, |h| {
                    h.as_array()
                        .unwrap()
                        .iter()
                        .map(|s| s["n"].as_f64().unwrap().abs())
                        .sum()
                });
            let scale = o["scale"].as_f64().unwrap() / sum;
            o.remove("inversion");
            o.remove("hotspots");
            o.insert("scale".into(), json!(scale));
        }
        Kind::Air => {
            let o = m.as_object_mut().unwrap();
            o.remove("hotspots");
            let t = o["air"]["temperature"].as_object_mut().unwrap();
            t.remove("exponential");
            t.remove("inversion");
        }
    }
    m
}

/// Each true term taken out of `truth` in turn (the inversion, the surface
/// layer, each hot spot), the others kept with their strengths.
fn without_each(truth: &Value, kind: Kind) -> Vec<Value> {
    let mut out = Vec::new();
    let spots = truth["hotspots"].as_array().map_or(0, Vec::len);
    let rescale = |m: &mut Value, removed_n: f64| {
        if kind == Kind::Logistic {
            let s = m["scale"].as_f64().unwrap();
            let sum = total_n(m) + removed_n.abs();
            m["scale"] = json!(s * (sum - removed_n.abs()) / sum);
        }
    };
    for key in ["inversion", "exponential"] {
        let mut m = truth.clone();
        let removed = match kind {
            Kind::Logistic if key == "inversion" => m.as_object_mut().unwrap().remove(key),
            Kind::Air => m["air"]["temperature"].as_object_mut().unwrap().remove(key),
            _ => None,
        };
        if let Some(r) = removed {
            rescale(&mut m, r["n"].as_f64().unwrap_or(0.0));
            out.push(m);
        }
    }
    for j in 0..spots {
        let mut m = truth.clone();
        let r = m["hotspots"].as_array_mut().unwrap().remove(j);
        if m["hotspots"].as_array().unwrap().is_empty() {
            m.as_object_mut().unwrap().remove("hotspots");
        }
        rescale(&mut m, r["n"].as_f64().unwrap_or(0.0));
        out.push(m);
    }
    out
}

/// Σ|n| of a logistic medium's JSON.
fn total_n(m: &Value) -> f64 {
    let mut s = m["background"]["n"].as_f64().unwrap_or(0.0).abs();
    s += m["inversion"]["n"].as_f64().unwrap_or(0.0).abs();
    if let Some(h) = m["hotspots"].as_array() {
        s += h
            .iter()
            .map(|x| x["n"].as_f64().unwrap().abs())
            .sum::<f64>();
    }
    s
}

/// The free parameters a user would set on the start, and their start
/// values' perturbation.
fn draw_free(kind: Kind, start: &mut Value, rng: &mut SplitMix64) -> Vec<&'static str> {
    let pick = rng.next_u64() % 3;
    match kind {
        Kind::Logistic => {
            let free: Vec<&'static str> = match pick {
                0 => vec![],
                1 => vec!["scale"],
                _ => vec!["scale", "background.a"],
            };
            if !free.is_empty() {
                let s = start["scale"].as_f64().unwrap();
                start["scale"] = json!(s * uniform(rng, 0.7, 1.4));
            }
            if free.len() == 2 {
                let a = start["background"]["a"].as_f64().unwrap();
                start["background"]["a"] = json!(a * uniform(rng, 0.7, 1.4));
            }
            free
        }
        Kind::Air => match pick {
            0 | 1 => vec![],
            _ => {
                start["air"]["temperature"]["lapse"] = json!(0.0);
                vec!["air.temperature.lapse"]
            }
        },
    }
}

fn problem_of(value: &Value, name: &str) -> Result<Problem> {
    Problem::parse(&value.to_string(), Path::new(name))
}

/// Traces `file`'s pairs through `medium` and moves each target to its
/// endpoint, until the target planes settle; pairs that cannot be traced
/// are dropped.
fn retarget(file: &mut Value, medium: &Medium, name: &str) -> Result<()> {
    for _ in 0..6 {
        let problem = problem_of(file, name)?;
        let report = trace_pairs(&problem, medium);
        let pairs = file["pairs"].as_array_mut().unwrap();
        let mut kept = Vec::new();
        let mut moved: f64 = 0.0;
        for (p, r) in pairs.iter().zip(&report.pairs) {
            if r.unreachable || r.endpoint.iter().any(|v| !v.is_finite()) {
                continue;
            }
            let mut p = p.clone();
            moved = moved.max(r.distance);
            p["target"] = json!(r.endpoint);
            kept.push(p);
        }
        *pairs = kept;
        if moved < 1e-10 {
            break;
        }
    }
    Ok(())
}

/// χ² by which the endpoints of `problem`'s pairs move between media `a`
/// and `b`, at noise σ.
fn separation(problem: &Problem, a: &Medium, b: &Medium, sigma: f64) -> f64 {
    let (ra, rb) = (trace_pairs(problem, a), trace_pairs(problem, b));
    ra.pairs
        .iter()
        .zip(&rb.pairs)
        .map(|(p, q)| {
            (0..3)
                .map(|k| (p.endpoint[k] - q.endpoint[k]).powi(2))
                .sum::<f64>()
        })
        .sum::<f64>()
        / (sigma * sigma)
}

/// Draws the case `spec` (see the module doc).
pub fn draw(spec: CaseSpec) -> Result<GrowCase> {
    let kind_name = match spec.kind {
        Kind::Logistic => "logistic",
        Kind::Air => "air",
    };
    let name = format!(
        "{kind_name}-{}-{}-{:x}",
        spec.family.name(),
        if spec.round { "round" } else { "flat" },
        spec.seed & 0xffff
    );
    let mut rng = SplitMix64(spec.seed);
    let noise = uniform(&mut rng, 0.003, 0.010);
    for _attempt in 0..40 {
        let g = draw_geometry(&mut rng);
        let Some(truth_value) = draw_truth(&spec, &g, &mut rng) else {
            continue;
        };
        let truth: Medium = match serde_json::from_value(truth_value.clone()) {
            Ok(m) => m,
            Err(_) => continue,
        };
        if truth.validate().is_err() {
            continue;
        }
        let mut start = background_of(&truth_value, spec.kind);
        let free = draw_free(spec.kind, &mut start, &mut rng);
        let pairs: Vec<Value> = g
            .lines
            .iter()
            .map(|&(k, dir, th, ta)| {
                let eye = g.eyes[k];
                json!({
                    "origin": eye,
                    "through": point(eye, dir, th[0], th[1], spec.round),
                    "target": point(eye, dir, ta[0], ta[1], spec.round),
                })
            })
            .collect();
        let mut file = json!({
            "name": name,
            "description": "",
            "medium": start,
            "free": free,
            "pairs": pairs,
            "trace": {"method": "dopri5", "tolerance": 1e-8},
            "solver": {"method": "lm", "grow": true, "noise": noise},
        });
        if spec.round {
            file["earth"] = json!({"radius": EARTH_RADIUS});
        }
        retarget(&mut file, &truth, &name)?;
        if file["pairs"].as_array().unwrap().len() < 9 {
            continue;
        }
        let clean = problem_of(&file, &name)?;
        // Every true term visible.
        let visible = without_each(&truth_value, spec.kind).iter().all(|w| {
            serde_json::from_value::<Medium>(w.clone())
                .is_ok_and(|w| separation(&clean, &truth, &w, noise) >= MIN_TERM_CHI2)
        });
        if !visible {
            continue;
        }
        // The noise: up along the target's vertical, across the line of sight.
        for p in file["pairs"].as_array_mut().unwrap() {
            let o: Vec<f64> = serde_json::from_value(p["origin"].clone()).unwrap();
            let mut t: Vec<f64> = serde_json::from_value(p["target"].clone()).unwrap();
            let (dx, dz) = (t[0] - o[0], t[2] - o[2]);
            let h = dx.hypot(dz);
            let up = if spec.round {
                let c = [t[0], t[1] + EARTH_RADIUS, t[2]];
                let n = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
                [c[0] / n, c[1] / n, c[2] / n]
            } else {
                [0.0, 1.0, 0.0]
            };
            let across = [-dz / h, 0.0, dx / h];
            let (a, b) = (normal(&mut rng), normal(&mut rng));
            for k in 0..3 {
                t[k] += noise * (a * across[k] + b * up[k]);
            }
            p["target"] = json!(t);
        }
        let terms = Terms::of(&truth).describe();
        file["description"] = json!(format!(
            "Drawn by the growth generator (seed {:#x}): {} observer(s), targets to {:.0} m, {} ground; the truth has {terms}; targets moved by {:.1} mm of noise.",
            spec.seed,
            g.eyes.len(),
            g.reach,
            if spec.round { "round" } else { "flat" },
            noise * 1e3
        ));
        let problem = problem_of(&file, &name)?;
        let truth_objective = trace_pairs(&problem, &truth).totals.objective;
        return Ok(GrowCase {
            name,
            spec,
            noise,
            truth,
            file,
            problem,
            truth_objective,
            observers: g.eyes.len(),
            reach: g.reach,
        });
    }
    Err(crate::error::Error::input(
        Path::new(&name),
        "generator",
        "no visible truth drawn in 40 attempts",
    ))
}
