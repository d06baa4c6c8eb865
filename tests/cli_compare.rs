//! `mirage compare` and `mirage sky` from the command line: metrics of known
//! images, limits, heat maps, and bad input (exit code 2, the file named).

use std::path::Path;
use std::process::{Command, Output};

fn mirage(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mirage"))
        .args(args)
        .output()
        .unwrap()
}

/// A (H, W, 3) float32 .npy of one colour.
fn npy(path: &Path, w: usize, h: usize, rgb: [f32; 3]) {
    let mut header =
        format!("{{'descr': '<f4', 'fortran_order': False, 'shape': ({h}, {w}, 3), }}");
    while (10 + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
    bytes.extend((header.len() as u16).to_le_bytes());
    bytes.extend(header.as_bytes());
    for _ in 0..w * h {
        for c in rgb {
            bytes.extend(c.to_le_bytes());
        }
    }
    std::fs::write(path, bytes).unwrap();
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

#[test]
fn known_offset_gives_known_metrics_and_json() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.npy"), dir.path().join("b.npy"));
    npy(&a, 20, 10, [0.2, 0.4, 0.6]);
    npy(&b, 20, 10, [0.3, 0.5, 0.7]);
    let json = dir.path().join("m.json");
    let heat = dir.path().join("heat.png");
    let o = mirage(&[
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--json",
        json.to_str().unwrap(),
        "--diff",
        heat.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert!((m["rmse"].as_f64().unwrap() - 0.1).abs() < 1e-6);
    assert!((m["psnr_db"].as_f64().unwrap() - 20.0).abs() < 1e-4);
    assert_eq!(m["share_over"].as_f64().unwrap(), 1.0);
    let img = image::open(&heat).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (20, 10));
    // 0.1 is twice the threshold: the top of the ramp.
    assert_eq!(img.get_pixel(3, 3).0, [255, 255, 255]);
}

#[test]
fn identical_images_report_infinite_psnr() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.npy");
    npy(&a, 12, 12, [0.5; 3]);
    let o = mirage(&[
        "compare",
        a.to_str().unwrap(),
        a.to_str().unwrap(),
        "--min-psnr",
        "35",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("inf (identical)"), "{}", text(&o));
}

#[test]
fn missed_limits_fail_after_writing_the_evidence() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.npy"), dir.path().join("b.npy"));
    npy(&a, 8, 8, [0.0; 3]);
    npy(&b, 8, 8, [0.1; 3]);
    let heat = dir.path().join("heat.png");
    let o = mirage(&[
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--diff",
        heat.to_str().unwrap(),
        "--min-psnr",
        "35",
        "--max-share-over",
        "0.01",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(text(&o).contains("PSNR 20.00 dB < 35 dB"), "{}", text(&o));
    assert!(heat.exists());
}

#[test]
fn bad_input_is_named_and_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.npy"), dir.path().join("b.npy"));
    npy(&a, 8, 8, [0.0; 3]);
    npy(&b, 9, 8, [0.0; 3]);
    let o = mirage(&["compare", a.to_str().unwrap(), b.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o).contains("b.npy") && text(&o).contains("differs"),
        "{}",
        text(&o)
    );

    let missing = dir.path().join("nope.exr");
    let o = mirage(&["compare", a.to_str().unwrap(), missing.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("nope.exr"), "{}", text(&o));

    let junk = dir.path().join("junk.png");
    std::fs::write(&junk, b"not a png").unwrap();
    let o = mirage(&["compare", junk.to_str().unwrap(), a.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("junk.png"), "{}", text(&o));

    let o = mirage(&[
        "compare",
        a.to_str().unwrap(),
        a.to_str().unwrap(),
        "--threshold=-1",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("--threshold"), "{}", text(&o));

    let o = mirage(&["compare", a.to_str().unwrap(), "image.tiff"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn sky_map_round_trips_through_compare_and_png_is_decoded_to_linear() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/scenes/road.json");
    let sky = dir.path().join("sky.exr");
    let o = mirage(&[
        "sky",
        scene.to_str().unwrap(),
        "-o",
        sky.to_str().unwrap(),
        "--width",
        "64",
        "--height",
        "33",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("lookup error"), "{}", text(&o));
    let o = mirage(&["compare", sky.to_str().unwrap(), sky.to_str().unwrap()]);
    assert!(
        o.status.success() && text(&o).contains("64×33"),
        "{}",
        text(&o)
    );

    // The albedo PNG of a render is the clamped linear value, sRGB-encoded:
    // read back as linear it matches the EXR to 8-bit quantisation.
    let (png, exr) = (dir.path().join("r.png"), dir.path().join("r.exr"));
    let o = mirage(&[
        "render",
        scene.to_str().unwrap(),
        "--albedo",
        "--width",
        "64",
        "-q",
        "-o",
        png.to_str().unwrap(),
        "--exr",
        exr.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let o = mirage(&[
        "compare",
        png.to_str().unwrap(),
        exr.to_str().unwrap(),
        "--threshold",
        "0.01",
        "--max-share-over",
        "0",
    ]);
    assert!(o.status.success(), "{}", text(&o));
}

#[test]
fn sky_rejects_bad_sizes_and_formats() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/scenes/road.json");
    let out = dir.path().join("sky.exr");
    let o = mirage(&[
        "sky",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--height",
        "1",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("--height"), "{}", text(&o));
    let png = dir.path().join("sky.png");
    let o = mirage(&["sky", scene.to_str().unwrap(), "-o", png.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!out.exists() && !png.exists());
}

#[test]
fn render_rejects_a_bad_hit_fraction() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/scenes/road.json");
    let out = dir.path().join("r.png");
    for bad in ["0", "1.5", "nan"] {
        let o = mirage(&[
            "render",
            scene.to_str().unwrap(),
            "-q",
            "--width",
            "16",
            "-o",
            out.to_str().unwrap(),
            "--hit-fraction",
            bad,
        ]);
        assert_eq!(o.status.code(), Some(2), "{bad}: {}", text(&o));
        assert!(text(&o).contains("--hit-fraction"), "{}", text(&o));
        assert!(!out.exists());
    }
}
