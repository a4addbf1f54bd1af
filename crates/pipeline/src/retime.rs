//! `rigport retime`: resample, speed up, warp, reverse or trim a clip.
//!
//! [`run`] is the whole pipeline; [`crate::retime()`] is the same function.

use rigport_anim::retime::{Retime, retime};
use rigport_anim::root_motion::RootMotionOptions;
use rigport_anim::sequence::trim;
use rigport_model::{Clip, Warning};

use crate::load::Input;
use crate::outputs::check_request;
use crate::progress::Progress;
use crate::write::{Output, write_output};
use crate::{PipelineError, Report};

/// How the clip's timing changes.
///
/// ```
/// use rigport_anim::retime::Retime;
/// use rigport_pipeline::retime::Change;
///
/// // Half speed: the clip lasts twice as long.
/// let slower = Change::Retime(Retime::Speed(0.5));
/// let start = Change::Trim { start: 0.0, end: 1.0 };
/// assert_ne!(slower, start);
/// ```
#[derive(Clone, Debug, PartialEq)]
pub enum Change {
    /// Resampled, sped up, warped or reversed ([`Retime`]).
    Retime(Retime),
    /// Only the keys between `start` and `end` seconds are kept.
    Trim {
        /// Seconds.
        start: f32,
        /// Seconds.
        end: f32,
    },
}

/// `START..END` seconds (`0.5..2`) as a [`Change::Trim`]; the message says what is wrong.
///
/// ```
/// use rigport_pipeline::retime::{parse_trim, Change};
///
/// assert_eq!(parse_trim("0.5..2"), Ok(Change::Trim { start: 0.5, end: 2.0 }));
/// assert!(parse_trim("0.5").is_err() && parse_trim("a..2").is_err());
/// ```
///
/// # Errors
/// No `..`, or a side that is not a finite number.
pub fn parse_trim(text: &str) -> Result<Change, String> {
    let seconds = |s: &str| match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(format!("{s:?} is not a number of seconds")),
    };
    let (a, b) = text
        .split_once("..")
        .ok_or_else(|| "expected START..END, e.g. 0.5..2".to_string())?;
    Ok(Change::Trim {
        start: seconds(a)?,
        end: seconds(b)?,
    })
}

/// What `retime` changes and writes.
///
/// ```
/// use rigport_pipeline::retime::{Change, RetimeOptions};
/// use rigport_pipeline::{load::Input, progress::Silent, retime, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let options = RetimeOptions {
///     clip: Some("end_sites".into()),
///     change: Change::Trim { start: 0.0, end: 0.05 },
///     output: Output::new(dir.path().join("start.glb")),
///     root_motion: Default::default(),
/// };
/// let report = retime(&input, &options, &Silent)?;
/// assert!(report.log[0].contains("0.050 s"), "{}", report.log[0]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct RetimeOptions {
    /// The clip (the first when `None`).
    pub clip: Option<String>,
    /// The change.
    pub change: Change,
    /// The output file and how it is written.
    pub output: Output,
    /// Every clip's root motion, changed after the retiming ([`crate::root_motion`]).
    pub root_motion: RootMotionOptions,
}

fn keys_of(clip: &Clip) -> usize {
    clip.tracks.iter().map(|t| t.times.len()).max().unwrap_or(0)
}

/// Reads `input`, changes the timing of one clip (and the root motion of every clip, if
/// asked), and writes the rig.
///
/// ```
/// use rigport_anim::retime::Retime;
/// use rigport_anim::root_motion::{RootMotion, RootMotionOptions};
/// use rigport_pipeline::retime::{Change, RetimeOptions};
/// use rigport_pipeline::{load::Input, progress::Silent, retime, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let out = dir.path().join("slow.glb");
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let options = RetimeOptions {
///     clip: None,
///     change: Change::Retime(Retime::Speed(0.5)),
///     output: Output::new(&out),
///     // Every clip played in place, its heading kept.
///     root_motion: RootMotionOptions { mode: RootMotion::InPlace, ..Default::default() },
/// };
/// let report = retime(&input, &options, &Silent)?;
/// assert!(report.log[0].starts_with("wrote "));
/// assert!(report.log[1].starts_with("root motion in place"), "{:?}", report.log);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// No such clip, or none; a change the clip cannot take; as the import and
/// [`write_output`].
pub fn run(
    input: &Input,
    options: &RetimeOptions,
    progress: &dyn Progress,
) -> Result<Report, PipelineError> {
    check_request(input, &options.output.path, &[])?;
    let (plan, imported) = input.load_single(progress, "reading input")?;
    let (mut asset, mut warnings) = (imported.asset, imported.warnings);
    let index = asset
        .clip_index(options.clip.as_deref())
        .map_err(|e| PipelineError::step(plan.label(), e))?
        .ok_or_else(|| {
            PipelineError::Invalid(format!("{}: the rig has no clip to retime", plan.label()))
        })?;
    let before = &asset.clips[index];
    let failed = |e| PipelineError::step(format!("cannot retime clip {:?}", before.name), e);
    let after = match &options.change {
        Change::Retime(how) => retime(before, &asset.skeleton, how).map_err(failed)?,
        Change::Trim { start, end } => {
            trim(before, &asset.skeleton, *start, *end).map_err(|e| {
                PipelineError::step(
                    format!("cannot retime clip {:?}", before.name),
                    PipelineError::step(format!("trim {start}..{end}"), e),
                )
            })?
        }
    };
    warnings.push(Warning::Note {
        location: format!("clip {:?}", before.name),
        message: format!(
            "retimed: {:.4} s with {} keys -> {:.4} s with {} keys",
            before.duration(),
            keys_of(before),
            after.duration(),
            keys_of(&after)
        ),
    });
    asset.clips[index] = after;
    let moved = crate::root_motion::apply(&mut asset, &options.root_motion)?;
    let line = write_output(asset, warnings, &options.output, &input.budget, progress)?;
    let mut report = Report::logged(line);
    report.log.extend(moved.iter().flat_map(|m| m.lines()));
    Ok(report)
}
