//! IGRA version 2 station data (NOAA NCEI, `igra2-data-format.txt`): each
//! sounding is a header record (`#` in column 1, the station id in columns
//! 2–12, year 14–17, month 19–20, day 22–23, hour 25–26, …, the number of
//! levels in 33–36) followed by one fixed-width record per level:
//!
//! | columns | field | unit |
//! | --- | --- | --- |
//! | 1, 2 | LVLTYP1, LVLTYP2 | level types |
//! | 4–8 | ETIME | elapsed time (not read) |
//! | 10–15 | PRESS | Pa |
//! | 16 | PFLAG | (not read) |
//! | 17–21 | GPH | geopotential height, m |
//! | 22 | ZFLAG | (not read) |
//! | 23–27 | TEMP | tenths of °C |
//! | 28 | TFLAG | (not read) |
//! | 29–33 | RH | tenths of a per cent |
//! | 35–39 | DPDP | dew-point depression, tenths of °C |
//! | 41–45, 47–51 | WDIR, WSPD | wind (not read) |
//!
//! −8888 (removed by quality control) and −9999 (missing) are missing
//! values. Only the first sounding of a file is read; the levels run from
//! its header to the next header or the end.

use super::row::{Row, at};
use crate::error::FieldError;

/// Whether `line` is an IGRA 2 header record: `#`, then a year in columns
/// 14–17.
pub(super) fn is_header(line: &str) -> bool {
    line.starts_with('#')
        && line
            .get(13..17)
            .is_some_and(|y| y.bytes().all(|b| b.is_ascii_digit()))
}

/// An integer field in 1-based columns `first..=last`, `None` when missing
/// (−8888, −9999).
fn field(
    line: &str,
    n: usize,
    first: usize,
    last: usize,
    name: &str,
) -> Result<Option<i64>, FieldError> {
    let text = line.get(first - 1..last).ok_or_else(|| {
        at(
            n,
            name,
            format!(
                "a level record holds {name} in columns {first}–{last}; this line has {} characters or is not plain ASCII",
                line.chars().count()
            ),
        )
    })?;
    let v: i64 = text.trim().parse().map_err(|_| {
        at(
            n,
            name,
            format!(
                "`{}` (columns {first}–{last}) is not an integer",
                text.trim()
            ),
        )
    })?;
    Ok(if v == -8888 || v == -9999 {
        None
    } else {
        Some(v)
    })
}

/// The rows of the first sounding in `text`.
pub(super) fn read(text: &str, notes: &mut Vec<String>) -> Result<Vec<Row>, FieldError> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r')));
    let (header_line, header) = lines
        .by_ref()
        .find(|(_, l)| !l.trim().is_empty())
        .ok_or_else(|| FieldError::new("line 1", "the file is empty"))?;
    if !is_header(header) {
        return Err(at(
            header_line,
            "header",
            "an IGRA 2 file starts with a header record: `#`, the station id, the date",
        ));
    }
    let mut rows = Vec::new();
    for (n, line) in lines {
        if line.trim().is_empty() {
            continue;
        }
        if line.starts_with('#') {
            notes.push(format!(
                "the file holds more than one sounding: the first (header on line {header_line}: `{}`) is read",
                header.get(..26).unwrap_or(header).trim_end()
            ));
            break;
        }
        let pressure = field(line, n, 10, 15, "PRESS")?;
        let height = field(line, n, 17, 21, "GPH")?;
        let temp = field(line, n, 23, 27, "TEMP")?;
        let rh = field(line, n, 29, 33, "RH")?;
        let dpdp = field(line, n, 35, 39, "DPDP")?;
        let celsius = temp.map(|t| t as f64 / 10.0);
        rows.push(Row {
            line: n,
            height: height.map(|h| h as f64),
            celsius,
            pressure: pressure.map(|p| p as f64),
            humidity: rh.map(|r| r as f64 / 1000.0),
            dewpoint: match (celsius, dpdp) {
                (Some(t), Some(d)) => Some(t - d as f64 / 10.0),
                _ => None,
            },
        });
    }
    Ok(rows)
}
