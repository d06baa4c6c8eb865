//! Plots of a problem and of a fit, as PNG or SVG.
//!
//! - [`draw_rays`]: the ray diagram of a problem (side view of every pair's ray
//!   beside the refractivity profile δ(y)).
//! - [`draw_air`]: a medium's T, P, n − 1 and dn/dh against height (`mirage air`).
//! - [`draw_refraction`]: refraction against apparent elevation, with
//!   Bennett's formula and the dip (`mirage refraction`).
//! - [`draw_convergence`]: how a fit's objective and parameters moved.
//! - [`draw_grow`]: the same for a grown fit, beside the criterion per step.
//! - [`draw_tradeoff`]: the speed/accuracy trade of the integrators.
//! - [`draw_overlay`]: a photo with its marks, where the air puts them and the
//!   apparent horizon.
//!
//! Text is drawn with an embedded DejaVu Sans ([`ensure_font`]), so plotting
//! needs no system font library; raster text is placed glyph by glyph (see
//! `text.rs`) because plotters' own placement spaces letters unevenly. Every
//! figure is rendered in memory and written with [`crate::io::write_atomic`]: a
//! failed plot never leaves a partial file.

mod air;
mod axes;
mod convergence;
mod ensemble;
mod figure;
mod grow;
mod legend;
mod marker;
mod overlay;
mod raster;
mod rays;
mod refraction;
mod style;
mod text;
mod tradeoff;

#[cfg(test)]
mod tests;

pub use air::draw_air;
pub use convergence::draw_convergence;
pub use ensemble::draw_ensemble;
pub use figure::ImageFormat;
pub use grow::draw_grow;
pub use overlay::{Overlay, OverlayMark, draw_overlay};
pub use rays::draw_rays;
pub use refraction::draw_refraction;
pub use style::ensure_font;
pub use tradeoff::draw_tradeoff;
