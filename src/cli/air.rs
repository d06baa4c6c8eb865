//! `mirage air`: a medium's temperature, pressure, n − 1 and dn/dh from the
//! ground up, at one horizontal position (`docs/air.md`, "`mirage air`"); for
//! a medium that is not real air, the air that would make the same mirage
//! ([`crate::profile`]). The input is a problem (it has `pairs`) or a scene (it
//! has `camera`; its `medium_from` is followed); outputs are written
//! atomically, and only after every flag and the input were accepted.

use crate::error::{Error, Result, ValueError};
use crate::io::json::{parse_json, read_input};
use crate::io::{Output, OutputKind, check_outputs, write_atomic, write_json};
use crate::medium::Medium;
use crate::problem::Problem;
use crate::profile::{AirProfile, air_profile};
use crate::scene::Scene;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Write and draw a medium's T, P, n − 1 and dn/dh against height.
#[derive(Clone, Debug, Default, PartialEq, clap::Args)]
pub struct AirOptions {
    /// Problem or scene file (JSON).
    pub file: PathBuf,
    /// Write the rows as JSON here.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Write the rows as CSV here.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Draw the four panels here (.png or .svg).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Horizontal position `X,Z` in metres (default: the first hot spot's
    /// centre, else 0,0).
    #[arg(long, allow_hyphen_values = true, value_parser = position)]
    pub at: Option<[f64; 2]>,
    /// Top of the profile, m > 0 (default: 3× the highest feature's reach,
    /// at least 20 m).
    #[arg(long, allow_negative_numbers = true, value_parser = top)]
    pub top: Option<f64>,
}

/// `--at`: two finite numbers `X,Z`.
fn position(s: &str) -> std::result::Result<[f64; 2], ValueError> {
    let parts: Vec<&str> = s.split(',').collect();
    let [x, z] = parts.as_slice() else {
        return Err(ValueError::OutOfRange {
            rule: format!("must be two numbers X,Z (metres), got `{s}`"),
        });
    };
    let num = |t: &str| -> std::result::Result<f64, ValueError> {
        match t.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(ValueError::NotANumber {
                value: t.to_string(),
            }),
        }
    };
    Ok([num(x)?, num(z)?])
}

/// `--top`: a finite height > 0 (m).
fn top(s: &str) -> std::result::Result<f64, ValueError> {
    let v: f64 = s.trim().parse().map_err(|_| ValueError::NotANumber {
        value: s.to_string(),
    })?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(ValueError::OutOfRange {
            rule: format!("must be a height > 0 m, got {v}"),
        })
    }
}

/// Reads the medium of a problem or a scene file, its name, and the files it
/// read (so that no output overwrites them).
pub fn load_medium(path: &Path) -> Result<(String, Medium, Vec<PathBuf>)> {
    let text = read_input(path)?;
    let value: serde_json::Value = parse_json(&text, path, "problem or scene")?;
    let mut inputs = vec![path.to_path_buf()];
    if value.get("camera").is_some() {
        let scene = Scene::parse(&text, path)?;
        inputs.extend(scene.inputs.iter().cloned());
        Ok((scene.name, scene.medium, inputs))
    } else if value.get("pairs").is_some() {
        let p = Problem::parse(&text, path)?;
        Ok((p.name, p.medium, inputs))
    } else {
        Err(Error::input(
            path,
            "-",
            "neither a scene (no `camera`) nor a problem (no `pairs`)",
        ))
    }
}

/// Computes the profile, prints its summary and warnings, writes the outputs.
pub fn run(o: &AirOptions) -> Result<AirProfile> {
    let (name, medium, inputs) = load_medium(&o.file)?;
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
    let profile = air_profile(&medium, o.at, o.top);
    for w in &profile.warnings {
        eprintln!("warning: {}", w.message);
    }
    if let Some(out) = &o.output {
        write_json(out, &profile)?;
    }
    if let Some(out) = &o.csv {
        write_atomic(out, csv(&profile).as_bytes())?;
    }
    if let Some(out) = &o.plot {
        crate::plot::draw_air(&name, &profile, out)?;
    }
    print!("{}", summary(&name, &profile));
    Ok(profile)
}

/// The rows as CSV (a header line, then one line per row).
pub fn csv(p: &AirProfile) -> String {
    let mut s = String::from("h,temperature_c,excess_k,pressure_pa,delta,dn_dh\n");
    for r in &p.rows {
        let excess = r.excess_k.map(|e| format!("{e:.9e}")).unwrap_or_default();
        let _ = writeln!(
            s,
            "{},{:.9e},{},{:.9e},{:.12e},{:.9e}",
            r.h, r.temperature_c, excess, r.pressure_pa, r.delta, r.dn_dh
        );
    }
    s
}

/// A few lines for the terminal: the ground row and the top row.
fn summary(name: &str, p: &AirProfile) -> String {
    let mut s = format!(
        "{name}: {} medium at x = {}, z = {} m, {} rows from 0 to {} m{}\n",
        p.medium_kind,
        p.at[0],
        p.at[1],
        p.rows.len(),
        p.top,
        if p.implied {
            " (implied air: the standard atmosphere carrying this δ(h))"
        } else {
            ""
        }
    );
    for r in [p.rows.first(), p.rows.last()].into_iter().flatten() {
        let _ = write!(s, "  h = {:>10.4} m   T = {:>9.4} °C", r.h, r.temperature_c);
        if let Some(e) = r.excess_k {
            let _ = write!(s, " (excess {e:+.4} K)");
        }
        let _ = writeln!(
            s,
            "   P = {:.2} Pa   n − 1 = {:.6e}   dn/dh = {:.4e} /m",
            r.pressure_pa, r.delta, r.dn_dh
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_parse_and_refuse() {
        assert_eq!(position("-3.5, 160"), Ok([-3.5, 160.0]));
        assert!(position("1").is_err() && position("1,2,3").is_err());
        assert!(position("1,nan").is_err());
        assert_eq!(top("20"), Ok(20.0));
        assert!(top("-1").is_err() && top("0").is_err() && top("inf").is_err());
    }
}
