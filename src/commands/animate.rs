//! `rigport animate`: keyframe a rig from a JSON file of poses.

use anyhow::Result;
use rigport_model::Warning;

use crate::cli::AnimateArgs;
use crate::context::Context;
use crate::{input, keys, output};

/// Runs `animate`.
pub fn run(ctx: &Context, args: &AnimateArgs) -> Result<()> {
    output::format_of(&args.output.output)?;
    let (plan, imported) = ctx.step("reading input", || input::load_single(&args.input))?;
    let mut asset = imported.asset;
    let mut warnings = imported.warnings;
    let stem = args
        .keys
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "keys".into());
    let clip = keys::load(&args.keys, &asset.skeleton, &stem)?;
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
    output::reduce_clips(&mut asset, &args.output, &mut warnings)?;
    output::write_asset(ctx, &asset, warnings, &args.output)
}
