//! The visual scene: `<scene><instance_visual_scene>` (else the first `<visual_scene>`)
//! flattened into its nodes, parents first (document order), `<instance_node>` expanded
//! in place; each node with its transform elements and its local and world matrices (the
//! scene's own space: the file's unit and up axis).

use std::collections::HashMap;

use rigport_model::glam::DMat4;

use super::transform::{self, Element};
use super::xml::{child, child_elements, Doc, Node};
use crate::ImportError;

/// How deep `<instance_node>` may nest: deeper is taken for a cycle.
const MAX_INSTANCE_DEPTH: usize = 64;

/// One node of the scene.
pub(super) struct SceneNode<'a, 'i> {
    /// The `<node>` element.
    pub(super) xml: Node<'a, 'i>,
    /// Its parent node (an index into the scene's nodes).
    pub(super) parent: Option<usize>,
    /// `type="JOINT"`.
    pub(super) joint: bool,
    /// Its transform elements, in order.
    pub(super) transforms: Vec<Element>,
    /// Local matrix (the elements composed).
    pub(super) local: DMat4,
    /// Scene-space matrix.
    pub(super) world: DMat4,
}

impl SceneNode<'_, '_> {
    /// The name a joint or mesh takes: `name`, else `id`, else `sid` (may be empty).
    pub(super) fn name(&self) -> &str {
        ["name", "id", "sid"]
            .iter()
            .find_map(|a| self.xml.attribute(*a).filter(|s| !s.is_empty()))
            .unwrap_or("")
    }
}

/// The scene's nodes, parents first.
pub(super) struct Scene<'a, 'i> {
    pub(super) nodes: Vec<SceneNode<'a, 'i>>,
    /// Node `id` -> its first node.
    by_id: HashMap<&'a str, usize>,
}

impl<'a, 'i> Scene<'a, 'i> {
    /// The node with `id`.
    pub(super) fn by_id(&self, id: &str) -> Option<usize> {
        self.by_id.get(id).copied()
    }

    /// The node with `sid` (else `id`, else `name`) equal to `key` within the subtrees of
    /// `roots` (the whole scene when empty), first in document order.
    pub(super) fn find_joint(&self, key: &str, roots: &[usize]) -> Option<usize> {
        let within = |n: usize| roots.is_empty() || roots.iter().any(|&r| self.is_under(n, r));
        for attr in ["sid", "id", "name"] {
            let found = (0..self.nodes.len())
                .find(|&n| within(n) && self.nodes[n].xml.attribute(attr) == Some(key));
            if found.is_some() {
                return found;
            }
        }
        None
    }

    /// Whether `node` is `root` or below it.
    pub(super) fn is_under(&self, node: usize, root: usize) -> bool {
        let mut at = Some(node);
        while let Some(n) = at {
            if n == root {
                return true;
            }
            at = self.nodes[n].parent;
        }
        false
    }

    /// The node whose `sid` is `sid` (or whose `id` is, for an unscoped path) at or below
    /// `from`: the second step of a channel's target path.
    pub(super) fn sid_below(&self, from: usize, sid: &str) -> Option<usize> {
        (from..self.nodes.len())
            .find(|&n| self.is_under(n, from) && self.nodes[n].xml.attribute("sid") == Some(sid))
    }
}

/// The visual scene of the document, flattened.
///
/// # Errors
/// No visual scene; a bad transform element; `<instance_node>`s that instance each other
/// (a cycle).
pub(super) fn read<'a, 'i>(doc: &Doc<'a, 'i>) -> Result<Scene<'a, 'i>, ImportError> {
    let root = doc.root();
    let visual = match child(root, "scene").and_then(|s| child(s, "instance_visual_scene")) {
        Some(instance) => doc.link(instance, "url", "visual scene")?,
        None => child(root, "library_visual_scenes")
            .and_then(|l| child(l, "visual_scene"))
            .ok_or_else(|| doc.invalid(root, "the document has no <visual_scene>"))?,
    };
    let mut scene = Scene {
        nodes: Vec::new(),
        by_id: HashMap::new(),
    };
    let mut stack = Vec::new();
    for node in child_elements(visual).filter(|n| n.tag_name().name() == "node") {
        add(doc, &mut scene, node, None, &mut stack)?;
    }
    Ok(scene)
}

/// Adds `node` and its subtree under `parent`; `stack` holds the `<instance_node>` urls
/// being expanded.
fn add<'a, 'i>(
    doc: &Doc<'a, 'i>,
    scene: &mut Scene<'a, 'i>,
    node: Node<'a, 'i>,
    parent: Option<usize>,
    stack: &mut Vec<Node<'a, 'i>>,
) -> Result<(), ImportError> {
    let transforms = transform::read(doc, node)?;
    let local = transform::compose(&transforms);
    let world = match parent {
        Some(p) => scene.nodes[p].world * local,
        None => local,
    };
    let index = scene.nodes.len();
    if let Some(id) = node.attribute("id") {
        scene.by_id.entry(id).or_insert(index);
    }
    scene.nodes.push(SceneNode {
        xml: node,
        parent,
        joint: node.attribute("type") == Some("JOINT"),
        transforms,
        local,
        world,
    });
    for c in child_elements(node) {
        match c.tag_name().name() {
            "node" => add(doc, scene, c, Some(index), stack)?,
            "instance_node" => {
                let target = doc.link(c, "url", "node")?;
                if stack.contains(&target) || stack.len() >= MAX_INSTANCE_DEPTH {
                    let mut names: Vec<String> = stack
                        .iter()
                        .map(|n| n.attribute("id").unwrap_or("?").to_string())
                        .collect();
                    names.push(target.attribute("id").unwrap_or("?").to_string());
                    return Err(doc.invalid(
                        c,
                        format!(
                            "the nodes {} instance each other: a cyclic hierarchy",
                            names.join(" -> ")
                        ),
                    ));
                }
                stack.push(target);
                add(doc, scene, target, Some(index), stack)?;
                stack.pop();
            }
            _ => {}
        }
    }
    Ok(())
}
