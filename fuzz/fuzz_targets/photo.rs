//! Photo problems (`docs/photo.md`): the input is a problem file, a NUL, then
//! the bytes of the image it names (written next to the problem as
//! `image.bin`, so the seeds say `"image": "image.bin"`). Any such input is
//! refused with an input error naming a field, or accepted; then the
//! objective's residuals and Jacobian at the start (air and camera) and the
//! photo report (each mark's predicted and straight-ray pixel, the horizon)
//! are finite, never a panic. EXIF bytes arrive inside the image's bytes.
#![no_main]

#[path = "common.rs"]
mod common;

use libfuzzer_sys::fuzz_target;
use mirage::fit::objective::Objective;
use mirage::fit::photo::photo_report;
use mirage::problem::Problem;

/// More marks than this cost seconds an input and find nothing new.
const MAX_MARKS: usize = 8;

fuzz_target!(|data: &[u8]| {
    let (text, image) = match data.iter().position(|&b| b == 0) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &[][..]),
    };
    let Ok(text) = std::str::from_utf8(text) else {
        return;
    };
    let dir = common::scratch();
    std::fs::write(dir.join("image.bin"), image).unwrap();
    let mut p = match Problem::parse(text, &dir.join("problem.json")) {
        Ok(p) => p,
        Err(e) => return common::check_error(&e),
    };
    if p.photo.as_ref().is_none_or(|s| s.marks.len() > MAX_MARKS) {
        return;
    }
    p.trace.max_steps = common::MAX_STEPS;
    let objective = Objective::from_problem(&p);
    let x = objective.start();
    let (r, _) = objective.residuals(x.as_slice());
    assert!(r.iter().all(|v| v.is_finite()), "residuals {r:?}");
    let (r, j) = objective.jacobian(x.as_slice());
    assert!(r.iter().all(|v| v.is_finite()), "residuals {r:?}");
    assert!(j.iter().all(|v| v.is_finite()), "Jacobian {j:?}");
    let report = photo_report(&objective, x.as_slice(), "image.bin").expect("a photo problem");
    assert!(report.focal_pixels.is_finite() && report.focal_pixels > 0.0);
    assert!(report.rms_pixels.is_finite(), "rms {}", report.rms_pixels);
    for (name, v) in &report.camera {
        assert!(v.is_finite(), "camera {name} = {v}");
    }
    for m in &report.marks {
        assert!(m.residual.is_finite(), "mark {m:?}");
        for q in m.predicted.iter().chain(&m.straight) {
            assert!(q.iter().all(|v| v.is_finite()), "mark {m:?}");
        }
    }
    for q in &report.horizon_line {
        assert!(q.iter().all(|v| v.is_finite()), "horizon {q:?}");
    }
});
