//! Scenes seen through the medium: objects as signed distance fields.

pub mod sdf;
