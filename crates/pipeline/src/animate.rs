//! `rigport animate`: keyframe a rig from a JSON file of poses (`KEYS.json`).
//!
//! [`run`] is the whole pipeline; [`crate::animate()`] is the same function.

use std::path::PathBuf;

use rigport_model::Warning;

use crate::load::Input;
use crate::outputs::check_request;
use crate::progress::Progress;
use crate::write::{Output, write_output};
use crate::{PipelineError, Report};

/// What `animate` keys and writes.
///
/// ```
/// use rigport_pipeline::animate::AnimateOptions;
/// use rigport_pipeline::inspect::InspectOptions;
/// use rigport_pipeline::{animate, inspect, load::Input, progress::Silent, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// // The keys file's stem names the clip, which comes before the rig's own clip.
/// let keys = dir.path().join("hop.json");
/// std::fs::write(&keys, r#"{"keys": [{"time": 0, "pose": {}}, {"time": 0.5, "pose": {}}]}"#)?;
/// let out = dir.path().join("hop.glb");
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// animate(&input, &AnimateOptions { keys, output: Output::new(&out) }, &Silent)?;
/// let listing = inspect(&Input::new(vec![out]), &InspectOptions { json: true }, &Silent)?;
/// let json: serde_json::Value = serde_json::from_str(listing.output.as_deref().unwrap_or(""))?;
/// assert_eq!(json[0]["clips"][0]["name"], "hop");
/// assert_eq!(json[0]["clips"][1]["name"], "end_sites");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, Default)]
pub struct AnimateOptions {
    /// The `KEYS.json` file; its stem names the clip unless the file does.
    pub keys: PathBuf,
    /// The output file and how it is written.
    pub output: Output,
}

/// Reads `input`, bakes the keys into a clip placed first, and writes the rig.
///
/// ```
/// use rigport_pipeline::{animate, load::Input, progress::Silent, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let keys = dir.path().join("hop.keys.json");
/// std::fs::write(&keys, r#"{"keys": [{"time": 0, "pose": {}}, {"time": 1, "pose": {}}]}"#)?;
/// let out = dir.path().join("hop.glb");
/// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
/// let options = animate::AnimateOptions { keys, output: Output::new(&out) };
/// animate(&input, &options, &Silent)?;
/// assert_eq!(&std::fs::read(&out)?[..4], b"glTF");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// The keys file's errors (with their JSON path); as the import and [`write_output`].
pub fn run(
    input: &Input,
    options: &AnimateOptions,
    progress: &dyn Progress,
) -> Result<Report, PipelineError> {
    check_request(input, &options.output.path, &[&options.keys])?;
    let (plan, imported) = input.load_single(progress, "reading input")?;
    let (mut asset, mut warnings) = (imported.asset, imported.warnings);
    let stem = options
        .keys
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "keys".into());
    let clip = crate::keys::load(&options.keys, &asset.skeleton, &stem)?;
    if !asset.clips.is_empty() {
        warnings.push(Warning::Note {
            location: plan.label(),
            message: format!(
                "the keyed clip {:?} comes first; the rig's {} clip(s) follow it",
                clip.name,
                asset.clips.len()
            ),
        });
    }
    asset.clips.insert(0, clip);
    let line = write_output(asset, warnings, &options.output, &input.budget, progress)?;
    Ok(Report::logged(line))
}
