//! Angles as users write them: a number of degrees, or degrees, minutes and
//! seconds in a string (`"-0°02'47\""`).
//!
//! Parsing is exact to the f64 of d + m/60 + s/3600 (one rounding per
//! operation); [`format_dms`] writes seconds to 0.01″ and round-trips any
//! finite angle to 0.005″ (and the rounding of d + m/60 + s/3600 to an f64,
//! which is more only beyond 10⁹ degrees).

use serde::de::{self, Deserializer, Visitor};
use serde::{Deserialize, Serialize, Serializer};
use std::fmt;
use std::str::FromStr;

/// An angle in degrees, read from a number or a degree-minute-second string.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Angle {
    /// Degrees.
    pub degrees: f64,
}

impl Angle {
    /// The angle in radians.
    pub fn radians(self) -> f64 {
        self.degrees.to_radians()
    }
}

/// Why a string is not an angle.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error(
    "`{text}` is not an angle: {why} (write degrees as a number, or as degrees, minutes and seconds: \"-0°02'47\\\"\", \"12d30m05s\", \"-0 2 47\")"
)]
pub struct AngleParseError {
    /// The text as given.
    pub text: String,
    /// What is wrong with it.
    pub why: String,
}

/// The unit marks after degrees, minutes and seconds.
const DEGREE_MARKS: [char; 3] = ['°', 'd', 'º'];
const MINUTE_MARKS: [char; 4] = ['\'', '′', 'm', '’'];
const SECOND_MARKS: [char; 3] = ['"', '″', 's'];

impl FromStr for Angle {
    type Err = AngleParseError;

    fn from_str(text: &str) -> Result<Angle, AngleParseError> {
        let bad = |why: &str| AngleParseError {
            text: text.to_string(),
            why: why.to_string(),
        };
        let t = text.trim();
        let (negative, rest) = match t.strip_prefix(['-', '−']) {
            Some(r) => (true, r),
            None => (false, t.strip_prefix('+').unwrap_or(t)),
        };
        // Split into numbers, each followed by an optional unit mark.
        let mut parts: Vec<(f64, Option<usize>)> = Vec::new();
        let mut chars = rest.chars().peekable();
        loop {
            while chars.peek().is_some_and(|c| c.is_whitespace()) {
                chars.next();
            }
            if chars.peek().is_none() {
                break;
            }
            let mut num = String::new();
            while let Some(&c) = chars.peek() {
                if c.is_ascii_digit() || c == '.' {
                    num.push(c);
                    chars.next();
                } else {
                    break;
                }
            }
            if num.is_empty() {
                return Err(bad(&format!(
                    "expected a number at `{}`",
                    chars.collect::<String>()
                )));
            }
            let value: f64 = num
                .parse()
                .map_err(|_| bad(&format!("`{num}` is not a number")))?;
            while chars.peek().is_some_and(|c| c.is_whitespace()) {
                chars.next();
            }
            let mark = match chars.peek() {
                Some(c) if DEGREE_MARKS.contains(c) => Some(0),
                Some(c) if MINUTE_MARKS.contains(c) => Some(1),
                Some(c) if SECOND_MARKS.contains(c) => Some(2),
                Some(c) if c.is_ascii_digit() => None,
                Some(c) => return Err(bad(&format!("unexpected `{c}`"))),
                None => None,
            };
            if mark.is_some() {
                chars.next();
            }
            parts.push((value, mark));
        }
        if parts.is_empty() {
            return Err(bad("it is empty"));
        }
        if parts.len() > 3 {
            return Err(bad("more than degrees, minutes and seconds"));
        }
        // Unmarked parts take the next place after the previous one.
        let mut fields = [None; 3];
        let mut next = 0;
        for (value, mark) in parts {
            let place = mark.unwrap_or(next);
            if place < next || place > 2 {
                return Err(bad(
                    "degrees, minutes and seconds must come in that order, once each",
                ));
            }
            fields[place] = Some(value);
            next = place + 1;
        }
        let [d, m, s] = fields.map(|f| f.unwrap_or(0.0));
        for (v, name) in [(m, "minutes"), (s, "seconds")] {
            if !(0.0..60.0).contains(&v) {
                return Err(bad(&format!("{name} must lie in [0, 60), got {v}")));
            }
        }
        // A fraction is allowed only in the last part given.
        let last = fields.iter().rposition(Option::is_some).unwrap_or(0);
        if fields[..last].iter().flatten().any(|v| v.fract() != 0.0) {
            return Err(bad("only the last part may have a fraction"));
        }
        let degrees = d + m / 60.0 + s / 3600.0;
        if !degrees.is_finite() {
            return Err(bad("it is too large"));
        }
        Ok(Angle {
            degrees: if negative { -degrees } else { degrees },
        })
    }
}

/// `degrees` as a degree-minute-second string, seconds to 0.01″:
/// `-0°02′47.00″`.
pub fn format_dms(degrees: f64) -> String {
    if !degrees.is_finite() {
        return format!("{degrees}");
    }
    let sign = if degrees < 0.0 { "-" } else { "" };
    // Whole degrees and the fraction apart (both exact): |degrees|·360000
    // overflowed to ∞ above 5·10³⁰² degrees and printed `inf°NaN′00NaN″`,
    // which does not read back (found by fuzzing).
    let mut d = degrees.abs().trunc();
    let mut hundredths = ((degrees.abs() - d) * 360_000.0).round();
    if hundredths >= 360_000.0 {
        d += 1.0;
        hundredths = 0.0;
    }
    let m = (hundredths / 6_000.0).floor();
    let s = (hundredths - m * 6_000.0) / 100.0;
    format!("{sign}{d:.0}°{m:02.0}′{s:05.2}″")
}

impl Serialize for Angle {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_f64(self.degrees)
    }
}

impl<'de> Deserialize<'de> for Angle {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Angle, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Angle;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("an angle: degrees as a number, or a string such as \"-0°02'47\\\"\"")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Angle, E> {
                if v.is_finite() {
                    Ok(Angle { degrees: v })
                } else {
                    Err(E::custom(format!("an angle must be finite, got {v}")))
                }
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Angle, E> {
                Ok(Angle { degrees: v as f64 })
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Angle, E> {
                Ok(Angle { degrees: v as f64 })
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Angle, E> {
                v.parse().map_err(E::custom)
            }
        }
        d.deserialize_any(V)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn deg(s: &str) -> f64 {
        s.parse::<Angle>().unwrap().degrees
    }

    #[test]
    fn the_surveyor_s_angles_read_as_written() {
        assert_eq!(deg("-0°02'47\""), -(2.0 / 60.0 + 47.0 / 3600.0));
        assert_eq!(deg("-0°05′09″"), -(5.0 / 60.0 + 9.0 / 3600.0));
        assert_eq!(deg("212°30'00\""), 212.5);
        assert_eq!(deg("12d30m5.5s"), 12.0 + 30.0 / 60.0 + 5.5 / 3600.0);
        assert_eq!(deg("-0 2 47"), deg("-0°02'47\""));
        assert_eq!(deg("45°"), 45.0);
        assert_eq!(deg("  7.25 "), 7.25);
        assert_eq!(deg("30'"), 0.5);
        assert_eq!(deg("+1°30'"), 1.5);
    }

    #[test]
    fn bad_strings_say_why() {
        for (s, why) in [
            ("", "empty"),
            ("abc", "expected a number"),
            ("1°60'", "minutes must lie in [0, 60)"),
            ("1°2'60\"", "seconds must lie in [0, 60)"),
            ("1'2°", "in that order"),
            ("1.5°30'", "only the last part"),
            ("1 2 3 4", "more than"),
            ("1°x", "expected a number at `x`"),
            ("1x", "unexpected `x`"),
            ("1..2", "not a number"),
        ] {
            let e = s.parse::<Angle>().unwrap_err();
            assert!(e.to_string().contains(why), "{s}: {e}");
        }
    }

    #[test]
    fn dms_round_trips_to_five_thousandths_of_a_second() {
        let mut rng = crate::math::SplitMix64(7);
        for _ in 0..2000 {
            let d = (rng.next_f64() - 0.5) * 720.0;
            let back = deg(&format_dms(d));
            assert!(
                (back - d).abs() * 3600.0 <= 0.005 + 1e-9,
                "{d} → {} → {back}",
                format_dms(d)
            );
        }
        assert_eq!(format_dms(-(2.0 / 60.0 + 47.0 / 3600.0)), "-0°02′47.00″");
        assert_eq!(format_dms(59.999_999_9), "60°00′00.00″");
    }

    #[test]
    fn json_takes_numbers_and_strings() {
        let a: Angle = serde_json::from_str("\"-0°02'47\\\"\"").unwrap();
        assert!((a.degrees + 0.046_388_888_888_888_89).abs() < 1e-15);
        let b: Angle = serde_json::from_str("-0.5").unwrap();
        assert_eq!(b.degrees, -0.5);
        assert!(serde_json::from_str::<Angle>("true").is_err());
    }
}
