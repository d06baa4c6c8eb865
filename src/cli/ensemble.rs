//! `mirage ensemble`: N fits of a problem to resampled observations, and the
//! spread of their parameters and profiles ([`crate::fit::ensemble`],
//! `docs/ensemble.md`). Every flag and the problem are checked before any
//! fit (exit code 2); the outputs are written atomically at the end.

use crate::error::{Result, ValueError};
use crate::fit::ensemble::{EnsembleReport, EnsembleSettings, PERCENTILES, check_members};
use crate::io::json::{parse_json, read_input};
use crate::io::{Output, OutputKind, check_outputs, write_json};
use crate::medium::Medium;
use crate::problem::{Problem, Residual};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Fit a problem N times to resampled observations: the parameters' spread
/// and the profiles' envelopes.
#[derive(Clone, Debug, PartialEq, clap::Args)]
pub struct EnsembleOptions {
    /// Problem file (JSON).
    pub problem: PathBuf,
    /// Number of members (fits).
    #[arg(short = 'n', long = "members", value_parser = members)]
    pub members: usize,
    /// The observations' noise σ: metres (arcseconds with angle residuals).
    /// Default: the pairs' own `noise`, else the fit's residual scale.
    #[arg(long, allow_negative_numbers = true, value_parser = noise)]
    pub noise: Option<f64>,
    /// Resample the pairs with replacement instead of adding noise.
    #[arg(long, conflicts_with = "noise")]
    pub bootstrap: bool,
    /// The ensemble's seed (the same seed gives the same members on any
    /// number of threads).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// A file whose `medium` is the true air (a problem or a fit result),
    /// drawn beside the envelopes.
    #[arg(long)]
    pub truth: Option<PathBuf>,
    /// Write the ensemble as JSON here.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Draw the temperature and n − 1 bands here (.png or .svg).
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

fn members(s: &str) -> std::result::Result<usize, ValueError> {
    let n: usize = s.trim().parse().map_err(|_| ValueError::NotAWholeNumber {
        value: s.to_string(),
    })?;
    check_members(n)
}

fn noise(s: &str) -> std::result::Result<f64, ValueError> {
    let v: f64 = s.trim().parse().map_err(|_| ValueError::NotANumber {
        value: s.to_string(),
    })?;
    crate::problem::check_noise(v)
}

/// Only the `medium` of a truth file.
#[derive(serde::Deserialize)]
struct MediumOnly {
    medium: Medium,
}

/// The true air of a document with a `medium` (a problem or a fit result:
/// `--truth`'s file, `path` naming it), validated; errors name
/// `medium.…` in it.
pub fn truth_of(text: &str, path: &std::path::Path) -> Result<Medium> {
    let file: MediumOnly = parse_json(text, path, "truth")?;
    file.medium
        .validate()
        .map_err(|e| e.within("medium").in_file(path))?;
    Ok(file.medium)
}

/// Runs the ensemble, writes its outputs, prints the summary.
pub fn run(o: &EnsembleOptions) -> Result<EnsembleReport> {
    let problem = Problem::load(&o.problem)?;
    crate::fit::ensemble::check_problem(&problem)?;
    let truth = match &o.truth {
        None => None,
        Some(path) => Some(truth_of(&read_input(path)?, path)?),
    };
    let mut inputs = vec![o.problem.as_path()];
    if let Some(t) = &o.truth {
        inputs.push(t.as_path());
    }
    check_outputs(
        [
            Some(Output::new("-o", &o.output, OutputKind::Any)),
            Output::optional("--plot", o.plot.as_ref(), OutputKind::Plot),
        ]
        .into_iter()
        .flatten(),
        &inputs,
    )?;
    let settings = EnsembleSettings {
        members: o.members,
        noise: o.noise,
        bootstrap: o.bootstrap,
        seed: o.seed,
    };
    let report = crate::fit::ensemble::ensemble(&problem, &settings, truth.as_ref())?;
    crate::interrupt::check()?;
    write_json(&o.output, &report)?;
    if let Some(plot) = &o.plot {
        crate::plot::draw_ensemble(&report, plot)?;
    }
    print!("{}", summary(&problem, &report));
    Ok(report)
}

/// The table printed after an ensemble.
pub fn summary(problem: &Problem, r: &EnsembleReport) -> String {
    let mut s = String::new();
    let unit = match problem.residual {
        Residual::Distance => "m",
        Residual::Angle => "″",
    };
    let how = match (r.resampling.kind, r.resampling.noise) {
        ("parametric", Some(sigma)) => format!(
            "parametric, σ = {sigma:.3e} {unit} ({})",
            match r.resampling.noise_from {
                Some("given") => "--noise",
                Some("pairs") => "the pairs' own noise",
                _ => "the fit's residual scale",
            }
        ),
        _ => "bootstrap (pairs drawn with replacement)".to_string(),
    };
    let _ = writeln!(
        s,
        "{}: {} members, {how}, seed {}, {:.2} s",
        r.problem,
        r.members.len(),
        r.resampling.seed,
        r.wall_time_s
    );
    let _ = writeln!(
        s,
        "{:<28} {:>13} {:>11} {:>11} {:>13} {:>13} {:>13}",
        "parameter", "best", "lin. s.e.", "ens. std", "2.5 %", "50 %", "97.5 %"
    );
    for p in &r.parameters {
        let se = p
            .standard_error
            .map_or_else(|| "—".to_string(), |v| format!("{v:.3e}"));
        let _ = writeln!(
            s,
            "{:<28} {:>13.6e} {:>11} {:>11.3e} {:>13.6e} {:>13.6e} {:>13.6e}",
            p.name, p.best, se, p.std, p.percentiles[0], p.percentiles[2], p.percentiles[4]
        );
    }
    for p in &r.parameters {
        if let Some(d) = &p.disagreement {
            let _ = writeln!(s, "note: {}: {d}", p.name);
        }
    }
    if r.resampling.noise_from == Some("fit") && r.objective < 1e-20 {
        let _ = writeln!(
            s,
            "note: the best fit is exact (F = {:.1e}), so its residual scale says nothing of the observations' noise: give --noise σ",
            r.objective
        );
    }
    let _ = writeln!(
        s,
        "profiles: {} heights to {:.4} m at x = {}, z = {} ({} temperature), percentiles {:?}",
        r.profiles.heights.len(),
        r.profiles.heights.last().copied().unwrap_or(0.0),
        r.profiles.at[0],
        r.profiles.at[1],
        if r.profiles.implied {
            "implied"
        } else {
            "the air's"
        },
        PERCENTILES
    );
    s
}
