//! Proposing terms: which term to try next, and the seeds its fits start from.
//!
//! - **Hot spot**: the pairs that fit worst (the [`WORST_PAIRS`] largest
//!   |rᵢ|) are the ones a missing hot spot would have bent. Each one's launch
//!   line (origin toward `through`) is followed to where it meets the ground,
//!   or, if it stays above it, to its lowest point before the target's
//!   distance: a hot spot that turned the ray up lies there. A seed is a spot
//!   centred under that point with radius [`RADIUS_SHARES`] of its distance
//!   from the observer, strength −2·S (S the current amplitude sum: the spot
//!   twice the rest, as in the bundled hot road) and vertical rate −0.4 × the
//!   lowest observer's height (the hot layer below the eyes).
//! - **Inversion**: a layer at heights spread over the rays' height range
//!   (origins, `through` points and targets), a quarter of the range apart, of
//!   either sign, its rate an eighth of the range.
//!
//! Bounds keep every seed's fit in the scene: centres within the pairs' box
//! widened by half its size, radii from 0.5 m to the longest pair's distance,
//! rates of the seeded sign (a rate never crosses zero, where the model is
//! undefined), layers within the height range widened by its size.

use super::model::{Model, Term};
use crate::medium::{HotSpot, Inversion};
use crate::pair::PointPair;

/// How many of the worst-fitting pairs seed hot spots.
pub const WORST_PAIRS: usize = 3;

/// Seed radii, as shares of the distance from the observer to the seed's centre.
pub const RADIUS_SHARES: [f64; 2] = [0.1, 0.25];

/// The rim sharpness e (1/m) of a grown hot spot, not fitted: a rim 4/e = 8 m
/// wide, smooth enough that a seed's rays feel the rim move, and one the
/// pairs rarely determine (see the README, "Growing the model").
pub const GROWN_EDGE: f64 = 0.5;

/// A term to try, with the models its fits start from.
#[derive(Clone, Debug)]
pub struct Candidate {
    /// The term it adds.
    pub term: Term,
    /// One model per seed.
    pub seeds: Vec<Model>,
}

/// The extent of the pairs: what seeds and bounds are scaled by.
#[derive(Clone, Copy, Debug)]
struct Scene {
    /// Lowest and highest height of any origin, `through` point or target (m).
    heights: (f64, f64),
    /// Lowest observer (m).
    lowest_origin: f64,
    /// x and z range of every point (m).
    x: (f64, f64),
    z: (f64, f64),
    /// Longest horizontal distance from an origin to its target (m).
    reach: f64,
}

impl Scene {
    fn of(pairs: &[PointPair]) -> Scene {
        let pts = || pairs.iter().flat_map(|p| [p.origin, p.through, p.target]);
        let range = |k: usize| {
            pts().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), q| {
                (lo.min(q[k]), hi.max(q[k]))
            })
        };
        Scene {
            heights: range(1),
            lowest_origin: pairs
                .iter()
                .map(|p| p.origin[1])
                .fold(f64::INFINITY, f64::min),
            x: range(0),
            z: range(2),
            reach: pairs
                .iter()
                .map(|p| horizontal(p.origin, p.target))
                .fold(0.0, f64::max),
        }
    }
}

fn horizontal(a: [f64; 3], b: [f64; 3]) -> f64 {
    (b[0] - a[0]).hypot(b[2] - a[2])
}

/// Where `pair`'s launch line meets the ground before the target's distance,
/// else its lowest point there: (x, z, horizontal distance from the origin).
pub fn lowest_ground_point(pair: &PointPair) -> (f64, f64, f64) {
    let o = pair.origin;
    let d = [
        pair.through[0] - o[0],
        pair.through[1] - o[1],
        pair.through[2] - o[2],
    ];
    let dh = d[0].hypot(d[2]);
    let reach = horizontal(o, pair.target);
    if dh <= 0.0 {
        return (o[0], o[2], 0.0);
    }
    // Parameter t along d per metre of horizontal distance.
    let per_metre = 1.0 / dh;
    let s = if d[1] < 0.0 {
        (-o[1] / d[1] / per_metre).min(reach)
    } else {
        // A rising line is lowest at the origin; a spot under the observer
        // would bend nothing, so take the middle of its way instead.
        0.5 * reach
    };
    let t = s * per_metre;
    (o[0] + t * d[0], o[2] + t * d[2], s)
}

/// The candidates for the next step from `model`, whose pairs have residual
/// norms `misfit` (one per pair, in order).
pub fn propose(model: &Model, pairs: &[PointPair], misfit: &[f64]) -> Vec<Candidate> {
    let scene = Scene::of(pairs);
    let s = model.medium.amplitude_sum().max(f64::MIN_POSITIVE);
    let mut out = Vec::new();
    if model.medium.inversion.is_none() {
        out.push(Candidate {
            term: Term::Inversion,
            seeds: inversion_seeds(model, &scene, s),
        });
    }
    let seeds = hot_spot_seeds(model, pairs, misfit, &scene, s);
    if !seeds.is_empty() {
        out.push(Candidate {
            term: Term::HotSpot(model.medium.hotspots.len()),
            seeds,
        });
    }
    out
}

fn inversion_seeds(model: &Model, scene: &Scene, s: f64) -> Vec<Model> {
    let (lo, hi) = scene.heights;
    let span = (hi - lo).max(1.0);
    let bounds = [
        (f64::NEG_INFINITY, f64::INFINITY),
        (1e-3, 10.0 * span),
        (lo - span, hi + span),
    ];
    let mut seeds = Vec::new();
    for sign in [1.0, -1.0] {
        for k in 0..4 {
            let layer = Inversion {
                n: sign * s,
                a: span / 8.0,
                height: lo + (k as f64 + 0.5) / 4.0 * span,
            };
            seeds.push(model.with_inversion(layer, bounds));
        }
    }
    seeds
}

fn hot_spot_seeds(
    model: &Model,
    pairs: &[PointPair],
    misfit: &[f64],
    scene: &Scene,
    s: f64,
) -> Vec<Model> {
    let mut order: Vec<usize> = (0..pairs.len()).collect();
    // Worst first; the index breaks ties, so the order is reproducible.
    order.sort_by(|&i, &j| misfit[j].total_cmp(&misfit[i]).then(i.cmp(&j)));
    let (wx, wz) = (
        0.5 * (scene.x.1 - scene.x.0).max(scene.reach),
        0.5 * (scene.z.1 - scene.z.0).max(scene.reach),
    );
    let rate = -0.4 * scene.lowest_origin.max(0.1);
    let bounds = |_: f64| {
        [
            (scene.x.0 - wx, scene.x.1 + wx),
            (scene.z.0 - wz, scene.z.1 + wz),
            (0.5, scene.reach.max(1.0)),
            (f64::NEG_INFINITY, f64::INFINITY),
            (-10.0 * scene.heights.1.abs().max(1.0), -1e-3),
        ]
    };
    let mut centres: Vec<(f64, f64, f64)> = Vec::new();
    for &i in order.iter().take(WORST_PAIRS) {
        let c = lowest_ground_point(&pairs[i]);
        // Two worst pairs through the same place seed one centre.
        let near = centres
            .iter()
            .any(|q| (q.0 - c.0).hypot(q.1 - c.1) < RADIUS_SHARES[0] * c.2.max(1.0));
        if !near {
            centres.push(c);
        }
    }
    let mut seeds = Vec::new();
    for (x, z, dist) in centres {
        for share in RADIUS_SHARES {
            let radius = (share * dist).max(1.0);
            let spot = HotSpot {
                x,
                z,
                radius,
                n: -2.0 * s,
                a: rate,
                edge: GROWN_EDGE,
            };
            seeds.push(model.with_hot_spot(spot, bounds(radius)));
        }
    }
    seeds
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_falling_line_is_seeded_where_it_meets_the_ground() {
        // From 1.5 m, falling 1.5 m over 100 m: meets the ground at z = 100.
        let pair = PointPair {
            origin: [0.0, 1.5, 0.0],
            through: [0.0, 0.0, 100.0],
            target: [0.0, 0.3, 300.0],
            weight: 1.0,
            wavelength: None,
        };
        let (x, z, d) = lowest_ground_point(&pair);
        assert!(x.abs() < 1e-12 && (z - 100.0).abs() < 1e-9 && (d - 100.0).abs() < 1e-9);
        // Beyond the target's distance the line is cut there.
        let far = PointPair {
            through: [30.0, 1.4, 40.0],
            ..pair
        };
        let (x, z, d) = lowest_ground_point(&far);
        assert!((d - 300.0).abs() < 1e-9 && (x - 180.0).abs() < 1e-9 && (z - 240.0).abs() < 1e-9);
    }
}
