//! The skeleton: which FBX nodes become joints, parents first, with their rest transforms.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use rigport_model::glam::{DMat4, DVec4, Quat, Vec3};
use rigport_model::{Joint, JointIndex, Skeleton, Transform};

use crate::names::unique;
use crate::{ImportError, Location, Problem};

/// The skeleton and where each FBX node went.
pub(super) struct Skel {
    /// The joints, parents first.
    pub(super) skeleton: Skeleton,
    /// ufbx node `typed_id` -> its joint.
    pub(super) joint_of: HashMap<u32, JointIndex>,
    /// Per joint: its node's rest `node_to_world` (model space = the converted scene).
    pub(super) world_rest: Vec<DMat4>,
}

impl Skel {
    /// The joint of `node`, or of its nearest ancestor that is a joint.
    pub(super) fn nearest_joint(&self, node: &ufbx::Node) -> Option<JointIndex> {
        if let Some(&j) = self.joint_of.get(&node.element.typed_id) {
            return Some(j);
        }
        let mut parent = node.parent.as_ref();
        while let Some(p) = parent {
            if let Some(&j) = self.joint_of.get(&p.element.typed_id) {
                return Some(j);
            }
            parent = p.parent.as_ref();
        }
        None
    }
}

/// A ufbx 4x3 matrix (column vectors) as a glam matrix.
pub(super) fn mat(m: &ufbx::Matrix) -> DMat4 {
    DMat4::from_cols(
        DVec4::new(m.m00, m.m10, m.m20, 0.0),
        DVec4::new(m.m01, m.m11, m.m21, 0.0),
        DVec4::new(m.m02, m.m12, m.m22, 0.0),
        DVec4::new(m.m03, m.m13, m.m23, 1.0),
    )
}

/// A ufbx transform as the model's (f32).
pub(super) fn transform(t: &ufbx::Transform) -> Transform {
    Transform {
        translation: vec3(&t.translation),
        rotation: quat(&t.rotation),
        scale: vec3(&t.scale),
    }
}

/// A ufbx vector in `f32`.
pub(super) fn vec3(v: &ufbx::Vec3) -> Vec3 {
    Vec3::new(v.x as f32, v.y as f32, v.z as f32)
}

/// A ufbx quaternion in `f32`, normalized (ufbx's are unit up to `f64` rounding).
pub(super) fn quat(q: &ufbx::Quat) -> Quat {
    Quat::from_xyzw(q.x as f32, q.y as f32, q.z as f32, q.w as f32).normalize()
}

/// The joints: every node with a bone attribute, every skin cluster's bone, every node in
/// `animated` (ufbx node typed ids), and every node between those and the scene root,
/// ordered by depth (parents first), then by ufbx's node order.
///
/// # Errors
/// A model rule broken by the hierarchy (duplicate names are made unique first).
pub(super) fn build(
    scene: &ufbx::Scene,
    animated: &HashSet<u32>,
    path: &Path,
) -> Result<Skel, ImportError> {
    let mut keep: HashSet<u32> = HashSet::new();
    let mark = |node: &ufbx::Node, keep: &mut HashSet<u32>| {
        let mut at = Some(node);
        while let Some(n) = at {
            if n.is_root || !keep.insert(n.element.typed_id) {
                break;
            }
            at = n.parent.as_deref();
        }
    };
    for node in scene.nodes.iter() {
        if node.bone.is_some() || animated.contains(&node.element.typed_id) {
            mark(node, &mut keep);
        }
    }
    for cluster in scene.skin_clusters.iter() {
        if let Some(bone) = cluster.bone_node.as_ref() {
            mark(bone, &mut keep);
        }
    }
    let mut nodes: Vec<&ufbx::Node> = scene
        .nodes
        .iter()
        .map(|n| &**n)
        .filter(|n| keep.contains(&n.element.typed_id))
        .collect();
    nodes.sort_by_key(|n| (n.node_depth, n.element.typed_id));

    let mut joint_of = HashMap::new();
    let mut used: HashSet<String> = HashSet::new();
    let mut joints = Vec::with_capacity(nodes.len());
    let mut world_rest = Vec::with_capacity(nodes.len());
    for (k, node) in nodes.iter().enumerate() {
        let parent = node
            .parent
            .as_ref()
            .and_then(|p| joint_of.get(&p.element.typed_id).copied());
        // A root joint's parent is the scene root: its local transform is its world one
        // (the root is the identity after ufbx's conversion; take it in either way).
        let rest_local = if parent.is_none() {
            from_matrix(&mat(&node.node_to_world))
        } else {
            transform(&node.local_transform)
        };
        joints.push(Joint {
            name: unique(&node.element.name, "node", &mut used),
            parent,
            rest_local,
        });
        world_rest.push(mat(&node.node_to_world));
        joint_of.insert(node.element.typed_id, JointIndex(k as u32));
    }
    let skeleton = Skeleton::new(joints)
        .map_err(|problems| ImportError::new(Location::file(path), Problem::Skeleton(problems)))?;
    Ok(Skel {
        skeleton,
        joint_of,
        world_rest,
    })
}

/// A TRS from an affine matrix without shear (ufbx's world matrices of root nodes).
fn from_matrix(m: &DMat4) -> Transform {
    let (scale, rotation, translation) = m.as_mat4().to_scale_rotation_translation();
    Transform {
        translation,
        rotation: rotation.normalize(),
        scale,
    }
}
