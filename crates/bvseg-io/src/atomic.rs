//! Writing files so that readers never see a partial one.
use std::fs::{self, File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::IoError;

/// Writes `bytes` to `path` so that `path` either keeps its old content or has all of the new
/// one, even if the process dies or the disk fills up half-way: the data goes to a temporary
/// file `.<name>.tmp-<pid>-<n>` in the same directory (a rename is only atomic within one file
/// system), is flushed to disk, and is then renamed over `path`. On any error the temporary
/// file is removed and `path` is left as it was.
///
/// # Errors
///
/// [`IoError::Io`] naming the file when it cannot be created, written, flushed or renamed.
pub fn write_atomic(path: impl AsRef<Path>, bytes: &[u8]) -> Result<(), IoError> {
    let path = path.as_ref();
    let name = path.display().to_string();
    let Some(file_name) = path.file_name() else {
        return Err(IoError::BadPath {
            name,
            message: "not a file name".into(),
        });
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    // The counter keeps two writers in one process apart; the pid keeps processes apart.
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(file_name);
    tmp_name.push(format!(".tmp-{}-{n}", std::process::id()));
    let tmp = dir.join(tmp_name);

    // create_new: never truncate a file that someone else is writing.
    let file = OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)
        .map_err(|e| IoError::io(&name, "create a temporary file for", e))?;
    let result = fill_and_rename(file, bytes, &tmp, path, &name);
    if result.is_err() {
        // Best effort: the error being reported is the one that matters.
        let _ = fs::remove_file(&tmp);
        return result;
    }
    // Make the rename itself durable. Not every platform can open a directory for this, and
    // the file is already complete and in place, so a failure here is not an error.
    if let Ok(d) = File::open(&dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

fn fill_and_rename(
    mut file: File,
    bytes: &[u8],
    tmp: &Path,
    path: &Path,
    name: &str,
) -> Result<(), IoError> {
    file.write_all(bytes)
        .map_err(|e| IoError::io(name, "write", e))?;
    file.sync_all().map_err(|e| IoError::io(name, "write", e))?;
    drop(file);
    fs::rename(tmp, path).map_err(|e| IoError::io(name, "replace", e))
}
