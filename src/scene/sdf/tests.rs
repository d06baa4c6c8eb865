use super::*;
use glam::DQuat;
use proptest::prelude::*;

// ---- helpers ---------------------------------------------------------

fn v3(lo: f64, hi: f64) -> impl Strategy<Value = DVec3> {
    (lo..hi, lo..hi, lo..hi).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

/// Deterministic PRNG (SplitMix64) for the sampling checks.
struct Rng(u64);
impl Rng {
    fn uniform(&mut self) -> f64 {
        let mut g = crate::math::SplitMix64(self.0);
        let u = g.next_f64();
        self.0 = g.0;
        u
    }
    fn unit_vector(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(
                2.0 * self.uniform() - 1.0,
                2.0 * self.uniform() - 1.0,
                2.0 * self.uniform() - 1.0,
            );
            let l = v.length();
            if l > 1e-3 && l <= 1.0 {
                return v / l;
            }
        }
    }
}

// Independent analytic distance formulas (written differently from the
// module's, via clamping / explicit case analysis / numeric search).

fn box_exact(p: DVec3, c: DVec3, he: DVec3) -> f64 {
    let q = p - c;
    let clamped = q.clamp(-he, he);
    if clamped == q {
        // inside or on: distance to the nearest face
        -(he - q.abs()).min_element()
    } else {
        (q - clamped).length()
    }
}

fn cylinder_exact(p: DVec3, c: DVec3, r: f64, h: f64) -> f64 {
    let q = p - c;
    let rho = (q.x * q.x + q.z * q.z).sqrt();
    let dx = rho - r;
    let dy = q.y.abs() - h;
    if dx <= 0.0 && dy <= 0.0 {
        dx.max(dy)
    } else {
        dx.max(0.0).hypot(dy.max(0.0))
    }
}

fn torus_exact(p: DVec3, c: DVec3, big: f64, small: f64) -> f64 {
    let q = p - c;
    let rho = q.x.hypot(q.z);
    (rho - big).hypot(q.y) - small
}

fn segment_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    // ternary search on the convex function t -> |p - seg(t)|
    let f = |t: f64| (p - (a + (b - a) * t)).length();
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    for _ in 0..200 {
        let m1 = lo + (hi - lo) / 3.0;
        let m2 = hi - (hi - lo) / 3.0;
        if f(m1) <= f(m2) {
            hi = m2;
        } else {
            lo = m1;
        }
    }
    f(0.5 * (lo + hi)).min(f(0.0)).min(f(1.0))
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

/// |∇d| ≈ 1 and projecting along the normal lands on the surface.
fn check_exactness(s: &Sdf, p: DVec3) -> Result<(), TestCaseError> {
    let d = s.distance(p);
    let g = s.gradient(p);
    prop_assert!(
        close(g.length(), 1.0, 1e-6),
        "|grad| = {} at {p} (d = {d})",
        g.length()
    );
    let n = s.normal(p);
    let q = p - n * d;
    let dq = s.distance(q);
    prop_assert!(
        dq.abs() <= 1e-7 * (1.0 + d.abs()),
        "d(p - d n) = {dq} at p = {p}, d = {d}"
    );
    Ok(())
}

// ---- primitives vs analytic formulas -----------------------------------

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn sphere_matches_formula(c in v3(-3.0, 3.0), r in 0.1f64..3.0, p in v3(-6.0, 6.0)) {
        let s = Sdf::sphere(c, r);
        let d = s.distance(p);
        prop_assert!(close(d, (p - c).length() - r, 1e-12));
        if (p - c).length() > 1e-3 {
            check_exactness(&s, p)?;
        }
    }

    #[test]
    fn box_matches_formula(c in v3(-3.0, 3.0), he in v3(0.1, 3.0), p in v3(-6.0, 6.0)) {
        let s = Sdf::cuboid(c, he);
        prop_assert!(close(s.distance(p), box_exact(p, c, he), 1e-12));
        let q = p - c;
        let face = he - q.abs();
        let inside = face.min_element() > 0.0;
        let medial = if inside {
            let mut f = face.to_array();
            f.sort_by(f64::total_cmp);
            f[1] - f[0] < 1e-3
        } else {
            false
        };
        if !medial {
            check_exactness(&s, p)?;
        }
    }

    #[test]
    fn rounded_box_matches_formula(
        c in v3(-3.0, 3.0), he in v3(0.2, 3.0), frac in 0.01f64..1.0, p in v3(-6.0, 6.0)
    ) {
        let r = frac * he.min_element();
        let s = Sdf::rounded_box(c, he, r);
        let inner = he - DVec3::splat(r);
        prop_assert!(close(s.distance(p), box_exact(p, c, inner) - r, 1e-12));
        prop_assert!(s.validate().is_ok());
        let face = inner - (p - c).abs();
        let medial = if face.min_element() > -1e-3 {
            let mut f = face.to_array();
            f.sort_by(f64::total_cmp);
            f[1] - f[0] < 1e-3 || f[0].abs() < 1e-3
        } else {
            false
        };
        if !medial {
            check_exactness(&s, p)?;
        }
    }

    #[test]
    fn plane_matches_formula(n in v3(-1.0, 1.0), off in -3.0f64..3.0, p in v3(-6.0, 6.0)) {
        prop_assume!(n.length() > 0.05);
        let s = Sdf::plane(n, off);
        let expect = n.dot(p) / n.length() - off;
        prop_assert!(close(s.distance(p), expect, 1e-12));
        check_exactness(&s, p)?;
    }

    #[test]
    fn torus_matches_formula(
        c in v3(-2.0, 2.0), big in 0.5f64..3.0, frac in 0.05f64..1.0, p in v3(-6.0, 6.0)
    ) {
        let small = frac * big;
        let s = Sdf::torus(c, big, small);
        prop_assert!(close(s.distance(p), torus_exact(p, c, big, small), 1e-12));
        let q = p - c;
        let rho = q.x.hypot(q.z);
        // medial axis: the y axis and the core circle
        if rho > 1e-3 && (rho - big).hypot(q.y) > 1e-3 {
            check_exactness(&s, p)?;
        }
    }

    #[test]
    fn cylinder_matches_formula(
        c in v3(-3.0, 3.0), r in 0.05f64..3.0, h in 0.05f64..3.0, p in v3(-6.0, 6.0)
    ) {
        let s = Sdf::cylinder(c, r, h);
        prop_assert!(close(s.distance(p), cylinder_exact(p, c, r, h), 1e-12));
        let q = p - c;
        let rho = q.x.hypot(q.z);
        let inside = rho < r && q.y.abs() < h;
        let medial = inside && (((r - rho) - (h - q.y.abs())).abs() < 1e-3 || rho < 1e-3);
        if !medial {
            check_exactness(&s, p)?;
        }
    }

    #[test]
    fn capsule_matches_formula(
        a in v3(-3.0, 3.0), b in v3(-3.0, 3.0), r in 0.05f64..2.0, p in v3(-6.0, 6.0)
    ) {
        let s = Sdf::capsule(a, b, r);
        prop_assert!(close(s.distance(p), segment_distance(p, a, b) - r, 1e-9));
        if segment_distance(p, a, b) > 1e-3 {
            check_exactness(&s, p)?;
        }
    }
}

#[test]
fn degenerate_capsule_is_sphere() {
    let c = DVec3::new(1.0, 2.0, 3.0);
    let s = Sdf::capsule(c, c, 0.5);
    let p = DVec3::new(4.0, -1.0, 0.5);
    assert!(close(s.distance(p), (p - c).length() - 0.5, 1e-12));
}

#[test]
fn sphere_normal_is_radial() {
    let c = DVec3::new(1000.0, 2.0, -3.0);
    let s = Sdf::sphere(c, 0.025);
    for dir in [DVec3::X, DVec3::NEG_Y, DVec3::new(1.0, 2.0, -2.0) / 3.0] {
        let p = c + dir * 0.025;
        let n = s.normal(p);
        assert!((n - dir).length() < 1e-5, "normal {n} vs {dir}");
    }
}

// ---- sphere tracing vs analytic ray intersections ----------------------

const TRACE_EPS: f64 = 1e-10;

fn ray_sphere(o: DVec3, d: DVec3, c: DVec3, r: f64) -> Option<f64> {
    let oc = o - c;
    let b = oc.dot(d);
    let cc = oc.length_squared() - r * r;
    let disc = b * b - cc;
    if disc < 0.0 {
        return None;
    }
    let t = -b - disc.sqrt();
    (t >= 0.0).then_some(t)
}

/// Slab test; returns (t_near, entering axis).
fn ray_box(o: DVec3, d: DVec3, c: DVec3, he: DVec3) -> Option<(f64, usize)> {
    let lo = c - he;
    let hi = c + he;
    let mut t_near = f64::NEG_INFINITY;
    let mut t_far = f64::INFINITY;
    let mut axis = 0;
    for i in 0..3 {
        let t1 = (lo[i] - o[i]) / d[i];
        let t2 = (hi[i] - o[i]) / d[i];
        let (a, b) = if t1 < t2 { (t1, t2) } else { (t2, t1) };
        if a > t_near {
            t_near = a;
            axis = i;
        }
        t_far = t_far.min(b);
    }
    (t_near <= t_far && t_near >= 0.0).then_some((t_near, axis))
}

/// Capped cylinder, axis y; returns (t, outward normal at hit).
fn ray_cylinder(o: DVec3, d: DVec3, c: DVec3, r: f64, h: f64) -> Option<(f64, DVec3)> {
    let q = o - c;
    let mut best: Option<(f64, DVec3)> = None;
    let mut consider = |t: f64, n: DVec3| {
        if t >= 0.0 && best.is_none_or(|(bt, _)| t < bt) {
            best = Some((t, n));
        }
    };
    let a = d.x * d.x + d.z * d.z;
    if a > 0.0 {
        let b = q.x * d.x + q.z * d.z;
        let cc = q.x * q.x + q.z * q.z - r * r;
        let disc = b * b - a * cc;
        if disc >= 0.0 {
            for t in [(-b - disc.sqrt()) / a, (-b + disc.sqrt()) / a] {
                let hit = q + d * t;
                if hit.y.abs() <= h {
                    consider(t, DVec3::new(hit.x, 0.0, hit.z) / r);
                }
            }
        }
    }
    if d.y != 0.0 {
        for (cap, ny) in [(h, 1.0), (-h, -1.0)] {
            let t = (cap - q.y) / d.y;
            let hit = q + d * t;
            if hit.x * hit.x + hit.z * hit.z <= r * r {
                consider(t, DVec3::new(0.0, ny, 0.0));
            }
        }
    }
    best
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn trace_sphere(
        c in v3(-2.0, 2.0), r in 0.1f64..2.0, o in v3(-10.0, 10.0), u in v3(-1.3, 1.3)
    ) {
        // aim near the solid: mostly hits, some near misses
        let tgt = c + u * r;
        prop_assume!((o - c).length() > r + 0.01);
        prop_assume!((tgt - o).length() > 1e-3);
        let d = (tgt - o).normalize();
        let s = Sdf::sphere(c, r);
        let exact = ray_sphere(o, d, c, r);
        // closest approach of the ray's line to the centre
        let along = (c - o).dot(d);
        let miss_margin = ((c - o) - d * along).length() - r;
        prop_assume!(miss_margin.abs() > 1e-3 || along < 0.0);
        let got = sphere_trace(&s, o, d, 100.0, TRACE_EPS);
        match exact {
            Some(t) => {
                let n = (o + d * t - c) / r;
                prop_assume!(-n.dot(d) > 0.05);
                let (tt, _) = got.expect("analytic hit, traced miss");
                prop_assert!((tt - t).abs() <= 1e-6 * t, "traced {tt}, exact {t}");
                prop_assert!(tt <= t + 1e-12);
            }
            None => {
                prop_assert!(got.is_none(), "analytic miss, traced {got:?}");
            }
        }
    }

    #[test]
    fn trace_box(
        c in v3(-2.0, 2.0), he in v3(0.1, 2.0), o in v3(-10.0, 10.0), u in v3(-1.3, 1.3)
    ) {
        let tgt = c + u * he;
        let s = Sdf::cuboid(c, he);
        prop_assume!(s.distance(o) > 0.01);
        prop_assume!((tgt - o).length() > 1e-3);
        let d = (tgt - o).normalize();
        let got = sphere_trace(&s, o, d, 100.0, TRACE_EPS);
        match ray_box(o, d, c, he) {
            Some((t, axis)) => {
                prop_assume!(d[axis].abs() > 0.05);
                let (tt, _) = got.expect("analytic hit, traced miss");
                prop_assert!((tt - t).abs() <= 1e-6 * t, "traced {tt}, exact {t}");
                prop_assert!(tt <= t + 1e-12);
            }
            None => {
                // skip rays grazing an edge/face (closest approach tiny)
                let closest = (0..2000)
                    .map(|i| s.distance(o + d * (i as f64 * 0.02)))
                    .fold(f64::INFINITY, f64::min);
                prop_assume!(closest > 1e-3);
                prop_assert!(got.is_none(), "analytic miss, traced {got:?}");
            }
        }
    }

    #[test]
    fn trace_plane(
        n in v3(-1.0, 1.0), off in -2.0f64..2.0, o in v3(-10.0, 10.0), dir in v3(-1.0, 1.0)
    ) {
        prop_assume!(n.length() > 0.1 && dir.length() > 0.1);
        let s = Sdf::plane(n, off);
        let nn = n.normalize();
        let d = dir.normalize();
        prop_assume!(s.distance(o) > 0.01);
        let denom = nn.dot(d);
        let got = sphere_trace(&s, o, d, 1000.0, TRACE_EPS);
        let t = (off - nn.dot(o)) / denom;
        if denom < -0.05 && t <= 900.0 {
            let (tt, _) = got.expect("analytic hit, traced miss");
            prop_assert!((tt - t).abs() <= 1e-6 * t, "traced {tt}, exact {t}");
        } else if denom >= 0.0 {
            prop_assert!(got.is_none(), "ray leaves the plane, traced {got:?}");
        }
    }

    #[test]
    fn trace_cylinder(
        c in v3(-2.0, 2.0), r in 0.05f64..2.0, h in 0.05f64..2.0,
        o in v3(-10.0, 10.0), u in v3(-1.3, 1.3)
    ) {
        let tgt = c + u * DVec3::new(r, h, r);
        let s = Sdf::cylinder(c, r, h);
        prop_assume!(s.distance(o) > 0.01);
        prop_assume!((tgt - o).length() > 1e-3);
        let d = (tgt - o).normalize();
        let got = sphere_trace(&s, o, d, 100.0, TRACE_EPS);
        match ray_cylinder(o, d, c, r, h) {
            Some((t, n)) => {
                prop_assume!(-n.dot(d) > 0.05);
                let (tt, _) = got.expect("analytic hit, traced miss");
                prop_assert!((tt - t).abs() <= 1e-6 * t, "traced {tt}, exact {t}");
                prop_assert!(tt <= t + 1e-12);
            }
            None => {
                let closest = (0..2000)
                    .map(|i| s.distance(o + d * (i as f64 * 0.02)))
                    .fold(f64::INFINITY, f64::min);
                prop_assume!(closest > 1e-3);
                prop_assert!(got.is_none(), "analytic miss, traced {got:?}");
            }
        }
    }
}

#[test]
fn trace_hits_targets_inside_shapes() {
    // Not filtered: rays aimed at the centre of each solid always hit.
    let mut rng = Rng(7);
    let shapes = [
        Sdf::sphere(DVec3::ZERO, 1.0),
        Sdf::cuboid(DVec3::ZERO, DVec3::new(1.0, 0.5, 2.0)),
        Sdf::cylinder(DVec3::ZERO, 0.5, 1.0),
        Sdf::torus(DVec3::ZERO, 1.0, 0.3),
    ];
    for s in &shapes {
        for _ in 0..200 {
            let o = rng.unit_vector() * 20.0;
            let target = if matches!(s, Sdf::Torus { .. }) {
                DVec3::X
            } else {
                DVec3::ZERO
            };
            let (t, steps) = sphere_trace(s, o, target - o, 100.0, 1e-9).expect("hit");
            assert!(s.distance(o + (target - o).normalize() * t).abs() < 1e-9);
            assert!(steps < 500);
        }
    }
}

#[test]
fn trace_edge_cases() {
    let s = Sdf::sphere(DVec3::ZERO, 1.0);
    // starting inside: hit at t = 0
    assert_eq!(
        sphere_trace(&s, DVec3::ZERO, DVec3::X, 10.0, 1e-9),
        Some((0.0, 1))
    );
    // degenerate direction
    assert_eq!(
        sphere_trace(&s, DVec3::X * 5.0, DVec3::ZERO, 10.0, 1e-9),
        None
    );
    // max_t shorter than the hit distance
    assert_eq!(
        sphere_trace(&s, DVec3::X * 5.0, DVec3::NEG_X, 3.0, 1e-9),
        None
    );
    // unnormalised direction: t is still a length
    let (t, _) = sphere_trace(&s, DVec3::X * 5.0, DVec3::NEG_X * 7.0, 10.0, 1e-12).unwrap();
    assert!(close(t, 4.0, 1e-9));
    // empty union: infinite distance, miss
    let empty = Sdf::union(vec![]);
    assert_eq!(
        sphere_trace(&empty, DVec3::ZERO, DVec3::X, 10.0, 1e-9),
        None
    );
}

// ---- the pole ----------------------------------------------------------

#[test]
fn thin_pole_one_km_away() {
    // 5 cm-diameter, 4 m tall pole standing on y = 0, 1 km down +x.
    let axis_x = 1000.0;
    let pole = Sdf::cylinder(DVec3::new(axis_x, 2.0, 0.0), 0.025, 2.0);
    let eye = DVec3::new(0.0, 1.5, 0.0);
    let eps = 1e-6;

    // Aimed at the axis: hits the front surface at 999.975 m.
    let (t, steps) =
        sphere_trace(&pole, eye, DVec3::new(axis_x, 1.5, 0.0) - eye, 2000.0, eps).expect("hit");
    assert!(((t - 999.975) / 999.975).abs() < 1e-6, "t = {t}");
    assert!(steps < 10, "steps = {steps}");

    // Aimed 2 cm off the axis (still within the 2.5 cm radius): hits.
    let tgt = DVec3::new(axis_x, 1.5, 0.02);
    let d = (tgt - eye).normalize();
    let (t, _) = sphere_trace(&pole, eye, d, 2000.0, eps).expect("off-centre hit");
    let exact = ray_cylinder(eye, d, DVec3::new(axis_x, 2.0, 0.0), 0.025, 2.0)
        .unwrap()
        .0;
    assert!(((t - exact) / exact).abs() < 1e-6, "t = {t}, exact {exact}");

    // Passing 3 cm beside the surface (5.5 cm from the axis): misses.
    let beside = DVec3::new(axis_x, 1.5, 0.025 + 0.03);
    assert_eq!(sphere_trace(&pole, eye, beside - eye, 2000.0, eps), None);
    // Even 3 cm from the axis (5 mm beside the surface): misses.
    let beside = DVec3::new(axis_x, 1.5, 0.03);
    assert_eq!(sphere_trace(&pole, eye, beside - eye, 2000.0, eps), None);
    // Passing 3 cm above its top: misses.
    let above = DVec3::new(axis_x, 4.03, 0.0);
    assert_eq!(sphere_trace(&pole, eye, above - eye, 2000.0, eps), None);
}

#[test]
fn pole_in_scene_is_the_nearest_object_at_the_hit() {
    let objects = vec![
        SceneObject {
            name: Some("ground".into()),
            albedo: [0.3, 0.25, 0.2],
            shape: Sdf::plane(DVec3::Y, 0.0),
        },
        SceneObject {
            name: Some("pole".into()),
            albedo: [0.8, 0.8, 0.8],
            shape: Sdf::cylinder(DVec3::new(1000.0, 2.0, 0.0), 0.025, 2.0),
        },
    ];
    validate_objects(&objects).unwrap();
    let eye = DVec3::new(0.0, 1.5, 0.0);
    let dir = DVec3::X;
    let (t, _) = sphere_trace(objects.as_slice(), eye, dir, 2000.0, 1e-6).expect("hit");
    let (d, idx) = nearest_object(&objects, eye + dir * t);
    assert_eq!(idx, Some(1));
    assert!(d < 1e-6);
    // Looking down hits the ground (index 0).
    let down = DVec3::new(1.0, -1.0, 0.0);
    let (t, _) = sphere_trace(objects.as_slice(), eye, down, 2000.0, 1e-9).expect("hit");
    assert!(close(t, 1.5 * 2f64.sqrt(), 1e-8));
    assert_eq!(
        nearest_object(&objects, eye + down.normalize() * t).1,
        Some(0)
    );
    assert_eq!(nearest_object(&[], eye), (f64::INFINITY, None));
}

// ---- combinators never overestimate ------------------------------------

/// Looks for a point strictly inside the ball of radius |f(p)| around `p`
/// whose inside/outside status differs from `p`'s (i.e. a surface
/// crossing closer than claimed), or a wrong sign at `p`.
fn find_overestimate(
    f: &dyn Fn(DVec3) -> f64,
    inside: &dyn Fn(DVec3) -> bool,
    p: DVec3,
    rng: &mut Rng,
    samples: usize,
) -> Option<String> {
    let d = f(p);
    let p_in = inside(p);
    if d.abs() > 1e-9 && (d < 0.0) != p_in {
        return Some(format!("wrong sign at {p}: d = {d}, inside = {p_in}"));
    }
    let r = d.abs() * (1.0 - 1e-9);
    if r < 1e-6 {
        return None;
    }
    for i in 0..samples {
        let dir = rng.unit_vector();
        // half on the ball's boundary, half in its volume
        let rad = if i % 2 == 0 {
            r
        } else {
            r * rng.uniform().cbrt()
        };
        let q = p + dir * rad;
        if inside(q) != p_in {
            return Some(format!(
                "at p = {p}, d = {d} but {q} (distance {}) is on the other side",
                (q - p).length()
            ));
        }
    }
    None
}

fn inside_sphere(p: DVec3, c: DVec3, r: f64) -> bool {
    (p - c).length() < r
}
fn inside_box(p: DVec3, c: DVec3, he: DVec3) -> bool {
    let q = (p - c).abs();
    q.x < he.x && q.y < he.y && q.z < he.z
}
fn inside_capsule(p: DVec3, a: DVec3, b: DVec3, r: f64) -> bool {
    segment_distance(p, a, b) < r
}

fn smin_ref(a: f64, b: f64, k: f64) -> f64 {
    // reference: mix form of the quadratic smooth minimum
    let h = (0.5 + 0.5 * (b - a) / k).clamp(0.0, 1.0);
    b * (1.0 - h) + a * h - k * h * (1.0 - h)
}

#[derive(Debug, Clone)]
struct Trio {
    sc: DVec3,
    sr: f64,
    bc: DVec3,
    bh: DVec3,
    ca: DVec3,
    cb: DVec3,
    cr: f64,
}

fn trio() -> impl Strategy<Value = Trio> {
    (
        v3(-1.5, 1.5),
        0.3f64..1.5,
        v3(-1.5, 1.5),
        v3(0.2, 1.2),
        v3(-1.5, 1.5),
        v3(-1.5, 1.5),
        0.1f64..0.8,
    )
        .prop_map(|(sc, sr, bc, bh, ca, cb, cr)| Trio {
            sc,
            sr,
            bc,
            bh,
            ca,
            cb,
            cr,
        })
}

impl Trio {
    fn shapes(&self) -> Vec<Sdf> {
        vec![
            Sdf::sphere(self.sc, self.sr),
            Sdf::cuboid(self.bc, self.bh),
            Sdf::capsule(self.ca, self.cb, self.cr),
        ]
    }
    fn inside(&self, p: DVec3) -> [bool; 3] {
        [
            inside_sphere(p, self.sc, self.sr),
            inside_box(p, self.bc, self.bh),
            inside_capsule(p, self.ca, self.cb, self.cr),
        ]
    }
    fn exact(&self, p: DVec3) -> [f64; 3] {
        [
            (p - self.sc).length() - self.sr,
            box_exact(p, self.bc, self.bh),
            segment_distance(p, self.ca, self.cb) - self.cr,
        ]
    }
}

const SAMPLES: usize = 600;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn union_never_overestimates(t in trio(), p in v3(-4.0, 4.0), seed in any::<u64>()) {
        let s = Sdf::union(t.shapes());
        let inside = |q: DVec3| t.inside(q).iter().any(|&b| b);
        let bad = find_overestimate(&|q| s.distance(q), &inside, p, &mut Rng(seed), SAMPLES);
        prop_assert!(bad.is_none(), "{}", bad.unwrap());
    }

    #[test]
    fn intersection_never_overestimates(t in trio(), p in v3(-4.0, 4.0), seed in any::<u64>()) {
        let s = Sdf::intersection(t.shapes());
        let inside = |q: DVec3| t.inside(q).iter().all(|&b| b);
        let bad = find_overestimate(&|q| s.distance(q), &inside, p, &mut Rng(seed), SAMPLES);
        prop_assert!(bad.is_none(), "{}", bad.unwrap());
    }

    #[test]
    fn difference_never_overestimates(t in trio(), p in v3(-4.0, 4.0), seed in any::<u64>()) {
        let [a, b, c] = <[Sdf; 3]>::try_from(t.shapes()).unwrap();
        // (sphere ∪ box) − capsule
        let s = Sdf::difference(Sdf::union(vec![a, b]), c);
        let inside = |q: DVec3| {
            let i = t.inside(q);
            (i[0] || i[1]) && !i[2]
        };
        let bad = find_overestimate(&|q| s.distance(q), &inside, p, &mut Rng(seed), SAMPLES);
        prop_assert!(bad.is_none(), "{}", bad.unwrap());
    }

    #[test]
    fn smooth_union_never_overestimates(
        t in trio(), k in 0.05f64..1.5, p in v3(-4.0, 4.0), seed in any::<u64>()
    ) {
        let s = Sdf::smooth_union(t.shapes(), k);
        // The surface is by definition the zero set of the smooth minimum
        // of the exact child distances (reference implementation).
        let field = |q: DVec3| {
            let e = t.exact(q);
            smin_ref(smin_ref(e[0], e[1], k), e[2], k)
        };
        prop_assert!(close(s.distance(p), field(p), 1e-9));
        let inside = |q: DVec3| field(q) < 0.0;
        let bad = find_overestimate(&|q| s.distance(q), &inside, p, &mut Rng(seed), SAMPLES);
        prop_assert!(bad.is_none(), "{}", bad.unwrap());
        // never above the plain union, never more than 2·k/4 below it
        let m = t.exact(p).into_iter().fold(f64::INFINITY, f64::min);
        prop_assert!(s.distance(p) <= m + 1e-12);
        prop_assert!(s.distance(p) >= m - 0.5 * k - 1e-12);
    }

    #[test]
    fn transforms_never_overestimate(
        t in trio(), off in v3(-2.0, 2.0), axis in v3(-1.0, 1.0), deg in -360.0f64..360.0,
        factor in 0.2f64..5.0, p in v3(-8.0, 8.0), seed in any::<u64>()
    ) {
        prop_assume!(axis.length() > 0.05);
        let base = Sdf::difference(
            Sdf::union(t.shapes()[..2].to_vec()),
            t.shapes()[2].clone(),
        );
        let base_inside = |q: DVec3| {
            let i = t.inside(q);
            (i[0] || i[1]) && !i[2]
        };
        let s = Sdf::scale(factor, Sdf::rotate(axis, deg, Sdf::translate(off, base)));
        prop_assert!(s.validate().is_ok());
        // independent inverse: undo scale, undo rotation via a quaternion, undo offset
        let undo = DQuat::from_axis_angle(axis.normalize(), -deg.to_radians());
        let inside = |q: DVec3| base_inside(undo * (q / factor) - off);
        let bad = find_overestimate(&|q| s.distance(q), &inside, p, &mut Rng(seed), SAMPLES);
        prop_assert!(bad.is_none(), "{}", bad.unwrap());
    }

    #[test]
    fn combinators_are_one_lipschitz(
        t in trio(), k in 0.05f64..1.5, axis in v3(-1.0, 1.0), deg in -180.0f64..180.0,
        factor in 0.2f64..5.0, p in v3(-5.0, 5.0), q in v3(-5.0, 5.0)
    ) {
        prop_assume!(axis.length() > 0.05);
        let [a, b, c] = <[Sdf; 3]>::try_from(t.shapes()).unwrap();
        let shapes = [
            Sdf::union(vec![a.clone(), b.clone(), c.clone()]),
            Sdf::intersection(vec![a.clone(), b.clone(), c.clone()]),
            Sdf::difference(a.clone(), b.clone()),
            Sdf::smooth_union(vec![a.clone(), b.clone(), c.clone()], k),
            Sdf::translate(axis, c.clone()),
            Sdf::rotate(axis, deg, b.clone()),
            Sdf::scale(factor, Sdf::smooth_union(vec![a, b, c], k)),
        ];
        for s in &shapes {
            let (dp, dq) = (s.distance(p), s.distance(q));
            prop_assert!((dp - dq).abs() <= (p - q).length() * (1.0 + 1e-9) + 1e-12);
        }
    }
}

#[test]
fn overestimate_checker_can_fail() {
    // Negative control: the checker must catch a field that claims 1.5x
    // the true union distance.
    let t = Trio {
        sc: DVec3::new(-1.0, 0.0, 0.0),
        sr: 1.0,
        bc: DVec3::new(1.0, 0.5, 0.0),
        bh: DVec3::new(0.5, 0.7, 0.9),
        ca: DVec3::new(0.0, -1.0, -1.0),
        cb: DVec3::new(0.5, -1.0, 1.0),
        cr: 0.3,
    };
    let s = Sdf::union(t.shapes());
    let inside = |q: DVec3| t.inside(q).iter().any(|&b| b);
    let cheat = |q: DVec3| 1.5 * s.distance(q);
    let mut rng = Rng(1);
    let mut caught = 0;
    for _ in 0..50 {
        let p = rng.unit_vector() * 4.0;
        if find_overestimate(&cheat, &inside, p, &mut rng, SAMPLES).is_some() {
            caught += 1;
        }
        assert!(find_overestimate(&|q| s.distance(q), &inside, p, &mut rng, SAMPLES).is_none());
    }
    assert!(caught >= 45, "caught only {caught}/50");
}

#[test]
fn union_of_exact_is_exact_outside() {
    // Outside everything, min of exact distances is the exact distance.
    let a = Sdf::sphere(DVec3::ZERO, 1.0);
    let b = Sdf::cuboid(DVec3::new(5.0, 0.0, 0.0), DVec3::splat(1.0));
    let u = Sdf::union(vec![a, b]);
    assert!(close(u.distance(DVec3::new(2.5, 0.0, 0.0)), 1.5, 1e-12));
    assert!(close(u.distance(DVec3::new(-3.0, 0.0, 0.0)), 2.0, 1e-12));
}

#[test]
fn transforms_move_surfaces_where_expected() {
    let s = Sdf::cuboid(DVec3::ZERO, DVec3::new(2.0, 0.5, 0.5));
    // rotate 90° about z: the long axis now points along y
    let r = Sdf::rotate(DVec3::Z, 90.0, s.clone());
    assert!(close(r.distance(DVec3::new(0.0, 3.0, 0.0)), 1.0, 1e-12));
    assert!(close(r.distance(DVec3::new(3.0, 0.0, 0.0)), 2.5, 1e-12));
    let t = Sdf::translate(DVec3::new(10.0, 0.0, 0.0), s.clone());
    assert!(close(t.distance(DVec3::new(13.0, 0.0, 0.0)), 1.0, 1e-12));
    let k = Sdf::scale(3.0, s);
    assert!(close(k.distance(DVec3::new(9.0, 0.0, 0.0)), 3.0, 1e-12));
    assert!(close(k.distance(DVec3::ZERO), -1.5, 1e-12));
}

// ---- bounding spheres --------------------------------------------------

/// The shapes whose bounding sphere and box are checked: a trio's shapes,
/// each primitive, turned ones, and every combinator.
fn bounded_shapes(t: &Trio, k: f64, off: DVec3, axis: DVec3, deg: f64, factor: f64) -> Vec<Sdf> {
    let [a, b, c] = <[Sdf; 3]>::try_from(t.shapes()).unwrap();
    vec![
        a.clone(),
        b.clone(),
        c.clone(),
        Sdf::torus(off, 1.0, 0.4),
        Sdf::cylinder(off, 0.3, 2.0),
        Sdf::capsule(off, off + axis * 3.0, 0.3),
        Sdf::rounded_box(off, DVec3::new(1.0, 0.3, 0.5), 0.2),
        Sdf::rotate(
            axis,
            deg,
            Sdf::rounded_box(off, DVec3::new(1.0, 0.3, 0.5), 0.2),
        ),
        Sdf::rotate(
            DVec3::Y,
            90.0 * (deg / 90.0).round(),
            Sdf::cuboid(off, DVec3::new(2.0, 0.3, 0.5)),
        ),
        Sdf::union(vec![a.clone(), b.clone(), c.clone()]),
        Sdf::intersection(vec![a.clone(), b.clone()]),
        Sdf::difference(b.clone(), a.clone()),
        Sdf::smooth_union(vec![a.clone(), b.clone(), c.clone()], k),
        Sdf::scale(
            factor,
            Sdf::rotate(
                axis,
                deg,
                Sdf::translate(off, Sdf::smooth_union(vec![a, b, c], k)),
            ),
        ),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn bounding_sphere_contains_solid(
        t in trio(), k in 0.05f64..1.5, off in v3(-3.0, 3.0), axis in v3(-1.0, 1.0),
        deg in -180.0f64..180.0, factor in 0.2f64..5.0, seed in any::<u64>()
    ) {
        prop_assume!(axis.length() > 0.05);
        let shapes = bounded_shapes(&t, k, off, axis, deg, factor);
        let mut rng = Rng(seed);
        for s in &shapes {
            let (center, radius) = s.bounding_sphere();
            prop_assert!(radius.is_finite());
            for _ in 0..200 {
                let p = center + rng.unit_vector() * radius * (1.0 + 1e-6 + 3.0 * rng.uniform());
                let d = s.distance(p);
                prop_assert!(d > 0.0, "{s:?}: d = {d} outside bounding sphere");
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Outside the bounding box the distance is positive: points just off
    /// every face (where a loose box would be caught) and farther out.
    #[test]
    fn bounding_box_contains_solid(
        t in trio(), k in 0.05f64..1.5, off in v3(-3.0, 3.0), axis in v3(-1.0, 1.0),
        deg in -180.0f64..180.0, factor in 0.2f64..5.0, seed in any::<u64>()
    ) {
        prop_assume!(axis.length() > 0.05);
        let shapes = bounded_shapes(&t, k, off, axis, deg, factor);
        let mut rng = Rng(seed);
        for s in &shapes {
            let (lo, hi) = s.bounding_box();
            prop_assert!(lo.is_finite() && hi.is_finite());
            let size = (hi - lo).max(DVec3::splat(1e-3));
            for i in 0..300 {
                // A point of the box, pushed off one face.
                let mut p = lo + size * DVec3::new(rng.uniform(), rng.uniform(), rng.uniform());
                let axis = i % 3;
                let u = rng.uniform();
                let gap = size[axis] * (1e-9 + 2.0 * u * u * u);
                p[axis] = if rng.uniform() < 0.5 { hi[axis] + gap } else { lo[axis] - gap };
                let d = s.distance(p);
                prop_assert!(d > 0.0, "{s:?}: d = {d} at {p} outside the bounding box {lo} {hi}");
            }
        }
    }
}

/// The box of a box is itself, turned by quarter turns too (to rounding);
/// unions take the box of their children's boxes; planes make it infinite.
#[test]
fn bounding_box_is_tight_for_boxes_and_quarter_turns() {
    let b = Sdf::rounded_box(DVec3::new(1.0, 0.78, 0.0), DVec3::new(0.9, 0.45, 2.2), 0.18);
    let near = |(lo, hi): (DVec3, DVec3), want: (DVec3, DVec3)| {
        assert!(
            (lo - want.0).abs().max_element() < 1e-9 && (hi - want.1).abs().max_element() < 1e-9,
            "{lo} {hi}, not {want:?}"
        );
    };
    let body = (DVec3::new(0.1, 0.33, -2.2), DVec3::new(1.9, 1.23, 2.2));
    near(b.bounding_box(), body);
    // A car turned half round and moved: body and cabin.
    let car = Sdf::translate(
        DVec3::new(-1.7, 0.0, 262.0),
        Sdf::rotate(
            DVec3::Y,
            180.0,
            Sdf::union(vec![
                Sdf::rounded_box(DVec3::new(0.0, 0.78, 0.0), DVec3::new(0.9, 0.45, 2.2), 0.18),
                Sdf::rounded_box(
                    DVec3::new(0.0, 1.48, -0.15),
                    DVec3::new(0.78, 0.33, 1.15),
                    0.2,
                ),
            ]),
        ),
    );
    near(
        car.bounding_box(),
        (DVec3::new(-2.6, 0.33, 259.8), DVec3::new(-0.8, 1.81, 264.2)),
    );
    // A quarter turn about y swaps x and z.
    let turned = Sdf::rotate(
        DVec3::Y,
        90.0,
        Sdf::cuboid(DVec3::ZERO, DVec3::new(2.0, 1.0, 0.5)),
    );
    let h = DVec3::new(0.5, 1.0, 2.0);
    near(turned.bounding_box(), (-h, h));
    let (lo, hi) = Sdf::union(vec![Sdf::plane(DVec3::Y, 0.0), b.clone()]).bounding_box();
    assert!(lo.x == f64::NEG_INFINITY && hi.y == f64::INFINITY);
    near(
        Sdf::intersection(vec![Sdf::plane(DVec3::Y, 0.0), b]).bounding_box(),
        body,
    );
}

#[test]
fn bounding_sphere_of_primitives_is_tight_lower_bound() {
    // For exact primitives, d(p) >= |p - c| - r.
    let shapes = [
        Sdf::sphere(DVec3::new(1.0, 2.0, 3.0), 0.5),
        Sdf::cuboid(DVec3::ONE, DVec3::new(1.0, 2.0, 3.0)),
        Sdf::capsule(DVec3::ZERO, DVec3::new(0.0, 4.0, 0.0), 0.5),
        Sdf::cylinder(DVec3::ZERO, 1.0, 3.0),
    ];
    let mut rng = Rng(3);
    for s in &shapes {
        let (c, r) = s.bounding_sphere();
        for _ in 0..1000 {
            let p = c + rng.unit_vector() * 10.0 * rng.uniform();
            assert!(s.distance(p) >= (p - c).length() - r - 1e-12);
        }
    }
    let (_, r) = Sdf::union(vec![Sdf::plane(DVec3::Y, 0.0), shapes[0].clone()]).bounding_sphere();
    assert_eq!(r, f64::INFINITY);
    let (_, r) =
        Sdf::intersection(vec![Sdf::plane(DVec3::Y, 0.0), shapes[0].clone()]).bounding_sphere();
    assert_eq!(r, 0.5);
}

// ---- gradients of unions: the near children only ----------------------

/// The gradient of a union under a translation and a rotation, which
/// evaluates only the children that can be nearest, is bit for bit the
/// central difference over every child: on and near the surfaces (edges and
/// corners, where children tie), and at larger steps.
#[test]
fn union_gradient_prunes_without_changing_a_bit() {
    let ship = Sdf::translate(
        DVec3::new(-60.0, 0.0, 4200.0),
        Sdf::rotate(
            DVec3::Y,
            70.0,
            Sdf::union(vec![
                Sdf::cuboid(DVec3::new(0.0, 3.0, 0.0), DVec3::new(5.0, 3.0, 40.0)),
                Sdf::cuboid(DVec3::new(0.0, 8.0, -25.0), DVec3::new(4.0, 2.0, 8.0)),
                Sdf::cylinder(DVec3::new(0.0, 14.0, -25.0), 0.4, 4.0),
                Sdf::sphere(DVec3::new(0.0, 6.5, 30.0), 1.5),
                Sdf::rounded_box(DVec3::new(0.0, 6.5, 10.0), DVec3::new(3.0, 0.5, 5.0), 0.2),
            ]),
        ),
    );
    let Sdf::Translate { child, .. } = &ship else {
        unreachable!()
    };
    let Sdf::Rotate(r) = child.as_ref() else {
        unreachable!()
    };
    let full = |p: DVec3, h: f64| {
        let e = [DVec3::X * h, DVec3::Y * h, DVec3::Z * h];
        DVec3::new(
            ship.distance(p + e[0]) - ship.distance(p - e[0]),
            ship.distance(p + e[1]) - ship.distance(p - e[1]),
            ship.distance(p + e[2]) - ship.distance(p - e[2]),
        ) / (2.0 * h)
    };
    let to_world = |q: DVec3| r.local_to_world() * q + DVec3::new(-60.0, 0.0, 4200.0);
    let mut rng = Rng(7);
    let mut pruned = 0;
    for i in 0..4000 {
        // Points on the parts' surfaces, their edges and corners, and where
        // two parts meet, in the ship's frame.
        let q = match i % 4 {
            0 => DVec3::new(5.0, 3.0 + 3.0 * rng.uniform(), 40.0 * rng.uniform()),
            1 => DVec3::new(4.0, 10.0, -25.0 + 8.0 * (2.0 * rng.uniform() - 1.0)),
            2 => DVec3::new(0.0, 6.0, 30.0) + rng.unit_vector() * 1.5,
            _ => DVec3::new(0.0, 6.0, -25.0) + rng.unit_vector() * 6.0,
        };
        let p = to_world(q) + rng.unit_vector() * (1e-3 * rng.uniform());
        for h in [NORMAL_RELATIVE_STEP * 4200.0, 0.01, 0.5] {
            let (a, b) = (ship.gradient_with_step(p, h), full(p, h));
            assert!(
                a.x.to_bits() == b.x.to_bits()
                    && a.y.to_bits() == b.y.to_bits()
                    && a.z.to_bits() == b.z.to_bits(),
                "at {p} (h = {h}): {a} vs {b}"
            );
        }
        let mask = ship.near_children(p, 1e-3).expect("a union of five");
        pruned += (mask.count_ones() < 5) as u32;
    }
    assert!(pruned > 3000, "only {pruned} of 4000 points pruned a child");
}
