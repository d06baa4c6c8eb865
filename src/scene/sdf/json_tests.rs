use super::*;
use proptest::prelude::*;

// The JSON and validation tests: the schema (tags, unknown fields), round
// trips and the field paths of validation errors.

fn v3(lo: f64, hi: f64) -> impl Strategy<Value = DVec3> {
    (lo..hi, lo..hi, lo..hi).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

// ---- JSON ----------------------------------------------------------------

/// The example from the module documentation.
const DOC_EXAMPLE: &str = r#"[
  { "name": "ground", "albedo": [0.3, 0.25, 0.2],
    "shape": { "type": "plane", "normal": [0, 1, 0], "offset": 0 } },
  { "name": "pole", "albedo": [0.8, 0.8, 0.8],
    "shape": { "type": "cylinder", "center": [1000, 2, 0],
               "radius": 0.025, "half_height": 2 } },
  { "name": "sign", "albedo": [0.9, 0.1, 0.1],
    "shape": { "type": "translate", "offset": [1000, 4.5, 0],
               "child": { "type": "rotate", "axis": [0, 1, 0], "degrees": 30,
                          "child": { "type": "smooth_union", "k": 0.05,
                                     "children": [
                                       { "type": "rounded_box", "center": [0, 0, 0],
                                         "half_extents": [0.5, 0.3, 0.02], "radius": 0.01 },
                                       { "type": "capsule", "a": [0, -0.5, 0],
                                         "b": [0, 0, 0], "radius": 0.025 } ] } } } }
]"#;

fn nested_scene() -> Vec<SceneObject> {
    let board = Sdf::smooth_union(
        vec![
            Sdf::rounded_box(DVec3::ZERO, DVec3::new(0.5, 0.3, 0.02), 0.01),
            Sdf::capsule(DVec3::new(0.0, -0.5, 0.0), DVec3::ZERO, 0.025),
        ],
        0.05,
    );
    vec![
        SceneObject {
            name: Some("ground".into()),
            albedo: [0.3, 0.25, 0.2],
            shape: Sdf::plane(DVec3::new(0.0, 1.0, 0.0), 0.0),
        },
        SceneObject {
            name: Some("pole".into()),
            albedo: [0.8, 0.8, 0.8],
            shape: Sdf::cylinder(DVec3::new(1000.0, 2.0, 0.0), 0.025, 2.0),
        },
        SceneObject {
            name: Some("sign".into()),
            albedo: [0.9, 0.1, 0.1],
            shape: Sdf::translate(
                DVec3::new(1000.0, 4.5, 0.0),
                Sdf::rotate(DVec3::Y, 30.0, board),
            ),
        },
    ]
}

#[test]
fn doc_example_parses_and_matches_builders() {
    let parsed: Vec<SceneObject> = serde_json::from_str(DOC_EXAMPLE).unwrap();
    validate_objects(&parsed).unwrap();
    assert_eq!(parsed, nested_scene());
}

#[test]
fn json_round_trip_of_nested_scene() {
    let mut scene = nested_scene();
    // Every variant, nested, with awkward numbers.
    scene.push(SceneObject {
        name: None,
        albedo: [0.1, 0.2, 0.3],
        shape: Sdf::scale(
            1.7,
            Sdf::difference(
                Sdf::intersection(vec![
                    Sdf::sphere(DVec3::new(0.1, -0.2, 1.0 / 3.0), 2.0f64.sqrt()),
                    Sdf::cuboid(DVec3::ZERO, DVec3::new(1.0, 2.0, 3.0)),
                    Sdf::torus(DVec3::Y, 1.0, 0.25),
                ]),
                Sdf::union(vec![
                    Sdf::cylinder(DVec3::ZERO, 0.3, 5.0),
                    Sdf::plane(DVec3::new(1.0, 1.0, 0.0), -0.7),
                    Sdf::rotate(DVec3::new(1.0, 2.0, 3.0), 17.3, Sdf::sphere(DVec3::X, 0.1)),
                ]),
            ),
        ),
    });
    validate_objects(&scene).unwrap();
    let json = serde_json::to_string_pretty(&scene).unwrap();
    let back: Vec<SceneObject> = serde_json::from_str(&json).unwrap();
    assert_eq!(back, scene);
    // and the tags are what the docs say
    for tag in [
        "\"plane\"",
        "\"cylinder\"",
        "\"translate\"",
        "\"rotate\"",
        "\"smooth_union\"",
        "\"rounded_box\"",
        "\"capsule\"",
        "\"scale\"",
        "\"difference\"",
        "\"intersection\"",
        "\"sphere\"",
        "\"box\"",
        "\"torus\"",
        "\"union\"",
    ] {
        assert!(json.contains(tag), "missing {tag} in {json}");
    }
    // a value re-serialized is identical text
    assert_eq!(serde_json::to_string_pretty(&back).unwrap(), json);
    // the plane keeps the normal as written, normalises for evaluation
    let p: Sdf = serde_json::from_str(r#"{"type":"plane","normal":[0,2,0],"offset":1}"#).unwrap();
    assert!(close(p.distance(DVec3::new(5.0, 3.0, 1.0)), 2.0, 1e-15));
    assert!(serde_json::to_string(&p).unwrap().contains("[0.0,2.0,0.0]"));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn json_round_trip_random_numbers(
        c in v3(-1e4, 1e4), r in 1e-3f64..1e3, axis in v3(-1.0, 1.0), deg in -720.0f64..720.0,
        f in 1e-3f64..1e3, k in 1e-3f64..1.0
    ) {
        let s = Sdf::scale(f, Sdf::rotate(axis, deg, Sdf::smooth_union(vec![
            Sdf::sphere(c, r), Sdf::capsule(c, -c, r), Sdf::plane(axis, r)], k)));
        let back: Sdf = serde_json::from_str(&serde_json::to_string(&s).unwrap()).unwrap();
        prop_assert_eq!(back, s);
    }
}

fn parse_err(json: &str) -> String {
    match serde_json::from_str::<Vec<SceneObject>>(json) {
        Ok(v) => panic!("expected an error, parsed {v:?}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn unknown_fields_are_rejected_everywhere() {
    let cases = [
        // struct variant (enum-level deny_unknown_fields)
        (
            r#"[{"albedo":[0,0,0],"shape":{"type":"sphere","center":[0,0,0],"radius":1,"colour":3}}]"#,
            "colour",
        ),
        // nested inside a combinator
        (
            r#"[{"albedo":[0,0,0],"shape":{"type":"union","children":[
                {"type":"box","center":[0,0,0],"half_extents":[1,1,1]},
                {"type":"cylinder","center":[0,0,0],"radius":1,"half_height":1,"height":2}]}}]"#,
            "height",
        ),
        // newtype variants (spec struct's deny_unknown_fields)
        (
            r#"[{"albedo":[0,0,0],"shape":{"type":"plane","normal":[0,1,0],"offset":0,"d":1}}]"#,
            "`d`",
        ),
        (
            r#"[{"albedo":[0,0,0],"shape":{"type":"rotate","axis":[0,1,0],"degrees":3,"radians":1,
                "child":{"type":"sphere","center":[0,0,0],"radius":1}}}]"#,
            "radians",
        ),
        (
            r#"[{"albedo":[0,0,0],"shape":{"type":"scale","factor":2,"factors":[1,2,3],
                "child":{"type":"sphere","center":[0,0,0],"radius":1}}}]"#,
            "factors",
        ),
        // a misspelt field in the deepest level
        (
            r#"[{"albedo":[0,0,0],"shape":{"type":"translate","offset":[0,0,0],
                "child":{"type":"smooth_union","k":0.1,"children":[
                {"type":"torus","center":[0,0,0],"major_radius":1,"minor_radus":0.1}]}}}]"#,
            "minor_radus",
        ),
        // the scene object itself
        (
            r#"[{"albedo":[0,0,0],"colour":[1,1,1],"shape":{"type":"sphere","center":[0,0,0],"radius":1}}]"#,
            "colour",
        ),
    ];
    for (json, name) in cases {
        let e = parse_err(json);
        assert!(e.contains("unknown field"), "{e}");
        assert!(e.contains(name), "message {e:?} lacks {name}");
    }
}

#[test]
fn unknown_or_missing_type_is_rejected() {
    let e = parse_err(r#"[{"albedo":[0,0,0],"shape":{"type":"blob","radius":1}}]"#);
    assert!(e.contains("unknown variant") && e.contains("blob"), "{e}");
    let e = parse_err(r#"[{"albedo":[0,0,0],"shape":{"center":[0,0,0],"radius":1}}]"#);
    assert!(e.contains("missing field `type`"), "{e}");
    let e = parse_err(r#"[{"albedo":[0,0,0],"shape":{"type":"sphere","center":[0,0,0]}}]"#);
    assert!(e.contains("missing field `radius`"), "{e}");
    // tags are snake_case only
    let e = parse_err(
        r#"[{"albedo":[0,0,0],"shape":{"type":"RoundedBox","center":[0,0,0],"half_extents":[1,1,1],"radius":0.1}}]"#,
    );
    assert!(e.contains("RoundedBox"), "{e}");
}

// ---- validation ------------------------------------------------------------

#[test]
fn validation_names_the_path() {
    let json = r#"[
      {"albedo":[0,0,0],"shape":{"type":"plane","normal":[0,1,0],"offset":0}},
      {"albedo":[0,0,0],"shape":{"type":"sphere","center":[0,0,0],"radius":1}},
      {"albedo":[0,0,0],"shape":{"type":"union","children":[
          {"type":"sphere","center":[0,0,0],"radius":1},
          {"type":"sphere","center":[0,0,0],"radius":-1}]}}
    ]"#;
    let objects: Vec<SceneObject> = serde_json::from_str(json).unwrap();
    assert_eq!(
        validate_objects(&objects)
            .unwrap_err()
            .within("objects")
            .to_string(),
        "objects[2].shape.children[1].radius: must be > 0, got -1"
    );
}

#[test]
fn validation_rejects_each_bad_parameter() {
    let ok = || Sdf::sphere(DVec3::ZERO, 1.0);
    let cases: Vec<(Sdf, &str)> = vec![
        (
            Sdf::sphere(DVec3::ZERO, 0.0),
            "s.radius: must be > 0, got 0",
        ),
        (
            Sdf::sphere(DVec3::new(0.0, f64::NAN, 0.0), 1.0),
            "s.center[1]: must be finite, got NaN",
        ),
        (
            Sdf::sphere(DVec3::ZERO, f64::INFINITY),
            "s.radius: must be finite, got inf",
        ),
        (
            Sdf::cuboid(DVec3::ZERO, DVec3::new(1.0, 1.0, -2.0)),
            "s.half_extents[2]: must be > 0, got -2",
        ),
        (
            Sdf::rounded_box(DVec3::ZERO, DVec3::new(1.0, 0.5, 1.0), 0.0),
            "s.radius: must be > 0, got 0",
        ),
        (
            Sdf::rounded_box(DVec3::ZERO, DVec3::new(1.0, 0.5, 1.0), 0.75),
            "s.radius: must be <= the smallest half extent (0.5), got 0.75",
        ),
        (
            Sdf::plane(DVec3::ZERO, 1.0),
            "s.normal: must be a non-zero vector, got [0, 0, 0]",
        ),
        (
            Sdf::plane(DVec3::new(f64::INFINITY, 0.0, 0.0), 1.0),
            "s.normal[0]: must be finite, got inf",
        ),
        (
            Sdf::plane(DVec3::Y, f64::NAN),
            "s.offset: must be finite, got NaN",
        ),
        (
            Sdf::torus(DVec3::ZERO, -1.0, 0.5),
            "s.major_radius: must be > 0, got -1",
        ),
        (
            Sdf::torus(DVec3::ZERO, 1.0, 0.0),
            "s.minor_radius: must be > 0, got 0",
        ),
        (
            Sdf::torus(DVec3::ZERO, 1.0, 1.5),
            "s.minor_radius: must be <= major_radius (1), got 1.5",
        ),
        (
            Sdf::cylinder(DVec3::ZERO, 1.0, 0.0),
            "s.half_height: must be > 0, got 0",
        ),
        (
            Sdf::cylinder(DVec3::ZERO, -0.1, 1.0),
            "s.radius: must be > 0, got -0.1",
        ),
        (
            Sdf::capsule(DVec3::ZERO, DVec3::new(0.0, 0.0, f64::NAN), 1.0),
            "s.b[2]: must be finite, got NaN",
        ),
        (
            Sdf::capsule(DVec3::ZERO, DVec3::X, -3.0),
            "s.radius: must be > 0, got -3",
        ),
        (
            Sdf::union(vec![]),
            "s.children: must contain at least one shape",
        ),
        (
            Sdf::intersection(vec![]),
            "s.children: must contain at least one shape",
        ),
        (
            Sdf::smooth_union(vec![], 0.1),
            "s.children: must contain at least one shape",
        ),
        (
            Sdf::smooth_union(vec![ok()], 0.0),
            "s.k: must be > 0, got 0",
        ),
        (
            Sdf::smooth_union(vec![ok()], -0.5),
            "s.k: must be > 0, got -0.5",
        ),
        (
            Sdf::difference(ok(), Sdf::sphere(DVec3::ZERO, -1.0)),
            "s.subtract.radius: must be > 0, got -1",
        ),
        (
            Sdf::difference(Sdf::union(vec![]), ok()),
            "s.base.children: must contain at least one shape",
        ),
        (
            Sdf::translate(DVec3::new(f64::NAN, 0.0, 0.0), ok()),
            "s.offset[0]: must be finite, got NaN",
        ),
        (
            Sdf::translate(DVec3::ZERO, Sdf::sphere(DVec3::ZERO, 0.0)),
            "s.child.radius: must be > 0, got 0",
        ),
        (
            Sdf::rotate(DVec3::ZERO, 10.0, ok()),
            "s.axis: must be a non-zero vector, got [0, 0, 0]",
        ),
        (
            Sdf::rotate(DVec3::Y, f64::NAN, ok()),
            "s.degrees: must be finite, got NaN",
        ),
        (Sdf::scale(0.0, ok()), "s.factor: must be > 0, got 0"),
        (Sdf::scale(-2.0, ok()), "s.factor: must be > 0, got -2"),
        (
            Sdf::scale(
                2.0,
                Sdf::rotate(
                    DVec3::X,
                    5.0,
                    Sdf::union(vec![ok(), Sdf::smooth_union(vec![ok()], -1.0)]),
                ),
            ),
            "s.child.child.children[1].k: must be > 0, got -1",
        ),
    ];
    for (s, msg) in cases {
        assert_eq!(s.validate().unwrap_err().within("s").to_string(), msg);
    }
    // empty prefix: no leading dot
    assert_eq!(
        Sdf::sphere(DVec3::ZERO, -1.0)
            .validate()
            .unwrap_err()
            .to_string(),
        "radius: must be > 0, got -1"
    );
    assert!(nested_scene()[2].shape.validate().is_ok());
}

#[test]
fn validation_rejects_bad_albedo() {
    let mut o = nested_scene().remove(1);
    o.albedo = [0.5, 1.5, 0.0];
    assert_eq!(
        o.validate().unwrap_err().within("objects[1]").to_string(),
        "objects[1].albedo[1]: must be in [0, 1], got 1.5"
    );
    o.albedo = [-0.1, 0.5, 0.0];
    assert_eq!(
        o.validate().unwrap_err().within("o").to_string(),
        "o.albedo[0]: must be in [0, 1], got -0.1"
    );
    o.albedo = [0.1, 0.5, f64::NAN];
    assert_eq!(
        o.validate().unwrap_err().within("o").to_string(),
        "o.albedo[2]: must be finite, got NaN"
    );
    o.albedo = [0.0, 1.0, 0.5];
    assert!(o.validate().is_ok());
}
