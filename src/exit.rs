//! Exit codes, documented in `rigport --help`.

/// An input could not be read or is invalid (the message names file and line).
pub const BAD_INPUT: u8 = 1;
/// A usage error: clap's (unknown flag, missing argument) and rigport's own (an output
/// extension rigport does not write, an output that is one of the inputs).
pub const USAGE: u8 = 2;
/// An output could not be written.
pub const OUTPUT: u8 = 3;
/// Warnings were reported and `--deny-warnings` was given.
pub const DENIED_WARNINGS: u8 = 4;

/// The exit-code table shown by `--help`.
pub const HELP: &str = "\
Exit codes:
  0  success
  1  an input could not be read or is invalid (the message names file and line)
  2  usage error (unknown flag, missing argument or input, an output extension rigport
     does not write, an output that is one of the inputs)
  3  an output could not be written (nothing partial is left behind); only regular files
     are replaced (a directory, fifo or device is refused); a symbolic link is followed
     and its target replaced
  4  warnings were reported and --deny-warnings was given
  130, 143  interrupted by SIGINT, SIGTERM (temporary files removed)";

/// Marks an error as an output failure.
#[derive(Debug, thiserror::Error)]
#[error("cannot write {path}")]
pub struct OutputError {
    /// The output path.
    pub path: String,
}

/// A usage error rigport finds after parsing (exit code 2): the message says what to change.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct UsageError(pub String);

/// Marks warnings turned into an error by `--deny-warnings`.
#[derive(Debug, thiserror::Error)]
#[error("{count} warning(s) reported and --deny-warnings was given")]
pub struct DeniedWarnings {
    /// How many.
    pub count: usize,
}

/// A pipeline's error as the command line words it: refused warnings name
/// `--deny-warnings` ([`DeniedWarnings`]); everything else is shown as it is.
pub fn command_line(err: rigport_pipeline::PipelineError) -> anyhow::Error {
    match err {
        rigport_pipeline::PipelineError::Denied(d) => DeniedWarnings { count: d.count }.into(),
        err => err.into(),
    }
}

/// The exit code for an error, from the markers in its chain.
pub fn code_for(err: &anyhow::Error) -> u8 {
    // anyhow's downcast sees context values at every layer as well as the root error.
    if err.downcast_ref::<DeniedWarnings>().is_some() {
        DENIED_WARNINGS
    } else if err.downcast_ref::<OutputError>().is_some() {
        OUTPUT
    } else if err.downcast_ref::<UsageError>().is_some() {
        USAGE
    } else if let Some(e) = err.downcast_ref::<rigport_pipeline::PipelineError>() {
        if e.is_output() {
            OUTPUT
        } else if e.is_usage() {
            USAGE
        } else {
            BAD_INPUT
        }
    } else {
        BAD_INPUT
    }
}

/// Whether the error is a closed stdout (`rigport inspect x | head`), which is success.
pub fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
