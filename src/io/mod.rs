//! Files in and out, and nothing else: reading JSON input with messages that name
//! the file and the field ([`json`]), the check every command makes of its
//! output paths before it starts work (`output.rs`: [`check_outputs`]), and the
//! atomic writer every output goes through (`atomic.rs`: [`write_atomic`]),
//! and the sounding files `mirage sounding` reads ([`sounding`]).
//! What the files mean lives with their types (the problem in
//! [`crate::problem`], results in [`crate::evaluate`] and
//! [`crate::fit::report`], scenes in [`crate::scene`]).

mod atomic;
pub mod json;
mod output;
pub mod sounding;

pub use atomic::{write_atomic, write_json};
pub use output::{Output, OutputKind, check_outputs};
