//! `KEYS.json` to a clip (`rigport animate`): the import parser, then the clip edit.

use std::path::Path;

use rigport_model::{Clip, Skeleton};

use crate::PipelineError;

/// Reads a keys file into a clip for `skeleton` (see `rigport_anim::keyed::clip`);
/// `default_name` names the clip when the file does not.
///
/// # Errors
/// The file's errors (`rigport_import::json::keys::read`), or a clip that cannot be baked.
pub(crate) fn load(
    path: &Path,
    skeleton: &Skeleton,
    default_name: &str,
) -> Result<Clip, PipelineError> {
    let keys = rigport_import::json::keys::read(path, skeleton)?;
    rigport_anim::keyed::clip(skeleton, &keys, default_name)
        .map_err(|e| PipelineError::step(format!("{}: cannot bake", path.display()), e))
}
