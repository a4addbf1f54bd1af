//! `rigport eval`: pose or sample a rig, skin it, and dump the result as an `.npz`
//! streamed to its file.
//!
//! [`run`] is the whole pipeline; [`crate::eval()`] is the same function.

use std::path::PathBuf;

use rigport_model::SkinningMethod;

pub use crate::dump::{Evaluation, PoseSource};
use crate::dump::{eval_arrays, eval_dump_to};
use crate::load::Input;
use crate::outputs::{check_not_read, extension};
use crate::progress::Progress;
use crate::{PipelineError, Report};
pub use rigport_export::npz::EvalArrays;
use rigport_model::{Asset, MemoryBudget};

/// What `eval` evaluates, and where it writes.
///
/// ```
/// use rigport_pipeline::eval::EvalOptions;
/// use rigport_pipeline::{eval, load::Input, progress::Silent};
///
/// let dir = tempfile::tempdir()?;
/// // One pose from a POSE.json instead of a clip (`{}`: every joint at rest).
/// let pose = dir.path().join("rest.json");
/// std::fs::write(&pose, "{}")?;
/// let options = EvalOptions {
///     pose: Some(pose),
///     output: dir.path().join("rest.npz"),
///     ..EvalOptions::default()
/// };
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let report = eval(&input, &options, &Silent)?;
/// assert!(report.log[0].ends_with("(9 joints, 1 meshes)"), "{}", report.log[0]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, Default)]
pub struct EvalOptions {
    /// A `POSE.json` to evaluate instead of a clip.
    pub pose: Option<PathBuf>,
    /// The clip to sample (default: the first; none: the rest pose).
    pub clip: Option<String>,
    /// Sample at this rate (default: the clip's key times).
    pub fps: Option<f32>,
    /// Limit the influences per vertex as a glTF would.
    pub max_influences: Option<usize>,
    /// The skinning method (default: the first skin's own).
    pub skinning: Option<SkinningMethod>,
    /// The `.npz` file.
    pub output: PathBuf,
}

/// Reads `input`, reports its warnings, and writes the dump.
///
/// ```
/// use rigport_pipeline::eval::EvalOptions;
/// use rigport_pipeline::{eval, load::Input, progress::Silent};
///
/// let dir = tempfile::tempdir()?;
/// let out = dir.path().join("walk.npz");
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let report = eval(&input, &EvalOptions { output: out.clone(), ..EvalOptions::default() }, &Silent)?;
/// assert!(report.log[0].starts_with("wrote "));
/// assert_eq!(&std::fs::read(&out)?[..2], b"PK");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// An output that is not `.npz` (a usage error); as the import; nothing to skin, an
/// unknown clip, a bad pose file, over the budget; an unwritable output.
pub fn run(
    input: &Input,
    options: &EvalOptions,
    progress: &dyn Progress,
) -> Result<Report, PipelineError> {
    let output = &options.output;
    if extension(output) != "npz" {
        return Err(PipelineError::Usage(format!(
            "{}: eval writes a numpy .npz archive; use the .npz extension",
            output.display()
        )));
    }
    let extra: Vec<&std::path::Path> = options.pose.iter().map(|p| p.as_path()).collect();
    check_not_read(input, output, &extra)?;
    let (plan, imported) = input.load_single(progress, "reading input")?;
    progress.warnings(&imported.warnings)?;
    let asset = &imported.asset;
    let opts = Evaluation {
        pose: options.pose.as_deref().map(PoseSource::File),
        clip: options.clip.as_deref(),
        fps: options.fps,
        times: None,
        max_influences: options.max_influences,
        skinning: options.skinning,
    };
    // Streamed to the file: memory stays bounded whatever the clip's length.
    let dump = eval_dump_to(asset, &plan.label(), &opts, output, &input.budget)?;
    let what = match &dump.clip {
        Some(name) => format!(", clip {name:?}"),
        None => String::new(),
    };
    Ok(Report::logged(format!(
        "wrote {} ({} joints, {} meshes{what})",
        output.display(),
        asset.skeleton.len(),
        asset.meshes.len()
    )))
}

/// Evaluates `asset` as `request` asks and returns the arrays in memory (for a caller that
/// keeps them, as the Python bindings do), with the name of the clip sampled (`None` for
/// a pose): the same frames, row for row, that [`run`] writes to its `.npz` (both fill one
/// `rigport_export::npz::EvalDump`). `label` names the asset in messages.
///
/// ```
/// use rigport_pipeline::eval::{evaluate, Evaluation};
/// use rigport_pipeline::{load::Input, progress::Silent, MemoryBudget};
///
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let (plan, imported) = input.load_single(&Silent, "reading")?;
/// let (arrays, clip) =
///     evaluate(&imported.asset, &plan.label(), &Evaluation::default(), &MemoryBudget::UNLIMITED)?;
/// assert!(clip.is_some() && arrays.frames > 1);
/// assert_eq!(arrays.joint_world.len(), arrays.frames * arrays.joints * 16);
/// assert_eq!(arrays.positions.len(), arrays.frames * arrays.vertices * 3);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// Nothing to skin, an unknown clip, a frame rate that is not positive, a pose file's
/// errors, over `budget`, or a clip that does not fit the skeleton.
pub fn evaluate(
    asset: &Asset,
    label: &str,
    request: &Evaluation<'_>,
    budget: &MemoryBudget,
) -> Result<(EvalArrays, Option<String>), PipelineError> {
    eval_arrays(asset, label, request, budget)
}
