//! Bad photo problems (`docs/photo.md`): every field of the photo section
//! and the marks, each refused with exit 2, one line naming the file and
//! the field or mark, and nothing written (`mirage fit -o … --overlay …`,
//! `mirage overlay`).

use serde_json::{Value, json};
use std::path::PathBuf;
use std::process::Command;

/// A valid photo problem: real air over the round earth, a target mark
/// and a horizon mark, the lapse and the tilt free.
fn base() -> Value {
    json!({
        "name": "bad-photo",
        "earth": {"radius": 6371000.0},
        "photo": {
            "image": "photo.png",
            "camera": {"horizontal_fov": 10.0, "azimuth": 0.0, "tilt": 0.0, "roll": 0.0,
                       "position": [0.0, 10.0, 0.0]}
        },
        "marks": [
            {"name": "lamp", "pixel": [600.0, 390.0], "target": [50.0, 20.0, 3000.0]},
            {"name": "sea", "pixel": [100.0, 420.0], "horizon": true}
        ],
        "noise": 0.5,
        "medium": {"air": {"temperature": {"base": 12.0, "lapse": -0.0065}, "pressure": 101325.0, "humidity": 0.0}},
        "free": ["air.temperature.lapse", "camera.tilt"]
    })
}

/// Writes `problem` beside a 1200 × 800 PNG and runs `args` on it:
/// (exit code, stderr, the problem's path, whether any output exists).
fn run(problem: &Value, args: &[&str]) -> (Option<i32>, String, PathBuf, bool) {
    let dir = tempfile::tempdir().unwrap();
    image::RgbImage::from_pixel(1200, 800, image::Rgb([80, 110, 150]))
        .save(dir.path().join("photo.png"))
        .unwrap();
    std::fs::write(dir.path().join("notes.png"), "not an image").unwrap();
    let input = dir.path().join("problem.json");
    std::fs::write(&input, serde_json::to_string_pretty(problem).unwrap()).unwrap();
    let outs: Vec<PathBuf> = ["out.json", "overlay.png"]
        .iter()
        .map(|n| dir.path().join(n))
        .collect();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_mirage"));
    for a in args {
        match *a {
            "PROBLEM" => cmd.arg(&input),
            "OUT" => cmd.arg(&outs[0]),
            "OVERLAY" => cmd.arg(&outs[1]),
            other => cmd.arg(other),
        };
    }
    let run = cmd.output().unwrap();
    let written = outs.iter().any(|p| p.exists());
    (
        run.status.code(),
        String::from_utf8_lossy(&run.stderr).into_owned(),
        input,
        written,
    )
}

const FIT: &[&str] = &["fit", "PROBLEM", "-o", "OUT", "--overlay", "OVERLAY", "-q"];

fn set(v: &mut Value, pointer: &str, x: Value) {
    let (parent, key) = pointer.rsplit_once('/').unwrap();
    let p = v.pointer_mut(parent).unwrap();
    match p {
        Value::Object(m) => {
            m.insert(key.to_string(), x);
        }
        Value::Array(a) => a[key.parse::<usize>().unwrap()] = x,
        _ => panic!("{pointer}"),
    }
}

fn remove(v: &mut Value, pointer: &str) {
    let (parent, key) = pointer.rsplit_once('/').unwrap();
    v.pointer_mut(parent)
        .unwrap()
        .as_object_mut()
        .unwrap()
        .remove(key);
}

fn check(problem: &Value, args: &[&str], expected: &[&str]) {
    let (code, stderr, input, written) = run(problem, args);
    assert_eq!(code, Some(2), "{expected:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(
        stderr.contains(&input.display().to_string())
            || expected.iter().any(|e| e.starts_with("--")),
        "the file is not named: {stderr}"
    );
    for e in expected {
        assert!(stderr.contains(e), "{e:?} missing from: {stderr}");
    }
    assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
    assert!(!written, "{expected:?}: an output was written");
}

#[test]
fn the_base_problem_fits_and_draws() {
    let (code, stderr, _, written) = run(&base(), FIT);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(written);
}

#[test]
fn every_photo_field_is_checked_by_name() {
    type Edit = Box<dyn Fn(&mut Value)>;
    let cases: Vec<(Edit, Vec<&str>)> = vec![
        (
            Box::new(|v| set(v, "/marks/0/pixel", json!([5000.0, 10.0]))),
            vec!["marks[0].pixel[0]", "outside the image"],
        ),
        (
            Box::new(|v| set(v, "/marks/1/pixel", json!([10.0, -3.0]))),
            vec!["marks[1].pixel[1]", "outside the image"],
        ),
        (
            // The fuzz target `photo`: a horizon mark's pixel beyond where
            // the distortion folds the image over had no ray, and a NaN
            // residual; a target mark's was refused already.
            Box::new(|v| set(v, "/photo/camera/distortion", json!({"k1": -200.0}))),
            vec!["marks[1].pixel", "fold the image over"],
        ),
        (
            Box::new(|v| set(v, "/photo/image", json!("nope.jpg"))),
            vec!["photo.image", "nope.jpg"],
        ),
        (
            Box::new(|v| set(v, "/photo/image", json!("notes.png"))),
            vec!["photo.image", "notes.png"],
        ),
        (
            Box::new(|v| remove(v, "/photo/camera/horizontal_fov")),
            vec!["photo.camera.focal_length", "EXIF"],
        ),
        (
            Box::new(|v| {
                remove(v, "/earth");
                set(v, "/free", json!(["camera.tilt"]));
            }),
            vec!["marks[1].horizon", "round earth"],
        ),
        (
            Box::new(|v| set(v, "/marks/0/target", json!([0.0, 5.0, -1000.0]))),
            vec!["marks[0].target", "behind the camera"],
        ),
        (
            Box::new(|v| {
                remove(v, "/photo/camera/horizontal_fov");
                set(v, "/photo/camera/focal_length", json!(200.0));
            }),
            vec!["photo.camera.sensor_width", "missing"],
        ),
        (
            Box::new(|v| set(v, "/photo/camera/focal_length", json!(200.0))),
            vec!["photo.camera.horizontal_fov", "not both"],
        ),
        (
            Box::new(|v| set(v, "/photo/camera/horizontal_fov", json!(200.0))),
            vec!["photo.camera.horizontal_fov", "between 0 and 180"],
        ),
        (
            Box::new(|v| set(v, "/photo/camera/tilt", json!(95.0))),
            vec!["photo.camera.tilt", "between -90 and 90"],
        ),
        (
            Box::new(|v| set(v, "/photo/camera/zoom", json!(2.0))),
            vec!["photo.camera", "zoom"],
        ),
        (
            Box::new(|v| set(v, "/photo/camera/distortion", json!({"k1": "a lot"}))),
            vec!["photo.camera.distortion.k1"],
        ),
        (
            Box::new(|v| set(v, "/photo/camera/distortion", json!({"k4": 0.1}))),
            vec!["photo.camera.distortion", "k4"],
        ),
        (
            Box::new(|v| set(v, "/photo/camera/principal_point", json!([1300.0, 400.0]))),
            vec!["photo.camera.principal_point[0]", "inside the image"],
        ),
        (
            Box::new(|v| set(v, "/free", json!(["air.temperature.lapse", "camera.zoom"]))),
            vec!["free[1]", "unknown camera parameter"],
        ),
        (
            Box::new(|v| set(v, "/free", json!(["camera.focal_length"]))),
            vec!["free[0]", "focal length"],
        ),
        (
            Box::new(|v| set(v, "/free", json!(["camera.tilt", "camera.tilt"]))),
            vec!["free[1]", "twice"],
        ),
        (
            Box::new(|v| set(v, "/bounds", json!({"camera.roll": [-1.0, 1.0]}))),
            vec!["bounds.camera.roll", "not a free parameter"],
        ),
        (
            Box::new(|v| set(v, "/bounds", json!({"camera.tilt": [1.0, 2.0]}))),
            vec!["bounds.camera.tilt", "holding the start"],
        ),
        (
            Box::new(|v| set(v, "/marks", json!([]))),
            vec!["marks", "at least one mark"],
        ),
        (
            Box::new(|v| remove(v, "/marks/0/target")),
            vec!["marks[0].target", "missing"],
        ),
        (
            Box::new(|v| set(v, "/marks/1/target", json!([0.0, 5.0, 900.0]))),
            vec!["marks[1].horizon", "not both"],
        ),
        (
            Box::new(|v| set(v, "/marks/0/colour", json!("red"))),
            vec!["marks[0]", "colour"],
        ),
        (
            Box::new(|v| set(v, "/noise", json!(-1.0))),
            vec!["noise", "pixels"],
        ),
        (
            Box::new(|v| {
                remove(v, "/photo");
                set(v, "/free", json!(["air.temperature.lapse"]));
            }),
            vec!["marks", "photo"],
        ),
        (
            Box::new(|v| {
                set(
                    v,
                    "/pairs",
                    json!([{"origin": [0, 10, 0], "through": [0, 10, 100], "target": [0, 10, 3000]}]),
                )
            }),
            vec!["pairs", "marks"],
        ),
        (
            Box::new(|v| remove(v, "/photo/camera/position")),
            vec!["photo.camera.position", "missing"],
        ),
        (
            Box::new(|v| set(v, "/photo/camera/position", json!([0.0, -3.0, 0.0]))),
            vec!["photo.camera.position", "below the ground"],
        ),
        (
            Box::new(|v| set(v, "/photo/horizon_range", json!(-5.0))),
            vec!["photo.horizon_range"],
        ),
        (
            Box::new(|v| {
                set(
                    v,
                    "/medium",
                    json!({"scale": 1.0, "background": {"n": 1.0, "a": 40.0},
                           "hotspots": [{"x": 0, "z": 500, "radius": 50, "n": -1, "a": -0.3}]}),
                );
                set(v, "/free", json!(["camera.tilt"]));
            }),
            vec!["marks", "height alone"],
        ),
        (
            Box::new(|v| set(v, "/residual", json!("angle"))),
            vec!["residual", "pixels"],
        ),
    ];
    for (edit, expected) in cases {
        let mut v = base();
        edit(&mut v);
        check(&v, FIT, &expected);
    }
}

#[test]
fn photo_flags_on_the_wrong_problem_fail_before_any_work() {
    // --overlay on a problem without a photo.
    let plain = json!({
        "medium": {"air": {"temperature": {"base": 12.0, "lapse": -0.0065}}},
        "free": ["air.temperature.lapse"],
        "pairs": [{"origin": [0, 10, 0], "through": [0, 10, 100], "target": [0, 10, 3000]}]
    });
    check(&plain, FIT, &["--overlay", "photo"]);
    check(
        &plain,
        &["overlay", "PROBLEM", "-o", "OVERLAY"],
        &["photo", "missing"],
    );
    // --grow on a photo problem; an overlay that is not a PNG.
    check(
        &base(),
        &["fit", "PROBLEM", "-o", "OUT", "--grow", "-q"],
        &["--grow", "photo"],
    );
    let (code, stderr, _, _) = run(&base(), &["overlay", "PROBLEM", "-o", "OUT"]);
    assert_eq!(code, Some(2), "{stderr}");
    assert!(stderr.contains(".png"), "{stderr}");
}

#[test]
fn a_camera_name_without_a_photo_is_refused() {
    let v = json!({
        "medium": {"air": {"temperature": {"base": 12.0, "lapse": -0.0065}}},
        "free": ["camera.tilt"],
        "pairs": [{"origin": [0, 10, 0], "through": [0, 10, 100], "target": [0, 10, 3000]}]
    });
    check(
        &v,
        &["fit", "PROBLEM", "-o", "OUT", "-q"],
        &["free[0]", "no `photo`"],
    );
}
