//! What the importer returns beside the asset, and the parsed `skin.config` (re-exported by
//! the parent module).

use glam::DVec3;
use rigport_model::conventions::EulerOrder;
use rigport_model::JointIndex;

use crate::Imported;

/// A CSCI 520 rig: the asset plus what the model has no field for.
///
/// Every per-joint vector has one entry per skeleton joint, in skeleton (parents-first)
/// order; [`Csci520Rig::file_index`] maps a skeleton joint to its index in the files.
#[derive(Clone, Debug)]
pub struct Csci520Rig {
    /// The asset (skeleton, mesh, and a skin unless the weights are absent) and the
    /// warnings of the import.
    pub imported: Imported,
    /// The `IKJointIDs` joints, in the config's order, as skeleton indices; empty when the
    /// config has no `IKJointIDs`. A handle's initial target is its joint's model-space
    /// rest position.
    pub ik_handles: Vec<JointIndex>,
    /// Each joint's rotate order (the order of its rest angles; joint orients are always
    /// `xyz`).
    pub rotate_orders: Vec<EulerOrder>,
    /// Each joint's rest Euler angles in degrees, `[x, y, z]` whatever the order: the
    /// angles the IK unknowns start from.
    pub rest_angles_deg: Vec<DVec3>,
    /// Each joint's `jointOrient` angles in degrees, `[x, y, z]`, applied in `xyz` order.
    pub joint_orients_deg: Vec<DVec3>,
    /// For each skeleton joint, its index in `jointHierarchy.txt`, the rest transforms,
    /// the weights and `IKJointIDs` (the `<i>` of its name `joint_<i>`).
    pub file_index: Vec<usize>,
}

/// A value of a `skin.config` option and the 1-based line it is on.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ConfigEntry<T> {
    /// The value (for file names: the trimmed line, relative to the config's folder).
    pub value: T,
    /// The 1-based line of the value in the config.
    pub line: usize,
}

/// The options of a `skin.config`, as read by [`parse_config`](crate::csci520::parse_config).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct SkinConfig {
    /// `*meshFilename`: the OBJ.
    pub mesh_filename: Option<ConfigEntry<String>>,
    /// `*jointHierarchyFilename`.
    pub joint_hierarchy_filename: Option<ConfigEntry<String>>,
    /// `*jointRestTransformsFilename`.
    pub joint_rest_transforms_filename: Option<ConfigEntry<String>>,
    /// `*jointWeightsFilename`.
    pub joint_weights_filename: Option<ConfigEntry<String>>,
    /// `*IKJointIDs`, ranges expanded, in the listed order (file joint numbering; not yet
    /// checked against the joint count).
    pub ik_joint_ids: Option<ConfigEntry<Vec<usize>>>,
    /// Every other option, in file order: its name as written and its value.
    pub other: Vec<(String, ConfigEntry<String>)>,
}

/// The contents of `jointRestTransforms.txt`, one entry per joint in file order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RestTransforms {
    /// Offset from the parent joint in the parent's frame (the root's: in model space),
    /// in the files' length unit.
    pub translations: Vec<DVec3>,
    /// Rest Euler angles in degrees, `[x, y, z]`, applied in `rotate_orders` order.
    pub rest_angles_deg: Vec<DVec3>,
    /// `jointOrient` angles in degrees, `[x, y, z]`, applied in `xyz` order.
    pub joint_orients_deg: Vec<DVec3>,
    /// Rotate order of each joint's rest angles (`xyz` for all when the file has none).
    pub rotate_orders: Vec<EulerOrder>,
    /// Whether the file has the rotate-order section.
    pub rotate_orders_given: bool,
}
