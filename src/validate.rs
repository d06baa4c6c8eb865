//! The checks every validator shares, each returning a [`FieldError`] at the
//! field's path, so that a rule ("a finite number > 0") is worded once.

use crate::error::FieldError;

/// `v` if it is a finite number > 0.
pub fn positive(field: &str, v: f64) -> Result<f64, FieldError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(FieldError::new(
            field,
            format!("must be a finite number > 0, got {v}"),
        ))
    }
}

/// `v` if it is a finite number ≥ 0.
pub fn non_negative(field: &str, v: f64) -> Result<f64, FieldError> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(FieldError::new(
            field,
            format!("must be a finite number ≥ 0, got {v}"),
        ))
    }
}

/// `v` if it is finite.
pub fn finite(field: &str, v: f64) -> Result<f64, FieldError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(FieldError::new(
            field,
            format!("must be a finite number, got {v}"),
        ))
    }
}

/// A command-line count: a whole number of at least 1 (`--threads`, `--frames`).
pub fn at_least_one<T: std::str::FromStr + PartialEq + From<u8>>(
    s: &str,
) -> Result<T, crate::error::ValueError> {
    let n: T = s
        .parse()
        .map_err(|_| crate::error::ValueError::NotAWholeNumber {
            value: s.to_string(),
        })?;
    if n == T::from(0) {
        return Err(crate::error::ValueError::OutOfRange {
            rule: "must be at least 1".into(),
        });
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rules_and_their_words() {
        assert_eq!(positive("a", 2.0), Ok(2.0));
        let e = positive("trace.step", 0.0).unwrap_err();
        assert_eq!(
            e.to_string(),
            "trace.step: must be a finite number > 0, got 0"
        );
        assert!(positive("a", f64::NAN).is_err());
        assert_eq!(non_negative("w", 0.0), Ok(0.0));
        assert!(non_negative("w", -1.0).is_err());
        assert!(finite("x", f64::INFINITY).is_err());
    }
}
