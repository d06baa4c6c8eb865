//! `mirage sounding` (`docs/sounding.md`) and humidity tables
//! (`docs/air.md`): the three formats read from hand-written files in
//! `tests/data/sounding/` (heights, °C, Pa, relative humidity as a
//! fraction, missing values skipped), each bad line refused by its number,
//! the written medium traced in a problem, and the physics of a humidity
//! table (a constant one equals the plain number; exact Jacobians).

use mirage::fit::objective::Objective;
use mirage::io::sounding::{Format, read};
use mirage::math::V3;
use mirage::medium::air::AirMedium;
use mirage::medium::air::humidity::saturation_vapour_pressure;
use mirage::medium::air::hydrostatic::{G, M, R};
use mirage::medium::{IndexField, Medium, Param};
use mirage::pair::PointPair;
use mirage::trace::{Method, TraceOptions};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/sounding")
        .join(name)
}

fn text(name: &str) -> String {
    std::fs::read_to_string(data(name)).unwrap()
}

/// The medium of a file read as `format`.
fn medium_of(name: &str, format: Format, site: Option<f64>) -> (AirMedium, Vec<String>) {
    let s = read(&text(name), format).unwrap_or_else(|e| panic!("{name}: {e}"));
    let (m, notes) = s.medium(site);
    m.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
    (m, notes)
}

fn rh(dewpoint: f64, celsius: f64) -> f64 {
    saturation_vapour_pressure(dewpoint) / saturation_vapour_pressure(celsius)
}

fn assert_rows(got: &[[f64; 2]], want: &[[f64; 2]], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: {got:?} vs {want:?}");
    for (g, w) in got.iter().zip(want) {
        assert!(
            (g[0] - w[0]).abs() < 1e-9 && (g[1] - w[1]).abs() < 1e-12,
            "{what}: {got:?} vs {want:?}"
        );
    }
}

fn humidity_rows(m: &AirMedium) -> Vec<[f64; 2]> {
    m.air.humidity.table().expect("a humidity table").to_vec()
}

#[test]
fn igra2_levels_become_the_tables() {
    let (m, notes) = medium_of("igra2-good.txt", Format::Igra2, None);
    // GPH 790 (surface), 800, 1480, 5800 m with TEMP; 80000 Pa has no GPH,
    // 70000 Pa no TEMP (−8888) but an RH of 30.0 %.
    assert_rows(
        m.air.temperature.table.as_ref().unwrap(),
        &[[0.0, 28.2], [10.0, 28.0], [690.0, 22.0], [5010.0, -15.0]],
        "temperature",
    );
    assert_rows(
        &humidity_rows(&m),
        &[
            [0.0, 0.4],
            [10.0, rh(28.0 - 16.0, 28.0)],
            [690.0, 0.35],
            [2310.0, 0.3],
        ],
        "humidity",
    );
    assert_eq!(m.air.pressure, 92_100.0);
    assert!(m.air.hydrostatic);
    assert!(
        notes.iter().any(|n| n.contains("more than one sounding")),
        "{notes:?}"
    );
    assert_eq!(
        Format::infer(Some("txt"), &text("igra2-good.txt")),
        Some(Format::Igra2)
    );
}

#[test]
fn the_site_height_moves_the_ground_and_its_pressure() {
    let (m, _) = medium_of("igra2-good.txt", Format::Igra2, Some(800.0));
    assert_rows(
        m.air.temperature.table.as_ref().unwrap(),
        &[[-10.0, 28.2], [0.0, 28.0], [680.0, 22.0], [5000.0, -15.0]],
        "temperature",
    );
    assert_eq!(m.air.pressure, 92_000.0);
    // Between levels: the nearest level's pressure carried hydrostatically.
    let (m, _) = medium_of("igra2-good.txt", Format::Igra2, Some(795.0));
    let want = 92_100.0 * (-(G * M / R) * 5.0 / (28.2 + 273.15)).exp();
    assert!((m.air.pressure - want).abs() < 1e-9, "{}", m.air.pressure);
    // Below the lowest level: heights stay above the lowest level.
    let (m, notes) = medium_of("igra2-good.txt", Format::Igra2, Some(10.0));
    assert_eq!(m.air.temperature.table.as_ref().unwrap()[0], [0.0, 28.2]);
    assert!(notes.iter().any(|n| n.contains("below the lowest")));
}

#[test]
fn wyoming_text_list_becomes_the_tables() {
    let (m, _) = medium_of("wyoming-good.html", Format::Wyoming, None);
    // 1000 and 925 hPa (below the ground, no TEMP) and 800 hPa (no TEMP)
    // are skipped; 900 hPa has TEMP only, 850 hPa DWPT but no RELH.
    assert_rows(
        m.air.temperature.table.as_ref().unwrap(),
        &[
            [0.0, 28.2],
            [83.0, 27.6],
            [195.0, 26.2],
            [690.0, 22.0],
            [2340.0, 9.4],
        ],
        "temperature",
    );
    assert_rows(
        &humidity_rows(&m),
        &[
            [0.0, 0.40],
            [83.0, 0.39],
            [690.0, rh(8.0, 22.0)],
            [2340.0, 0.35],
        ],
        "humidity",
    );
    assert_eq!(m.air.pressure, 921.0 * 100.0);
    assert_eq!(
        Format::infer(Some("html"), &text("wyoming-good.html")),
        Some(Format::Wyoming)
    );
}

#[test]
fn csv_columns_by_name_with_humidity_or_dew_point() {
    let (m, _) = medium_of("mast.csv", Format::Csv, None);
    assert_rows(
        m.air.temperature.table.as_ref().unwrap(),
        &[[0.0, 18.5], [8.0, 17.9], [48.0, 17.0]],
        "temperature",
    );
    assert_rows(
        &humidity_rows(&m),
        &[[0.0, 0.65], [8.0, 0.6], [23.0, 0.55]],
        "humidity",
    );
    assert_eq!(m.air.pressure, 1013.2 * 100.0);
    let (m, notes) = medium_of("mast-dewpoint.csv", Format::Csv, None);
    assert_rows(
        m.air.temperature.table.as_ref().unwrap(),
        &[[0.0, 20.0], [5.0, 19.0], [20.0, 18.0]],
        "temperature",
    );
    assert_rows(
        &humidity_rows(&m),
        &[[0.0, rh(10.0, 20.0)], [20.0, rh(12.0, 18.0)]],
        "humidity",
    );
    assert_eq!(m.air.pressure, 101_325.0);
    assert!(notes.iter().any(|n| n.contains("no pressure")), "{notes:?}");
    assert_eq!(
        Format::infer(Some("csv"), &text("mast.csv")),
        Some(Format::Csv)
    );
    assert_eq!(
        Format::infer(None, &text("mast-dewpoint.csv")),
        Some(Format::Csv)
    );
    assert_eq!(Format::infer(Some("txt"), &text("unknown.txt")), None);
}

#[test]
fn each_bad_line_is_refused_by_its_number_and_column() {
    let cases = [
        (
            "igra2-height.txt",
            Format::Igra2,
            "line 4, GPH",
            "strictly increasing",
        ),
        (
            "igra2-number.txt",
            Format::Igra2,
            "line 3, TEMP",
            "not an integer",
        ),
        ("igra2-cold.txt", Format::Igra2, "line 4, TEMP", "-160 °C"),
        (
            "igra2-one-row.txt",
            Format::Igra2,
            "TEMP",
            "at least two rows",
        ),
        (
            "wyoming-height.txt",
            Format::Wyoming,
            "line 7, HGHT",
            "strictly increasing",
        ),
        (
            "wyoming-number.txt",
            Format::Wyoming,
            "line 6, RELH",
            "`4O`",
        ),
        (
            "wyoming-hot.txt",
            Format::Wyoming,
            "line 7, TEMP",
            "327.6 °C",
        ),
        (
            "wyoming-one-row.txt",
            Format::Wyoming,
            "TEMP",
            "at least two rows",
        ),
        (
            "csv-height.csv",
            Format::Csv,
            "line 4, height",
            "strictly increasing",
        ),
        (
            "csv-number.csv",
            Format::Csv,
            "line 3, temperature",
            "`abc`",
        ),
        (
            "csv-humidity.csv",
            Format::Csv,
            "line 3, humidity",
            "[0, 100] %",
        ),
        (
            "csv-cold.csv",
            Format::Csv,
            "line 3, temperature",
            "-151 °C",
        ),
        (
            "csv-one-row.csv",
            Format::Csv,
            "temperature",
            "at least two rows",
        ),
        (
            "csv-no-column.csv",
            Format::Csv,
            "line 1, header",
            "`temperature`",
        ),
        ("mast.csv", Format::Igra2, "line 1, header", "header record"),
        ("mast.csv", Format::Wyoming, "line 1", "no TEXT:LIST table"),
    ];
    for (name, format, path, words) in cases {
        let e = read(&text(name), format).expect_err(name);
        assert_eq!(e.path, path, "{name}: {e}");
        assert!(e.message.contains(words), "{name}: {e}");
    }
}

fn mirage(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mirage"))
        .args(args)
        .output()
        .unwrap()
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("mirage-sounding-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn the_command_refuses_bad_files_with_exit_code_2_and_no_output() {
    let dir = scratch("bad");
    let out = dir.join("air.json");
    for (name, format, words) in [
        ("csv-height.csv", None, "csv-height.csv: line 4, height:"),
        ("igra2-cold.txt", None, "igra2-cold.txt: line 4, TEMP:"),
        (
            "wyoming-number.txt",
            Some("wyoming"),
            "wyoming-number.txt: line 6, RELH:",
        ),
        ("unknown.txt", None, "give --format"),
        ("mast.csv", Some("grib"), "--format"),
    ] {
        let file = data(name);
        let mut args = vec![
            "sounding",
            file.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ];
        if let Some(f) = format {
            args.extend(["--format", f]);
        }
        let run = mirage(&args);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{name}: {stderr}");
        assert!(stderr.contains(words), "{name}: {stderr}");
        assert!(!out.exists(), "{name}: an output was written");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_written_medium_loads_and_traces_in_a_problem() {
    let dir = scratch("trace");
    for (name, site) in [
        ("igra2-good.txt", None),
        ("wyoming-good.html", Some("795")),
        ("mast.csv", None),
    ] {
        let out = dir.join("air.json");
        let file = data(name);
        let mut args = vec![
            "sounding",
            file.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ];
        if let Some(s) = site {
            args.extend(["--site-height", s]);
        }
        let run = mirage(&args);
        assert!(
            run.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        let medium = std::fs::read_to_string(&out).unwrap();
        let m: Medium = serde_json::from_str(&medium).unwrap();
        m.validate().unwrap();
        let problem = dir.join("problem.json");
        std::fs::write(
            &problem,
            format!(
                r#"{{"name": "sounding", "medium": {medium},
                  "free": [],
                  "pairs": [{{"origin": [0, 2, 0], "through": [0, 2.5, 1000], "target": [0, 2.5, 1000]}},
                            {{"origin": [0, 2, 0], "through": [0, 1.5, 800], "target": [0, 1.5, 800]}}],
                  "trace": {{"method": "dopri5", "tolerance": 1e-9}}}}"#
            ),
        )
        .unwrap();
        let report = dir.join("report.json");
        let run = mirage(&[
            "trace",
            problem.to_str().unwrap(),
            "-o",
            report.to_str().unwrap(),
        ]);
        assert!(
            run.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        let r: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        let pairs = r["pairs"].as_array().unwrap();
        assert_eq!(pairs.len(), 2, "{name}");
        for p in pairs {
            let distance = p["distance"].as_f64().unwrap();
            // Nearly straight over a kilometre: centimetres, not metres.
            assert!(distance.is_finite() && distance < 0.5, "{name}: {p}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

fn air(json: &str) -> Medium {
    let m: Medium = serde_json::from_str(json).unwrap_or_else(|e| panic!("{e}: {json}"));
    m.validate().unwrap_or_else(|e| panic!("{e}: {json}"));
    m
}

#[test]
fn a_constant_humidity_table_is_the_plain_number() {
    for formula in [r#""ciddor""#, r#""edlen""#] {
        let body = r#""temperature": {"table": [[0, 25], [3, 21], [40, 20], [900, 14]]},
            "pressure": 95000"#;
        let plain = air(&format!(
            r#"{{"air": {{{body}, "humidity": 0.62, "refractivity": {formula}}}}}"#
        ));
        let table = air(&format!(
            r#"{{"air": {{{body}, "humidity": {{"table": [[-5, 0.62], [2, 0.62], [700, 0.62]]}},
                "refractivity": {formula}}}}}"#
        ));
        let (fp, ft) = (plain.field(), table.field());
        for y in [-1.0, 0.0, 0.3, 1.9, 2.0, 17.0, 450.0, 2000.0] {
            let p = V3::new(3.0, y, 40.0);
            let (dp, gp) = fp.delta_gradient(p);
            let (dt, gt) = ft.delta_gradient(p);
            // Each field is its compiled profile (medium::compiled), within
            // 1e-12 of the same formula: the table's rows are extra knots,
            // so the two profiles differ at that level, not at rounding.
            // The formulas themselves agree to rounding.
            if let (mirage::medium::Field::Air(a), mirage::medium::Field::Air(b)) = (&fp, &ft) {
                let (da, _) = a.formula_delta_gradient(p);
                let (db, _) = b.formula_delta_gradient(p);
                assert!((da - db).abs() <= 1e-15 * da, "{formula} {y}: {da} vs {db}");
            } else {
                panic!("real air has an air field");
            }
            let bound = mirage::medium::compiled::BOUND;
            let floor = dp / mirage::medium::compiled::SLOPE_SCALE;
            assert!(
                (dp - dt).abs() <= 2.0 * bound * dp,
                "{formula} {y}: {dp} vs {dt}"
            );
            assert!(
                (gp - gt).norm() <= 2.0 * bound * gp.norm().max(floor),
                "{formula} {y}: {gp:?} vs {gt:?}"
            );
        }
    }
    // The file form: a plain number stays a number, a table round-trips.
    let plain = air(r#"{"air": {"temperature": {"base": 10}, "humidity": 0.5}}"#);
    let text = serde_json::to_string(&plain).unwrap();
    assert!(text.contains(r#""humidity":0.5"#), "{text}");
    let table = air(
        r#"{"air": {"temperature": {"base": 10}, "humidity": {"table": [[0, 0.9], [50, 0.4]]}}}"#,
    );
    let text = serde_json::to_string(&table).unwrap();
    assert!(
        text.contains(r#""humidity":{"table":[[0.0,0.9],[50.0,0.4]]}"#),
        "{text}"
    );
    assert_eq!(serde_json::from_str::<Medium>(&text).unwrap(), table);
}

#[test]
fn humidity_tables_are_checked_by_row() {
    for (humidity, path, words) in [
        (
            r#"{"table": [[0, 0.5]]}"#,
            "air.humidity.table",
            "at least two rows",
        ),
        (
            r#"{"table": [[0, 0.5], [0, 0.6]]}"#,
            "air.humidity.table[1][0]",
            "strictly increasing",
        ),
        (
            r#"{"table": [[0, 0.5], [9, 1.2]]}"#,
            "air.humidity.table[1][1]",
            "[0, 1]",
        ),
    ] {
        let m: Medium = serde_json::from_str(&format!(
            r#"{{"air": {{"temperature": {{"base": 10}}, "humidity": {humidity}}}}}"#
        ))
        .unwrap();
        let e = m.validate().expect_err(humidity);
        assert!(
            e.path.ends_with(path) && e.message.contains(words),
            "{humidity}: {e}"
        );
    }
    let e = serde_json::from_str::<Medium>(
        r#"{"air": {"temperature": {"base": 10}, "humidity": {"rows": [[0, 0.5]]}}}"#,
    )
    .unwrap_err();
    assert!(e.to_string().contains("unknown field `rows`"), "{e}");
}

#[test]
fn a_humidity_table_changes_the_gradient_as_finite_differences_say() {
    let m = air(
        r#"{"air": {"temperature": {"table": [[0, 30], [5, 26], [100, 24]]},
            "humidity": {"table": [[0, 0.95], [2, 0.6], [30, 0.2], [80, 0.1]]},
            "refractivity": "edlen"}}"#,
    );
    let field = m.field();
    for y in [0.3, 1.0, 2.7, 15.0, 55.0] {
        let p = V3::new(0.0, y, 10.0);
        let (_, g) = field.delta_gradient(p);
        let h = 1e-4;
        let fd = (field.delta(p + V3::new(0.0, h, 0.0)) - field.delta(p - V3::new(0.0, h, 0.0)))
            / (2.0 * h);
        assert!(
            (g.y - fd).abs() < 1e-5 * g.y.abs(),
            "{y}: analytic {} vs {fd}",
            g.y
        );
    }
}

fn pairs() -> Vec<PointPair> {
    [(0.25, 200.0), (0.4, 260.0), (0.15, 320.0), (0.3, 380.0)]
        .iter()
        .map(|&(down, z): &(f64, f64)| {
            let y = 1.5 - z * down.to_radians().tan();
            serde_json::from_str(&format!(
                r#"{{"origin": [0, 1.5, 0], "through": [2, {y}, {z}], "target": [2, {y}, {z}]}}"#
            ))
            .unwrap()
        })
        .collect()
}

#[test]
fn the_jacobian_with_a_humidity_table_matches_finite_differences() {
    let m = air(
        r#"{"air": {"temperature": {"table": [[0, 34], [0.3, 29], [2, 27], [60, 26]]},
            "humidity": {"table": [[0, 0.9], [0.5, 0.5], [3, 0.3], [60, 0.2]]},
            "pressure": 99000}}"#,
    );
    let free: Vec<Param> = [
        "air.temperature.table[1][1]",
        "air.pressure",
        "air.humidity.table[1][1]",
        "air.humidity.table[1][0]",
    ]
    .iter()
    .map(|s| s.parse().unwrap())
    .collect();
    let obj = Objective::new(
        m,
        free.clone(),
        pairs(),
        TraceOptions::new(Method::Rk4 { step: 2.0 }),
    );
    let x = obj.start();
    let (_, jac) = obj.jacobian(x.as_slice());
    for (k, p) in free.iter().enumerate() {
        let h = 1e-5 * x[k].abs().max(1.0);
        let (mut xp, mut xm) = (x.clone(), x.clone());
        xp[k] += h;
        xm[k] -= h;
        let fd = (obj.residuals(xp.as_slice()).0 - obj.residuals(xm.as_slice()).0) / (2.0 * h);
        let col = jac.column(k);
        let err = (&fd - col).norm() / col.norm().max(1e-14);
        eprintln!("{p}: |J| = {:.3e}, relative error {err:.1e}", col.norm());
        assert!(col.norm() > 0.0, "{p}: no effect");
        assert!(err < 1e-4, "{p}: exact {col:?} vs {fd:?}");
    }
}
