//! Proposing terms: which term to try next, and the seeds its fits start from.
//!
//! - **Hot spot**: the pairs that fit worst (the [`WORST_PAIRS`] largest
//!   |rᵢ|) are the ones a missing hot spot would have bent. Each one's launch
//!   line (origin toward `through`) is followed to where it meets the ground,
//!   or, if it stays above it, to its lowest point before the target's
//!   distance: a hot spot that turned the ray up lies there. A seed is a spot
//!   centred under that point with radius [`RADIUS_SHARES`] of its distance
//!   from the observer. Logistic: strength −2·S (S the current amplitude sum:
//!   the spot twice the rest, as in the bundled hot road) and vertical rate
//!   −0.4 × the lowest observer's height (the hot layer below the eyes). Real
//!   air: excesses of [`AIR_SPOT_DELTAS`] K and a scale height of
//!   [`AIR_SCALE_SHARE`] × the lowest observer's height.
//! - **Inversion**: a layer at heights spread over the rays' height range
//!   (origins, `through` points and targets), a quarter of the range apart, of
//!   either sign. Logistic: amplitude ±S, rate an eighth of the range. Real
//!   air (`air.temperature.inversion`): a step of ±[`AIR_DELTAS`] K, its
//!   thickness an eighth of the range.
//! - **Surface layer** (real air only, `air.temperature.exponential`): an
//!   excess of ±[`AIR_DELTAS`] K at the ground, its scale height
//!   [`SURFACE_SHARES`] of the lowest observer's height (a layer below the
//!   eyes, as over a warm road or a cold sea).
//!
//! Real air with a measured profile (`temperature.table`) grows hot spots
//! only: validation refuses analytic terms beside a table.
//!
//! Bounds keep every seed's fit in the scene and the medium's domain: centres
//! within the pairs' box widened by half its size, radii from 0.5 m to the
//! longest pair's distance, logistic rates of the seeded sign (a rate never
//! crosses zero, where the model is undefined), scale heights and thicknesses
//! from 1 mm up to ten times the height range (> 0, as real air requires),
//! excesses within ±[`AIR_MAX_DELTA`] K (far from −150 °C), layers within the
//! height range widened by its size.

use super::model::{Model, Term};
use crate::medium::air::{AirHotSpot, Exponential, Step};
use crate::medium::{HotSpot, Inversion, Medium};
use crate::pair::PointPair;
use crate::trace::Earth;

/// How many of the worst-fitting pairs seed hot spots.
pub const WORST_PAIRS: usize = 3;

/// Seed radii, as shares of the distance from the observer to the seed's centre.
pub const RADIUS_SHARES: [f64; 2] = [0.1, 0.25];

/// The rim sharpness e (1/m) of a grown hot spot, not fitted: a rim 4/e = 8 m
/// wide, smooth enough that a seed's rays feel the rim move, and one the
/// pairs rarely determine (see the README, "Growing the model").
pub const GROWN_EDGE: f64 = 0.5;

/// The magnitudes (K) of a real-air layer's seeds, each of either sign.
pub const AIR_DELTAS: [f64; 2] = [1.0, 5.0];

/// The excesses (K) of a real-air hot spot's seeds: hot patches, a warm one
/// and one as hot as a road's surface air in the sun.
pub const AIR_SPOT_DELTAS: [f64; 2] = [5.0, 15.0];

/// A real-air hot spot seed's scale height, as a share of the lowest
/// observer's height.
pub const AIR_SCALE_SHARE: f64 = 0.25;

/// A real-air surface layer's seed scale heights, as shares of the lowest
/// observer's height.
pub const SURFACE_SHARES: [f64; 2] = [0.05, 0.25];

/// The bound (K) on a grown real-air excess, either sign.
pub const AIR_MAX_DELTA: f64 = 50.0;

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
/// Over the round earth the ground is the sphere: the line meets it where
/// |o + t·u − c| = R, or is lowest where it passes closest to the centre.
pub fn lowest_ground_point(pair: &PointPair, earth: Earth) -> (f64, f64, f64) {
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
    // Horizontal distance s along the line, per unit of d: dh.
    let s = match earth {
        Earth::Flat => {
            if d[1] < 0.0 {
                (-o[1] / d[1] * dh).min(reach)
            } else {
                // A rising line is lowest at the origin; a spot under the
                // observer would bend nothing, so take the middle of its way.
                0.5 * reach
            }
        }
        Earth::Round { radius } => {
            // |q + t·d|² = R² with q = o − c: t² |d|² + 2t q·d + |q|² − R² = 0.
            let q = [o[0], o[1] + radius, o[2]];
            let dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            let b = (q[0] * d[0] + q[1] * d[1] + q[2] * d[2]) / dd;
            let c = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] - radius * radius) / dd;
            let disc = b * b - c;
            let t = if b < 0.0 && disc >= 0.0 {
                // The first crossing: −b − √(b² − c), written without the
                // cancellation of two near numbers (c = t₁·t₂).
                c / (-b + disc.sqrt())
            } else if b < 0.0 {
                // Closest to the centre, above the ground.
                -b
            } else {
                0.5 * reach / dh
            };
            (t * dh).min(reach)
        }
    };
    let t = s / dh;
    (o[0] + t * d[0], o[2] + t * d[2], s)
}

/// The candidates for the next step from `model`, whose pairs have residual
/// norms `misfit` (one per pair, in order).
pub fn propose(model: &Model, pairs: &[PointPair], misfit: &[f64], earth: Earth) -> Vec<Candidate> {
    let scene = Scene::of(pairs);
    let mut out = Vec::new();
    let centres = worst_centres(pairs, misfit, earth);
    match &model.medium {
        Medium::Logistic(m) => {
            let s = m.amplitude_sum().max(f64::MIN_POSITIVE);
            if m.inversion.is_none() {
                out.push(Candidate {
                    term: Term::Inversion,
                    seeds: inversion_seeds(model, &scene, s),
                });
            }
            out.push(Candidate {
                term: Term::HotSpot(m.hotspots.len()),
                seeds: hot_spot_seeds(model, &centres, &scene, s),
            });
        }
        Medium::Air(m) => {
            let t = &m.air.temperature;
            // A table takes no analytic term beside it.
            let analytic = t.table.is_none();
            if analytic && t.exponential.is_none() {
                out.push(Candidate {
                    term: Term::SurfaceLayer,
                    seeds: surface_seeds(model, &scene),
                });
            }
            if analytic && t.inversion.is_none() {
                out.push(Candidate {
                    term: Term::Inversion,
                    seeds: air_inversion_seeds(model, &scene),
                });
            }
            out.push(Candidate {
                term: Term::HotSpot(m.hotspots.len()),
                seeds: air_hot_spot_seeds(model, &centres, &scene),
            });
        }
        Medium::LinearSquare(_) => {}
    }
    out.retain(|c| !c.seeds.is_empty());
    out
}

/// The seed heights of a layer: spread over the rays' height range, a
/// quarter of it apart; and the range's size.
fn layer_heights(scene: &Scene) -> ([f64; 4], f64) {
    let (lo, hi) = scene.heights;
    let span = (hi - lo).max(1.0);
    (
        std::array::from_fn(|k| lo + (k as f64 + 0.5) / 4.0 * span),
        span,
    )
}

fn inversion_seeds(model: &Model, scene: &Scene, s: f64) -> Vec<Model> {
    let (heights, span) = layer_heights(scene);
    let (lo, hi) = scene.heights;
    let bounds = [
        (f64::NEG_INFINITY, f64::INFINITY),
        (1e-3, 10.0 * span),
        (lo - span, hi + span),
    ];
    let mut seeds = Vec::new();
    for sign in [1.0, -1.0] {
        for height in heights {
            let layer = Inversion {
                n: sign * s,
                a: span / 8.0,
                height,
            };
            seeds.push(model.with_inversion(layer, bounds));
        }
    }
    seeds
}

/// The signed seed excesses of a real-air layer: each of [`AIR_DELTAS`],
/// warm then cold.
fn air_deltas() -> impl Iterator<Item = f64> {
    AIR_DELTAS.into_iter().flat_map(|d| [d, -d])
}

fn air_inversion_seeds(model: &Model, scene: &Scene) -> Vec<Model> {
    let (heights, span) = layer_heights(scene);
    let (lo, hi) = scene.heights;
    let bounds = [
        (-AIR_MAX_DELTA, AIR_MAX_DELTA),
        (lo - span, hi + span),
        (1e-3, 10.0 * span),
    ];
    let mut seeds = Vec::new();
    for delta in air_deltas() {
        for height in heights {
            let step = Step {
                delta,
                height,
                thickness: span / 8.0,
            };
            seeds.push(model.with_air_inversion(step, bounds));
        }
    }
    seeds
}

fn surface_seeds(model: &Model, scene: &Scene) -> Vec<Model> {
    let (_, span) = layer_heights(scene);
    let bounds = [(-AIR_MAX_DELTA, AIR_MAX_DELTA), (1e-3, 10.0 * span)];
    let eyes = scene.lowest_origin.max(0.1);
    let mut seeds = Vec::new();
    for delta in air_deltas() {
        for share in SURFACE_SHARES {
            let layer = Exponential {
                delta,
                scale_height: share * eyes,
            };
            seeds.push(model.with_surface_layer(layer, bounds));
        }
    }
    seeds
}

/// The seed centres of a hot spot: under the [`WORST_PAIRS`] worst pairs'
/// launch lines (see [`lowest_ground_point`]), one per place.
fn worst_centres(pairs: &[PointPair], misfit: &[f64], earth: Earth) -> Vec<(f64, f64, f64)> {
    let mut order: Vec<usize> = (0..pairs.len()).collect();
    // Worst first; the index breaks ties, so the order is reproducible.
    order.sort_by(|&i, &j| misfit[j].total_cmp(&misfit[i]).then(i.cmp(&j)));
    let mut centres: Vec<(f64, f64, f64)> = Vec::new();
    for &i in order.iter().take(WORST_PAIRS) {
        let c = lowest_ground_point(&pairs[i], earth);
        // Two worst pairs through the same place seed one centre.
        let near = centres
            .iter()
            .any(|q| (q.0 - c.0).hypot(q.1 - c.1) < RADIUS_SHARES[0] * c.2.max(1.0));
        if !near {
            centres.push(c);
        }
    }
    centres
}

/// The bounds of a hot spot's centre (x, z) and radius.
fn spot_box(scene: &Scene) -> [(f64, f64); 3] {
    let (wx, wz) = (
        0.5 * (scene.x.1 - scene.x.0).max(scene.reach),
        0.5 * (scene.z.1 - scene.z.0).max(scene.reach),
    );
    [
        (scene.x.0 - wx, scene.x.1 + wx),
        (scene.z.0 - wz, scene.z.1 + wz),
        (0.5, scene.reach.max(1.0)),
    ]
}

fn air_hot_spot_seeds(model: &Model, centres: &[(f64, f64, f64)], scene: &Scene) -> Vec<Model> {
    let [x, z, r] = spot_box(scene);
    let (_, span) = layer_heights(scene);
    let bounds = [
        x,
        z,
        r,
        (-AIR_MAX_DELTA, AIR_MAX_DELTA),
        (1e-3, 10.0 * span),
    ];
    let scale_height = AIR_SCALE_SHARE * scene.lowest_origin.max(0.1);
    let mut seeds = Vec::new();
    for &(x, z, dist) in centres {
        for share in RADIUS_SHARES {
            for delta in AIR_SPOT_DELTAS {
                let spot = AirHotSpot {
                    x,
                    z,
                    radius: (share * dist).max(1.0),
                    edge: GROWN_EDGE,
                    delta,
                    scale_height,
                };
                seeds.push(model.with_air_hot_spot(spot, bounds));
            }
        }
    }
    seeds
}

fn hot_spot_seeds(model: &Model, centres: &[(f64, f64, f64)], scene: &Scene, s: f64) -> Vec<Model> {
    let [x, z, r] = spot_box(scene);
    let bounds = [
        x,
        z,
        r,
        (f64::NEG_INFINITY, f64::INFINITY),
        (-10.0 * scene.heights.1.abs().max(1.0), -1e-3),
    ];
    let rate = -0.4 * scene.lowest_origin.max(0.1);
    let mut seeds = Vec::new();
    for &(x, z, dist) in centres {
        for share in RADIUS_SHARES {
            let spot = HotSpot {
                x,
                z,
                radius: (share * dist).max(1.0),
                n: -2.0 * s,
                a: rate,
                edge: GROWN_EDGE,
            };
            seeds.push(model.with_hot_spot(spot, bounds));
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
        let (x, z, d) = lowest_ground_point(&pair, Earth::Flat);
        assert!(x.abs() < 1e-12 && (z - 100.0).abs() < 1e-9 && (d - 100.0).abs() < 1e-9);
        // Beyond the target's distance the line is cut there.
        let far = PointPair {
            through: [30.0, 1.4, 40.0],
            ..pair
        };
        let (x, z, d) = lowest_ground_point(&far, Earth::Flat);
        assert!((d - 300.0).abs() < 1e-9 && (x - 180.0).abs() < 1e-9 && (z - 240.0).abs() < 1e-9);
    }

    #[test]
    fn over_the_round_earth_a_falling_line_meets_the_sphere() {
        // From 2 m, toward the point of the sphere 1 km out: the line meets
        // the sphere there (it is a chord from 2 m up to the surface).
        let r: f64 = 6_371_000.0;
        let phi = 1000.0 / r;
        let on = [0.0, r * phi.cos() - r, r * phi.sin()];
        let pair = PointPair {
            origin: [0.0, 2.0, 0.0],
            through: on,
            target: [0.0, -1.0, 3000.0],
            weight: 1.0,
            wavelength: None,
        };
        let (x, z, d) = lowest_ground_point(&pair, Earth::Round { radius: r });
        assert!(x.abs() < 1e-9 && (z - on[2]).abs() < 1e-6, "{z}");
        assert!((d - on[2]).abs() < 1e-6);
        // The flat ground would put it nearer: the sphere falls away below
        // the plane y = 0 (by 7.8 cm at 1 km), so the line reaches y = 0 first.
        let (_, _, flat) = lowest_ground_point(&pair, Earth::Flat);
        assert!(flat < d - 30.0, "{flat}");
        // A level line stays above the sphere: lowest at its start, so the
        // middle of its way is taken (as for a rising line on flat ground).
        let level = PointPair {
            through: [0.0, 2.0, 500.0],
            ..pair
        };
        let (_, _, d) = lowest_ground_point(&level, Earth::Round { radius: r });
        assert!((d - 1500.0).abs() < 1e-6, "{d}");
    }
}
