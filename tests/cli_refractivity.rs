//! `mirage refractivity` (docs/air.md): n − 1 on a line of its own, and bad flags
//! refused with one line naming the flag, exit code 2, nothing on stdout.

use std::process::{Command, Output};

fn mirage_refractivity(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mirage"))
        .arg("refractivity")
        .args(args)
        .output()
        .unwrap()
}

/// Runs with `args`, asserts success and one line on stdout, and parses it.
fn printed(args: &[&str]) -> f64 {
    let run = mirage_refractivity(args);
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{args:?}: {stderr}");
    assert_eq!(stdout.lines().count(), 1, "{stdout}");
    let text = stdout.trim();
    // At least 12 significant digits.
    let mantissa = text.split(['e', 'E']).next().unwrap();
    let digits = mantissa.chars().filter(char::is_ascii_digit).count();
    assert!(digits >= 12, "{text}");
    text.parse().unwrap()
}

#[test]
fn nist_procedure_at_633_nm_by_both_formulas() {
    // 633 nm, 20 °C, 101325 Pa, 20 % RH, 450 ppm: n = 1.0002716285340578 by
    // Ciddor, 1.000271629169165 by Edlén (NIST's appendix A procedure, as
    // computed by github.com/phn/ref_index, README).
    let flags = [
        "--temperature",
        "20",
        "--pressure",
        "101325",
        "--humidity",
        "0.2",
        "--wavelength",
        "633",
    ];
    let ciddor = printed(&[&flags[..], &["--co2", "450"]].concat());
    assert!((ciddor - 2.716285340578e-4).abs() < 1e-12, "{ciddor:e}");
    let also = printed(&[&flags[..], &["--formula", "ciddor"]].concat());
    assert_eq!(also, ciddor);
    let edlen = printed(&[&flags[..], &["--formula", "edlen"]].concat());
    assert!((edlen - 2.71629169165e-4).abs() < 1e-12, "{edlen:e}");
}

#[test]
fn defaults_are_dry_standard_air_at_550_nm() {
    // 15 °C, 101325 Pa, dry, 450 ppm, 550 nm: λ_air = 549.84723175 nm by Ciddor
    // (ref_index's vac2air, 8 decimals).
    let n1 = printed(&[]);
    assert!(
        (n1 - (550.0 / 549.847_231_75 - 1.0)).abs() < 3e-11,
        "{n1:e}"
    );
    // Negative temperatures are values, not flags; colder air refracts more.
    assert!(printed(&["--temperature", "-20"]) > n1);
    assert!(printed(&["--temperature=-20"]) > n1);
}

#[test]
fn outside_the_stated_range_warns_but_computes() {
    let run = mirage_refractivity(&["--temperature", "-100"]);
    assert!(run.status.success());
    assert_eq!(String::from_utf8_lossy(&run.stdout).lines().count(), 1);
    assert!(String::from_utf8_lossy(&run.stderr).contains("warning: --temperature"));
}

#[test]
fn bad_flags_exit_2_naming_the_flag() {
    for (flag, value) in [
        ("--humidity", "1.5"),
        ("--humidity", "-0.1"),
        ("--humidity", "50%"),
        ("--pressure", "0"),
        ("--pressure", "-5"),
        ("--pressure", "inf"),
        ("--wavelength", "299"),
        ("--wavelength", "1800"),
        ("--temperature", "warm"),
        ("--temperature", "-151"),
        ("--temperature", "100.5"),
        ("--temperature", "nan"),
        ("--co2", "-1"),
        ("--formula", "gladstone"),
    ] {
        let run = mirage_refractivity(&[flag, value]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{flag} {value}: {stderr}");
        assert!(run.stdout.is_empty(), "{flag} {value}: stdout not empty");
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(stderr.contains(flag), "{flag} not named: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    }
}
