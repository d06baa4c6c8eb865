//! The physical sky and the veiling glare in renders: the noon and sunset
//! variants of the bundled scenes load and render; a sunset's glare brightens
//! the picture around the sun and fades with distance, takes its light from
//! the sun and adds nothing to albedo renders; the sky near the horizon is
//! redder at sunset than at noon.

use mirage::render::{RenderOptions, Renderer, Shading};
use mirage::scene::Scene;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

fn scene(name: &str) -> Scene {
    Scene::load(&root().join("problems/scenes").join(format!("{name}.json"))).unwrap()
}

fn small(glare: bool, shading: Shading) -> RenderOptions {
    RenderOptions {
        width: Some(160),
        glare,
        shading,
        ..RenderOptions::default()
    }
}

fn luminance(p: [f32; 3]) -> f64 {
    0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64
}

#[test]
fn noon_and_sunset_variants_load_with_a_physical_sky_and_glare() {
    for base in ["road", "sea", "desert"] {
        for v in ["noon", "sunset"] {
            let s = scene(&format!("{base}-{v}"));
            assert!(matches!(
                s.sky,
                mirage::scene::description::SkySpec::Physical { .. }
            ));
            assert!(s.glare.is_some(), "{base}-{v}");
            // Same air and objects as the base scene.
            let b = scene(base);
            assert_eq!(s.medium, b.medium);
            assert_eq!(s.objects.len(), b.objects.len());
        }
    }
}

#[test]
fn sunset_glare_veils_the_picture_around_the_sun() {
    let s = scene("road-sunset");
    let with = Renderer::new(&s, &small(true, Shading::Lit)).render();
    let without = Renderer::new(&s, &small(false, Shading::Lit)).render();
    let g = with.stats.glare.expect("glare applied");
    assert!(g.sources > 0, "the sun is in the frame");
    assert!(without.stats.glare.is_none());
    let (w, h) = (with.width, with.height);
    // Where is the sun? The brightest pixel without glare.
    let (sun_i, _) = without
        .pixels
        .iter()
        .enumerate()
        .map(|(i, p)| (i, luminance(*p)))
        .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
    let (sx, sy) = ((sun_i as u32 % w) as f64, (sun_i as u32 / w) as f64);
    // Glare only adds light away from the sources, and adds more nearer them.
    let mut near = (0.0, 0);
    let mut far = (0.0, 0);
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let (a, b) = (luminance(with.pixels[i]), luminance(without.pixels[i]));
            if luminance(without.pixels[i]) > 20.0 {
                // A source keeps all but the spread fraction of its light.
                assert!(a < b && a > 0.99 * b, "source {x},{y}: {a} vs {b}");
                continue;
            }
            assert!(a >= b - 1e-6, "pixel {x},{y} darker with glare: {a} < {b}");
            let d = (x as f64 - sx).hypot(y as f64 - sy);
            if d < 0.25 * w as f64 {
                near.0 += a - b;
                near.1 += 1;
            } else if d > 0.6 * w as f64 {
                far.0 += a - b;
                far.1 += 1;
            }
        }
    }
    let (near, far) = (near.0 / near.1 as f64, far.0 / far.1.max(1) as f64);
    assert!(near > 0.0 && near > 3.0 * far, "near {near}, far {far}");
    // Albedo renders show no glare.
    let albedo = Renderer::new(&s, &small(true, Shading::Albedo)).render();
    assert!(albedo.stats.glare.is_none());
}

#[test]
fn the_sky_over_the_road_is_redder_at_sunset_than_at_noon() {
    let ratio = |name: &str| {
        let s = scene(name);
        let r = Renderer::new(
            &s,
            &RenderOptions {
                width: Some(64),
                glare: false,
                ..RenderOptions::default()
            },
        )
        .render();
        // The top row: sky between the trees, half a degree up.
        let (mut red, mut blue) = (0.0, 0.0);
        for p in &r.pixels[..r.width as usize] {
            red += p[0] as f64;
            blue += p[2] as f64;
        }
        red / blue
    };
    let (noon, sunset) = (ratio("road-noon"), ratio("road-sunset"));
    assert!(
        sunset > 3.0 * noon,
        "R/B at noon {noon}, at sunset {sunset}"
    );
}
