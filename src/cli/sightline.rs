//! The lines-of-sight table that `mirage trace` and `mirage fit` print over
//! the round earth (`crate::sightline`), and the units of F.

use crate::evaluate::PairReport;
use crate::geo::format_dms;
use crate::problem::{Problem, Residual};
use std::fmt::Write as _;

/// F's unit and what a residual is, for the summaries.
pub(crate) fn objective_unit(problem: &Problem) -> &'static str {
    if problem.photo.is_some() {
        return "px² (photo marks: ½ Σ residual²)";
    }
    match problem.residual {
        Residual::Distance => "m²",
        Residual::Angle => "rad² (angle residuals: miss / range)",
    }
}

/// What `summed distance` and `largest` sum, for the summaries: metres,
/// or with angle residuals the weighted misses in radians.
pub(crate) fn summed_unit(problem: &Problem) -> &'static str {
    if problem.photo.is_some() {
        return "px (Σ over target marks)";
    }
    match problem.residual {
        Residual::Distance => "m",
        Residual::Angle => "rad (Σ miss/range)",
    }
}

/// The table of every pair's line of sight, or nothing over the flat
/// ground.
pub(crate) fn sightline_table(pairs: &[PairReport]) -> String {
    let mut s = String::new();
    if pairs.iter().all(|p| p.sightline.is_none()) {
        return s;
    }
    let _ = writeln!(
        s,
        "line of sight: apparent and geometric elevation, refraction ρ (apparent − geometric) and k = 2Rρ/s of the sighting; the air's own ρ and k (a ray that meets the target) and the miss seen from the origin"
    );
    let _ = writeln!(
        s,
        "{:>5} {:>10} {:>14} {:>14} {:>10} {:>7} {:>10} {:>7} {:>9} {:>14} {:>11}",
        "pair",
        "arc (m)",
        "apparent",
        "geometric",
        "ρ (″)",
        "k",
        "air ρ (″)",
        "air k",
        "miss (″)",
        "horizon",
        "clear (m)"
    );
    for (i, p) in pairs.iter().enumerate() {
        let Some(l) = &p.sightline else {
            continue;
        };
        let opt = |v: Option<f64>, prec: usize| match v {
            Some(v) => format!("{v:.prec$}"),
            None => "–".into(),
        };
        let _ = writeln!(
            s,
            "{:>5} {:>10.1} {:>14} {:>14} {:>10.2} {:>7.3} {:>10} {:>7} {:>9} {:>14} {:>11.2}",
            i,
            l.arc_distance,
            format_dms(l.apparent_elevation),
            format_dms(l.geometric_elevation),
            l.refraction_arcsec,
            l.k,
            opt(l.air_refraction_arcsec, 2),
            opt(l.air_k, 3),
            opt(l.miss_up_arcsec, 2),
            if l.below_horizon {
                "below horizon"
            } else {
                "above horizon"
            },
            l.clearance
        );
    }
    s
}
