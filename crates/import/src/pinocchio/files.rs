//! The two files Pinocchio writes: `skeleton.out` ([`PinocchioSkeleton`], one joint per
//! line) and `attachment.out` ([`Attachment`], one row of bone weights per OBJ vertex),
//! parsed line-exactly, and the skeleton's topology check.

use std::path::Path;

use glam::Vec3;
use rigport_model::{parents_first_order, Warning};

use crate::problem::{Hierarchy, Mismatch, Missing};
use crate::text::{self, Lines, Number};
use crate::{exact_fields, obj, ImportError, Location, Problem};

/// A Pinocchio skeleton as written in `skeleton.out`: joints in Pinocchio's numbering.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PinocchioSkeleton {
    /// Joint positions, in the mesh's coordinates and unit; one per joint.
    pub positions: Vec<Vec3>,
    /// Parent of each joint (`None` for the root, which must be joint 0); one per joint.
    /// Need not be parents-first.
    pub parents: Vec<Option<usize>>,
}

/// Per-vertex weights as read from `attachment.out` (renormalized), or generated.
///
/// Stored flat, row-major: row `r` (OBJ `v` line `r`) is
/// `weights[r * bones..(r + 1) * bones]`, column `k` being the bone that ends at Pinocchio
/// joint `k + 1`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Attachment {
    /// Bone weights, `bones` per row, rows in OBJ `v` order.
    pub weights: Vec<f32>,
    /// Weights per row: the skeleton's joint count minus 1.
    pub bones: usize,
    /// The leading root column of a `J`-column file, one value per row; `None` for
    /// Pinocchio's own `J - 1`-column layout. A row's bone weights plus its root weight sum
    /// to 1 after [`parse_attachment`].
    pub root_weights: Option<Vec<f32>>,
}

impl Attachment {
    /// Number of rows (`weights.len() / bones`; 0 when `bones` is 0).
    pub fn row_count(&self) -> usize {
        self.weights.len().checked_div(self.bones).unwrap_or(0)
    }

    /// The rows' bone weights, in order (`bones` values each).
    pub fn rows(&self) -> std::slice::ChunksExact<'_, f32> {
        self.weights.chunks_exact(self.bones.max(1))
    }
}

/// Parses `skeleton.out`.
///
/// Tolerates CRLF line ends, leading/trailing spaces, blank lines anywhere (a blank first
/// line included), a missing final newline and a UTF-8 byte-order mark. Joints may be
/// listed in any parent/child order.
///
/// # Errors
/// At the offending line (`file:line: problem`): not 5 fields, an index, coordinate or
/// parent that does not parse, a non-finite coordinate, an index that is not the line's
/// ordinal among joint lines, a parent below -1 or past the last joint, a joint that is
/// its own parent (e.g. a root written with parent `0`), a parent cycle (at its first
/// joint's line), a second root, a root other than joint 0, a single joint (no bone).
/// A file without joint lines is [`Problem::Empty`].
pub fn parse_skeleton(text: &str, path: &Path) -> Result<PinocchioSkeleton, ImportError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut skeleton = PinocchioSkeleton::default();
    let mut lines = Vec::new();
    for (line_no, raw) in Lines::new(text) {
        let line = raw.trim_ascii();
        if line.is_empty() {
            continue;
        }
        let at = || Location::line(path, line_no);
        let at_token = |token: &str| text::at(path, line_no, raw, token);
        let Some(fields) = exact_fields::<5>(line) else {
            return Err(ImportError::syntax(
                at(),
                "5 fields `index x y z parent`",
                line,
            ));
        };
        let ordinal = skeleton.positions.len();
        let index: usize = text::number(fields[0], "joint index", || at_token(fields[0]))?;
        if index != ordinal {
            return Err(ImportError::at(
                at(),
                Hierarchy::Numbering {
                    found: index,
                    expected: ordinal,
                },
            ));
        }
        let mut p = [0.0_f32; 3];
        for (slot, token) in p.iter_mut().zip(&fields[1..4]) {
            *slot = text::number(token, "coordinate", || at_token(token))?;
        }
        let parent: i64 = text::number(fields[4], "parent index", || at_token(fields[4]))?;
        let parent = match parent {
            -1 => None,
            p => Some(usize::try_from(p).map_err(|_| {
                ImportError::at(
                    at(),
                    Hierarchy::ParentNotIndex {
                        joint: index,
                        parent: p,
                    },
                )
            })?),
        };
        skeleton.positions.push(Vec3::from_array(p));
        skeleton.parents.push(parent);
        lines.push(line_no);
    }
    if lines.is_empty() {
        return Err(ImportError::new(Location::file(path), Problem::Empty));
    }
    check_topology(&skeleton.parents).map_err(|(joint, problem)| {
        let location = match joint.and_then(|j| lines.get(j)) {
            Some(&line) => Location::line(path, line),
            None => Location::file(path),
        };
        ImportError::new(location, problem)
    })?;
    Ok(skeleton)
}

/// [`parse_skeleton`], except that a root written as its own parent (joint 0 with parent
/// `0`, as the pynocchio SMPL files write it) is read as the root, with a
/// [`Warning::Repaired`] at its line: joint 0 is the root by the format's rules, so the
/// repair is unambiguous.
///
/// # Errors
/// As [`parse_skeleton`].
pub fn read_skeleton(
    text: &str,
    path: &Path,
) -> Result<(PinocchioSkeleton, Option<Warning>), ImportError> {
    let first = Lines::new(text).find(|(_, l)| !l.trim_ascii().is_empty());
    if let Some((line_no, raw)) = first {
        let fields: Vec<&str> = raw.split_ascii_whitespace().collect();
        if fields.len() == 5 && fields[0] == "0" && fields[4] == "0" {
            let mut fixed = String::with_capacity(text.len() + 1);
            for (n, l) in Lines::new(text) {
                if n == line_no {
                    fixed.push_str(&fields[..4].join(" "));
                    fixed.push_str(" -1");
                } else {
                    fixed.push_str(l);
                }
                fixed.push('\n');
            }
            let skeleton = parse_skeleton(&fixed, path)?;
            let warning = Warning::Repaired {
                location: Location::line(path, line_no).to_string(),
                message:
                    "the root (joint 0) is written as its own parent (0); read as the root (-1)"
                        .into(),
            };
            return Ok((skeleton, Some(warning)));
        }
    }
    Ok((parse_skeleton(text, path)?, None))
}

/// Parses `attachment.out` for a skeleton of `joint_count` joints and a mesh of
/// `vertex_count` OBJ `v` lines.
///
/// Rows are renormalized to sum to 1 (bone weights plus the root weight, if any); negative
/// zero reads as zero. Blank lines are skipped; CRLF, trailing spaces and a missing final
/// newline are fine. Returns the weights and, in order, a [`Warning::Note`] naming the
/// column layout seen and, if any row was rescaled by more than 1e-6, one
/// [`Warning::WeightsRenormalized`] with the largest `|row sum - 1|` and the rescaled row
/// count.
///
/// # Errors
/// At the offending line (`file:line: problem`): a row count other than `vertex_count` (at
/// the first extra row, or the line after the last row), a first row with neither
/// `joint_count - 1` nor `joint_count` weights, a later row with a different count, a
/// weight that does not parse or is NaN, infinite or negative, a row of zeros.
/// `joint_count < 2` (no bone) is an error at the file, and an empty file is
/// [`Problem::Empty`] when `vertex_count > 0`.
pub fn parse_attachment(
    text: &str,
    path: &Path,
    joint_count: usize,
    vertex_count: usize,
) -> Result<(Attachment, Vec<Warning>), ImportError> {
    if joint_count < 2 {
        return Err(ImportError::at(
            Location::file(path),
            Missing::Bones(joint_count),
        ));
    }
    let bones = joint_count - 1;
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut weights: Vec<f32> = Vec::with_capacity(vertex_count.saturating_mul(bones));
    let mut row_count = 0;
    let mut root_weights: Vec<f32> = Vec::new();
    // (columns, line) of the first row.
    let mut layout: Option<(usize, usize)> = None;
    let mut last_line = 0;
    let mut rescaled = 0_usize;
    let mut max_error = 0.0_f64;
    let mut buf: Vec<f32> = Vec::with_capacity(joint_count);
    let mut lines = Lines::new(text);
    while let Some((line_no, raw)) = lines.next() {
        let line = raw.trim_ascii();
        if line.is_empty() {
            continue;
        }
        let at = || Location::line(path, line_no);
        if row_count == vertex_count {
            let extra = 1 + lines.filter(|(_, l)| !l.trim_ascii().is_empty()).count();
            return Err(ImportError::at(
                at(),
                Mismatch::ExtraRows {
                    vertices: vertex_count,
                    extra,
                },
            ));
        }
        parse_row(line, &mut buf).map_err(|(_, token)| {
            let location = text::at(path, line_no, raw, token);
            match f32::read(token) {
                Err(issue) => text::number_error(location, "weight", token, issue),
                Ok(_) => ImportError::new(
                    location,
                    Problem::Negative {
                        what: "weight",
                        found: crate::error::shortened(token),
                    },
                ),
            }
        })?;
        let (columns, first_line) = match layout {
            Some(l) => l,
            None => {
                if buf.len() != bones && buf.len() != joint_count {
                    return Err(ImportError::count(
                        at(),
                        "weights",
                        buf.len(),
                        format_args!("{bones} (one per bone) or {joint_count} (a root column, then one per bone) for a skeleton of {joint_count} joints"),
                    ));
                }
                *layout.insert((buf.len(), line_no))
            }
        };
        if buf.len() != columns {
            return Err(ImportError::count(
                at(),
                "weights",
                buf.len(),
                format_args!("{columns} as on line {first_line}"),
            ));
        }
        let sum: f64 = buf.iter().map(|&w| f64::from(w)).sum();
        if sum <= 0.0 {
            return Err(ImportError::at(at(), Missing::NonzeroWeight));
        }
        let error = (sum - 1.0).abs();
        if error > 1e-6 {
            rescaled += 1;
            max_error = max_error.max(error);
        }
        let scale = 1.0 / sum;
        let mut scaled = buf.iter().map(|&w| (f64::from(w) * scale) as f32);
        if columns == joint_count {
            root_weights.push(scaled.next().unwrap_or(0.0));
        }
        weights.extend(scaled);
        row_count += 1;
        last_line = line_no;
    }
    if row_count < vertex_count {
        if row_count == 0 {
            return Err(ImportError::new(Location::file(path), Problem::Empty));
        }
        return Err(ImportError::at(
            Location::line(path, last_line + 1),
            Mismatch::MissingRows {
                rows: row_count,
                vertices: vertex_count,
            },
        ));
    }
    let location = path.display().to_string();
    let mut warnings = Vec::new();
    if let Some((columns, _)) = layout {
        let message = if columns == joint_count {
            format!(
                "{columns} weight columns for {joint_count} joints: a leading root column (bound to `root`), then one per bone"
            )
        } else {
            format!("{columns} weight columns for {joint_count} joints: one per bone (Pinocchio's layout)")
        };
        warnings.push(Warning::Note {
            location: location.clone(),
            message,
        });
    }
    if rescaled > 0 {
        warnings.push(Warning::WeightsRenormalized {
            source: location,
            rows: rescaled,
            max_row_sum_error: max_error as f32,
        });
    }
    let has_root = layout.is_some_and(|(columns, _)| columns == joint_count);
    Ok((
        Attachment {
            weights,
            bones,
            root_weights: has_root.then_some(root_weights),
        },
        warnings,
    ))
}

/// Parses a row of weights into `out` (cleared first), read by [`obj::parse_f32`].
/// Negative zero becomes zero.
///
/// # Errors
/// The 1-based column and the token of the first weight that does not parse or is NaN,
/// infinite or negative.
fn parse_row<'a>(line: &'a str, out: &mut Vec<f32>) -> Result<(), (usize, &'a str)> {
    out.clear();
    if fast_row(line.as_bytes(), out) {
        return Ok(());
    }
    out.clear();
    for token in line.split_ascii_whitespace() {
        match obj::parse_f32(token) {
            // `>= 0` is false for NaN; + 0.0 turns -0.0 into 0.0.
            Some(w) if w >= 0.0 && w.is_finite() => out.push(w + 0.0),
            _ => return Err((out.len() + 1, token)),
        }
    }
    Ok(())
}

/// The common case of a weight row in one pass over its bytes: unsigned decimals
/// (`0`, `0.9991`, `.5`) of at most 7 significant digits separated by blanks, which is all
/// Pinocchio writes. Returns `false` on anything else (exponents, signs, long mantissas,
/// junk), and the caller parses the row the general way, which also finds the error.
/// Gives the same `f32`s as `str::parse` (the mantissa is exact, and the one division by a
/// power of ten is correctly rounded).
fn fast_row(bytes: &[u8], out: &mut Vec<f32>) -> bool {
    let mut number = obj::Decimal::default();
    let mut in_token = false;
    for &b in bytes {
        if matches!(b, b' ' | b'\t' | b'\r') {
            if in_token {
                match number.value() {
                    Some(w) => out.push(w),
                    None => return false,
                }
                number = obj::Decimal::default();
                in_token = false;
            }
        } else if number.push(b) {
            in_token = true;
        } else {
            return false;
        }
    }
    if in_token {
        match number.value() {
            Some(w) => out.push(w),
            None => return false,
        }
    }
    true
}

/// Checks that `parents` is one tree rooted at joint 0 with at least one bone; returns a
/// parents-first order, or the joint to blame (if any) and the problem.
pub(super) fn check_topology(
    parents: &[Option<usize>],
) -> Result<Vec<usize>, (Option<usize>, Problem)> {
    let count = parents.len();
    if count == 0 {
        return Err((None, Hierarchy::NoJoints.into()));
    }
    for (j, parent) in parents.iter().enumerate() {
        match *parent {
            Some(p) if p >= count => {
                return Err((
                    Some(j),
                    Hierarchy::ParentMissing {
                        joint: j,
                        parent: p,
                        count,
                    }
                    .into(),
                ))
            }
            Some(p) if p == j => return Err((Some(j), Hierarchy::SelfParent(j).into())),
            _ => {}
        }
    }
    let order = parents_first_order(parents).map_err(|problems| {
        let first = problems.iter().find_map(|p| match p {
            rigport_model::SkeletonProblem::Cycle { joints } => joints.iter().min().copied(),
            _ => None,
        });
        (first, Problem::Skeleton(problems))
    })?;
    let mut roots = parents
        .iter()
        .enumerate()
        .filter(|(_, p)| p.is_none())
        .map(|(j, _)| j);
    match (roots.next(), roots.next()) {
        (Some(0), None) => {}
        (Some(first), Some(second)) => {
            return Err((
                Some(second),
                Hierarchy::SecondPinocchioRoot { first, second }.into(),
            ))
        }
        (Some(root), None) => {
            let parent = parents.first().copied().flatten().unwrap_or(0);
            return Err((Some(0), Hierarchy::RootNotFirst { parent, root }.into()));
        }
        // Every finite parent graph without a root has a cycle, reported above.
        (None, _) => return Err((None, Hierarchy::NoRootJoint.into())),
    }
    if count < 2 {
        return Err((Some(0), Hierarchy::OnlyRoot.into()));
    }
    Ok(order)
}
