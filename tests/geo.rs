//! Geographic points (`mirage::geo`) against GeographicLib: the Python
//! package `geographiclib` (Karney's own implementation) is the oracle.
//!
//! Seeded cases: sites at latitudes from −89° to 89° (some beside the
//! antimeridian, their points across it), points from 1 m to 1,000 km away
//! in every direction, drawn by GeographicLib's direct problem. Each point
//! placed in the site's frame must keep GeographicLib's inverse distance to
//! 1 mm (as the arc from the site's foot on the frame's sphere) and its
//! initial azimuth to 1e-9° (as the bearing in the frame), or, a few
//! metres out where doubles of latitude and longitude do not fix the
//! azimuth that well, to a nanometre across the line of sight.
//!
//! The Python used: the notebooks' venv (`bash notebooks/setup.sh`
//! installs `geographiclib` from `notebooks/requirements.txt`), else a
//! `python3` that imports `geographiclib`; else the test is skipped loudly,
//! or fails under `MIRAGE_REQUIRE_MITSUBA=1` (as `.ci/run` sets).

use mirage::geo::{GeoPoint, Site};
use mirage::math::SplitMix64;
use std::io::Write as _;
use std::path::PathBuf;
use std::process::{Command, Stdio};

/// A Python that imports `geographiclib`.
fn python() -> Option<PathBuf> {
    let venv = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("notebooks/.venv/bin/python");
    let candidates = [venv, PathBuf::from("python3")];
    for p in candidates {
        let ok = Command::new(&p)
            .args(["-c", "import geographiclib"])
            .output()
            .is_ok_and(|o| o.status.success());
        if ok {
            return Some(p);
        }
    }
    let m = "no Python with `geographiclib` (run `bash notebooks/setup.sh`, or `pip install geographiclib==2.1`)";
    if std::env::var("MIRAGE_REQUIRE_MITSUBA").is_ok_and(|v| v == "1") {
        panic!("GeographicLib oracle: MIRAGE_REQUIRE_MITSUBA=1 but {m}");
    }
    let bar = "=".repeat(78);
    eprintln!("\n{bar}\nSKIPPED: the GeographicLib oracle: {m}\n{bar}\n");
    None
}

const ORACLE: &str = r#"
import json, sys
from geographiclib.geodesic import Geodesic
g = Geodesic.WGS84
out = []
for lat1, lon1, azi, s in json.load(sys.stdin):
    d = g.Direct(lat1, lon1, azi, s)
    i = g.Inverse(lat1, lon1, d["lat2"], d["lon2"])
    out.append([d["lat2"], d["lon2"], i["s12"], i["azi1"]])
json.dump(out, sys.stdout)
"#;

/// (site latitude, longitude, azimuth, distance) drawn from `seed`.
fn cases(seed: u64, n: usize) -> Vec<[f64; 4]> {
    let mut rng = SplitMix64(seed);
    (0..n)
        .map(|i| {
            let lat = -89.0 + 178.0 * rng.next_f64();
            // Every fourth site beside the antimeridian, looking across it.
            let (lon, azi) = if i % 4 == 0 {
                let east = rng.next_f64() < 0.5;
                (
                    if east { 179.999 } else { -179.999 },
                    if east {
                        30.0 + 120.0 * rng.next_f64()
                    } else {
                        -150.0 + 120.0 * rng.next_f64()
                    },
                )
            } else {
                (
                    -180.0 + 360.0 * rng.next_f64(),
                    -180.0 + 360.0 * rng.next_f64(),
                )
            };
            // 1 m to 1,000 km, log-uniform.
            let s = (1e6f64.ln() * rng.next_f64()).exp();
            [lat, lon, azi, s]
        })
        .collect()
}

#[test]
fn geographic_points_keep_geographiclib_s_distance_and_azimuth() {
    let Some(python) = python() else {
        return;
    };
    let cases = cases(0x6e0, 2000);
    let mut child = Command::new(python)
        .args(["-c", ORACLE])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(serde_json::to_string(&cases).unwrap().as_bytes())
        .unwrap();
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    let reference: Vec<[f64; 4]> = serde_json::from_slice(&out.stdout).unwrap();
    let (mut worst_s, mut worst_az, mut worst_across, mut crossed) = (0.0f64, 0.0f64, 0.0f64, 0);
    for (c, r) in cases.iter().zip(&reference) {
        let site = Site {
            latitude: c[0],
            longitude: c[1],
            height: 0.0,
        };
        let p = GeoPoint {
            latitude: r[0],
            longitude: r[1],
            height: 0.0,
        };
        if (c[1] > 0.0) != (r[1] > 0.0) && c[1].abs() > 179.0 {
            crossed += 1;
        }
        let radius = site.gaussian_radius();
        let x = site.place(&p, radius);
        // The arc from the site's foot and the bearing, read off the frame.
        let c3 = [x[0], x[1] + radius, x[2]];
        let arc = radius * c3[0].hypot(c3[2]).atan2(c3[1]);
        let bearing = x[0].atan2(x[2]).to_degrees();
        let ds = (arc - r[2]).abs();
        let mut da = (bearing - r[3]).abs() % 360.0;
        da = da.min(360.0 - da);
        worst_s = worst_s.max(ds);
        // A latitude in doubles fixes a point to about a nanometre, so a
        // few metres out the azimuth itself is only defined to ~1e-8°
        // (two implementations of the same inverse differ there by their
        // rounding): below 1e-9° or, failing that, a nanometre across the
        // line of sight.
        let across = r[2] * da.to_radians();
        if r[2] >= 1000.0 {
            worst_az = worst_az.max(da);
        }
        worst_across = worst_across.max(across);
        assert!(ds < 1e-3, "{c:?}: arc {arc} vs GeographicLib {}", r[2]);
        assert!(
            da < 1e-9 || across < 1e-9,
            "{c:?}: bearing {bearing} vs GeographicLib {} ({across:e} m across)",
            r[3]
        );
    }
    eprintln!(
        "{} points, {crossed} across the antimeridian: worst distance error {worst_s:.2e} m, worst azimuth error {worst_az:.2e}° (beyond 1 km), worst miss across the line {worst_across:.2e} m",
        cases.len()
    );
    assert!(crossed > 100, "{crossed} cases cross the antimeridian");
}
