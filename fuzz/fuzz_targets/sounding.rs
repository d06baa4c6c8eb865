//! Sounding files (`docs/sounding.md`): the first byte picks the format
//! (IGRA 2, Wyoming, CSV, or inferred from the rest), the second an
//! optional site height; the rest is the file's text. Refused with an error
//! naming a line and a column (or a field of the medium), or, when it is
//! read, the medium it makes is valid or refused by a named field, and a
//! valid one is finite everywhere as in the `air` target.
#![no_main]

#[path = "common.rs"]
mod common;

use libfuzzer_sys::fuzz_target;
use mirage::io::sounding::{Format, read};
use mirage::medium::Medium;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let [pick, site, rest @ ..] = data else {
        return;
    };
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    let format = match pick % 4 {
        0 => Format::Igra2,
        1 => Format::Wyoming,
        2 => Format::Csv,
        _ => match Format::infer(None, text) {
            Some(f) => f,
            None => return,
        },
    };
    let site = (site % 2 == 1).then(|| f64::from(*site) * 10.0 - 1000.0);
    let path = Path::new("sounding.txt");
    let sounding = match read(text, format) {
        Ok(s) => s,
        Err(e) => return common::check_error(&e.in_file(path)),
    };
    let (medium, _notes) = sounding.medium(site);
    match medium.validate() {
        Ok(()) => common::check_medium(&Medium::Air(medium)),
        Err(e) => common::check_error(&e.within("medium").in_file(path)),
    }
});
