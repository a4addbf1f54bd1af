//! One AMC motion as a clip: per-node rotation and translation tracks, one key per frame.

use std::ops::Range;

use glam::{DQuat, DVec3, Vec3};
use rigport_model::{Clip, Interpolation, JointIndex, Track, TrackTarget, Warning};

use crate::problem::{Limit, Mismatch};
use crate::{ImportError, Location, Problem};

use super::lines::line_error;
use super::skeleton::{euler, Rig};
use super::types::{Amc, AmcFrame, Asf, Dof};

/// How one node's frame values become the values of its tracks.
struct NodeTracks<'a> {
    joint: JointIndex,
    range: Range<usize>,
    dofs: &'a [Dof],
    /// The node's frame `C` and its inverse: a local rotation is `C · M · C⁻¹`.
    frame: DQuat,
    frame_inv: DQuat,
    /// The rest translation the dof translation is added to.
    rest: DVec3,
    /// Bones translate along the axes of `C`; the root in its parent (world) frame.
    translate_in_frame: bool,
    rotations: Option<Vec<f32>>,
    translations: Option<Vec<f32>>,
    /// The last rotation key, for sign continuity.
    previous: DQuat,
}

pub(super) fn build_clip(
    asf: &Asf,
    rig: &Rig,
    name: &str,
    amc: &Amc,
    fps: f32,
    warnings: &mut Vec<Warning>,
) -> Result<Clip, ImportError> {
    let path = &amc.path;
    let at = |line: usize| format!("{}:{line}", path.display());
    let channels = asf.channel_count();
    let frame_count = amc.frames.len();
    if amc.channels != channels || frame_count.checked_mul(channels) != Some(amc.values.len()) {
        return Err(ImportError::at(
            Location::file(path),
            Mismatch::AmcSkeleton {
                per_frame: amc.channels,
                values: amc.values.len(),
                frames: frame_count,
                skeleton: asf.path.clone(),
                dofs: channels,
            },
        ));
    }
    if frame_count == 0 {
        return Err(ImportError::new(
            Location::file(path),
            Problem::Truncated("the motion has no frames".into()),
        ));
    }
    let mut times = Vec::with_capacity(frame_count);
    for k in 0..frame_count {
        let t = (k as f64 / f64::from(fps)) as f32;
        if !t.is_finite() || times.last().is_some_and(|&previous| t <= previous) {
            return Err(ImportError::at(
                Location::file(path),
                Limit::KeyTime { frame: k, fps },
            ));
        }
        times.push(t);
    }

    let unit = amc.angle.unwrap_or(asf.units.angle);
    let asf_radians =
        |v: DVec3| DVec3::from_array(v.to_array().map(|a| asf.units.angle.to_radians(a)));
    let ranges = asf.channel_ranges();
    let node_range = |node: usize| ranges.get(node).cloned().unwrap_or(0..0);
    let node_joint = |node: usize| rig.node_joint.get(node).copied().unwrap_or(JointIndex(0));
    let keys = |wanted: bool, width: usize| wanted.then(|| Vec::with_capacity(width * frame_count));
    let mut nodes = Vec::with_capacity(ranges.len());
    let c_root = euler(asf.root.axis, asf_radians(asf.root.orientation));
    nodes.push(NodeTracks {
        joint: node_joint(0),
        range: node_range(0),
        dofs: &asf.root.order,
        frame: c_root,
        frame_inv: c_root.inverse(),
        rest: asf.root.position,
        translate_in_frame: false,
        rotations: keys(true, 4),
        translations: keys(true, 3),
        previous: DQuat::IDENTITY,
    });
    for (b, bone) in asf.bones.iter().enumerate() {
        let rotates = bone.dofs.iter().any(|d| d.is_rotation());
        let translates = bone.dofs.iter().any(|d| d.is_translation());
        if !rotates && !translates {
            continue;
        }
        let c = euler(bone.axis_order, asf_radians(bone.axis));
        nodes.push(NodeTracks {
            joint: node_joint(b + 1),
            range: node_range(b + 1),
            dofs: &bone.dofs,
            frame: c,
            frame_inv: c.inverse(),
            rest: bone
                .parent
                .and_then(|p| asf.bones.get(p))
                .map_or(DVec3::ZERO, |p| p.direction * p.length),
            translate_in_frame: true,
            rotations: keys(rotates, 4),
            translations: keys(translates, 3),
            previous: DQuat::IDENTITY,
        });
    }

    for (k, frame) in amc.frames.iter().enumerate() {
        let values = amc.frame_values(k).unwrap_or_default();
        for node in &mut nodes {
            let node_values = values.get(node.range.clone()).unwrap_or_default();
            let mut m = DQuat::IDENTITY;
            let mut t = DVec3::ZERO;
            for (&dof, &value) in node.dofs.iter().zip(node_values) {
                // The first listed dof is applied first (FORMATS.md): later ones multiply
                // on the left.
                match dof {
                    Dof::Rx => m = DQuat::from_rotation_x(unit.to_radians(value)) * m,
                    Dof::Ry => m = DQuat::from_rotation_y(unit.to_radians(value)) * m,
                    Dof::Rz => m = DQuat::from_rotation_z(unit.to_radians(value)) * m,
                    Dof::Tx => t.x += value,
                    Dof::Ty => t.y += value,
                    Dof::Tz => t.z += value,
                    Dof::L => {}
                }
            }
            if let Some(out) = node.rotations.as_mut() {
                let mut q = (node.frame * m * node.frame_inv).normalize();
                if q.dot(node.previous) < 0.0 {
                    q = -q;
                }
                node.previous = q;
                out.extend(q.as_quat().to_array());
            }
            if let Some(out) = node.translations.as_mut() {
                let offset = if node.translate_in_frame {
                    node.frame * t
                } else {
                    t
                };
                let p: Vec3 = (node.rest + offset).as_vec3();
                if !p.is_finite() {
                    let joint = rig
                        .skeleton
                        .joints()
                        .get(node.joint.get())
                        .map_or("?", |j| j.name.as_str());
                    return Err(line_error(
                        path,
                        frame.line,
                        Limit::Translation {
                            frame: frame.number,
                            joint: joint.to_string(),
                        },
                    ));
                }
                out.extend(p.to_array());
            }
        }
    }

    nodes.sort_by_key(|n| n.joint);
    let mut tracks = Vec::with_capacity(2 * nodes.len());
    for node in nodes {
        if let Some(values) = node.translations {
            tracks.push(Track {
                target: TrackTarget::Translation(node.joint),
                interpolation: Interpolation::Linear,
                times: times.clone(),
                values,
            });
        }
        if let Some(values) = node.rotations {
            tracks.push(Track {
                target: TrackTarget::Rotation(node.joint),
                interpolation: Interpolation::Linear,
                times: times.clone(),
                values,
            });
        }
    }

    for skipped in &amc.header {
        warnings.push(Warning::Note {
            location: at(skipped.line),
            message: format!(
                "skipped header line `{}`: rigport does not use it",
                skipped.keyword
            ),
        });
    }
    if let Some(first) = amc.held.first() {
        let mut frames: Vec<usize> = amc.held.iter().map(|h| h.frame).collect();
        frames.dedup();
        let frame = amc.frames.get(first.frame);
        warnings.push(Warning::Repaired {
            location: at(frame.map_or(0, |f| f.line)),
            message: format!(
                "{} bone entries were missing from {} frames (the first: {:?} in frame {}); each held its value from the frame before (the rest pose in the first frame)",
                amc.held.len(),
                frames.len(),
                first.bone.and_then(|b| asf.bones.get(b)).map_or("root", |b| b.name.as_str()),
                frame.map_or(0, |f| f.number),
            ),
        });
    }
    let gaps: Vec<(&AmcFrame, &AmcFrame)> = amc
        .frames
        .windows(2)
        .filter_map(|w| match w {
            [a, b] if a.number.checked_add(1) != Some(b.number) => Some((a, b)),
            _ => None,
        })
        .collect();
    if let Some((before, after)) = gaps.first() {
        warnings.push(Warning::Note {
            location: at(after.line),
            message: format!(
                "frame numbers are not consecutive in {} place{} (the first: frame {} after frame {}); kept the file's order, key k at k / {fps} s",
                gaps.len(),
                if gaps.len() == 1 { "" } else { "s" },
                after.number,
                before.number
            ),
        });
    }
    Ok(Clip {
        name: name.to_string(),
        tracks,
    })
}
