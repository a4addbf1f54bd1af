//! Units of inputs that state none. BVH, OBJ (with Pinocchio files) and CSCI 520 rigs carry
//! lengths without a unit; rigport reads them as metres unless told otherwise, so a BVH in
//! centimetres became a character 170 m tall in every viewer. [`InputUnits`] gives the unit
//! (a name or metres per unit, or `auto` for the guess below); a file that states its unit
//! (ASF `:units`, USD `metersPerUnit`, glTF's metres) keeps it, and units given that
//! contradict it are an error unless forced.
//!
//! Without units given, a skeleton that stands taller than [`TALL`] units gets a
//! [`Warning::UnitsUnknown`] naming its height; a human one (legs found from its structure)
//! 100 to 250 units tall is taken to be in centimetres, which `auto` then applies.

use std::str::FromStr;

use rigport_eval::Pose;
use rigport_eval::sample::{CompiledClip, SampleJob};
use rigport_import::Imported;
use rigport_model::glam::{DVec3, Vec3};
use rigport_model::{Asset, UpAxis, Warning};

use crate::PipelineError;
pub use crate::error::UnitsConflict;

/// Units a skeleton may stand in before a missing unit is worth a warning (a human in metres
/// is about 1.7 units tall; 20 is no creature's height in metres that a rig shows).
///
/// ```
/// use rigport_pipeline::units::{standing_height, TALL};
///
/// // The fixture's skeleton is a few units tall: no warning.
/// let walk = rigport_import::bvh::import("../../fixtures/bvh/end_sites.bvh".as_ref())?;
/// assert!(standing_height(&walk.asset).is_some_and(|h| h < TALL));
/// # Ok::<(), rigport_import::ImportError>(())
/// ```
pub const TALL: f32 = 20.0;

/// The unit of an input that states none.
///
/// ```
/// use rigport_pipeline::units::InputUnits;
///
/// assert_eq!("cm".parse(), Ok(InputUnits::MetersPerUnit(0.01)));
/// assert_eq!("0.3048".parse(), Ok(InputUnits::MetersPerUnit(0.3048)));
/// assert_eq!("auto".parse(), Ok(InputUnits::Auto));
/// assert!("furlong".parse::<InputUnits>().is_err() && "-1".parse::<InputUnits>().is_err());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InputUnits {
    /// This many metres per unit of the file.
    MetersPerUnit(f64),
    /// The guess rigport warns about without units: centimetres for a human skeleton 100 to
    /// 250 units tall; nothing otherwise.
    Auto,
}

impl FromStr for InputUnits {
    type Err = String;

    /// `m`, `cm`, `mm`, `in`, `ft`, a positive number of metres per unit, or `auto`.
    fn from_str(text: &str) -> Result<Self, String> {
        let t = text.trim();
        let mpu = match t.to_ascii_lowercase().as_str() {
            "auto" => return Ok(Self::Auto),
            "m" => 1.0,
            "cm" => 0.01,
            "mm" => 0.001,
            "in" => 0.0254,
            "ft" => 0.3048,
            _ => t
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v > 0.0)
                .ok_or_else(|| {
                    format!("{t:?}: expected m, cm, mm, in, ft, metres per unit, or auto")
                })?,
        };
        Ok(Self::MetersPerUnit(mpu))
    }
}

/// How tall `asset`'s skeleton stands along its scene's up axis, in its own units: in the
/// first frame of its first clip (a BVH's rest pose may lie flat), else at rest; `None`
/// without joints.
///
/// ```
/// use rigport_pipeline::units::standing_height;
///
/// let walk = rigport_import::bvh::import("../../fixtures/bvh/end_sites.bvh".as_ref())?;
/// assert!(standing_height(&walk.asset).is_some_and(|h| h > 0.0));
/// # Ok::<(), rigport_import::ImportError>(())
/// ```
pub fn standing_height(asset: &Asset) -> Option<f32> {
    let skeleton = &asset.skeleton;
    let rest = Pose::rest(skeleton);
    let mut pose = rest.clone();
    let first = asset
        .clips
        .first()
        .and_then(|c| CompiledClip::new(c, skeleton).ok());
    if let Some(clip) = &first {
        let mut job = SampleJob {
            clip,
            time: clip.start(),
            rest: &rest.local,
            output: &mut pose.local,
        };
        if job.run().is_err() {
            pose = rest.clone();
        }
    }
    let model = pose.model_matrices(skeleton).ok()?;
    let to_y_up = asset.frame.model_to(None, UpAxis::Y, None);
    let heights = model
        .iter()
        .map(|m| to_y_up.transform_point3(m.w_axis.truncate().as_dvec3()).y as f32);
    let (lo, hi) = heights.fold(None, |acc: Option<(f32, f32)>, y| match acc {
        None => Some((y, y)),
        Some((lo, hi)) => Some((lo.min(y), hi.max(y))),
    })?;
    Some(hi - lo)
}

/// The unit a human skeleton `height` units tall is almost certainly in: centimetres for
/// 100 to 250 (metres per unit), `None` otherwise or when `asset` shows no legs.
fn guess(asset: &Asset, height: f32) -> Option<f64> {
    // The skeleton's own up: the scene's up axis taken back into model space.
    let to_y_up = asset.frame.model_to(None, UpAxis::Y, None);
    let up: Vec3 = to_y_up
        .inverse()
        .transform_vector3(DVec3::Y)
        .normalize_or_zero()
        .as_vec3();
    let human = rigport_ik::retarget::find_body(&asset.skeleton, up, asset.clips.first()).is_some();
    (human && (100.0..=250.0).contains(&height)).then_some(0.01)
}

/// Gives `imported` the units `given` (see the module doc) and `force`s them over a stated
/// unit when asked; warns about a tall skeleton without units. `label` names the input.
///
/// # Errors
/// Units given that contradict the file's own, unless `force`.
pub(crate) fn apply(
    imported: &mut Imported,
    given: Option<InputUnits>,
    force: bool,
    label: &str,
) -> Result<(), PipelineError> {
    let asset = &mut imported.asset;
    let height = standing_height(asset).filter(|_| asset.skeleton.len() > 1);
    match (given, asset.meters_per_unit) {
        (Some(InputUnits::MetersPerUnit(given)), Some(stated))
            if (given - stated).abs() > 1e-9 * stated.abs() =>
        {
            if !force {
                return Err(PipelineError::Units(UnitsConflict {
                    file: label.to_string(),
                    stated,
                    given,
                }));
            }
            asset.meters_per_unit = Some(given);
        }
        (Some(InputUnits::MetersPerUnit(given)), None) => asset.meters_per_unit = Some(given),
        (Some(InputUnits::Auto), None) => {
            let guessed = height.and_then(|h| guess(asset, h).map(|g| (h, g)));
            if let Some((h, g)) = guessed {
                asset.meters_per_unit = Some(g);
                imported.warnings.push(Warning::Note {
                    location: label.to_string(),
                    message: format!(
                        "the skeleton stands {h:.1} units tall with no unit stated: read as \
                         centimetres ({:.2} m)",
                        f64::from(h) * g
                    ),
                });
            } else if let Some(h) = height.filter(|h| *h > TALL) {
                imported.warnings.push(Warning::UnitsUnknown {
                    location: label.to_string(),
                    height: h,
                    guess: None,
                });
            }
        }
        (None, None) => {
            if let Some(h) = height.filter(|h| *h > TALL) {
                let guess = guess(asset, h);
                imported.warnings.push(Warning::UnitsUnknown {
                    location: label.to_string(),
                    height: h,
                    guess,
                });
            }
        }
        _ => {}
    }
    Ok(())
}
