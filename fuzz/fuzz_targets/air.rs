//! Real-air media (`docs/air.md`): the input is the text of a `medium`
//! section. Refused with an error naming a field, or, when it is a valid
//! medium, its field finite at every height below its ceiling and rays from
//! grazing to vertical, over the flat and the round earth, ending finitely.
#![no_main]

#[path = "common.rs"]
mod common;

use libfuzzer_sys::fuzz_target;
use mirage::io::json::parse_json;
use mirage::medium::Medium;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new("medium.json");
    let m: Medium = match parse_json(text, path, "medium") {
        Ok(m) => m,
        Err(e) => return common::check_error(&e),
    };
    match m.validate() {
        Ok(()) => common::check_medium(&m),
        Err(e) => common::check_error(&e.in_file(path)),
    }
});
