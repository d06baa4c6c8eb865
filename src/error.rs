//! Errors a user can see, in one vocabulary.
//!
//! - [`FieldError`] is what every parser and validator returns: the path of the
//!   field inside its document (`medium.hotspots[0].a`) and what is wrong. A
//!   validator of a part returns paths relative to that part; the caller prefixes
//!   them with [`FieldError::within`] as the error travels up.
//! - [`Error`] is what a command returns. Bad input is [`Error::Input`] (a
//!   [`FieldError`] and the file it came from), [`Error::Usage`] (a command-line
//!   flag) or [`Error::Output`] (an output path that cannot be written, found
//!   before the work starts): one line naming the file or flag, the field or
//!   path and what is wrong, exit code 2. A check the user asked for that the
//!   result misses ([`Error::LimitsMissed`]) is exit code 1; everything else
//!   (files that cannot be read or written, images that cannot be encoded, the
//!   GPU, the solver) has a typed variant and exit code 1 too. A run stopped
//!   by Ctrl-C is [`Error::Interrupted`], exit code 130.

use std::path::{Path, PathBuf};

/// The path of the whole document (or of no particular field), in messages.
pub const WHOLE_DOCUMENT: &str = "-";

/// A problem with one field of an input document. Shown as `path: message`,
/// or as the message alone when it is about the whole document
/// ([`WHOLE_DOCUMENT`]), so that no `-:` stands where a field name goes.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{}{message}", if path == WHOLE_DOCUMENT { String::new() } else { format!("{path}: ") })]
pub struct FieldError {
    /// Path of the field (`medium.hotspots[0].a`, `objects[2].radius`), relative
    /// to whatever the validator was given; [`WHOLE_DOCUMENT`] for none.
    pub path: String,
    /// What is wrong, in words.
    pub message: String,
}

impl FieldError {
    /// An error at `path`.
    pub fn new(path: impl Into<String>, message: impl Into<String>) -> Self {
        FieldError {
            path: path.into(),
            message: message.into(),
        }
    }

    /// An error about the document as a whole (no particular field).
    pub fn whole(message: impl Into<String>) -> Self {
        FieldError::new(WHOLE_DOCUMENT, message)
    }

    /// The same error seen from one level up: `prefix` is the path of the part
    /// the validator was given (`medium`, `pairs[3]`, `objects[1].children[0]`).
    /// Indices join without a dot: `pairs` + `[3].origin` → `pairs[3].origin`.
    pub fn within(mut self, prefix: &str) -> Self {
        if prefix.is_empty() {
            return self;
        }
        self.path = join_path(prefix, &self.path);
        self
    }

    /// This error, found in `file`.
    pub fn in_file(self, file: &Path) -> Error {
        Error::Input {
            file: file.display().to_string(),
            error: self,
        }
    }
}

/// `prefix` joined with a relative `path`.
pub fn join_path(prefix: &str, path: &str) -> String {
    if path.is_empty() || path == WHOLE_DOCUMENT {
        prefix.to_string()
    } else if path.starts_with('[') {
        format!("{prefix}{path}")
    } else {
        format!("{prefix}.{path}")
    }
}

/// The marker around a path below the place a deserializer reports an error:
/// a `Deserialize` implementation that must buffer (and so loses serde's
/// path tracking) writes `nested_message(path, message)`, and the JSON reader
/// joins `path` to the reported one (see [`split_nested`]).
const NESTED: char = '\u{1}';

/// A deserialization error message that carries a path below the reported one.
pub fn nested_message(path: &str, message: &str) -> String {
    format!("{NESTED}{path}{NESTED}{message}")
}

/// The (path, message) of a [`nested_message`], or `None` for a plain one.
pub fn split_nested(message: &str) -> Option<(&str, &str)> {
    let rest = message.strip_prefix(NESTED)?;
    rest.split_once(NESTED)
}

/// A command-line value refused by its parser; clap names the flag (see
/// `cli::parse_error`, which makes it an [`Error::Usage`]).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ValueError {
    /// Not a number at all.
    #[error("not a number: `{value}`")]
    NotANumber {
        /// The value as typed.
        value: String,
    },
    /// Not a whole number.
    #[error("not a whole number: `{value}`")]
    NotAWholeNumber {
        /// The value as typed.
        value: String,
    },
    /// A number outside the flag's range.
    #[error("{rule}")]
    OutOfRange {
        /// The range and the value, in words (`must be at least 1, got 0`).
        rule: String,
    },
}

/// Every error mirage reports.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An input file is invalid (exit code 2).
    #[error("{file}: {error}")]
    Input {
        /// The file.
        file: String,
        /// The field and what is wrong with it.
        error: FieldError,
    },
    /// A command-line flag is invalid (exit code 2).
    #[error("{flag}: {message}")]
    Usage {
        /// The flag, as typed (`--hit-fraction`).
        flag: String,
        /// What is wrong.
        message: String,
    },
    /// An output path is unusable: its folder is missing, it names an input or
    /// another output, its extension is not one the output can have (exit
    /// code 2; found before the work starts, `crate::io::check_outputs`).
    #[error("{flag} {}: {message}", path.display())]
    Output {
        /// The flag that named it (`-o`, `--plot`).
        flag: String,
        /// The path as given.
        path: PathBuf,
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
    /// An output could not be encoded: an image, a plot, a JSON document (exit
    /// code 1).
    #[error("cannot encode {what}: {message}")]
    Encode {
        /// What was being encoded (`the PNG`, `the plot`, `the result`).
        what: &'static str,
        /// The encoder's message.
        message: String,
    },
    /// The GPU (adapter, device, window, surface, read-back) failed (exit code 1).
    #[error("GPU: {stage}: {message}")]
    Gpu {
        /// What was being done (`requesting an adapter`, `reading back the frame`).
        stage: &'static str,
        /// The driver's or library's message.
        message: String,
    },
    /// A check the user asked for was missed, e.g. `mirage compare --min-psnr`,
    /// or a fit that ends above the `target_objective` its problem sets (exit
    /// code 1).
    #[error("{subject}: {}", missed.join("; "))]
    LimitsMissed {
        /// What was checked (`ours.png vs ref.exr`).
        subject: String,
        /// Each limit missed, in words.
        missed: Vec<String>,
    },
    /// The run was interrupted (Ctrl-C) before it finished; nothing was
    /// written (exit code 130, [`crate::interrupt`]).
    #[error("interrupted (Ctrl-C): stopped before the end, no output written")]
    Interrupted,
    /// The solver could not run (exit code 1).
    #[error("solver run `{run}`: {message}")]
    Solver {
        /// The run (`lm`, `lm (start 3)`, `nelder-mead`).
        run: String,
        /// The solver library's message.
        message: String,
    },
}

/// The exit code of a run stopped by Ctrl-C (128 + SIGINT, as shells report it).
pub const INTERRUPTED_EXIT_CODE: u8 = 130;

impl Error {
    /// An input error in `file` at `field`.
    pub fn input(file: &Path, field: impl Into<String>, message: impl Into<String>) -> Self {
        FieldError::new(field, message).in_file(file)
    }

    /// A bad command-line flag.
    pub fn usage(flag: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Usage {
            flag: flag.into(),
            message: message.into(),
        }
    }

    /// An encoder's failure.
    pub fn encode(what: &'static str, e: impl std::fmt::Display) -> Self {
        Error::Encode {
            what,
            message: e.to_string(),
        }
    }

    /// A GPU failure at `stage`.
    pub fn gpu(stage: &'static str, e: impl std::fmt::Display) -> Self {
        Error::Gpu {
            stage,
            message: e.to_string(),
        }
    }

    /// The field error of an input error.
    pub fn field(&self) -> Option<&FieldError> {
        match self {
            Error::Input { error, .. } => Some(error),
            _ => None,
        }
    }

    /// The process exit code for this error: 2 for bad input (a file, a flag
    /// or an output path), 130 for an interrupted run, 1 for everything else.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Input { .. } | Error::Usage { .. } | Error::Output { .. } => 2,
            Error::Interrupted => i32::from(INTERRUPTED_EXIT_CODE),
            Error::Io { .. }
            | Error::Encode { .. }
            | Error::Gpu { .. }
            | Error::LimitsMissed { .. }
            | Error::Solver { .. } => 1,
        }
    }
}

/// Result with mirage's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_join_with_dots_and_brackets() {
        let e = FieldError::new("a", "bad").within("[3]").within("hotspots");
        assert_eq!(e.path, "hotspots[3].a");
        assert_eq!(FieldError::whole("x").within("medium").path, "medium");
        let err = FieldError::new("medium.background.a", "zero").in_file(Path::new("p.json"));
        assert_eq!(err.to_string(), "p.json: medium.background.a: zero");
        assert_eq!(err.exit_code(), 2);
        assert_eq!(Error::usage("--spp", "must be ≥ 1").exit_code(), 2);
    }
}
