//! Atomic file output: write a temporary file beside the target, then rename it over.
//!
//! A rename within one directory is atomic on POSIX file systems and replaces the target on
//! Windows (`MoveFileEx` with `MOVEFILE_REPLACE_EXISTING`), so a reader sees either the old
//! file or the complete new one, never a truncated file; a failed or interrupted export
//! leaves the old file untouched.

use std::fs::{self, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Writes `bytes` to `path` atomically.
///
/// The bytes go to a hidden temporary file in the same directory
/// (`.<file name>.<pid>.<n>.tmp`), which is then renamed over `path`.
///
/// This protects against partial output from a failing or interrupted *process*. It does
/// not `fsync`: like cargo, Blender and gltfpack, rigport leaves durability across a
/// machine crash to the file system (ext4 and XFS flush a file renamed over another before
/// the rename commits). A sync cost about 60 ms per file here, more than the conversion.
/// The file gets the permissions of a newly created file (`0o666` minus the umask on Unix).
///
/// # Errors
/// Any I/O error creating, writing or renaming the temporary file, or
/// [`io::ErrorKind::InvalidInput`] when `path` has no file name. On error the temporary file
/// has been removed and `path` is unchanged.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    TempFile::create_beside(path, bytes)?.persist(path)
}

/// A temporary file that is deleted on drop unless [`TempFile::persist`] renamed it.
pub(crate) struct TempFile {
    path: PathBuf,
    armed: bool,
}

/// Distinguishes the temporary files of one process.
static COUNTER: AtomicU64 = AtomicU64::new(0);

impl TempFile {
    /// Creates a new temporary file in `target`'s directory holding `bytes`.
    ///
    /// # Errors
    /// I/O errors; [`io::ErrorKind::InvalidInput`] when `target` has no file name.
    pub(crate) fn create_beside(target: &Path, bytes: &[u8]) -> io::Result<Self> {
        let name = target.file_name().ok_or_else(|| {
            io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("{} has no file name", target.display()),
            )
        })?;
        let dir = target.parent().unwrap_or_else(|| Path::new(""));
        // `create_new` never clobbers a file: on a name clash (another process, a leftover
        // from a crash) try the next number.
        let mut attempts = 0;
        let (path, mut file) = loop {
            let n = COUNTER.fetch_add(1, Ordering::Relaxed);
            let mut tmp_name = std::ffi::OsString::from(".");
            tmp_name.push(name);
            tmp_name.push(format!(".{}.{n}.tmp", std::process::id()));
            let path = dir.join(tmp_name);
            match OpenOptions::new().write(true).create_new(true).open(&path) {
                Ok(file) => break (path, file),
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists && attempts < 100 => {
                    attempts += 1;
                }
                Err(e) => return Err(e),
            }
        };
        let tmp = Self { path, armed: true };
        file.write_all(bytes)?;
        Ok(tmp)
    }

    /// Renames the temporary file to `target`, replacing it.
    ///
    /// # Errors
    /// The rename's I/O error; the temporary file is then removed.
    pub(crate) fn persist(mut self, target: &Path) -> io::Result<()> {
        fs::rename(&self.path, target)?;
        self.armed = false;
        Ok(())
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if self.armed {
            // Best effort: nothing more can be done about a failing cleanup here.
            let _ = fs::remove_file(&self.path);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .expect("read dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn writes_and_replaces_without_leftovers() {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("out.npz");
        write_atomic(&path, b"first").expect("write");
        write_atomic(&path, b"second").expect("overwrite");
        assert_eq!(fs::read(&path).expect("read"), b"second");
        assert_eq!(names(dir.path()), vec!["out.npz".to_string()]);
    }

    #[test]
    fn failed_rename_removes_the_temp_file() {
        let dir = tempfile::tempdir().expect("tempdir");
        // Renaming a file over a non-empty directory fails on every platform.
        let target = dir.path().join("taken");
        fs::create_dir(&target).expect("mkdir");
        fs::write(target.join("inside"), b"x").expect("write");
        assert!(write_atomic(&target, b"data").is_err());
        assert_eq!(names(dir.path()), vec!["taken".to_string()]);
    }

    #[test]
    fn missing_directory_is_an_error() {
        let dir = tempfile::tempdir().expect("tempdir");
        let err = write_atomic(&dir.path().join("no/such/dir/f.bin"), b"x").unwrap_err();
        assert_eq!(err.kind(), io::ErrorKind::NotFound);
        assert!(write_atomic(Path::new("/"), b"x").is_err());
    }
}
