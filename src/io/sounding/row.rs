//! One level of a sounding as the readers give it, and the humidity it
//! carries.

use crate::error::FieldError;
use crate::medium::air::humidity::saturation_vapour_pressure;

/// One level as the file gives it, in the file's units turned into the
/// crate's: m, °C, Pa, relative humidity as a fraction; `None` where missing.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Row {
    /// The line of the file (1-based).
    pub line: usize,
    /// Height (m, the file's datum).
    pub height: Option<f64>,
    /// Temperature (°C).
    pub celsius: Option<f64>,
    /// Pressure (Pa).
    pub pressure: Option<f64>,
    /// Relative humidity (0…1).
    pub humidity: Option<f64>,
    /// Dew point (°C).
    pub dewpoint: Option<f64>,
}

/// An error at `line` in `column`.
/// A cell's number: `None` when the cell is empty, else the number or an
/// error at `line` naming `column`.
pub(super) fn number(text: &str, line: usize, column: &str) -> Result<Option<f64>, FieldError> {
    if text.is_empty() {
        return Ok(None);
    }
    text.parse::<f64>()
        .map(Some)
        .map_err(|_| at(line, column, format!("`{text}` is not a number")))
}

pub(super) fn at(line: usize, column: &str, message: impl Into<String>) -> FieldError {
    FieldError::new(format!("line {line}, {column}"), message)
}

impl Row {
    /// Whether the medium uses this row: it has a height, and a temperature
    /// or a humidity (a row of a height alone, as the levels below the
    /// ground on a Wyoming page, is skipped).
    pub fn is_used(&self) -> bool {
        self.height.is_some() && (self.celsius.is_some() || self.humidity.is_some())
    }

    /// The relative humidity (0…1): the given one, else the dew point's.
    pub fn relative_humidity(&self) -> Option<f64> {
        self.humidity.or_else(|| {
            let (td, t) = (self.dewpoint?, self.celsius?);
            Some((saturation_vapour_pressure(td) / saturation_vapour_pressure(t)).min(1.0))
        })
    }
}
