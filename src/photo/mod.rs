//! From a photograph to the air: reading the photo and its EXIF focal length.
pub mod exif;
pub mod picture;
