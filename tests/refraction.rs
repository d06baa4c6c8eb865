//! `mirage refraction` (`docs/air.md`): the geometric dip without
//! refraction, the US 1976 atmosphere against Bennett's formula and the
//! surveyors' k, a raised observer's lines of sight below the horizon, and
//! the command's outputs.

use mirage::math::V3;
use mirage::medium::air::AirField;
use mirage::medium::air::AirMedium;
use mirage::medium::{IndexField, Medium};
use mirage::problem::Problem;
use mirage::refraction::{air_refraction, geometric_dip};
use std::path::{Path, PathBuf};
use std::process::Command;

const R: f64 = 6_371_000.0;
const ARCMIN: f64 = std::f64::consts::PI / (180.0 * 60.0);

fn bundled() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/atmospheres/us1976.json")
}

/// The bundled US 1976 atmosphere (15 °C, 101 325 Pa, dry, 550 nm, Ciddor).
fn us1976() -> AirMedium {
    match Problem::load(&bundled()).unwrap().medium {
        Medium::Air(a) => a,
        _ => panic!("the bundled atmosphere is real air"),
    }
}

/// Air with n − 1 = 0 everywhere (Gladstone–Dale with K = 0).
fn vacuum() -> AirMedium {
    let mut a = us1976();
    a.air.refractivity = mirage::medium::air::Formula::GladstoneDale(0.0);
    a
}

#[test]
fn without_refraction_the_dip_is_geometric_and_nothing_bends() {
    let air = vacuum();
    for h in [2.0, 10.0, 100.0, 1000.0] {
        let geometric = (R / (R + h)).acos();
        let below = -0.5 * geometric.to_degrees();
        let r = air_refraction(
            &air,
            h,
            R,
            &[0.0, 10.0, below, -1.01 * geometric.to_degrees()],
        )
        .unwrap();
        let dip = r.dip_arcmin.unwrap() * ARCMIN;
        assert!(
            (dip - geometric).abs() < 1e-9,
            "{h} m: {dip} vs {geometric}"
        );
        assert!((geometric_dip(h, R) - geometric).abs() < 1e-12);
        assert_eq!(r.k, 0.0);
        for row in &r.rows[..3] {
            let a = row.refraction_arcmin.unwrap();
            assert!(a.abs() < 1e-6, "{h} m, {}°: {a}′", row.elevation_deg);
        }
        assert!(r.rows[3].hits_ground && r.rows[3].refraction_arcmin.is_none());
    }
}

#[test]
fn the_standard_atmosphere_refracts_as_bennett_says_and_k_is_the_surveyors() {
    let r = air_refraction(&us1976(), 0.0, R, &[0.0, 5.0, 10.0]).unwrap();
    for row in &r.rows[1..] {
        let (a, b) = (row.refraction_arcmin.unwrap(), row.bennett_arcmin.unwrap());
        assert!(
            (a - b).abs() < 0.1,
            "{}°: mirage {a}′, Bennett {b}′",
            row.elevation_deg
        );
    }
    // At the horizon about 34′: Bennett gives 33.99′ at 15 °C and 101 325 Pa,
    // with a constant about 3 % above Ciddor's n − 1 at 550 nm (see 45°).
    let horizon = r.rows[0].refraction_arcmin.unwrap();
    assert!(horizon > 32.5 && horizon < 34.5, "{horizon}′");
    // High up, any layered air refracts by (n₀ − 1)·cot e, less terms of the
    // order of the scale height over R and (n₀ − 1)·cot² e: 0.3 % at 45°.
    let delta0 = AirField::new(&us1976()).delta(V3::new(0.0, 0.0, 0.0));
    let r45 = air_refraction(&us1976(), 0.0, R, &[45.0]).unwrap();
    let a45 = r45.rows[0].refraction_arcmin.unwrap() * ARCMIN;
    assert!((a45 / delta0 - 1.0).abs() < 5e-3, "{a45} vs {delta0}");
    assert!((r.k - 0.17).abs() < 0.01, "k = {}", r.k);
    assert!(
        (r.k_traced / r.k - 1.0).abs() < 1e-3,
        "{} vs {}",
        r.k_traced,
        r.k
    );
    assert_eq!(r.dip_arcmin.map(|d| d.abs() < 1e-6), Some(true));
}

#[test]
fn a_raised_observer_sees_below_the_horizontal_down_to_the_dip() {
    let h = 100.0;
    let air = us1976();
    let geometric = geometric_dip(h, R);
    let r0 = air_refraction(&air, h, R, &[]).unwrap();
    let dip = r0.dip_arcmin.unwrap() * ARCMIN;
    // Smaller than the geometric dip, by √(1 − k) nearly (k falls a little
    // over the 100 m down to the grazing point).
    assert!(dip < geometric);
    let expected = geometric * (1.0 - r0.k).sqrt();
    assert!((dip / expected - 1.0).abs() < 0.01, "{dip} vs {expected}");
    let d = dip.to_degrees();
    let r = air_refraction(&air, h, R, &[-0.5 * d, -0.98 * d, -1.02 * d, -2.0 * d]).unwrap();
    for row in &r.rows[..2] {
        let a = row.refraction_arcmin.unwrap();
        // A grazing ray crosses the low air twice: more than the horizon's.
        assert!(!row.hits_ground && a > 30.0, "{}°: {a}′", row.elevation_deg);
        assert!(row.true_elevation_deg.unwrap() < row.elevation_deg);
    }
    for row in &r.rows[2..] {
        assert!(row.hits_ground && row.refraction_arcmin.is_none());
    }
}

#[test]
fn the_command_writes_json_csv_and_a_figure() {
    let dir = tempfile::tempdir().unwrap();
    let (json, csv, png) = (
        dir.path().join("r.json"),
        dir.path().join("r.csv"),
        dir.path().join("r.png"),
    );
    let run = Command::new(env!("CARGO_BIN_EXE_mirage"))
        .arg("refraction")
        .arg(bundled())
        .args(["--height", "2", "--elevations", "-1,-0.02,0,5"])
        .arg("-o")
        .arg(&json)
        .arg("--csv")
        .arg(&csv)
        .arg("--plot")
        .arg(&png)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(stdout.contains("dip of the horizon") && stdout.contains("hits the ground"));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 4);
    assert_eq!(rows[0]["elevation_deg"], -1.0);
    assert_eq!(rows[0]["hits_ground"], true);
    assert!(rows[0]["refraction_arcmin"].is_null());
    for row in &rows[1..] {
        assert_eq!(row["hits_ground"], false);
        assert!(row["refraction_arcmin"].as_f64().unwrap() > 5.0);
    }
    // The earth is the file's; the dip is below the geometric one at 2 m.
    assert_eq!(v["earth_radius"], R);
    let (dip, geometric) = (
        v["dip_arcmin"].as_f64().unwrap(),
        v["geometric_dip_arcmin"].as_f64().unwrap(),
    );
    assert!(
        dip < geometric && dip > 0.85 * geometric,
        "{dip} vs {geometric}"
    );
    assert!((v["k"].as_f64().unwrap() - 0.17).abs() < 0.01);
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 5);
    assert!(lines[0].starts_with("elevation_deg,refraction_arcmin"));
    assert!(lines[1].starts_with("-1,,,true,false,"));
    let png = std::fs::read(&png).unwrap();
    assert!(png.starts_with(b"\x89PNG") && png.len() > 10_000);
}
