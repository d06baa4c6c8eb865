//! Places and angles (`docs/geo.md`): the first byte picks what the rest is.
//!
//! - 0: an angle string, read by `str::parse::<Angle>` and as a JSON string
//!   (the two agree); a parsed angle is finite, and `format_dms` of it, seconds
//!   to 0.01″, reads back within 0.005″ (plus the f64 rounding of the degrees)
//!   and prints the same again.
//! - 1: `arbitrary` numbers (mostly in range, some at the edges, some any
//!   f64): a site and geographic points read from JSON objects, the geodesic
//!   from the site, points placed over the site's sphere or an `earth` of any
//!   valid radius, the horizon there, and pairs resolved from `through` or from
//!   `elevation`/`azimuth` (numbers or degree-minute-second strings), over the
//!   round earth and the flat ground; the same pair in a whole problem file.
//!   Placing never panics, and either refuses by a named field or gives
//!   finite coordinates at the right distance from the sphere's centre.
//! - 2: a problem file (a `site` and geographic points), as the `problem`
//!   target, its resolved pairs finite.
#![no_main]

#[path = "common.rs"]
mod common;

use arbitrary::{Arbitrary, Unstructured};
use libfuzzer_sys::fuzz_target;
use mirage::error::FieldError;
use mirage::geo::{Angle, GeoPoint, Horizon, Point, Site, format_dms};
use mirage::pair::PairEntry;
use mirage::problem::Problem;
use mirage::trace::{Earth, EarthSpec};
use serde_json::{Value, json};
use std::path::Path;

/// 0.005″ in degrees: half the last place `format_dms` prints.
const HALF_HUNDREDTH_SECOND: f64 = 0.005 / 3600.0;

fuzz_target!(|data: &[u8]| {
    let [pick, rest @ ..] = data else {
        return;
    };
    match pick % 3 {
        0 => {
            if let Ok(text) = std::str::from_utf8(rest) {
                check_angle_text(text);
            }
        }
        1 => {
            if let Ok(case) = Case::arbitrary_take_rest(Unstructured::new(rest)) {
                check_case(&case);
            }
        }
        _ => {
            if let Ok(text) = std::str::from_utf8(rest) {
                check_problem_text(text);
            }
        }
    }
});

/// A refusal of a part (a site, a point, a pair): a field and a message.
fn check_field_error(e: &FieldError) {
    assert!(!e.path.is_empty(), "no field named: {e}");
    assert!(!e.message.is_empty(), "no message: {e}");
}

/// `text` as an angle: `parse` and serde (a JSON string) agree; an angle is
/// finite and its `format_dms` reads back.
fn check_angle_text(text: &str) {
    let parsed = text.parse::<Angle>();
    let quoted = serde_json::to_string(text).unwrap();
    let from_json = serde_json::from_str::<Angle>(&quoted);
    match (&parsed, &from_json) {
        (Ok(a), Ok(b)) => assert_eq!(a.degrees.to_bits(), b.degrees.to_bits(), "{text:?}"),
        (Err(e), Err(j)) => {
            let shown = e.to_string();
            assert!(shown.contains("is not an angle"), "{text:?}: {shown}");
            assert!(!j.to_string().is_empty());
        }
        _ => panic!("{text:?}: parse {parsed:?} but JSON {from_json:?}"),
    }
    if let Ok(a) = parsed {
        check_angle(a.degrees, text);
    }
    // The text as a JSON value (a number, a string, anything else): an angle
    // read from it is finite.
    if let Ok(a) = serde_json::from_str::<Angle>(text) {
        assert!(a.degrees.is_finite(), "{text:?} read as {a:?}");
        check_angle(a.degrees, text);
    }
}

/// A finite angle, printed by `format_dms` and read back.
fn check_angle(degrees: f64, text: &str) {
    assert!(degrees.is_finite(), "{text:?} read as {degrees}");
    let shown = format_dms(degrees);
    let back = shown
        .parse::<Angle>()
        .unwrap_or_else(|e| panic!("{text:?} = {degrees}° printed as {shown:?}, which fails: {e}"));
    // Rounded to 0.01″, then d + m/60 + s/3600 and |degrees|·360000 each
    // round once or twice more in f64.
    let tolerance = HALF_HUNDREDTH_SECOND * (1.0 + 1e-9) + 8.0 * f64::EPSILON * degrees.abs();
    assert!(
        (back.degrees - degrees).abs() <= tolerance,
        "{text:?} = {degrees}° printed as {shown:?}, read back as {}° ({}″ off)",
        back.degrees,
        (back.degrees - degrees).abs() * 3600.0
    );
    // Printing what was read back gives the same string (where f64 resolves
    // 0.01″ with room to spare), but for the sign of an angle printed as
    // `-0°00′00.00″`, which reads back as −0 and prints without it.
    if degrees.abs() <= 1.0e6 {
        let again = format_dms(back.degrees);
        let zero = back.degrees == 0.0
            && again.trim_start_matches('-') == "0°00′00.00″"
            && shown.trim_start_matches('-') == "0°00′00.00″";
        assert!(
            again == shown || zero,
            "{text:?} = {degrees}° printed as {shown:?}, then as {again:?}"
        );
    }
}

/// Degrees: mostly inside ±400, some at the edges, some any f64.
#[derive(Debug, Clone, Copy)]
struct Deg(f64);

const EDGES: [f64; 14] = [
    0.0,
    -0.0,
    90.0,
    -90.0,
    180.0,
    -180.0,
    360.0,
    -360.0,
    89.999_999_999_999,
    -179.999_999_999,
    1.0e-9,
    5.0e-324,
    f64::MIN_POSITIVE,
    1.0e-300,
];

impl<'a> Arbitrary<'a> for Deg {
    fn arbitrary(u: &mut Unstructured<'a>) -> arbitrary::Result<Self> {
        Ok(Deg(match u.int_in_range(0u8..=7)? {
            0 => f64::arbitrary(u)?,
            1 => *u.choose(&EDGES)? * if bool::arbitrary(u)? { -1.0 } else { 1.0 },
            // Near an edge: a few ulps or a small step away.
            2 => {
                let e = *u.choose(&EDGES)?;
                e + f64::from(i8::arbitrary(u)?) * 10f64.powi(u.int_in_range(-15i32..=0)?)
            }
            _ => (f64::from(u32::arbitrary(u)?) / f64::from(u32::MAX) * 2.0 - 1.0) * 400.0,
        }))
    }
}

/// Metres: mostly inside the heights allowed, some at the edges, some any f64.
#[derive(Debug, Clone, Copy)]
struct Height(f64);

impl<'a> Arbitrary<'a> for Height {
    fn arbitrary(u: &mut Unstructured<'a>) -> arbitrary::Result<Self> {
        Ok(Height(match u.int_in_range(0u8..=5)? {
            0 => f64::arbitrary(u)?,
            1 => *u.choose(&[0.0, -11_000.0, 100_000.0, -10_999.999, 1.5, 23.42])?,
            _ => f64::from(u32::arbitrary(u)?) / f64::from(u32::MAX) * 111_000.0 - 11_000.0,
        }))
    }
}

/// An earth: none (the site's Gaussian radius), or `{"radius": R}` of mostly
/// valid radii (a kilometre to 10¹⁵ m), some any f64.
#[derive(Debug, Clone, Copy)]
struct Radius(Option<f64>);

impl<'a> Arbitrary<'a> for Radius {
    fn arbitrary(u: &mut Unstructured<'a>) -> arbitrary::Result<Self> {
        Ok(Radius(match u.int_in_range(0u8..=5)? {
            0 | 1 => None,
            2 => Some(f64::arbitrary(u)?),
            3 => Some(*u.choose(&[1000.0, 1.0e15, 6.371e6, 999.999, 11_000.0])?),
            _ => Some(10f64.powf(3.0 + 12.0 * f64::from(u16::arbitrary(u)?) / 65535.0)),
        }))
    }
}

#[derive(Arbitrary, Debug, Clone, Copy)]
struct Place {
    latitude: Deg,
    longitude: Deg,
    /// Absent: the default (0).
    height: Option<Height>,
}

impl Place {
    fn json(&self) -> Value {
        let mut v = json!({"latitude": self.latitude.0, "longitude": self.longitude.0});
        if let Some(h) = self.height {
            v["height"] = json!(h.0);
        }
        v
    }
}

#[derive(Arbitrary, Debug, Clone, Copy)]
enum PointCase {
    Local([Height; 3]),
    Geo(Place),
}

impl PointCase {
    fn json(&self) -> Value {
        match self {
            PointCase::Local(v) => json!([v[0].0, v[1].0, v[2].0]),
            PointCase::Geo(p) => p.json(),
        }
    }
}

#[derive(Arbitrary, Debug, Clone)]
enum AngleCase {
    Number(Deg),
    /// The number as `format_dms` prints it.
    Dms(Deg),
    Text(String),
}

impl AngleCase {
    fn json(&self) -> Value {
        match self {
            AngleCase::Number(d) => json!(d.0),
            AngleCase::Dms(d) => json!(format_dms(d.0)),
            AngleCase::Text(s) => json!(s),
        }
    }
}

#[derive(Arbitrary, Debug, Clone)]
enum Sight {
    Through(PointCase),
    Angles {
        elevation: Option<AngleCase>,
        azimuth: Option<AngleCase>,
    },
}

#[derive(Arbitrary, Debug, Clone)]
struct PairCase {
    origin: PointCase,
    target: PointCase,
    sight: Sight,
}

impl PairCase {
    fn json(&self) -> Value {
        let mut v = json!({"origin": self.origin.json(), "target": self.target.json()});
        match &self.sight {
            Sight::Through(t) => v["through"] = t.json(),
            Sight::Angles { elevation, azimuth } => {
                if let Some(e) = elevation {
                    v["elevation"] = e.json();
                }
                if let Some(a) = azimuth {
                    v["azimuth"] = a.json();
                }
            }
        }
        v
    }
}

#[derive(Arbitrary, Debug)]
struct Case {
    /// Absent: a file without a site.
    site: Option<Place>,
    earth: Radius,
    points: [Place; 2],
    pairs: Vec<PairCase>,
}

/// Reads `v` as `T` the way a file would be; `None` when serde refuses it.
fn read<T: serde::de::DeserializeOwned>(v: &Value) -> Option<T> {
    serde_json::from_str(&v.to_string()).ok()
}

fn check_case(case: &Case) {
    let site: Option<Site> = case.site.and_then(|s| read(&s.json()));
    let site = site.filter(|s| match s.validate() {
        Ok(()) => true,
        Err(e) => {
            check_field_error(&e);
            false
        }
    });
    let spec: Option<EarthSpec> = case.earth.0.and_then(|r| read(&json!({"radius": r})));
    let spec = spec.filter(|e| match e.validate() {
        Ok(()) => true,
        Err(e) => {
            check_field_error(&e);
            false
        }
    });
    let earth = match (spec, site) {
        (Some(e), _) => Earth::Round { radius: e.radius },
        (None, Some(s)) => {
            let r = s.gaussian_radius();
            assert!((6.356e6..6.4e6).contains(&r), "{s:?}: Gaussian radius {r}");
            Earth::Round { radius: r }
        }
        (None, None) => Earth::Flat,
    };

    for place in &case.points {
        let Some(g) = read::<GeoPoint>(&place.json()) else {
            continue;
        };
        let p: Point = read(&place.json()).expect("a GeoPoint that serde read is a Point");
        assert_eq!(p, Point::Geo(g));
        if let Err(e) = g.validate() {
            check_field_error(&e);
            let e = p.resolve(site.as_ref(), 6.371e6).unwrap_err();
            check_field_error(&e);
            continue;
        }
        let Some(s) = site else {
            let e = p.resolve(None, 6.371e6).unwrap_err();
            check_field_error(&e);
            continue;
        };
        let (distance, azimuth) = s.geodesic_to(&g);
        // Half the meridian of WGS 84 is 20,003,931.5 m, the longest geodesic.
        assert!(
            (0.0..=20_003_932.0).contains(&distance) && (-180.0..=180.0).contains(&azimuth),
            "{s:?} to {g:?}: distance {distance}, azimuth {azimuth}"
        );
        for e in [earth, Earth::Flat] {
            let radius = match e {
                Earth::Round { radius } => radius,
                Earth::Flat => f64::INFINITY,
            };
            let x = p
                .resolve(Some(&s), radius)
                .unwrap_or_else(|err| panic!("{s:?}: valid {g:?} refused: {err}"));
            assert!(
                x.iter().all(|c| c.is_finite()),
                "{g:?} from {s:?} over {e:?}: {x:?}"
            );
            match e {
                Earth::Round { radius } => {
                    // On the sphere of radius + height about (0, −radius, 0).
                    let c = [x[0], x[1] + radius, x[2]];
                    let n = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
                    let want = (radius + g.height).abs();
                    assert!(
                        (n - want).abs() <= 1e-9 * (radius + g.height.abs()),
                        "{g:?} from {s:?} over {e:?}: {x:?} is {n} m from the centre, not {want}"
                    );
                }
                Earth::Flat => {
                    // The geodesic's length along the plane, at its height.
                    let along = x[0].hypot(x[2]);
                    assert!(
                        (along - distance).abs() <= 1e-9 * (distance + 1.0) && x[1] == g.height,
                        "{g:?} from {s:?} over the flat ground: {x:?}, not {distance} m away"
                    );
                }
            }
            let round = match e {
                Earth::Round { radius } => Some(radius),
                Earth::Flat => None,
            };
            check_horizon(x, round);
        }
    }

    for (i, pair) in case.pairs.iter().take(4).enumerate() {
        let Some(entry) = read::<PairEntry>(&pair.json()) else {
            continue;
        };
        if let Point::Local(o) = entry.origin {
            check_horizon(o, Some(6.371e6));
            check_horizon(o, None);
        }
        let mut earths = vec![earth];
        if site.is_none() {
            earths.push(Earth::Round { radius: 6.371e6 });
        } else {
            earths.push(Earth::Flat);
        }
        for e in earths {
            match entry.resolve(site.as_ref(), e) {
                Ok(p) => {
                    let all = p.origin.iter().chain(&p.through).chain(&p.target);
                    for c in all {
                        assert!(c.is_finite(), "pair {i} {entry:?} over {e:?}: {p:?}");
                    }
                    match p.validate().and_then(|()| p.validate_on(e)) {
                        Ok(()) => {
                            let d = p.direction();
                            assert!((d.norm() - 1.0).abs() < 1e-9, "pair {i}: {d:?} of {p:?}");
                        }
                        Err(err) => check_field_error(&err),
                    }
                }
                Err(err) => check_field_error(&err),
            }
        }
    }

    // The same pairs in a problem file.
    let mut file = json!({
        "medium": {"air": {"temperature": {"base": 15.0, "lapse": -0.0065},
                   "pressure": 101325.0, "humidity": 0.0}},
        "residual": "angle",
        "pairs": case.pairs.iter().take(4).map(PairCase::json).collect::<Vec<_>>(),
    });
    if let Some(s) = case.site {
        file["site"] = s.json();
    }
    if let Some(r) = case.earth.0 {
        file["earth"] = json!({"radius": r});
    }
    check_problem_text(&file.to_string());
}

/// The horizon at `x`: refused by name, or up, north and east unit vectors.
fn check_horizon(x: [f64; 3], radius: Option<f64>) {
    match Horizon::at(x, radius) {
        Ok(h) => {
            for v in [h.up, h.north, h.east] {
                let n = v[0].hypot(v[1]).hypot(v[2]);
                assert!(
                    (n - 1.0).abs() < 1e-9,
                    "{x:?} over {radius:?}: horizon {h:?}"
                );
            }
        }
        Err(err) => check_field_error(&err),
    }
}

/// A problem file: refused by a named field, or its pairs finite.
fn check_problem_text(text: &str) {
    match Problem::parse(text, Path::new("fuzz.json")) {
        Ok(p) => {
            for (i, pair) in p.pairs.iter().enumerate() {
                let all = pair.origin.iter().chain(&pair.through).chain(&pair.target);
                for c in all {
                    assert!(c.is_finite(), "pair {i}: {pair:?}");
                }
                assert!(pair.weight.is_finite(), "pair {i}: {pair:?}");
                let d = pair.direction();
                assert!(
                    (d.norm() - 1.0).abs() < 1e-9,
                    "pair {i}: direction {d:?} of {pair:?}"
                );
            }
        }
        Err(e) => common::check_error(&e),
    }
}
