//! With δ ≡ 0 the renderer must reproduce straight-ray geometry: a sphere's
//! silhouette and a box's edges land where the pinhole projection puts them.
//! The projection here is computed from the camera model's definition
//! (`README`/`camera.rs` docs), independently of the renderer's code.

use glam::{DMat3, DQuat, DVec2, DVec3};
use mirage::render::{RenderOptions, Rendered, Shading, render};
use mirage::scene::Scene;
use std::path::Path;

const W: u32 = 160;
const H: u32 = 120;
const FOV: f64 = 10.0;
const EYE: [f64; 3] = [0.0, 5.0, 0.0];
const LOOK: [f64; 3] = [0.3, 5.2, 100.0];

/// The hit tolerance dilates a silhouette by at most this fraction of a pixel
/// (`RenderOptions::hit_fraction`).
const DILATION: f64 = 0.05;

fn scene(objects: &str, medium: &str) -> Scene {
    let text = format!(
        r#"{{
          "camera": {{ "position": {EYE:?}, "look_at": {LOOK:?}, "vertical_fov": {FOV},
                       "width": {W}, "height": {H} }},
          "medium": {medium},
          "sky": {{ "type": "gradient", "zenith": [0, 0, 1], "horizon": [0, 0, 1] }},
          "objects": [ {objects} ],
          "trace": {{ "step": 2.0, "max_distance": 1000.0 }}
        }}"#
    );
    Scene::parse(&text, Path::new("geometry.json")).unwrap()
}

const ROAD_AIR: &str = r#"{"scale":0.02,"background":{"n":1.0,"a":150.0},"hotspots":[{"x":0.0,"z":160.0,"radius":110.0,"n":-3.0,"a":-0.35,"edge":0.5}]}"#;

fn albedo(scene: &Scene, spp: u32, straight: bool) -> Rendered {
    albedo_with(scene, spp, straight, RenderOptions::default().hit_fraction)
}

fn albedo_with(scene: &Scene, spp: u32, straight: bool, hit_fraction: f64) -> Rendered {
    render(
        scene,
        &RenderOptions {
            shading: Shading::Albedo,
            straight,
            samples_per_pixel: Some(spp),
            hit_fraction,
            ..RenderOptions::default()
        },
    )
}

/// The camera frame by its definition: forward to the look-at point, right =
/// forward × up, up' = right × forward; image plane at unit distance spans
/// ±tan(fov/2) vertically and ±tan(fov/2)·W/H horizontally; pixel (0, 0) is
/// the top-left corner.
struct Frame {
    f: DVec3,
    r: DVec3,
    u: DVec3,
    t: f64,
}

fn frame() -> Frame {
    let f = (DVec3::from(LOOK) - DVec3::from(EYE)).normalize();
    let r = f.cross(DVec3::Y).normalize();
    let u = r.cross(f);
    Frame {
        f,
        r,
        u,
        t: (0.5 * FOV.to_radians()).tan(),
    }
}

impl Frame {
    fn ray(&self, px: f64, py: f64) -> DVec3 {
        let a = W as f64 / H as f64;
        let sx = (2.0 * px / W as f64 - 1.0) * self.t * a;
        let sy = (1.0 - 2.0 * py / H as f64) * self.t;
        self.f + self.r * sx + self.u * sy
    }

    fn project(&self, p: DVec3) -> DVec2 {
        let d = p - DVec3::from(EYE);
        let (x, y, z) = (d.dot(self.r), d.dot(self.u), d.dot(self.f));
        let a = W as f64 / H as f64;
        DVec2::new(
            0.5 * W as f64 * (1.0 + x / z / (self.t * a)),
            0.5 * H as f64 * (1.0 - y / z / self.t),
        )
    }
}

fn is_object(c: [f32; 3]) -> bool {
    c[0] > 0.5
}

/// Checks every pixel centre whose classification is robust (all points
/// within `margin` px agree) against `inside`, and the first/last covered
/// column of every row against the analytic edges `edges(py)`.
fn check_silhouette(
    img: &Rendered,
    inside: impl Fn(f64, f64) -> bool,
    edges: impl Fn(f64) -> Option<(f64, f64)>,
) -> (usize, f64) {
    let margin = DILATION + 0.01;
    let mut checked = 0;
    let mut worst_edge = 0.0f64;
    for j in 0..H {
        let py = j as f64 + 0.5;
        for i in 0..W {
            let px = i as f64 + 0.5;
            let c = inside(px, py);
            let robust = [(margin, 0.0), (-margin, 0.0), (0.0, margin), (0.0, -margin)]
                .iter()
                .all(|&(dx, dy)| inside(px + dx, py + dy) == c);
            if robust {
                checked += 1;
                assert_eq!(
                    is_object(img.pixel(i, j)),
                    c,
                    "pixel ({i}, {j}): rendered {:?}, analytic {}",
                    img.pixel(i, j),
                    c
                );
            }
        }
        let cols: Vec<u32> = (0..W).filter(|&i| is_object(img.pixel(i, j))).collect();
        // Where the outline runs nearly along the row, a centre a hair inside
        // the hit tolerance vertically can be far from it horizontally: judge
        // the row's edges only where the outline is steeper than 45°.
        let steep = match (edges(py - 0.5), edges(py), edges(py + 0.5)) {
            (Some((l0, r0)), Some((l, r)), Some((l1, r1))) => [l0 - l, l1 - l, r0 - r, r1 - r]
                .iter()
                .all(|d| d.abs() <= 0.5),
            _ => false,
        };
        if !steep {
            continue;
        }
        if let (Some((xl, xr)), Some(&first), Some(&last)) = (edges(py), cols.first(), cols.last())
        {
            // The edge between the last miss and the first hit is at `first`.
            let el = (first as f64 - xl).abs();
            let er = (last as f64 + 1.0 - xr).abs();
            worst_edge = worst_edge.max(el).max(er);
            assert!(
                el <= 0.5 + DILATION && er <= 0.5 + DILATION,
                "row {j}: edges {first}..{} vs analytic {xl:.3}..{xr:.3}",
                last + 1
            );
        }
    }
    (checked, worst_edge)
}

fn sphere_edges(fr: &Frame, c: DVec3, radius: f64, py: f64) -> Option<(f64, f64)> {
    // The ray d(sx) = A + sx·r (A = f + sy·u) touches the sphere where
    // |q|²|d|² − (q·d)² = R²|d|², q = c − eye: a quadratic in sx.
    let q = c - DVec3::from(EYE);
    let sy = (1.0 - 2.0 * py / H as f64) * fr.t;
    let k = q.length_squared() - radius * radius;
    let (qf, qr, qu) = (q.dot(fr.f), q.dot(fr.r), q.dot(fr.u));
    let a2 = k - qr * qr;
    let b = -2.0 * qr * (qf + sy * qu);
    let c0 = k * (1.0 + sy * sy) - (qf + sy * qu).powi(2);
    let disc = b * b - 4.0 * a2 * c0;
    if disc < 0.0 {
        return None;
    }
    let s1 = (-b - disc.sqrt()) / (2.0 * a2);
    let s2 = (-b + disc.sqrt()) / (2.0 * a2);
    let a = W as f64 / H as f64;
    let to_px = |sx: f64| 0.5 * W as f64 * (1.0 + sx / (fr.t * a));
    Some((to_px(s1), to_px(s2)))
}

#[test]
fn sphere_silhouette_lands_on_projected_pixels() {
    let fr = frame();
    let c = DVec3::new(1.0, 5.5, 100.0);
    let radius = 3.0;
    let objects = r#"{ "albedo": [1, 0, 0], "shape": { "type": "sphere", "center": [1.0, 5.5, 100.0], "radius": 3.0 } }"#;
    let inside = |px: f64, py: f64| {
        let d = fr.ray(px, py);
        let q = c - DVec3::from(EYE);
        let b = q.dot(d);
        b > 0.0 && b * b - d.length_squared() * (q.length_squared() - radius * radius) >= 0.0
    };
    // Straight rays through real air (--straight), and through no air at all.
    for (medium, straight) in [(ROAD_AIR, true), (r#"{"scale": 1.0}"#, false)] {
        let img = albedo(&scene(objects, medium), 1, straight);
        let (checked, worst) =
            check_silhouette(&img, inside, |py| sphere_edges(&fr, c, radius, py));
        assert!(
            checked > (W * H) as usize * 9 / 10,
            "only {checked} robust pixels"
        );
        println!("sphere: {checked} pixels checked, worst row edge {worst:.3} px");
    }

    // Sub-pixel: with 64 samples per pixel the covered fraction of each row
    // measures the chord of the silhouette, integrated over the pixel's height.
    // The hit tolerance widens a silhouette by up to its fraction of a pixel
    // on every side; made negligible here, the rows must agree to 0.05 px.
    let img = albedo_with(&scene(objects, ROAD_AIR), 128, true, 0.001);
    let mut worst = 0.0f64;
    let mut rows = 0;
    for j in 0..H {
        // Rows the outline crosses steeply: two boundary pixels each, so the
        // sampling error stays near 1/128 px per boundary.
        let steep = [0.0, 0.5, 1.0].iter().all(|&dy| {
            match (
                sphere_edges(&fr, c, radius, j as f64 + dy),
                sphere_edges(&fr, c, radius, j as f64 + 0.5),
            ) {
                (Some((l0, r0)), Some((l, r))) => (l0 - l).abs() <= 0.5 && (r0 - r).abs() <= 0.5,
                _ => false,
            }
        });
        if !steep {
            continue;
        }
        rows += 1;
        let rendered: f64 = (0..W).map(|i| img.pixel(i, j)[0] as f64).sum();
        let n = 256;
        let analytic: f64 = (0..n)
            .map(|k| {
                let py = j as f64 + (k as f64 + 0.5) / n as f64;
                sphere_edges(&fr, c, radius, py).map_or(0.0, |(l, r)| r - l)
            })
            .sum::<f64>()
            / n as f64;
        worst = worst.max((rendered - analytic).abs());
    }
    println!("sphere: worst row coverage error {worst:.4} px over {rows} rows");
    assert!(rows > 25, "{rows}");
    assert!(worst < 0.05, "row coverage off by {worst} px");
}

/// Convex hull (counter-clockwise) of 2-D points, Andrew's monotone chain.
fn hull(mut pts: Vec<DVec2>) -> Vec<DVec2> {
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut lower: Vec<DVec2> = Vec::new();
    for &p in &pts {
        while lower.len() >= 2 && cross(lower[lower.len() - 2], lower[lower.len() - 1], p) <= 0.0 {
            lower.pop();
        }
        lower.push(p);
    }
    let mut upper: Vec<DVec2> = Vec::new();
    for &p in pts.iter().rev() {
        while upper.len() >= 2 && cross(upper[upper.len() - 2], upper[upper.len() - 1], p) <= 0.0 {
            upper.pop();
        }
        upper.push(p);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

#[test]
fn box_edges_land_on_projected_pixels() {
    let fr = frame();
    let offset = DVec3::new(-3.0, 4.5, 90.0);
    let axis = DVec3::new(0.3, 1.0, 0.2).normalize();
    let half = DVec3::new(2.5, 1.5, 3.0);
    let objects = r#"{ "albedo": [1, 0, 0], "shape": { "type": "translate", "offset": [-3.0, 4.5, 90.0],
        "child": { "type": "rotate", "axis": [0.3, 1.0, 0.2], "degrees": 35.0,
          "child": { "type": "box", "center": [0, 0, 0], "half_extents": [2.5, 1.5, 3.0] } } } }"#;
    // A right-handed rotation by the angle about the axis: the schema of
    // `rotate` in sdf.rs.
    let rot = DMat3::from_quat(DQuat::from_axis_angle(axis, 35f64.to_radians()));
    let mut corners = Vec::new();
    for sx in [-1.0, 1.0] {
        for sy in [-1.0, 1.0] {
            for sz in [-1.0, 1.0] {
                corners.push(fr.project(offset + rot * (half * DVec3::new(sx, sy, sz))));
            }
        }
    }
    let poly = hull(corners);
    let inside = |px: f64, py: f64| {
        let p = DVec2::new(px, py);
        (0..poly.len()).all(|k| (poly[(k + 1) % poly.len()] - poly[k]).perp_dot(p - poly[k]) >= 0.0)
    };
    let edges = |py: f64| {
        // Where the row's line crosses the polygon's edges.
        let mut xs = Vec::new();
        for k in 0..poly.len() {
            let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
            if (a.y - py) * (b.y - py) < 0.0 {
                xs.push(a.x + (py - a.y) / (b.y - a.y) * (b.x - a.x));
            }
        }
        (xs.len() == 2).then(|| (xs[0].min(xs[1]), xs[0].max(xs[1])))
    };
    let img = albedo(&scene(objects, ROAD_AIR), 1, true);
    let (checked, worst) = check_silhouette(&img, inside, edges);
    assert!(checked > (W * H) as usize * 9 / 10);
    println!("box: {checked} pixels checked, worst row edge {worst:.3} px");
    // The box covers a fair part of the image, so the test sees real edges.
    let covered = img.pixels.iter().filter(|&&c| is_object(c)).count();
    assert!(covered > 500, "{covered}");
}
