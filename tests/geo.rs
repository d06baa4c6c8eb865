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

use mirage::geo::{Angle, GeoPoint, Horizon, Point, Site, format_dms};
use mirage::math::SplitMix64;
use mirage::pair::PairEntry;
use mirage::problem::Problem;
use mirage::trace::Earth;
use std::io::Write as _;
use std::path::{Path, PathBuf};
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

// Crashes the `geo` fuzz target found (`fuzz/fuzz_targets/geo.rs`), each
// with the input it found (shortened where the rest did not matter).

/// `geo`, in its first second: a geographic point placed over the flat
/// ground (`PairEntry::resolve` with `Earth::Flat`, radius ∞) was [NaN, NaN,
/// NaN]: (R + h)·sin(s/R) is ∞·0 and (R + h)·cos(s/R) − R is ∞ − ∞. Now the
/// sphere's limit: the geodesic's distance along its azimuth on the plane.
#[test]
fn fuzz_regression_geo_point_over_the_flat_ground_is_finite() {
    let site = Site {
        latitude: 0.0,
        longitude: 0.0,
        height: 0.0,
    };
    // The input found: the site itself.
    let here = GeoPoint {
        latitude: 0.0,
        longitude: 0.0,
        height: 0.0,
    };
    assert_eq!(site.place(&here, f64::INFINITY), [0.0, 0.0, 0.0]);
    let p = GeoPoint {
        latitude: 0.01,
        longitude: 0.02,
        height: 30.0,
    };
    let (s, azimuth) = site.geodesic_to(&p);
    let x = Point::Geo(p).resolve(Some(&site), f64::INFINITY).unwrap();
    assert_eq!(x[1], 30.0);
    assert!((x[0].hypot(x[2]) - s).abs() < 1e-9, "{x:?} vs {s} m");
    assert!((x[0].atan2(x[2]).to_degrees() - azimuth).abs() < 1e-12);
    // The limit of ever larger spheres.
    let far = site.place(&p, 1e12);
    for k in 0..3 {
        assert!((far[k] - x[k]).abs() < 1e-3, "{far:?} vs {x:?}");
    }
    // A whole pair, aimed by elevation, over the flat ground.
    let pair: PairEntry = serde_json::from_str(
        r#"{"origin": {"latitude": 0, "longitude": 0, "height": 1.5},
            "elevation": "-0°02'47\"", "target": {"latitude": 0.01, "longitude": 0.02}}"#,
    )
    .unwrap();
    let r = pair.resolve(Some(&site), Earth::Flat).unwrap();
    let all = r.origin.iter().chain(&r.through).chain(&r.target);
    assert!(all.into_iter().all(|c| c.is_finite()), "{r:?}");
}

/// `geo`, on the JSON angle `1e303` (a valid angle): `format_dms` printed
/// `inf°NaN′00NaN″`, which does not read back, as |degrees|·360000
/// overflowed above 5·10³⁰² degrees. Every finite angle now reads back to
/// 0.005″ and the f64 rounding of d + m/60 + s/3600.
#[test]
fn fuzz_regression_geo_format_dms_reads_back_any_finite_angle() {
    let a: Angle = serde_json::from_str("1e303").unwrap();
    for d in [
        a.degrees,
        -a.degrees,
        f64::MAX,
        4e15,
        1e10,
        -123_456_789.123_456,
    ] {
        let shown = format_dms(d);
        let back: Angle = shown
            .parse()
            .unwrap_or_else(|e| panic!("{d} printed as {shown}: {e}"));
        assert!(
            (back.degrees - d).abs() <= 0.005 / 3600.0 + f64::EPSILON * d.abs(),
            "{d} printed as {shown}, read back as {}",
            back.degrees
        );
    }
    assert_eq!(format_dms(1e10), "10000000000°00′00.00″");
}

/// `geo`: a pair aimed by `elevation` at a target 2.4·10²⁸⁵ m away got
/// `through` = [inf, NaN, -inf] (the distance was the square root of a sum of
/// squares, ∞ beyond 10¹⁵⁴ m), and a problem refused it as
/// `pairs[0].through: coordinates must be finite`, a field the file does not
/// have. Now the target is refused by name, for `through` pairs too.
#[test]
fn fuzz_regression_geo_elevation_toward_a_target_beyond_1e154_m_names_the_target() {
    let pair: PairEntry = serde_json::from_str(
        r#"{"origin": [100000, -11000, 100000], "elevation": 0,
            "target": [100000, 2.4374274493454076e285, 1.5]}"#,
    )
    .unwrap();
    for earth in [Earth::Flat, Earth::Round { radius: 6.371e6 }] {
        let e = pair.resolve(None, earth).unwrap_err();
        assert_eq!(e.path, "target", "{e}");
        assert!(e.message.contains("2.4374274493454076e285 m"), "{e}");
    }
    let problem = |sight: &str| {
        format!(
            r#"{{"medium": {{"scale": 1.0}}, "pairs": [{{"origin": [0, 1.5, 0], {sight},
                "target": [1e200, 0, 0]}}]}}"#
        )
    };
    for sight in [r#""elevation": 0"#, r#""through": [1, 1.5, 0]"#] {
        let e = Problem::parse(&problem(sight), Path::new("fuzz.json")).unwrap_err();
        let field = e.field().unwrap();
        assert_eq!(field.path, "pairs[0].target", "{e}");
        assert_eq!(e.exit_code(), 2);
    }
    // The same overflow in |through − origin| (found reading the code) made
    // the launch direction the zero vector: `through` is refused by name.
    let text = r#"{"medium": {"scale": 1.0}, "pairs": [{"origin": [0, 1.5, 0],
        "through": [1e200, 1.5, 0], "target": [900, 1.5, 0]}]}"#;
    let e = Problem::parse(text, Path::new("fuzz.json")).unwrap_err();
    assert_eq!(e.field().unwrap().path, "pairs[0].through", "{e}");
}

/// `geo`: with `"residual": "angle"` each weight is divided by |target −
/// origin|, and a target 5.4·10⁻³¹² m from its origin (beside it, so not
/// straight above) squared that distance to 0 and loaded with weight ∞.
/// Now a target must lie 10⁻¹⁵⁰ to 10¹⁵⁰ m away, refused by name.
#[test]
fn fuzz_regression_geo_target_5e_312_m_away_is_refused() {
    let text = r#"{"medium": {"scale": 1.0}, "residual": "angle",
        "pairs": [{"origin": [-10998.30630025787, 0, 5.420658057725e-312],
                   "through": [0, 0, 0], "target": [-10998.30630025787, 0, 0]}]}"#;
    let e = Problem::parse(text, Path::new("fuzz.json")).unwrap_err();
    let field = e.field().unwrap();
    assert_eq!(field.path, "pairs[0].target", "{e}");
    assert!(field.message.contains("5.420658057725e-312 m"), "{e}");
}

/// `geo`: a `through` point 8.9·10⁻¹⁵⁹ m from its origin: the launch
/// direction's squared norm was subnormal, and the direction came out
/// 1.000000008 long (below 10⁻¹⁶² m it is 0 and `through` equals `origin`).
/// Now `through` too must lie 10⁻¹⁵⁰ to 10¹⁵⁰ m away, refused by name.
#[test]
fn fuzz_regression_geo_through_9e_159_m_away_is_refused() {
    let text = r#"{"medium": {"scale": 1.0}, "pairs": [{"origin": [0, 0, 8.854359478573806e-159],
        "through": [0, 0, 0], "target": [-8823.529411764706, -8823.529411764706, -8823.529411764706]}]}"#;
    let e = Problem::parse(text, Path::new("fuzz.json")).unwrap_err();
    let field = e.field().unwrap();
    assert_eq!(field.path, "pairs[0].through", "{e}");
    assert!(field.message.contains("8.854359478573806e-159 m"), "{e}");
}

/// Beside the crash of a target beyond 10¹⁵⁴ m (found reading the code, and
/// checked by the target since): the horizon at a point that far out (a
/// pair's origin, where `elevation` is measured) had up = east = 0, the
/// squares of its norm overflowing, so the elevation was silently dropped.
#[test]
fn fuzz_regression_geo_horizon_far_out_is_orthonormal() {
    let h = Horizon::at([1e200, 0.0, 0.0], Some(6.371e6)).unwrap();
    for (got, want) in [
        (h.up, [1.0, 0.0, 0.0]),
        (h.north, [0.0, 0.0, 1.0]),
        (h.east, [0.0, -1.0, 0.0]),
    ] {
        assert!((0..3).all(|k| (got[k] - want[k]).abs() < 1e-15), "{h:?}");
    }
}
