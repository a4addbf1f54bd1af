//! `rigport cloth`: a garment simulated on the animated body and baked into the output
//! (the work is `rigport_deform::cloth::asset`).
//!
//! [`run`] is the whole pipeline; [`crate::cloth()`] is the same function.

use std::path::PathBuf;

use rigport_deform::cloth::asset::{self, ClothReport, GarmentSource};
use rigport_deform::cloth::{
    ClothOptions, PinSelection, UNSTABLE_MEAN_SPEED, UNSTABLE_SPEED, UNSTABLE_STRETCH,
};
use rigport_model::Warning;
use serde_json::json;

use crate::load::Input;
use crate::outputs::check_request;
use crate::progress::Progress;
use crate::write::{Output, WriteOptions, write_output};
use crate::{PipelineError, Report};

/// What `cloth` simulates, and where it writes.
///
/// ```
/// use rigport_pipeline::cloth::ClothRequest;
/// use rigport_pipeline::{cloth, load::Input, progress::Silent};
///
/// // The output is checked before any work: it must not be one of the inputs.
/// let input = Input::new(vec!["../../fixtures/gltf/skin_basic.glb".into()]);
/// let request = ClothRequest {
///     garment: "Cape".into(),
///     seconds: Some(2.0),
///     substeps: Some(8),
///     output: "../../fixtures/gltf/skin_basic.glb".into(),
///     ..ClothRequest::default()
/// };
/// let err = cloth(&input, &request, &Silent).unwrap_err();
/// assert!(err.is_usage(), "{err}");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, Default)]
#[cfg_attr(feature = "clap", derive(clap::Args))]
pub struct ClothRequest {
    /// The garment: the name of an unskinned mesh of the input, or an .obj file.
    #[cfg_attr(feature = "clap", arg(long, value_name = "GARMENT"))]
    pub garment: String,
    /// The pinned vertices (none: the garment's own control points).
    #[cfg_attr(feature = "clap", arg(skip))]
    pub pins: Vec<PinSelection>,
    /// The clip to simulate (default: the first).
    #[cfg_attr(feature = "clap", arg(long, value_name = "NAME"))]
    pub clip: Option<String>,
    /// Output frames per second (default: the clip's key rate when 24 or more, else 30).
    #[cfg_attr(feature = "clap", arg(long, value_name = "F", value_parser = crate::numbers::frame_rate))]
    pub fps: Option<f32>,
    /// Simulate S seconds, looping the clip (default: the clip once).
    #[cfg_attr(feature = "clap", arg(long, value_name = "S"))]
    pub seconds: Option<f32>,
    /// Substeps per frame (default: 1200 per second).
    #[cfg_attr(feature = "clap", arg(long, value_name = "N"))]
    pub substeps: Option<u32>,
    /// Collision thickness in model units (default: 1% of the body's diagonal).
    #[cfg_attr(feature = "clap", arg(long, value_name = "D"))]
    pub thickness: Option<f32>,
    /// Seconds of pre-roll settling the garment into the first pose and each cut (default 2).
    #[cfg_attr(feature = "clap", arg(long, value_name = "S"))]
    pub preroll: Option<f32>,
    /// Collide with the whole body, not only the bones near the garment at rest (and up).
    #[cfg_attr(feature = "clap", arg(long))]
    pub collide_all: bool,
    /// Keep a simulation past the stability limits (warning W007) instead of failing.
    #[cfg_attr(feature = "clap", arg(long))]
    pub allow_unstable: bool,
    /// Print the report as JSON on stdout, with every frame's measurements.
    #[cfg_attr(feature = "clap", arg(long))]
    pub json: bool,
    /// Compress the per-frame targets to K shared ones (PCA), as `bake --correctives`.
    #[cfg_attr(feature = "clap", arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(1..)))]
    pub targets: Option<u32>,
    /// Output file: .glb, .gltf (+ .bin), .usda, .usdc or .usdz.
    #[cfg_attr(feature = "clap", arg(long, short, value_name = "OUT"))]
    pub output: PathBuf,
}

/// Reads `input`, simulates the garment on one clip, and writes the rig with the garment
/// baked in (glTF: morph targets; USD: time-sampled points).
///
/// ```
/// use rigport_pipeline::cloth::ClothRequest;
/// use rigport_pipeline::{cloth, load::Input, progress::Silent};
///
/// let dir = tempfile::tempdir()?;
/// let out = dir.path().join("dressed.glb");
/// let input = Input::new(vec!["../../fixtures/gltf/skin_basic.glb".into()]);
/// // The garment must be a mesh of the input or an .obj file.
/// let request = ClothRequest {
///     garment: "Skirt".into(),
///     output: out.clone(),
///     ..ClothRequest::default()
/// };
/// assert!(cloth(&input, &request, &Silent).is_err());
/// assert!(!out.exists());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// A garment that cannot be read or found; a failed simulation; as the import and
/// [`write_output`].
pub fn run(
    input: &Input,
    request: &ClothRequest,
    progress: &dyn Progress,
) -> Result<Report, PipelineError> {
    let garment_path = PathBuf::from(&request.garment);
    let garment_file = garment_path.is_file();
    let extra: Vec<&std::path::Path> = garment_file
        .then_some(garment_path.as_path())
        .into_iter()
        .collect();
    check_request(input, &request.output, &extra)?;
    let (plan, imported) = input.load_single(progress, "reading input")?;
    let (mut asset, mut warnings): (_, Vec<Warning>) = (imported.asset, imported.warnings);
    let source = if garment_file {
        let obj = rigport_import::obj::import(&garment_path).map_err(|e| {
            PipelineError::step(
                format!("cannot read the garment {}", garment_path.display()),
                e,
            )
        })?;
        warnings.extend(obj.warnings);
        let mesh = obj.asset.meshes.into_iter().next().ok_or_else(|| {
            PipelineError::Invalid(format!(
                "the garment {} holds no mesh",
                garment_path.display()
            ))
        })?;
        GarmentSource::Mesh(Box::new(mesh))
    } else {
        GarmentSource::Named(&request.garment)
    };
    let opts = ClothOptions {
        clip: request.clip.as_deref(),
        fps: request.fps,
        seconds: request.seconds,
        substeps: request.substeps,
        thickness: request.thickness,
        preroll: request.preroll,
        allow_unstable: request.allow_unstable,
        collide_all: request.collide_all,
        ..ClothOptions::default()
    };
    let report = asset::run(
        &mut asset,
        source,
        &request.pins,
        &opts,
        request.targets.map(|k| k as usize),
        &mut warnings,
        |done, total| progress.count("simulating cloth", done, total),
    )
    .map_err(|e| {
        PipelineError::step(
            format!("cannot simulate the garment on {}", plan.label()),
            e,
        )
    })?;
    let output = Output {
        path: request.output.clone(),
        options: WriteOptions {
            morphs_as_points: true,
            ..WriteOptions::default()
        },
        reduce_tolerance: None,
        reduce: false,
        cubic: false,
    };
    let mut done = Report::logged(write_output(
        asset,
        warnings,
        &output,
        &input.budget,
        progress,
    )?);
    if request.json {
        let text = serde_json::to_string_pretty(&report_json(&report))
            .map_err(|e| PipelineError::step("cannot write the report as JSON", e))?;
        done.output = Some(text + "\n");
    } else {
        done.log.push(report.to_string());
    }
    Ok(done)
}

/// The report as JSON: the run, the limits, the worst values and every frame's.
fn report_json(r: &ClothReport) -> serde_json::Value {
    let frames: Vec<_> = r
        .stats
        .iter()
        .zip(&r.times)
        .map(|(s, t)| {
            json!({"time": t, "max_stretch": s.max_stretch, "kinetic_energy": s.kinetic_energy,
                "max_speed": s.max_speed, "penetration_depth": s.body_depth,
                "penetration_count": s.body_inside, "capsule_depth": s.max_depth})
        })
        .collect();
    let first = r.stats.first().copied().unwrap_or_default();
    json!({
        "garment": r.garment, "particles": r.particles, "pins": r.pins,
        "capsules": r.capsules, "fps": r.fps, "substeps": r.substeps,
        "thickness": r.thickness, "diagonal": r.diagonal, "preroll": r.preroll,
        "settle_residual": r.settle_residual,
        "cuts": r.cuts.iter().map(|c| json!({"frame": c.frame, "jump": c.jump})).collect::<Vec<_>>(),
        "frame_0": {"max_stretch": first.max_stretch, "kinetic_energy": first.kinetic_energy,
            "max_speed": first.max_speed, "penetration_depth": first.body_depth},
        "limits": {"max_stretch": UNSTABLE_STRETCH, "speed_diagonals_per_second": UNSTABLE_SPEED,
            "mean_speed_diagonals_per_second": UNSTABLE_MEAN_SPEED},
        "worst": {"max_stretch": r.worst.max_stretch, "kinetic_energy": r.worst.kinetic_energy,
            "max_speed": r.worst.max_speed, "penetration_depth": r.worst.body_depth,
            "penetration_count": r.worst.body_inside},
        "targets": r.targets, "max_target_error": r.max_target_error,
        "frames": frames,
    })
}
