//! From a photograph: the camera, the marks and the apparent horizon
//! (`docs/photo.md`).
//!
//! The flow: [`picture`] reads the image's size and bytes, [`exif`] its
//! focal length; [`spec`] validates the `photo` section and the `marks` into
//! a [`spec::PhotoSetup`]; [`camera`] maps pixels to rays and back (exact
//! derivatives in dual numbers); [`horizon`] gives the apparent sea horizon
//! of stratified air. The problem layer turns target marks into pairs, and
//! the fit's objective (`crate::fit::objective`) fits the camera's free
//! numbers beside the air's.

pub mod camera;
pub mod exif;
pub mod horizon;
pub mod picture;
pub mod spec;
