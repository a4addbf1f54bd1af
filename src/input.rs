//! Resolves input arguments into import plans and runs the importers
//! (`rigport_pipeline::load`).

use anyhow::Result;
use rigport_import::Imported;
use rigport_pipeline::load::{self, Inputs};

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
    Ok(load::plan(&inputs(args))?)
}

/// Resolves the arguments into exactly one asset plan.
pub fn single_plan(args: &InputArgs) -> Result<Plan> {
    Ok(load::single_plan(&inputs(args))?)
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
