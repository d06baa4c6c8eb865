//! Measured air from a radiosonde or a mast (`docs/sounding.md`): a sounding
//! file read into rows of height, temperature, pressure and humidity, and
//! turned into a real-air medium (`docs/air.md`) with a temperature table,
//! the pressure at the ground and a humidity table.
//!
//! Formats, one file each:
//!
//! - [`Format::Igra2`] (`igra2.rs`): the IGRA version 2 station data format
//!   (NOAA NCEI's `igra2-data-format.txt`): a header line starting with `#`,
//!   then fixed-width level records; the columns read are PRESS (10–15, Pa),
//!   GPH (17–21, m), TEMP (23–27, tenths of °C), RH (29–33, tenths of a per
//!   cent) and DPDP (35–39, dew-point depression, tenths of °C); −8888 and
//!   −9999 are missing. Only the first sounding of a file is read.
//! - [`Format::Wyoming`] (`wyoming.rs`): the University of Wyoming sounding
//!   page's TEXT:LIST table, the fixed-width table between dashed lines
//!   under the header `PRES HGHT TEMP DWPT RELH …` (hPa, m, °C, °C, %); a
//!   blank cell is missing.
//! - [`Format::Csv`] (`csv.rs`): a header row naming `height` (m) and
//!   `temperature` (°C), and optionally `pressure` (hPa) and `humidity` (%)
//!   or `dewpoint` (°C); other columns are ignored, an empty cell is missing,
//!   `#` starts a comment line.
//!
//! The rules, the same for every format:
//!
//! - a row without a height is skipped, and so is its temperature, or its
//!   humidity, where either is missing; a row's humidity is its relative
//!   humidity where given, else the one its dew point gives,
//!   RH = p_sv(T_d)/p_sv(T) with the crate's saturation vapour pressure
//!   ([`crate::medium::air::humidity::saturation_vapour_pressure`]), so
//!   that the medium's water-vapour pressure is the measured one;
//! - the heights of the rows used (a height with a temperature or a
//!   humidity) must be strictly increasing, temperatures
//!   inside [−150, 300] °C, relative humidities inside [0, 100] %, dew
//!   points not above the temperature, pressures inside (0, 10⁷] Pa, and
//!   every value a finite number: anything else is an error naming the line
//!   and the column;
//! - at least two rows with a height and a temperature are needed;
//! - heights in the medium are above the lowest usable row, or above the
//!   site height (`--site-height`, in the file's datum) when that is higher;
//!   the pressure at h = 0 is the measured one there, or that of the nearest
//!   row with a temperature and a pressure, carried hydrostatically to h = 0
//!   at that row's temperature, or 101 325 Pa when no row has both;
//! - the humidity is a table of the rows that have one, one number when only
//!   one row has one, and absent (dry air) when none has.

mod csv;
mod igra2;
mod row;
mod wyoming;

pub use row::Row;
use row::at;

use crate::error::FieldError;
use crate::medium::air::hydrostatic::{G, M, R};
use crate::medium::air::{
    Air, AirMedium, COLDEST, DEFAULT_CO2, DEFAULT_PRESSURE, DEFAULT_WAVELENGTH, Formula, HOTTEST,
    Humidity, Temperature,
};

/// The highest pressure accepted (Pa), as real air's (100 atmospheres).
const MAX_PRESSURE: f64 = 1.0e7;

/// A sounding file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// IGRA version 2 station data.
    Igra2,
    /// The University of Wyoming's TEXT:LIST table.
    Wyoming,
    /// Comma-separated values with a header row.
    Csv,
}

impl Format {
    /// The format's name, as `--format` takes it.
    pub fn name(self) -> &'static str {
        match self {
            Format::Igra2 => "igra2",
            Format::Wyoming => "wyoming",
            Format::Csv => "csv",
        }
    }

    /// The format of a file: `.csv` by its extension, else by its content
    /// (an IGRA 2 header line `#` + station id + date, a Wyoming header
    /// line with `PRES` and `HGHT`, a first line naming `height` and
    /// `temperature` between commas); `None` when none matches.
    pub fn infer(extension: Option<&str>, text: &str) -> Option<Format> {
        if extension.is_some_and(|e| e.eq_ignore_ascii_case("csv")) {
            return Some(Format::Csv);
        }
        let first = text.lines().find(|l| !l.trim().is_empty())?;
        if igra2::is_header(first) {
            return Some(Format::Igra2);
        }
        if text.lines().any(wyoming::is_header) {
            return Some(Format::Wyoming);
        }
        let lower = first.to_ascii_lowercase();
        let names: Vec<&str> = lower.split(',').map(str::trim).collect();
        if names.contains(&"height") && names.contains(&"temperature") {
            return Some(Format::Csv);
        }
        None
    }
}

/// The column names a format uses for each quantity, for messages.
#[derive(Clone, Copy, Debug)]
struct Columns {
    height: &'static str,
    celsius: &'static str,
    pressure: &'static str,
    humidity: &'static str,
    dewpoint: &'static str,
}

impl Format {
    fn columns(self) -> Columns {
        match self {
            Format::Igra2 => Columns {
                height: "GPH",
                celsius: "TEMP",
                pressure: "PRESS",
                humidity: "RH",
                dewpoint: "DPDP",
            },
            Format::Wyoming => Columns {
                height: "HGHT",
                celsius: "TEMP",
                pressure: "PRES",
                humidity: "RELH",
                dewpoint: "DWPT",
            },
            Format::Csv => Columns {
                height: "height",
                celsius: "temperature",
                pressure: "pressure",
                humidity: "humidity",
                dewpoint: "dewpoint",
            },
        }
    }
}

/// A sounding read from a file: its format and its rows, in file order.
#[derive(Clone, Debug, PartialEq)]
pub struct Sounding {
    /// The format it was read as.
    pub format: Format,
    /// The rows, missing values as `None`.
    pub rows: Vec<Row>,
    /// What the reader chose and the user may want to know (stderr).
    pub notes: Vec<String>,
}

/// Reads `text` as `format`: its rows, each value checked; the first
/// violation names its line and column.
pub fn read(text: &str, format: Format) -> Result<Sounding, FieldError> {
    let mut notes = Vec::new();
    let rows = match format {
        Format::Igra2 => igra2::read(text, &mut notes)?,
        Format::Wyoming => wyoming::read(text)?,
        Format::Csv => csv::read(text)?,
    };
    let c = format.columns();
    for r in &rows {
        let finite = [
            (r.height, c.height),
            (r.celsius, c.celsius),
            (r.pressure, c.pressure),
            (r.humidity, c.humidity),
            (r.dewpoint, c.dewpoint),
        ];
        for (v, name) in finite {
            if let Some(v) = v
                && !v.is_finite()
            {
                return Err(at(r.line, name, format!("not a finite number: {v}")));
            }
        }
        if let Some(t) = r.celsius
            && !(COLDEST..=HOTTEST).contains(&t)
        {
            return Err(at(
                r.line,
                c.celsius,
                format!("{t} °C is outside air's range [{COLDEST}, {HOTTEST}] °C"),
            ));
        }
        if let Some(p) = r.pressure
            && !(p > 0.0 && p <= MAX_PRESSURE)
        {
            return Err(at(
                r.line,
                c.pressure,
                format!("{p} Pa is outside air's range (0, {MAX_PRESSURE}] Pa"),
            ));
        }
        if let Some(h) = r.humidity
            && !(0.0..=1.0).contains(&h)
        {
            return Err(at(
                r.line,
                c.humidity,
                format!(
                    "a relative humidity must lie in [0, 100] %, got {} %",
                    h * 100.0
                ),
            ));
        }
        if let (Some(td), Some(t)) = (r.dewpoint, r.celsius)
            && td > t
        {
            return Err(at(
                r.line,
                c.dewpoint,
                format!("the dew point {td} °C is above the temperature {t} °C"),
            ));
        }
    }
    let mut last: Option<(f64, usize)> = None;
    for r in rows.iter().filter(|r| r.is_used()) {
        let Some(h) = r.height else { continue };
        if let Some((prev, line)) = last
            && h <= prev
        {
            return Err(at(
                r.line,
                c.height,
                format!(
                    "the heights must be strictly increasing: {h} m after {prev} m (line {line})"
                ),
            ));
        }
        last = Some((h, r.line));
    }
    let usable = rows
        .iter()
        .filter(|r| r.height.is_some() && r.celsius.is_some())
        .count();
    if usable < 2 {
        return Err(FieldError::new(
            c.celsius,
            format!(
                "a sounding needs at least two rows with both {} and {}, this one has {usable}",
                c.height, c.celsius
            ),
        ));
    }
    Ok(Sounding {
        format,
        rows,
        notes,
    })
}

impl Sounding {
    /// The real-air medium of this sounding, heights above the lowest
    /// usable row or above `site_height` (the file's datum) when higher.
    pub fn medium(&self, site_height: Option<f64>) -> (AirMedium, Vec<String>) {
        let mut notes = self.notes.clone();
        let temps: Vec<(&Row, f64, f64)> = self
            .rows
            .iter()
            .filter_map(|r| Some((r, r.height?, r.celsius?)))
            .collect();
        let lowest = temps[0].1;
        let base = match site_height {
            Some(s) if s > lowest => s,
            Some(s) => {
                if s < lowest {
                    notes.push(format!(
                        "--site-height {s} m is below the lowest level ({lowest} m): heights are above the lowest level"
                    ));
                }
                lowest
            }
            None => lowest,
        };
        let table: Vec<[f64; 2]> = temps.iter().map(|&(_, h, t)| [h - base, t]).collect();
        let wet: Vec<[f64; 2]> = self
            .rows
            .iter()
            .filter_map(|r| Some([r.height? - base, r.relative_humidity()?]))
            .collect();
        let humidity = match wet.len() {
            0 => {
                notes.push("no humidity in the file: dry air".to_string());
                Humidity::Constant(0.0)
            }
            1 => Humidity::Constant(wet[0][1]),
            _ => Humidity::Table(wet),
        };
        let pressure = self.ground_pressure(base, &mut notes);
        let medium = AirMedium {
            air: Air {
                temperature: Temperature {
                    base: None,
                    lapse: None,
                    exponential: None,
                    inversion: None,
                    table: Some(table),
                },
                pressure,
                hydrostatic: true,
                humidity,
                wavelength: DEFAULT_WAVELENGTH,
                co2: DEFAULT_CO2,
                refractivity: Formula::Ciddor,
            },
            hotspots: Vec::new(),
        };
        (medium, notes)
    }

    /// The pressure (Pa) at `base`: that of the row with a temperature and
    /// a pressure nearest to it, carried hydrostatically at the row's
    /// temperature.
    fn ground_pressure(&self, base: f64, notes: &mut Vec<String>) -> f64 {
        let nearest = self
            .rows
            .iter()
            .filter(|r| r.celsius.is_some())
            .filter_map(|r| Some((r, r.height?, r.pressure?)))
            .min_by(|a, b| (a.1 - base).abs().total_cmp(&(b.1 - base).abs()));
        let Some((row, h, p)) = nearest else {
            notes.push(format!(
                "no pressure in the file: {DEFAULT_PRESSURE} Pa at the ground"
            ));
            return DEFAULT_PRESSURE;
        };
        if h == base {
            return p;
        }
        let kelvin = row.celsius.unwrap_or(15.0) + crate::medium::air::KELVIN;
        p * (-(G * M / R) * (base - h) / kelvin).exp()
    }
}
