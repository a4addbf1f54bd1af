//! Inputs to assets, as the CLI opens them: [`plan`] resolves paths into one
//! [`Source`] per asset (`rigport_import::detect`), [`load`] imports one under the memory
//! budget and gives a skeleton-only asset a bone mesh so viewers show its motion.
//!
//! ```
//! use rigport_pipeline::{load, MemoryBudget};
//!
//! let inputs = load::Inputs::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
//! let plan = load::single_plan(&inputs)?;
//! let imported = load::load(&plan, true, &MemoryBudget::UNLIMITED)?;
//! assert_eq!(imported.asset.meshes.len(), 1, "a bone mesh was added");
//! assert!(imported.warnings.iter().any(|w| w.to_string().contains("bone mesh")));
//! # Ok::<(), rigport_pipeline::PipelineError>(())
//! ```

use std::path::PathBuf;

pub use rigport_import::detect::{Inputs, Source};
use rigport_import::Imported;
use rigport_model::{MemoryBudget, Warning};

use crate::progress::Progress;
use crate::PipelineError;

/// What a command reads: the input files as named, whether a skeleton-only rig gets a
/// bone mesh, and the memory budget imports and writes are checked against.
#[derive(Clone, Debug)]
pub struct Input {
    /// The files, as the command line names them.
    pub files: Inputs,
    /// A skeleton-only rig gets a generated bone mesh (one shape per bone).
    pub bone_mesh: bool,
    /// The memory budget.
    pub budget: MemoryBudget,
}

impl Input {
    /// `paths`, with a bone mesh for skeleton-only rigs and no memory limit.
    pub fn new(paths: Vec<PathBuf>) -> Self {
        Self {
            files: Inputs::new(paths),
            bone_mesh: true,
            budget: MemoryBudget::UNLIMITED,
        }
    }

    /// One plan per asset.
    ///
    /// # Errors
    /// As [`plan`].
    pub fn plans(&self) -> Result<Vec<Source>, PipelineError> {
        plan(&self.files)
    }

    /// Imports `plan` (see [`load`]).
    ///
    /// # Errors
    /// As [`load`].
    pub fn load(&self, plan: &Source) -> Result<Imported, PipelineError> {
        load(plan, self.bone_mesh, &self.budget)
    }

    /// Resolves and imports exactly one asset, as a step of `progress`.
    ///
    /// # Errors
    /// As [`single_plan`] and [`load`].
    pub fn load_single(
        &self,
        progress: &dyn Progress,
        step: &str,
    ) -> Result<(Source, Imported), PipelineError> {
        crate::progress::step(progress, step, || {
            let plan = single_plan(&self.files)?;
            let imported = self.load(&plan)?;
            Ok((plan, imported))
        })
    }

    /// The files these inputs read ([`input_files`]).
    pub fn read_files(&self) -> Vec<PathBuf> {
        input_files(&self.files)
    }
}

/// Resolves inputs into one plan per asset (see `rigport_import::detect::plan`).
///
/// # Errors
/// The inputs do not group into assets.
pub fn plan(inputs: &Inputs) -> Result<Vec<Source>, PipelineError> {
    Ok(rigport_import::detect::plan(inputs)?)
}

/// Resolves inputs into exactly one asset plan.
///
/// # Errors
/// As [`plan`], or more or fewer than one asset.
pub fn single_plan(inputs: &Inputs) -> Result<Source, PipelineError> {
    let mut plans = plan(inputs)?;
    if plans.len() != 1 {
        return Err(PipelineError::Invalid(format!(
            "this command takes one rig; {} were given",
            plans.len()
        )));
    }
    Ok(plans.remove(0))
}

/// Imports a plan within `budget`; with `bone_mesh`, a skeleton-only asset gets a
/// generated bone mesh (noted in the warnings).
///
/// # Errors
/// Over the memory budget; as the importer.
pub fn load(
    plan: &Source,
    bone_mesh: bool,
    budget: &MemoryBudget,
) -> Result<Imported, PipelineError> {
    crate::memory::check_import(plan, budget)?;
    let mut imported = plan.import()?;
    if bone_mesh && rigport_import::bone_mesh::add_bone_mesh(&mut imported.asset) {
        imported.warnings.push(Warning::Note {
            location: plan.label(),
            message: "skeleton only: added a bone mesh (one shape per bone; the bone-mesh setting leaves it out)".into(),
        });
    }
    Ok(imported)
}

/// The files an input specification reads: those of its resolved plans (a folder stands
/// for the files picked from it), or the paths as given when they do not resolve (the
/// command then reports why).
pub fn input_files(inputs: &Inputs) -> Vec<PathBuf> {
    let Ok(plans) = plan(inputs) else {
        let mut files = inputs.paths.clone();
        files.extend(inputs.mesh.iter().cloned());
        files.extend(inputs.skeleton.iter().cloned());
        files.extend(inputs.attachment.iter().cloned());
        files.extend(inputs.motions.iter().cloned());
        return files;
    };
    let mut files = Vec::new();
    for plan in plans {
        match plan {
            Source::Gltf(p)
            | Source::Obj(p)
            | Source::Csci520(p)
            | Source::Bvh(p)
            | Source::Usda(p) => files.push(p),
            Source::Pinocchio {
                mesh,
                skeleton,
                attachment,
            } => files.extend([mesh, skeleton, attachment]),
            Source::AsfAmc { asf, motions, .. } => {
                files.push(asf);
                files.extend(motions);
            }
        }
    }
    files
}
