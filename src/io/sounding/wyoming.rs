//! The University of Wyoming sounding page's TEXT:LIST table: a header line
//! of column names (`PRES HGHT TEMP DWPT RELH MIXR DRCT SKNT THTA THTE
//! THTV`), a line of units (hPa, m, C, C, %, …), between dashed lines, then
//! one fixed-width row per level until a line that is blank, dashed or
//! markup (`</PRE>`). Each column ends where its name ends in the header
//! and starts after the previous one (7 characters each on the page); a
//! blank cell is missing. The page may be saved whole (HTML around the
//! table) or as the table alone.
//!
//! Read: PRES (hPa), HGHT (m), TEMP (°C), DWPT (°C), RELH (%).

use super::row::{Row, at, number};
use crate::error::FieldError;

/// Whether `line` is the table's header line.
pub(super) fn is_header(line: &str) -> bool {
    let mut words = line.split_whitespace();
    words.next() == Some("PRES") && words.next() == Some("HGHT")
}

fn is_dashed(line: &str) -> bool {
    let t = line.trim();
    !t.is_empty() && t.bytes().all(|b| b == b'-')
}

/// The rows of the first table in `text`.
pub(super) fn read(text: &str) -> Result<Vec<Row>, FieldError> {
    let lines: Vec<&str> = text.lines().map(|l| l.trim_end_matches('\r')).collect();
    let Some(head) = lines.iter().position(|l| is_header(l)) else {
        return Err(FieldError::new(
            "line 1",
            "no TEXT:LIST table: no header line `PRES HGHT TEMP DWPT …`",
        ));
    };
    // Each column: (name, start, end) in bytes, ending where its name ends.
    let header = lines[head];
    let mut columns: Vec<(&str, usize, usize)> = Vec::new();
    let mut start = 0;
    let mut rest = header;
    let mut offset = 0;
    while let Some(i) = rest.find(|c: char| !c.is_whitespace()) {
        let word_start = offset + i;
        let len = rest[i..]
            .find(char::is_whitespace)
            .unwrap_or(rest.len() - i);
        let end = word_start + len;
        columns.push((&header[word_start..end], start, end));
        start = end;
        offset = end;
        rest = &header[end..];
    }
    let index = |name: &str| columns.iter().find(|c| c.0 == name).map(|c| (c.1, c.2));
    let (Some(pres), Some(hght), Some(temp)) = (index("PRES"), index("HGHT"), index("TEMP")) else {
        return Err(at(
            head + 1,
            "header",
            "the header must name PRES, HGHT and TEMP",
        ));
    };
    let (dwpt, relh) = (index("DWPT"), index("RELH"));
    // Skip the units line and the dashed lines under the header.
    let mut i = head + 1;
    while i < lines.len() && (is_dashed(lines[i]) || lines[i].contains("hPa")) {
        i += 1;
    }
    let mut rows = Vec::new();
    for (k, line) in lines.iter().enumerate().skip(i) {
        let n = k + 1;
        let t = line.trim();
        if t.is_empty() || is_dashed(line) || t.starts_with('<') {
            break;
        }
        let cell = |span: Option<(usize, usize)>, name: &str| -> Result<Option<f64>, FieldError> {
            let Some((a, b)) = span else { return Ok(None) };
            let a = a.min(line.len());
            let b = b.min(line.len());
            let text = line.get(a..b).ok_or_else(|| {
                at(
                    n,
                    name,
                    "the line is not plain ASCII where this column lies",
                )
            })?;
            number(text.trim(), n, name)
        };
        rows.push(Row {
            line: n,
            pressure: cell(Some(pres), "PRES")?.map(|p| p * 100.0),
            height: cell(Some(hght), "HGHT")?,
            celsius: cell(Some(temp), "TEMP")?,
            dewpoint: cell(dwpt, "DWPT")?,
            humidity: cell(relh, "RELH")?.map(|r| r / 100.0),
        });
    }
    Ok(rows)
}
