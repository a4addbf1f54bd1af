//! The skeleton: which scene nodes become joints, parents first, with their rest
//! transforms.
//!
//! Joints are the `type="JOINT"` nodes, the nodes skins name as joints, the nodes an
//! animation moves, and every node between those and the scene root (so a joint's parent
//! is always a joint, as fbx/ does). Each joint's rest transform is its node's local
//! matrix (its transform elements composed) as translation, rotation and scale; a shear
//! (from `<skew>`, `<lookat>` or a `<matrix>`) cannot be a TRS and is dropped there (a W004
//! warning names the joints), while
//! meshes are placed from the TRS so that what they sit on is what the file shows.

use std::collections::HashSet;
use std::path::Path;

use rigport_model::glam::DMat4;
use rigport_model::{Joint, JointIndex, Skeleton, Transform};

use super::scene::Scene;
use crate::names::unique;
use crate::{ImportError, Location, Problem};

/// How far (relative to the matrix's largest element) a node matrix may be from its TRS
/// before the difference counts as a lost shear (`f32` rounding of a TRS is ~1e-7).
const SHEAR_TOLERANCE: f64 = 1e-5;

/// The skeleton and where each scene node went.
pub(super) struct Skel {
    pub(super) skeleton: Skeleton,
    /// Per scene node: its joint.
    pub(super) joint_of: Vec<Option<JointIndex>>,
    /// Per joint: its rest model-space matrix from the TRS rest transforms.
    pub(super) world: Vec<DMat4>,
    /// The joints whose node matrix has a shear the TRS left out, with the largest
    /// element of the difference (relative to the matrix's largest).
    pub(super) sheared: Vec<(String, f64)>,
}

impl Skel {
    /// The joint of scene node `node`, or of its nearest ancestor that is one.
    pub(super) fn nearest_joint(&self, scene: &Scene, node: usize) -> Option<JointIndex> {
        let mut at = Some(node);
        while let Some(n) = at {
            if let Some(j) = self.joint_of[n] {
                return Some(j);
            }
            at = scene.nodes[n].parent;
        }
        None
    }
}

/// The joints: the `type="JOINT"` nodes, the nodes in `used` (skin joints, animated
/// nodes) and their ancestors, in scene order (parents first).
///
/// # Errors
/// A model rule broken by the hierarchy (names are made unique first).
pub(super) fn build(scene: &Scene, used: &[usize], path: &Path) -> Result<Skel, ImportError> {
    let mut keep = vec![false; scene.nodes.len()];
    let starts = (0..scene.nodes.len())
        .filter(|&n| scene.nodes[n].joint)
        .chain(used.iter().copied());
    for start in starts {
        let mut at = Some(start);
        while let Some(n) = at {
            if keep[n] {
                break;
            }
            keep[n] = true;
            at = scene.nodes[n].parent;
        }
    }
    let mut joint_of: Vec<Option<JointIndex>> = vec![None; scene.nodes.len()];
    let mut joints = Vec::new();
    let mut world: Vec<DMat4> = Vec::new();
    let mut names = HashSet::new();
    let mut sheared = Vec::new();
    for (n, node) in scene.nodes.iter().enumerate() {
        if !keep[n] {
            continue;
        }
        let parent = node.parent.and_then(|p| joint_of[p]);
        let rest_local = Transform::from_mat4(&node.local.as_mat4());
        let local = rest_local.to_mat4().as_dmat4();
        let size = node
            .local
            .to_cols_array()
            .iter()
            .fold(0.0f64, |a, v| a.max(v.abs()));
        let off = (local - node.local)
            .to_cols_array()
            .iter()
            .fold(0.0f64, |a, v| a.max(v.abs()))
            / size.max(f64::MIN_POSITIVE);
        if off > SHEAR_TOLERANCE {
            sheared.push((node.name().to_string(), off));
        }
        world.push(match parent {
            Some(p) => world[p.get()] * local,
            None => local,
        });
        joint_of[n] = Some(JointIndex(joints.len() as u32));
        joints.push(Joint {
            name: unique(node.name(), "joint", &mut names),
            parent,
            rest_local,
        });
    }
    let skeleton = Skeleton::new(joints)
        .map_err(|problems| ImportError::new(Location::file(path), Problem::Skeleton(problems)))?;
    Ok(Skel {
        skeleton,
        joint_of,
        world,
        sheared,
    })
}
