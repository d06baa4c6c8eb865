//! Scenes seen through the medium: objects as signed distance fields
//! ([`sdf`]), and the scene files the renderer reads ([`description`]).

pub mod description;
pub mod sdf;

pub use description::Scene;
