//! `rigport bake`: a dual quaternion skinning result baked into an ordinary (LBS) glTF as
//! per-frame corrective morph targets in bind space (`rigport_deform::bake::asset`).
//!
//! [`run`] is the whole pipeline; [`crate::bake()`] is the same function.

use rigport_deform::bake::asset::{DqsBakeOptions, bake_dqs};
use rigport_model::{InfluencesFit, SkinningMethod, Warning};

use crate::load::Input;
use crate::outputs::check_request;
use crate::progress::{Progress, step};
use crate::write::{Output, WriteOptions, write_output};
use crate::{PipelineError, Report};

/// What `bake` bakes, and where it writes.
///
/// ```
/// use rigport_model::SkinningMethod;
/// use rigport_pipeline::bake::BakeOptions;
/// use rigport_pipeline::{bake, load::Input, progress::Silent};
///
/// // A bake writes glTF; a USD stage declares DQS itself, so a .usda is a usage error.
/// let input = Input::new(vec!["../../fixtures/gltf/skin_basic.glb".into()]);
/// let options = BakeOptions {
///     skinning: Some(SkinningMethod::Dqs),
///     clip: None,
///     fps: Some(30.0),
///     threshold: None,
///     correctives: Some(2),
///     max_influences: 4,
///     output: "bend_dqs.usda".into(),
/// };
/// let err = bake(&input, &options, &Silent).unwrap_err();
/// assert!(err.is_usage(), "{err}");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug)]
pub struct BakeOptions {
    /// The skinning to bake (`None`: the first skin's own); LBS writes the plain file.
    pub skinning: Option<SkinningMethod>,
    /// The clip (the first when `None`).
    pub clip: Option<String>,
    /// Sample at this rate (default: the clip's key times).
    pub fps: Option<f32>,
    /// Corrections no longer than this (bind-space units) are left out of the sparse
    /// targets (default: 1e-6 of the skinned meshes' diagonal).
    pub threshold: Option<f32>,
    /// Compress the per-frame targets to this many shared targets (PCA).
    pub correctives: Option<u32>,
    /// Influences kept per vertex in the glTF, and used for the DQS being baked.
    pub max_influences: u8,
    /// The `.glb` or `.gltf` file.
    pub output: std::path::PathBuf,
}

/// Reads `input`, bakes one clip's DQS result into corrective morph targets, and writes an
/// LBS glTF that every viewer plays as DQS.
///
/// ```
/// use rigport_model::SkinningMethod;
/// use rigport_pipeline::bake::BakeOptions;
/// use rigport_pipeline::{bake, load::Input, progress::Silent};
///
/// let dir = tempfile::tempdir()?;
/// let input = Input::new(vec!["../../fixtures/gltf/skin_basic.glb".into()]);
/// let options = BakeOptions {
///     skinning: Some(SkinningMethod::Dqs),
///     clip: Some("bend".into()),
///     fps: None,
///     threshold: None,
///     correctives: None,
///     max_influences: 4,
///     output: dir.path().join("bend_dqs.glb"),
/// };
/// let report = bake(&input, &options, &Silent)?;
/// assert!(report.log.last().is_some_and(|l| l.starts_with("file size: ")));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// An output that is not glTF (a usage error); as the import, the bake and
/// [`write_output`].
pub fn run(
    input: &Input,
    options: &BakeOptions,
    progress: &dyn Progress,
) -> Result<Report, PipelineError> {
    if !crate::outputs::format_of(&options.output)?.is_gltf() {
        return Err(PipelineError::Usage(format!(
            "{}: bake writes glTF (.glb/.gltf); a .usda declares DQS directly (`rigport convert` to .usda with the DQS skinning method)",
            options.output.display()
        )));
    }
    check_request(input, &options.output, &[])?;
    let output = Output {
        path: options.output.clone(),
        options: WriteOptions {
            max_influences: Some(usize::from(options.max_influences)),
            // The DQS corrections are measured against what truncation leaves.
            influences_fit: InfluencesFit::Truncate,
            // The file itself is LBS; the DQS result lives in its morph targets.
            skinning: Some(SkinningMethod::Lbs),
            ..WriteOptions::default()
        },
        reduce_tolerance: None,
        reduce: false,
        cubic: false,
    };
    let (plan, imported) = input.load_single(progress, "reading input")?;
    let (mut asset, mut warnings) = (imported.asset, imported.warnings);
    let skinning = options
        .skinning
        .unwrap_or(asset.skins.first().map(|s| s.method).unwrap_or_default());
    if skinning == SkinningMethod::Lbs {
        warnings.push(Warning::Note {
            location: plan.label(),
            message: "skinning lbs: glTF skins with LBS already, no corrective targets needed; writing the plain file".into(),
        });
        let line = write_output(asset, warnings, &output, &input.budget, progress)?;
        return Ok(Report::logged(line));
    }
    let max_influences = usize::from(options.max_influences);
    let reports = step(progress, "baking DQS correctives", || {
        bake_dqs(
            &mut asset,
            &DqsBakeOptions {
                clip: options.clip.as_deref(),
                fps: options.fps,
                threshold: options.threshold,
                correctives: options.correctives,
            },
            // Exactly the influences the glTF will hold, so the viewer's LBS is what we invert.
            |skeleton, skin| rigport_export::gltf_influences(skeleton, skin, max_influences),
            &plan.label(),
            &mut warnings,
        )
    })
    .map_err(PipelineError::failed)?;
    // The DQS result is baked into the targets: the file itself skins linearly.
    asset
        .skins
        .iter_mut()
        .for_each(|s| s.method = Default::default());
    let mut report = Report::logged(write_output(
        asset,
        warnings,
        &output,
        &input.budget,
        progress,
    )?);
    report.log.extend(reports.iter().map(ToString::to_string));
    let path = &options.output;
    let mut size = std::fs::metadata(path).map_or(0, |m| m.len());
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf"))
    {
        size += std::fs::metadata(path.with_extension("bin")).map_or(0, |m| m.len());
    }
    report.log.push(format!("file size: {size} bytes"));
    Ok(report)
}
