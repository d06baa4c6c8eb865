//! Scene files, `medium_from` included: the input is a scene, a NUL byte, and
//! the sibling file its `medium_from` may name (`sibling.json`). Refused with an
//! input error naming a field, or accepted with a medium that traces finitely.
#![no_main]

#[path = "common.rs"]
mod common;

use libfuzzer_sys::fuzz_target;
use mirage::scene::Scene;

fuzz_target!(|data: &[u8]| {
    let (scene, sibling) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &[][..]),
    };
    let Ok(text) = std::str::from_utf8(scene) else {
        return;
    };
    let dir = common::scratch();
    std::fs::write(dir.join("sibling.json"), sibling).unwrap();
    match Scene::parse(text, &dir.join("scene.json")) {
        Ok(s) => common::check_medium(&s.medium),
        Err(e) => common::check_error(&e),
    }
});
