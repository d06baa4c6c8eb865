//! Errors a user can see. Bad input is always one line naming the file, the
//! field and what is wrong, and exits with code 2.

use std::path::{Path, PathBuf};

/// Every error mirage reports.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The user's input is invalid (exit code 2).
    #[error("{file}: {field}: {message}")]
    Input {
        /// The file (or `<command line>`).
        file: String,
        /// Path of the field within the file (`medium.hotspots[0].a`), or `-`.
        field: String,
        /// What is wrong.
        message: String,
    },
    /// Reading or writing a file failed (exit code 1).
    #[error("{}: {source}", path.display())]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// Anything else that went wrong while running (exit code 1).
    #[error("{0}")]
    Failed(String),
}

impl Error {
    /// An input error in `file` at `field`.
    pub fn input(file: &Path, field: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Input {
            file: file.display().to_string(),
            field: field.into(),
            message: message.into(),
        }
    }

    /// The process exit code for this error.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Input { .. } => 2,
            Error::Io { .. } | Error::Failed(_) => 1,
        }
    }
}

/// Result with mirage's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
