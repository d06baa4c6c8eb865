//! Dispersion in a render: R, G and B each traced through the air at its own
//! vacuum wavelength, so that refraction separates the colours (the green
//! rim of a low sun seen through a duct, the coloured fringes of a mirage).
//!
//! Algorithm: the scene is rendered three times, once per channel, each time
//! with the medium at that channel's wavelength ([`CHANNEL_WAVELENGTHS`],
//! through [`crate::medium::Medium::at_wavelength`]) and the veiling glare
//! off; the image takes R from the first render, G from the second and B from
//! the third, and the glare is then applied once to that image (its sources
//! are chosen by luminance, so it must see the combined colours). This costs
//! three renders and changes nothing in the non-dispersive path: a render is
//! exactly a plain render of the same scene with the channel's wavelength
//! written into `air.wavelength`. A per-ray channel split would share the
//! shading of the three rays but not their paths, which is where the cost is.
//!
//! The wavelengths are those the physical sky already assigns to its channels
//! (`sky::WAVELENGTHS_UM`: 680, 550, 440 nm, Bruneton's choice for Rayleigh
//! scattering), so a pixel's colour is one consistent three-wavelength model:
//! the sun is reddened and refracted at the same wavelengths. They lie near
//! the ends of the eye's red and blue response rather than at the dominant
//! wavelengths of the sRGB primaries (≈ 611, 549, 464 nm): with Ciddor's
//! formula n − 1 at 440 nm exceeds that at 680 nm by 1.6 %, against 1.0 %
//! between 464 and 611 nm, so fringes are about 1.5× wider than a
//! sensor-weighted average would make them; at the widths involved (a few
//! arcseconds for a sunset) this keeps them visible at practical image sizes.
//!
//! Only real air has a wavelength: scenes of other kinds that ask for
//! dispersion are refused when they are read (`dispersion`).

use super::{RenderOptions, Rendered, Renderer};
use crate::scene::Scene;

/// The vacuum wavelengths of the R, G and B channels (nm), the physical
/// sky's channel wavelengths.
pub const CHANNEL_WAVELENGTHS: [f64; 3] = [680.0, 550.0, 440.0];

impl Renderer {
    /// The three per-channel renderers of a dispersive scene, or `None` if the
    /// scene is not dispersive (or its medium has no wavelength, or the render is
    /// straight, where the air does nothing).
    pub(super) fn channel_renderers(
        scene: &Scene,
        options: &RenderOptions,
    ) -> Option<Box<[Renderer; 3]>> {
        if !scene.dispersion || options.straight {
            return None;
        }
        let mut media = Vec::with_capacity(3);
        for nm in CHANNEL_WAVELENGTHS {
            media.push(scene.medium.at_wavelength(nm)?);
        }
        let channel_options = RenderOptions {
            glare: false,
            progress: false,
            ..*options
        };
        let mut it = media.into_iter().map(|medium| {
            let s = Scene {
                medium,
                dispersion: false,
                ..scene.clone()
            };
            Renderer::new(&s, &channel_options)
        });
        let (r, g, b) = (it.next()?, it.next()?, it.next()?);
        Some(Box::new([r, g, b]))
    }

    /// Renders the three channels and takes channel c of image c; the work of
    /// all three is summed in the stats (the glare is the caller's).
    pub(super) fn render_channels(channels: &[Renderer; 3]) -> Rendered {
        let images = channels.each_ref().map(|r| r.render());
        let [r, g, b] = &images;
        let pixels = r
            .pixels
            .iter()
            .zip(&g.pixels)
            .zip(&b.pixels)
            .map(|((r, g), b)| [r[0], g[1], b[2]])
            .collect();
        let mut stats = r.stats;
        for s in [&g.stats, &b.stats] {
            stats.samples += s.samples;
            stats.table_samples += s.table_samples;
            stats.march += s.march;
            stats.shadow += s.shadow;
            stats.table_seconds += s.table_seconds;
            stats.grid_seconds += s.grid_seconds;
            stats.setup_seconds += s.setup_seconds;
            stats.trace_seconds += s.trace_seconds;
        }
        Rendered {
            width: r.width,
            height: r.height,
            pixels,
            stats,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::sky::WAVELENGTHS_UM;

    #[test]
    fn channel_wavelengths_are_the_sky_channels() {
        for (nm, um) in CHANNEL_WAVELENGTHS.iter().zip(WAVELENGTHS_UM) {
            assert!((nm - um * 1000.0).abs() < 1e-9);
        }
        let (lo, hi) = crate::medium::air::WAVELENGTH_RANGE;
        assert!(CHANNEL_WAVELENGTHS.iter().all(|w| (lo..=hi).contains(w)));
    }
}
