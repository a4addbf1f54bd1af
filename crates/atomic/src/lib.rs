//! Atomic file output: write a temporary file beside the target, then rename it over.
//!
//! A rename within one directory is atomic on POSIX file systems and replaces the target on
//! Windows (`MoveFileEx` with `MOVEFILE_REPLACE_EXISTING`), so a reader sees either the old
//! file or the complete new one, never a truncated file; a failed or interrupted export
//! leaves the old file untouched.
//!
//! # What may be replaced
//! - A symbolic link is followed (through any chain of links) and its final target is
//!   replaced atomically; the link itself stays a link. A dangling link creates its target.
//! - Only regular files are replaced: a directory, fifo, socket or device at the target is
//!   refused ([`NotRegularFile`]) and left untouched, so `-o /dev/null` or a named pipe
//!   never becomes a regular file.
//!
//! # Temporary files
//! Temporary files are named `.<file name>.<pid>.<n>.tmp`. Every live one is listed in a
//! process-wide registry that [`remove_temp_files`] empties (on SIGINT and SIGTERM once
//! [`remove_temp_files_on_interrupt`] runs, as the CLI does). A process killed outright (SIGKILL, power loss) cannot clean up: the first
//! write into a folder then removes the temporary files of that naming whose process is no
//! longer running (Linux only, where `/proc/<pid>` tells; elsewhere nothing is swept).
//! The sweep trusts the process id: a folder shared over the network with another machine
//! writing into it at the same moment could lose that machine's temporary file.
//!
//! For tests of that cleanup, the environment variable `RIGPORT_TEST_RENAME_DELAY_MS`
//! makes every rename wait that many milliseconds (at most 60 s) once its temporary file is
//! written, so that a test can interrupt a write while the file exists.
#![warn(missing_docs)]

mod signals;

pub use signals::remove_temp_files_on_interrupt;

use std::ffi::OsString;
use std::fs::{self, File, OpenOptions};
use std::io::{self, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};

/// Writes `bytes` to `path` atomically.
///
/// A symbolic link at `path` is followed to its final target, which is what gets replaced
/// (see the module docs). The bytes go to a hidden temporary file in the target's directory
/// (`.<file name>.<pid>.<n>.tmp`), which is then renamed over the target.
///
/// This protects against partial output from a failing or interrupted *process*. It does
/// not `fsync`: like cargo, Blender and gltfpack, rigport leaves durability across a
/// machine crash to the file system (ext4 and XFS flush a file renamed over another before
/// the rename commits). A sync cost about 60 ms per file here, more than the conversion.
/// The file gets the permissions of a newly created file (`0o666` minus the umask on Unix).
///
/// # Errors
/// Those of [`check_output`]; any I/O error creating, writing or renaming the temporary
/// file; [`io::ErrorKind::InvalidInput`] when `path` has no file name;
/// [`io::ErrorKind::Interrupted`] after [`remove_temp_files`]. On error the temporary file
/// has been removed and the target is unchanged.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_atomic_with(path, |file| file.write_all(bytes))
}

/// Writes `path` atomically with what `write` writes into the temporary file: for output
/// too large to build in memory first. The rules of [`write_atomic`] apply (symbolic links,
/// the temporary file's name, the registry that [`remove_temp_files`] empties, the sweep of
/// stale files); `write` gets the file open for writing (and seeking) at its start.
///
/// ```
/// use std::io::Write as _;
///
/// let dir = tempfile::tempdir()?;
/// let path = dir.path().join("out.txt");
/// rigport_atomic::write_atomic_with(&path, |file| file.write_all(b"streamed"))?;
/// assert_eq!(std::fs::read(&path)?, b"streamed");
/// # Ok::<(), std::io::Error>(())
/// ```
///
/// # Errors
/// Those of [`write_atomic`], and `write`'s own. On error the temporary file has been
/// removed and the target is unchanged.
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut File) -> io::Result<()>,
) -> io::Result<()> {
    let target = check_output(path)?;
    TempFile::create_beside_with(&target, write)?.persist(&target)
}

/// The file that writing `path` replaces or creates: `path` itself, or the final target
/// of the symbolic link(s) at `path`, checked to be a regular file or absent.
///
/// # Errors
/// [`NotRegularFile`] (as the source of an [`io::ErrorKind::InvalidInput`] error, or
/// [`io::ErrorKind::IsADirectory`] for a directory) when the target exists and is not a
/// regular file; I/O errors reading the links; a chain of more than 40 links.
pub fn check_output(path: &Path) -> io::Result<PathBuf> {
    let target = resolve_links(path)?;
    match fs::symlink_metadata(&target) {
        Ok(meta) if meta.is_file() => Ok(target),
        Ok(meta) => {
            let kind = if meta.is_dir() {
                io::ErrorKind::IsADirectory
            } else {
                io::ErrorKind::InvalidInput
            };
            Err(io::Error::new(
                kind,
                NotRegularFile {
                    kind: describe(&meta.file_type()),
                },
            ))
        }
        Err(e) if e.kind() == io::ErrorKind::NotFound => Ok(target),
        Err(e) => Err(e),
    }
}

/// An output path names something other than a regular file; it is never replaced.
#[derive(Debug, thiserror::Error)]
#[error("it is {kind}, not a regular file; only regular files are replaced")]
pub struct NotRegularFile {
    /// What it is: "a directory", "a fifo (named pipe)", "a character device", ...
    pub kind: &'static str,
}

/// Most symbolic links followed (Linux's `MAXSYMLINKS`).
const MAX_LINKS: usize = 40;

/// Follows the symbolic links at `path` (not in its folders) to the final name.
fn resolve_links(path: &Path) -> io::Result<PathBuf> {
    let mut current = path.to_path_buf();
    for _ in 0..=MAX_LINKS {
        match fs::symlink_metadata(&current) {
            Ok(meta) if meta.file_type().is_symlink() => {
                let link = fs::read_link(&current)?;
                // A relative link is relative to the folder holding it.
                current = match current.parent() {
                    Some(dir) if link.is_relative() => dir.join(link),
                    _ => link,
                };
            }
            Ok(_) => return Ok(current),
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(current),
            Err(e) => return Err(e),
        }
    }
    Err(io::Error::new(
        io::ErrorKind::InvalidInput,
        format!("more than {MAX_LINKS} levels of symbolic links"),
    ))
}

/// A file type in words, for [`NotRegularFile`].
fn describe(t: &fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt as _;
        if t.is_fifo() {
            return "a fifo (named pipe)";
        }
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_dir() {
        "a directory"
    } else {
        "a special file"
    }
}

/// Removes every temporary file this process has not yet renamed or removed, and makes
/// later attempts to create one fail ([`io::ErrorKind::Interrupted`]). For a signal
/// handler that is about to end the process: afterwards no output of this process can
/// appear, complete or partial, except renames already under way.
pub fn remove_temp_files() {
    let mut registry = registry();
    registry.closed = true;
    for path in registry.live.drain(..) {
        // Best effort: the process is about to exit.
        let _ = fs::remove_file(path);
    }
}

/// The live temporary files of this process.
struct Registry {
    live: Vec<PathBuf>,
    /// Set by [`remove_temp_files`]: no new temporary file may be created.
    closed: bool,
}

static REGISTRY: Mutex<Registry> = Mutex::new(Registry {
    live: Vec::new(),
    closed: false,
});

/// Folders already swept of stale temporary files by this process.
static SWEPT: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn registry() -> MutexGuard<'static, Registry> {
    // The registry stays consistent if a holder panicked: every change is one push or remove.
    REGISTRY.lock().unwrap_or_else(PoisonError::into_inner)
}

fn unregister(path: &Path) {
    let mut registry = registry();
    if let Some(i) = registry.live.iter().position(|p| p == path) {
        registry.live.swap_remove(i);
    }
}

/// The process id in a temporary file name of ours (`.<name>.<pid>.<n>.tmp`).
fn temp_file_pid(name: &str) -> Option<u32> {
    let inner = name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let mut parts = inner.rsplitn(3, '.');
    let n = parts.next()?;
    let pid = parts.next()?;
    let stem = parts.next()?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if stem.is_empty() || !digits(n) || !digits(pid) {
        return None;
    }
    pid.parse().ok()
}

/// Removes the temporary files of our naming in `dir` whose process is gone, once per
/// folder per process. Linux only: `/proc/<pid>` tells whether a process runs.
fn sweep_stale(dir: &Path) {
    if !cfg!(target_os = "linux") || !Path::new("/proc/self").exists() {
        return;
    }
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    {
        let mut swept = SWEPT.lock().unwrap_or_else(PoisonError::into_inner);
        if swept.iter().any(|d| d == dir) {
            return;
        }
        swept.push(dir.to_path_buf());
    }
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    let own = std::process::id();
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(temp_file_pid) else {
            continue;
        };
        let alive = pid == own || Path::new("/proc").join(pid.to_string()).exists();
        if !alive && entry.file_type().is_ok_and(|t| t.is_file()) {
            // Best effort: another process may be sweeping the same folder.
            let _ = fs::remove_file(entry.path());
        }
    }
}

/// Sleeps for `RIGPORT_TEST_RENAME_DELAY_MS` (read once; see the module docs).
fn test_rename_delay() {
    static DELAY: std::sync::OnceLock<Option<std::time::Duration>> = std::sync::OnceLock::new();
    let delay = DELAY.get_or_init(|| {
        let ms: u64 = std::env::var("RIGPORT_TEST_RENAME_DELAY_MS")
            .ok()?
            .parse()
            .ok()?;
        Some(std::time::Duration::from_millis(ms.min(60_000)))
    });
    if let Some(delay) = delay {
        std::thread::sleep(*delay);
    }
}

/// A temporary file that is deleted on drop unless [`TempFile::persist`] renamed it.
#[derive(Debug)]
pub struct TempFile {
    path: PathBuf,
    armed: bool,
}

/// Distinguishes the temporary files of one process.
static COUNTER: AtomicU64 = AtomicU64::new(0);

impl TempFile {
    /// Creates a new temporary file in `target`'s directory holding `bytes`.
    ///
    /// # Errors
    /// I/O errors; [`io::ErrorKind::InvalidInput`] when `target` has no file name;
    /// [`io::ErrorKind::Interrupted`] after [`remove_temp_files`].
    pub fn create_beside(target: &Path, bytes: &[u8]) -> io::Result<Self> {
        Self::create_beside_with(target, |file| file.write_all(bytes))
    }

    /// Creates a new temporary file in `target`'s directory holding what `write` writes.
    ///
    /// # Errors
    /// I/O errors, `write`'s among them; [`io::ErrorKind::InvalidInput`] when `target` has
    /// no file name; [`io::ErrorKind::Interrupted`] after [`remove_temp_files`].
    pub fn create_beside_with(
        target: &Path,
        write: impl FnOnce(&mut File) -> io::Result<()>,
    ) -> io::Result<Self> {
        let (tmp, mut file) = Self::fresh(target, |path| {
            OpenOptions::new().write(true).create_new(true).open(path)
        })?;
        write(&mut file)?;
        Ok(tmp)
    }

    /// Creates a new, empty temporary file in `target`'s directory, open for writing, for
    /// output written piece by piece (a long USD text).
    ///
    /// # Errors
    /// As [`TempFile::create_beside`].
    pub fn create_beside_open(target: &Path) -> io::Result<(Self, fs::File)> {
        Self::fresh(target, |path| {
            OpenOptions::new().write(true).create_new(true).open(path)
        })
    }

    /// A second name (a hard link) for the existing file `target`, so that it can be put
    /// back after `target` is replaced; `None` when there is no such file or the file
    /// system cannot link (best effort).
    pub fn backup_of(target: &Path) -> Option<Self> {
        if !fs::symlink_metadata(target).is_ok_and(|m| m.is_file()) {
            return None;
        }
        Self::fresh(target, |path| fs::hard_link(target, path))
            .ok()
            .map(|(tmp, ())| tmp)
    }

    /// Makes a new name `.<file name>.<pid>.<n>.tmp` beside `target` and calls `make` to
    /// create it, registering it in the same step (under the registry's lock, so that
    /// [`remove_temp_files`] never misses a file that exists).
    fn fresh<T>(target: &Path, make: impl Fn(&Path) -> io::Result<T>) -> io::Result<(Self, T)> {
        let name = target.file_name().ok_or_else(|| {
            io::Error::new(
                io::ErrorKind::InvalidInput,
                format!("{} has no file name", target.display()),
            )
        })?;
        let dir = target.parent().unwrap_or_else(|| Path::new(""));
        sweep_stale(dir);
        // `create_new` never clobbers a file: on a name clash (another process, a leftover
        // from a crash) try the next number.
        let mut attempts = 0;
        loop {
            let n = COUNTER.fetch_add(1, Ordering::Relaxed);
            let mut tmp_name = OsString::from(".");
            tmp_name.push(name);
            tmp_name.push(format!(".{}.{n}.tmp", std::process::id()));
            let path = dir.join(tmp_name);
            let mut registry = registry();
            if registry.closed {
                return Err(io::Error::new(
                    io::ErrorKind::Interrupted,
                    "interrupted: no new output is written",
                ));
            }
            match make(&path) {
                Ok(made) => {
                    registry.live.push(path.clone());
                    return Ok((Self { path, armed: true }, made));
                }
                Err(e) if e.kind() == io::ErrorKind::AlreadyExists && attempts < 100 => {
                    attempts += 1;
                }
                Err(e) => return Err(e),
            }
        }
    }

    /// Renames the temporary file to `target`, replacing it.
    ///
    /// # Errors
    /// The rename's I/O error; the temporary file is then removed.
    pub fn persist(mut self, target: &Path) -> io::Result<()> {
        test_rename_delay();
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
        unregister(&self.path);
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
    fn follows_symlinks_and_replaces_the_target() {
        let dir = tempfile::tempdir().expect("tempdir");
        let real = dir.path().join("real.glb");
        fs::write(&real, b"old").expect("write");
        let link = dir.path().join("link.glb");
        let chain = dir.path().join("chain.glb");
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink("real.glb", &link).expect("symlink");
            std::os::unix::fs::symlink(&link, &chain).expect("symlink");
            write_atomic(&chain, b"new").expect("write through links");
            assert_eq!(fs::read(&real).expect("read"), b"new");
            assert!(fs::symlink_metadata(&link).expect("meta").is_symlink());
            assert!(fs::symlink_metadata(&chain).expect("meta").is_symlink());
            // A dangling link creates its target.
            let dangling = dir.path().join("dangling.usda");
            std::os::unix::fs::symlink("made.usda", &dangling).expect("symlink");
            write_atomic(&dangling, b"made").expect("write");
            assert_eq!(
                fs::read(dir.path().join("made.usda")).expect("read"),
                b"made"
            );
            assert!(fs::symlink_metadata(&dangling).expect("meta").is_symlink());
            // A loop is an error, not a hang.
            let a = dir.path().join("a");
            std::os::unix::fs::symlink("b", &a).expect("symlink");
            std::os::unix::fs::symlink("a", dir.path().join("b")).expect("symlink");
            assert!(write_atomic(&a, b"x").is_err());
            assert_eq!(
                names(dir.path()),
                [
                    "a",
                    "b",
                    "chain.glb",
                    "dangling.usda",
                    "link.glb",
                    "made.usda",
                    "real.glb"
                ]
            );
        }
    }

    #[test]
    fn refuses_directories_and_special_files() {
        let dir = tempfile::tempdir().expect("tempdir");
        let sub = dir.path().join("sub.glb");
        fs::create_dir(&sub).expect("mkdir");
        let err = write_atomic(&sub, b"x").unwrap_err();
        assert_eq!(err.kind(), io::ErrorKind::IsADirectory);
        assert!(
            err.to_string().contains("a directory, not a regular file"),
            "{err}"
        );
        #[cfg(unix)]
        {
            let fifo = dir.path().join("pipe.npz");
            let made = std::process::Command::new("mkfifo").arg(&fifo).status();
            if made.is_ok_and(|s| s.success()) {
                let err = write_atomic(&fifo, b"x").unwrap_err();
                assert!(err.to_string().contains("fifo"), "{err}");
                use std::os::unix::fs::FileTypeExt as _;
                assert!(fs::symlink_metadata(&fifo)
                    .expect("meta")
                    .file_type()
                    .is_fifo());
            } else {
                eprintln!("SKIPPED: mkfifo is not available");
            }
        }
        assert!(names(dir.path()).iter().all(|n| !n.ends_with(".tmp")));
    }

    #[test]
    fn recognizes_our_temp_file_names() {
        assert_eq!(temp_file_pid(".out.glb.123.7.tmp"), Some(123));
        assert_eq!(temp_file_pid(".a.b.c.gltf.9.0.tmp"), Some(9));
        for other in [
            "out.glb.123.7.tmp",
            ".out.glb.123.7.tmp.bak",
            "..123.7.tmp",
            ".out.x.7.tmp",
            ".out.123..tmp",
            ".123.7.tmp",
        ] {
            assert_eq!(temp_file_pid(other), None, "{other}");
        }
    }

    #[test]
    fn sweeps_stale_temp_files_of_dead_processes() {
        if !Path::new("/proc/self").exists() {
            eprintln!("SKIPPED: no /proc to tell live processes");
            return;
        }
        let dir = tempfile::tempdir().expect("tempdir");
        // A pid above Linux's maximum (4194304) never runs.
        let stale = dir.path().join(".old.glb.99999999.0.tmp");
        let live = dir
            .path()
            .join(format!(".old.glb.{}.99999.tmp", std::process::id()));
        let theirs = dir.path().join(".notes.txt.99999999.x.tmp");
        for p in [&stale, &live, &theirs] {
            fs::write(p, b"partial").expect("write");
        }
        write_atomic(&dir.path().join("new.glb"), b"data").expect("write");
        let left = names(dir.path());
        assert!(
            !left.contains(&".old.glb.99999999.0.tmp".to_string()),
            "{left:?}"
        );
        assert!(left.contains(&format!(".old.glb.{}.99999.tmp", std::process::id())));
        assert!(left.contains(&".notes.txt.99999999.x.tmp".to_string()));
    }

    #[test]
    fn missing_directory_is_an_error() {
        let dir = tempfile::tempdir().expect("tempdir");
        let err = write_atomic(&dir.path().join("no/such/dir/f.bin"), b"x").unwrap_err();
        assert_eq!(err.kind(), io::ErrorKind::NotFound);
        assert!(write_atomic(Path::new("/"), b"x").is_err());
    }
}
