//! Comma-separated soundings (read with the `csv` crate): a header row
//! naming the columns, case and surrounding spaces aside: `height` (m) and
//! `temperature` (°C) required, `pressure` (hPa), `humidity` (relative, %)
//! and `dewpoint` (°C) optional, any other column ignored. An empty cell is
//! missing; a line starting with `#` is a comment.

use super::row::{Row, at, number};
use crate::error::FieldError;

/// The rows of `text`.
pub(super) fn read(text: &str) -> Result<Vec<Row>, FieldError> {
    let mut reader = ::csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .flexible(true)
        .trim(::csv::Trim::All)
        .from_reader(text.as_bytes());
    let header = reader
        .headers()
        .map_err(|e| FieldError::new("line 1", format!("cannot read the header row: {e}")))?
        .clone();
    // The header row's line: the first that is neither blank nor a comment.
    let header_line = text
        .lines()
        .position(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .map_or(1, |i| i + 1);
    let find = |name: &str| header.iter().position(|h| h.eq_ignore_ascii_case(name));
    let (Some(height), Some(temperature)) = (find("height"), find("temperature")) else {
        return Err(at(
            header_line,
            "header",
            "the header row must name `height` (m) and `temperature` (°C)",
        ));
    };
    let (pressure, humidity, dewpoint) = (find("pressure"), find("humidity"), find("dewpoint"));
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| {
            let line = e.position().map_or(0, |p| p.line() as usize);
            at(line, "row", format!("cannot read the row: {e}"))
        })?;
        let n = record.position().map_or(0, |p| p.line() as usize);
        let cell = |i: Option<usize>, name: &str| -> Result<Option<f64>, FieldError> {
            let Some(text) = i.and_then(|i| record.get(i)) else {
                return Ok(None);
            };
            number(text, n, name)
        };
        rows.push(Row {
            line: n,
            height: cell(Some(height), "height")?,
            celsius: cell(Some(temperature), "temperature")?,
            pressure: cell(pressure, "pressure")?.map(|p| p * 100.0),
            humidity: cell(humidity, "humidity")?.map(|h| h / 100.0),
            dewpoint: cell(dewpoint, "dewpoint")?,
        });
    }
    Ok(rows)
}
