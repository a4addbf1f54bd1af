//! The AMC parser: header lines, then frames of `bone v1 v2 ...` lines.

use std::collections::HashMap;
use std::ops::Range;
use std::path::Path;

use crate::problem::{Mismatch, Rule};
use crate::{text, ImportError, Location, Problem};

use super::lines::{column, content, duplicate, line_error, number, syntax, Lines};
use super::types::{Amc, AmcFrame, AngleUnit, Asf, HeldValue, Skipped};

/// Parses an AMC motion of `asf`. `path` is used in messages and kept in [`Amc::path`].
///
/// A frame's bone lines may come in any order. A bone (or the root) with dofs that a frame
/// does not list takes its values from the frame before (all zeros, the rest pose, in the
/// first frame) and is recorded in [`Amc::held`]. Frame numbers are kept as written; they
/// need not be consecutive.
///
/// # Errors
/// At the offending line (and column for a bad token): a line before the first frame that
/// is not a `:` header line; a second `:DEGREES` / `:RADIANS` that contradicts the first; a
/// header line after the first frame; a frame number that does not fit `u64`; a bone line
/// before the first frame number; a bone the ASF lacks; a bone listed twice in one frame;
/// a value count other than the bone's dof count (the message names the bone and its
/// dofs); a value that is not a finite number. A file with no content is
/// [`Problem::Empty`]; one with no frame is [`Problem::Truncated`].
pub fn parse_amc(text: &str, path: &Path, asf: &Asf) -> Result<Amc, ImportError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let ranges = asf.channel_ranges();
    let channels = asf.channel_count();
    let node_count = ranges.len();
    let names: HashMap<&str, usize> = asf
        .bones
        .iter()
        .enumerate()
        .map(|(b, bone)| (bone.name.as_str(), b + 1))
        .collect();
    let mut amc = Amc {
        path: path.to_path_buf(),
        angle: None,
        fully_specified: false,
        header: Vec::new(),
        frames: Vec::new(),
        channels,
        values: Vec::new(),
        held: Vec::new(),
    };
    // The line each node was given on in the current frame (0: not given).
    let mut given = vec![0_usize; node_count];
    let mut angle_line = 0;
    let mut any = false;
    let mut last_line = 0;
    for (line_no, raw) in Lines::new(text) {
        last_line = line_no;
        let line = content(raw);
        if line.is_empty() {
            continue;
        }
        any = true;
        if let Some(keyword) = line.strip_prefix(':') {
            if !amc.frames.is_empty() {
                return Err(ImportError::syntax(
                    Location::line(path, line_no),
                    "a frame number or a bone line (`:` header lines come before the first frame)",
                    line,
                ));
            }
            let unit = if keyword.eq_ignore_ascii_case("degrees") {
                Some(AngleUnit::Degrees)
            } else if keyword.eq_ignore_ascii_case("radians") {
                Some(AngleUnit::Radians)
            } else {
                None
            };
            match unit {
                Some(unit) => {
                    if amc.angle.is_some_and(|previous| previous != unit) {
                        return Err(line_error(
                            path,
                            line_no,
                            Rule::AngleUnit {
                                line: line.to_string(),
                                first_line: angle_line,
                            },
                        ));
                    }
                    amc.angle = Some(unit);
                    angle_line = line_no;
                }
                None if keyword.eq_ignore_ascii_case("fully-specified") => {
                    amc.fully_specified = true
                }
                None => amc.header.push(Skipped {
                    keyword: line.to_string(),
                    line: line_no,
                }),
            }
            continue;
        }
        let mut tokens = line.split_ascii_whitespace();
        let Some(first) = tokens.next() else {
            continue;
        };
        let alone = tokens.clone().next().is_none();
        if alone && first.bytes().all(|b| b.is_ascii_digit()) {
            let number: u64 = text::number(first, "frame number", || {
                text::at(path, line_no, raw, first)
            })?;
            close_frame(&mut amc, &given, &ranges);
            given.fill(0);
            // A new frame starts as a copy of the previous one, so bones it does not list
            // hold their values; the first starts at the rest pose (all dofs 0).
            let end = amc.values.len();
            match end.checked_sub(channels) {
                Some(start) if !amc.frames.is_empty() => amc.values.extend_from_within(start..end),
                _ => amc.values.resize(end + channels, 0.0),
            }
            amc.frames.push(AmcFrame {
                number,
                line: line_no,
            });
            continue;
        }
        let node = if first.eq_ignore_ascii_case("root") {
            0
        } else if let Some(&node) = names.get(first) {
            node
        } else if alone && first.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '+') {
            return Err(syntax(
                path,
                line_no,
                raw,
                first,
                "a frame number (a non-negative integer)",
            ));
        } else {
            return Err(ImportError::new(
                Location::line_column(path, line_no, column(raw, first)),
                Problem::UnknownName {
                    what: "bone",
                    name: first.to_string(),
                    within: format!("the skeleton {}", asf.path.display()),
                },
            ));
        };
        let Some(frame) = amc.frames.last() else {
            return Err(line_error(
                path,
                line_no,
                Rule::BeforeFirstFrame(first.to_string()),
            ));
        };
        let frame_number = frame.number;
        if let Some(slot) = given.get_mut(node) {
            if *slot != 0 {
                return Err(duplicate(
                    path,
                    line_no,
                    format!("{first:?} in frame {frame_number}"),
                    *slot,
                ));
            }
            *slot = line_no;
        }
        let range = ranges.get(node).cloned().unwrap_or(0..0);
        let frame_start = (amc.frames.len() - 1) * channels;
        let slots = amc
            .values
            .get_mut(frame_start + range.start..frame_start + range.end)
            .unwrap_or_default();
        let expected = slots.len();
        let mut count = 0;
        for token in tokens {
            if let Some(slot) = slots.get_mut(count) {
                *slot = number(path, line_no, raw, token, "dof value")?;
            }
            count += 1;
        }
        if count != expected {
            let dofs = if node == 0 {
                &asf.root.order
            } else {
                asf.bones
                    .get(node - 1)
                    .map(|b| &b.dofs)
                    .unwrap_or(&asf.root.order)
            };
            return Err(line_error(
                path,
                line_no,
                Mismatch::BoneValues {
                    bone: first.to_string(),
                    count,
                    dofs: dofs.iter().map(|d| d.as_str()).collect(),
                    expected,
                },
            ));
        }
    }
    close_frame(&mut amc, &given, &ranges);
    if !any {
        return Err(ImportError::new(Location::file(path), Problem::Empty));
    }
    if amc.frames.is_empty() {
        return Err(ImportError::new(
            Location::line(path, last_line),
            Problem::Truncated("the file ends before its first frame".into()),
        ));
    }
    Ok(amc)
}

/// Records in [`Amc::held`] the nodes with dofs that the last frame did not give (they kept
/// the values copied from the frame before). `given` holds each node's line, 0 if absent.
fn close_frame(amc: &mut Amc, given: &[usize], ranges: &[Range<usize>]) {
    let Some(frame) = amc.frames.len().checked_sub(1) else {
        return;
    };
    for (node, (&line, range)) in given.iter().zip(ranges).enumerate() {
        if line == 0 && !range.is_empty() {
            amc.held.push(HeldValue {
                frame,
                bone: node.checked_sub(1),
            });
        }
    }
}
