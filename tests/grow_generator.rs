//! `mirage fit --grow` on scenes it has never seen: the seeded generator of
//! `mirage::fit::synthetic::grow_cases` draws cases from a known truth
//! (nothing, a layer, one or two hot spots; the logistic model and real air
//! in kelvins; flat and round ground; 9–28 pairs, observers 1.5–5.5 m up,
//! targets 0.3–4 km out, 3–10 mm of noise), and growing from the background
//! alone must find the truth's set of terms with F ≤ 2 × the truth's own F
//! on the noisy pairs.
//!
//! - `short_form` (CI): 8 of the standard cases, every family and both
//!   kinds, flat and round, all of which growing passes today: a guard
//!   against regressions. All 8 must pass.
//! - `full_form` (`cargo test --release --test grow_generator -- --ignored
//!   --nocapture`): the 24 standard cases; the target (issue #39) is at
//!   least 23. It prints the table the README shows. At this commit 20 of 24
//!   pass: growing misses two hot spots that each turn rays by metres at
//!   2–4 km (indices 3, 11, 19) and, with 9 pairs, takes an inversion beside
//!   two real-air hot spots (23).
//!
//! `MIRAGE_GROW_CASES=DIR` also writes each drawn problem to DIR (to time
//! `mirage fit --grow` on them as a user would); `MIRAGE_GROW_ONLY=i,j,…`
//! runs only those standard indices.

use mirage::fit::synthetic::grow_cases::{CaseSpec, GrowCase, Terms, draw};
use std::time::Instant;

/// One case's outcome.
struct Row {
    index: u64,
    case: GrowCase,
    found: Terms,
    ratio: f64,
    seconds: f64,
    steps: Vec<String>,
    fits: usize,
}

impl Row {
    fn passed(&self) -> bool {
        self.found == self.case.terms() && self.ratio <= 2.0
    }
}

fn run(index: u64) -> Row {
    let case = draw(CaseSpec::standard(index)).expect("the generator draws a case");
    if let Ok(dir) = std::env::var("MIRAGE_GROW_CASES") {
        let path = std::path::Path::new(&dir).join(format!("{index:02}-{}.json", case.name));
        std::fs::write(
            &path,
            serde_json::to_string_pretty(&case.file).unwrap() + "\n",
        )
        .unwrap();
        let truth = serde_json::to_string_pretty(&case.truth).unwrap();
        std::fs::write(path.with_extension("truth"), truth + "\n").unwrap();
    }
    let started = Instant::now();
    let report = mirage::fit::fit(&case.problem, None).expect("growing runs");
    let seconds = started.elapsed().as_secs_f64();
    let g = report.grow.as_ref().expect("a growth report");
    // No fitted number runs away: every reported value is finite and within
    // 1e6 of its start's size (the generator's scenes are metres and kelvins).
    for p in &report.parameters {
        assert!(
            p.value.is_finite() && p.value.abs() <= 1e6 * p.start.abs().max(1.0),
            "{}: {} = {} (start {})",
            case.name,
            p.name,
            p.value,
            p.start
        );
    }
    Row {
        index,
        found: Terms::of(&report.medium),
        ratio: report.totals.objective / case.truth_objective,
        seconds,
        steps: g.steps.iter().map(|s| s.action.clone()).collect(),
        fits: g.fits,
        case,
    }
}

fn table(rows: &[Row]) -> String {
    let mut s = String::from(
        "|  # | case | pairs | obs. | reach (m) | σ (mm) | truth | found | F / F_truth | fits | time (s) | ok |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        s += &format!(
            "| {:2} | {} | {} | {} | {:.0} | {:.1} | {} | {} | {:.3} | {} | {:.1} | {} |\n",
            r.index,
            r.case.name,
            r.case.problem.pairs.len(),
            r.case.observers,
            r.case.reach,
            r.case.noise * 1e3,
            r.case.terms().describe(),
            r.found.describe(),
            r.ratio,
            r.fits,
            r.seconds,
            if r.passed() { "yes" } else { "**no**" }
        );
    }
    s
}

fn indices(default: impl Iterator<Item = u64>) -> Vec<u64> {
    match std::env::var("MIRAGE_GROW_ONLY") {
        Ok(list) => list
            .split(',')
            .map(|t| t.trim().parse().expect("MIRAGE_GROW_ONLY: indices"))
            .collect(),
        Err(_) => default.collect(),
    }
}

fn run_all(which: &[u64]) -> Vec<Row> {
    which
        .iter()
        .map(|&i| {
            let r = run(i);
            eprintln!(
                "case {:2} {:<34} truth {:<28} found {:<28} F/F_truth {:>8.3} {:>5.1} s  {}  {:?}",
                i,
                r.case.name,
                r.case.terms().describe(),
                r.found.describe(),
                r.ratio,
                r.seconds,
                if r.passed() { "ok" } else { "FAIL" },
                r.steps
            );
            r
        })
        .collect()
}

/// Standard indices 0–7 hold every (family, kind) once, flat; 8–15 over
/// the round earth. The short form: nothing, a layer and one hot spot of
/// the logistic model (flat, and one spot round), nothing, a layer and one
/// spot of real air round, two real-air spots flat.
#[test]
fn short_form() {
    let rows = run_all(&indices([0, 1, 2, 10, 12, 13, 14, 7].into_iter()));
    eprintln!("{}", table(&rows));
    let failed: Vec<u64> = rows
        .iter()
        .filter(|r| !r.passed())
        .map(|r| r.index)
        .collect();
    assert!(
        failed.is_empty(),
        "cases {failed:?} failed:\n{}",
        table(&rows)
    );
}

#[test]
#[ignore = "the 24 standard cases: a few minutes in release"]
fn full_form() {
    let rows = run_all(&indices(0..24));
    let passed = rows.iter().filter(|r| r.passed()).count();
    println!("{}", table(&rows));
    println!(
        "{passed} of {} cases found the truth's terms with F ≤ 2 F_truth; {:.1} s in all",
        rows.len(),
        rows.iter().map(|r| r.seconds).sum::<f64>()
    );
    assert!(
        passed + 1 >= rows.len(),
        "{passed} of {} passed",
        rows.len()
    );
}

/// The generator is what it says: seeded (the same case twice), every
/// family and kind present, every true term visible, 9–28 pairs.
#[test]
fn the_generator_is_seeded_and_covers_every_family() {
    let a = draw(CaseSpec::standard(5)).unwrap();
    let b = draw(CaseSpec::standard(5)).unwrap();
    assert_eq!(a.file, b.file);
    let mut seen = std::collections::BTreeSet::new();
    for i in 0..24 {
        let c = draw(CaseSpec::standard(i)).unwrap();
        let n = c.problem.pairs.len();
        assert!((9..=28).contains(&n), "{}: {n} pairs", c.name);
        assert!(c.truth_objective > 0.0 && c.truth_objective.is_finite());
        seen.insert((
            c.spec.family.name(),
            format!("{:?}", c.spec.kind),
            c.spec.round,
        ));
    }
    // 4 families × 2 kinds, each on flat and on round ground.
    assert_eq!(seen.len(), 16, "{seen:?}");
}
