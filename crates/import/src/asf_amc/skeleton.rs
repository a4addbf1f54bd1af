//! The ASF as a model skeleton: a joint per bone start, an `_end` joint per leaf bone, rest
//! translations, parents-first order.

use std::collections::HashMap;

use glam::{DQuat, DVec3};
use rigport_model::conventions::EulerOrder;
use rigport_model::{parents_first_order, Joint, JointIndex, Skeleton, Transform};

use crate::problem::{Hierarchy, Limit};
use crate::{ImportError, Location, Problem};

use super::hierarchy::hierarchy_error;
use super::lines::line_error;
use super::types::{Asf, Bone};

/// The skeleton and where each ASF node (0 = root, `1 + b` = bone `b`) went.
pub(super) struct Rig {
    pub(super) skeleton: Skeleton,
    pub(super) node_joint: Vec<JointIndex>,
}

/// One joint before sorting.
struct SourceJoint {
    name: String,
    parent: Option<usize>,
    translation: DVec3,
    /// The node it belongs to (an `_end` joint: its bone's node).
    node: usize,
    /// Whether this is the `<bone>_end` joint of a leaf bone.
    is_end: bool,
}

fn bone_name(asf: &Asf, node: usize) -> &str {
    node.checked_sub(1)
        .and_then(|b| asf.bones.get(b))
        .map_or("root", |b| b.name.as_str())
}

fn node_of(bone: &Bone) -> usize {
    bone.parent.map_or(0, |p| p + 1)
}

pub(super) fn build_skeleton(asf: &Asf) -> Result<Rig, ImportError> {
    let path = &asf.path;
    let bone_count = asf.bones.len();
    let mut has_children = vec![false; bone_count];
    for bone in &asf.bones {
        if let Some(p) = bone.parent {
            let Some(flag) = has_children.get_mut(p) else {
                return Err(line_error(
                    path,
                    bone.hierarchy_line,
                    Hierarchy::ParentBone {
                        bone: bone.name.clone(),
                        parent: p,
                        count: bone_count,
                    },
                ));
            };
            *flag = true;
        }
    }
    // Source order: the root, then each bone followed by its `_end` joint when it is a leaf.
    let mut node_source = Vec::with_capacity(bone_count + 1);
    node_source.push(0);
    let mut next = 1;
    for &parent in &has_children {
        node_source.push(next);
        next += if parent { 1 } else { 2 };
    }
    let source_of = |node: usize| node_source.get(node).copied().unwrap_or(0);
    let mut source = Vec::with_capacity(next);
    source.push(SourceJoint {
        name: "root".into(),
        parent: None,
        translation: asf.root.position,
        node: 0,
        is_end: false,
    });
    for (b, bone) in asf.bones.iter().enumerate() {
        let translation = bone
            .parent
            .and_then(|p| asf.bones.get(p))
            .map_or(DVec3::ZERO, |p| p.direction * p.length);
        source.push(SourceJoint {
            name: bone.name.clone(),
            parent: Some(source_of(node_of(bone))),
            translation,
            node: b + 1,
            is_end: false,
        });
        if !has_children.get(b).copied().unwrap_or(true) {
            source.push(SourceJoint {
                name: format!("{}_end", bone.name),
                parent: Some(source_of(b + 1)),
                translation: bone.direction * bone.length,
                node: b + 1,
                is_end: true,
            });
        }
    }
    let line_of = |node: usize| {
        node.checked_sub(1)
            .and_then(|b| asf.bones.get(b))
            .map_or(asf.root.line, |b| b.line)
    };
    // Bone names are unique (parse_asf checks), but a bone may take the name of the `_end`
    // joint of a leaf bone.
    let mut names: HashMap<&str, &SourceJoint> = HashMap::with_capacity(source.len());
    for joint in &source {
        if let Some(other) = names.insert(&joint.name, joint) {
            let (end, bone) = if joint.is_end {
                (Some(joint), other)
            } else if other.is_end {
                (Some(other), joint)
            } else {
                (None, joint)
            };
            let problem = Hierarchy::SameName {
                bone: bone.name.clone(),
                leaf: end.map(|end| bone_name(asf, end.node).to_string()),
            };
            return Err(line_error(path, line_of(bone.node), problem));
        }
    }
    let parents: Vec<Option<usize>> = source.iter().map(|j| j.parent).collect();
    let order = parents_first_order(&parents).map_err(|problems| {
        hierarchy_error(asf, &problems, |s| {
            source
                .get(s)
                .filter(|j| !j.is_end)
                .and_then(|j| j.node.checked_sub(1))
        })
    })?;
    let mut new_index = vec![0_u32; source.len()];
    for (k, &s) in order.iter().enumerate() {
        let k =
            u32::try_from(k).map_err(|_| ImportError::at(Location::file(path), Limit::Joints))?;
        if let Some(slot) = new_index.get_mut(s) {
            *slot = k;
        }
    }
    let mut joints = Vec::with_capacity(order.len());
    for &s in &order {
        let Some(joint) = source.get(s) else {
            continue;
        };
        let translation = joint.translation.as_vec3();
        if !translation.is_finite() {
            return Err(line_error(
                path,
                line_of(joint.node),
                Limit::RestOffset {
                    joint: joint.name.clone(),
                    offset: joint.translation,
                },
            ));
        }
        joints.push(Joint {
            name: joint.name.clone(),
            parent: joint
                .parent
                .and_then(|p| new_index.get(p))
                .map(|&p| JointIndex(p)),
            rest_local: Transform::from_translation(translation),
        });
    }
    let skeleton = Skeleton::new(joints)
        .map_err(|problems| ImportError::new(Location::file(path), Problem::Skeleton(problems)))?;
    let node_joint = (0..=bone_count)
        .map(|node| JointIndex(new_index.get(source_of(node)).copied().unwrap_or(0)))
        .collect();
    Ok(Rig {
        skeleton,
        node_joint,
    })
}

/// A rotation from Euler angles in radians `[x, y, z]`, the first letter of `order` applied
/// first (`Xyz` = `Rz · Ry · Rx`, FORMATS.md), in `f64`.
pub(super) fn euler(order: EulerOrder, angles_rad: DVec3) -> DQuat {
    order.as_str().bytes().fold(DQuat::IDENTITY, |q, axis| {
        let r = match axis {
            b'x' => DQuat::from_rotation_x(angles_rad.x),
            b'y' => DQuat::from_rotation_y(angles_rad.y),
            _ => DQuat::from_rotation_z(angles_rad.z),
        };
        r * q
    })
}
