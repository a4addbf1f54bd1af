//! Nodes to joints: the scene's node forest as a parents-first skeleton, unique names, and
//! each node's rest transform.

use std::collections::HashSet;

use ::gltf::Semantic;
use rigport_model::glam::{Mat4, Quat, Vec3};
use rigport_model::{parents_first_order, Joint, JointIndex, Skeleton, SkeletonProblem, Transform};

use crate::{ImportError, Location, Problem};

use super::importer::{Importer, UNIT_QUAT_TOLERANCE};

/// Largest element difference between a node `matrix` and its TRS decomposition (relative
/// to the largest element of its 3x3 part, at least 1) before the matrix counts as sheared.
const MATRIX_TOLERANCE: f32 = 1e-5;

/// The imported nodes as a skeleton.
pub(super) struct SceneNodes {
    pub(super) skeleton: Skeleton,
    /// Node indices in skeleton (parents-first) order.
    pub(super) order: Vec<usize>,
    /// Each node's joint; `None` for nodes outside the imported scene and for
    /// `mesh_only` nodes.
    pub(super) node_joint: Vec<Option<JointIndex>>,
    /// Skinned-mesh nodes that are not joints: leaves that no skin uses and no animation
    /// moves. glTF ignores a skinned mesh node's transform, so such a node carries nothing
    /// but its mesh; making it a joint would add a node on every round trip.
    /// `(node, parent joint)`.
    pub(super) mesh_only: Vec<(usize, Option<JointIndex>)>,
}

impl<'a> Importer<'a> {
    /// Builds the skeleton of the imported nodes, checking that the children lists form a
    /// forest (one parent per node, no cycles).
    pub(super) fn skeleton(&mut self) -> Result<SceneNodes, ImportError> {
        let nodes: Vec<::gltf::Node<'a>> = self.doc.nodes().collect();
        let n = nodes.len();
        let mut parent: Vec<Option<usize>> = vec![None; n];
        for node in &nodes {
            let p = node.index();
            for (k, child) in node.children().enumerate() {
                let c = child.index();
                let at = format!("/nodes/{p}/children/{k}");
                if c == p {
                    return Err(self.err(at, format!("node {p} lists itself as a child")));
                }
                let Some(slot) = parent.get_mut(c) else {
                    return Err(self.err(at, format!("node {c} does not exist")));
                };
                if let Some(q) = *slot {
                    return Err(self.err(
                        at,
                        format!(
                            "node {c} is already a child of node {q}; a glTF node has at most \
                             one parent"
                        ),
                    ));
                }
                *slot = Some(p);
            }
        }
        let full_order = parents_first_order(&parent).map_err(|problems| {
            match problems.iter().find_map(|p| match p {
                SkeletonProblem::Cycle { joints } => Some(joints.clone()),
                _ => None,
            }) {
                Some(cycle) => self.err(
                    format!("/nodes/{}/children", cycle.first().copied().unwrap_or(0)),
                    format!("nodes {cycle:?} form a cycle of children"),
                ),
                None => ImportError::new(
                    Location::json(self.path, "/nodes"),
                    Problem::Skeleton(problems),
                ),
            }
        })?;

        // Which nodes: the default scene's, else every scene's, else all.
        let scene_count = self.doc.scenes().count();
        let roots: Vec<usize> = match self.doc.default_scene() {
            Some(scene) => scene.nodes().map(|node| node.index()).collect(),
            None if scene_count > 0 => {
                self.note(
                    "/scenes",
                    format!("no default scene: importing the nodes of all {scene_count} scenes"),
                );
                self.doc
                    .scenes()
                    .flat_map(|s| s.nodes().map(|node| node.index()).collect::<Vec<_>>())
                    .collect()
            }
            None => {
                if n > 0 {
                    self.note("/nodes", "no scenes: importing every node".into());
                }
                (0..n).filter(|&i| parent[i].is_none()).collect()
            }
        };
        let mut selected = vec![false; n];
        let mut stack = roots.clone();
        while let Some(i) = stack.pop() {
            match selected.get_mut(i) {
                Some(s) if !*s => *s = true,
                _ => continue,
            }
            if let Some(node) = nodes.get(i) {
                stack.extend(node.children().map(|c| c.index()));
            }
        }
        let mut used = vec![false; n];
        for skin in self.doc.skins() {
            for j in skin.joints() {
                if let Some(u) = used.get_mut(j.index()) {
                    *u = true;
                }
            }
            if let Some(u) = skin.skeleton().and_then(|s| used.get_mut(s.index())) {
                *u = true;
            }
        }
        // From the JSON: the gltf crate's channel accessors unwrap unvalidated indices.
        for anim in &self.doc.as_json().animations {
            for ch in &anim.channels {
                if let Some(u) = used.get_mut(ch.target.node.value()) {
                    *u = true;
                }
            }
        }
        let mesh_only_node = |i: usize| {
            let node = &nodes[i];
            node.mesh().is_some_and(|m| {
                m.primitives()
                    .all(|p| p.get(&Semantic::Joints(0)).is_some())
            }) && node.skin().is_some()
                && node.children().len() == 0
                && !used[i]
        };
        let (order, mesh_only_nodes): (Vec<usize>, Vec<usize>) = full_order
            .into_iter()
            .filter(|&i| selected[i])
            .partition(|&i| !mesh_only_node(i));
        let mut node_joint: Vec<Option<JointIndex>> = vec![None; n];
        for (k, &i) in order.iter().enumerate() {
            node_joint[i] = Some(JointIndex(k as u32));
        }

        // Unique, non-empty names: authored names first (lowest node index wins), then
        // generated ones that avoid every authored name.
        let mut taken: HashSet<String> = HashSet::new();
        let mut names: Vec<Option<String>> = vec![None; n];
        for &i in &order {
            if let Some(name) = nodes[i].name().filter(|s| !s.is_empty()) {
                if taken.insert(name.to_string()) {
                    names[i] = Some(name.to_string());
                }
            }
        }
        let mut unnamed = 0usize;
        let mut missing: Vec<usize> = order
            .iter()
            .copied()
            .filter(|&i| names[i].is_none())
            .collect();
        missing.sort_unstable();
        for i in missing {
            let authored = nodes[i].name().filter(|s| !s.is_empty());
            let base = match authored {
                Some(name) => format!("{name}_{i}"),
                None => format!("node_{i}"),
            };
            let mut candidate = base.clone();
            let mut k = 1;
            while taken.contains(&candidate) {
                candidate = format!("{base}_{k}");
                k += 1;
            }
            taken.insert(candidate.clone());
            match authored {
                Some(name) => self.note(
                    &format!("/nodes/{i}/name"),
                    format!("duplicate node name {name:?}: joint renamed {candidate:?}"),
                ),
                None => {
                    unnamed += 1;
                    if candidate != base {
                        self.note(
                            &format!("/nodes/{i}/name"),
                            format!("unnamed node; {base:?} is taken, joint named {candidate:?}"),
                        );
                    }
                }
            }
            names[i] = Some(candidate);
        }
        if unnamed > 0 {
            self.note(
                "/nodes",
                format!("{unnamed} unnamed node(s): joints named node_<index>"),
            );
        }

        let mut joints = Vec::with_capacity(order.len());
        for &i in &order {
            let parent_joint = match parent[i] {
                Some(p) if selected[p] => node_joint[p],
                Some(p) => {
                    self.note(
                        &format!("/nodes/{i}"),
                        format!(
                            "scene root node {i} is a child of node {p}, which is not in the \
                             scene; imported as a root"
                        ),
                    );
                    None
                }
                None => None,
            };
            joints.push(Joint {
                name: names[i].take().unwrap_or_else(|| format!("node_{i}")),
                parent: parent_joint,
                rest_local: self.rest_local(&nodes[i])?,
            });
        }
        let skeleton = Skeleton::new(joints).map_err(|problems| {
            ImportError::new(
                Location::json(self.path, "/nodes"),
                Problem::Skeleton(problems),
            )
        })?;
        let mesh_only = mesh_only_nodes
            .into_iter()
            .map(|i| (i, parent[i].and_then(|p| node_joint[p])))
            .collect();
        Ok(SceneNodes {
            skeleton,
            order,
            node_joint,
            mesh_only,
        })
    }

    fn rest_local(&mut self, node: &::gltf::Node<'_>) -> Result<Transform, ImportError> {
        let i = node.index();
        match node.transform() {
            ::gltf::scene::Transform::Matrix { matrix } => {
                let at = format!("/nodes/{i}/matrix");
                let m = Mat4::from_cols_array_2d(&matrix);
                if !m.is_finite() {
                    return Err(self.err(at, "matrix is not finite"));
                }
                let mut t = Transform::from_mat4(&m);
                if !t.rotation.is_finite() {
                    // A zero scale leaves no rotation to recover.
                    t.rotation = Quat::IDENTITY;
                }
                let back = t.to_mat4();
                let diff = (back - m)
                    .to_cols_array()
                    .iter()
                    .fold(0.0f32, |a, v| a.max(v.abs()));
                let scale = [m.x_axis, m.y_axis, m.z_axis]
                    .iter()
                    .flat_map(|c| c.truncate().to_array())
                    .fold(1.0f32, |a, v| a.max(v.abs()));
                if !diff.is_finite() || diff > MATRIX_TOLERANCE * scale {
                    self.repaired(
                        &at,
                        format!(
                            "matrix is not a TRS (shear or projection): the nearest TRS differs \
                             by up to {diff:.3e}; kept the TRS"
                        ),
                    );
                }
                Ok(t)
            }
            ::gltf::scene::Transform::Decomposed {
                translation,
                rotation,
                scale,
            } => {
                let translation = Vec3::from(translation);
                let scale = Vec3::from(scale);
                let q = Quat::from_array(rotation);
                if !translation.is_finite() {
                    return Err(self.err(format!("/nodes/{i}/translation"), "not finite"));
                }
                if !scale.is_finite() {
                    return Err(self.err(format!("/nodes/{i}/scale"), "not finite"));
                }
                let len = q.length();
                if !(len > 1e-6 && len.is_finite()) {
                    return Err(self.err(
                        format!("/nodes/{i}/rotation"),
                        format!("rotation quaternion has length {len}"),
                    ));
                }
                if (len - 1.0).abs() > UNIT_QUAT_TOLERANCE {
                    self.repaired(
                        &format!("/nodes/{i}/rotation"),
                        format!("rotation quaternion has length {len}; normalized"),
                    );
                }
                Ok(Transform {
                    translation,
                    rotation: q / len,
                    scale,
                })
            }
        }
    }
}
