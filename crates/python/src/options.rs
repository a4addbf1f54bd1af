//! Python values to the pipeline's option types, each converted at this edge with the
//! parser the CLI uses (`InputUnits::from_str`, `UpAxis::parse`): where a rig comes from
//! ([`input`]), how an asset is written ([`output`]), and the enumerations given as
//! strings.

use std::path::PathBuf;
use std::str::FromStr as _;

use pyo3::prelude::*;
use rigport_anim::root_motion::{RootMotion, RootMotionOptions};
use rigport_model::{Compression, InfluencesFit, MemoryBudget, SkinningMethod, UpAxis};
use rigport_pipeline::load::{Input, Inputs};
use rigport_pipeline::units::InputUnits;
use rigport_pipeline::write::{Output, WriteOptions};

use crate::errors::usage;

/// Where a rig comes from: the keyword arguments of `rigport.open`, as the CLI's input
/// options.
#[derive(Clone, Debug, Default)]
pub struct InputOptions {
    /// The OBJ mesh of a Pinocchio rig.
    pub mesh: Option<PathBuf>,
    /// The Pinocchio `skeleton.out`.
    pub skeleton: Option<PathBuf>,
    /// The Pinocchio `attachment.out`.
    pub attachment: Option<PathBuf>,
    /// AMC motions for an `.asf`.
    pub motion: Vec<PathBuf>,
    /// The frame rate of AMC motions.
    pub amc_fps: Option<f32>,
    /// A skeleton-only rig gets a bone mesh.
    pub bone_mesh: bool,
    /// `"auto"`: bone-heat weights for a Pinocchio mesh and skeleton.
    pub weights: Option<String>,
    /// The unit of inputs that state none.
    pub input_units: Option<String>,
    /// Apply `input_units` even over a unit the file states.
    pub force_units: bool,
    /// The memory budget in bytes (default: the CLI's).
    pub max_memory: Option<u64>,
}

/// The pipeline's [`Input`] for `paths` and `options`.
///
/// # Errors
/// A usage error for a value the CLI would refuse.
pub fn input(paths: Vec<PathBuf>, options: &InputOptions) -> PyResult<Input> {
    if let Some(fps) = options.amc_fps {
        positive("amc_fps", fps)?;
    }
    let auto_weights = match options.weights.as_deref() {
        None => false,
        Some("auto") => true,
        Some(other) => return Err(usage(format!("weights={other:?}: expected \"auto\""))),
    };
    let units = match &options.input_units {
        None => None,
        Some(text) => Some(
            InputUnits::from_str(text).map_err(|e| usage(format!("input_units={text:?}: {e}")))?,
        ),
    };
    if options.force_units && units.is_none() {
        return Err(usage("force_units=True needs input_units"));
    }
    if paths.is_empty()
        && options.mesh.is_none()
        && options.skeleton.is_none()
        && options.attachment.is_none()
    {
        return Err(usage(
            "no input: give paths, or mesh=, skeleton= and attachment=",
        ));
    }
    Ok(Input {
        files: Inputs {
            paths,
            mesh: options.mesh.clone(),
            skeleton: options.skeleton.clone(),
            attachment: options.attachment.clone(),
            motions: options.motion.clone(),
            amc_fps: options.amc_fps,
            auto_weights,
        },
        bone_mesh: options.bone_mesh,
        budget: budget(options.max_memory),
        units,
        force_units: options.force_units,
    })
}

/// The memory budget: `max_memory` bytes, or the CLI's default.
pub fn budget(max_memory: Option<u64>) -> MemoryBudget {
    match max_memory {
        Some(bytes) => rigport_pipeline::memory::process_budget(Some(bytes), "max_memory"),
        None => rigport_pipeline::memory::DEFAULT,
    }
}

/// How an asset is written: the keyword arguments of `Asset.write` and of every command
/// that writes an asset, as the CLI's output options.
#[derive(Clone, Debug, Default)]
pub struct OutputOptions {
    /// Influences kept per vertex (1 to 8).
    pub max_influences: Option<u8>,
    /// `"truncate"` or `"refit"`.
    pub influences_fit: Option<String>,
    /// Remove keys within this distance.
    pub reduce_tolerance: Option<f32>,
    /// Reduce keys (within `reduce_tolerance`, or the default 1 mm).
    pub reduce: bool,
    /// Also fit CUBICSPLINE tracks (core glTF).
    pub reduce_cubic: bool,
    /// glTF compression: `"none"` or `"meshopt"`.
    pub compress: Option<String>,
    /// The skinning method a USD declares.
    pub skinning: Option<String>,
    /// The up axis a USD declares.
    pub up_axis: Option<String>,
    /// The metres per unit a USD declares.
    pub meters_per_unit: Option<f64>,
}

/// The pipeline's [`Output`] to `path`.
///
/// # Errors
/// A usage error for a value the CLI would refuse.
pub fn output(path: PathBuf, options: &OutputOptions) -> PyResult<Output> {
    if let Some(k) = options.max_influences {
        if !(1..=8).contains(&k) {
            return Err(usage(format!("max_influences={k}: expected 1 to 8")));
        }
    }
    let influences_fit = match options.influences_fit.as_deref() {
        None | Some("truncate") => InfluencesFit::Truncate,
        Some("refit") => InfluencesFit::Refit,
        Some(other) => {
            return Err(usage(format!(
                "influences_fit={other:?}: expected \"truncate\" or \"refit\""
            )));
        }
    };
    if let Some(d) = options.reduce_tolerance {
        if !(d.is_finite() && d >= 0.0) {
            return Err(usage(format!(
                "reduce_tolerance={d}: expected a distance >= 0"
            )));
        }
    }
    Ok(Output {
        path,
        options: WriteOptions {
            max_influences: options.max_influences.map(usize::from),
            influences_fit,
            skinning: skinning(options.skinning.as_deref())?,
            up_axis: up_axis(options.up_axis.as_deref())?,
            meters_per_unit: options.meters_per_unit,
            morphs_as_points: false,
            compression: match options.compress.as_deref() {
                None | Some("none") => Compression::None,
                Some("meshopt") => Compression::Meshopt,
                Some(other) => {
                    return Err(usage(format!(
                        "compress={other:?}: expected \"none\" or \"meshopt\""
                    )));
                }
            },
        },
        reduce_tolerance: options.reduce_tolerance,
        reduce: options.reduce || options.reduce_tolerance.is_some(),
        cubic: options.reduce_cubic,
    })
}

/// `"lbs"` or `"dqs"`.
///
/// # Errors
/// Any other text.
pub fn skinning(text: Option<&str>) -> PyResult<Option<SkinningMethod>> {
    match text {
        None => Ok(None),
        Some("lbs") => Ok(Some(SkinningMethod::Lbs)),
        Some("dqs") => Ok(Some(SkinningMethod::Dqs)),
        Some(other) => Err(usage(format!(
            "skinning={other:?}: expected \"lbs\" or \"dqs\""
        ))),
    }
}

/// `"Y"` or `"Z"` (either case).
///
/// # Errors
/// Any other text.
pub fn up_axis(text: Option<&str>) -> PyResult<Option<UpAxis>> {
    match text {
        None => Ok(None),
        Some(t) => UpAxis::parse(t)
            .map(Some)
            .ok_or_else(|| usage(format!("up_axis={t:?}: expected \"Y\" or \"Z\""))),
    }
}

/// The clips' root motion: `mode` `"keep"`, `"in-place"` or `"extract"`, the heading too
/// with `yaw`, smoothed over `window_s` seconds.
///
/// # Errors
/// An unknown mode, or a window that is negative or not finite.
pub fn root_motion(mode: &str, yaw: bool, window_s: Option<f32>) -> PyResult<RootMotionOptions> {
    let mode = match mode {
        "keep" => RootMotion::Keep,
        "in-place" | "in_place" => RootMotion::InPlace,
        "extract" => RootMotion::Extract,
        other => {
            return Err(usage(format!(
                "root_motion={other:?}: expected \"keep\", \"in-place\" or \"extract\""
            )));
        }
    };
    let defaults = RootMotionOptions::default();
    let window_s = window_s.unwrap_or(defaults.window_s);
    if !(window_s.is_finite() && window_s >= 0.0) {
        return Err(usage(format!(
            "root_window={window_s}: expected seconds >= 0"
        )));
    }
    Ok(RootMotionOptions {
        mode,
        yaw,
        window_s,
    })
}

/// A frame rate: positive and finite.
///
/// # Errors
/// Anything else, named `name`.
pub fn positive(name: &str, value: f32) -> PyResult<f32> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(usage(format!("{name}={value}: expected a positive number")))
    }
}
