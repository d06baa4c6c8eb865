//! Real air (docs/air.md).
pub mod hydrostatic;
pub mod pchip;
pub mod standard;
