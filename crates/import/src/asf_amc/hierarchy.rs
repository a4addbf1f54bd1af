//! The ASF `:hierarchy` section: every bone's parent, checked to form one tree under the
//! root.

use std::collections::HashMap;

use rigport_model::{parents_first_order, SkeletonProblem};

use crate::problem::Hierarchy;
use crate::{ImportError, Location, Problem};

use super::lines::{column, line_error};
use super::types::{Asf, Bone};

/// Sets every bone's parent from the `:hierarchy` lines and checks the tree.
pub(super) fn resolve_hierarchy(
    asf: &mut Asf,
    lines: &[(usize, &str, &str)],
) -> Result<(), ImportError> {
    let path = asf.path.clone();
    let index: HashMap<&str, usize> = asf
        .bones
        .iter()
        .enumerate()
        .map(|(i, b)| (b.name.as_str(), i))
        .collect();
    // (parent, line) per bone; `Some(None)` is the root.
    let mut parents: Vec<Option<(Option<usize>, usize)>> = vec![None; asf.bones.len()];
    for &(line_no, raw, line) in lines {
        let mut tokens = line.split_ascii_whitespace();
        let Some(parent_token) = tokens.next() else {
            continue;
        };
        let lookup = |token: &str| {
            index.get(token).copied().ok_or_else(|| {
                ImportError::new(
                    Location::line_column(&path, line_no, column(raw, token)),
                    Problem::UnknownName {
                        what: "bone",
                        name: token.to_string(),
                        within: "`:bonedata`".into(),
                    },
                )
            })
        };
        let parent = if parent_token.eq_ignore_ascii_case("root") {
            None
        } else {
            Some(lookup(parent_token)?)
        };
        for child_token in tokens {
            if child_token.eq_ignore_ascii_case("root") {
                return Err(ImportError::at(
                    Location::line_column(&path, line_no, column(raw, child_token)),
                    Hierarchy::RootAsChild,
                ));
            }
            let child = lookup(child_token)?;
            if parent == Some(child) {
                return Err(ImportError::at(
                    Location::line_column(&path, line_no, column(raw, child_token)),
                    Hierarchy::OwnChild(child_token.to_string()),
                ));
            }
            let Some(slot) = parents.get_mut(child) else {
                continue;
            };
            if let Some((previous, first)) = *slot {
                let previous = previous
                    .and_then(|p| asf.bones.get(p))
                    .map_or("root", |b| b.name.as_str());
                return Err(ImportError::at(
                    Location::line_column(&path, line_no, column(raw, child_token)),
                    Hierarchy::SecondParent {
                        bone: child_token.to_string(),
                        parent: previous.to_string(),
                        line: first,
                    },
                ));
            }
            *slot = Some((parent, line_no));
        }
    }
    for (bone, parent) in asf.bones.iter_mut().zip(&parents) {
        let Some((parent, line)) = *parent else {
            return Err(line_error(
                &path,
                bone.line,
                Hierarchy::NotListed(bone.name.clone()),
            ));
        };
        bone.parent = parent;
        bone.hierarchy_line = line;
    }
    // A cycle (bones parented to each other, none to the root) is found here.
    let node_parents: Vec<Option<usize>> = std::iter::once(None)
        .chain(
            asf.bones
                .iter()
                .map(|b| Some(b.parent.map_or(0, |p| p + 1))),
        )
        .collect();
    parents_first_order(&node_parents)
        .map_err(|problems| hierarchy_error(asf, &problems, |node| node.checked_sub(1)))?;
    Ok(())
}

/// An error for a broken parent structure; `bone_of` maps a problem's index to a bone.
/// A cycle is reported at the first `:hierarchy` line involved, naming its bones.
pub(super) fn hierarchy_error(
    asf: &Asf,
    problems: &[SkeletonProblem],
    bone_of: impl Fn(usize) -> Option<usize>,
) -> ImportError {
    if let Some(SkeletonProblem::Cycle { joints }) = problems.first() {
        let bones: Vec<&Bone> = joints
            .iter()
            .filter_map(|&j| bone_of(j).and_then(|b| asf.bones.get(b)))
            .collect();
        let line = bones.iter().map(|b| b.hierarchy_line).min().unwrap_or(0);
        let names = bones.iter().map(|b| b.name.clone()).collect();
        return line_error(&asf.path, line, Hierarchy::Cycle(names));
    }
    ImportError::new(
        Location::file(&asf.path),
        Problem::Skeleton(problems.to_vec()),
    )
}
