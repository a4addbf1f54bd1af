//! `KEYS.json` to a clip (`rigport animate`, the demo): the import parser, then the
//! evaluator's bake.

use std::path::Path;

use anyhow::{Context, Result};
use rigport_model::{Clip, Skeleton};

/// Reads a keys file into a clip for `skeleton` (see `rigport_anim::keyed::clip`);
/// `default_name` names the clip when the file does not.
///
/// # Errors
/// The file's errors (`rigport_import::json::keys::read`), or a clip that cannot be baked.
pub fn load(path: &Path, skeleton: &Skeleton, default_name: &str) -> Result<Clip> {
    let keys = rigport_import::json::keys::read(path, skeleton)?;
    rigport_anim::keyed::clip(skeleton, &keys, default_name)
        .with_context(|| format!("{}: cannot bake", path.display()))
}
