//! Scene files and the `mirage render` command: the bundled scenes load and
//! use the air their problems fit to; bad input is one line naming the file
//! and the field (exit 2, no output); `medium_from` reads a fit result; the
//! image does not depend on the number of threads; PNG and EXR are written;
//! path reuse changes nothing a picture can show.

use glam::DVec3;
use mirage::math::V3;
use mirage::medium::IndexField;
use mirage::problem::Problem;
use mirage::render::march::MarchStats;
use mirage::render::{RenderOptions, Renderer, Shading, render};
use mirage::scene::Scene;
use mirage::trace::state::rate;
use mirage::trace::{RayState, rk4_step};
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

fn scene(name: &str) -> Scene {
    Scene::load(&root().join("problems/scenes").join(format!("{name}.json"))).unwrap()
}

#[test]
fn bundled_scenes_use_the_air_their_problems_fit_to() {
    for (scene_name, problem) in [
        ("road", "hot-road"),
        ("sea", "cold-sea"),
        ("desert", "desert-lake"),
    ] {
        let s = scene(scene_name);
        let p = Problem::load(&root().join("problems").join(format!("{problem}.json"))).unwrap();
        let fitted = mirage::fit::fit(&p, None).unwrap().medium;
        let (a, b) = (s.medium.params(), fitted.params());
        assert_eq!(a.len(), b.len(), "{scene_name}");
        for ((pa, va), (pb, vb)) in a.iter().zip(&b) {
            assert_eq!(pa, pb);
            assert!(
                (va - vb).abs() <= 1e-6 * vb.abs().max(1.0),
                "{scene_name}: {pa} = {va}, the fit of {problem} gives {vb}"
            );
        }
        assert!(!s.objects.is_empty() && s.ground.is_some());
    }
}

const GOOD: &str = r#"{
  "camera": { "position": [0, 2, 0], "look_at": [0, 2, 100], "vertical_fov": 2.0, "width": 8, "height": 6 },
  "medium": { "scale": 0.02, "background": { "n": 1.0, "a": 150.0 } },
  "ground": { "albedo": [0.3, 0.3, 0.3] },
  "objects": [ { "albedo": [1, 0, 0], "shape": { "type": "sphere", "center": [0, 2, 50], "radius": 1 } } ],
  "trace": { "step": 4, "max_distance": 1000 }
}"#;

/// Runs `mirage render` on `text` (written as scene.json in a temporary
/// folder, with `extra` files beside it) and returns (exit code, stderr, the
/// folder's files afterwards).
fn run(text: &str, extra: &[(&str, &str)], args: &[&str]) -> (Option<i32>, String, Vec<String>) {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("scene.json");
    std::fs::write(&input, text).unwrap();
    for (name, content) in extra {
        std::fs::write(dir.path().join(name), content).unwrap();
    }
    let out = Command::new(env!("CARGO_BIN_EXE_mirage"))
        .current_dir(dir.path())
        .arg("render")
        .arg("scene.json")
        .args(args)
        .output()
        .unwrap();
    let mut files: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
        files,
    )
}

fn rejects(text: &str, extra: &[(&str, &str)], args: &[&str], expected: &[&str]) {
    let (code, stderr, files) = run(text, extra, args);
    assert_eq!(code, Some(2), "{expected:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    for e in expected {
        assert!(stderr.contains(e), "{e:?} missing from {stderr}");
    }
    let mut inputs: Vec<String> = std::iter::once("scene.json".to_string())
        .chain(extra.iter().map(|(n, _)| n.to_string()))
        .collect();
    inputs.sort();
    assert_eq!(files, inputs, "something was written: {stderr}");
}

fn with(field: &str, value: &str) -> String {
    let mut v: serde_json::Value = serde_json::from_str(GOOD).unwrap();
    let mut at = &mut v;
    let parts: Vec<&str> = field.split('.').collect();
    for p in &parts[..parts.len() - 1] {
        at = &mut at[*p];
    }
    at[parts[parts.len() - 1]] = serde_json::from_str(value).unwrap();
    v.to_string()
}

#[test]
fn bad_scenes_are_refused_with_file_and_field() {
    let png = ["-o", "out.png"];
    // The good scene renders (so the refusals below are about their fields).
    let (code, stderr, files) = run(GOOD, &[], &["-o", "out.png", "-q"]);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(files.contains(&"out.png".to_string()));

    rejects(
        &with("camera.fov", "1.0"),
        &[],
        &png,
        &["scene.json", "camera", "unknown field `fov`"],
    );
    rejects(
        &with("camera.vertical_fov", "0"),
        &[],
        &png,
        &["scene.json: camera.vertical_fov", "(0, 179]"],
    );
    rejects(&with("camera.width", "0"), &[], &png, &["camera.width"]);
    rejects(
        &with("camera.look_at", "[0, 2, 0]"),
        &[],
        &png,
        &["camera.look_at", "must differ"],
    );
    rejects(
        &with("camera.up", "[0, 0, 1]"),
        &[],
        &png,
        &["camera.up", "parallel"],
    );
    rejects(
        &with("medium.background.a", "0"),
        &[],
        &png,
        &["medium.background.a", "rate"],
    );
    rejects(
        &with("medium_from", "\"r.json\""),
        &[],
        &png,
        &["medium_from", "not both"],
    );
    rejects(
        &with(
            "ground.checker",
            r#"{"size": 1, "colors": [[0,0,0],[1,1,1]]}"#,
        ),
        &[],
        &png,
        &["ground.checker", "not both"],
    );
    rejects(
        &with("ground.albedo", "[0.5, 2, 0]"),
        &[],
        &png,
        &["ground.albedo[1]", "[0, 1]"],
    );
    rejects(
        &with(
            "objects",
            r#"[{"albedo": [1,0,0], "shape": {"type": "sphere", "center": [0,0,0], "radius": -1}}]"#,
        ),
        &[],
        &png,
        &["objects[0].shape.radius", "> 0"],
    );
    rejects(
        &with(
            "objects",
            r#"[{"albedo": [1,0,0], "shape": {"type": "blob"}}]"#,
        ),
        &[],
        &png,
        &["objects[0].shape", "blob"],
    );
    rejects(
        &with("sun", r#"{"elevation": 95, "azimuth": 0}"#),
        &[],
        &png,
        &["sun.elevation"],
    );
    rejects(
        &with("sky", r#"{"type": "spectral"}"#),
        &[],
        &png,
        &["sky", "spectral"],
    );
    rejects(
        &with("sky", r#"{"type": "physical", "mie_scale": -1}"#),
        &[],
        &png,
        &["sky.mie_scale", "[0, 1000]"],
    );
    rejects(
        &with("sky", r#"{"type": "physical", "haze": 2}"#),
        &[],
        &png,
        &["sky", "unknown field `haze`"],
    );
    rejects(
        &with(
            "glare",
            r#"{"kernels": [{"type": "gaussian", "sigma": 0.1, "weight": 1.5}]}"#,
        ),
        &[],
        &png,
        &["glare.kernels[0].weight", "[0, 1]"],
    );
    rejects(
        &with(
            "glare",
            r#"{"kernels": [{"type": "compact", "radius": 0, "weight": 0.1}]}"#,
        ),
        &[],
        &png,
        &["glare.kernels[0].radius", "(0, 90]"],
    );
    rejects(
        &with("glare", r#"{"strength": 400}"#),
        &[],
        &png,
        &["glare.strength", "≤ 1"],
    );
    rejects(
        &with("glare", r#"{"epsilon": 0.5}"#),
        &[],
        &png,
        &["glare.epsilon"],
    );
    rejects(&with("exposure", "0"), &[], &png, &["exposure", "> 0"]);
    rejects(
        &with("samples_per_pixel", "0"),
        &[],
        &png,
        &["samples_per_pixel"],
    );
    rejects(&with("trace.step", "-1"), &[], &png, &["trace.step", "> 0"]);
    rejects(
        &with("trace.max_distnce", "5"),
        &[],
        &png,
        &["trace", "max_distnce"],
    );
    rejects(
        "{ \"camera\": ",
        &[],
        &png,
        &["scene.json", "ends too early"],
    );
    // Command-line errors.
    rejects(
        GOOD,
        &[],
        &["-o", "out.png", "--spp", "0"],
        &["error: --spp: must be between 1 and"],
    );
    rejects(
        GOOD,
        &[],
        &["-o", "out.png", "--width", "0"],
        &["error: --width: must be between 1 and"],
    );
    rejects(
        GOOD,
        &[],
        &["-o", "out.png", "--tracer", "fast"],
        &["--tracer", "fast"],
    );
    rejects(GOOD, &[], &["-o", "out.svg"], &["out.svg", ".png"]);
    rejects(
        GOOD,
        &[],
        &["-o", "out.png", "--exr", "out.tif"],
        &["out.tif", ".exr"],
    );

    // medium_from: a missing file, a result whose medium is bad (named by its
    // own file and field), and an output over it.
    let mut v: serde_json::Value = serde_json::from_str(GOOD).unwrap();
    v.as_object_mut().unwrap().remove("medium");
    v["medium_from"] = "fit.json".into();
    let from = v.to_string();
    rejects(
        &from,
        &[],
        &png,
        &["scene.json: medium_from", "cannot read"],
    );
    let bad_result = r#"{ "name": "x", "medium": { "scale": 1.0, "inversion": { "n": 1, "a": 0, "height": 3 } } }"#;
    rejects(
        &from,
        &[("fit.json", bad_result)],
        &png,
        &["fit.json: medium.inversion.a"],
    );
    let good_result = r#"{ "medium": { "scale": 0.02, "background": { "n": 1.0, "a": 150.0 } }, "objective": 0 }"#;
    v["medium_from"] = "fit.png".into();
    rejects(
        &v.to_string(),
        &[("fit.png", good_result)],
        &["-o", "fit.png"],
        &["fit.png", "overwrite an input"],
    );
}

#[test]
fn medium_from_reads_a_fit_result() {
    let dir = tempfile::tempdir().unwrap();
    let mut v: serde_json::Value = serde_json::from_str(GOOD).unwrap();
    let inline = Scene::parse(GOOD, Path::new("inline.json")).unwrap();
    v.as_object_mut().unwrap().remove("medium");
    v["medium_from"] = "results/fit.json".into();
    std::fs::create_dir(dir.path().join("results")).unwrap();
    std::fs::write(
        dir.path().join("results/fit.json"),
        r#"{ "name": "t", "medium": { "scale": 0.02, "background": { "n": 1.0, "a": 150.0 } }, "pairs": [] }"#,
    )
    .unwrap();
    let path = dir.path().join("scene.json");
    std::fs::write(&path, v.to_string()).unwrap();
    let from = Scene::load(&path).unwrap();
    assert_eq!(from.medium, inline.medium);
    assert_eq!(from.inputs, vec![dir.path().join("results/fit.json")]);
}

#[test]
fn images_do_not_depend_on_the_thread_count() {
    for name in ["road", "sea"] {
        let s = scene(name);
        let opts = RenderOptions {
            width: Some(96),
            samples_per_pixel: Some(2),
            ..RenderOptions::default()
        };
        let go = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| render(&s, &opts))
        };
        let (one, two) = (go(1), go(2));
        assert_eq!(one.pixels, two.pixels, "{name}");
        assert_eq!(one.stats.march, two.stats.march, "{name}");
    }
}

#[test]
fn render_writes_png_and_exr() {
    let dir = tempfile::tempdir().unwrap();
    let scene_path = root().join("problems/scenes/sea.json");
    let png = dir.path().join("sea.png");
    let exr = dir.path().join("sea.exr");
    let out = Command::new(env!("CARGO_BIN_EXE_mirage"))
        .args(["render", "-q", "--width", "64", "--height", "36", "-o"])
        .arg(&png)
        .arg("--exr")
        .arg(&exr)
        .arg(&scene_path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = image::open(&png).unwrap();
    assert_eq!((img.width(), img.height()), (64, 36));
    let hdr = exr::prelude::read_first_rgba_layer_from_file(
        &exr,
        |res, _| vec![[0f32; 3]; res.width() * res.height()],
        |px: &mut Vec<[f32; 3]>, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.y() * 64 + pos.x()] = [r, g, b];
        },
    )
    .unwrap();
    let direct = Renderer::new(
        &Scene::load(&scene_path).unwrap(),
        &RenderOptions {
            width: Some(64),
            height: Some(36),
            ..RenderOptions::default()
        },
    )
    .render();
    assert_eq!(hdr.layer_data.channel_data.pixels, direct.pixels);
    // Outputs went through a temporary file and a rename: nothing else left.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
}

/// The path table's interpolated paths against rays integrated on their own
/// (same RK4 step), as angles seen from the camera, in pixels.
#[test]
fn path_table_interpolation_error_is_bounded() {
    let s = scene("sea");
    let r = Renderer::new(&s, &RenderOptions::default());
    let table = r.table().expect("stratified air: a table");
    let cam = *r.camera();
    let px = cam.pixel_angle();
    let field = r.air().field();
    let h = table.step();
    let mut worst = Vec::new();
    for k in 0..400 {
        let (u, v) = ((k * 37 % 400) as f64 / 400.0, k as f64 / 400.0);
        let dir = cam.direction(u * cam.width as f64, v * cam.height as f64);
        let ray = table.ray(dir).unwrap();
        // The reference: this ray integrated by itself.
        let mut evals = 0;
        let x0 = V3::new(cam.origin.x, cam.origin.y, cam.origin.z);
        let n0 = 1.0 + field.delta(x0);
        let mut y = RayState {
            x: x0,
            v: V3::new(dir.x, dir.y, dir.z) * n0,
            s: 0.0,
        };
        let mut f = rate(field, &y, &mut evals);
        let mut err = 0.0f64;
        let mut tau = 0.0;
        while tau + h < ray.tau_objects_end.min(ray.tau_max) {
            (y, f) = rk4_step(field, &y, &f, h, &mut evals);
            tau += h;
            if y.x.y < 0.0 {
                break;
            }
            let (p, _) = table.position(&ray, tau);
            let q = DVec3::new(y.x.x, y.x.y, y.x.z);
            err = err.max((p - q).length() / (q - cam.origin).length() / px);
        }
        worst.push(err);
    }
    worst.sort_by(f64::total_cmp);
    let (median, p99, max) = (worst[200], worst[396], worst[399]);
    println!(
        "interpolation error over 400 rays: median {median:.5} px, 99% {p99:.5} px, max {max:.5} px (table estimate {:.5} px)",
        table.stats().error_estimate / px
    );
    assert!(p99 <= 0.02, "{p99}");
    assert!(max <= 0.1, "{max}");
}

/// Path reuse changes nothing a picture shows: the same outcome for almost
/// every pixel, the rest at the edges of objects.
#[test]
fn path_reuse_agrees_with_integration() {
    let mut s = scene("sea");
    // One sky colour: compare what rays hit (the sky's gradient follows the
    // final direction, computed by the two routes in different ways).
    s.sky = mirage::scene::description::SkySpec::Gradient {
        zenith: Some([0.5; 3]),
        horizon: Some([0.5; 3]),
    };
    let opts = |path_reuse| RenderOptions {
        width: Some(160),
        shading: Shading::Albedo,
        path_reuse,
        ..RenderOptions::default()
    };
    let (a, b) = (render(&s, &opts(true)), render(&s, &opts(false)));
    assert!(a.stats.table_samples == a.stats.samples && b.stats.table_samples == 0);
    let differ = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .filter(|(p, q)| (0..3).any(|c| (p[c] - q[c]).abs() > 1e-3))
        .count();
    println!(
        "{differ} of {} pixels differ; SDF evaluations per pixel {:.1} vs {:.1}, RK4 steps {} vs {}",
        a.pixels.len(),
        a.stats.march.counters.object_evaluations as f64 / a.pixels.len() as f64,
        b.stats.march.counters.object_evaluations as f64 / b.pixels.len() as f64,
        a.stats.table.unwrap().rk4_steps,
        b.stats.march.rk4_steps
    );
    assert!(differ * 200 < a.pixels.len(), "{differ}");
    let _ = MarchStats::default();
}

/// Integrating camera rays ahead in packs of SIMD lanes changes nothing a
/// picture shows: the lanes take the very steps the tracer takes (to within
/// the polynomial exponential's ulp), so the lit renders of the hot-spot
/// scenes agree pixel for pixel to far below an 8-bit level, over the flat
/// ground and over the round earth, and nearly every step of the image is
/// taken in a pack.
#[test]
fn packs_agree_with_rays_one_by_one() {
    let mut round = scene("road");
    round.earth = mirage::trace::Earth::Round { radius: 6.371e6 };
    for (name, s) in [
        ("road", scene("road")),
        ("desert", scene("desert")),
        ("road over the round earth", round),
    ] {
        let opts = |packs| RenderOptions {
            width: Some(240),
            packs,
            ..RenderOptions::default()
        };
        let (a, b) = (render(&s, &opts(true)), render(&s, &opts(false)));
        assert_eq!(b.stats.march.pack_steps, 0, "{name}");
        assert!(
            a.stats.march.pack_steps * 10 > a.stats.march.rk4_steps * 9,
            "{name}: {} of {} steps in packs",
            a.stats.march.pack_steps,
            a.stats.march.rk4_steps
        );
        let worst = a
            .pixels
            .iter()
            .zip(&b.pixels)
            .map(|(p, q)| (0..3).map(|c| (p[c] - q[c]).abs()).fold(0.0f32, f32::max))
            .fold(0.0f32, f32::max);
        let differ = a
            .pixels
            .iter()
            .zip(&b.pixels)
            .filter(|(p, q)| (0..3).any(|c| (p[c] - q[c]).abs() > 1e-4))
            .count();
        println!(
            "{name}: {differ} of {} pixels differ by > 1e-4 (worst {worst:.1e}); RK4 steps per pixel {:.1} (packs) vs {:.1}",
            a.pixels.len(),
            a.stats.march.rk4_steps as f64 / a.pixels.len() as f64,
            b.stats.march.rk4_steps as f64 / b.pixels.len() as f64,
        );
        assert!(differ * 1000 <= a.pixels.len(), "{name}: {differ}");
    }
}

/// The desert of patches: hundreds of hot spots, culled (each step pays
/// for the patches within reach), and it renders: finite pixels, and the
/// patches' ponds change what straight rays would show.
#[test]
fn the_desert_of_patches_culls_and_renders() {
    let s = scene("desert-patches");
    let mirage::medium::Medium::Logistic(m) = &s.medium else {
        panic!("a logistic medium");
    };
    assert!(m.hotspots.len() >= 300, "{} hot spots", m.hotspots.len());
    let field = m.field();
    let grid = field.grid().expect("hundreds of small patches are culled");
    assert!(grid.longest() < m.hotspots.len() / 10, "{}", grid.longest());
    assert!(!s.objects.is_empty() && s.ground.is_some());
    let opts = RenderOptions {
        width: Some(96),
        ..RenderOptions::default()
    };
    let curved = render(&s, &opts);
    let straight = render(
        &s,
        &RenderOptions {
            straight: true,
            ..opts
        },
    );
    assert!(
        curved
            .pixels
            .iter()
            .flatten()
            .all(|c| c.is_finite() && *c >= 0.0)
    );
    let changed = curved
        .pixels
        .iter()
        .zip(&straight.pixels)
        .filter(|(a, b)| (0..3).any(|c| (a[c] - b[c]).abs() > 0.02))
        .count();
    assert!(
        changed * 100 >= curved.pixels.len(),
        "only {changed} of {} pixels differ from straight rays",
        curved.pixels.len()
    );
}
