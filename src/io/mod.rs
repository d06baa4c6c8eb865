//! The file formats, in one place: problem files in, results out, and the
//! atomic writer every output goes through.

mod atomic;
pub mod problem;
pub mod report;

pub use atomic::{check_not_input, write_atomic, write_json};
pub use problem::{Problem, SolverSettings};
