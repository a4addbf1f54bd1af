//! Resolves input arguments into import plans and runs the importers
//! (`rigport_pipeline::load`).

use anyhow::Result;
use rigport_import::detect::{DetectError, PinocchioFile};
use rigport_import::Imported;
use rigport_pipeline::load::{self, Inputs};
use rigport_pipeline::PipelineError;

use crate::cli::InputArgs;

/// One asset to import.
pub type Plan = load::Source;

/// The library's view of the input arguments.
pub fn inputs(args: &InputArgs) -> Inputs {
    Inputs {
        paths: args.inputs.clone(),
        mesh: args.mesh.clone(),
        skeleton: args.skeleton.clone(),
        attachment: args.attachment.clone(),
        motions: args.motion.clone(),
        amc_fps: args.amc_fps,
    }
}

/// Resolves the arguments into one plan per asset.
pub fn plans(args: &InputArgs) -> Result<Vec<Plan>> {
    load::plan(&inputs(args)).map_err(with_flags)
}

/// Resolves the arguments into exactly one asset plan.
pub fn single_plan(args: &InputArgs) -> Result<Plan> {
    load::single_plan(&inputs(args)).map_err(with_flags)
}

/// Imports a plan within the budget (a skeleton-only asset gets a bone mesh unless
/// `--no-bone-mesh`).
pub fn load(plan: &Plan, args: &InputArgs) -> Result<Imported> {
    let budget = crate::memory::budget();
    Ok(load::load(plan, !args.no_bone_mesh, &budget)?)
}

/// Resolves and imports exactly one asset.
pub fn load_single(args: &InputArgs) -> Result<(Plan, Imported)> {
    let plan = single_plan(args)?;
    let imported = load(&plan, args)?;
    Ok((plan, imported))
}

/// An input error worded with the flags that set what it is about (the library names
/// [`Inputs`] fields, not flags); other errors pass through.
fn with_flags(err: PipelineError) -> anyhow::Error {
    let PipelineError::Detect(detect) = &err else {
        return err.into();
    };
    let message = match detect {
        DetectError::FpsWithoutAsf => "--fps sets the frame rate of AMC motions and needs an .asf \
            input; to resample a clip use `rigport retime --fps`"
            .to_string(),
        DetectError::BadAmcFps(fps) => {
            format!("--fps {fps}: the AMC frame rate must be a positive number")
        }
        DetectError::IncompletePinocchio(missing) => {
            let flags: Vec<&str> = missing
                .iter()
                .map(|file| match file {
                    PinocchioFile::Mesh => "--mesh",
                    PinocchioFile::Skeleton => "--skeleton",
                    PinocchioFile::Attachment => "--attachment",
                })
                .collect();
            format!(
                "a Pinocchio rig needs a mesh, a skeleton and an attachment; missing {}",
                flags.join(", ")
            )
        }
        DetectError::NoInput => "no input given (see --help)".to_string(),
        _ => return err.into(),
    };
    // Exit code 1 (bad input), as for the library's error, which has no cause to print.
    anyhow::Error::msg(message)
}
