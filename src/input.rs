//! Resolves input arguments into import plans (`rigport_import::detect`) and runs the
//! importers.

use anyhow::{bail, Result};
use rigport_import::detect::{self, Inputs};
use rigport_import::Imported;

use crate::cli::InputArgs;

/// One asset to import.
pub type Plan = detect::Source;

/// The library's view of the input arguments.
fn inputs(args: &InputArgs) -> Inputs {
    Inputs {
        paths: args.inputs.clone(),
        mesh: args.mesh.clone(),
        skeleton: args.skeleton.clone(),
        attachment: args.attachment.clone(),
        motions: args.motion.clone(),
        amc_fps: args.amc_fps,
    }
}

/// Resolves the arguments into one plan per asset (see `rigport_import::detect::plan`).
pub fn plans(args: &InputArgs) -> Result<Vec<Plan>> {
    Ok(detect::plan(&inputs(args))?)
}

/// Resolves the arguments into exactly one asset plan.
pub fn single_plan(args: &InputArgs) -> Result<Plan> {
    let mut plans = plans(args)?;
    if plans.len() != 1 {
        bail!("this command takes one rig; {} were given", plans.len());
    }
    Ok(plans.remove(0))
}

/// Imports a plan; unless `--no-bone-mesh`, a skeleton-only asset gets a generated bone
/// mesh (noted in the warnings) so viewers show its motion.
///
/// # Errors
/// Over the memory budget; as the importer.
pub fn load(plan: &Plan, args: &InputArgs) -> Result<Imported> {
    crate::memory::check_import(plan)?;
    let mut imported = plan.import()?;
    if !args.no_bone_mesh && rigport_eval::bone_mesh::add_bone_mesh(&mut imported.asset) {
        imported.warnings.push(rigport_model::Warning::Note {
            location: plan.label(),
            message: "skeleton only: added a bone mesh (one shape per bone; --no-bone-mesh to leave it out)".into(),
        });
    }
    Ok(imported)
}

/// Resolves and imports exactly one asset.
///
/// # Errors
/// As [`single_plan`] and [`load`].
pub fn load_single(args: &InputArgs) -> Result<(Plan, Imported)> {
    let plan = single_plan(args)?;
    let imported = load(&plan, args)?;
    Ok((plan, imported))
}
