//! Dispersion: per-pair wavelengths in problems (traced through the medium
//! at their own wavelength, with an exact Jacobian) and dispersive renders
//! (each colour channel through the air at its own wavelength).

use mirage::evaluate::trace_pairs;
use mirage::fit::objective::Objective;
use mirage::math::V3;
use mirage::medium::IndexField;
use mirage::problem::Problem;
use mirage::render::{RenderOptions, Renderer};
use mirage::scene::Scene;
use std::path::Path;

/// Real air with a lapse rate (rays bend down, nearly uniformly) and a cold
/// layer over the ground; pairs 0 and 1 are the same ray at 450 and 700 nm.
const PROBLEM: &str = r#"{
  "name": "dispersion",
  "medium": { "air": {
    "temperature": { "base": 12.0, "lapse": -0.0065,
                     "exponential": { "delta": -2.0, "scale_height": 4.0 } },
    "humidity": 0.0, "wavelength": 550.0 } },
  "free": ["air.temperature.base", "air.temperature.exponential.delta", "air.temperature.lapse"],
  "pairs": [
    { "origin": [0.0, 5.0, 0.0], "through": [0.0, 5.0, 100.0], "target": [0.0, 5.0, 4000.0], "wavelength": 450.0 },
    { "origin": [0.0, 5.0, 0.0], "through": [0.0, 5.0, 100.0], "target": [0.0, 5.0, 4000.0], "wavelength": 700.0 },
    { "origin": [0.0, 5.0, 0.0], "through": [0.0, 5.0, 100.0], "target": [0.0, 5.0, 4000.0] },
    { "origin": [0.0, 3.0, 0.0], "through": [0.0, 3.5, 1000.0], "target": [0.0, 4.0, 3000.0], "wavelength": 450.0 }
  ],
  "trace": { "method": "rk4", "step": 5.0 }
}"#;

fn problem() -> Problem {
    Problem::parse(PROBLEM, Path::new("dispersion.json")).unwrap()
}

#[test]
fn blue_and_red_land_at_heights_in_the_ratio_of_their_refractivities() {
    let p = problem();
    let report = trace_pairs(&p, &p.medium);
    let drop = |i: usize| report.pairs[i].endpoint[1] - 5.0;
    let (blue, red, plain) = (drop(0), drop(1), drop(2));
    // The rays bend down (δ falls with height), blue more than red.
    assert!(
        blue < red && red < 0.0,
        "drops: 450 nm {blue}, 700 nm {red}"
    );
    assert!(blue < plain && plain < red, "550 nm drop {plain} between");
    // n − 1 is a wavelength factor times a density for dry air, so the
    // bending (first order in ∇δ) scales with δ(λ): compare the ratios
    // (within 10 %: measured 5.5 %, from second-order bending and the
    // compressibility term).
    let at = |nm: f64| {
        let m = p.medium.at_wavelength(nm).unwrap();
        m.field().delta(V3::new(0.0, 5.0, 0.0))
    };
    let expected = at(450.0) / at(700.0) - 1.0;
    let got = blue / red - 1.0;
    assert!(expected > 0.01, "δ(450)/δ(700) − 1 = {expected}");
    assert!(
        (got - expected).abs() < 0.1 * expected,
        "drop ratio − 1 = {got}, refractivity ratio − 1 = {expected}"
    );
}

#[test]
fn the_jacobian_with_per_pair_wavelengths_matches_finite_differences() {
    let obj = Objective::from_problem(&problem());
    let x = obj.start();
    let (r, jac) = obj.jacobian(x.as_slice());
    let (r_plain, _) = obj.residuals(x.as_slice());
    assert!((&r - &r_plain).norm() <= 1e-12 * r.norm().max(1.0));
    // Pairs 0 and 2 differ only in their wavelength: so do their derivatives.
    assert!((jac.row(1) - jac.row(7)).norm() > 1e-6 * jac.row(1).norm());
    for k in 0..x.len() {
        let h = 1e-4 * x[k].abs().max(1e-2);
        let (mut xp, mut xm) = (x.clone(), x.clone());
        xp[k] += h;
        xm[k] -= h;
        let fd = (obj.residuals(xp.as_slice()).0 - obj.residuals(xm.as_slice()).0) / (2.0 * h);
        let col = jac.column(k);
        let err = (&fd - col).norm() / col.norm().max(1e-12);
        assert!(err < 1e-5, "parameter {k}: exact {col:?} vs fd {fd:?}");
    }
}

/// A small scene through real air without gradients (constant temperature,
/// no hydrostatic fall): every wavelength sees straight rays.
fn uniform_scene(dispersion: bool) -> Scene {
    let text = format!(
        r#"{{
  "camera": {{ "position": [0, 2, 0], "look_at": [0, 1.5, 40], "vertical_fov": 20, "width": 48, "height": 27 }},
  "medium": {{ "air": {{ "temperature": {{ "base": 15.0 }}, "hydrostatic": false }} }},
  "ground": {{ "checker": {{ "size": 1.0, "colors": [[0.1, 0.1, 0.1], [0.5, 0.4, 0.3]] }} }},
  "objects": [ {{ "albedo": [0.8, 0.3, 0.2], "shape": {{ "type": "sphere", "center": [0, 1.5, 40], "radius": 2.0 }} }} ],
  "sun": {{ "elevation": 30, "azimuth": 160 }},
  "dispersion": {dispersion}
}}"#
    );
    Scene::parse(&text, Path::new("uniform.json")).unwrap()
}

#[test]
fn air_without_gradients_renders_the_same_with_and_without_dispersion() {
    let options = RenderOptions::default();
    let plain = Renderer::new(&uniform_scene(false), &options).render();
    let disp = Renderer::new(&uniform_scene(true), &options).render();
    assert_eq!(disp.stats.samples, 3 * plain.stats.samples);
    let worst = plain
        .pixels
        .iter()
        .zip(&disp.pixels)
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs()))
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-4, "largest channel difference {worst}");
}

#[test]
fn the_green_flash_scene_shows_a_green_rim_above_the_red_sun() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/scenes/green-flash.json");
    let scene = Scene::load(&path).unwrap();
    assert!(scene.dispersion);
    let options = RenderOptions {
        width: Some(96),
        height: Some(54),
        glare: false,
        ..RenderOptions::default()
    };
    let disp = Renderer::new(&scene, &options).render();
    let plain_scene = Scene {
        dispersion: false,
        ..scene
    };
    let plain = Renderer::new(&plain_scene, &options).render();
    // Upper half of the frame: the sun's top edge. Red stands lower than
    // green (550 nm, the medium's own wavelength: G equals the plain render's
    // G), so along the edge red is lost and green, relative to red, gains.
    let (mut dg, mut dr) = (0.0f64, 0.0f64);
    for y in 0..disp.height / 2 {
        for x in 0..disp.width {
            let (d, p) = (disp.pixel(x, y), plain.pixel(x, y));
            dg += (d[1] - p[1]) as f64;
            dr += (d[0] - p[0]) as f64;
        }
    }
    assert!(dr < 0.0 && dg - dr > 0.0, "top edge: ΔG = {dg}, ΔR = {dr}");
}
