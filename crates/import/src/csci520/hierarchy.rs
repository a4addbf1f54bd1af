//! `jointHierarchy.txt`: one parent index per joint.

use std::path::Path;

use rigport_model::{parents_first_order, SkeletonProblem};

use crate::problem::{Hierarchy, Limit};
use crate::text::{self, Lines};
use crate::{ImportError, Location, Problem};

/// Parses `jointHierarchy.txt`: entry `i` is joint `i`'s parent, `-1` for the root.
///
/// Entries are integers separated by white space and/or commas, on any number of lines;
/// blank lines and `#` comment lines are skipped. Returns one parent per joint in file
/// numbering (not necessarily parents-first), already checked to form one tree.
///
/// # Errors
/// At the line of the offending entry: a token that is not an integer; a parent below -1
/// or not a joint; a joint that is its own parent; a parent cycle (at the line of the
/// cycle's smallest joint); a second root. A file without entries is [`Problem::Empty`].
pub fn parse_hierarchy(text: &str, path: &Path) -> Result<Vec<Option<usize>>, ImportError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut parents: Vec<Option<usize>> = Vec::new();
    let mut lines: Vec<usize> = Vec::new();
    for (line_no, raw) in Lines::new(text) {
        let line = raw.trim_ascii();
        if line.starts_with('#') {
            continue;
        }
        let at = || Location::line(path, line_no);
        for token in line
            .split(|c: char| c.is_ascii_whitespace() || c == ',')
            .filter(|t| !t.is_empty())
        {
            let joint = parents.len();
            let value: i64 = text::number(token, "parent index", || {
                text::at(path, line_no, raw, token)
            })?;
            let parent = match value {
                -1 => None,
                p => Some(usize::try_from(p).map_err(|_| {
                    ImportError::at(at(), Hierarchy::ParentNotJoint { joint, parent: p })
                })?),
            };
            parents.push(parent);
            lines.push(line_no);
        }
    }
    let count = parents.len();
    if count == 0 {
        return Err(ImportError::new(Location::file(path), Problem::Empty));
    }
    if u32::try_from(count).is_err() {
        return Err(ImportError::at(
            Location::file(path),
            Limit::JointCount(count),
        ));
    }
    let line_of = |joint: usize| match lines.get(joint) {
        Some(&line) => Location::line(path, line),
        None => Location::file(path),
    };
    for (joint, parent) in parents.iter().enumerate() {
        match *parent {
            Some(p) if p >= count => {
                return Err(ImportError::at(
                    line_of(joint),
                    Hierarchy::ParentBeyond {
                        joint,
                        parent: p,
                        count,
                    },
                ))
            }
            Some(p) if p == joint => {
                return Err(ImportError::at(line_of(joint), Hierarchy::OwnParent(joint)))
            }
            _ => {}
        }
    }
    parents_first_order(&parents).map_err(|problems| {
        let joint = problems.iter().find_map(|p| match p {
            SkeletonProblem::Cycle { joints } => joints.iter().min().copied(),
            _ => None,
        });
        let location = joint.map_or_else(|| Location::file(path), line_of);
        ImportError::new(location, Problem::Skeleton(problems))
    })?;
    let mut roots = parents
        .iter()
        .enumerate()
        .filter(|(_, p)| p.is_none())
        .map(|(j, _)| j);
    match (roots.next(), roots.next()) {
        (Some(_), None) => Ok(parents),
        (Some(first), Some(second)) => Err(ImportError::at(
            line_of(second),
            Hierarchy::SecondRoot { first, second },
        )),
        // A finite parent array without a root has a cycle, reported above.
        (None, _) => Err(ImportError::at(Location::file(path), Hierarchy::NoRoot)),
    }
}
