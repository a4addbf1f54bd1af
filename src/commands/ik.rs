//! `rigport ik`: IK handles over time, solved per frame and baked into a clip
//! (`rigport_pipeline::ik`).

use std::path::PathBuf;

use anyhow::{bail, Result};
use rigport_ik::clip::ClipSolveOptions;
use rigport_ik::{IkMethod, Lambda};
use rigport_pipeline::ik::IkOptions;

use crate::args::{frame_rate, non_negative, positive, InputArgs, OutputArgs};
use crate::context::Context;

/// `rigport ik`.
#[derive(Debug, clap::Args)]
pub struct IkArgs {
    /// The rig.
    #[command(flatten)]
    pub input: InputArgs,
    /// The handle tracks (see below).
    #[arg(long, value_name = "HANDLES.json")]
    pub handles: PathBuf,
    /// Solver: dls (damped least squares, adaptive damping), pinv (SVD pseudo-inverse),
    /// transpose (Jacobian transpose), ccd, fabrik.
    #[arg(long, default_value = "dls")]
    pub solver: String,
    /// Frames per second of the baked clip (default: the file's, else 30).
    #[arg(long, value_name = "F", value_parser = frame_rate)]
    pub fps: Option<f32>,
    /// A handle has converged within this distance of its target (default: 1e-4 of the
    /// skeleton's height).
    #[arg(long, value_name = "T", value_parser = positive)]
    pub tolerance: Option<f32>,
    /// Most iterations per frame (per sub-step).
    #[arg(long, default_value_t = 100, value_name = "N")]
    pub max_iterations: u32,
    /// Fixed damping for dls (default: adaptive from the residual).
    #[arg(long, value_name = "L", value_parser = non_negative)]
    pub lambda: Option<f32>,
    /// Split target moves longer than D into sub-steps.
    #[arg(long, value_name = "D")]
    pub substep: Option<f32>,
    /// Let the root translate too (Jacobian solvers); the same as `"root_motion": "free"`
    /// in the handles file.
    #[arg(long)]
    pub free_root: bool,
    /// Print the residual summary as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// Where to write.
    #[command(flatten)]
    pub output: OutputArgs,
}

/// The solver `--solver` and `--lambda` name.
fn method(args: &IkArgs) -> Result<IkMethod> {
    let Some(m) = IkMethod::from_name(&args.solver) else {
        bail!(
            "--solver {:?}: expected one of dls, pinv, transpose, ccd, fabrik",
            args.solver
        );
    };
    Ok(match (m, args.lambda) {
        (IkMethod::Dls { .. }, Some(l)) => IkMethod::Dls {
            lambda: Lambda::Fixed(l),
        },
        (_, Some(_)) => bail!("--lambda applies to --solver dls only"),
        (m, None) => m,
    })
}

/// Runs `ik`.
pub fn run(ctx: &Context, args: &IkArgs) -> Result<()> {
    let options = IkOptions {
        handles: args.handles.clone(),
        solve: ClipSolveOptions {
            method: method(args)?,
            fps: args.fps,
            tolerance: args.tolerance,
            max_iterations: args.max_iterations,
            substep: args.substep,
            free_root: args.free_root,
        },
        json: args.json,
        output: args.output.to_output(),
    };
    ctx.run(|progress| rigport_pipeline::ik(&args.input.to_input(), &options, progress))
}
