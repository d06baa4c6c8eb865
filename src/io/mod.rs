//! Files in and out, and nothing else: reading JSON input with messages that name
//! the file and the field ([`json`]), and the atomic writer every output goes
//! through (`atomic.rs`: [`write_atomic`]). What the files mean lives with their types (the
//! problem in [`crate::problem`], results in [`crate::evaluate`] and
//! [`crate::fit::report`], scenes in [`crate::scene`]).

mod atomic;
pub mod json;

pub use atomic::{check_not_input, write_atomic, write_json};
