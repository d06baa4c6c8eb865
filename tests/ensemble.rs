//! `mirage ensemble` (`docs/ensemble.md`): the envelopes hold the truth at
//! their nominal rate over a seeded family of synthetic problems, the same
//! seed gives the same members on any number of threads, a plan sent as JSON
//! gives the same members one at a time in any order, and bad input fails
//! before any work.
//!
//! The family: an inversion over the round earth (height 8–20 m, strength
//! and sharpness drawn) seen from 3–8 m by 10–16 sightings 2.5–8 km out in
//! all directions that clear the sea; targets where the true air puts each
//! ray, plus Gaussian
//! noise of σ = 1–3 cm in the target plane. Each problem's ensemble (100
//! members, parametric at the true σ) gives a 16–84 % band per parameter;
//! over 40 problems it must hold the truth within the binomial's mean ± 2σ
//! (21–33 of 40), and the 2.5–97.5 % band in at least 35.
//! `MIRAGE_ENSEMBLE_CASES=N` runs N problems instead (100: 59–65 and 94–95).

use mirage::fit::ensemble::{EnsemblePlan, EnsembleSettings, Member, ensemble};
use mirage::fit::synthetic::retarget;
use mirage::math::{SplitMix64, V3};
use mirage::problem::{Problem, ProblemFile};
use std::path::Path;
use std::process::Command;

fn gaussian(rng: &mut SplitMix64) -> f64 {
    let u1 = 1.0 - rng.next_f64();
    let u2 = rng.next_f64();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Seeded case k: the problem (starting at the truth) and the true values of
/// its free parameters, and σ.
fn case(k: u64) -> (Problem, [f64; 3], f64) {
    let mut rng = SplitMix64(0xe25e_0b1e ^ k.wrapping_mul(0x9e37_79b9_7f4a_7c15));
    let mut u = |lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
    let height = u(8.0, 20.0);
    let a = u(1.0, 4.0);
    let n = u(0.6, 1.4);
    let eye = u(3.0, 8.0);
    let sigma = u(0.01, 0.03);
    let count = u(10.0, 17.0) as usize;
    let mut pairs = Vec::new();
    for _ in 0..6 * count {
        let d = u(2500.0, 8000.0);
        let az = u(0.0, std::f64::consts::TAU);
        // Through a point 0–2 layer-heights up at the target's range (the
        // sea's drop there, d²/2R, included).
        let drop = d * d / (2.0 * 6.371e6);
        let up = u(0.3, 2.5) * height - drop;
        pairs.push(format!(
            r#"{{"origin": [0, {eye}, 0], "through": [{}, {up}, {}], "target": [{}, 0, {}]}}"#,
            d * az.sin(),
            d * az.cos(),
            d * az.sin(),
            d * az.cos()
        ));
    }
    let text = format!(
        r#"{{ "name": "inversion-{k}", "earth": {{"radius": 6371000.0}},
             "medium": {{"scale": 0.015, "background": {{"n": 1.0, "a": 300.0}},
                         "inversion": {{"n": {n}, "a": {a}, "height": {height}}}}},
             "free": ["inversion.height", "inversion.a", "inversion.n"],
             "pairs": [{}],
             "trace": {{"method": "dopri5", "tolerance": 1e-9}},
             "solver": {{"method": "lm", "max_iterations": 200}} }}"#,
        pairs.join(",")
    );
    let mut p = Problem::parse(&text, Path::new("generated.json")).unwrap();
    let field = p.medium.field();
    let (moved, failed) = retarget(&p.pairs, &field, &p.trace);
    // Sightlines that clear the sea: the first `count` of those drawn.
    let moved: Vec<_> = moved
        .into_iter()
        .enumerate()
        .filter(|(i, pair)| {
            !failed.contains(i) && !pair.evaluate::<f64, _>(&field, &p.trace, None).0.occluded
        })
        .map(|(_, pair)| pair)
        .take(count)
        .collect();
    assert!(
        moved.len() >= 6,
        "case {k}: {} clear sightlines",
        moved.len()
    );
    let mut rng = SplitMix64(k ^ 0x5eed_0000_0000);
    p.pairs = moved
        .into_iter()
        .map(|mut pair| {
            let normal = pair.plane_on(p.trace.earth).normal;
            let side = V3::new(normal.z, 0.0, -normal.x).normalized();
            let t = V3::from(pair.target)
                + V3::new(0.0, 1.0, 0.0) * (sigma * gaussian(&mut rng))
                + side * (sigma * gaussian(&mut rng));
            pair.target = t.to_array();
            pair
        })
        .collect();
    (p, [height, a, n], sigma)
}

#[test]
fn the_68_percent_band_holds_the_truth_at_its_rate() {
    let cases: u64 = std::env::var("MIRAGE_ENSEMBLE_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(40);
    let mut held = [0usize; 3];
    let mut held95 = [0usize; 3];
    let mut ratio = [0.0f64; 3];
    for k in 0..cases {
        let (problem, truth, sigma) = case(k);
        let r = ensemble(
            &problem,
            &EnsembleSettings {
                members: 100,
                noise: Some(sigma),
                bootstrap: false,
                seed: k,
            },
            None,
        )
        .unwrap();
        for (j, p) in r.parameters.iter().enumerate() {
            let q = p.percentiles;
            held[j] += usize::from(q[1] <= truth[j] && truth[j] <= q[3]);
            held95[j] += usize::from(q[0] <= truth[j] && truth[j] <= q[4]);
            if let Some(se) = p.standard_error {
                ratio[j] += p.std / se / cases as f64;
            }
        }
    }
    eprintln!(
        "{cases} problems: 68 % band held the truth {held:?} times, 95 % band {held95:?}; mean ensemble std / linearised s.e. {ratio:.2?}"
    );
    // The binomial's mean ± 2 standard deviations at 68 %, and at least
    // its mean − 2 standard deviations at 95 %.
    let n = cases as f64;
    let (mean, sd) = (0.68 * n, (n * 0.68 * 0.32).sqrt());
    let (lo, hi) = (
        (mean - 2.0 * sd).ceil() as usize,
        (mean + 2.0 * sd).floor() as usize,
    );
    let least95 = (0.95 * n - 2.0 * (n * 0.05 * 0.95).sqrt()).floor() as usize;
    for j in 0..3 {
        assert!(
            (lo..=hi).contains(&held[j]),
            "parameter {j}: the 68 % band held the truth in {} of {cases} (allowed {lo}–{hi})",
            held[j]
        );
        assert!(
            held95[j] >= least95,
            "parameter {j}: the 95 % band held the truth in {} of {cases} (at least {least95})",
            held95[j]
        );
    }
}

#[test]
fn the_same_seed_gives_the_same_members_on_any_threads() {
    let (problem, _, sigma) = case(3);
    let settings = EnsembleSettings {
        members: 6,
        noise: Some(sigma),
        bootstrap: false,
        seed: 11,
    };
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| ensemble(&problem, &settings, None).unwrap());
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
        .install(|| ensemble(&problem, &settings, None).unwrap());
    assert_eq!(one.members, two.members);
    // Another seed, other members; bootstrap differs from parametric.
    let other = ensemble(
        &problem,
        &EnsembleSettings {
            seed: 12,
            ..settings
        },
        None,
    )
    .unwrap();
    assert_ne!(one.members, other.members);
    let boot = ensemble(
        &problem,
        &EnsembleSettings {
            bootstrap: true,
            noise: None,
            ..settings
        },
        None,
    )
    .unwrap();
    assert_eq!(boot.resampling.kind, "bootstrap");
    assert_ne!(one.members, boot.members);
}

/// A plan as another process gets it: written as JSON, read back, its
/// members run one at a time, last first, then summarised. Members and
/// report equal `ensemble()`'s bit for bit: on a logistic problem (with a
/// truth), bootstrapped, on the Maine surveyor (angle residuals, a site and
/// geographic points), on real air, and on a problem that grows (the
/// members fit the grown model's terms).
#[test]
fn a_plan_sent_as_json_gives_the_members_and_report_of_the_whole() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems");
    let read = |name: &str| std::fs::read_to_string(root.join(name)).unwrap();
    let mut grows: serde_json::Value =
        serde_json::from_str(&read("grow/one-hot-spot.json")).unwrap();
    grows["free"] = serde_json::json!(["background.a"]);
    let settings = |members, noise, bootstrap| EnsembleSettings {
        members,
        noise,
        bootstrap,
        seed: 7,
    };
    let cases = [
        (
            "cold-sea.json",
            read("cold-sea.json"),
            settings(5, Some(0.02), false),
            true,
        ),
        (
            "cold-sea.json",
            read("cold-sea.json"),
            settings(5, None, true),
            false,
        ),
        (
            "maine-surveyor.json",
            read("maine-surveyor.json"),
            settings(4, Some(3.0), false),
            false,
        ),
        (
            "cold-sea-kelvin.json",
            read("cold-sea-kelvin.json"),
            settings(3, Some(0.01), false),
            true,
        ),
        (
            "grows.json",
            grows.to_string(),
            settings(3, Some(0.01), false),
            false,
        ),
    ];
    for (name, text, settings, with_truth) in cases {
        let path = root.join(name);
        let file: ProblemFile = serde_json::from_str(&text).unwrap();
        let problem = Problem::from_file(file.clone(), &path).unwrap();
        let truth = with_truth.then(|| problem.medium.clone());
        let whole = ensemble(&problem, &settings, truth.as_ref()).unwrap();
        let plan = EnsemblePlan::new(&problem, &settings, truth.as_ref()).unwrap();
        let json = plan.to_json(&file).unwrap();
        let again = EnsemblePlan::from_json(&json).unwrap();
        assert_eq!(again.settings(), &settings);
        let mut members: Vec<Member> = (0..settings.members)
            .rev()
            .map(|k| again.member(k).unwrap())
            .collect();
        members.reverse();
        assert_eq!(members, whole.members, "{name}");
        let mut report = again.summarise(members.clone(), 0.0).unwrap();
        report.wall_time_s = whole.wall_time_s;
        assert_eq!(
            serde_json::to_value(&report).unwrap(),
            serde_json::to_value(&whole).unwrap(),
            "{name}"
        );
        // Too few members, or a member of another model, is refused.
        let e = again
            .summarise(members[1..].to_vec(), 0.0)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("members: "), "{e}");
        let mut short = members.clone();
        short[0].params.pop();
        let e = again.summarise(short, 0.0).unwrap_err().to_string();
        assert!(e.contains("member 0 has"), "{e}");
    }
    // A damaged plan names its field.
    let problem = Problem::parse(&read("cold-sea.json"), &root.join("cold-sea.json")).unwrap();
    let file: ProblemFile = serde_json::from_str(&read("cold-sea.json")).unwrap();
    let plan = EnsemblePlan::new(&problem, &settings(2, Some(0.02), false), None).unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&plan.to_json(&file).unwrap()).unwrap();
    doc["sigma"].as_array_mut().unwrap().pop();
    let e = EnsemblePlan::from_json(&doc.to_string())
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("<plan>: sigma"), "{e}");
}

fn mirage(args: &[&str]) -> (Option<i32>, String) {
    let run = Command::new(env!("CARGO_BIN_EXE_mirage"))
        .args(args)
        .output()
        .unwrap();
    (
        run.status.code(),
        String::from_utf8_lossy(&run.stderr).into_owned(),
    )
}

#[test]
fn the_command_writes_the_ensemble_and_its_bands() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ens.json");
    let plot = dir.path().join("bands.png");
    let problem = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/cold-sea.json");
    let (code, stderr) = mirage(&[
        "ensemble",
        problem.to_str().unwrap(),
        "-n",
        "8",
        "--noise",
        "0.02",
        "--truth",
        problem.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--plot",
        plot.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{stderr}");
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(r["members"].as_array().unwrap().len(), 8);
    assert_eq!(r["parameters"].as_array().unwrap().len(), 3);
    let heights = r["profiles"]["heights"].as_array().unwrap().len();
    assert_eq!(
        r["profiles"]["temperature"]["percentiles"][2]
            .as_array()
            .unwrap()
            .len(),
        heights
    );
    assert!(r["profiles"]["temperature"]["truth"].is_array());
    assert!(std::fs::metadata(&plot).unwrap().len() > 10_000);
}

#[test]
fn bad_input_fails_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("ens.json");
    let o = out.to_str().unwrap();
    let problem = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/cold-sea.json");
    let p = problem.to_str().unwrap();
    let bad = dir.path().join("bad.json");
    std::fs::write(
        &bad,
        r#"{"name": "x", "medium": {"scale": 1.0}, "pairs": []}"#,
    )
    .unwrap();
    let no_medium = dir.path().join("truth.json");
    std::fs::write(&no_medium, r#"{"name": "x"}"#).unwrap();
    for (args, expected) in [
        (
            vec!["ensemble", p, "-n", "0", "-o", o],
            vec!["--members", "at least 1"],
        ),
        (vec!["ensemble", p, "-n", "x", "-o", o], vec!["--members"]),
        (
            vec!["ensemble", p, "-n", "5", "--noise", "-1", "-o", o],
            vec!["--noise"],
        ),
        (
            vec![
                "ensemble",
                p,
                "-n",
                "5",
                "--noise",
                "0.1",
                "--bootstrap",
                "-o",
                o,
            ],
            vec!["--bootstrap"],
        ),
        (
            vec!["ensemble", bad.to_str().unwrap(), "-n", "5", "-o", o],
            vec!["bad.json", "free"],
        ),
        (vec!["ensemble", p, "-n", "5", "-o", p], vec!["-o"]),
        (
            vec![
                "ensemble",
                p,
                "-n",
                "5",
                "--truth",
                no_medium.to_str().unwrap(),
                "-o",
                o,
            ],
            vec!["truth.json", "medium"],
        ),
        (
            vec!["ensemble", p, "-n", "5", "-o", o, "--plot", "bands.gif"],
            vec!["--plot"],
        ),
    ] {
        let (code, stderr) = mirage(&args);
        assert_eq!(code, Some(2), "{args:?}: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
        for e in expected {
            assert!(stderr.contains(e), "{e:?} missing from {stderr}");
        }
        assert!(!out.exists(), "{args:?} wrote an output");
    }
}
