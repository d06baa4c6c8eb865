//! In stratified air, where things appear is fixed by Snell's invariant: along a
//! ray n(y)·cos θ = n(h₀)·cos θ₀. A ray launched at θ₀ from h₀ turns where
//! n(y) = n(h₀)·cos θ₀, and its horizontal distance to height y is
//! ∫ c / √(n² − c²) dy (c = n(h₀) cos θ₀). The renderer's images must put the
//! edges there to 0.1 px: the apparent horizon of an inferior mirage, the edge
//! of a superior mirage's looming sea, and both edges of a wall's erect and
//! inverted images, with the path table (default) and without it.

use mirage::math::V3;
use mirage::medium::{IndexField, LogisticMedium};
use mirage::render::{RenderOptions, Rendered, Shading, render};
use mirage::scene::Scene;
use std::path::Path;

/// Image of one column: the edges are located from the covered fraction of
/// the transition pixels, sampled 256 times per pixel.
const H: u32 = 200;
const FOV: f64 = 1.0;
const SPP: u32 = 256;

struct Setup {
    medium: LogisticMedium,
    eye: f64,
    pitch: f64,
}

impl Setup {
    fn n(&self, y: f64) -> f64 {
        1.0 + self.medium.field().delta(V3::new(0.0, y, 0.0))
    }

    fn delta(&self, y: f64) -> f64 {
        self.medium.field().delta(V3::new(0.0, y, 0.0))
    }

    /// c − 1 for launch elevation θ₀, without cancellation.
    fn c1(&self, theta: f64) -> f64 {
        let d0 = self.delta(self.eye);
        d0 - (1.0 + d0) * 2.0 * (0.5 * theta).sin().powi(2)
    }

    /// ∫_{a}^{b} c/√(n² − c²) dy on a branch with no turning point inside,
    /// Gauss–Legendre on many panels.
    fn run(&self, c1: f64, a: f64, b: f64) -> f64 {
        let c = 1.0 + c1;
        integrate(a, b, |y| {
            let dn = self.delta(y) - c1;
            c / (dn * (2.0 + self.delta(y) + c1)).sqrt()
        })
    }

    /// The same from the turning point y_t (where n = c) to y, with y = y_t + u²
    /// so that the 1/√ singularity disappears.
    fn past_turn(&self, c1: f64, yt: f64, y: f64) -> f64 {
        let c = 1.0 + c1;
        integrate(0.0, (y - yt).abs().sqrt(), |u| {
            let yy = yt + u * u * (y - yt).signum();
            let dn = self.delta(yy) - c1;
            if dn <= 0.0 {
                return 0.0;
            }
            2.0 * u * c / (dn * (2.0 + self.delta(yy) + c1)).sqrt()
        })
    }

    /// The height in [lo, hi] where δ = c1 (δ monotone there).
    fn turning(&self, c1: f64, lo: f64, hi: f64) -> f64 {
        let (mut a, mut b) = (lo, hi);
        let fa = self.delta(a) - c1;
        for _ in 0..64 {
            let m = 0.5 * (a + b);
            if (self.delta(m) - c1).signum() == fa.signum() {
                a = m;
            } else {
                b = m;
            }
        }
        0.5 * (a + b)
    }

    /// Continuous pixel row of the centre column's ray at elevation θ.
    fn row(&self, theta: f64) -> f64 {
        let t = (0.5 * FOV.to_radians()).tan();
        0.5 * H as f64 * (1.0 - (theta - self.pitch).tan() / t)
    }

    fn scene(&self, ground: &str, objects: &str, step: f64) -> Scene {
        self.scene_with_sky(ground, objects, step, [0.0, 0.0, 1.0])
    }

    fn scene_with_sky(&self, ground: &str, objects: &str, step: f64, sky: [f64; 3]) -> Scene {
        let look = [0.0, self.eye + 1000.0 * self.pitch.tan(), 1000.0];
        let text = format!(
            r#"{{ "camera": {{ "position": [0, {}, 0], "look_at": {look:?}, "vertical_fov": {FOV},
                              "width": 1, "height": {H} }},
                 "medium": {},
                 {ground}
                 "sky": {{ "type": "gradient", "zenith": {sky:?}, "horizon": {sky:?} }},
                 "objects": [{objects}],
                 "trace": {{ "step": {step}, "max_distance": 30000 }} }}"#,
            self.eye,
            serde_json::to_string(&self.medium).unwrap()
        );
        Scene::parse(&text, Path::new("snell.json")).unwrap()
    }
}

fn integrate(a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
    // 8-point Gauss–Legendre on 400 panels: far below 1e-9 relative for the
    // smooth integrands here.
    const X: [f64; 4] = [
        0.183_434_642_495_65,
        0.525_532_409_916_329,
        0.796_666_477_413_627,
        0.960_289_856_497_536,
    ];
    const W: [f64; 4] = [
        0.362_683_783_378_362,
        0.313_706_645_877_887,
        0.222_381_034_453_374,
        0.101_228_536_290_376,
    ];
    let n = 100;
    let h = (b - a) / n as f64;
    let mut sum = 0.0;
    for k in 0..n {
        let m = a + (k as f64 + 0.5) * h;
        for j in 0..4 {
            sum += W[j] * (f(m - 0.5 * h * X[j]) + f(m + 0.5 * h * X[j]));
        }
    }
    sum * 0.5 * h
}

fn bisect(mut lo: f64, mut hi: f64, f: impl Fn(f64) -> f64) -> f64 {
    let flo = f(lo);
    for _ in 0..64 {
        let m = 0.5 * (lo + hi);
        if (f(m) > 0.0) == (flo > 0.0) {
            lo = m;
        } else {
            hi = m;
        }
    }
    0.5 * (lo + hi)
}

fn albedo(scene: &Scene, path_reuse: bool) -> Rendered {
    render(
        scene,
        &RenderOptions {
            shading: Shading::Albedo,
            samples_per_pixel: Some(SPP),
            path_reuse,
            hit_fraction: 0.001,
            ..RenderOptions::default()
        },
    )
}

/// Fraction of each row's samples whose albedo is `colour` (channel index).
fn fractions(img: &Rendered, channel: usize) -> Vec<f64> {
    (0..H).map(|j| img.pixel(0, j)[channel] as f64).collect()
}

/// Top edge of the band of rows where `f` > 0 (the class lies below the edge).
fn top_edge(f: &[f64]) -> f64 {
    let j = f
        .iter()
        .position(|&v| v > 1e-9)
        .expect("class not in the image");
    j as f64 + 1.0 - f[j]
}

/// Hot ground: a thin layer (10 cm) where n grows with height,
/// δ = −C·k·σ(−y/0.1): a textbook inferior mirage.
fn inferior() -> Setup {
    let medium: LogisticMedium =
        serde_json::from_str(r#"{"scale": 0.05, "background": {"n": -1.0, "a": -0.1}}"#).unwrap();
    Setup {
        medium,
        eye: 1.5,
        pitch: -0.35f64.to_radians(),
    }
}

/// What the centre column's ray at θ₀ meets in the inferior-mirage scene: a
/// wall `WALL_D` metres away, blue from `WALL_B` to `WALL_H` metres, green
/// below, red ground, black sky.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Seen {
    Sky,
    Upper,
    Lower,
    Ground,
}

const WALL_D: f64 = 300.0;
const WALL_H: f64 = 1.6;
const WALL_B: f64 = 0.8;

impl Setup {
    /// The ray's height when it is `d` metres away, or `None` if it meets the
    /// ground first; by Snell's invariant alone (quadrature of dx/dy).
    fn height_at(&self, theta: f64, d: f64) -> Option<f64> {
        let c1 = self.c1(theta);
        let solve = |lo: f64, hi: f64, x: &dyn Fn(f64) -> f64| bisect(lo, hi, |y| x(y) - d);
        if theta > 0.0 {
            return Some(solve(self.eye, 60.0, &|y| self.run(c1, self.eye, y)));
        }
        if self.delta(0.0) >= c1 {
            // It does not turn above the ground.
            let x_ground = self.run(c1, 0.0, self.eye);
            return (x_ground > d).then(|| solve(0.0, self.eye, &|y| self.run(c1, y, self.eye)));
        }
        let yt = self.turning(c1, 0.0, self.eye);
        let down = self.past_turn(c1, yt, self.eye);
        if down >= d {
            Some(solve(yt, self.eye, &|y| down - self.past_turn(c1, yt, y)))
        } else {
            Some(solve(yt, 60.0, &|y| down + self.past_turn(c1, yt, y)))
        }
    }

    fn seen(&self, theta: f64) -> Seen {
        match self.height_at(theta, WALL_D) {
            None => Seen::Ground,
            Some(y) if y >= WALL_H => Seen::Sky,
            Some(y) if y >= WALL_B => Seen::Upper,
            Some(_) => Seen::Lower,
        }
    }
}

#[test]
fn inferior_mirage_apparent_horizon_and_inverted_wall() {
    let s = inferior();
    // Apparent horizon: the ray that grazes the ground, n(0) = n(h₀) cos θ₀.
    let horizon = -(s.n(0.0) / s.n(s.eye)).acos();
    // Every edge in the column: scan θ₀ finely, bisect each change of what is
    // seen (an edge is where a ray meets the wall's top or colour line, or
    // grazes the ground).
    let lo = s.pitch - 0.5 * FOV.to_radians() + 1e-6;
    let hi = s.pitch + 0.5 * FOV.to_radians() - 1e-6;
    let n = 400;
    let mut edges: Vec<(f64, Seen, Seen)> = Vec::new();
    let mut prev = (hi, s.seen(hi));
    for k in 1..=n {
        let t = hi - (hi - lo) * k as f64 / n as f64;
        let c = s.seen(t);
        if c != prev.1 {
            let (mut a, mut b) = (t, prev.0);
            for _ in 0..50 {
                let m = 0.5 * (a + b);
                if s.seen(m) == c {
                    a = m;
                } else {
                    b = m;
                }
            }
            edges.push((0.5 * (a + b), prev.1, c));
        }
        prev = (t, c);
    }
    for (t, above, below) in &edges {
        println!(
            "predicted edge at {:.6}°: {above:?} above, {below:?} below",
            t.to_degrees()
        );
    }
    // The wall's erect image (blue over green) and, below it, its inverted
    // image (green over blue), then the mirrored sky and the ground.
    let order: Vec<Seen> = std::iter::once(edges[0].1)
        .chain(edges.iter().map(|e| e.2))
        .collect();
    assert_eq!(
        order,
        [
            Seen::Sky,
            Seen::Upper,
            Seen::Lower,
            Seen::Upper,
            Seen::Sky,
            Seen::Ground
        ],
        "unexpected image structure"
    );
    let ground_edge = edges.last().unwrap().0;
    assert!(
        (ground_edge - horizon).abs() < 1e-7,
        "{ground_edge} vs {horizon}"
    );

    let wall = format!(
        r#"{{ "albedo": [0, 0, 1], "shape": {{ "type": "box", "center": [0, {}, {}], "half_extents": [50, {}, 0.5] }} }},
           {{ "albedo": [0, 1, 0], "shape": {{ "type": "box", "center": [0, {}, {}], "half_extents": [50, {}, 0.5] }} }}"#,
        0.5 * (WALL_B + WALL_H),
        WALL_D + 0.5,
        0.5 * (WALL_H - WALL_B),
        0.5 * WALL_B,
        WALL_D + 0.5,
        0.5 * WALL_B
    );
    let ground = r#""ground": { "albedo": [1, 0, 0] },"#;
    for path_reuse in [true, false] {
        let img = albedo(&s.scene_with_sky(ground, &wall, 1.0, [0.0; 3]), path_reuse);
        let frac = |class: Seen, j: usize| -> f64 {
            let p = img.pixel(0, j as u32);
            match class {
                Seen::Ground => p[0] as f64,
                Seen::Lower => p[1] as f64,
                Seen::Upper => p[2] as f64,
                Seen::Sky => 1.0 - (p[0] + p[1] + p[2]) as f64,
            }
        };
        for &(theta, above, below) in &edges {
            let want = s.row(theta);
            let j = want.floor() as usize;
            // The class below the edge fills the pixel's lower part.
            let got = j as f64 + 1.0 - frac(below, j);
            let also = j as f64 + frac(above, j);
            println!(
                "path reuse {path_reuse}: {above:?}/{below:?} at {:.6}°: rendered row {got:.4} ({also:.4}), Snell {want:.4}",
                theta.to_degrees()
            );
            assert!(
                (got - want).abs() < 0.1 && (also - want).abs() < 0.1,
                "{above:?}/{below:?}: {got} vs {want} (path reuse {path_reuse})"
            );
        }
    }
}

#[test]
fn superior_mirage_looming_edge() {
    // Warm air over cold water: n falls through an inversion at 10 m.
    let medium: LogisticMedium = serde_json::from_str(
        r#"{"scale": 0.03, "inversion": {"n": 1.0, "a": 1.0, "height": 10.0}}"#,
    )
    .unwrap();
    let s = Setup {
        medium,
        eye: 4.0,
        pitch: 0.7f64.to_radians(),
    };
    // Rays below θ_e turn back down to the sea; above it they reach the top
    // of the model, where n = n(∞) = 1: n(∞)·1 = n(h₀) cos θ_e.
    let n_top = s.n(1e4);
    let edge = (n_top / s.n(s.eye)).acos();
    let ground = r#""ground": { "albedo": [1, 0, 0] },"#;
    for path_reuse in [true, false] {
        let img = albedo(&s.scene(ground, "", 4.0), path_reuse);
        let sea = fractions(&img, 0);
        let got = top_edge(&sea);
        let want = s.row(edge);
        println!(
            "path reuse {path_reuse}: looming edge {:.6}°: rendered row {got:.4}, Snell {want:.4}",
            edge.to_degrees()
        );
        assert!((got - want).abs() < 0.1, "{got} vs {want}");
    }
}
