//! `mirage refraction`: the astronomical refraction against apparent
//! elevation for an observer over the round earth, the dip of the apparent
//! horizon and the terrestrial refraction coefficient k
//! (`docs/air.md`, "`mirage refraction`"; the work is [`crate::refraction`]).
//!
//! The input is a problem or a scene whose medium is real air; the earth is
//! `--earth-radius` if given, else the file's `earth`, else 6 371 000 m.
//! Every flag and the file are checked before any ray is traced, and the
//! outputs are written atomically after the work: bad input exits 2 and
//! leaves no file.

use super::air::load_medium;
use crate::error::{Error, FieldError, Result, ValueError};
use crate::io::json::{parse_json, read_input};
use crate::io::{Output, OutputKind, check_outputs, write_atomic, write_json};
use crate::medium::Medium;
use crate::refraction::{Refraction, air_refraction};
use crate::trace::EarthSpec;
use crate::trace::earth::{EARTH_RADIUS, MIN_RADIUS};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The elevations when `--elevations` is not given (degrees).
pub const DEFAULT_ELEVATIONS: [f64; 9] = [0.0, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 45.0, 90.0];

/// Tabulate the refraction near the horizon, the dip and k through real air.
#[derive(Clone, Debug, Default, PartialEq, clap::Args)]
pub struct RefractionOptions {
    /// Problem or scene file whose medium is real air (JSON).
    pub file: PathBuf,
    /// The observer's height above the ground (m, ≥ 0, below the top of the air).
    #[arg(long, allow_negative_numbers = true, value_parser = height)]
    pub height: f64,
    /// Apparent elevations, degrees in −90…90, comma-separated (default
    /// 0,0.5,1,2,5,10,20,45,90).
    #[arg(long, allow_hyphen_values = true, value_parser = elevations)]
    pub elevations: Option<Elevations>,
    /// The earth's radius (m, ≥ 1000; default: the file's `earth`, else 6371000).
    #[arg(long, allow_negative_numbers = true, value_parser = radius)]
    pub earth_radius: Option<f64>,
    /// Write the report as JSON here.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Write the rows as CSV here.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Draw the refraction against elevation, with Bennett's curve and the dip, here (.png or .svg).
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

/// The value of `--elevations`: degrees, in the order given.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Elevations(pub Vec<f64>);

/// `--height`: a finite height ≥ 0 (m).
fn height(s: &str) -> std::result::Result<f64, ValueError> {
    let v = number(s)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        Err(ValueError::OutOfRange {
            rule: format!("must be a height ≥ 0 m above the ground, got {v}"),
        })
    }
}

/// `--earth-radius`: at least [`MIN_RADIUS`] metres.
fn radius(s: &str) -> std::result::Result<f64, ValueError> {
    let v = number(s)?;
    if v >= MIN_RADIUS {
        Ok(v)
    } else {
        Err(ValueError::OutOfRange {
            rule: format!("must be at least {MIN_RADIUS} m (the earth's is 6371000), got {v}"),
        })
    }
}

/// `--elevations`: one or more degrees in −90…90, comma-separated.
fn elevations(s: &str) -> std::result::Result<Elevations, ValueError> {
    let mut out = Vec::new();
    for part in s.split(',') {
        let v = number(part)?;
        if !(-90.0..=90.0).contains(&v) {
            return Err(ValueError::OutOfRange {
                rule: format!("each elevation must be within −90…90 degrees, got {v}"),
            });
        }
        out.push(v);
    }
    Ok(Elevations(out))
}

/// A finite number.
fn number(s: &str) -> std::result::Result<f64, ValueError> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(ValueError::NotANumber {
            value: s.to_string(),
        }),
    }
}

/// The file's `earth` (validated), if it has one.
fn file_earth(path: &Path) -> Result<Option<EarthSpec>> {
    let text = read_input(path)?;
    let value: serde_json::Value = parse_json(&text, path, "problem or scene")?;
    let Some(earth) = value.get("earth") else {
        return Ok(None);
    };
    let spec: EarthSpec = serde_json::from_value(earth.clone())
        .map_err(|e| Error::input(path, "earth", format!("must be {{\"radius\": R}}: {e}")))?;
    spec.validate()
        .map_err(|e| e.within("earth").in_file(path))?;
    Ok(Some(spec))
}

/// Runs the command: checks, traces, writes, prints the table.
pub fn run(o: &RefractionOptions) -> Result<Refraction> {
    let (name, medium, inputs) = load_medium(&o.file)?;
    let Medium::Air(air) = &medium else {
        return Err(Error::input(
            &o.file,
            "medium",
            "`mirage refraction` needs real air (a medium with `air`, docs/air.md), not the logistic model",
        ));
    };
    let radius = match (o.earth_radius, file_earth(&o.file)?) {
        (Some(r), _) => r,
        (None, Some(spec)) => spec.radius,
        (None, None) => EARTH_RADIUS,
    };
    let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    check_outputs(
        [
            Output::optional("-o", o.output.as_ref(), OutputKind::Any),
            Output::optional("--csv", o.csv.as_ref(), OutputKind::Any),
            Output::optional("--plot", o.plot.as_ref(), OutputKind::Plot),
        ]
        .into_iter()
        .flatten(),
        &inputs,
    )?;
    let elevations = o
        .elevations
        .as_ref()
        .map_or(DEFAULT_ELEVATIONS.to_vec(), |e| e.0.clone());
    let report = air_refraction(air, o.height, radius, &elevations)
        .map_err(|e| flag_error(e, o.earth_radius.is_some(), &o.file))?;
    if let Some(out) = &o.output {
        write_json(out, &report)?;
    }
    if let Some(out) = &o.csv {
        write_atomic(out, csv(&report).as_bytes())?;
    }
    if let Some(out) = &o.plot {
        crate::plot::draw_refraction(&name, &report, out)?;
    }
    print!("{}", table(&name, &report));
    Ok(report)
}

/// The library's refusal as the flag (or the file's field) that caused it.
fn flag_error(e: FieldError, radius_flag: bool, file: &Path) -> Error {
    match e.path.as_str() {
        "height" => Error::usage("--height", e.message),
        "radius" if radius_flag => Error::usage("--earth-radius", e.message),
        "radius" => e.within("earth").in_file(file),
        p if p.starts_with("elevations") => Error::usage("--elevations", e.message),
        _ => e.within("medium").in_file(file),
    }
}

/// The rows as CSV: a header line, then one line per elevation (empty cells
/// where a value is absent).
pub fn csv(r: &Refraction) -> String {
    let mut s = String::from(
        "elevation_deg,refraction_arcmin,true_elevation_deg,hits_ground,trapped,bennett_arcmin\n",
    );
    let cell = |v: Option<f64>| v.map(|v| format!("{v:.9e}")).unwrap_or_default();
    for row in &r.rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{}",
            row.elevation_deg,
            cell(row.refraction_arcmin),
            cell(row.true_elevation_deg),
            row.hits_ground,
            row.trapped,
            cell(row.bennett_arcmin)
        );
    }
    s
}

/// The table for the terminal.
pub fn table(name: &str, r: &Refraction) -> String {
    let mut s = format!(
        "{name}: observer {} m above a sphere of radius {} m, air to {} m",
        r.height, r.earth_radius, r.top
    );
    if let (Some(p), Some(t)) = (r.pressure_pa, r.temperature_c) {
        let _ = write!(s, " (at the observer {p:.1} Pa, {t:.2} °C)");
    }
    s.push('\n');
    let _ = writeln!(
        s,
        "  elevation (°)  refraction (′)  true elevation (°)  Bennett (′)"
    );
    for row in &r.rows {
        let _ = write!(s, "  {:>13.4}", row.elevation_deg);
        match (row.refraction_arcmin, row.true_elevation_deg) {
            (Some(a), Some(t)) => {
                let _ = write!(s, "  {a:>14.4}  {t:>18.6}");
            }
            _ if row.hits_ground => s.push_str("  hits the ground"),
            _ => s.push_str("  trapped (neither leaves the air nor meets the ground)"),
        }
        if let Some(b) = row.bennett_arcmin {
            let _ = write!(s, "  {b:>11.4}");
        }
        s.push('\n');
    }
    let surveyors = 1.76 * r.height.sqrt();
    match r.dip_arcmin {
        Some(d) => {
            let _ = writeln!(
                s,
                "dip of the horizon: {d:.4}′ (geometric acos(R/(R+H)) {:.4}′, surveyors' 1.76′·√H {surveyors:.4}′)",
                r.geometric_dip_arcmin
            );
        }
        None => {
            let _ = writeln!(
                s,
                "dip of the horizon: none (no ray up to 0.1 rad clears the ground)"
            );
        }
    }
    let _ = writeln!(
        s,
        "k = {:.5} (a horizontal ray's curvature × R; traced over 1 km: {:.5})",
        r.k, r.k_traced
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_parse_and_refuse() {
        assert_eq!(height("2"), Ok(2.0));
        assert!(height("-1").is_err() && height("nan").is_err() && height("x").is_err());
        assert_eq!(radius("6371000"), Ok(6_371_000.0));
        assert!(radius("999").is_err() && radius("inf").is_err());
        assert_eq!(
            elevations("-0.5, 0,10"),
            Ok(Elevations(vec![-0.5, 0.0, 10.0]))
        );
        assert!(elevations("91").is_err() && elevations("1,,2").is_err());
        assert!(elevations("-90.5").is_err());
    }
}
