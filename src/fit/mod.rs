//! Fitting the free parameters to the point pairs.

pub mod history;
pub mod lm;
pub mod objective;

pub use history::{History, IterationRecord, RunHistory};
