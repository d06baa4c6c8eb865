//! Fit results read back: the input is the file a scene's `medium_from` names
//! (normally `mirage fit -o`'s result). Refused with an input error naming a
//! field of that file, or accepted with a medium that traces finitely.
#![no_main]

#[path = "common.rs"]
mod common;

use libfuzzer_sys::fuzz_target;
use mirage::scene::Scene;

const SCENE: &str = r#"{"camera": {"position": [0, 1.5, 0], "look_at": [0, 1.5, 100],
  "up": [0, 1, 0], "vertical_fov": 1.0, "width": 8, "height": 8},
  "medium_from": "result.json"}"#;

fuzz_target!(|data: &[u8]| {
    let dir = common::scratch();
    let result = dir.join("result.json");
    std::fs::write(&result, data).unwrap();
    match Scene::parse(SCENE, &dir.join("scene.json")) {
        Ok(s) => common::check_medium(&s.medium),
        Err(e) => common::check_error(&e),
    }
});
