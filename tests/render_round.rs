//! The renderer over the round earth (`"earth": {"radius": R}` in a scene):
//! a huge sphere renders as the flat ground, the horizon of straight rays
//! sits at the geometric dip, what lies beyond it is hidden as the tangent
//! line says, and the renderer's early decisions (Bouguer's invariant) agree
//! with integrating the rays to their end.

use glam::DVec3;
use mirage::math::V3;
use mirage::medium::{IndexField, LogisticMedium, Medium};
use mirage::render::air::{Air, Fate};
use mirage::render::camera::Camera;
use mirage::render::{RenderOptions, Rendered, Shading, render};
use mirage::scene::Scene;
use mirage::trace::state::rate;
use mirage::trace::{Earth, RayState, rk4_step};
use std::path::Path;

const R: f64 = 6_371_000.0;
const SKY: [f64; 3] = [0.0, 0.0, 1.0];
const SEA: [f64; 3] = [0.0, 1.0, 0.0];
const SHIP: [f64; 3] = [1.0, 0.0, 0.0];

/// A warm layer over a cold sea (the air of `problems/scenes/sea.json`): a
/// duct for glances below a few tenths of a degree.
const DUCT: &str = r#"{"scale": 0.015, "background": {"n": 1.0, "a": 300.0}, "inversion": {"n": 1.2, "a": 1.2, "height": 12.0}}"#;
const VACUUM: &str = r#"{"scale": 1.0}"#;

#[allow(clippy::too_many_arguments)]
fn scene(
    earth: Option<f64>,
    medium: &str,
    eye: f64,
    look: [f64; 3],
    fov: f64,
    size: (u32, u32),
    objects: &str,
    max_distance: f64,
) -> Scene {
    let earth = earth.map_or(String::new(), |r| format!(r#""earth": {{"radius": {r}}},"#));
    let text = format!(
        r#"{{
          "camera": {{ "position": [0, {eye}, 0], "look_at": {look:?}, "vertical_fov": {fov},
                       "width": {}, "height": {} }},
          "medium": {medium},
          {earth}
          "ground": {{ "albedo": {SEA:?} }},
          "sky": {{ "type": "gradient", "zenith": {SKY:?}, "horizon": {SKY:?} }},
          "objects": [ {objects} ],
          "trace": {{ "step": 5.0, "max_distance": {max_distance} }}
        }}"#,
        size.0, size.1
    );
    Scene::parse(&text, Path::new("round.json")).unwrap()
}

fn albedo(scene: &Scene, path_reuse: bool) -> Rendered {
    render(
        scene,
        &RenderOptions {
            shading: Shading::Albedo,
            path_reuse,
            ..RenderOptions::default()
        },
    )
}

fn is(px: [f32; 3], c: [f64; 3]) -> bool {
    (0..3).all(|k| (px[k] as f64 - c[k]).abs() < 1e-6)
}

const FREIGHTER: &str = r#"{"name": "freighter", "albedo": [1, 0, 0], "shape": {"type": "union", "children": [
    {"type": "box", "center": [-20, 3.0, 4200], "half_extents": [40.0, 3.0, 5.0]},
    {"type": "cylinder", "center": [-5, 16.0, 4200], "radius": 0.4, "half_height": 10.0}]}}"#;

#[test]
fn a_huge_earth_renders_as_the_flat_ground() {
    // R = 10⁹ m: the ground 4.2 km out lies 8.8 mm below the tangent plane,
    // a hundredth of a pixel at this zoom; the rays through the duct, the
    // ship and the sky must come out the same.
    let make = |earth| {
        scene(
            earth,
            DUCT,
            6.0,
            [0.0, 10.0, 4200.0],
            0.8,
            (72, 40),
            FREIGHTER,
            30_000.0,
        )
    };
    let flat = albedo(&make(None), false);
    let round = albedo(&make(Some(1e9)), false);
    let differ = flat
        .pixels
        .iter()
        .zip(&round.pixels)
        .filter(|(a, b)| (0..3).any(|k| (a[k] - b[k]).abs() > 1e-6))
        .count();
    let ship = flat.pixels.iter().filter(|p| is(**p, SHIP)).count();
    let sea = flat.pixels.iter().filter(|p| is(**p, SEA)).count();
    assert!(
        ship > 20 && sea > 200,
        "a scene with a ship and a sea: {ship}, {sea}"
    );
    // An edge pixel may flip where the 9 mm drop moves a silhouette across
    // a pixel centre.
    assert!(
        differ <= 2,
        "{differ} of {} pixels differ",
        flat.pixels.len()
    );
    // The flat render with its path table agrees too (its own tolerance).
    let table = albedo(&make(None), true);
    let differ_table = table
        .pixels
        .iter()
        .zip(&round.pixels)
        .filter(|(a, b)| (0..3).any(|k| (a[k] - b[k]).abs() > 1e-6))
        .count();
    assert!(
        differ_table <= 6,
        "{differ_table} pixels differ from the table's"
    );
}

/// The first row from the top whose pixel shows the ground, per column.
fn ground_rows(image: &Rendered) -> Vec<Option<u32>> {
    (0..image.width)
        .map(|x| (0..image.height).find(|&y| is(image.pixels[(y * image.width + x) as usize], SEA)))
        .collect()
}

#[test]
fn the_horizon_of_straight_rays_sits_at_the_geometric_dip() {
    // 10 m up, looking level: the horizon is acos(R/(R + H)) = 0.1013° below
    // the centre row, 16 pixels at 0.4° over 64 rows.
    let h = 10.0;
    for earth in [Some(R), None] {
        let s = scene(
            earth,
            VACUUM,
            h,
            [0.0, h, 1000.0],
            0.4,
            (48, 64),
            "",
            60_000.0,
        );
        let image = albedo(&s, true);
        let camera = Camera::new(&s.camera);
        // Flat: the ground at the end of the rays (60 km of arc).
        let dip = match earth {
            Some(r) => (r / (r + h)).acos(),
            None => (h / 60_000.0).asin(),
        };
        let (_, row) = camera
            .project(DVec3::new(0.0, h - 1000.0 * dip.tan(), 1000.0))
            .unwrap();
        for (x, first) in ground_rows(&image).into_iter().enumerate() {
            let first = first.expect("the ground shows in every column") as f64;
            // The pixel whose centre is the first below the horizon.
            assert!(
                (first + 0.5 - row).abs() <= 1.0,
                "{earth:?}, column {x}: ground from row {first}, horizon at {row:.2}"
            );
        }
    }
}

#[test]
fn what_lies_beyond_the_horizon_is_hidden() {
    // 2 m up; 15 km out the sphere is 17.66 m below y = 0. A hull 6 m high
    // standing on the sphere there is hidden (7.8 m is below the horizon);
    // its 30 m mast shows above the tangent line from the eye.
    let (eye, d) = (2.0, 15_000.0);
    // The scene author stands the ship on the sphere: lowered by the drop.
    let objects = |drop: f64| {
        format!(
            r#"{{"name": "hull", "albedo": [1, 0, 0], "shape": {{"type": "box", "center": [0, {}, {d}], "half_extents": [30, 3, 5]}}}},
               {{"name": "mast", "albedo": [1, 0, 0], "shape": {{"type": "box", "center": [15, {}, {d}], "half_extents": [1, 15, 1]}}}}"#,
            3.0 - drop,
            15.0 - drop
        )
    };
    let make = |earth: Option<f64>| {
        let drop = earth.map_or(0.0, |r| r - (r * r - d * d).sqrt());
        scene(
            earth,
            VACUUM,
            eye,
            [0.0, eye - 10.0, d],
            0.3,
            (64, 96),
            &objects(drop),
            40_000.0,
        )
    };
    let s = make(Some(R));
    let image = albedo(&s, true);
    let camera = Camera::new(&s.camera);
    let hull_column = camera.project(DVec3::new(-15.0, 0.0, d)).unwrap().0 as u32;
    let mast_column = camera.project(DVec3::new(15.0, 0.0, d)).unwrap().0 as u32;
    let column = |x: u32| -> Vec<u32> {
        (0..image.height)
            .filter(|&y| is(image.pixels[(y * image.width + x) as usize], SHIP))
            .collect()
    };
    assert!(column(hull_column).is_empty(), "the hull shows");
    let mast = column(mast_column);
    let lowest = *mast.last().expect("the mast shows") as f64 + 1.0;
    // The tangent line from the eye: elevation −acos(R/(R + eye)).
    let dip = (R / (R + eye)).acos();
    let (_, horizon_row) = camera
        .project(DVec3::new(15.0, eye - d * dip.tan(), d))
        .unwrap();
    assert!(
        (lowest - horizon_row).abs() <= 1.0,
        "mast down to row {lowest}, tangent line at {horizon_row:.2}"
    );
    // Over the flat ground the hull stands in full view.
    let flat = albedo(&make(None), true);
    let hull_flat = (0..flat.height)
        .filter(|&y| is(flat.pixels[(y * flat.width + hull_column) as usize], SHIP))
        .count();
    assert!(hull_flat > 3, "the flat ground shows {hull_flat} hull rows");
}

/// Integrates a ray in the air over the sphere until it is below the ground
/// or above the profile's top; its last state.
fn integrate(air: &Air, origin: DVec3, dir: DVec3) -> (bool, DVec3) {
    let optics = air.optics();
    let earth = air.earth();
    let x = V3::new(origin.x, origin.y, origin.z);
    let n0 = 1.0 + optics.delta(x);
    let mut y = RayState {
        x,
        v: V3::new(dir.x, dir.y, dir.z) * n0,
        s: 0.0,
    };
    let mut evals = 0;
    let mut f = rate(&optics, &y, &mut evals);
    let top = air.profile_top();
    for _ in 0..200_000 {
        let (y1, f1) = rk4_step(&optics, &y, &f, 2.0, &mut evals);
        (y, f) = (y1, f1);
        let h = earth.height(y.x);
        if h < 0.0 {
            return (true, DVec3::new(y.v.x, y.v.y, y.v.z).normalize());
        }
        if h > top && y.v.dot(earth.up(y.x)) > 0.0 {
            return (false, DVec3::new(y.v.x, y.v.y, y.v.z).normalize());
        }
    }
    panic!(
        "the ray neither landed nor escaped: {:?} at height {}",
        y.x,
        earth.height(y.x)
    );
}

#[test]
fn early_decisions_agree_with_the_full_march() {
    // A hot sea surface 0.5 m deep under the air of a duct: rays that dip
    // into it turn and escape.
    const HOT: &str = r#"{"scale": 0.005, "background": {"n": 1.0, "a": 300.0}, "inversion": {"n": -1.0, "a": 0.3, "height": 0.5}}"#;
    // (air, radius, whether some rays land, whether some dip and escape):
    // 20 km out the sphere drops away below every ray of ±0.6° from 6 m.
    for (text, radius, lands, turns) in [
        (DUCT, R, true, false),
        (DUCT, 20_000.0, false, true),
        (HOT, R, true, true),
    ] {
        let medium: Medium = serde_json::from_str(text).unwrap();
        let earth = Earth::Round { radius };
        let air = Air::new(&medium, false, 5.0, true, None, earth);
        let origin = DVec3::new(0.0, 6.0, 0.0);
        let n0 = 1.0 + air.optics().delta(V3::new(0.0, 6.0, 0.0));
        let (mut sky, mut ground, mut turned) = (0, 0, 0);
        for i in 0..=60 {
            // −0.6° … +0.6°, across the duct's trapped band and the horizon.
            let e = (-0.6 + 0.02 * i as f64).to_radians();
            let dir = DVec3::new(0.0, e.sin(), e.cos());
            // Undecided rays (trapped in the duct) may run for ever.
            let Some(fate) = air.fate(origin, dir * n0) else {
                continue;
            };
            let (landed, last) = integrate(&air, origin, dir);
            match fate {
                Fate::GroundBound => {
                    ground += 1;
                    assert!(landed, "R {radius}, {e}: decided for the ground, escaped");
                }
                Fate::Sky(d) => {
                    sky += 1;
                    turned += usize::from(e < 0.0);
                    assert!(!landed, "R {radius}, {e}: decided for the sky, landed");
                    let angle = d.cross(last).length().asin();
                    assert!(
                        angle < 2e-6,
                        "R {radius}, elevation {e}: sky direction off by {angle:e} rad"
                    );
                }
            }
        }
        assert!(
            sky > 5 && (ground > 5) == lands && (turned > 5) == turns,
            "R {radius}: {sky} sky ({turned} after turning), {ground} ground"
        );
    }
    // A vacuum over the sphere: the sky direction is the ray's own.
    let air = Air::new(
        &LogisticMedium::vacuum().into(),
        false,
        5.0,
        true,
        None,
        Earth::Round { radius: R },
    );
    let dir = DVec3::new(0.0, 0.01, 1.0).normalize();
    match air.fate(DVec3::new(0.0, 3.0, 0.0), dir) {
        Some(Fate::Sky(d)) => assert!((d - dir).length() < 1e-12, "{d:?}"),
        other => panic!("{other:?}"),
    }
}

/// The hull pixels of an albedo render of a bundled looming scene, small.
fn hull_pixels(file: &str) -> usize {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("problems/scenes")
        .join(file);
    let scene = Scene::load(&path).unwrap();
    let hull = scene.objects[0].albedo;
    let image = render(
        &scene,
        &RenderOptions {
            shading: Shading::Albedo,
            width: Some(96),
            height: Some(36),
            ..RenderOptions::default()
        },
    );
    image.pixels.iter().filter(|p| is(**p, hull)).count()
}

#[test]
fn the_cold_sea_lifts_the_hull_over_the_horizon() {
    // problems/scenes/looming*.json: the hull 15 km out is hidden by the
    // curvature in standard air, lifted into view by the cold-sea duct, and
    // in full view in standard air over the flat ground.
    let standard = hull_pixels("looming-standard.json");
    let looming = hull_pixels("looming.json");
    let flat = hull_pixels("looming-flat.json");
    assert_eq!(standard, 0, "the hull shows in standard air");
    assert!(looming > 20, "the duct shows {looming} hull pixels");
    assert!(flat > 20, "the flat ground shows {flat} hull pixels");
}
