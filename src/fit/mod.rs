//! Fitting the free parameters to the point pairs.

pub mod history;
pub mod lm;

pub use history::{History, IterationRecord, RunHistory};
