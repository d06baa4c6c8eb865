//! The plots: ray diagrams and convergence plots render to PNG and SVG with
//! real content, a bad extension is an input error that writes nothing, and no
//! history (however odd) makes the convergence plot panic.

use mirage::fit::{History, IterationRecord, RunHistory};
use mirage::plot::{ImageFormat, draw_convergence, draw_rays};
use mirage::problem::Problem;
use std::collections::HashSet;
use std::path::Path;

/// Colour of pair 0's ray (the first colour of the plots' palette).
const PAIR0: [u8; 3] = [31, 119, 180];
/// The side view takes the left 72 % of the 1400 px ray diagram.
const SIDE_VIEW_RIGHT_EDGE: u32 = 1000;

const PROBLEM: &str = r#"{
  "name": "test-road",
  "medium": {
    "background": { "n": 1.0, "a": 40.0 },
    "hotspots": [ { "x": 0.0, "z": 500.0, "radius": 150.0, "n": -2.0, "a": -0.5 } ]
  },
  "pairs": [
    { "origin": [0.0, 1.6, 0.0], "through": [0.0, -1.0, 800.0], "target": [0.0, 12.0, 800.0] },
    { "origin": [0.0, 1.6, 0.0], "through": [30.0, -0.5, 800.0], "target": [30.0, 8.0, 800.0] },
    { "origin": [5.0, 3.0, 0.0], "through": [5.0, 2.0, 5000.0], "target": [5.0, 1.0, 600.0] }
  ],
  "trace": { "method": "rk4", "step": 2.0 }
}"#;

fn problem() -> Problem {
    Problem::parse(PROBLEM, Path::new("t.json")).expect("the test problem is valid")
}

/// Keeps a rendered file for inspection when `MIRAGE_PLOT_DIR` names a folder.
fn keep(path: &Path) {
    if let Some(dir) = std::env::var_os("MIRAGE_PLOT_DIR") {
        let name = path.file_name().unwrap();
        std::fs::copy(path, Path::new(&dir).join(name)).unwrap();
    }
}

fn decode(path: &Path) -> image::RgbImage {
    image::open(path)
        .unwrap_or_else(|e| panic!("{} does not decode: {e}", path.display()))
        .to_rgb8()
}

fn distinct_colours(img: &image::RgbImage) -> usize {
    img.pixels().map(|p| p.0).collect::<HashSet<_>>().len()
}

#[test]
fn ray_diagram_renders_to_png() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rays.png");
    let p = problem();
    draw_rays(&p, &p.medium, &out).unwrap();
    keep(&out);

    let img = decode(&out);
    assert_eq!(img.dimensions(), (1400, 700));
    assert!(
        distinct_colours(&img) >= 8,
        "only {} colours: the plot looks blank",
        distinct_colours(&img)
    );
    let pair0_in_side_view = img
        .enumerate_pixels()
        .filter(|(x, _, p)| *x < SIDE_VIEW_RIGHT_EDGE && p.0 == PAIR0)
        .count();
    assert!(
        pair0_in_side_view > 200,
        "pair 0's ray colour covers only {pair0_in_side_view} px of the side view"
    );
    // Text was rasterised: the title row (top 40 px) has dark pixels.
    let dark_title = img
        .enumerate_pixels()
        .filter(|(_, y, p)| *y < 40 && p.0.iter().all(|&c| c < 100))
        .count();
    assert!(
        dark_title > 50,
        "no title text drawn ({dark_title} dark px)"
    );
    // Nothing but the image is left in the folder (no temporary file).
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn ray_diagram_renders_to_svg_with_its_text() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("rays.SVG");
    let p = problem();
    draw_rays(&p, &p.medium, &out).unwrap();

    let svg = std::fs::read_to_string(&out).unwrap();
    assert!(
        svg.starts_with("<svg"),
        "not an SVG: {}",
        &svg[..60.min(svg.len())]
    );
    for text in [
        "test-road",
        "distance along the view (m)",
        "height (m",
        "δ × 10⁶",
        "traced with RK4, step 2 m",
        "pair 0",
        "pair 2",
        "over hotspots[0]",
    ] {
        assert!(svg.contains(text), "the SVG lacks {text:?}");
    }
    // Metres of bending over hundreds of metres: heights must be exaggerated.
    assert!(svg.contains("height (m, exaggerated)"));
}

#[test]
fn ray_diagram_of_a_problem_without_pairs_or_hot_spots() {
    let dir = tempfile::tempdir().unwrap();
    let text =
        r#"{ "name": "empty", "medium": { "background": { "n": 1.0, "a": 40.0 } }, "pairs": [] }"#;
    let p = Problem::parse(text, Path::new("e.json")).unwrap();
    let out = dir.path().join("e.svg");
    draw_rays(&p, &p.medium, &out).unwrap();
    let svg = std::fs::read_to_string(&out).unwrap();
    assert!(svg.contains("no point pairs"));
    assert!(!svg.contains("over hotspots"));
}

#[test]
fn a_bad_extension_is_an_input_error_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let p = problem();
    for name in ["rays.jpg", "rays"] {
        let out = dir.path().join(name);
        let e = draw_rays(&p, &p.medium, &out).unwrap_err();
        assert_eq!(e.exit_code(), 2, "{name}: {e}");
        assert!(e.to_string().contains(".png or .svg"), "{e}");
        let e = draw_convergence(&history(), &out).unwrap_err();
        assert_eq!(e.exit_code(), 2, "{name}: {e}");
    }
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    assert_eq!(
        ImageFormat::from_path(Path::new("x.Png")).unwrap(),
        ImageFormat::Png
    );
}

/// Two runs over three parameters; the first converges to exactly 0.
fn history() -> History {
    let run = |label: &str, n: u64, rate: f64, end_at_zero: bool| RunHistory {
        label: label.into(),
        records: (0..n)
            .map(|i| {
                let f = 0.5 * rate.powi(i as i32 * 3);
                IterationRecord {
                    iteration: i,
                    elapsed_s: 0.013 * i as f64,
                    objective: if end_at_zero && i + 1 == n { 0.0 } else { f },
                    params: vec![
                        -2.0 + 1.5 * (1.0 - rate.powi(i as i32)),
                        120.0 - 30.0 * (1.0 - rate.powi(i as i32)),
                        0.0 + 5.0 * rate.powi(i as i32),
                    ],
                }
            })
            .collect(),
    };
    History {
        param_names: vec![
            "hotspots[0].n".into(),
            "hotspots[0].radius".into(),
            "hotspots[0].x".into(),
        ],
        runs: vec![
            run("lm", 12, 0.3, true),
            run("lm (start 1)", 25, 0.7, false),
        ],
    }
}

#[test]
fn convergence_plot_renders_to_png_and_svg() {
    let dir = tempfile::tempdir().unwrap();
    let h = history();

    let png = dir.path().join("convergence.png");
    draw_convergence(&h, &png).unwrap();
    keep(&png);
    let img = decode(&png);
    assert_eq!(img.dimensions(), (1400, 900));
    assert!(distinct_colours(&img) >= 8, "the plot looks blank");
    let run0 = img.pixels().filter(|p| p.0 == PAIR0).count();
    assert!(run0 > 200, "run 0's colour covers only {run0} px");

    let svg_path = dir.path().join("convergence.svg");
    draw_convergence(&h, &svg_path).unwrap();
    let svg = std::fs::read_to_string(&svg_path).unwrap();
    for text in [
        "Fit convergence",
        "objective F (m²)",
        "iteration",
        "wall time since the start of the run (s)",
        "lm (start 1)",
        "hotspots[0].radius",
        "F = 0 is drawn on this line",
    ] {
        assert!(svg.contains(text), "the SVG lacks {text:?}");
    }
}

#[test]
fn convergence_plot_survives_odd_histories() {
    let dir = tempfile::tempdir().unwrap();
    let record = |iteration, objective, params: Vec<f64>| IterationRecord {
        iteration,
        elapsed_s: 0.0,
        objective,
        params,
    };
    let cases = vec![
        ("empty", History::default()),
        (
            "runs-without-records",
            History {
                param_names: vec!["scale".into()],
                runs: vec![RunHistory {
                    label: String::new(),
                    records: vec![],
                }],
            },
        ),
        (
            "single-record",
            History {
                param_names: vec!["scale".into()],
                runs: vec![RunHistory {
                    label: "lm".into(),
                    records: vec![record(0, 3.0, vec![1.0])],
                }],
            },
        ),
        (
            "all-zero-and-huge",
            History {
                param_names: vec!["a".into(), "b".into()],
                runs: vec![
                    RunHistory {
                        label: "zero".into(),
                        records: vec![
                            record(0, 0.0, vec![0.0, 0.0]),
                            record(1, 0.0, vec![0.0, 0.0]),
                        ],
                    },
                    RunHistory {
                        label: "huge".into(),
                        records: vec![
                            record(0, 1e300, vec![1e300, -1e300]),
                            record(u64::MAX, 1e-310, vec![-1e300, 1e-300]),
                        ],
                    },
                ],
            },
        ),
        (
            "params-disagree-with-names",
            History {
                param_names: vec![],
                runs: vec![RunHistory {
                    label: "nm".into(),
                    records: vec![
                        record(0, f64::INFINITY, vec![1.0, 2.0]),
                        record(1, 2.0, vec![f64::INFINITY]),
                        record(2, 1.0, vec![1.5, 2.5, 3.5]),
                    ],
                }],
            },
        ),
    ];
    for (name, h) in cases {
        for ext in ["png", "svg"] {
            let out = dir.path().join(format!("{name}.{ext}"));
            let result = std::panic::catch_unwind(|| draw_convergence(&h, &out));
            match result {
                Ok(Ok(())) => assert!(out.exists(), "{name}.{ext}: Ok but no file"),
                Ok(Err(e)) => assert!(!out.exists(), "{name}.{ext}: Err ({e}) left a file"),
                Err(_) => panic!("{name}.{ext}: draw_convergence panicked"),
            }
        }
    }
}

#[test]
fn crowded_plots_keep_their_legends_in_bounds() {
    let dir = tempfile::tempdir().unwrap();
    // Forty pairs fanning out over a hot spot.
    let pairs: Vec<String> = (0..40)
        .map(|i| {
            let x = i as f64 - 20.0;
            format!(
                r#"{{ "origin": [0, 1.6, 0], "through": [{x}, -0.5, 600], "target": [{x}, 5, 600] }}"#
            )
        })
        .collect();
    let text = PROBLEM.replace(
        &PROBLEM[PROBLEM.find("\"pairs\"").unwrap()..PROBLEM.find("\"trace\"").unwrap()],
        &format!("\"pairs\": [{}],\n  ", pairs.join(",\n")),
    );
    let p = Problem::parse(&text, Path::new("crowded.json")).unwrap();
    let out = dir.path().join("crowded.svg");
    draw_rays(&p, &p.medium, &out).unwrap();
    let svg = std::fs::read_to_string(&out).unwrap();
    assert!(svg.contains("pair 14:"));
    assert!(!svg.contains("pair 15:"), "the legend lists every pair");
    assert!(svg.contains("… and 25 more pairs"));

    // Fifteen runs over twenty parameters.
    let h = History {
        param_names: (0..20).map(|k| format!("p{k}")).collect(),
        runs: (0..15)
            .map(|r| RunHistory {
                label: format!("lm (start {r})"),
                records: (0..5)
                    .map(|i| IterationRecord {
                        iteration: i,
                        elapsed_s: 0.1 * i as f64,
                        objective: 10f64.powi(-(i as i32) - r),
                        params: (0..20).map(|k| (k * r) as f64 / (1.0 + i as f64)).collect(),
                    })
                    .collect(),
            })
            .collect(),
    };
    let out = dir.path().join("crowded-convergence.png");
    draw_convergence(&h, &out).unwrap();
    keep(&out);
    assert_eq!(decode(&out).dimensions(), (1400, 900));
}

/// Colour of the ground's line in the side view.
const GROUND_LINE: [u8; 3] = [140, 110, 70];

/// The mean row of the ground line's pixels in a band of columns of the side
/// view, if it shows there.
fn ground_row(img: &image::RgbImage, columns: std::ops::Range<u32>) -> Option<f64> {
    let rows: Vec<u32> = columns
        .flat_map(|x| (0..img.height()).map(move |y| (x, y)))
        .filter(|&(x, y)| img.get_pixel(x, y).0 == GROUND_LINE)
        .map(|(_, y)| y)
        .collect();
    (!rows.is_empty()).then(|| rows.iter().sum::<u32>() as f64 / rows.len() as f64)
}

#[test]
fn ray_diagram_draws_the_round_earth_curved() {
    // Over a 20 km earth the ground 800 m out lies 16 m below y = 0: the
    // ground line falls from left to right; over the flat ground it is level.
    let dir = tempfile::tempdir().unwrap();
    let round_text = PROBLEM.replace(
        r#""trace": {"#,
        r#""earth": { "radius": 20000.0 }, "trace": {"#,
    );
    let mut rows = Vec::new();
    for (name, text) in [("flat.png", PROBLEM.to_string()), ("round.png", round_text)] {
        let p = Problem::parse(&text, Path::new(name)).unwrap();
        let out = dir.path().join(name);
        draw_rays(&p, &p.medium, &out).unwrap();
        keep(&out);
        let img = decode(&out);
        let left = ground_row(&img, 150..200).expect("the ground shows on the left");
        let right = ground_row(&img, SIDE_VIEW_RIGHT_EDGE - 120..SIDE_VIEW_RIGHT_EDGE - 70)
            .expect("the ground shows on the right");
        rows.push((left, right));
    }
    let ((fl, fr), (rl, rr)) = (rows[0], rows[1]);
    assert!(
        (fl - fr).abs() < 1.5,
        "the flat ground is level: {fl} vs {fr}"
    );
    assert!(rr > rl + 40.0, "the round earth falls away: {rl} to {rr}");
    let svg = dir.path().join("round.svg");
    let round = Problem::parse(
        &PROBLEM.replace(
            r#""trace": {"#,
            r#""earth": { "radius": 20000.0 }, "trace": {"#,
        ),
        Path::new("round.json"),
    )
    .unwrap();
    draw_rays(&round, &round.medium, &svg).unwrap();
    assert!(
        std::fs::read_to_string(&svg)
            .unwrap()
            .contains("over the round earth")
    );
}
