//! `rigport convert`: a rig to glTF.

use anyhow::{Context as _, Result};
use rigport_export::GltfOptions;

use super::Context;
use crate::cli::ConvertArgs;
use crate::exit::OutputError;
use crate::input;

/// Runs `convert`.
pub fn run(ctx: &Context, args: &ConvertArgs) -> Result<()> {
    let plan = input::single_plan(&args.input)?;
    let imported = ctx.step(&format!("reading {}", plan.label()), || plan.import())?;
    let opts = GltfOptions {
        max_influences: usize::from(args.max_influences),
    };
    let prepared = ctx
        .step("building glTF", || {
            rigport_export::prepare_gltf(&imported.asset, &args.output, &opts)
        })
        .with_context(|| format!("cannot export {}", plan.label()))?;
    let mut warnings = imported.warnings.clone();
    warnings.extend(prepared.warnings().iter().cloned());
    ctx.report(&warnings)?;
    prepared.write().with_context(|| OutputError {
        path: args.output.display().to_string(),
    })?;
    if !ctx.quiet {
        let asset = &imported.asset;
        let vertices: usize = asset.meshes.iter().map(|m| m.vertex_count()).sum();
        eprintln!(
            "wrote {}: {} joints, {} meshes ({} vertices), {} skins, {} clips",
            args.output.display(),
            asset.skeleton.len(),
            asset.meshes.len(),
            vertices,
            asset.skins.len(),
            asset.clips.len()
        );
    }
    Ok(())
}
