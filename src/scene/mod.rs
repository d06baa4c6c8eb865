//! Scenes seen through the medium: objects as signed distance fields
//! ([`sdf`]), the scene files the renderer reads ([`description`]) and
//! their glare section ([`glare`]). Descriptions only: nothing here renders.

pub mod description;
pub mod glare;
pub mod sdf;

pub use description::Scene;
