//! `rigport eval`: pose a rig and dump the skinned result as `.npz`
//! (`rigport_pipeline::dump`).

use anyhow::Result;
use rigport_pipeline::dump::{eval_dump_to, DumpOptions};

use crate::cli::EvalArgs;
use crate::context::Context;
use crate::input;

/// Runs `eval`.
pub fn run(ctx: &Context, args: &EvalArgs) -> Result<()> {
    let (plan, imported) = ctx.step("reading input", || input::load_single(&args.input))?;
    ctx.report(&imported.warnings)?;
    let asset = &imported.asset;
    let opts = DumpOptions {
        pose: args.pose.as_deref(),
        clip: args.clip.as_deref(),
        fps: args.fps,
        max_influences: args.max_influences.map(usize::from),
        skinning: args.skinning,
    };
    let budget = crate::memory::budget();
    // Streamed to the file: memory stays bounded whatever the clip's length.
    let dump = eval_dump_to(asset, &plan.label(), &opts, &args.output, &budget)?;
    if !ctx.quiet {
        let what = match &dump.clip {
            Some(name) => format!(", clip {name:?}"),
            None => String::new(),
        };
        eprintln!(
            "wrote {} ({} joints, {} meshes{what})",
            args.output.display(),
            asset.skeleton.len(),
            asset.meshes.len()
        );
    }
    Ok(())
}
