//! Reading JSON input files: one message naming the file and the field for every
//! failure (unreadable file, empty file, not an object, a type error deep inside,
//! trailing text), so that no caller writes its own.

use crate::error::{Error, FieldError, Result, WHOLE_DOCUMENT, join_path, split_nested};
use std::path::Path;

/// Reads an input file; failure is an input error naming the file (exit 2).
pub fn read_input(path: &Path) -> Result<String> {
    std::fs::read_to_string(path)
        .map_err(|e| FieldError::whole(format!("cannot read the file: {e}")).in_file(path))
}

/// Parses JSON text into `T`, turning every failure into one message that names
/// the file and the field (`what` names the kind of file for the top level).
pub fn parse_json<T: serde::de::DeserializeOwned>(
    text: &str,
    path: &Path,
    what: &str,
) -> Result<T> {
    let trimmed = text.trim_start();
    if trimmed.is_empty() {
        return Err(Error::input(
            path,
            "-",
            format!("the file is empty; a {what} file is a JSON object"),
        ));
    }
    if !trimmed.starts_with('{') {
        return Err(Error::input(
            path,
            "-",
            format!(
                "the top level must be a JSON object ({{ ... }}), found `{}`",
                trimmed.chars().next().unwrap_or(' ')
            ),
        ));
    }
    let mut de = serde_json::Deserializer::from_str(text);
    let value: T = serde_path_to_error::deserialize(&mut de).map_err(|e| {
        let field = e.path().to_string();
        // The top level is ".", and a syntax error inside a key that was never
        // finished (fuzzing found `{"": {"a", ...`) has an empty path: both
        // are the whole document; the message gives the line and column.
        let field = if field == "." || field.is_empty() {
            WHOLE_DOCUMENT.to_string()
        } else {
            field
        };
        let inner = e.into_inner();
        let message = if inner.is_eof() {
            format!("the JSON ends too early (truncated file?): {inner}")
        } else {
            inner.to_string()
        };
        match split_nested(&message) {
            Some((below, rest)) => {
                let field = if field == WHOLE_DOCUMENT {
                    below.to_string()
                } else {
                    join_path(&field, below)
                };
                Error::input(path, field, rest.to_string())
            }
            None => Error::input(path, field, message),
        }
    })?;
    de.end().map_err(|e| {
        Error::input(
            path,
            "-",
            format!("unexpected text after the JSON object: {e}"),
        )
    })?;
    Ok(value)
}
