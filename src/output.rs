//! Writing an asset: the format by the output's extension, warnings reported before
//! anything is written, one summary line after.

use std::path::Path;

use anyhow::{bail, Context as _, Result};
use rigport_export::{GltfOptions, UsdOptions, UsdSkinning};
use rigport_model::{Asset, Warning};

use crate::cli::{OutputArgs, Skinning};
use crate::commands::Context;
use crate::exit::OutputError;

/// The output formats.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// `.glb` or `.gltf` (+ `.bin`).
    Gltf,
    /// `.usda`.
    Usda,
}

/// The format an output path asks for.
///
/// # Errors
/// An extension rigport does not write.
pub fn format_of(path: &Path) -> Result<Format> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    Ok(match ext.as_str() {
        "glb" | "gltf" => Format::Gltf,
        "usda" => Format::Usda,
        "usd" | "usdc" | "usdz" => bail!(
            "{}: rigport writes USD as text; use the .usda extension (usdcat converts it to .usdc/.usdz)",
            path.display()
        ),
        _ => bail!(
            "{}: unknown output type; expected .glb, .gltf or .usda",
            path.display()
        ),
    })
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
    for clip in &mut asset.clips {
        let (reduced, stats) = rigport_eval::reduce::reduce(clip, &asset.skeleton, tolerance)
            .with_context(|| format!("cannot reduce clip {:?}", clip.name))?;
        warnings.push(Warning::Note {
            location: format!("clip {:?}", clip.name),
            message: format!(
                "key reduction kept {} of {} keys (largest joint position error {:.3e}, tolerance {tolerance:.3e})",
                stats.keys_after, stats.keys_before, stats.max_error
            ),
        });
        *clip = reduced;
    }
    Ok(())
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
    mut warnings: Vec<Warning>,
    args: &OutputArgs,
) -> Result<()> {
    let path = &args.output;
    let format = format_of(path)?;
    let output_error = || OutputError {
        path: path.display().to_string(),
    };
    match format {
        Format::Gltf => {
            if args.skinning == Some(Skinning::Dqs) {
                bail!("glTF defines only linear blend skinning; `rigport bake --skinning dqs` bakes a DQS result into a glTF, and a .usda output can declare DQS");
            }
            let opts = GltfOptions {
                max_influences: usize::from(args.max_influences),
            };
            let prepared = ctx
                .step("building glTF", || {
                    rigport_export::prepare_gltf(asset, path, &opts)
                })
                .with_context(|| format!("cannot export {:?}", asset.name))?;
            warnings.extend(prepared.warnings().iter().cloned());
            ctx.report(&warnings)?;
            prepared.write().with_context(output_error)?;
        }
        Format::Usda => {
            let opts = UsdOptions {
                skinning: args.skinning.map(|m| match m {
                    Skinning::Lbs => UsdSkinning::Lbs,
                    Skinning::Dqs => UsdSkinning::Dqs,
                }),
                up_axis: args.up_axis.map(|a| match a {
                    crate::cli::UpAxisArg::Y => rigport_model::UpAxis::Y,
                    crate::cli::UpAxisArg::Z => rigport_model::UpAxis::Z,
                }),
                meters_per_unit: args.meters_per_unit,
            };
            let prepared = ctx
                .step("building USD", || {
                    rigport_export::prepare_usd(asset, path, &opts)
                })
                .with_context(|| format!("cannot export {:?}", asset.name))?;
            warnings.extend(prepared.warnings().iter().cloned());
            ctx.report(&warnings)?;
            prepared.write().with_context(output_error)?;
        }
    }
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
