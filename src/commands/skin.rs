//! `rigport skin`: automatic skin weights for a mesh and a skeleton
//! (`rigport_pipeline::skin`).

use anyhow::Result;
use rigport_pipeline::numbers::point;
use rigport_pipeline::skin::{Placement, SkinOptions};

use crate::args::{positive, InputArgs, OutputArgs};
use crate::context::Context;

/// `rigport skin` (docs/help/skin.txt).
#[derive(Debug, clap::Args)]
#[command(after_help = include_str!("../../docs/help/skin.txt"))]
pub struct SkinArgs {
    /// MESH.obj and SKELETON: a Pinocchio skeleton.out, or a rig (BVH, ASF, glTF, ...).
    #[command(flatten)]
    pub input: InputArgs,
    /// OUT: .out writes Pinocchio's attachment.out; else the rig (.glb, .usda, ...).
    #[command(flatten)]
    pub output: OutputArgs,
    /// Where the skeleton's origin sits in the mesh's space (mesh units).
    #[arg(long, value_name = "X,Y,Z", value_parser = point, allow_hyphen_values = true)]
    pub skeleton_offset: Option<rigport_model::glam::Vec3>,
    /// Mesh units per skeleton unit (e.g. 0.01 for a BVH in cm on a mesh in m).
    #[arg(long, value_name = "S", value_parser = positive)]
    pub skeleton_scale: Option<f32>,
}

/// Runs `skin`.
pub fn run(ctx: &Context, args: &SkinArgs) -> Result<()> {
    let placement = Placement {
        offset: args.skeleton_offset.unwrap_or_default(),
        scale: args.skeleton_scale.unwrap_or(1.0),
    };
    let output = args.output.to_output();
    let options = SkinOptions { output, placement };
    ctx.run(|progress| rigport_pipeline::skin(&args.input.to_input(), &options, progress))
}
