//! Writing an asset (`rigport_pipeline::write`): the format by the output's extension,
//! warnings reported before anything is written, one summary line after.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use rigport_model::OutputFormat;
use rigport_model::{Asset, InfluencesFit, SkinningMethod, Warning};
pub use rigport_pipeline::outputs::extension;
use rigport_pipeline::write::{self, WriteOptions};

use crate::cli::{InputArgs, OutputArgs};
use crate::context::Context;
use crate::exit::UsageError;

/// The format an output path asks for (a usage error, exit code 2, else).
pub fn format_of(path: &Path) -> Result<OutputFormat> {
    Ok(rigport_pipeline::outputs::format_of(path)?)
}

/// Checks that `path` ends in `.npz`, the one format `eval` writes.
///
/// # Errors
/// Any other extension ([`UsageError`], exit code 2).
pub fn require_npz(path: &Path) -> Result<()> {
    if extension(path) != "npz" {
        return Err(UsageError(format!(
            "{}: eval writes a numpy .npz archive; use the .npz extension",
            path.display()
        ))
        .into());
    }
    Ok(())
}

/// The files an input specification reads (`rigport_pipeline::load::input_files`).
pub fn input_files(args: &InputArgs) -> Vec<PathBuf> {
    rigport_pipeline::load::input_files(&crate::input::inputs(args))
}

/// Checks the outputs of a command before any work is done
/// (`rigport_pipeline::outputs::check_outputs`; exit code 3 or 2).
pub fn check_outputs(outputs: &[&Path], inputs: &[PathBuf]) -> Result<()> {
    Ok(rigport_pipeline::outputs::check_outputs(outputs, inputs)?)
}

/// Applies `--reduce-tolerance` to every clip, adding a note per clip.
///
/// # Errors
/// A tolerance that is negative or not finite, or a clip that does not fit the skeleton.
pub fn reduce_clips(
    asset: &mut Asset,
    args: &OutputArgs,
    warnings: &mut Vec<Warning>,
) -> Result<()> {
    let Some(tolerance) = args.reduce_tolerance else {
        return Ok(());
    };
    if !(tolerance.is_finite() && tolerance >= 0.0) {
        bail!("--reduce-tolerance {tolerance}: expected a distance >= 0");
    }
    Ok(write::reduce_clips(asset, tolerance, warnings)?)
}

/// Writes `asset` to `args.output` in the format its extension names. `warnings` (from
/// import and earlier steps) are reported together with the exporter's, before anything is
/// written; with `--deny-warnings` nothing is written when there is any.
///
/// # Errors
/// Export failures, denied warnings, or an unwritable output (exit code 3).
pub fn write_asset(
    ctx: &Context,
    asset: &Asset,
    warnings: Vec<Warning>,
    args: &OutputArgs,
) -> Result<()> {
    write_asset_with(ctx, asset, warnings, args, false)
}

/// [`write_asset`]; with `usd_point_caches`, a .usda writes unskinned morph-animated meshes
/// as `points.timeSamples`.
///
/// # Errors
/// As [`write_asset`].
pub fn write_asset_with(
    ctx: &Context,
    asset: &Asset,
    mut warnings: Vec<Warning>,
    args: &OutputArgs,
    usd_point_caches: bool,
) -> Result<()> {
    let path = &args.output;
    let format = format_of(path)?;
    write::check_memory(asset, path, format, &crate::memory::budget())?;
    let opts = WriteOptions {
        max_influences: args.max_influences.map(usize::from),
        influences_fit: args.influences_fit,
        skinning: args.skinning,
        up_axis: args.up_axis,
        meters_per_unit: args.meters_per_unit,
        morphs_as_points: usd_point_caches,
    };
    if format.is_gltf() && opts.max_influences.is_some_and(|k| k > 4) && !ctx.quiet {
        if let Some(note) = write::four_influence_note(asset) {
            eprintln!("influences: {note}");
        }
    }
    let fitted = match opts.influences_fit {
        InfluencesFit::Refit => ctx.step("refitting influences", || {
            write::fit_influences(asset, &opts, format)
        })?,
        InfluencesFit::Truncate => write::fit_influences(asset, &opts, format)?,
    };
    if let Some(report) = fitted.as_ref().and_then(|f| f.refit.as_ref()) {
        let k = opts.max_influences.unwrap_or(4);
        for line in write::describe_refit(report, k)
            .iter()
            .filter(|_| !ctx.quiet)
        {
            eprintln!("influences: {line}");
        }
    }
    let asset = fitted.as_ref().map_or(asset, |f| &f.asset);
    if format.is_gltf() && args.skinning == Some(SkinningMethod::Dqs) {
        bail!("glTF defines only linear blend skinning; `rigport bake --skinning dqs` bakes a DQS result into a glTF, and a .usda output can declare DQS");
    }
    let building = match format {
        OutputFormat::Glb | OutputFormat::Gltf => "building glTF",
        OutputFormat::Usda | OutputFormat::Usdc | OutputFormat::Usdz => "building USD",
    };
    let prepared = ctx.step(building, || write::prepare(asset, path, format, &opts))?;
    warnings.extend(prepared.warnings().iter().cloned());
    ctx.report(&warnings)?;
    prepared.write()?;
    if !ctx.quiet {
        let vertices: usize = asset.meshes.iter().map(|m| m.vertex_count()).sum();
        let frames: Vec<String> = asset
            .clips
            .iter()
            .map(|c| {
                let keys = c.tracks.iter().map(|t| t.times.len()).max().unwrap_or(0);
                format!("{:?} {:.3} s, {keys} keys", c.name, c.duration())
            })
            .collect();
        eprintln!(
            "wrote {}: {} joints, {} meshes ({} vertices), {} skins, {} clips{}",
            path.display(),
            asset.skeleton.len(),
            asset.meshes.len(),
            vertices,
            asset.skins.len(),
            asset.clips.len(),
            if frames.is_empty() {
                String::new()
            } else {
                format!(" ({})", frames.join("; "))
            }
        );
    }
    Ok(())
}
