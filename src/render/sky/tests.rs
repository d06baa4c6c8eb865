use super::*;
use crate::scene::description::Sun;
use std::f64::consts::PI;

fn sun(elevation_deg: f64) -> Sun {
    let e = elevation_deg.to_radians();
    Sun {
        direction: DVec3::new(0.0, e.sin(), e.cos()),
        irradiance: [1.0; 3],
    }
}

#[test]
fn vertical_transmittance_matches_closed_form() {
    let a = Atmosphere::default();
    let table = TransmittanceTable::new(&a);
    let h_top = a.top_radius - a.bottom_radius;
    let [lo, _, hi] = a.ozone_tent;
    for c in 0..3 {
        let closed = a.rayleigh_scattering[c]
            * a.rayleigh_scale_height
            * (1.0 - (-h_top / a.rayleigh_scale_height).exp())
            + a.mie_extinction * a.mie_scale_height * (1.0 - (-h_top / a.mie_scale_height).exp())
            + a.ozone_absorption[c] * 0.5 * (hi - lo);
        let expected = (-closed).exp();
        let direct = (-a.optical_depth(a.bottom_radius, 1.0, 4000)[c]).exp();
        let tabled = table.transmittance(a.bottom_radius, 1.0)[c];
        assert!(
            (direct - expected).abs() < 1e-6,
            "{c}: {direct} vs {expected}"
        );
        assert!(
            (tabled - expected).abs() < 1e-3,
            "{c}: {tabled} vs {expected}"
        );
    }
    let t = table.transmittance(a.bottom_radius, 1.0);
    for (got, want) in t.iter().zip([0.940, 0.868, 0.762]) {
        assert!((got - want).abs() < 1e-3, "{t:?}");
    }
}

#[test]
fn transmittance_table_error_against_direct_integration() {
    let a = Atmosphere::default();
    let table = TransmittanceTable::new(&a);
    let (mut worst, mut worst_low): (f64, f64) = (0.0, 0.0);
    for i in 0..40 {
        let h = 60_000.0 * (i as f64 / 39.0).powi(3);
        let r = a.bottom_radius + h;
        let mu_horizon = -(1.0 - (a.bottom_radius / r).powi(2)).max(0.0).sqrt();
        for j in 0..60 {
            // Dense near the horizon, where mirages look.
            let s = j as f64 / 59.0;
            let mu = mu_horizon + 1e-9 + (1.0 - mu_horizon) * s.powi(3);
            let t_ref = a.optical_depth(r, mu, 8000).map(|d| (-d).exp());
            let t_tab = table.transmittance(r, mu);
            for c in 0..3 {
                if t_ref[c] > 1e-3 {
                    let e = (t_tab[c] / t_ref[c] - 1.0).abs();
                    worst = worst.max(e);
                    if h < 10_000.0 {
                        worst_low = worst_low.max(e);
                    }
                }
            }
        }
    }
    eprintln!(
        "transmittance table: worst relative error {worst:.2e} (below 10 km: {worst_low:.2e})"
    );
    assert!(worst < 6e-3, "worst relative error {worst}");
    assert!(
        worst_low < 1e-3,
        "worst relative error below 10 km {worst_low}"
    );
}

#[test]
fn phase_functions_integrate_to_one() {
    let n = 20_000;
    let mut r = 0.0;
    let mut m = 0.0;
    for i in 0..n {
        let nu = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
        r += rayleigh_phase(nu);
        m += cornette_shanks_phase(nu, 0.8);
    }
    let w = 2.0 * PI * 2.0 / n as f64;
    assert!((r * w - 1.0).abs() < 2e-3, "{}", r * w);
    assert!((m * w - 1.0).abs() < 2e-3, "{}", m * w);
}

#[test]
fn noon_zenith_is_blue_and_sunset_horizon_is_redder() {
    let s = PhysicalSkySettings::default();
    let noon = PhysicalSky::new(&s, &sun(60.0), 1.5, 1e-3);
    let z = noon.radiance(DVec3::Y);
    assert!(z[2] > z[1] && z[1] > z[0], "zenith {z:?}");
    let sunset = PhysicalSky::new(&s, &sun(1.0), 1.5, 1e-3);
    let toward = DVec3::new(0.0, 0.02, 1.0);
    let a = noon.radiance(toward);
    let b = sunset.radiance(toward);
    assert!(b[0] / b[2] > 1.5 * a[0] / a[2], "noon {a:?}, sunset {b:?}");
    // Sunlight reddens too.
    let tn = noon.sun_transmittance();
    let ts = sunset.sun_transmittance();
    assert!(ts[0] / ts[2] > 5.0 * tn[0] / tn[2], "{tn:?} {ts:?}");
}

#[test]
fn sky_view_table_matches_direct_integration() {
    let s = PhysicalSkySettings::default();
    let mut worst: f64 = 0.0;
    for elev in [60.0, 10.0, 0.5] {
        let sky = PhysicalSky::new(&s, &sun(elev), 1.5, 1e-3);
        for (e, az) in [
            (0.001, 0.3),
            (0.01, 2.0),
            (0.3, 1.0),
            (1.0, 0.05),
            (0.05, 3.0),
            (1.4, 2.5),
        ] {
            let dir = DVec3::new(
                f64::cos(e) * f64::sin(az),
                f64::sin(e),
                f64::cos(e) * f64::cos(az),
            );
            let a = sky.diffuse(dir);
            let b = sky.single_scattering_reference(dir);
            for c in 0..3 {
                worst = worst.max((a[c] / b[c] - 1.0).abs());
            }
        }
    }
    eprintln!("sky-view table: worst relative error {worst:.2e}");
    assert!(worst < 0.01, "worst relative error {worst}");
}

#[test]
fn sun_disc_and_stars() {
    let s = PhysicalSkySettings::default();
    let noon = PhysicalSky::new(&s, &sun(30.0), 1.5, 1e-3);
    let d = noon.sun_disc().unwrap();
    let at_sun = noon.radiance(d.direction);
    let beside = noon.radiance((d.direction + DVec3::X * 0.01).normalize());
    assert!(at_sun[1] > 1e3 * beside[1]);
    // The disc's flux is the transmitted irradiance.
    let flux = d.radiance[1] * PI * SUN_ANGULAR_RADIUS * SUN_ANGULAR_RADIUS;
    assert!((flux - noon.sun_transmittance()[1]).abs() < 1e-12);
    // No star survives the day; some shine at night.
    let night = PhysicalSky::new(&s, &sun(-30.0), 1.5, 1e-3);
    let (mut day_stars, mut night_stars) = (0, 0);
    for i in 0..200 {
        for j in 0..100 {
            let az = 1.0 + i as f64 * 0.0031;
            let e = 0.5 + j as f64 * 0.0007;
            let dir = DVec3::new(
                f64::cos(e) * f64::sin(az),
                f64::sin(e),
                f64::cos(e) * f64::cos(az),
            );
            if noon.radiance(dir)[1] > noon.diffuse(dir)[1] {
                day_stars += 1;
            }
            if night.radiance(dir)[1] > night.diffuse(dir)[1] {
                night_stars += 1;
            }
        }
    }
    assert_eq!(day_stars, 0);
    assert!(night_stars > 0);
    assert_eq!(night.sun_transmittance(), [0.0; 3]);
}
