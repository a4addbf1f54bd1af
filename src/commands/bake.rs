//! `rigport bake`: a dual quaternion skinning result baked into an ordinary (LBS) glTF as
//! per-frame corrective morph targets in bind space (FORMATS.md, "glTF 2.0 skins and
//! animation"; the eval side is `rigport_eval::bake`).

use std::path::PathBuf;

use anyhow::{bail, Result};
use rigport_eval::bake::pipeline::{bake_dqs, DqsBakeOptions};
use rigport_model::Warning;

use super::Context;
use crate::cli::{InputArgs, OutputArgs, Skinning};
use crate::input;
use crate::output::{self, Format};

/// `rigport bake` arguments.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "For every sampled frame and skinned vertex, with M the vertex's blended \
    LBS matrix (of the influences the glTF holds), the frame's target holds \
    M^-1 * p_dqs - p_rest, so a viewer's LBS of the morphed vertex lands on the DQS result. \
    Morph weights are animated (LINEAR, one key per frame) so that exactly frame k's target \
    is active at its time."
)]
pub struct BakeArgs {
    /// The rig, with at least one clip.
    #[command(flatten)]
    pub input: InputArgs,
    /// Output file: .glb or .gltf (+ .bin).
    #[arg(long, short, value_name = "OUT")]
    pub output: PathBuf,
    /// The skinning to bake. `lbs` needs no correction and writes the plain file.
    #[arg(long, value_enum)]
    pub skinning: Skinning,
    /// The clip to bake (default: the first).
    #[arg(long, value_name = "NAME")]
    pub clip: Option<String>,
    /// Sample the clip at F frames per second (default: at its own key times).
    #[arg(long, value_name = "F")]
    pub fps: Option<f32>,
    /// Corrections no longer than D (bind-space units) are left out of the sparse targets
    /// (default: 1e-6 of the bounding-box diagonal of the skinned meshes).
    #[arg(long, value_name = "D")]
    pub threshold: Option<f32>,
    /// Compress the per-frame targets to K shared targets (PCA) with per-frame weights.
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..))]
    pub correctives: Option<u32>,
    /// Influences kept per vertex in the glTF (1 to 8), and used for the DQS being baked.
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u8).range(1..=8))]
    pub max_influences: u8,
}

/// Runs `bake`.
pub fn run(ctx: &Context, args: &BakeArgs) -> Result<()> {
    if output::format_of(&args.output)? != Format::Gltf {
        bail!(
            "{}: bake writes glTF (.glb/.gltf); a .usda declares DQS directly (`rigport convert --skinning dqs`)",
            args.output.display()
        );
    }
    if let Some(fps) = args.fps {
        if !(fps.is_finite() && fps > 0.0) {
            bail!("--fps {fps}: expected a positive frame rate");
        }
    }
    if let Some(t) = args.threshold {
        if !(t.is_finite() && t >= 0.0) {
            bail!("--threshold {t}: expected a distance >= 0");
        }
    }
    let out_args = OutputArgs {
        output: args.output.clone(),
        max_influences: args.max_influences,
        reduce_tolerance: None,
        // The file itself is LBS; the DQS result lives in its morph targets.
        skinning: Skinning::Lbs,
    };
    let (plan, imported) = ctx.step("reading input", || input::load_single(&args.input))?;
    let mut asset = imported.asset;
    let mut warnings = imported.warnings;
    if args.skinning == Skinning::Lbs {
        warnings.push(Warning::Note {
            location: plan.label(),
            message: "--skinning lbs: glTF skins with LBS already, no corrective targets needed; writing the plain file".into(),
        });
        return output::write_asset(ctx, &asset, warnings, &out_args);
    }
    let reports = ctx.step("baking DQS correctives", || {
        bake_dqs(
            &mut asset,
            &DqsBakeOptions {
                clip: args.clip.as_deref(),
                fps: args.fps,
                threshold: args.threshold,
                correctives: args.correctives,
            },
            // Exactly the influences the glTF will hold, so the viewer's LBS is what we invert.
            |skeleton, skin| {
                rigport_export::gltf_influences(skeleton, skin, usize::from(args.max_influences))
            },
            &plan.label(),
            &mut warnings,
        )
    })?;
    output::write_asset(ctx, &asset, warnings, &out_args)?;
    if !ctx.quiet {
        for report in &reports {
            eprintln!("{report}");
        }
        let mut size = std::fs::metadata(&args.output).map_or(0, |m| m.len());
        if args
            .output
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("gltf"))
        {
            size += std::fs::metadata(args.output.with_extension("bin")).map_or(0, |m| m.len());
        }
        eprintln!("file size: {size} bytes");
    }
    Ok(())
}
