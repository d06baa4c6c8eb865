use crate::error::{Error, Result};
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The temporary file [`write_atomic`] writes `path` through: a hidden name
/// with the process id, in the same folder (so the rename cannot cross file
/// systems); `None` when `path` names no file.
pub(super) fn temporary_path(path: &Path) -> Option<PathBuf> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path.file_name()?;
    Some(dir.join(format!(
        ".{}.{}.tmp",
        name.to_string_lossy(),
        std::process::id()
    )))
}

/// Writes `bytes` to `path` through a temporary file in the same folder and a
/// rename, so a reader never sees a partial file and a failure leaves nothing.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// [`write_atomic`] of what `write` writes into a buffered writer on the
/// temporary file (so a large output is never held whole in memory). The
/// data reaches the disk (`fsync`) before the rename, so that after a crash
/// `path` holds either its old content or the whole new one.
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
) -> Result<()> {
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let tmp = temporary_path(path).ok_or_else(|| {
        io(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "the output path names no file",
        ))
    })?;
    // Ctrl-C's forced exit waits for the write to end (crate::interrupt).
    let _writing = crate::interrupt::Writing::start();
    let result = (|| {
        let mut w = std::io::BufWriter::with_capacity(1 << 16, std::fs::File::create(&tmp)?);
        write(&mut w)?;
        let f = w.into_inner().map_err(|e| e.into_error())?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(io(e));
    }
    Ok(())
}

/// Serialises `value` as pretty JSON and writes it atomically, streamed into
/// the file. A value that cannot be encoded (a non-string map key) is
/// reported as such, and leaves no file.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let mut encode_error = None;
    let written = write_atomic_with(path, |w| {
        if let Err(e) = serde_json::to_writer_pretty(&mut *w, value) {
            if e.is_io() {
                return Err(e.into());
            }
            let message = e.to_string();
            encode_error = Some(e);
            return Err(std::io::Error::other(message));
        }
        w.write_all(b"\n")
    });
    match (written, encode_error) {
        (_, Some(e)) => Err(Error::encode("the result as JSON", e)),
        (result, None) => result,
    }
}
