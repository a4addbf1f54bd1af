//! Compact clips: every clip's keys reduced within a model-space bound on joints and on
//! virtual points fixed to them (`rigport_anim::reduce`), with rotations as 16-bit
//! normalized integers in glTF, and the report of what it saved ([`CompactReport`]).
//!
//! The bound is a distance in the rig's length unit; by default 1 mm
//! ([`DEFAULT_TOLERANCE_M`]) converted with the asset's metres per unit (a rig that states
//! no unit is taken to be in metres, as glTF export takes it). Virtual points sit at 3 cm
//! ([`POINT_DISTANCE_M`], ACL's default shell distance) from every joint, farther for a
//! joint that skins vertices farther than that (the farthest such vertex, in the joint's
//! bind frame), so the bound covers the skinned mesh as ACL's metric does.

use rigport_anim::reduce::metric::point_error_bits;
use rigport_anim::reduce::{Codec, ReduceOptions, RotationBits, reduce_clip};
use rigport_model::quantize::PositionGrid;
use rigport_model::{Asset, Clip, Compression, Interpolation, JointIndex, Skeleton, TrackTarget};
use serde::Serialize;

use crate::PipelineError;

/// The default bound: 1 mm.
///
/// ```
/// use rigport_pipeline::compact::{DEFAULT_TOLERANCE_M, POINT_DISTANCE_M};
/// // ACL's threshold (0.01 cm) is a tenth of the default bound; its points sit 30 times farther.
/// assert_eq!(DEFAULT_TOLERANCE_M, 0.001);
/// assert!((POINT_DISTANCE_M / DEFAULT_TOLERANCE_M - 30.0).abs() < 1e-9);
/// ```
pub const DEFAULT_TOLERANCE_M: f64 = 0.001;
/// The distance of the virtual points from each joint: 3 cm, ACL's default.
///
/// ```
/// assert_eq!(rigport_pipeline::compact::POINT_DISTANCE_M, 0.03);
/// ```
pub const POINT_DISTANCE_M: f64 = 0.03;

/// What compacting one clip did. Errors are in the rig's length unit unless named `_cm`.
///
/// ```
/// let clip = rigport_pipeline::compact::ClipReport { keys_before: 10, keys_after: 4, ..Default::default() };
/// assert_eq!(serde_json::to_value(&clip)?["keys_after"], 4);
/// # Ok::<(), serde_json::Error>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ClipReport {
    /// The clip's name.
    pub clip: String,
    /// Keys over every track, before and after.
    pub keys_before: usize,
    /// See `keys_before`.
    pub keys_after: usize,
    /// The largest and mean model-space error of joints and their virtual points (at 3 cm,
    /// or a skinned mesh's reach), over every original key time.
    pub max_error: f32,
    /// See `max_error`.
    pub mean_error: f32,
    /// ACL's metric: the largest and mean error of virtual points at 3 cm from every joint,
    /// in centimetres (ACL's threshold is 0.01 cm).
    pub acl_max_error_cm: f64,
    /// See `acl_max_error_cm`.
    pub acl_mean_error_cm: f64,
}

/// What compacting an asset's clips did ([`crate::write::write_output_report`]).
///
/// ```
/// use rigport_pipeline::write::{write_output_report, Output};
/// use rigport_pipeline::{progress::Silent, MemoryBudget};
///
/// let dir = tempfile::tempdir()?;
/// let imported = rigport_import::bvh::import("../../fixtures/bvh/end_sites.bvh".as_ref())?;
/// let output = Output { reduce: true, ..Output::new(dir.path().join("walk.glb")) };
/// let (_, report) = write_output_report(imported.asset, imported.warnings, &output,
///     &MemoryBudget::UNLIMITED, &Silent)?;
/// let report = report.expect("reduced");
/// // The default bound: 1 mm in a rig that states no unit (metres).
/// assert_eq!(report.tolerance, 0.001);
/// // The reduced clips are written only when they make the file no bigger.
/// assert_eq!(report.reduced_written, report.bytes_after <= report.bytes_before);
/// assert!(report.clips.iter().all(|c| c.max_error <= 0.001 && c.keys_after <= c.keys_before));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct CompactReport {
    /// The bound, in the rig's length unit.
    pub tolerance: f32,
    /// Metres per rig unit (1 when the rig states none).
    pub meters_per_unit: f64,
    /// The most quantizing the skinned meshes' positions moves a vertex, in rig units
    /// (`KHR_mesh_quantization`), paid out of the bound before the clips are reduced: the
    /// clips' errors stay within `tolerance - mesh_grid_error`. 0 when positions are floats.
    pub mesh_grid_error: f32,
    /// Whether key values are written as the compression stores them (16-bit rotations; with
    /// meshopt, its filters), as the error was measured; `false`: exact floats.
    pub rotations_i16: bool,
    /// The compression the file is written with.
    pub compression: String,
    /// The output's size without and with the reduction, in bytes.
    pub bytes_before: u64,
    /// See `bytes_before`.
    pub bytes_after: u64,
    /// Whether the reduced clips were written (`false`: they made the file no smaller, and
    /// the unreduced clips were written instead).
    pub reduced_written: bool,
    /// Per clip, in the asset's order.
    pub clips: Vec<ClipReport>,
}

impl CompactReport {
    /// One line per clip, then the sizes.
    ///
    /// ```
    /// let report = rigport_pipeline::compact::CompactReport { bytes_before: 9, bytes_after: 4,
    ///     reduced_written: true, ..Default::default() };
    /// assert_eq!(report.lines(), ["compact: 9 -> 4 bytes (reduced clips written)"]);
    /// ```
    pub fn lines(&self) -> Vec<String> {
        let mut lines: Vec<String> = self
            .clips
            .iter()
            .map(|c| {
                format!(
                    "compact: clip {:?}: {} -> {} keys; error max {:.3e} mean {:.3e} (bound {:.3e}, rig units); ACL metric (3 cm points) max {:.4} mean {:.4} cm",
                    c.clip, c.keys_before, c.keys_after, c.max_error, c.mean_error,
                    self.tolerance, c.acl_max_error_cm, c.acl_mean_error_cm
                )
            })
            .collect();
        lines.push(format!(
            "compact: {} -> {} bytes ({}{})",
            self.bytes_before,
            self.bytes_after,
            if self.reduced_written {
                "reduced clips written"
            } else {
                "unreduced clips written: the reduction made the file no smaller"
            },
            if self.rotations_i16 {
                ", rotations as 16-bit integers"
            } else {
                ""
            }
        ));
        lines
    }
}

/// The bound in rig units: `tolerance` when given, else 1 mm in the asset's unit.
pub(crate) fn tolerance_in_rig_units(asset: &Asset, tolerance: Option<f32>) -> f32 {
    tolerance.unwrap_or_else(|| (DEFAULT_TOLERANCE_M / meters_per_unit(asset)) as f32)
}

/// Metres per rig unit, 1 when the asset states none (or a value that is not positive).
fn meters_per_unit(asset: &Asset) -> f64 {
    asset
        .meters_per_unit
        .filter(|m| m.is_finite() && *m > 0.0)
        .unwrap_or(1.0)
}

/// Per joint: 3 cm in rig units, or the farthest vertex the joint skins (weight above
/// zero), measured in its bind frame, when that is farther.
fn point_distances(asset: &Asset) -> Vec<f32> {
    let base = (POINT_DISTANCE_M / meters_per_unit(asset)) as f32;
    let mut out = vec![base; asset.skeleton.len()];
    for skin in &asset.skins {
        let Some(mesh) = asset.meshes.get(skin.mesh.get()) else {
            continue;
        };
        for (row, &p) in skin.influences.rows().zip(&mesh.positions) {
            for influence in row.iter().filter(|i| i.weight > 0.0) {
                let palette = influence.joint as usize;
                let (Some(joint), Some(inv_bind)) =
                    (skin.joints.get(palette), skin.inv_bind.get(palette))
                else {
                    continue;
                };
                let reach = inv_bind.transform_point3(p).length();
                if let Some(d) = out.get_mut(joint.get()) {
                    if reach.is_finite() {
                        *d = d.max(reach);
                    }
                }
            }
        }
    }
    out
}

/// The most a skinned vertex moves, in rig units, when the glTF writer quantizes the
/// skinned meshes' positions (`KHR_mesh_quantization`: 16-bit integers on each mesh's
/// [`PositionGrid`]), or `None` when that is not bounded by the grid alone: a skinning
/// matrix (a joint's model matrix times its inverse bind matrix) with a scale, from a rest
/// scale, a scale track or an inverse bind matrix, would scale the rounding too; `None`
/// too without a skinned mesh. The writer quantizes skinned meshes without morph targets;
/// the bound covers every skinned mesh. Each mesh's grid is the coarsest whose rounding is
/// at most `position_error` ([`PositionGrid::within`], what the writer's
/// `GltfOptions::position_error` asks for; 0: the finest grid).
///
/// ```
/// use rigport_pipeline::compact::mesh_grid_error;
/// let mut asset = rigport_import::bvh::import("../../fixtures/bvh/end_sites.bvh".as_ref())?.asset;
/// assert_eq!(mesh_grid_error(&asset, 0.0), None, "no skinned mesh");
/// assert!(rigport_import::bone_mesh::add_bone_mesh(&mut asset));
/// // Half a step (the mesh's longest side / 65,534) on each axis.
/// let error = mesh_grid_error(&asset, 0.0).expect("rigid");
/// assert!(error > 0.0 && error < 1e-4 * asset.skeleton.len() as f32, "{error}");
/// // A coarser grid, as `--compress meshopt` writes it, within what it is allowed.
/// let coarse = mesh_grid_error(&asset, 0.01).expect("rigid");
/// assert!(coarse > 10.0 * error && coarse <= 0.01 * (1.0 + 4e-4), "{coarse}");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn mesh_grid_error(asset: &Asset, position_error: f32) -> Option<f32> {
    const UNIT: f32 = 1e-4;
    let unit = |v: rigport_model::glam::Vec3| {
        (v - rigport_model::glam::Vec3::ONE).abs().max_element() <= UNIT
    };
    let rigid_rest = asset
        .skeleton
        .joints()
        .iter()
        .all(|j| unit(j.rest_local.scale));
    let scale_tracks = asset.clips.iter().flat_map(|c| &c.tracks).any(|t| {
        matches!(t.target, TrackTarget::Scale(_))
            && t.values
                .chunks_exact(3)
                .any(|v| !unit(rigport_model::glam::Vec3::from_slice(v)))
    });
    let rigid_bind = asset.skins.iter().flat_map(|s| &s.inv_bind).all(|m| {
        [m.x_axis, m.y_axis, m.z_axis]
            .iter()
            .all(|c| (c.truncate().length() - 1.0).abs() <= UNIT)
    });
    if !rigid_rest || scale_tracks || !rigid_bind {
        return None;
    }
    let skinned = asset
        .skins
        .iter()
        .filter_map(|s| asset.meshes.get(s.mesh.get()));
    let grids = skinned.filter_map(|m| PositionGrid::within(&m.positions, position_error));
    // The rigid skinning matrices may still scale by UNIT; pay for it.
    // The writer's grid is made in metres, after the frame's rotation: its error is at
    // most the allowance when this one's is.
    grids
        .map(|g| g.max_error().max(position_error) * (1.0 + 4.0 * UNIT))
        .reduce(f32::max)
}

/// The mesh grid error a reduction within `tolerance` pays for ([`mesh_grid_error`] at
/// `position_error`): the writer quantizes the skinned meshes only when that rounding
/// takes at most a tenth of the bound, and the clips get the rest of it; `None` otherwise.
pub(crate) fn paid_grid_error(asset: &Asset, position_error: f32, tolerance: f32) -> Option<f32> {
    mesh_grid_error(asset, position_error).filter(|&e| e <= 0.1 * tolerance)
}

/// What `GltfOptions::position_error` is for a bound of `tolerance` (rig units): 0 (the
/// finest grid) for plain glTF, whose 16-bit positions take their bytes whatever their
/// values; with meshopt, a coarser grid whose rounding takes [`MESHOPT_GRID_SHARE`] of
/// the bound (less the rigid skinning matrices' scale that [`mesh_grid_error`] pays for).
pub(crate) fn position_error(tolerance: f32, compression: Compression) -> f32 {
    match compression {
        Compression::None => 0.0,
        Compression::Meshopt => MESHOPT_GRID_SHARE * tolerance / (1.0 + 5e-4),
    }
}

/// The share of the bound a meshopt file's position grid may take: fewer distinct integers
/// are fewer bytes through meshoptimizer's vertex codec (gltfpack writes 14 bits along
/// the longest side; this is about 14 bits on a 1.8 m figure at the 1 mm default).
pub(crate) const MESHOPT_GRID_SHARE: f32 = 0.1;

/// With meshopt, what a kept key's own time weighs against a 16-bit rotation's 8 bytes
/// (`Codec::key_time_bytes`): the vertex codec packs a full-rate track's small steps into
/// a few bits a key, while removed keys leave jumps, and their times (float seconds) barely
/// pack. On the Bandai kick: 37,176 bytes at 4, 36,568 at 32 and more (gltfpack -cc
/// 39,372); on 57 Bandai clips, 0.9654 of gltfpack -cc's total size at 32, 0.9643 at 64,
/// 0.9638 at 128 (the worst file the same).
const MESHOPT_KEY_TIME_BYTES: usize = 64;

/// The `QUATERNION` filter's bits per component the reducer may pick for a rotation track
/// (the filter takes 4 to 16; 16 is the default, and below 6 a key's rounding passes 0.03
/// rad).
const MESHOPT_ROTATION_BITS: [u8; 10] = [6, 7, 8, 9, 10, 11, 12, 13, 14, 15];

/// How a glTF writer with `compression` stores key values: 16-bit rotations (and 8-bit
/// ones for the tracks whose tolerance allows them, with `byte_rotations`), or
/// meshoptimizer's quaternion and exponential filters (with 16 mantissa bits when
/// `vector_bits` is 16, else 20).
pub(crate) fn codec(compression: Compression, vector_bits: u8, byte_rotations: bool) -> Codec {
    match compression {
        Compression::None if byte_rotations => Codec::CORE,
        Compression::None => Codec::I16,
        Compression::Meshopt => Codec {
            rotation: rigport_export::meshopt_rotation_as_written,
            vector: Some(match vector_bits {
                16 => rigport_export::meshopt_vector_as_written_16,
                _ => rigport_export::meshopt_vector_as_written,
            }),
            rotation_bits: Some(RotationBits {
                written: rigport_export::meshopt_rotations_as_written_bits,
                choices: &MESHOPT_ROTATION_BITS,
                // 16-bit components, whatever the bits: the filter keeps their width.
                key_bytes: |_| 8,
            }),
            key_time_bytes: MESHOPT_KEY_TIME_BYTES,
        },
    }
}

/// The `EXPONENTIAL` filter's mantissa bits for `asset`'s translation and scale keys under
/// a bound of `tolerance`: 16 (as gltfpack writes them) when that rounds every key by at
/// most a tenth of the bound (a relative 2^-15 of the largest value), else 20.
///
/// ```
/// use rigport_pipeline::compact::vector_bits;
/// // The root's translation keys reach 20 units: 16 bits round them by up to 6.1e-4.
/// let asset = rigport_import::bvh::import("../../fixtures/bvh/mixed_orders.bvh".as_ref())?.asset;
/// assert_eq!(vector_bits(&asset, 0.01), 16);
/// assert_eq!(vector_bits(&asset, 0.001), 20);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn vector_bits(asset: &Asset, tolerance: f32) -> u8 {
    let largest = asset
        .clips
        .iter()
        .flat_map(|c| &c.tracks)
        .filter(|t| {
            matches!(
                t.target,
                TrackTarget::Translation(_) | TrackTarget::Scale(_)
            )
        })
        .flat_map(|t| &t.values)
        .fold(0.0_f32, |m, v| m.max(v.abs()));
    if largest / (1 << 15) as f32 <= 0.1 * tolerance {
        16
    } else {
        20
    }
}

/// What [`compact_clips`] made.
pub(crate) struct Compacted {
    /// The reduced clips, in the asset's order.
    pub clips: Vec<Clip>,
    /// What reducing each did.
    pub reports: Vec<ClipReport>,
    /// Whether key values are measured (and so must be written) through the codec.
    pub coded: bool,
    /// Per clip, per track: the rotation bits the writer must use (`ReduceStats`).
    pub rotation_bits: Vec<Vec<u8>>,
}

/// The asset's clips reduced within `tolerance` (rig units), with their reports and
/// whether key values are measured (and so must be written) through `codec`: kept only
/// when every clip's rounding fits the bound. `cubic` lets tracks become CUBICSPLINE
/// where that is smaller (glTF outputs; USD time samples are linear).
///
/// # Errors
/// A clip that does not fit the skeleton, or a tolerance that is negative or not finite.
pub(crate) fn compact_clips(
    asset: &Asset,
    tolerance: f32,
    codec: Option<Codec>,
    cubic: bool,
) -> Result<Compacted, PipelineError> {
    let points = point_distances(asset);
    let acl_points = vec![(POINT_DISTANCE_M / meters_per_unit(asset)) as f32; points.len()];
    let cm_per_unit = meters_per_unit(asset) * 100.0;
    let mut codec = codec;
    'again: loop {
        let options = ReduceOptions {
            tolerance,
            point_distance: points.clone(),
            codec,
            uniform_rate: true,
            cubic,
        };
        let mut clips = Vec::with_capacity(asset.clips.len());
        let mut reports = Vec::with_capacity(asset.clips.len());
        let mut rotation_bits = Vec::with_capacity(asset.clips.len());
        for clip in &asset.clips {
            let failed = |e| PipelineError::step(format!("cannot reduce clip {:?}", clip.name), e);
            let (reduced, stats) = reduce_clip(clip, &asset.skeleton, &options).map_err(failed)?;
            if codec.is_some() && !stats.coded {
                // One writer setting for the file: exact values for every clip.
                codec = None;
                continue 'again;
            }
            let acl = point_error_bits(
                clip,
                &reduced,
                &asset.skeleton,
                &acl_points,
                codec.as_ref(),
                &stats.rotation_bits,
            )
            .map_err(failed)?;
            reports.push(ClipReport {
                clip: clip.name.clone(),
                keys_before: stats.keys_before,
                keys_after: stats.keys_after,
                max_error: stats.max_error,
                mean_error: stats.mean_error,
                acl_max_error_cm: f64::from(acl.max) * cm_per_unit,
                acl_mean_error_cm: f64::from(acl.mean) * cm_per_unit,
            });
            clips.push(reduced);
            rotation_bits.push(stats.rotation_bits);
        }
        return Ok(Compacted {
            clips,
            reports,
            coded: codec.is_some(),
            rotation_bits,
        });
    }
}

/// Moves every joint property that every clip holds at one value (LINEAR or STEP keys all
/// bit for bit equal, in every clip) into the rest pose, so that the glTF writer drops its
/// tracks (a property without a channel keeps its node's value, glTF 2.0 §3.11). Returns
/// the skeleton as it was when something moved, `None` when nothing did. A rest rotation is
/// the clips' value normalized.
pub(crate) fn constants_into_rest(asset: &mut Asset) -> Option<Skeleton> {
    if asset.clips.is_empty() {
        return None;
    }
    let mut joints = asset.skeleton.joints().to_vec();
    let mut moved = false;
    for (j, joint) in joints.iter_mut().enumerate() {
        let at = JointIndex(j as u32);
        for target in [
            TrackTarget::Translation(at),
            TrackTarget::Rotation(at),
            TrackTarget::Scale(at),
        ] {
            let Some(value) = held_value(&asset.clips, target) else {
                continue;
            };
            let rest = &mut joint.rest_local;
            match (target, value.as_slice()) {
                (TrackTarget::Translation(_), &[x, y, z]) => {
                    rest.translation = rigport_model::glam::Vec3::new(x, y, z);
                }
                (TrackTarget::Scale(_), &[x, y, z]) => {
                    rest.scale = rigport_model::glam::Vec3::new(x, y, z);
                }
                (TrackTarget::Rotation(_), &[x, y, z, w]) => {
                    let q = rigport_model::glam::Quat::from_xyzw(x, y, z, w);
                    if q.length() == 0.0 || !q.is_finite() {
                        continue;
                    }
                    rest.rotation = q.normalize();
                }
                _ => continue,
            }
            moved = true;
        }
    }
    if !moved {
        return None;
    }
    replace_joints(asset, joints)
}

/// The fraction of the bound under which a rest translation component is noise
/// ([`zero_rest_noise`]): 1e-4 (0.1 µm of a 1 mm bound).
pub(crate) const REST_NOISE: f32 = 1e-4;

/// The most [`zero_rest_noise`] with `below` moves any point: each joint on the deepest
/// chain moved by at most `√3 below` (unit scales; a scaled parent is left alone there).
pub(crate) fn rest_noise_error(skeleton: &Skeleton, below: f32) -> f32 {
    let parents: Vec<Option<JointIndex>> = skeleton.parents().collect();
    let mut depth = vec![0usize; parents.len()];
    for (j, parent) in parents.iter().enumerate() {
        // Parents first: a parent's depth is known.
        depth[j] = parent.map_or(1, |p| depth.get(p.0 as usize).copied().unwrap_or(0) + 1);
    }
    let deepest = depth.iter().copied().max().unwrap_or(0);
    deepest as f32 * 3f32.sqrt() * below
}

/// Sets to 0 the rest translation components under `below` in magnitude (capture noise
/// such as 5.1e-8, which the glTF JSON prints in 13 characters) of joints whose parent (if
/// any) has a unit rest scale and whose translation every clip holds at the rest value (no
/// track, or one the glTF writer drops: every key equal to the rest, as
/// [`constants_into_rest`] leaves them), in the rest and in those tracks alike. Returns the
/// skeleton as it was when something changed. The caller pays [`rest_noise_error`] out of
/// the bound.
pub(crate) fn zero_rest_noise(asset: &mut Asset, below: f32) -> Option<Skeleton> {
    let parents: Vec<Option<JointIndex>> = asset.skeleton.parents().collect();
    let mut joints = asset.skeleton.joints().to_vec();
    let mut changed = false;
    for (j, joint) in joints.iter_mut().enumerate() {
        let at = TrackTarget::Translation(JointIndex(j as u32));
        let rest = joint.rest_local.translation.to_array();
        let unit_parent = parents[j].is_none_or(|p| {
            asset.skeleton.joint(p).rest_local.scale == rigport_model::glam::Vec3::ONE
        });
        let held = asset
            .clips
            .iter()
            .flat_map(|c| &c.tracks)
            .filter(|t| t.target == at)
            .all(|t| {
                t.interpolation != Interpolation::CubicSpline
                    && t.values.chunks_exact(3).all(|k| k == rest)
            });
        let zeroed = rest.map(|c| if c.abs() < below { 0.0 } else { c });
        if !unit_parent || !held || zeroed == rest {
            continue;
        }
        joint.rest_local.translation = rigport_model::glam::Vec3::from_array(zeroed);
        for track in asset.clips.iter_mut().flat_map(|c| &mut c.tracks) {
            if track.target == at {
                for k in track.values.chunks_exact_mut(3) {
                    k.copy_from_slice(&zeroed);
                }
            }
        }
        changed = true;
    }
    if !changed {
        return None;
    }
    replace_joints(asset, joints)
}

/// Gives `asset` a skeleton of `joints` (the same hierarchy, other rest transforms), its
/// joint limits kept; returns the skeleton it had.
fn replace_joints(asset: &mut Asset, joints: Vec<rigport_model::Joint>) -> Option<Skeleton> {
    let mut skeleton = Skeleton::new(joints).ok()?;
    skeleton.set_limits(asset.skeleton.limits().iter().cloned());
    Some(std::mem::replace(&mut asset.skeleton, skeleton))
}

/// The one value every clip's (first) track for `target` holds at every key, if any.
fn held_value(clips: &[Clip], target: TrackTarget) -> Option<Vec<f32>> {
    let mut value: Option<&[f32]> = None;
    for clip in clips {
        let track = clip.tracks.iter().find(|t| t.target == target)?;
        let c = track.components();
        if track.interpolation == Interpolation::CubicSpline || c == 0 {
            return None;
        }
        let first = track.values.get(..c)?;
        if !track.values.chunks_exact(c).all(|k| k == first) || value.is_some_and(|v| v != first) {
            return None;
        }
        value = Some(first);
    }
    value.map(<[f32]>::to_vec)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rigport_model::Track;

    fn walk() -> Asset {
        let path = std::path::Path::new("../../fixtures/bvh/end_sites.bvh");
        match rigport_import::bvh::import(path) {
            Ok(imported) => imported.asset,
            Err(e) => panic!("fixture: {e}"),
        }
    }

    /// A rotation every clip holds at one value goes into the rest pose; one that a clip
    /// changes, or that one clip does not animate, stays.
    #[test]
    fn properties_every_clip_holds_move_into_the_rest_pose() {
        let mut asset = walk();
        let (ti, joint) = asset.clips[0]
            .tracks
            .iter()
            .enumerate()
            .find_map(|(ti, t)| match t.target {
                TrackTarget::Rotation(j) => Some((ti, j)),
                _ => None,
            })
            .expect("a rotation track");
        let held = [0.0f32, 0.6, 0.0, 0.8];
        let keys = asset.clips[0].tracks[ti].times.len();
        asset.clips[0].tracks[ti].values = held.repeat(keys);
        asset.clips.push(asset.clips[0].clone());
        let before = asset.skeleton.clone();
        let mut moved = asset.clone();
        assert_eq!(constants_into_rest(&mut moved), Some(before.clone()));
        let rest = moved.skeleton.joint(joint).rest_local.rotation;
        assert!(
            rest.abs_diff_eq(rigport_model::glam::Quat::from_array(held), 1e-7),
            "{rest}"
        );
        // Everything else is as it was.
        for (a, b) in moved.skeleton.joints().iter().zip(before.joints()) {
            if a.name != before.joint(joint).name {
                assert_eq!(a, b);
            }
        }
        // One clip holds another value at one key: nothing moves.
        let mut changed = asset.clone();
        changed.clips[1].tracks[ti].values[0] = 0.1;
        assert_eq!(constants_into_rest(&mut changed), None);
        assert_eq!(changed.skeleton, before);
        // One clip does not animate it: nothing moves.
        let mut missing = asset.clone();
        missing.clips[1].tracks.remove(ti);
        assert_eq!(constants_into_rest(&mut missing), None);
    }

    /// Rest translation noise under the threshold becomes 0 in the rest and in the tracks
    /// that hold it; a translation a clip changes, and components at or above the
    /// threshold, stay; the bound is the deepest chain's count of joints times √3 times
    /// the threshold.
    #[test]
    fn rest_translation_noise_becomes_zero_where_every_clip_holds_it() {
        let mut asset = walk();
        let below = 1e-4;
        let parents: Vec<Option<JointIndex>> = asset.skeleton.parents().collect();
        // A child of the root (unit scales in the fixture) with noise on x and a value on z.
        let j = (0..asset.skeleton.len())
            .find(|&j| parents[j].is_some())
            .expect("a child joint");
        let at = TrackTarget::Translation(JointIndex(j as u32));
        let mut joints = asset.skeleton.joints().to_vec();
        let noisy = [5.1e-8f32, 0.25, 3e-4];
        joints[j].rest_local.translation = rigport_model::glam::Vec3::from_array(noisy);
        asset.skeleton = Skeleton::new(joints).expect("same hierarchy");
        asset.clips[0].tracks.retain(|t| t.target != at);
        let held = Track {
            target: at,
            interpolation: Interpolation::Linear,
            times: vec![0.0, 1.0],
            values: noisy.repeat(2),
        };
        asset.clips[0].tracks.push(held.clone());
        let before = asset.skeleton.clone();
        let mut zeroed = asset.clone();
        assert_eq!(zero_rest_noise(&mut zeroed, below), Some(before));
        let expected = [0.0, 0.25, 3e-4];
        let rest = zeroed
            .skeleton
            .joint(JointIndex(j as u32))
            .rest_local
            .translation;
        assert_eq!(rest.to_array(), expected);
        let track = zeroed.clips[0]
            .tracks
            .iter()
            .find(|t| t.target == at)
            .expect("kept");
        assert_eq!(track.values, expected.repeat(2));
        // Once clean, nothing more changes.
        assert_eq!(zero_rest_noise(&mut zeroed, below), None);
        // A clip that moves the joint keeps its noise.
        let mut moving = asset.clone();
        let track = moving.clips[0]
            .tracks
            .iter_mut()
            .find(|t| t.target == at)
            .expect("kept");
        track.values[3] = 0.5;
        let kept = moving
            .skeleton
            .joint(JointIndex(j as u32))
            .rest_local
            .translation;
        zero_rest_noise(&mut moving, below);
        assert_eq!(
            moving
                .skeleton
                .joint(JointIndex(j as u32))
                .rest_local
                .translation,
            kept
        );
        // The bound: the deepest chain, √3 per joint.
        let mut depth = vec![0usize; parents.len()];
        for (k, p) in parents.iter().enumerate() {
            depth[k] = p.map_or(1, |p| depth[p.0 as usize] + 1);
        }
        let deepest = *depth.iter().max().expect("joints") as f32;
        let bound = rest_noise_error(&asset.skeleton, below);
        assert!(
            (bound - deepest * 3f32.sqrt() * below).abs() < 1e-9,
            "{bound}"
        );
    }
}
