//! Exit codes, documented in `rigport --help`, and pipeline errors worded for the command
//! line (the libraries name no flag).

use rigport_deform::cloth::ClothError;
use rigport_import::detect::{DetectError, PinocchioFile};
use rigport_model::Warning;
use rigport_pipeline::PipelineError;

/// An input could not be read or is invalid (the message names file and line).
pub const BAD_INPUT: u8 = 1;
/// A usage error: clap's (unknown flag, missing argument) and rigport's own (an output
/// extension rigport does not write, an output that is one of the inputs).
pub const USAGE: u8 = 2;
/// An output could not be written.
pub const OUTPUT: u8 = 3;
/// Warnings were reported and `--deny-warnings` was given.
pub const DENIED_WARNINGS: u8 = 4;
/// `verify`: the candidate differs from the reference beyond `--tol`.
pub const MISMATCH: u8 = 5;

/// The exit-code table shown by `--help`.
pub const HELP: &str = include_str!("../docs/help/exit_codes.txt");

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

/// `verify`'s candidate differs beyond the tolerance (exit code 5), a fraction of the
/// reference's diagonal.
#[derive(Debug, thiserror::Error)]
#[error("CANDIDATE differs from REFERENCE beyond --tol {0:e}")]
pub struct Mismatch(pub f64);

/// Marks warnings turned into an error by `--deny-warnings`.
#[derive(Debug, thiserror::Error)]
#[error("{count} warning(s) reported and --deny-warnings was given")]
pub struct DeniedWarnings {
    /// How many.
    pub count: usize,
}

/// A pipeline's error as the command line words it: refused warnings name
/// `--deny-warnings` ([`DeniedWarnings`]); everything else is shown as it is.
///
/// The input errors about what the files are (the library names the [`Inputs`] fields)
/// name the flags that set them, with exit code 1 as the library's error.
///
/// [`Inputs`]: rigport_pipeline::load::Inputs
pub fn command_line(err: PipelineError) -> anyhow::Error {
    let detect = match err {
        PipelineError::Denied(d) => return DeniedWarnings { count: d.count }.into(),
        PipelineError::Step { ref source, .. }
            if matches!(
                source.downcast_ref::<ClothError>(),
                Some(ClothError::Unstable { .. })
            ) =>
        {
            return anyhow::Error::new(err).context(
                "the cloth simulation is unstable (limits: `rigport cloth --help`; more \
                 --substeps cure a time step too large, not a body that jumps, such as a \
                 looped clip going back to its start; --allow-unstable keeps the result with a \
                 warning)",
            )
        }
        PipelineError::Units(conflict) => {
            return UsageError(format!(
                "{conflict}; pass --force-units to use the units given anyway"
            ))
            .into()
        }
        PipelineError::Detect(ref detect) => detect,
        PipelineError::Budget(over) => {
            return anyhow::anyhow!(
                "{over}; raise it with --max-memory if the machine has the memory"
            )
        }
        err if err.is_partial_map() => {
            return anyhow::Error::msg(format!(
                "{:#}; to retarget anyway, pass --allow-partial",
                anyhow::Error::from(err)
            ))
        }
        err => return err.into(),
    };
    let message = match detect {
        DetectError::FpsWithoutAsf => "--amc-fps sets the frame rate of AMC motions and needs \
            an .asf input; to resample a clip use `rigport retime --fps`"
            .to_string(),
        DetectError::BadAmcFps(fps) => {
            format!("--amc-fps {fps}: the AMC frame rate must be a positive number")
        }
        DetectError::IncompletePinocchio(missing) => {
            let flags: Vec<&str> = missing
                .iter()
                .map(|file| match file {
                    PinocchioFile::Mesh => "--mesh",
                    PinocchioFile::Skeleton => "--skeleton",
                    PinocchioFile::Attachment => "--attachment",
                })
                .collect();
            let auto = (flags == ["--attachment"]).then_some(" (or --weights auto)");
            format!(
                "a Pinocchio rig needs a mesh, a skeleton and an attachment; missing {}{}",
                flags.join(", "),
                auto.unwrap_or_default()
            )
        }
        DetectError::NoInput => "no input given (see --help)".to_string(),
        _ => return err.into(),
    };
    anyhow::Error::msg(message)
}

/// A warning as the command line prints it: [`Warning::labelled`], and for the warnings
/// whose cure is a flag, the flag (the libraries name none).
pub fn warning_line(w: &Warning) -> String {
    let line = w.labelled();
    match w {
        Warning::NoContacts {
            suggested_fps: Some(fps),
            ..
        } => format!(
            "{line}; for an ASF/AMC motion, give its frame rate with --amc-fps {fps} (`rigport retime --speed` slows a clip in another format)"
        ),
        Warning::Incomplete { message, .. }
            if message.ends_with(rigport_import::csci520::NO_WEIGHTS) =>
        {
            format!("{line} (--weights auto computes them)")
        }
        Warning::NoContacts { .. } => format!(
            "{line}; the contact thresholds are `rigport footlock --height` and `--speed`"
        ),
        // The one guess is centimetres (`rigport_pipeline::units`).
        Warning::UnitsUnknown { guess, .. } => match guess {
            Some(_) => format!("{line}; pass --input-units cm (or --input-units auto)"),
            None => format!("{line}; give the unit with --input-units"),
        },
        _ => line,
    }
}

/// The exit code for an error, from the markers in its chain.
pub fn code_for(err: &anyhow::Error) -> u8 {
    // anyhow's downcast sees context values at every layer as well as the root error.
    if err.downcast_ref::<DeniedWarnings>().is_some() {
        DENIED_WARNINGS
    } else if err.downcast_ref::<Mismatch>().is_some() {
        MISMATCH
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
