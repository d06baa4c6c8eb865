//! Fitting the free parameters to the point pairs.

pub mod lm;
