//! Problem files: any bytes given to `Problem::parse` are refused with an
//! input error naming a field, or accepted and then traced to finite endpoints.
#![no_main]

#[path = "common.rs"]
mod common;

use libfuzzer_sys::fuzz_target;
use mirage::problem::Problem;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match Problem::parse(text, Path::new("fuzz.json")) {
        Ok(p) => common::check_problem(p),
        Err(e) => common::check_error(&e),
    }
});
