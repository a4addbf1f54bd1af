//! Inputs to assets, as the CLI opens them: [`Input`] names the files, `plan` resolves
//! them into one [`Source`] per asset (`rigport_import::detect`), and `load` imports one
//! under the memory budget and gives a skeleton-only asset a bone mesh so viewers show its
//! motion.

use std::path::PathBuf;

use rigport_import::Imported;
pub use rigport_import::detect::{Inputs, Source};
use rigport_model::{MemoryBudget, Warning};

use crate::PipelineError;
use crate::progress::Progress;

/// What a command reads: the input files as named, whether a skeleton-only rig gets a
/// bone mesh, and the memory budget imports and writes are checked against.
///
/// ```
/// use rigport_pipeline::inspect::InspectOptions;
/// use rigport_pipeline::{inspect, load::Input, progress::Silent, MemoryBudget};
///
/// // A BVH is a skeleton only: by default it gets a bone mesh, here it does not.
/// let input = Input {
///     bone_mesh: false,
///     budget: MemoryBudget { limit: 1 << 30, origin: "this example" },
///     ..Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()])
/// };
/// let report = inspect(&input, &InspectOptions { json: true }, &Silent)?;
/// let json: serde_json::Value = serde_json::from_str(report.output.as_deref().unwrap_or(""))?;
/// assert_eq!(json[0]["meshes"].as_array().map(Vec::len), Some(0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct Input {
    /// The files, as the command line names them.
    pub files: Inputs,
    /// A skeleton-only rig gets a generated bone mesh (one shape per bone).
    pub bone_mesh: bool,
    /// The memory budget.
    pub budget: MemoryBudget,
    /// The unit of inputs that state none (BVH, OBJ/Pinocchio, CSCI 520); `None`: metres,
    /// with a warning for a skeleton too tall for them ([`crate::units`]).
    pub units: Option<crate::units::InputUnits>,
    /// Apply `units` even over a unit the file states.
    pub force_units: bool,
}

impl Input {
    /// `paths`, with a bone mesh for skeleton-only rigs and no memory limit.
    ///
    /// ```
    /// let input = rigport_pipeline::load::Input::new(vec!["walk.bvh".into()]);
    /// assert!(input.bone_mesh);
    /// // The process's budget (`memory::install`), unlimited when none was installed.
    /// assert_eq!(input.budget, rigport_pipeline::MemoryBudget::UNLIMITED);
    /// ```
    pub fn new(paths: Vec<PathBuf>) -> Self {
        Self {
            files: Inputs::new(paths),
            bone_mesh: true,
            budget: crate::memory::installed(),
            units: None,
            force_units: false,
        }
    }

    /// One plan per asset.
    ///
    /// # Errors
    /// As [`plan`].
    pub(crate) fn plans(&self) -> Result<Vec<Source>, PipelineError> {
        plan(&self.files)
    }

    /// Imports `plan` (see [`load`]); weights computed on the way (`auto_weights`) tell
    /// `progress` how far they are.
    ///
    /// # Errors
    /// As [`load`].
    pub(crate) fn load(
        &self,
        plan: &Source,
        progress: &dyn Progress,
    ) -> Result<Imported, PipelineError> {
        let mut imported = load(plan, self.bone_mesh, &self.budget, progress)?;
        if self.files.auto_weights && matches!(plan, Source::Csci520(_)) {
            // The weights are computed: their absence is no loss.
            use rigport_import::csci520::NO_WEIGHTS;
            (imported.warnings).retain(|w| !matches!(w, Warning::Incomplete { message, .. } if message.ends_with(NO_WEIGHTS)));
            crate::weights::bind_unskinned(&mut imported, &plan.label(), progress)?;
        }
        crate::units::apply(&mut imported, self.units, self.force_units, &plan.label())?;
        Ok(imported)
    }

    /// Resolves and imports exactly one asset, as a step of `progress` named `step`: the
    /// asset's plan (its label names it in messages) and the asset with its warnings.
    ///
    /// ```
    /// use rigport_pipeline::{load::Input, progress::Silent};
    ///
    /// let input = Input::new(vec!["../../fixtures/bvh/end_sites.bvh".into()]);
    /// let (plan, imported) = input.load_single(&Silent, "reading")?;
    /// assert!(plan.label().ends_with("end_sites.bvh"), "{}", plan.label());
    /// assert_eq!(imported.asset.skeleton.len(), 9);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// The inputs do not make exactly one asset; as the import.
    pub fn load_single(
        &self,
        progress: &dyn Progress,
        step: &str,
    ) -> Result<(Source, Imported), PipelineError> {
        crate::progress::step(progress, step, || {
            let plan = single_plan(&self.files)?;
            let imported = self.load(&plan, progress)?;
            Ok((plan, imported))
        })
    }

    /// The files these inputs read ([`input_files`]).
    pub(crate) fn read_files(&self) -> Vec<PathBuf> {
        input_files(&self.files)
    }
}

/// Resolves inputs into one plan per asset (see `rigport_import::detect::plan`).
///
/// # Errors
/// The inputs do not group into assets.
pub(crate) fn plan(inputs: &Inputs) -> Result<Vec<Source>, PipelineError> {
    Ok(rigport_import::detect::plan(inputs)?)
}

/// Resolves inputs into exactly one asset plan.
///
/// # Errors
/// As [`plan`], or more or fewer than one asset.
pub(crate) fn single_plan(inputs: &Inputs) -> Result<Source, PipelineError> {
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
/// generated bone mesh (noted in the warnings). Weights computed for a Pinocchio mesh
/// without its attachment tell `progress` how far they are.
///
/// # Errors
/// Over the memory budget; as the importer.
pub(crate) fn load(
    plan: &Source,
    bone_mesh: bool,
    budget: &MemoryBudget,
    progress: &dyn Progress,
) -> Result<Imported, PipelineError> {
    crate::memory::check_import(plan, budget)?;
    let mut imported = match plan {
        Source::PinocchioUnweighted { mesh, skeleton } => {
            crate::weights::auto_rig(mesh, skeleton, progress)?
        }
        _ => plan.import()?,
    };
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
pub(crate) fn input_files(inputs: &Inputs) -> Vec<PathBuf> {
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
            | Source::Usda(p)
            | Source::Fbx(p)
            | Source::Collada(p) => files.push(p),
            Source::Pinocchio {
                mesh,
                skeleton,
                attachment,
            } => files.extend([mesh, skeleton, attachment]),
            Source::PinocchioUnweighted { mesh, skeleton } => files.extend([mesh, skeleton]),
            Source::AsfAmc { asf, motions, .. } => {
                files.push(asf);
                files.extend(motions);
            }
        }
    }
    files
}
