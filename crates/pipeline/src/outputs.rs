//! Outputs: the format an output path asks for, and the checks made before any work, so a
//! special file, a `.gltf` link or an input given as output fail at once, not after a long
//! computation.

use std::path::{Path, PathBuf};

use rigport_export::ExportError;
use rigport_model::OutputFormat;

use crate::PipelineError;
use crate::error::Message;

/// The format an output path asks for, by its extension ([`OutputFormat::of_path`]).
///
/// # Errors
/// An extension rigport does not write, or `.usd` (a usage error naming the path).
pub(crate) fn format_of(path: &Path) -> Result<OutputFormat, PipelineError> {
    OutputFormat::of_path(path)
        .map_err(|e| PipelineError::Usage(format!("{}: {e}", path.display())))
}

/// The lower-case extension of `path` ("" when none).
pub(crate) fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// Checks the outputs of a command before any work is done: each (and the `.bin` beside a
/// `.gltf`) must be a regular file or absent, symbolic links followed, its folder must
/// exist and take a new file (a temporary file is made there and removed: a missing or
/// read-only folder fails now, not after a long computation), and a `.gltf` must not be a
/// symbolic link (see `rigport_export::PreparedGltf::write`) (an output error else), and
/// none may be one of `inputs`, compared by file identity (device and inode on Unix), so a
/// link or a second path to an input counts (a usage error).
///
/// # Errors
/// As above.
pub(crate) fn check_outputs(outputs: &[&Path], inputs: &[PathBuf]) -> Result<(), PipelineError> {
    for &output in outputs {
        let mut files = vec![output.to_path_buf()];
        let target =
            rigport_export::check_output(output).map_err(|e| PipelineError::output(output, e))?;
        // Written the way the output will be: a temporary file beside it, then renamed.
        rigport_atomic::TempFile::create_beside(&target, b"")
            .map_err(|e| PipelineError::output(output, e))?;
        if extension(output) == "gltf" {
            if std::fs::symlink_metadata(output).is_ok_and(|m| m.file_type().is_symlink()) {
                return Err(PipelineError::output(output, Message(
                    "it is a symbolic link, and a .gltf finds its .bin relative to its own folder; write to the link's target or to a .glb".into(),
                )));
            }
            let bin = output.with_extension("bin");
            rigport_export::check_output(&bin).map_err(|e| PipelineError::output(&bin, e))?;
            files.push(bin);
        }
        for file in &files {
            if let Some(input) = inputs.iter().find(|i| same_file(file, i)) {
                let also = if input == file {
                    String::new()
                } else {
                    format!(" ({})", input.display())
                };
                return Err(PipelineError::Usage(format!(
                    "{}: this output is one of the inputs{also}; write to another file",
                    file.display()
                )));
            }
        }
    }
    Ok(())
}

/// Whether two paths name the same existing file (after symbolic links).
fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt as _;
        match (std::fs::metadata(a), std::fs::metadata(b)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        }
    }
}

/// An export's write failure as an output error that names the file once (the file that
/// failed: `path` or one written beside it).
pub(crate) fn write_failure(err: ExportError, path: &Path) -> PipelineError {
    match err {
        ExportError::Io { path, source } => PipelineError::output(&path, source),
        other => PipelineError::output(path, other),
    }
}

/// Writes `bytes` to `path` atomically (an output error naming `path` on failure).
///
/// # Errors
/// The file cannot be written.
pub(crate) fn write_file(path: &Path, bytes: &[u8]) -> Result<(), PipelineError> {
    rigport_export::write_atomic(path, bytes).map_err(|e| PipelineError::output(path, e))
}

/// The checks every command that writes an asset makes before any work: the output's
/// format (by its extension), and that the output is none of the files read (`input`'s
/// and `extra`), nor a special file.
///
/// # Errors
/// A usage or output error ([`format_of`], [`check_outputs`]).
pub(crate) fn check_request(
    input: &crate::load::Input,
    output: &std::path::Path,
    extra: &[&std::path::Path],
) -> Result<rigport_model::OutputFormat, PipelineError> {
    let format = format_of(output)?;
    check_not_read(input, output, extra)?;
    Ok(format)
}

/// Checks that `output` is none of the files read (`input`'s and `extra`) nor a special
/// file ([`check_outputs`]), for commands whose output is not an asset (eval's `.npz`,
/// render's pictures).
///
/// # Errors
/// As [`check_outputs`].
pub(crate) fn check_not_read(
    input: &crate::load::Input,
    output: &std::path::Path,
    extra: &[&std::path::Path],
) -> Result<(), PipelineError> {
    let mut read = input.read_files();
    read.extend(extra.iter().map(|p| p.to_path_buf()));
    check_outputs(&[output], &read)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_by_extension_and_an_input_is_no_output() {
        assert_eq!(format_of(Path::new("a.GLB")).ok(), Some(OutputFormat::Glb));
        assert_eq!(
            format_of(Path::new("a.usdz")).ok(),
            Some(OutputFormat::Usdz)
        );
        assert!(format_of(Path::new("a.usd")).is_err_and(|e| e.is_usage()));
        let input = Path::new("../../fixtures/bvh/end_sites.bvh");
        let err = check_outputs(&[input], &[input.to_path_buf()]).unwrap_err();
        assert!(err.to_string().contains("this output is one of the inputs"));
    }

    #[test]
    fn an_output_folder_that_cannot_take_the_file_fails_before_any_work() {
        let dir = tempfile::tempdir().unwrap();
        let missing = dir.path().join("gone/walk.glb");
        let err = check_outputs(&[&missing], &[]).unwrap_err();
        assert!(err.is_output(), "{err}");
        assert!(check_outputs(&[&dir.path().join("walk.glb")], &[]).is_ok());
        // The probe leaves nothing behind.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt as _;
            let locked = dir.path().join("locked");
            std::fs::create_dir(&locked).unwrap();
            std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
            // Root writes anywhere: the check is only meaningful when the folder refuses.
            let refuses = std::fs::write(locked.join("probe"), b"").is_err();
            if refuses {
                let err = check_outputs(&[&locked.join("walk.glb")], &[]).unwrap_err();
                assert!(err.is_output(), "{err}");
            }
            std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o755)).unwrap();
        }
    }
}
