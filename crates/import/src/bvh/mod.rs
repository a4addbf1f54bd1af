//! BioVision Hierarchy (BVH) motion capture: a joint hierarchy and one clip.
//!
//! # The file (FORMATS.md, BVH)
//! ```text
//! HIERARCHY
//! ROOT Hips
//! {
//!   OFFSET 0 0 0
//!   CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
//!   JOINT Spine
//!   {
//!     OFFSET 0 10 0
//!     CHANNELS 3 Zrotation Yrotation Xrotation
//!     End Site
//!     {
//!       OFFSET 0 5 0
//!     }
//!   }
//! }
//! MOTION
//! Frames: 2
//! Frame Time: 0.0333333
//! 0 90 0 0 0 0 0 0 0
//! 0 91 0 10 0 0 0 0 15
//! ```
//! - `HIERARCHY`, then one or more `ROOT` blocks (some writers emit several), then `MOTION`.
//! - A joint block is `ROOT|JOINT name`, `{`, `OFFSET x y z`, an optional
//!   `CHANNELS n name...` (any subset of the six channels, in any order, each at most
//!   once; a missing line means no channels), then any number of `JOINT` and `End Site`
//!   blocks, then `}`. An `End Site` block holds only `OFFSET x y z`. `OFFSET` and
//!   `CHANNELS` keep their values on their own line, as every writer does; the `{` may
//!   also end the name line.
//! - `MOTION` is followed by `Frames: N`, `Frame Time: dt` (seconds) and one line per frame
//!   holding every joint's channels, joints in file order, each joint's channels in its
//!   `CHANNELS` order.
//!
//! The reader is lenient where writers are known to differ (Blender, MotionBuilder, CMU
//! cgspeed, Bandai Namco, ...) and strict elsewhere: keywords, channel names
//! and the `Frames:` / `Frame Time:` labels are case-insensitive (`End Site`, `END SITE`,
//! `Frame time:`, `FrameTime:`), white space is any mix of spaces and tabs, lines may end
//! in CRLF (even mixed with LF, as the cgspeed files do), blank lines are skipped, and a
//! byte-order mark is ignored. A name of several words is joined with `_`, as Blender
//! does, with a [`Warning::Repaired`].
//!
//! Motion: a frame line with the wrong number of values, or a value that does not parse or
//! is not finite, is an error at that line, with one exception. When the file holds fewer frames than `Frames:` declares (a truncated file),
//! the complete frames are kept with a [`Warning::Incomplete`] naming both counts, and a
//! cut-off last line (fewer values than channels, or its last value cut mid-number) is
//! dropped. Lines after the declared frames are not read: a [`Warning::Repaired`] counts
//! them.
//!
//! # The asset rigport builds ([`to_asset`])
//! - Skeleton: every `ROOT`/`JOINT` in file order (asset joint `i` is [`Bvh::joints`]`[i]`),
//!   then every `End Site` in file order as a leaf joint named `<parent>_end`. Several
//!   `ROOT`s give several roots. Rest pose: translation = `OFFSET`, rotation identity,
//!   scale 1. Lengths stay in the file's unit ([`Asset::meters_per_unit`] is `None`: BVH
//!   does not say, and real files use centimetres, inches or metres).
//! - Names are made unique with a `_2`, `_3`, ... suffix. Duplicate joint names are
//!   unambiguous in BVH (channels are positional, never looked up by name), so they are
//!   renamed with a [`Warning::Repaired`] rather than rejected; an end site whose
//!   `<parent>_end` name is taken is suffixed silently (the name is rigport's own).
//! - One clip (named like the asset: the file stem for [`import`]), one LINEAR key per
//!   frame at `k * frame_time` seconds; no clip, with a [`Warning::Note`], when the file
//!   has no frames or no channels.
//!   Every joint with rotation channels gets a rotation track and every joint with
//!   position channels a translation track, one key per frame even where constant.
//! - A joint's local translation at a frame is its `OFFSET` with each present position
//!   channel **replacing** that axis (FORMATS.md: as Blender reads it). Its local
//!   rotation is the product of its rotation channels in listed order, in degrees:
//!   `Zrotation Xrotation Yrotation` is `R = Rz · Rx · Ry` (column vectors), i.e.
//!   [`EulerOrder::Yxz`](rigport_model::conventions::EulerOrder::Yxz). Quaternions are
//!   computed in `f64`, normalized, and made sign-continuous along the track (negated when
//!   the dot product with the previous key is negative), so LINEAR slerp takes the short
//!   way as the file's dense samples intend.
//!
//! ```
//! use std::path::Path;
//! use rigport_import::bvh;
//!
//! let text = "HIERARCHY\nROOT Hips\n{\n OFFSET 0 0 0\n CHANNELS 2 Yposition Zrotation\n \
//!             End Site\n {\n  OFFSET 0 1 0\n }\n}\nMOTION\nFrames: 2\nFrame Time: 0.5\n\
//!             3 0\n4 90\n";
//! let parsed = bvh::parse(text, Path::new("tiny.bvh"))?;
//! assert_eq!((parsed.frame_count, parsed.frame_time), (2, 0.5));
//! let imported = bvh::to_asset("tiny", &parsed)?;
//! let names: Vec<&str> =
//!     imported.asset.skeleton.joints().iter().map(|j| j.name.as_str()).collect();
//! assert_eq!(names, ["Hips", "Hips_end"]);
//! assert_eq!(imported.asset.clips[0].tracks.len(), 2);
//! # Ok::<(), rigport_import::ImportError>(())
//! ```

mod hierarchy;
mod motion;
mod parser;
#[cfg(test)]
mod tests;
mod tracks;
mod types;

pub use self::types::{Bvh, BvhEndSite, BvhJoint, Channel};

use std::borrow::Cow;
use std::collections::HashMap;
use std::path::Path;

use rigport_model::{Asset, Joint, JointIndex, Skeleton, Transform, Warning};

use crate::problem::{Hierarchy, Limit, Mismatch, Repeated, Rule};
use crate::{read_file, ImportError, Imported, Location, Problem};

use self::parser::keyword;
use self::parser::Parser;
use self::tracks::clip;
use crate::text::Cursor;

/// Imports a BVH file: the skeleton and one clip named after the file stem (see the
/// module docs for the mapping).
///
/// A file that is not UTF-8 (joint names in a legacy code page) is read with each invalid
/// sequence replaced by U+FFFD and a [`Warning::Repaired`] naming the line: the format's
/// structure is ASCII, so only names can suffer.
///
/// # Errors
/// The file cannot be read, or [`parse`] or [`to_asset`] fails.
pub fn import(path: &Path) -> Result<Imported, ImportError> {
    let bytes = read_file(path)?;
    let (text, repaired) = decode(&bytes, path);
    let bvh = parse(&text, path)?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut imported = to_asset(&name, &bvh)?;
    if let Some(w) = repaired {
        imported.warnings.insert(0, w);
    }
    Ok(imported)
}

/// The bytes as text: borrowed when UTF-8, else with U+FFFD replacements and a warning
/// at the line of the first invalid byte.
fn decode<'b>(bytes: &'b [u8], path: &Path) -> (Cow<'b, str>, Option<Warning>) {
    match std::str::from_utf8(bytes) {
        Ok(text) => (Cow::Borrowed(text), None),
        Err(e) => {
            let before = bytes.get(..e.valid_up_to()).unwrap_or_default();
            let line = 1 + before.iter().filter(|&&b| b == b'\n').count();
            let warning = Warning::Repaired {
                location: format!("{}:{line}", path.display()),
                message: "not UTF-8: invalid bytes were replaced by U+FFFD".into(),
            };
            (String::from_utf8_lossy(bytes), Some(warning))
        }
    }
}

/// Parses BVH text (see the module docs for the grammar and the leniencies).
///
/// Returns the file as written, with the [`Warning`]s of the parse in [`Bvh::warnings`]:
/// a multi-word name joined with `_`, fewer complete frames than declared, lines after the
/// declared frames.
///
/// # Errors
/// The first problem, at `file:line:column` where a token is to blame (`file:line` for a
/// whole line): an empty file ([`Problem::Empty`]); a missing or unknown keyword
/// (`expected OFFSET, found "CHANNELS"`); a number that does not parse, or is NaN or
/// infinite; a `CHANNELS` count above 6 or different from the names listed; an unknown or
/// repeated channel name; a missing `{` or `}`; anything but `ROOT` or `MOTION` after a
/// root's `}`; a missing or malformed `Frames:` / `Frame Time:` line; a `Frame Time` that
/// is not > 0; a frame line with the wrong number of values (unless it is the cut-off last
/// line of a truncated file). The file ending early in the hierarchy or before the motion
/// header is [`Problem::UnexpectedEnd`] ([`Problem::Truncated`] inside a joint block).
/// Lines end at LF, CRLF or a lone CR.
pub fn parse(text: &str, path: &Path) -> Result<Bvh, ImportError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut p = Parser {
        path,
        cur: Cursor::new(text),
        last_line: 1,
        joints: Vec::new(),
        end_sites: Vec::new(),
        channel_total: 0,
        warnings: Vec::new(),
    };
    match p.next() {
        None => return Err(ImportError::new(Location::file(path), Problem::Empty)),
        Some(t) if keyword(t, "HIERARCHY") => {}
        Some(t) => return Err(p.syntax(t, "HIERARCHY")),
    }
    let motion_line = loop {
        let expected = if p.joints.is_empty() {
            "ROOT"
        } else {
            "ROOT or MOTION"
        };
        let t = p.expect(expected)?;
        if keyword(t, "ROOT") {
            p.hierarchy(t)?;
        } else if keyword(t, "MOTION") && !p.joints.is_empty() {
            break t.line;
        } else {
            return Err(p.syntax(t, expected));
        }
    };
    if let Some(t) = p.cur.next_on_line() {
        return Err(p.syntax(t, "the end of the line after MOTION"));
    }
    let rest = p.cur.text.get(p.cur.pos..).unwrap_or_default();
    let motion = p.motion(rest, motion_line)?;
    Ok(Bvh {
        path: path.to_path_buf(),
        joints: p.joints,
        end_sites: p.end_sites,
        frames_declared: motion.frames_declared,
        frame_count: motion.frame_count,
        frame_time: motion.frame_time,
        motion: motion.values,
        motion_line,
        warnings: p.warnings,
    })
}

/// Builds the asset of a parsed file (see the module docs): skeleton, one clip named
/// `name` (when the file has frames and channels), no meshes, `meters_per_unit` unset.
///
/// Warnings come in order: those of the parse ([`Bvh::warnings`]), renamed duplicate
/// joint names, and a [`Warning::Note`] when there is no clip (no frames or no channels).
///
/// # Errors
/// At the file (and the joint's line where one is to blame), for a [`Bvh`] whose public
/// fields break the invariants [`parse`] guarantees: a parent that is not an earlier joint,
/// a repeated channel kind, a `first_channel` other than the count of earlier channels,
/// `motion.len() != frame_count * channel_count`, a `frame_time` that is not a finite
/// positive number, more than `u32::MAX` joints; also non-finite offsets or values
/// ([`Problem::Skeleton`] or [`Problem::Invalid`]), and a frame time so small that
/// `f32` key times would not increase.
pub fn to_asset(name: &str, bvh: &Bvh) -> Result<Imported, ImportError> {
    let path = bvh.path.as_path();
    let at_line = |line: usize| {
        if line > 0 {
            Location::line(path, line)
        } else {
            Location::file(path)
        }
    };
    let channel_count = check(bvh, &at_line)?;
    let mut warnings = bvh.warnings.clone();

    let total = bvh.joints.len() + bvh.end_sites.len();
    let joint_index = |i: usize| {
        u32::try_from(i)
            .map(JointIndex)
            .map_err(|_| ImportError::at(Location::file(path), Limit::SkeletonJoints(total)))
    };
    // Each name given so far and the line of the joint holding it.
    let mut taken: HashMap<String, usize> = HashMap::with_capacity(total);
    let mut joints = Vec::with_capacity(total);
    for j in &bvh.joints {
        let unique = unique_name(&j.name, j.line, &mut taken);
        if unique != j.name {
            let first = taken.get(&j.name).copied().unwrap_or_default();
            warnings.push(Warning::Repaired {
                location: format!("{}:{}", path.display(), j.line),
                message: format!(
                    "joint name {:?} is also used at line {first}: renamed {unique:?}",
                    j.name
                ),
            });
        }
        joints.push(Joint {
            name: unique,
            parent: j.parent.map(joint_index).transpose()?,
            rest_local: Transform::from_translation(j.offset),
        });
    }
    for e in &bvh.end_sites {
        let parent_name = joints
            .get(e.parent)
            .map(|p: &Joint| p.name.as_str())
            .unwrap_or_default();
        let unique = unique_name(&format!("{parent_name}_end"), e.line, &mut taken);
        joints.push(Joint {
            name: unique,
            parent: Some(joint_index(e.parent)?),
            rest_local: Transform::from_translation(e.offset),
        });
    }
    let skeleton = Skeleton::new(joints)
        .map_err(|problems| ImportError::new(Location::file(path), Problem::Skeleton(problems)))?;

    let mut clips = Vec::new();
    if bvh.frame_count > 0 && channel_count > 0 {
        clips.push(clip(name, bvh, channel_count, &at_line)?);
    } else {
        warnings.push(Warning::Note {
            location: format!("{}:{}", path.display(), bvh.motion_line),
            message: if channel_count == 0 {
                "no joint has channels: the asset has no clip".into()
            } else {
                "no frames: the asset has no clip".into()
            },
        });
    }
    let asset = Asset {
        name: name.to_string(),
        skeleton,
        clips,
        meters_per_unit: None,
        ..Asset::default()
    };
    crate::check_asset(&asset, || Location::file(path))?;
    Ok(Imported { asset, warnings })
}

/// Checks the invariants [`parse`] guarantees on a possibly hand-built [`Bvh`]; returns
/// the channel count.
fn check(bvh: &Bvh, at_line: &dyn Fn(usize) -> Location) -> Result<usize, ImportError> {
    let mut channels = 0_usize;
    for (i, j) in bvh.joints.iter().enumerate() {
        if let Some(p) = j.parent {
            if p >= i {
                return Err(ImportError::at(
                    at_line(j.line),
                    Hierarchy::ParentNotEarlier {
                        joint: i,
                        name: j.name.clone(),
                        parent: p,
                    },
                ));
            }
        }
        if j.first_channel != channels {
            return Err(ImportError::at(
                at_line(j.line),
                Mismatch::FirstChannel {
                    joint: j.name.clone(),
                    first: j.first_channel,
                    before: channels,
                },
            ));
        }
        for (k, c) in j.channels.iter().enumerate() {
            if j.channels.get(..k).is_some_and(|before| before.contains(c)) {
                return Err(ImportError::at(
                    at_line(j.line),
                    Repeated::JointChannel {
                        joint: j.name.clone(),
                        channel: c.name(),
                    },
                ));
            }
        }
        channels += j.channels.len();
    }
    if let Some(e) = bvh.end_sites.iter().find(|e| e.parent >= bvh.joints.len()) {
        return Err(ImportError::at(
            at_line(e.line),
            Hierarchy::EndSiteJoint {
                joint: e.parent,
                count: bvh.joints.len(),
            },
        ));
    }
    if !(bvh.frame_time.is_finite() && bvh.frame_time > 0.0) {
        return Err(ImportError::at(
            at_line(bvh.motion_line),
            Rule::FrameTime(format!("{:?}", bvh.frame_time)),
        ));
    }
    if bvh.frame_count.checked_mul(channels) != Some(bvh.motion.len()) {
        return Err(ImportError::at(
            at_line(bvh.motion_line),
            Mismatch::MotionValues {
                values: bvh.motion.len(),
                frames: bvh.frame_count,
                channels,
            },
        ));
    }
    Ok(channels)
}

/// `name`, or `name_2`, `name_3`, ... (the first not yet taken); records it as taken by
/// the joint at `line`.
fn unique_name(name: &str, line: usize, taken: &mut HashMap<String, usize>) -> String {
    let mut candidate = name.to_string();
    let mut k = 2_usize;
    while taken.contains_key(&candidate) {
        candidate = format!("{name}_{k}");
        k += 1;
    }
    taken.insert(candidate.clone(), line);
    candidate
}
