//! Sphere tracing along curved rays: with δ ≡ 0 it is straight sphere tracing
//! (same hits, same number of distance queries), and a thin pole is never
//! stepped over, whatever the RK4 step.

use glam::DVec3;
use mirage::medium::LogisticMedium;
use mirage::render::accel::{Aabb, Grid, NearCache, SceneDistance};
use mirage::render::air::Air;
use mirage::render::march::{HitTolerance, MarchStats, Marcher, Outcome};
use mirage::scene::sdf::{SceneObject, sphere_trace};
use mirage::trace::Earth;

fn objects() -> Vec<SceneObject> {
    serde_json::from_str(
        r#"[
      { "albedo": [1, 0, 0], "shape": { "type": "sphere", "center": [3, 2, 60], "radius": 2.5 } },
      { "albedo": [0, 1, 0], "shape": { "type": "translate", "offset": [-4, 3, 80],
          "child": { "type": "rotate", "axis": [0.2, 1, 0.1], "degrees": 30,
            "child": { "type": "rounded_box", "center": [0, 0, 0], "half_extents": [2, 3, 1.5], "radius": 0.3 } } } },
      { "albedo": [0, 0, 1], "shape": { "type": "cylinder", "center": [0.5, 4, 120], "radius": 0.4, "half_height": 4 } },
      { "albedo": [1, 1, 0], "shape": { "type": "torus", "center": [-1, 6, 100], "major_radius": 3, "minor_radius": 0.5 } },
      { "albedo": [1, 0, 1], "shape": { "type": "capsule", "a": [6, 1, 90], "b": [9, 7, 95], "radius": 0.6 } }
    ]"#,
    )
    .unwrap()
}

const EPS: f64 = 1e-4;
const MAX_T: f64 = 500.0;

/// A deterministic stream of numbers in [0, 1) (xorshift64 from `seed`).
fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Deterministic rays from the origin area toward the objects.
fn rays(n: usize) -> Vec<(DVec3, DVec3)> {
    let mut next = uniform(0x2545_f491_4f6c_dd1d);
    (0..n)
        .map(|_| {
            let o = DVec3::new(next() - 0.5, 1.5 + next(), next() - 0.5);
            let target = DVec3::new(-12.0 + 24.0 * next(), 12.0 * next(), 60.0 + 60.0 * next());
            (o, (target - o).normalize())
        })
        .collect()
}

fn marcher<'a>(air: &'a Air, d: &'a SceneDistance, omega: f64) -> Marcher<'a> {
    Marcher {
        air,
        distance: d,
        omega,
        tolerance: HitTolerance {
            absolute: EPS,
            relative: 0.0,
        },
        max_distance: MAX_T,
        ground: false,
    }
}

#[test]
fn zero_delta_curved_tracing_matches_straight_sphere_tracing() {
    let objs = objects();
    let direct = SceneDistance::Direct(objs.clone());
    let bx = Aabb::of_objects(&objs);
    // δ ≡ 0 two ways: no air at all (one straight step), and air whose scale is
    // 0 (δ ≡ 0 but integrated with 2 m RK4 steps, several per query).
    let vacuum = Air::new(
        &LogisticMedium::vacuum().into(),
        false,
        2.0,
        false,
        bx,
        Earth::Flat,
    );
    let zero: LogisticMedium =
        serde_json::from_str(r#"{"scale": 0.0, "background": {"n": 1.0, "a": 50.0}}"#).unwrap();
    zero.validate().unwrap();
    let zero_air = Air::new(&zero.clone().into(), false, 2.0, false, bx, Earth::Flat);
    assert!(vacuum.is_straight() && !zero_air.is_straight());

    let mut hits = 0;
    let mut same_steps = 0;
    let all = rays(4000);
    for (air, name) in [(&vacuum, "vacuum"), (&zero_air, "scale 0")] {
        let m = marcher(air, &direct, 1.0);
        let mut rk4 = 0;
        for &(o, d) in &all {
            let reference = sphere_trace(objs.as_slice(), o, d, MAX_T, EPS);
            let mut st = MarchStats::default();
            let got = m.march(o, d, &mut st);
            rk4 += st.rk4_steps;
            match (reference, got) {
                (Some((t, steps)), Outcome::Object { point, .. }) => {
                    hits += 1;
                    let expect = o + d * t;
                    assert!(
                        (point - expect).length() < 1e-6 * (1.0 + t),
                        "{name}: hit {point} vs {expect}"
                    );
                    // The same sequence of spheres: one query per step.
                    if st.counters.queries == steps as u64 {
                        same_steps += 1;
                    } else {
                        assert!(
                            st.counters.queries.abs_diff(steps as u64) <= 1,
                            "{name}: {} queries vs {steps} steps",
                            st.counters.queries
                        );
                    }
                }
                (None, Outcome::Sky { .. }) => {}
                (r, g) => panic!("{name}: straight {r:?} vs curved {g:?} for {o} {d}"),
            }
        }
        println!("{name}: {rk4} RK4 steps");
    }
    println!("{hits} hits, {same_steps} with identical step counts");
    assert!(hits > 1000, "{hits}");
    assert!(
        same_steps as f64 >= 0.999 * hits as f64,
        "{same_steps} of {hits}"
    );
}

#[test]
fn enhanced_and_quadric_tracers_find_the_same_hits() {
    let objs = objects();
    let direct = SceneDistance::Direct(objs.clone());
    let grid = SceneDistance::Grid(Box::new(Grid::build(&objs, f64::NEG_INFINITY).unwrap()));
    let bx = Aabb::of_objects(&objs);
    let air = Air::new(
        &LogisticMedium::vacuum().into(),
        true,
        2.0,
        false,
        bx,
        Earth::Flat,
    );
    let plain = marcher(&air, &direct, 1.0);
    let enhanced = marcher(&air, &direct, 1.6);
    let quadric = marcher(&air, &grid, 1.6);
    let mut stats = [MarchStats::default(); 3];
    for &(o, d) in &rays(4000) {
        let outs: Vec<Outcome> = [plain, enhanced, quadric]
            .iter()
            .zip(stats.iter_mut())
            .map(|(m, s)| m.march(o, d, s))
            .collect();
        match outs[0] {
            Outcome::Object { index, point, .. } => {
                for other in &outs[1..] {
                    match *other {
                        Outcome::Object {
                            index: i, point: p, ..
                        } => {
                            assert_eq!(i, index);
                            // Within the hit tolerance of the same surface.
                            assert!((p - point).length() < 0.01, "{p} vs {point}");
                        }
                        ref o => panic!("plain hit, other {o:?}"),
                    }
                }
            }
            _ => {
                for other in &outs[1..] {
                    assert!(matches!(other, Outcome::Sky { .. }), "{other:?}");
                }
            }
        }
    }
    for (name, s) in ["plain", "enhanced", "quadric"].iter().zip(stats) {
        println!(
            "{name}: {} queries, {} SDF evaluations, {} fallbacks",
            s.counters.queries, s.counters.object_evaluations, s.fallbacks
        );
    }
    // Over-relaxation saves queries; the grid saves SDF evaluations.
    assert!(stats[1].counters.queries < stats[0].counters.queries);
    assert!(stats[2].counters.object_evaluations < stats[1].counters.object_evaluations);
}

/// A 5 cm pole (radius 2.5 cm) 1 km away (1001 m: not on a multiple of the
/// step), 10 m tall, in air with refraction:
/// rays swept across it in the horizontal. In stratified air a ray keeps the
/// vertical plane of its launch direction, so it passes the pole's axis at the
/// lateral distance 1001·sin(azimuth) exactly: every ray nearer than the radius
/// must hit, every ray farther must miss.
#[test]
fn a_thin_pole_is_never_missed() {
    let pole: Vec<SceneObject> = serde_json::from_str(
        r#"[{ "albedo": [1, 1, 1], "shape": { "type": "cylinder", "center": [0, 5, 1001], "radius": 0.025, "half_height": 5 } }]"#,
    )
    .unwrap();
    let sea: LogisticMedium = serde_json::from_str(
        r#"{"scale":0.015,"background":{"n":1.0,"a":300.0},"inversion":{"n":1.2,"a":1.2,"height":12.0}}"#,
    )
    .unwrap();
    let bx = Aabb::of_objects(&pole);
    let direct = SceneDistance::Direct(pole.clone());
    let grid = SceneDistance::Grid(Box::new(Grid::build(&pole, 0.0).unwrap()));
    let origin = DVec3::new(0.0, 3.0, 0.0);
    for (name, air) in [
        (
            "stratified air",
            Air::new(&sea.clone().into(), false, 2.0, true, bx, Earth::Flat),
        ),
        (
            "straight",
            Air::new(&sea.clone().into(), true, 2.0, true, bx, Earth::Flat),
        ),
    ] {
        for (tracer, distance, omega) in [
            ("plain", &direct, 1.0),
            ("enhanced", &direct, 1.6),
            ("quadric", &grid, 1.6),
        ] {
            let m = Marcher {
                air: &air,
                distance,
                omega,
                tolerance: HitTolerance {
                    absolute: 1e-4,
                    relative: 0.0,
                },
                max_distance: 5000.0,
                ground: true,
            };
            let mut naive_hits = 0;
            let mut must_hit = 0;
            for k in -400..=400 {
                let lateral = k as f64 * 1e-4; // −4 cm … 4 cm at 1 km
                let az = (lateral / 1001.0).asin();
                // 0.1° up: the ray crosses z = 1000 m at about 4.7 m, on the pole.
                let el = 0.1f64.to_radians();
                let d = DVec3::new(az.sin() * el.cos(), el.sin(), az.cos() * el.cos());
                let mut st = MarchStats::default();
                let out = m.march(origin, d, &mut st);
                let hit = matches!(out, Outcome::Object { .. });
                if lateral.abs() < 0.025 - 1e-4 {
                    must_hit += 1;
                    assert!(hit, "{name}/{tracer}: missed at {lateral} m: {out:?}");
                    // A naive marcher that only looks at the end of each 2 m
                    // step would have to land inside the pole.
                    let lands =
                        (1..2000).any(|k| pole[0].distance(origin + d * (2.0 * k as f64)) <= 0.0);
                    naive_hits += lands as u32;
                } else if lateral.abs() > 0.025 + 1e-4 {
                    assert!(!hit, "{name}/{tracer}: hit at {lateral} m: {out:?}");
                }
            }
            assert!(must_hit > 400);
            // The test would catch a tracer that steps over the pole.
            assert!(naive_hits * 10 < must_hit, "{naive_hits} of {must_hit}");
        }
    }
}

/// A point on the circle of curvature `kappa` (0: the line) from `p` along
/// the unit `t`, bending toward the unit `n` ⊥ t, after arc `s`.
fn on_arc(p: DVec3, t: DVec3, n: DVec3, kappa: f64, s: f64) -> DVec3 {
    if kappa == 0.0 {
        p + t * s
    } else {
        p + t * ((kappa * s).sin() / kappa) + n * ((1.0 - (kappa * s).cos()) / kappa)
    }
}

/// The free arc a grid probe gives (its unbounding spheres and clear boxes,
/// from inside and outside the grid) is free: no point of a ray bending at
/// most κ, in any direction, lies inside an object over that arc.
#[test]
fn free_arcs_of_the_grid_are_free() {
    let objs = objects();
    let grid = SceneDistance::Grid(Box::new(Grid::build(&objs, f64::NEG_INFINITY).unwrap()));
    let mut next = uniform(0x9e37_79b9_7f4a_7c15);
    let mut counters = Default::default();
    let (mut long, mut total) = (0, 0);
    for k in 0..3000 {
        // Points in and around the objects' box (x ±15, y −2…14, z 40…140).
        let p = DVec3::new(
            -15.0 + 30.0 * next(),
            -2.0 + 16.0 * next(),
            40.0 + 100.0 * next(),
        );
        let t = DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize();
        let n = t.any_orthonormal_vector();
        let n = (n * (next() - 0.5) + t.cross(n) * (next() - 0.5)).normalize();
        let kappa = [0.0, 1e-4, 1e-2][k % 3];
        let (q, arc) = grid.probe(p, t, kappa, &mut counters, &mut NearCache::default());
        if q.radius <= 0.0 {
            continue;
        }
        let arc = arc.min(400.0);
        total += 1;
        if arc > 2.0 * q.radius {
            long += 1;
        }
        for i in 0..=4000 {
            let x = on_arc(p, t, n, kappa, arc * i as f64 / 4000.0);
            let (d, _) = mirage::scene::sdf::nearest_object(&objs, x);
            assert!(
                d > -1e-9,
                "point {i}/4000 of the free arc {arc} from {p} along {t} (κ {kappa}) is inside: {d}"
            );
        }
    }
    // The boxes do reach beyond the spheres (else this tests little).
    assert!(
        long * 4 > total,
        "{long} of {total} arcs beyond twice the radius"
    );
}

/// Near a surface the grid gives the arc along the ray to an object's
/// bounding box, not only the radius: a ray running beside the side of a bus
/// or past a pole crosses it in a few long steps, and a ray grazing into a
/// side steps straight to it. Every such arc is free, bending included.
#[test]
fn rays_run_past_objects_beside_them_in_long_free_steps() {
    let objs: Vec<SceneObject> = serde_json::from_str(
        r#"[
      { "albedo": [1, 1, 1], "shape": { "type": "rounded_box", "center": [-1.6, 1.9, 900], "half_extents": [1.25, 1.45, 6], "radius": 0.2 } },
      { "albedo": [1, 1, 1], "shape": { "type": "translate", "offset": [-1.7, 0, 262],
          "child": { "type": "rotate", "axis": [0, 1, 0], "degrees": 180, "child": { "type": "union", "children": [
            { "type": "rounded_box", "center": [0, 0.78, 0], "half_extents": [0.9, 0.45, 2.2], "radius": 0.18 },
            { "type": "rounded_box", "center": [0, 1.48, -0.15], "half_extents": [0.78, 0.33, 1.15], "radius": 0.2 } ] } } } },
      { "albedo": [1, 1, 1], "shape": { "type": "cylinder", "center": [-5, 3.5, 500], "radius": 0.08, "half_height": 3.5 } },
      { "albedo": [1, 1, 1], "shape": { "type": "sphere", "center": [20, 6, 1130], "radius": 3.2 } }
    ]"#,
    )
    .unwrap();
    let grid = SceneDistance::Grid(Box::new(Grid::build(&objs, 0.0).unwrap()));
    let mut counters = Default::default();
    let check_free = |p: DVec3, t: DVec3, kappa: f64, arc: f64| {
        let n = t.cross(DVec3::X).normalize();
        for i in 0..=4000 {
            for bend in [n, -n, t.cross(n)] {
                let x = on_arc(p, t, bend, kappa, arc * i as f64 / 4000.0);
                let (d, _) = mirage::scene::sdf::nearest_object(&objs, x);
                assert!(
                    d > -1e-9,
                    "{i}/4000 of the arc {arc} from {p} along {t} is inside: {d}"
                );
            }
        }
    };
    for kappa in [0.0, 1e-5, 1e-3] {
        // Beside the bus's side (x = -0.35), 0.3 m off it, along it.
        let p = DVec3::new(-0.05, 1.5, 895.0);
        let (q, arc) = grid.probe(p, DVec3::Z, kappa, &mut counters, &mut NearCache::default());
        assert!(q.radius < 0.31, "radius {}", q.radius);
        assert!(arc > 5.0, "κ {kappa}: arc {arc} beside the bus");
        check_free(p, DVec3::Z, kappa, arc);
        // Beside the car's body (x = -0.8) and past the pole (x = -4.92).
        for p in [DVec3::new(-0.5, 0.8, 260.5), DVec3::new(-4.6, 3.0, 499.9)] {
            let (q, arc) = grid.probe(p, DVec3::Z, kappa, &mut counters, &mut NearCache::default());
            assert!(
                arc > 2.0 * q.radius + 0.5,
                "κ {kappa}: arc {arc}, radius {} at {p}",
                q.radius
            );
            check_free(p, DVec3::Z, kappa, arc);
        }
        // Grazing into the bus's side at 1/200: it is 0.3 m away, 60 m
        // ahead along the ray (into its flat part): one step of most of it.
        let t = DVec3::new(-0.005, 0.0, 1.0).normalize();
        let p = DVec3::new(-0.05, 1.9, 840.0);
        let (q, arc) = grid.probe(p, t, kappa, &mut counters, &mut NearCache::default());
        let ahead = 0.3 / 0.005 * t.z.recip();
        assert!(
            q.radius > 0.29 && arc > 0.5 * ahead && arc < ahead,
            "κ {kappa}: arc {arc}, radius {}",
            q.radius
        );
        check_free(p, t, kappa, arc);
    }
}

/// Shadow rays through the objects seen along the sun give what marching
/// every object gives.
#[test]
fn sun_columns_agree_with_marching_every_object() {
    use mirage::render::shadow::SunColumns;
    let objs = objects();
    let sun = DVec3::new(0.3, 0.5, -0.6).normalize();
    let columns = SunColumns::new(&objs, sun).unwrap();
    let brute = |p: DVec3| -> bool {
        let mut t = 0.0;
        for _ in 0..100_000 {
            let (d, _) = mirage::scene::sdf::nearest_object(&objs, p + sun * t);
            if d < 1e-4 + 1e-7 * t {
                return false;
            }
            t += d;
            if t > 1000.0 {
                return true;
            }
        }
        true
    };
    let mut next = uniform(0x2545_f491_4f6c_dd1d);
    let mut counters = Default::default();
    let (mut shadowed, mut skipped) = (0, 0);
    for _ in 0..20_000 {
        // Ground points under and behind the objects.
        let p = DVec3::new(-20.0 + 40.0 * next(), 0.0, 40.0 + 120.0 * next());
        if mirage::scene::sdf::nearest_object(&objs, p).0 < 1e-3 {
            continue;
        }
        let before = counters;
        let lit = columns.sunlit(&objs, p, &mut counters);
        assert_eq!(lit, brute(p), "at {p}");
        shadowed += usize::from(!lit);
        skipped += usize::from(counters == before);
    }
    assert!(shadowed > 500, "only {shadowed} points in shadow");
    assert!(skipped > 5000, "only {skipped} points without a query");
}

/// A ray keeps the children of a union that can be nearest from one query
/// to the next ([`NearCache`]): every query along sphere-traced rays closing
/// in on two ships of boxes and cylinders (and a lighthouse of three parts)
/// gives the same radius, to the bit, the same object and the same free arc
/// as with a fresh cache; and the kept masks are used (fewer child
/// evaluations is not observable, so the test checks the answers only, on
/// rays that surely reuse: each takes tens of queries near one ship).
#[test]
fn a_kept_near_mask_changes_no_query() {
    let ship = |x: f64, z: f64, deg: f64| {
        format!(
            r#"{{ "albedo": [0.5, 0.5, 0.5], "shape": {{ "type": "translate", "offset": [{x}, 0, {z}],
              "child": {{ "type": "rotate", "axis": [0, 1, 0], "degrees": {deg},
                "child": {{ "type": "union", "children": [
                  {{ "type": "box", "center": [0, 3, 0], "half_extents": [5, 3, 40] }},
                  {{ "type": "box", "center": [0, 8, -14], "half_extents": [4, 2, 8.8] }},
                  {{ "type": "box", "center": [0, 11, -14], "half_extents": [3, 1.2, 4.8] }},
                  {{ "type": "cylinder", "center": [0, 13, -4], "radius": 1.3, "half_height": 3.5 }},
                  {{ "type": "cylinder", "center": [0, 20, 18], "radius": 0.35, "half_height": 14 }},
                  {{ "type": "cylinder", "center": [0, 17.2, -24], "radius": 0.3, "half_height": 11.2 }}
                ] }} }} }} }}"#
        )
    };
    let json = format!(
        r#"[{}, {}, {{ "albedo": [1, 1, 1], "shape": {{ "type": "union", "children": [
            {{ "type": "cylinder", "center": [30, 12, 260], "radius": 3, "half_height": 12 }},
            {{ "type": "cylinder", "center": [30, 26, 260], "radius": 2.2, "half_height": 2 }},
            {{ "type": "sphere", "center": [30, 29, 260], "radius": 1.8 }} ] }} }}]"#,
        ship(-10.0, 200.0, 70.0),
        ship(20.0, 320.0, -60.0)
    );
    let objs: Vec<SceneObject> = serde_json::from_str(&json).unwrap();
    let grid = SceneDistance::Grid(Box::new(Grid::build(&objs, 0.0).unwrap()));
    let mut next = uniform(0x2545_f491_4f6c_dd1d);
    let mut counters = Default::default();
    let (mut queries, mut hits) = (0, 0);
    for k in 0..400 {
        // From a harbour wall toward a point on one of the objects.
        let from = DVec3::new(-5.0 + 10.0 * next(), 6.0, 0.0);
        let target = match k % 3 {
            0 => DVec3::new(-10.0 + 30.0 * (next() - 0.5), 34.0 * next(), 200.0),
            1 => DVec3::new(20.0 + 30.0 * (next() - 0.5), 34.0 * next(), 320.0),
            _ => DVec3::new(30.0 + 8.0 * (next() - 0.5), 32.0 * next(), 260.0),
        };
        let t = (target - from).normalize();
        let kappa = [0.0, 1e-5][k % 2];
        let mut near = NearCache::default();
        let mut p = from;
        for _ in 0..200 {
            let kept = grid.probe(p, t, kappa, &mut counters, &mut near);
            let fresh = grid.probe(p, t, kappa, &mut counters, &mut NearCache::default());
            assert_eq!(
                kept.0.radius.to_bits(),
                fresh.0.radius.to_bits(),
                "ray {k} at {p}"
            );
            assert_eq!(kept.0.object, fresh.0.object, "ray {k} at {p}");
            assert_eq!(kept.1.to_bits(), fresh.1.to_bits(), "ray {k} at {p}");
            queries += 1;
            if kept.0.radius < 1e-6 {
                hits += 1;
                break;
            }
            p += t * kept.0.radius.max(1e-7);
            if p.z > 400.0 || p.y < 0.0 {
                break;
            }
        }
    }
    // The rays did close in on the objects, over many queries each.
    assert!(
        hits > 150 && queries > 4000,
        "{hits} hits, {queries} queries"
    );
}
