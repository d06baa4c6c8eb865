//! Geographic points in scene files: a camera placed and aimed by latitude,
//! longitude, elevation and azimuth, and objects standing `at` a place.
//!
//! Seeded families (sites at latitudes −89…89°, places 10 m to 2,000 km
//! away in every direction, heights 0–3 km, shapes written upright in their
//! own frame): a point written at local (0, H, 0) in an object's frame must
//! land where the site puts the place raised by H (1 µm), its local x and z
//! must stay horizontal there and keep lengths (a proper rotation), and a
//! camera aimed by elevation and azimuth must look that way in its own
//! horizon (1e-9°), its default up the local vertical.

use geographiclib_rs::{DirectGeodesic, Geodesic};
use glam::DVec3;
use mirage::geo::{GeoPoint, Horizon, Site};
use mirage::math::SplitMix64;
use mirage::scene::description::Scene;
use std::path::Path;

/// One drawn case: a site, a place `distance` metres away along `azimuth`,
/// and that place's height.
struct Case {
    site: Site,
    place: GeoPoint,
}

fn draw(rng: &mut SplitMix64) -> Case {
    let latitude = -89.0 + 178.0 * rng.next_f64();
    let longitude = -180.0 + 360.0 * rng.next_f64();
    let site = Site {
        latitude,
        longitude,
        height: 500.0 * rng.next_f64(),
    };
    // Distances log-uniform over 10 m … 2,000 km.
    let distance = 10.0 * (2e5f64).powf(rng.next_f64());
    let azimuth = -180.0 + 360.0 * rng.next_f64();
    let (lat2, lon2): (f64, f64) = Geodesic::wgs84().direct(latitude, longitude, azimuth, distance);
    let place = GeoPoint {
        latitude: lat2,
        longitude: lon2,
        height: 3000.0 * rng.next_f64(),
    };
    Case { site, place }
}

fn scene(case: &Case, camera: &str, objects: &str) -> Scene {
    let s = &case.site;
    let text = format!(
        r#"{{ "site": {{ "latitude": {}, "longitude": {}, "height": {} }},
             "camera": {{ {camera}, "vertical_fov": 1, "width": 8, "height": 8 }},
             "medium": {{ "air": {{ "temperature": {{ "base": 15, "lapse": -0.0065 }} }} }},
             "objects": [ {objects} ] }}"#,
        s.latitude, s.longitude, s.height
    );
    Scene::parse(&text, Path::new("generated.json")).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

fn place_json(p: &GeoPoint) -> String {
    format!(
        r#"{{ "latitude": {}, "longitude": {}, "height": {} }}"#,
        p.latitude, p.longitude, p.height
    )
}

fn radius_of(scene: &Scene) -> f64 {
    match scene.earth {
        mirage::trace::Earth::Round { radius } => radius,
        mirage::trace::Earth::Flat => panic!("a scene with a site must be round"),
    }
}

#[test]
fn objects_stand_upright_at_their_place() {
    let mut rng = SplitMix64(0x5eed_0b1e);
    let mut worst = 0.0f64;
    for k in 0..300 {
        let case = draw(&mut rng);
        let (h, d) = (100.0 * rng.next_f64(), 1000.0 * rng.next_f64());
        // Three unit spheres in the object's own frame: above its origin by
        // h, and d along its x and its z.
        let sphere = |c: [f64; 3]| {
            format!(
                r#"{{ "albedo": [0.5, 0.5, 0.5], "at": {},
                      "shape": {{ "type": "sphere", "center": [{}, {}, {}], "radius": 1 }} }}"#,
                place_json(&case.place),
                c[0],
                c[1],
                c[2]
            )
        };
        let objects = [
            sphere([0.0, h, 0.0]),
            sphere([d, 0.0, 0.0]),
            sphere([0.0, 0.0, d]),
        ];
        let sc = scene(
            &case,
            r#""position": [0, 10, 0], "look_at": [0, 10, 100]"#,
            &objects.join(","),
        );
        let radius = radius_of(&sc);
        assert_eq!(radius, case.site.gaussian_radius());
        let centre = DVec3::new(0.0, -radius, 0.0);
        let foot = DVec3::from_array(case.site.place(&case.place, radius));
        // The sphere above the origin: where the place raised by h is.
        let top = case.site.place(
            &GeoPoint {
                height: case.place.height + h,
                ..case.place
            },
            radius,
        );
        let miss = (sc.objects[0].shape.distance(DVec3::from_array(top)) + 1.0).abs();
        worst = worst.max(miss);
        assert!(miss < 1e-6, "case {k}: the top is {miss} m off");
        // Along x and z: d away from the foot, horizontal there. A unit
        // sphere's centre is where its distance is −1 and its gradient
        // vanishes; find it from the distance at the foot plus d·axis for
        // the axes the rotation must give (orthonormal, ⊥ up).
        for (i, obj) in sc.objects[1..].iter().enumerate() {
            // Distance from the foot is |c − foot| − 1 = d − 1.
            let from_foot = obj.shape.distance(foot) + 1.0;
            assert!(
                (from_foot - d).abs() < 1e-6,
                "case {k} axis {i}: {from_foot} vs {d}"
            );
            // Height of the centre above the sphere through the foot:
            // |c − centre|² = |foot − centre|² + d² when c − foot ⊥ up.
            // The distance from the earth's centre is |c − centre| − 1.
            let r = obj.shape.distance(centre) + 1.0;
            let expected = ((foot - centre).length_squared() + d * d).sqrt();
            assert!(
                (r - expected).abs() < 1e-6,
                "case {k} axis {i}: {r} vs {expected} (not horizontal)"
            );
        }
    }
    eprintln!("300 places: worst miss of an object's top {worst:.2e} m");
}

#[test]
fn cameras_are_placed_and_aimed_by_angles() {
    let mut rng = SplitMix64(0x00ca_3e7a);
    for k in 0..300 {
        let case = draw(&mut rng);
        let elevation = -5.0 + 10.0 * rng.next_f64();
        let azimuth = 360.0 * rng.next_f64();
        let camera = format!(
            r#""position": {}, "elevation": {elevation}, "azimuth": {azimuth}"#,
            place_json(&case.place)
        );
        let sc = scene(&case, &camera, "");
        let radius = radius_of(&sc);
        let at = case.site.place(&case.place, radius);
        let c = &sc.camera;
        assert!((c.position - DVec3::from_array(at)).length() < 1e-9);
        let h = Horizon::at(at, Some(radius)).unwrap();
        let view = (c.look_at - c.position).to_array();
        let (e, a) = (h.elevation(view), h.azimuth(view));
        assert!(
            (e - elevation).abs() < 1e-9,
            "case {k}: elevation {e} vs {elevation}"
        );
        let da = (a - azimuth + 540.0).rem_euclid(360.0) - 180.0;
        assert!(da.abs() < 1e-9, "case {k}: azimuth {a} vs {azimuth}");
        // The default up is the local vertical there.
        assert!(
            (c.up - DVec3::from_array(h.up)).length() < 1e-12,
            "case {k}"
        );

        // Aimed at the site instead: the view points at (0, height, 0).
        let camera = format!(
            r#""position": {}, "look_at": {}"#,
            place_json(&case.place),
            place_json(&GeoPoint {
                latitude: case.site.latitude,
                longitude: case.site.longitude,
                height: case.site.height,
            })
        );
        let sc = scene(&case, &camera, "");
        let site = DVec3::new(0.0, case.site.height, 0.0);
        assert!((sc.camera.look_at - site).length() < 1e-6, "case {k}");
    }
}

#[test]
fn a_local_place_over_the_flat_ground_only_moves() {
    // Without a site or earth the ground is flat: `at` translates, no turn.
    let text = r#"{ "camera": { "position": [0, 2, 0], "look_at": [0, 2, 100], "vertical_fov": 1, "width": 8, "height": 8 },
        "medium": { "scale": 1.0, "background": { "n": 1.0, "a": 40.0 } },
        "objects": [ { "albedo": [1, 1, 1], "at": [300, 0, 2000],
                       "shape": { "type": "box", "center": [0, 5, 0], "half_extents": [1, 5, 2] } } ] }"#;
    let sc = Scene::parse(text, Path::new("flat.json")).unwrap();
    let d = sc.objects[0]
        .shape
        .distance(DVec3::new(300.0, 12.0, 2000.0));
    assert!((d - 2.0).abs() < 1e-12, "{d}");
    let d = sc.objects[0].shape.distance(DVec3::new(303.0, 5.0, 2000.0));
    assert!((d - 2.0).abs() < 1e-12, "{d}");
    assert_eq!(sc.camera.up, DVec3::Y);
}

/// The bundled long-distance scene: the Pic du Canigou, 252.76 km from
/// Marseille, seen from 164 m. Straight lines of sight hide it entirely
/// (the sea's horizon, at the closed-form dip acos(R/(R+h)) = 0.4109°,
/// stands above the summit's −0.5417°); through the standard atmosphere
/// its top shows above the sea. A strip down the middle of the picture,
/// in albedo shading (the mountain's own albedo where a ray meets it).
#[test]
fn the_canigou_shows_through_standard_air_and_hides_from_straight_lines() {
    use mirage::render::{RenderOptions, Shading, render};
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/scenes/canigou.json");
    let mut sc = Scene::load(&path).unwrap();
    // The bundled picture's middle: 0.2° over 320 rows, 0.000625° a row.
    assert_eq!((sc.camera.vertical_fov, sc.camera.height), (0.2, 320));
    sc.camera.width = 4;
    let radius = radius_of(&sc);
    let rock = sc.objects[0].albedo.map(|c| c as f32);
    let sea = [0.03f32, 0.07, 0.1];
    let rows = |straight: bool| {
        let img = render(
            &sc,
            &RenderOptions {
                shading: Shading::Albedo,
                straight,
                ..RenderOptions::default()
            },
        );
        let kind = |y: u32| {
            let p = img.pixel(1, y);
            let near = |c: [f32; 3]| (0..3).all(|k| (p[k] - c[k]).abs() < 1e-4);
            if near(rock) {
                'm'
            } else if near(sea) {
                's'
            } else {
                'k'
            }
        };
        (0..img.height).map(kind).collect::<String>()
    };
    // The elevation of row y's centre (a pinhole: tan-spaced rows).
    let elevation = |y: usize| {
        let half = (0.1f64).to_radians().tan();
        let v = half * (1.0 - (2.0 * y as f64 + 1.0) / 320.0);
        -0.36 + v.atan().to_degrees()
    };
    let straight = rows(true);
    assert!(
        !straight.contains('m'),
        "straight lines show the mountain: {straight}"
    );
    let horizon = straight
        .find('s')
        .unwrap_or_else(|| panic!("no sea: {straight}"));
    let dip = (radius / (radius + 164.0)).acos().to_degrees();
    let row = 0.2 / 320.0;
    assert!(
        (elevation(horizon) + dip).abs() <= row,
        "straight horizon at {}°, dip {dip}°",
        elevation(horizon)
    );
    let curved = rows(false);
    let shown = curved.matches('m').count();
    // ~0.02° of the summit: its top ~90 m over 252.8 km.
    assert!(
        (20..=60).contains(&shown),
        "{shown} rows of mountain: {curved}"
    );
    let top = curved.find('m').unwrap();
    let sea_row = curved.find('s').unwrap();
    assert!(top < sea_row && sea_row < horizon, "{curved}");
    eprintln!(
        "canigou: straight horizon {:.4}° (dip {dip:.4}°), through standard air the summit's top {:.4}° and {shown} rows (~{:.0} m) above the sea",
        elevation(horizon),
        elevation(top),
        shown as f64 * row.to_radians() * 252_755.0
    );
}
