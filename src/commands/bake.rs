//! `rigport bake`: a dual quaternion skinning result baked into an ordinary (LBS) glTF as
//! per-frame corrective morph targets in bind space (FORMATS.md, "glTF 2.0 skins and
//! animation"; the pipeline is `rigport_pipeline::bake`).

use std::path::PathBuf;

use anyhow::Result;
use rigport_model::SkinningMethod;
use rigport_pipeline::bake::BakeOptions;

use crate::args::{distance, frame_rate, InputArgs};
use crate::context::Context;
use crate::exit::UsageError;

/// `rigport bake` arguments.
#[derive(Debug, clap::Args)]
#[command(
    after_help = include_str!("../../docs/help/bake.txt")
)]
pub struct BakeArgs {
    /// The rig, with at least one clip.
    #[command(flatten)]
    pub input: InputArgs,
    /// Output file: .glb or .gltf (+ .bin).
    #[arg(long, short, value_name = "OUT")]
    pub output: PathBuf,
    /// The skinning to bake (default: the one the source declares for its skin). `lbs`
    /// needs no correction and writes the plain file.
    #[arg(long, value_enum)]
    pub skinning: Option<SkinningMethod>,
    /// The clip to bake (default: the first).
    #[arg(long, value_name = "NAME")]
    pub clip: Option<String>,
    /// Sample the clip at F frames per second (default: at its own key times).
    #[arg(long, value_name = "F", value_parser = frame_rate)]
    pub fps: Option<f32>,
    /// Corrections no longer than D (bind-space units) are left out of the sparse targets
    /// (default: 1e-6 of the bounding-box diagonal of the skinned meshes).
    #[arg(long, value_name = "D", value_parser = distance)]
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
    // The pipeline refuses a USD output too; here the refusal says which flag does it.
    if rigport_model::OutputFormat::of_path(&args.output).is_ok_and(|f| f.is_usd()) {
        return Err(UsageError(format!(
            "{}: bake writes glTF (.glb/.gltf); a .usda declares DQS directly (`rigport convert --skinning dqs`)",
            args.output.display()
        ))
        .into());
    }
    let options = BakeOptions {
        skinning: args.skinning,
        clip: args.clip.clone(),
        fps: args.fps,
        threshold: args.threshold,
        correctives: args.correctives,
        max_influences: args.max_influences,
        output: args.output.clone(),
    };
    ctx.run(|progress| rigport_pipeline::bake(&args.input.to_input(), &options, progress))
}
