//! One test per crash the fuzz targets found (`fuzz/`, issue #16), named after
//! the target and what it found, with the input it found (shortened where the
//! rest did not matter). Each asserted contract is the targets' own: refused
//! with an input error that names a field or the whole document (exit 2), or
//! accepted and then finite everywhere; never a panic.

use mirage::error::{Error, WHOLE_DOCUMENT};
use mirage::io::json::parse_json;
use mirage::math::V3;
use mirage::medium::{Field, IndexField, Medium};
use mirage::problem::Problem;
use mirage::trace::{Earth, EarthSpec, Method, TargetPlane, TraceOptions, trace};
use std::path::Path;

/// The input error of `e`: exit 2, a field path, a message; and its text has
/// no `-:` where a field name would go.
fn named(e: &Error) -> (String, String) {
    let field = e
        .field()
        .unwrap_or_else(|| panic!("not an input error: {e}"));
    assert_eq!(e.exit_code(), 2, "{e}");
    assert!(!field.path.is_empty() && !field.message.is_empty(), "{e}");
    let text = e.to_string();
    assert!(!text.contains(": -:") && !text.contains(": :"), "{text}");
    (field.path.clone(), text)
}

/// One ray from `o` along `d` toward a plane `distance` ahead in z, capped at
/// 20,000 steps and 4 × `distance` as the fuzz targets trace it
/// (`fuzz/fuzz_targets/common.rs`): its endpoint, direction and length finite.
fn assert_finite_ray(field: &Field, o: V3, d: V3, method: Method, earth: Earth, distance: f64) {
    let mut opts = TraceOptions::new(method);
    opts.max_steps = 20_000;
    opts.max_length = Some(4.0 * distance);
    opts.earth = earth;
    let plane = TargetPlane {
        point: o + V3::new(0.0, 0.0, distance),
        normal: V3::new(0.0, 0.0, 1.0),
    };
    let t = trace::<f64, _>(field, o, d, Some(&plane), &opts, None);
    assert!(
        t.endpoint.is_finite() && t.direction.is_finite() && t.arc_length.is_finite(),
        "from {o:?} along {d:?} by {method:?} over {earth:?}: {t:?}"
    );
}

/// `problem`: a key `""` whose colon never came (`{"": "…` cut short) had
/// an empty field path, printed as `fuzz.json: : expected ...`.
#[test]
fn fuzz_problem_unfinished_empty_key_names_the_document() {
    let text = "{\n  \"\"description\"\u{1a}bwarm fia";
    let e = Problem::parse(text, Path::new("fuzz.json")).unwrap_err();
    let (path, message) = named(&e);
    assert_eq!(path, WHOLE_DOCUMENT);
    assert!(message.contains("line 2"), "{message}");
}

/// `problem` and `scene`: an unknown key `""` at the top level had an empty
/// path too (`unknown field ``, expected one of ...`).
#[test]
fn fuzz_problem_and_scene_empty_unknown_key_names_the_document() {
    let problem = r#"{"name": "x", "": 1, "medium": {"scale": 0.02}, "pairs": []}"#;
    let e = Problem::parse(problem, Path::new("fuzz.json")).unwrap_err();
    let (path, message) = named(&e);
    assert_eq!(path, WHOLE_DOCUMENT);
    assert!(message.contains("unknown field ``"), "{message}");

    let scene = r#"{"name": "x", "": {"method": "auto"}}"#;
    let e = mirage::scene::Scene::parse(scene, Path::new("scene.json")).unwrap_err();
    let (path, _) = named(&e);
    assert_eq!(path, WHOLE_DOCUMENT);
}

/// `fit_result`: a result file broken inside a nested key
/// (`{"": {"temperatuson", ...`) named no field either.
#[test]
fn fuzz_fit_result_broken_nested_key_names_the_document() {
    let text = r#"{"": {"temperatuson", "medium": {"air": {}}}}"#;
    let e =
        parse_json::<serde_json::Value>(text, Path::new("result.json"), "fit result").unwrap_err();
    let (path, message) = named(&e);
    assert_eq!(path, WHOLE_DOCUMENT);
    assert!(message.contains("column"), "{message}");
}

/// `air`: a Gladstone–Dale constant of 99,475,020 K made n ≈ 3.5·10⁵, and a
/// ray's endpoint overflowed to ∞ with a NaN direction. Constants above 1 K
/// (13× air's) are refused by name, as are pressures above 10⁷ Pa.
#[test]
fn fuzz_air_huge_gladstone_dale_constant_is_refused() {
    let parse = |text: &str| -> Result<(), Error> {
        let path = Path::new("medium.json");
        let m: Medium = parse_json(text, path, "medium")?;
        m.validate().map_err(|e| e.in_file(path))
    };
    let air = |k: &str, p: &str| {
        format!(
            r#"{{"air": {{"temperature": {{"base": 10.233, "exponential": {{"delta": 0.0, "scale_height": 0.04}}}}, "pressure": {p}, "refractivity": {{"gladstone_dale": {k}}}}}}}"#
        )
    };
    let e = parse(&air("99475020", "101325")).unwrap_err();
    let (path, message) = named(&e);
    assert_eq!(path, "air.refractivity.gladstone_dale");
    assert!(message.contains("0.079"), "{message}");
    let e = parse(&air("0.079", "1e9")).unwrap_err();
    assert_eq!(named(&e).0, "air.pressure");
    // The largest allowed constant at the highest pressure still traces finitely.
    let path = Path::new("medium.json");
    let m: Medium = parse_json(&air("1.0", "1e7"), path, "medium").unwrap();
    m.validate().unwrap();
    let field = m.field();
    for elevation in [-0.01_f64, 0.0, 0.1, 89.0, 90.0] {
        let e = elevation.to_radians();
        let d = V3::new(0.0, e.sin(), e.cos());
        let o = V3::new(0.0, 1.5, 0.0);
        assert_finite_ray(&field, o, d, Method::Rk4 { step: 5.0 }, Earth::Flat, 300.0);
    }
}

/// `structured`: a logistic medium of extreme but valid numbers (scale
/// 4.7·10⁻³⁰⁸, an inversion of amplitude 10¹⁹³ and rate 8.9·10⁻⁶ m at the
/// ground, a hot spot of radius 0) and a ray from the ground at x = 10⁻³²¹:
/// its direction became NaN.
#[test]
fn fuzz_structured_subnormal_scale_ray_stays_finite() {
    let text = r#"{"scale": 4.729372673361406e-308,
        "inversion": {"n": 1.0234173826077954e193, "a": 8.901960784313726e-6, "height": 0.0},
        "hotspots": [{"x": 0.0, "z": 0.0, "radius": 0.0, "n": 0.0, "a": -0.00028896009765774013, "edge": 9692.072938124667}]}"#;
    let path = Path::new("structured.json");
    let m: Medium = parse_json(text, path, "medium").unwrap();
    if let Err(e) = m.validate() {
        // Refusing it by name is a valid answer too.
        named(&e.in_file(path));
        return;
    }
    let field = m.field();
    let o = V3::new(1.27e-321, 0.0, 0.0);
    let d = V3::new(-0.479425538604203, 0.0, 0.8775825618903728);
    let (delta, grad) = field.delta_gradient(o);
    assert!(
        delta.is_finite() && grad.is_finite(),
        "δ {delta}, ∇δ {grad:?}"
    );
    assert_finite_ray(&field, o, d, Method::Rk4 { step: 0.01 }, Earth::Flat, 1.0);
}

/// The same hunt, one step on: amplitudes that are all subnormal had no
/// finite 1/max|n| in the normalisation by S, and δ was NaN. Only the ratios
/// n/S matter, so such a medium is the one with n = 1.
#[test]
fn fuzz_structured_subnormal_amplitudes_keep_their_ratios() {
    let path = Path::new("structured.json");
    let at = |n: &str| {
        let text = format!(
            r#"{{"scale": 0.02, "background": {{"n": {n}, "a": 150.0}}, "hotspots": [{{"x": 0.0, "z": 100.0, "radius": 50.0, "n": -{n}, "a": -0.5, "edge": 0.5}}]}}"#
        );
        let m: Medium = parse_json(&text, path, "medium").unwrap();
        m.validate().unwrap();
        m.field().delta_gradient(V3::new(3.0, 0.7, 90.0))
    };
    let (d1, g1) = at("1.0");
    let (d0, g0) = at("1e-310");
    assert!(d0.is_finite() && g0.is_finite(), "δ {d0}, ∇δ {g0:?}");
    assert!((d0 - d1).abs() <= 1e-15 * d1.abs(), "{d0} vs {d1}");
    assert!((g0 - g1).norm() <= 1e-12 * g1.norm(), "{g0:?} vs {g1:?}");
}

/// `air` (10 minutes in): an inversion 2 m thick at 1.26·10⁸³ m. The
/// hydrostatic table's node spacing near it fell below the spacing of floats
/// there, so its nodes never advanced and the table grew until the fuzzer's
/// 2 GB limit. Now the table stops at the last distinct node.
#[test]
fn fuzz_air_inversion_at_1e83_m_builds_a_finite_table() {
    let text = r#"{"air": {"temperature": {"base": 10.0, "exponential": {"delta": -3.0, "scale_height": 4.0},
        "inversion": {"delta": 10.0, "height": 1.25555e83, "thickness": 2.0}},
        "pressure": 101325.0, "humidity": 0.6, "wavelength": 550.0}}"#;
    let path = Path::new("medium.json");
    let m: Medium = parse_json(text, path, "medium").unwrap();
    if let Err(e) = m.validate() {
        named(&e.in_file(path));
        return;
    }
    let field = m.field();
    for h in [0.0, 1.0, 100.0, 1e4] {
        let (d, g) = field.delta_gradient(V3::new(0.0, h, 0.0));
        assert!(d.is_finite() && g.is_finite(), "{h} m: δ {d}, ∇δ {g:?}");
    }
}

/// `structured` (4 minutes in): a round earth of radius 6·10³⁰³ m. A height
/// takes y·(2R + y), which overflowed, and a ray 100 km up got a NaN
/// direction. Radii above 10¹⁵ m are refused by name; at that radius the
/// same ray is finite.
#[test]
fn fuzz_structured_earth_radius_6e303_is_refused() {
    let e = EarthSpec {
        radius: 6.001795188716654e303,
    }
    .validate()
    .unwrap_err();
    assert_eq!(e.path, "radius");
    assert!(e.message.contains("at most 1e15"), "{e}");
    let text = r#"{"scale": 0.02, "background": {"n": 1.0, "a": 150.0}}"#;
    let m: Medium = parse_json(text, Path::new("m.json"), "medium").unwrap();
    let field = m.field();
    let spec = EarthSpec { radius: 1.0e15 };
    spec.validate().unwrap();
    let o = V3::new(1e-6, 1e5, 0.0);
    let d = V3::new(0.4723077727790377, -0.1716754988696719, 0.8645535789413831);
    let earth = Earth::Round {
        radius: spec.radius,
    };
    assert_finite_ray(&field, o, d, Method::Dopri5 { tolerance: 1e-3 }, earth, 1e5);
}

/// The image of [`fuzz_photo_ray_through_the_ground_has_a_finite_jacobian`]: a PNG
/// whose header says 64 × 9,963,568 pixels (only the header is read).
const TALL_PNG_HEX: &[&str] = &[
    "89504e470d0a1a0a0000000d4948445200000040009808300802000000e1a30a6b0000021749444154789c2cd247434a",
    "356cec9b42d8e6e4dac5bb630057ff6163a704ce0f5db17ef3273dfb8fa59dbf76fbfeb3b75f7e1b16295dae4a6d3b87",
    "1610b6b974e8e6d367d0c809d3e7842c5bbd695b5ce2a193672fddcc7df4f2c3f7ff6f206cfca34e43d8469d86b08d3a",
    "0d611b751ac236ea34846dd4ea34846dd46908dba8d310b651a7216ca34e43d8469d86b08d3a0d611b751ac236ea3484",
    "6dd4000000000000000000006ca34e43d8469d86b08d3a0d611b751ac233eaf43f5b78be009dc8c3120000000049454e",
    "44ae426082eba16573",
];

#[test]
fn fuzz_photo_ray_through_the_ground_has_a_finite_jacobian() {
    // `photo` found: in an image 9,963,568 pixels tall with a 31° field of
    // view and k1 = −0.05, a mark near the top row lies far beyond where the
    // lens folds the image over; undistortion converged to the mirrored
    // root, a ray straight down, which went 2,000 km through the flat
    // ground, where the hydrostatic pressure (4e265 Pa) made the camera's
    // Jacobian NaN. Now such a pixel is refused by name, and a ray that
    // does go straight down (a mark near the bottom row, no distortion)
    // keeps a finite Jacobian: the pressure is held at 1e8 Pa below ~50 km.
    use mirage::fit::objective::Objective;
    let dir = tempfile::tempdir().unwrap();
    let hex: String = TALL_PNG_HEX.concat();
    let bytes: Vec<u8> = (0..hex.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&hex[i..i + 2], 16).unwrap())
        .collect();
    std::fs::write(dir.path().join("image.bin"), bytes).unwrap();
    let text = r#"{"name": "photo-1", "photo": {"image": "image.bin", "camera": {"horizontal_fov": 31.0, "azimuth": 0.0, "tilt": 0.0, "roll": 0.3, "position": [0.0, 10.0, 0.0], "distortion": {"k1": -0.05}}}, "marks": [{"name": "lamp", "pixel": [33.5, 22.0], "target": [54.0, 20.0, 300050]}, {"name": "mast", "pixel": [12.0, 25.5], "target": [-400.0, 5.0, 800010]}], "noise": 0.5, "medium": {"air": {"temperature": {"base": 12.0, "lapse": -0.0056}, "pressure": 101325.0, "humidity": 0.0}}, "free": ["camera.tilt", "camera.roll", "camera.azimuth"]}"#;
    let path = dir.path().join("problem.json");
    let e = Problem::parse(text, &path).unwrap_err();
    let (field, message) = named(&e);
    assert_eq!(field, "marks[0].pixel", "{message}");
    assert!(message.contains("fold the image over"), "{message}");
    let down = text
        .replace(r#", "distortion": {"k1": -0.05}"#, "")
        .replace("[33.5, 22.0]", "[33.5, 9963500.0]")
        .replace("[12.0, 25.5]", "[12.0, 9963540.5]");
    let mut p = Problem::parse(&down, &path).unwrap();
    for max_steps in [20_000, p.trace.max_steps] {
        p.trace.max_steps = max_steps;
        let objective = Objective::from_problem(&p);
        let x = objective.start();
        let (r, j) = objective.jacobian(x.as_slice());
        assert!(r.iter().all(|v| v.is_finite()), "{r:?}");
        assert!(
            j.iter().all(|v| v.is_finite()),
            "max_steps {max_steps}: {j:?}"
        );
    }
}
