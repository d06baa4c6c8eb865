//! A scene camera with a roll and a lens distortion (`camera.roll`,
//! `camera.distortion`) renders what the photo camera of `docs/photo.md`
//! sees: with straight rays, small spheres land where a photo camera built
//! from its azimuth, tilt and roll (`mirage::photo::camera`, independently
//! of the renderer's camera) projects their centres, within 0.3 pixel (the
//! centroid of whole pixels; 0.25 measured).
//!
//! The scene's frame and the photo problem's are mirror images (the
//! renderer's right is forward × up; the photo camera's is up × forward):
//! a scene point (x, y, z) is the photo point (−x, y, z), a scene azimuth a
//! the photo azimuth −a, with the same tilt, roll and radial distortion.

use mirage::geo::Horizon;
use mirage::math::V3;
use mirage::photo::camera::{CameraParam, CameraParams, FocalSource};
use mirage::render::{RenderOptions, Shading, render};
use mirage::scene::Scene;
use std::path::Path;
use std::process::Command;

const W: u32 = 320;
const H: u32 = 240;
const FOV: f64 = 20.0;
const AZ: f64 = 20.0;
const TILT: f64 = 1.0;
const ROLL: f64 = 3.0;
const K1: f64 = -0.5;
const K2: f64 = 0.1;
const EYE: [f64; 3] = [0.0, 2.0, 0.0];

fn scene_text(spheres: &str, camera_extra: &str) -> String {
    format!(
        r#"{{
          "camera": {{ "position": {EYE:?}, "azimuth": {AZ}, "elevation": {TILT},
                       "vertical_fov": {FOV}, "width": {W}, "height": {H}{camera_extra} }},
          "medium": {{ "scale": 0.02, "background": {{ "n": 1.0, "a": 150.0 }} }},
          "sky": {{ "type": "gradient", "zenith": [0, 0, 0], "horizon": [0, 0, 0] }},
          "objects": [ {spheres} ],
          "trace": {{ "step": 2.0, "max_distance": 1000.0 }}
        }}"#
    )
}

/// The photo camera of the scene's camera, in the photo frame.
fn photo_camera() -> CameraParams {
    let mut values = [0.0; 12];
    values[CameraParam::Azimuth.index()] = -AZ;
    values[CameraParam::Tilt.index()] = TILT;
    values[CameraParam::Roll.index()] = ROLL;
    values[CameraParam::Cx.index()] = 0.5 * (W as f64 - 1.0);
    values[CameraParam::Cy.index()] = 0.5 * (H as f64 - 1.0);
    values[CameraParam::K1.index()] = K1;
    values[CameraParam::K2.index()] = K2;
    CameraParams {
        values,
        focal: FocalSource::Pixels(0.5 * H as f64 / (0.5 * FOV.to_radians()).tan()),
        size: [W, H],
        position: EYE,
        frame: Horizon::at(EYE, None).unwrap(),
    }
}

#[test]
fn spheres_land_where_the_photo_camera_projects_them() {
    // Spheres 200 m out, over the whole frame (the corners are where the
    // distortion and the roll move pixels most).
    let offsets = [
        (0.0, 0.0),
        (-12.0, 6.0),
        (12.0, -6.5),
        (-11.0, -7.0),
        (12.5, 7.5),
        (4.0, -3.0),
    ];
    let frame = Horizon::at(EYE, None).unwrap();
    let centres: Vec<[f64; 3]> = offsets
        .iter()
        .map(|&(daz, del)| {
            let d = frame.direction(TILT + del, -AZ + daz);
            [
                EYE[0] + 200.0 * d[0],
                EYE[1] + 200.0 * d[1],
                EYE[2] + 200.0 * d[2],
            ]
        })
        .collect();
    // The scene holds the mirror images of the photo frame's points.
    let spheres: Vec<String> = centres
        .iter()
        .map(|c| {
            format!(
                r#"{{ "albedo": [1, 1, 1], "shape": {{ "type": "sphere", "center": [{}, {}, {}], "radius": 1.2 }} }}"#,
                -c[0], c[1], c[2]
            )
        })
        .collect();
    let extra = format!(r#", "roll": {ROLL}, "distortion": {{ "k1": {K1}, "k2": {K2} }}"#);
    let scene = Scene::parse(
        &scene_text(&spheres.join(","), &extra),
        Path::new("lens.json"),
    )
    .unwrap();
    let image = render(
        &scene,
        &RenderOptions {
            shading: Shading::Albedo,
            straight: true,
            progress: false,
            ..RenderOptions::default()
        },
    );
    let cam = photo_camera().at_values();
    let mut worst: f64 = 0.0;
    for c in &centres {
        let d = V3::new(c[0] - EYE[0], c[1] - EYE[1], c[2] - EYE[2]);
        let [u, v] = cam.project(d).unwrap();
        // The centroid of the lit pixels within 12 px of the expected one
        // (one sample a pixel, at its centre: whole pixels, so the centroid
        // of a disc about 12 px across is within a few tenths of a pixel).
        let (mut su, mut sv, mut n) = (0.0, 0.0, 0.0);
        for y in 0..H {
            for x in 0..W {
                let (du, dv) = (x as f64 - u, y as f64 - v);
                if du.hypot(dv) < 12.0 && image.pixel(x, y)[0] > 0.5 {
                    su += x as f64;
                    sv += y as f64;
                    n += 1.0;
                }
            }
        }
        assert!(n > 20.0, "sphere at pixel ({u:.1}, {v:.1}): {n} pixels lit");
        let miss = (su / n - u).hypot(sv / n - v);
        worst = worst.max(miss);
    }
    println!("worst centroid miss {worst:.3} px");
    assert!(worst < 0.3, "worst miss {worst} px");
    // And the corners really move: without the lens the spheres land
    // elsewhere (by more than 2 px at the corners).
    let plain = photo_camera();
    let mut values = plain.values;
    values[CameraParam::K1.index()] = 0.0;
    values[CameraParam::K2.index()] = 0.0;
    values[CameraParam::Roll.index()] = 0.0;
    let pin = plain.camera(&values);
    let c = centres[4];
    let d = V3::new(c[0] - EYE[0], c[1] - EYE[1], c[2] - EYE[2]);
    let (a, b) = (cam.project(d).unwrap(), pin.project(d).unwrap());
    assert!((a[0] - b[0]).hypot(a[1] - b[1]) > 2.0);
}

#[test]
fn bad_roll_and_distortion_are_named() {
    let bad = [
        (r#", "roll": 400"#, "camera.roll"),
        (r#", "distortion": { "k1": -30 }"#, "camera.distortion"),
        (r#", "distortion": { "k9": 0.1 }"#, "k9"),
        (r#", "roll": "left""#, "camera.roll"),
    ];
    for (extra, field) in bad {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("scene.json");
        std::fs::write(&input, scene_text("", extra)).unwrap();
        let output = dir.path().join("out.png");
        let run = Command::new(env!("CARGO_BIN_EXE_mirage"))
            .arg("render")
            .arg(&input)
            .arg("-o")
            .arg(&output)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{extra}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(stderr.contains("scene.json"), "{stderr}");
        assert!(stderr.contains(field), "{extra}: {stderr}");
        assert!(!output.exists());
    }
}
