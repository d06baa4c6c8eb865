//! `mirage sounding`: a radiosonde or mast profile (IGRA 2, the University
//! of Wyoming's TEXT:LIST, or CSV) read into a real-air medium, written as
//! JSON that a problem or scene takes as its `medium` (`docs/sounding.md`;
//! the reader and its rules: [`crate::io::sounding`]). Bad input is an
//! error naming the file, the line and the column (exit code 2), found
//! before anything is written; the output is written atomically.

use crate::error::{FieldError, Result, ValueError};
use crate::io::json::read_input;
use crate::io::sounding::{self, Format};
use crate::io::{Output, OutputKind, check_outputs, write_json};
use crate::medium::air::AirMedium;
use std::path::{Path, PathBuf};

/// Read a radiosonde or mast profile and write it as a real-air medium.
#[derive(Clone, Debug, PartialEq, clap::Args)]
pub struct SoundingOptions {
    /// The sounding file.
    pub file: PathBuf,
    /// Its format (default: `csv` for a `.csv` file, else told by the
    /// content: an IGRA 2 header line, a Wyoming `PRES HGHT` header).
    #[arg(long, value_enum)]
    pub format: Option<FormatName>,
    /// The observer's height in the file's datum, m: heights are measured
    /// from it when it is above the lowest level (default: the lowest level).
    #[arg(long, allow_negative_numbers = true, value_parser = site_height)]
    pub site_height: Option<f64>,
    /// Write the medium (JSON) here.
    #[arg(short, long)]
    pub output: PathBuf,
}

/// The formats by their command-line names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum FormatName {
    /// IGRA version 2 station data (NOAA NCEI).
    Igra2,
    /// The University of Wyoming sounding page's TEXT:LIST table.
    Wyoming,
    /// Comma-separated values with a header row (height, temperature, …).
    Csv,
}

impl FormatName {
    /// The reader's format.
    pub fn format(self) -> Format {
        match self {
            FormatName::Igra2 => Format::Igra2,
            FormatName::Wyoming => Format::Wyoming,
            FormatName::Csv => Format::Csv,
        }
    }
}

/// `--site-height`: a finite number of metres.
fn site_height(s: &str) -> std::result::Result<f64, ValueError> {
    match s.trim().parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(ValueError::NotANumber {
            value: s.to_string(),
        }),
    }
}

/// Reads `file` (its format given or inferred) into a validated medium,
/// with the notes the reader made.
pub fn medium_of(
    file: &Path,
    format: Option<Format>,
    site_height: Option<f64>,
) -> Result<(AirMedium, Format, Vec<String>)> {
    let text = read_input(file)?;
    let extension = file.extension().and_then(|e| e.to_str());
    let format = match format {
        Some(f) => f,
        None => Format::infer(extension, &text).ok_or_else(|| {
            FieldError::whole(
                "cannot tell the sounding's format (no IGRA 2 header, no Wyoming `PRES HGHT` header, no CSV header naming height and temperature): give --format igra2, wyoming or csv",
            )
            .in_file(file)
        })?,
    };
    let s = sounding::read(&text, format).map_err(|e| e.in_file(file))?;
    let (medium, notes) = s.medium(site_height);
    medium
        .validate()
        .map_err(|e| e.within("medium").in_file(file))?;
    Ok((medium, format, notes))
}

/// Reads the sounding, prints what was chosen, writes the medium.
pub fn run(o: &SoundingOptions) -> Result<AirMedium> {
    let (medium, format, notes) =
        medium_of(&o.file, o.format.map(FormatName::format), o.site_height)?;
    check_outputs(
        [Output::new("-o", &o.output, OutputKind::Any)],
        &[o.file.as_path()],
    )?;
    for n in &notes {
        eprintln!("note: {n}");
    }
    write_json(&o.output, &medium)?;
    let rows = medium.air.temperature.table.as_ref().map_or(0, Vec::len);
    let humidity_rows = medium.air.humidity.table().map_or(0, <[_]>::len);
    println!(
        "{}: {} sounding, {rows} temperature rows, {humidity_rows} humidity rows, {:.0} Pa at the ground -> {}",
        o.file.display(),
        format.name(),
        medium.air.pressure,
        o.output.display()
    );
    Ok(medium)
}
