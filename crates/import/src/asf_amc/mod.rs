//! Acclaim ASF skeletons with AMC motions (CMU motion capture).
//!
//! # The files (FORMATS.md "Acclaim ASF/AMC")
//! - Both are line based. Lines end with LF, CRLF or a lone CR; blank lines, indentation,
//!   tabs and trailing white space are fine everywhere. A `#` at the start of a line or
//!   after white space starts a comment that runs to the end of the line (a `#` inside a
//!   token, as in a Windows `-1.#IND`, is not a comment: that token is not a number).
//!   Keywords (`:units`, `begin`, `order`, `TX`, `XYZ`, `dof`, `rx`, `deg`, `:DEGREES`,
//!   `root`, ...) are case-insensitive; bone names are case-sensitive.
//! - ASF ([`parse_asf`]): `:version`, `:name` and `:documentation` are kept as text;
//!   `:units` gives `mass` (kept, unused), `length` and `angle deg|rad` (default `deg`);
//!   `:root` needs `order` (1 to 6 of `TX TY TZ RX RY RZ`), `axis` (an Euler order such as
//!   `XYZ`), `position` and `orientation` (3 numbers each); `:bonedata` holds `begin` ...
//!   `end` blocks with `name`, `direction` (3 numbers), `length` and `axis ax ay az ORDER`
//!   (required), `id`, `dof` (any of `tx ty tz rx ry rz l`, each at most once, in the order
//!   the AMC lists the values) and `limits` (one `(min max)` pair per dof, on the `limits`
//!   line and/or the lines after it; `inf` is allowed), and `bodymass` / `cofmass` (read
//!   and ignored, as `mass` is). `:hierarchy` holds a `begin` ... `end` block of
//!   `parent child child ...` lines. Unknown `:sections` and unknown `:units` entries are
//!   skipped (listed in [`Asf::skipped`], reported as [`Warning::Note`]s).
//! - AMC ([`parse_amc`]): header lines (`:FULLY-SPECIFIED`, `:DEGREES` or `:RADIANS`,
//!   others kept in [`Amc::header`]), then frames: a line holding only the frame number,
//!   followed by `bone v1 v2 ...` lines, one value per dof in the ASF's dof order (the
//!   root's in its `order`). Bones with no dof may be listed with no values. The frame
//!   rate is not in the file (CMU records at [`DEFAULT_FPS`]).
//!
//! # Choices where the format leaves room
//! - A bone that `:hierarchy` never lists as a child is an **error** (at its `name` line),
//!   not silently attached to the root: a bone placed at the root would look plausible and
//!   be wrong.
//! - A bone missing from an AMC frame holds its value from the frame before (the rest pose,
//!   all dofs 0, in the first frame); one [`Warning::Repaired`] per file counts them.
//!   Frame numbers that are not consecutive give one [`Warning::Note`]; the frames keep
//!   the file's order and key `k` is at `k / fps` whatever its number.
//! - Translation dofs (`tx ty tz`) of a bone move the bone's start along the axes of its
//!   frame `C` (so the bone's local translation becomes `parent offset + C · t`).
//! - The length dof `l` is read but **ignored** (its meaning, a new length or a change of
//!   length, differs between writers); a [`Warning::Note`] per such bone says so.
//!
//! # The asset rigport builds ([`to_asset`])
//! - Joints: `root`, then one joint per bone at the bone's **start** (its parent's end; the
//!   root's position for children of the root), each leaf bone followed by a joint
//!   `<bone>_end` at its end, so that every bone has a visible extent. Joints are ordered
//!   parents-first by [`parents_first_order`], which keeps the file order where possible.
//! - Rest pose: every rest rotation is the identity; a bone joint's rest translation is its
//!   parent bone's `direction * length` (zero under the root), an `_end` joint's its own
//!   bone's, the root's the `:root` `position`. Lengths stay in file units;
//!   [`Asset::meters_per_unit`] is `0.0254 / length` when `:units` states `length` (one
//!   file unit is `1 / length` inches).
//! - With identity rest rotations a joint's model-space rotation is FORMATS.md's
//!   `W = W_parent · C · M · C⁻¹`, so the local rotation of a bone's joint is `C · M · C⁻¹`
//!   (`C` from `axis` in its order, `M` from the frame's rotation dofs, first listed applied
//!   first), the root's likewise with `C` from `orientation` in the root `axis` order; the
//!   root's local translation is `position + (TX, TY, TZ)`.
//! - Clips: one per AMC, one key per frame at `k / fps` seconds, linear interpolation; a
//!   translation and a rotation track for the root, a rotation track for every bone with a
//!   rotation dof, a translation track for every bone with a translation dof. Every frame
//!   is kept, also for constant tracks. Quaternions are unit length and sign-continuous
//!   (each key is on the same side as the previous one).
//! - [`Asf`] keeps what the model has no field for yet (dof limits for IK, bone ids, axis
//!   angles).
//!
//! [`parents_first_order`]: rigport_model::parents_first_order

mod amc;
mod asf;
mod hierarchy;
mod lines;
mod skeleton;
#[cfg(test)]
mod tests;
mod tracks;
mod types;

pub use self::amc::parse_amc;
pub use self::asf::parse_asf;
pub use self::types::{
    Amc, AmcFrame, AngleUnit, Asf, Bone, Dof, HeldValue, Root, Skipped, Units, METERS_PER_INCH,
};

use std::path::{Path, PathBuf};

use rigport_model::{Asset, Warning};

use crate::problem::Rule;
use crate::{read_file, utf8, ImportError, Imported, Location};

use self::skeleton::build_skeleton;
use self::tracks::build_clip;

/// The frame rate CMU captured at, in frames per second; AMC files do not state a rate.
pub const DEFAULT_FPS: f32 = 120.0;

/// A bone `direction` whose length differs from 1 by more than this gets a
/// [`Warning::Note`] (it is used as written). CMU files write 6 significant digits, so
/// their directions are unit length within 1e-5.
pub const UNIT_DIRECTION_TOLERANCE: f64 = 1e-3;

/// Imports an ASF skeleton and any number of AMC motions of it (one clip each, named after
/// the file stem, in the order given) at `fps` frames per second.
///
/// The asset is named after the ASF's file stem. See the module docs for the mapping.
///
/// # Errors
/// `fps` is not finite and positive (at the ASF); a file cannot be read or is not UTF-8;
/// [`parse_asf`], [`parse_amc`] or [`to_asset`] fails.
pub fn import(asf: &Path, amcs: &[PathBuf], fps: f32) -> Result<Imported, ImportError> {
    check_fps(fps, asf)?;
    let bytes = read_file(asf)?;
    let skeleton = parse_asf(utf8(&bytes, asf)?, asf)?;
    let mut motions = Vec::with_capacity(amcs.len());
    for path in amcs {
        let bytes = read_file(path)?;
        let amc = parse_amc(utf8(&bytes, path)?, path, &skeleton)?;
        motions.push((stem(path), amc));
    }
    to_asset(&stem(asf), &skeleton, &motions, fps)
}

fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn check_fps(fps: f32, path: &Path) -> Result<(), ImportError> {
    if fps.is_finite() && fps > 0.0 {
        Ok(())
    } else {
        Err(ImportError::at(Location::file(path), Rule::FrameRate(fps)))
    }
}

/// Builds the asset: the skeleton of `asf` and one clip per motion, named by its string,
/// in the order given, keys at `k / fps` seconds. `name` names the asset.
///
/// See the module docs for the mapping. Warnings come in order: the ASF's skipped parts,
/// bone directions that are not unit length, `l` dofs ignored (only when there are
/// motions), then per motion its unknown header lines, its held values and its frame
/// number gaps.
///
/// # Errors
/// `fps` is not finite and positive (at the ASF); the hierarchy is broken (bones edited
/// into a cycle or naming a parent out of range, at the hierarchy line); a bone name clashes
/// with the `<bone>_end` joint of a leaf bone (at the clashing bone's `name` line); a rest
/// offset or an animated value does not fit `f32` (at the bone's line or the frame's
/// line); an [`Amc`] was parsed against another skeleton (its value count differs) or has
/// no frames; the key times `k / fps` do not fit `f32` as strictly increasing values (at
/// the AMC); the result fails [`Asset::validate`] (at the ASF).
pub fn to_asset(
    name: &str,
    asf: &Asf,
    motions: &[(String, Amc)],
    fps: f32,
) -> Result<Imported, ImportError> {
    check_fps(fps, &asf.path)?;
    let mut warnings = Vec::new();
    let at = |line: usize| format!("{}:{line}", asf.path.display());
    for skipped in &asf.skipped {
        warnings.push(Warning::Note {
            location: at(skipped.line),
            message: format!("skipped `{}`: rigport does not use it", skipped.keyword),
        });
    }
    for bone in &asf.bones {
        let norm = bone.direction.length();
        if (norm - 1.0).abs() > UNIT_DIRECTION_TOLERANCE {
            warnings.push(Warning::Note {
                location: at(bone.line),
                message: format!(
                    "bone {:?}: direction has length {norm}, not 1; used as written (the bone is {} units long)",
                    bone.name,
                    norm * bone.length
                ),
            });
        }
    }
    if !motions.is_empty() {
        for bone in asf.bones.iter().filter(|b| b.dofs.contains(&Dof::L)) {
            warnings.push(Warning::Note {
                location: at(bone.line),
                message: format!(
                    "bone {:?}: the length dof `l` is not supported; its values are ignored",
                    bone.name
                ),
            });
        }
    }
    let mut rig = build_skeleton(asf)?;
    let limits: Vec<_> = rotation_limits(asf, &rig).collect();
    rig.skeleton.set_limits(limits);
    let mut clips = Vec::with_capacity(motions.len());
    for (clip_name, amc) in motions {
        clips.push(build_clip(asf, &rig, clip_name, amc, fps, &mut warnings)?);
    }
    let asset = Asset {
        name: name.to_string(),
        skeleton: rig.skeleton,
        clips,
        meters_per_unit: asf.units.meters_per_unit(),
        ..Asset::default()
    };
    crate::check_asset(&asset, || Location::file(&asf.path))?;
    Ok(Imported { asset, warnings })
}

/// The bones' rotation limits for IK: per bone, Euler angles of `M` (the frame rotation of
/// `W = W_parent · C · M · C⁻¹`, read in the bone's `axis` frame `C`) in dof order, each
/// listed rotational dof within its `limits` pair (unbounded without `limits`; infinite or
/// wider bounds cut to ±180°), each rotation axis the bone does not list locked at 0 (ASF:
/// a bone turns only about its dofs). The root is not limited.
fn rotation_limits<'a>(
    asf: &'a Asf,
    rig: &'a skeleton::Rig,
) -> impl Iterator<Item = rigport_model::RotationLimit> + 'a {
    use rigport_model::conventions::EulerOrder;
    use rigport_model::glam::Vec3;
    let pi = std::f64::consts::PI;
    asf.bones.iter().enumerate().filter_map(move |(b, bone)| {
        let joint = *rig.node_joint.get(b + 1)?;
        let mut order = String::new();
        let mut min = [0.0f64; 3];
        let mut max = [0.0f64; 3];
        for (k, dof) in bone.dofs.iter().enumerate() {
            let axis = match dof {
                Dof::Rx => 0,
                Dof::Ry => 1,
                Dof::Rz => 2,
                _ => continue,
            };
            order.push(['x', 'y', 'z'][axis]);
            let (lo, hi) = bone.limits.get(k).copied().unwrap_or((-pi, pi));
            let to_rad = |v: f64| asf.units.angle.to_radians(v);
            min[axis] = if lo.is_finite() {
                to_rad(lo).max(-pi)
            } else {
                -pi
            };
            max[axis] = if hi.is_finite() {
                to_rad(hi).min(pi)
            } else {
                pi
            }
            .max(min[axis]);
        }
        for axis in ['x', 'y', 'z'] {
            if !order.contains(axis) {
                order.push(axis);
            }
        }
        let order = EulerOrder::parse(&order)?;
        let frame = skeleton::euler(
            bone.axis_order,
            rigport_model::glam::DVec3::from_array(
                bone.axis.to_array().map(|a| asf.units.angle.to_radians(a)),
            ),
        );
        Some(rigport_model::RotationLimit {
            joint,
            frame: frame.as_quat(),
            order,
            min_rad: Vec3::from(min.map(|v| v as f32)),
            max_rad: Vec3::from(max.map(|v| v as f32)),
        })
    })
}
