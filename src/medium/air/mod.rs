//! Real air (docs/air.md): the state of the air turned into a refractive index.
pub mod humidity;
pub mod hydrostatic;
pub mod pchip;
pub mod refractivity;
pub mod standard;
