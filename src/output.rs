//! Writing an asset: the format by the output's extension, warnings reported before
//! anything is written, one summary line after.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context as _, Result};
use rigport_export::{ExportError, GltfOptions, UsdOptions, UsdSkinning};
use rigport_model::{Asset, Warning};

use crate::cli::{InfluencesFit, InputArgs, OutputArgs, Skinning};
use crate::context::Context;
use crate::exit::{OutputError, UsageError};
use crate::input::{self, Plan};

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
/// An extension rigport does not write ([`UsageError`], exit code 2).
pub fn format_of(path: &Path) -> Result<Format> {
    Ok(match extension(path).as_str() {
        "glb" | "gltf" => Format::Gltf,
        "usda" => Format::Usda,
        "usd" | "usdc" | "usdz" => return Err(UsageError(format!(
            "{}: rigport writes USD as text; use the .usda extension (usdcat converts it to .usdc/.usdz)",
            path.display()
        ))
        .into()),
        _ => {
            return Err(UsageError(format!(
                "{}: unknown output type; expected .glb, .gltf or .usda",
                path.display()
            ))
            .into())
        }
    })
}

/// The lower-case extension of `path` ("" when none).
pub fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
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

/// The files an input specification reads: those of its resolved plans (a folder stands
/// for the files picked from it), or the paths as given when they do not resolve (the
/// command then reports why).
pub fn input_files(args: &InputArgs) -> Vec<PathBuf> {
    let Ok(plans) = input::plans(args) else {
        let mut files = args.inputs.clone();
        files.extend(args.mesh.iter().cloned());
        files.extend(args.skeleton.iter().cloned());
        files.extend(args.attachment.iter().cloned());
        files.extend(args.motion.iter().cloned());
        return files;
    };
    let mut files = Vec::new();
    for plan in plans {
        match plan {
            Plan::Gltf(p) | Plan::Obj(p) | Plan::Csci520(p) | Plan::Bvh(p) | Plan::Usda(p) => {
                files.push(p);
            }
            Plan::Pinocchio {
                mesh,
                skeleton,
                attachment,
            } => files.extend([mesh, skeleton, attachment]),
            Plan::AsfAmc { asf, motions, .. } => {
                files.push(asf);
                files.extend(motions);
            }
        }
    }
    files
}

/// Checks the outputs of a command before any work is done: each (and the `.bin` beside a
/// `.gltf`) must be a regular file or absent, symbolic links followed, and a `.gltf` must
/// not be a symbolic link (see `rigport_export::PreparedGltf::write`) (exit code 3 else),
/// and none may be one of `inputs`, compared by file identity (device and inode on Unix),
/// so a link or a second path to an input counts (exit code 2).
///
/// # Errors
/// As above.
pub fn check_outputs(outputs: &[&Path], inputs: &[PathBuf]) -> Result<()> {
    for &output in outputs {
        let mut files = vec![output.to_path_buf()];
        rigport_export::check_output(output).with_context(|| OutputError {
            path: output.display().to_string(),
        })?;
        if extension(output) == "gltf" {
            if std::fs::symlink_metadata(output).is_ok_and(|m| m.file_type().is_symlink()) {
                return Err(anyhow::anyhow!(
                    "it is a symbolic link, and a .gltf finds its .bin relative to its own folder; write to the link's target or to a .glb"
                )
                .context(OutputError {
                    path: output.display().to_string(),
                }));
            }
            let bin = output.with_extension("bin");
            rigport_export::check_output(&bin).with_context(|| OutputError {
                path: bin.display().to_string(),
            })?;
            files.push(bin);
        }
        for file in &files {
            if let Some(input) = inputs.iter().find(|i| same_file(file, i)) {
                let also = if input == file {
                    String::new()
                } else {
                    format!(" ({})", input.display())
                };
                return Err(UsageError(format!(
                    "{}: this output is one of the inputs{also}; write to another file",
                    file.display()
                ))
                .into());
            }
        }
    }
    Ok(())
}

/// Whether two paths name the same existing file (after symbolic links).
fn same_file(a: &Path, b: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt as _;
        match (std::fs::metadata(a), std::fs::metadata(b)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        }
    }
}

/// An export's write failure as an output error (exit code 3) that names the file once.
pub fn write_failure(err: ExportError, path: &Path) -> anyhow::Error {
    match err {
        ExportError::Io { path, source } => anyhow::Error::new(source).context(OutputError {
            path: path.display().to_string(),
        }),
        other => anyhow::Error::new(other).context(OutputError {
            path: path.display().to_string(),
        }),
    }
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
/// Checks that writing `asset` as `format` fits the memory budget.
fn check_memory(asset: &Asset, path: &Path, format: Format) -> Result<()> {
    use rigport_export::estimate;
    let (needed, as_what) = match format {
        Format::Gltf => (estimate::gltf_memory(asset), "glTF"),
        Format::Usda => (estimate::usd_memory(asset), "USD text"),
    };
    let what = format!(
        "{}: writing {} joints x {} samples and {} vertices as {as_what}",
        path.display(),
        asset.skeleton.len(),
        estimate::max_clip_samples(asset),
        asset
            .meshes
            .iter()
            .map(|m| m.positions.len())
            .sum::<usize>()
    );
    Ok(crate::memory::budget().check(what, needed)?)
}

/// The asset with at most `--max-influences` per vertex as `--influences-fit` asks (glTF:
/// 4 by default; USD: all unless given), or `None` when the writer's own limiting does.
/// A refit prints, per skin, its deviation from the full weights against truncation's.
fn fit_influences(
    ctx: &Context,
    asset: &Asset,
    args: &OutputArgs,
    format: Format,
) -> Result<Option<Asset>> {
    use rigport_eval::refit::{self, asset::PoseSet};
    let k = match (format, args.max_influences) {
        (Format::Usda, None) => return Ok(None),
        (_, limit) => limit.map_or(4, usize::from),
    };
    let k = std::num::NonZeroUsize::new(k).context("--max-influences is at least 1")?;
    if k.get() > 4 && format == Format::Gltf && !ctx.quiet {
        let eps = rigport_model::conventions::WEIGHT_EPSILON;
        let over: usize = (asset.skins.iter().flat_map(|s| s.influences.rows()))
            .filter(|r| r.iter().filter(|i| i.weight > eps).count() > 4)
            .count();
        if over > 0 {
            eprintln!("influences: {over} vertices need more than 4 influences; three.js, model-viewer, Filament, Bevy and Unity read only JOINTS_0/WEIGHTS_0 (each vertex's 4 largest weights) and show them otherwise than Babylon.js, Godot 4 and the Khronos sample viewer, which read 8");
        }
    }
    if asset
        .skins
        .iter()
        .all(|s| s.influences.max_per_vertex() <= k.get())
    {
        return Ok(None);
    }
    let mut fitted = asset.clone();
    match args.influences_fit {
        InfluencesFit::Truncate if format == Format::Gltf => return Ok(None),
        InfluencesFit::Truncate => {
            for skin in &mut fitted.skins {
                skin.influences = rigport_model::Influences::from_rows(
                    skin.influences
                        .rows()
                        .map(|r| refit::truncate_row(r, k.get())),
                );
            }
        }
        InfluencesFit::Refit => {
            let report = ctx.step("refitting influences", || {
                refit::asset::refit_asset(&mut fitted, k)
            })?;
            let poses = match report.pose_set {
                PoseSet::Clips => "the clips' frames",
                PoseSet::RangeOfMotion => "a range of motion",
            };
            for s in report.skins.iter().filter(|_| !ctx.quiet) {
                let rel = |d: f64| d / s.diagonal.max(f64::MIN_POSITIVE);
                eprintln!(
                    "influences: skin {} refitted to {k} per vertex over {} poses ({poses}): deviation from all weights, max {:.2e} -> {:.2e}, RMS {:.2e} -> {:.2e} of the diagonal (truncation -> refit); {} vertices changed",
                    s.skin, report.poses, rel(s.truncated.max), rel(s.refit.max),
                    rel(s.truncated.rms), rel(s.refit.rms), s.changed
                );
            }
        }
    }
    Ok(Some(fitted))
}

pub fn write_asset(
    ctx: &Context,
    asset: &Asset,
    warnings: Vec<Warning>,
    args: &OutputArgs,
) -> Result<()> {
    write_asset_with(ctx, asset, warnings, args, false)
}

/// [`write_asset`]; with `usd_point_caches`, a .usda writes unskinned morph-animated meshes
/// as `points.timeSamples` ([`UsdOptions::morphs_as_points`]).
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
    check_memory(asset, path, format)?;
    let fitted = fit_influences(ctx, asset, args, format)?;
    let asset = fitted.as_ref().unwrap_or(asset);
    match format {
        Format::Gltf => {
            if args.skinning == Some(Skinning::Dqs) {
                bail!("glTF defines only linear blend skinning; `rigport bake --skinning dqs` bakes a DQS result into a glTF, and a .usda output can declare DQS");
            }
            let opts = GltfOptions {
                max_influences: args.max_influences.map_or(4, usize::from),
            };
            let prepared = ctx
                .step("building glTF", || {
                    rigport_export::prepare_gltf(asset, path, &opts)
                })
                .with_context(|| format!("cannot export {:?}", asset.name))?;
            warnings.extend(prepared.warnings().iter().cloned());
            ctx.report(&warnings)?;
            prepared.write().map_err(|e| write_failure(e, path))?;
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
                morphs_as_points: usd_point_caches,
            };
            let prepared = ctx
                .step("building USD", || {
                    rigport_export::prepare_usd(asset, path, &opts)
                })
                .with_context(|| format!("cannot export {:?}", asset.name))?;
            warnings.extend(prepared.warnings().iter().cloned());
            ctx.report(&warnings)?;
            prepared.write().map_err(|e| write_failure(e, path))?;
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
