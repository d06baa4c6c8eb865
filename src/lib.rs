//! mirage: inverse design of atmospheric mirages.
//!
//! Data flows one way: problem file ([`problem`]) → parameters ([`medium::Medium`]) →
//! compiled medium ([`medium::Field`]) → rays ([`trace`]) → residuals →
//! solver → fitted medium → images.

pub mod cli;
pub mod compare;
pub mod envmap;
pub mod error;
pub mod evaluate;
pub mod fit;
pub mod geo;
pub mod interrupt;
pub mod io;
pub mod math;
pub mod medium;
pub mod pair;
pub mod photo;
pub mod plot;
#[cfg(feature = "preview")]
pub mod preview;
pub mod problem;
pub mod profile;
#[cfg(feature = "python")]
mod python;
pub mod refraction;
pub mod render;
pub mod scene;
pub mod sightline;
pub mod terrain;
pub mod trace;
pub mod tradeoff;
pub mod validate;
