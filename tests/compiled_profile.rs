//! The compiled profile of real air (`src/medium/compiled.rs`) against the
//! formula it was compiled from, over seeded random media: every kind of
//! temperature term (lapse, US 1976 layers, surface layer, inversion) or a
//! measured table, one humidity or a table, the three formulas, hydrostatic
//! or constant pressure, over the flat ground and the round earth. At random
//! heights, wherever the profile answers: |δ̃ − δ| ≤ 1e-12·|δ| and
//! |∇δ̃ − ∇δ| ≤ 1e-12·max(|∇δ|, |δ|/1 km).

use mirage::math::V3;
use mirage::medium::compiled::{BOUND, SLOPE_SCALE};
use mirage::medium::{Field, IndexField, Medium};
use mirage::trace::OnEarth;

/// A 64-bit LCG: uniform numbers in [0, 1).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * self.next()
    }
    fn coin(&mut self) -> bool {
        self.next() < 0.5
    }
}

/// Rows `[h, value]` rising from `h0` with random gaps, values from `v`.
fn rows(rng: &mut Rng, h0: f64, mut v: impl FnMut(&mut Rng) -> f64) -> String {
    let n = 3 + (rng.next() * 6.0) as usize;
    let mut h = h0;
    let mut out = Vec::new();
    for _ in 0..n {
        out.push(format!("[{h}, {}]", v(rng)));
        h += rng.range(0.2, 400.0);
    }
    format!("[{}]", out.join(", "))
}

/// One random real-air medium, as a file gives it.
fn random_air(rng: &mut Rng) -> String {
    let temperature = if rng.next() < 0.25 {
        let h0 = rng.range(-5.0, 2.0);
        let t = rows(rng, h0, |r| r.range(-5.0, 40.0));
        format!(r#"{{"table": {t}}}"#)
    } else {
        let mut terms = vec![format!(r#""base": {}"#, rng.range(-10.0, 35.0))];
        match (rng.next() * 3.0) as u32 {
            0 => terms.push(format!(r#""lapse": {}"#, rng.range(-0.0098, 0.01))),
            1 => terms.push(r#""lapse": "standard""#.to_string()),
            _ => {}
        }
        if rng.coin() {
            terms.push(format!(
                r#""exponential": {{"delta": {}, "scale_height": {}}}"#,
                rng.range(-6.0, 15.0),
                rng.range(0.05, 30.0)
            ));
        }
        if rng.coin() {
            terms.push(format!(
                r#""inversion": {{"delta": {}, "height": {}, "thickness": {}}}"#,
                rng.range(-5.0, 10.0),
                rng.range(2.0, 800.0),
                rng.range(0.5, 60.0)
            ));
        }
        format!("{{{}}}", terms.join(", "))
    };
    let humidity = if rng.next() < 0.3 {
        let h0 = rng.range(-5.0, 2.0);
        let t = rows(rng, h0, |r| r.range(0.0, 1.0));
        format!(r#"{{"table": {t}}}"#)
    } else {
        format!("{}", rng.range(0.0, 1.0))
    };
    let formula = match (rng.next() * 3.0) as u32 {
        0 => r#""ciddor""#.to_string(),
        1 => r#""edlen""#.to_string(),
        _ => format!(r#"{{"gladstone_dale": {}}}"#, rng.range(0.07, 0.09)),
    };
    format!(
        r#"{{"air": {{"temperature": {temperature}, "pressure": {}, "hydrostatic": {},
             "humidity": {humidity}, "wavelength": {}, "co2": {},
             "refractivity": {formula}}}}}"#,
        rng.range(80_000.0, 105_000.0),
        rng.next() < 0.8,
        rng.range(380.0, 1000.0),
        rng.range(300.0, 600.0),
    )
}

/// A random height: mostly near the ground, where mirages are.
fn height(rng: &mut Rng, lo: f64, hi: f64) -> f64 {
    match (rng.next() * 4.0) as u32 {
        0 => rng.range(lo, 0.0),
        1 => rng.range(0.0, 30.0),
        2 => rng.range(0.0, 3000.0),
        _ => rng.range(lo, hi),
    }
}

fn norm(v: V3) -> f64 {
    (v.x * v.x + v.y * v.y + v.z * v.z).sqrt()
}

#[test]
fn the_compiled_profile_is_the_formula_to_1e_12_over_random_media() {
    let mut rng = Rng(0x005e_ed41);
    let (mut answered, mut media) = (0usize, 0usize);
    let (mut most_pieces, mut most_exact) = (0usize, 0usize);
    while media < 48 {
        let json = random_air(&mut rng);
        let medium: Medium = serde_json::from_str(&json).unwrap_or_else(|e| panic!("{e}: {json}"));
        if medium.validate().is_err() {
            continue;
        }
        media += 1;
        let Field::Air(field) = medium.field() else {
            unreachable!()
        };
        let profile = field
            .profile()
            .expect("plain air without hot spots compiles");
        let (lo, hi) = profile.range();
        let (pieces, exact) = profile.pieces();
        // A piece that cannot pass down to 0.1 mm (a kink nobody named: the
        // saturation pressure's step at 0 °C) is left to the formula, and
        // there the bound holds by itself.
        assert!(pieces > exact, "{pieces} pieces, {exact} exact: {json}");
        // Every kink is a knot (the US 1976 layers, the tables' rows, 0 °C):
        // a few hundred pieces, at most two left to the formula (four without
        // the 0 °C knots).
        assert!(
            pieces < 1000 && exact <= 2,
            "{pieces} pieces, {exact} left to the formula at {:?}: {json}",
            profile.formula_spans()
        );
        most_pieces = most_pieces.max(pieces);
        most_exact = most_exact.max(exact);
        let formula = field.clone().without_profile();
        let round = rng.coin();
        let radius = if round { 6_371_000.0 } else { 0.0 };
        for _ in 0..400 {
            let h = height(&mut rng, lo, hi);
            let (d, g, d0, g0) = if round {
                // A point over the sphere at height ≈ h, some km out.
                let (x, z) = (rng.range(-20e3, 20e3), rng.range(-20e3, 20e3));
                let y = h - (x * x + z * z) / (2.0 * radius);
                let p = V3::new(x, y, z);
                let c = OnEarth {
                    field: &field,
                    radius,
                };
                let f = OnEarth {
                    field: &formula,
                    radius,
                };
                let ((d, g), (d0, g0)) = (c.delta_gradient(p), f.delta_gradient(p));
                (d, g, d0, g0)
            } else {
                let p = V3::new(rng.range(-1e3, 1e3), h, rng.range(-1e3, 1e3));
                let ((d, g), (d0, g0)) = (field.delta_gradient(p), formula.delta_gradient(p));
                (d, g, d0, g0)
            };
            if profile.eval(h).is_some() {
                answered += 1;
            }
            assert!(
                (d - d0).abs() <= BOUND * d0.abs(),
                "δ at h = {h}: {d} against {d0} ({json})"
            );
            let dg = norm(V3::new(g.x - g0.x, g.y - g0.y, g.z - g0.z));
            assert!(
                dg <= BOUND * norm(g0).max(d0.abs() / SLOPE_SCALE),
                "∇δ at h = {h}: {g:?} against {g0:?} ({json})"
            );
        }
    }
    // Most heights are the profile's (not the formula's fallback).
    println!(
        "{media} media: {answered} of {} heights answered by the profile; at most {most_pieces} pieces, {most_exact} left to the formula",
        media * 400
    );
    assert!(answered > 48 * 400 / 2, "{answered}");
}

#[test]
fn dual_numbers_and_hot_spots_evaluate_the_formula() {
    let medium: Medium = serde_json::from_str(
        r#"{"air": {"temperature": {"base": 12.0, "lapse": "standard"}, "humidity": 0.5},
            "hotspots": [{"x": 0.0, "z": 0.0, "radius": 5.0, "delta": 3.0, "scale_height": 1.0}]}"#,
    )
    .unwrap();
    let Field::Air(field) = medium.field() else {
        unreachable!()
    };
    assert!(field.profile().is_none(), "air with hot spots");
    let dual = medium.map(|_, v| num_dual::Dual64::from(v));
    let Field::Air(field) = dual.field() else {
        unreachable!()
    };
    assert!(field.profile().is_none(), "dual numbers");
}
