//! Checking output paths before the work: every command that writes files
//! hands all of its output flags to [`check_outputs`] once its inputs are read
//! and before it traces, fits or renders anything, so that a typo in a folder
//! name costs a second, not the whole run.
//!
//! Each output must, in this order: have the extension its kind wants
//! ([`OutputKind`]); name a file (not a folder); sit in a folder that exists;
//! not be one of the inputs (an input is never overwritten); differ from the
//! other outputs; and its folder must let a file be created there (checked
//! last, by creating and removing the temporary file [`super::write_atomic`]
//! will write through). A failure is an [`Error::Output`] naming the flag and
//! the path (exit code 2).

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

/// What an output file holds, as far as its extension is concerned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputKind {
    /// Any extension (JSON and CSV reports).
    Any,
    /// A plot: `.png` or `.svg`.
    Plot,
    /// A raster image only `.png` can hold; the words say what it is
    /// (`a render`), for the message.
    Png(&'static str),
    /// An OpenEXR image; the words say what it is (`the sky map`).
    Exr(&'static str),
}

/// One output a command was asked to write.
#[derive(Clone, Copy, Debug)]
pub struct Output<'a> {
    /// The flag that named it, as the user types it (`-o`, `--plot`).
    pub flag: &'static str,
    /// The path given.
    pub path: &'a Path,
    /// What it holds.
    pub kind: OutputKind,
}

impl<'a> Output<'a> {
    /// An output named by `flag`.
    pub fn new(flag: &'static str, path: &'a Path, kind: OutputKind) -> Self {
        Output { flag, path, kind }
    }

    /// An output of an optional flag: `None` when the flag was not given.
    pub fn optional(
        flag: &'static str,
        path: Option<&'a PathBuf>,
        kind: OutputKind,
    ) -> Option<Self> {
        path.map(|p| Output::new(flag, p, kind))
    }

    fn error(&self, message: impl Into<String>) -> Error {
        Error::Output {
            flag: self.flag.to_string(),
            path: self.path.to_path_buf(),
            message: message.into(),
        }
    }

    fn check_extension(&self) -> Result<()> {
        let ext = self
            .path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        let (ok, expected) = match self.kind {
            OutputKind::Any => return Ok(()),
            OutputKind::Plot => (
                matches!(ext.as_deref(), Some("png" | "svg")),
                "expected .png or .svg".to_string(),
            ),
            OutputKind::Png(what) => (
                ext.as_deref() == Some("png"),
                format!("expected .png ({what} is a raster image)"),
            ),
            OutputKind::Exr(what) => (
                ext.as_deref() == Some("exr"),
                format!("expected .exr ({what} is written as OpenEXR)"),
            ),
        };
        match (ok, ext) {
            (true, _) => Ok(()),
            (false, Some(e)) => {
                Err(self.error(format!("unsupported extension `.{e}`: {expected}")))
            }
            (false, None) => Err(self.error(format!("the path has no extension: {expected}"))),
        }
    }

    /// The folder the file goes into (`.` for a bare file name).
    fn folder(&self) -> &Path {
        match self.path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        }
    }

    fn check_place(&self) -> Result<()> {
        let names_a_folder = self
            .path
            .as_os_str()
            .to_string_lossy()
            .ends_with(['/', '\\']);
        if self.path.file_name().is_none() || names_a_folder || self.path.is_dir() {
            return Err(self.error("names a folder, not a file"));
        }
        let folder = self.folder();
        if !folder.exists() {
            return Err(self.error(format!("the folder `{}` does not exist", folder.display())));
        }
        if !folder.is_dir() {
            return Err(self.error(format!("`{}` is not a folder", folder.display())));
        }
        Ok(())
    }

    /// The path made absolute through its folder (which exists), so that two
    /// spellings of one file compare equal before the file exists.
    fn resolved(&self) -> Option<PathBuf> {
        let folder = std::fs::canonicalize(self.folder()).ok()?;
        Some(folder.join(self.path.file_name()?))
    }

    fn check_creatable(&self) -> Result<()> {
        let tmp = super::atomic::temporary_path(self.path)
            .ok_or_else(|| self.error("names a folder, not a file"))?;
        match std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
        {
            Ok(f) => {
                drop(f);
                let _ = std::fs::remove_file(&tmp);
                Ok(())
            }
            // A stale temporary file of this process: the folder is writable.
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(()),
            Err(e) => Err(self.error(format!(
                "cannot create a file in `{}`: {e}",
                self.folder().display()
            ))),
        }
    }
}

/// Checks every output (see the module documentation) against the command's
/// `inputs` and each other; the first failure is returned.
pub fn check_outputs<'a>(
    outputs: impl IntoIterator<Item = Output<'a>>,
    inputs: &[&Path],
) -> Result<()> {
    let outputs: Vec<Output<'a>> = outputs.into_iter().collect();
    for o in &outputs {
        o.check_extension()?;
        o.check_place()?;
    }
    let inputs: Vec<PathBuf> = inputs
        .iter()
        .filter_map(|p| std::fs::canonicalize(p).ok())
        .collect();
    let mut seen: Vec<(PathBuf, &Output<'a>)> = Vec::new();
    for o in &outputs {
        let Some(at) = o.resolved() else { continue };
        if inputs.contains(&at) {
            return Err(
                o.error("the output would overwrite an input file; choose another output path")
            );
        }
        if let Some((_, first)) = seen.iter().find(|(p, _)| *p == at) {
            return Err(o.error(format!(
                "the same file as {} {}; give each output its own path",
                first.flag,
                first.path.display()
            )));
        }
        seen.push((at, o));
    }
    for o in &outputs {
        o.check_creatable()?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn message(outputs: &[Output], inputs: &[&Path]) -> String {
        let e = check_outputs(outputs.iter().copied(), inputs).unwrap_err();
        assert_eq!(e.exit_code(), 2, "{e}");
        e.to_string()
    }

    #[test]
    fn a_good_output_passes_and_leaves_nothing_behind() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("r.json");
        check_outputs([Output::new("-o", &out, OutputKind::Any)], &[]).unwrap();
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn each_failure_names_the_flag_and_the_path() {
        let dir = tempfile::tempdir().unwrap();
        let input = dir.path().join("in.json");
        std::fs::write(&input, "{}").unwrap();
        let missing = dir.path().join("nope/r.json");
        let m = message(&[Output::new("-o", &missing, OutputKind::Any)], &[]);
        assert!(m.starts_with("-o ") && m.contains("nope/r.json"), "{m}");
        assert!(m.contains("does not exist"), "{m}");

        let m = message(&[Output::new("-o", &input, OutputKind::Any)], &[&input]);
        assert!(
            m.contains("overwrite an input") && !m.contains(": -:"),
            "{m}"
        );

        let jpg = dir.path().join("x.jpg");
        let m = message(&[Output::new("-o", &jpg, OutputKind::Png("a render"))], &[]);
        assert!(
            m.contains("expected .png (a render") && !m.contains("svg"),
            "{m}"
        );
        let m = message(&[Output::new("--plot", &jpg, OutputKind::Plot)], &[]);
        assert!(
            m.starts_with("--plot ") && m.contains(".png or .svg"),
            "{m}"
        );
        let m = message(
            &[Output::new("-o", &jpg, OutputKind::Exr("the sky map"))],
            &[],
        );
        assert!(m.contains("expected .exr"), "{m}");

        let m = message(&[Output::new("-o", dir.path(), OutputKind::Any)], &[]);
        assert!(m.contains("names a folder"), "{m}");

        let a = dir.path().join("a.png");
        let again = dir.path().join(".").join("a.png");
        let m = message(
            &[
                Output::new("--plot", &a, OutputKind::Plot),
                Output::new("--rays", &again, OutputKind::Plot),
            ],
            &[],
        );
        assert!(
            m.starts_with("--rays ") && m.contains("same file as --plot"),
            "{m}"
        );

        let under_a_file = input.join("r.json");
        let m = message(&[Output::new("-o", &under_a_file, OutputKind::Any)], &[]);
        assert!(m.contains("not a folder"), "{m}");
    }

    #[cfg(unix)]
    #[test]
    fn a_folder_that_refuses_new_files_is_found() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let locked = dir.path().join("locked");
        std::fs::create_dir(&locked).unwrap();
        std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o500)).unwrap();
        // Root writes anywhere: the test means something only where we cannot.
        let we_can_write = std::fs::File::create(locked.join("probe")).is_ok();
        let out = locked.join("r.json");
        let result = check_outputs([Output::new("-o", &out, OutputKind::Any)], &[]);
        std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o700)).unwrap();
        if !we_can_write {
            let m = result.unwrap_err().to_string();
            assert!(m.contains("cannot create a file"), "{m}");
        }
    }
}
