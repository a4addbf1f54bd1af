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

use std::borrow::Cow;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{DQuat, DVec3, Vec3};
use rigport_model::{
    Asset, Clip, Interpolation, Joint, JointIndex, Skeleton, Track, TrackTarget, Transform, Warning,
};

use crate::{number, read_file, ImportError, Imported, Location, Problem};

/// One BVH channel: a position or rotation about one axis of the joint's parent frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Channel {
    /// Local translation along x, in the file's length unit (replaces `OFFSET.x`).
    Xposition,
    /// Local translation along y, in the file's length unit (replaces `OFFSET.y`).
    Yposition,
    /// Local translation along z, in the file's length unit (replaces `OFFSET.z`).
    Zposition,
    /// Rotation about x, in degrees.
    Xrotation,
    /// Rotation about y, in degrees.
    Yrotation,
    /// Rotation about z, in degrees.
    Zrotation,
}

impl Channel {
    /// All six channels.
    pub const ALL: [Channel; 6] = [
        Channel::Xposition,
        Channel::Yposition,
        Channel::Zposition,
        Channel::Xrotation,
        Channel::Yrotation,
        Channel::Zrotation,
    ];

    /// Parses a channel name as written after `CHANNELS` (`Xrotation`; case-insensitive).
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL
            .into_iter()
            .find(|c| c.name().eq_ignore_ascii_case(name))
    }

    /// The name as BVH writers spell it (`"Xrotation"`).
    pub fn name(self) -> &'static str {
        match self {
            Channel::Xposition => "Xposition",
            Channel::Yposition => "Yposition",
            Channel::Zposition => "Zposition",
            Channel::Xrotation => "Xrotation",
            Channel::Yrotation => "Yrotation",
            Channel::Zrotation => "Zrotation",
        }
    }

    /// The axis: 0 for x, 1 for y, 2 for z.
    pub fn axis(self) -> usize {
        match self {
            Channel::Xposition | Channel::Xrotation => 0,
            Channel::Yposition | Channel::Yrotation => 1,
            Channel::Zposition | Channel::Zrotation => 2,
        }
    }

    /// Whether this is a rotation channel (degrees) rather than a position channel.
    pub fn is_rotation(self) -> bool {
        matches!(
            self,
            Channel::Xrotation | Channel::Yrotation | Channel::Zrotation
        )
    }
}

/// A `ROOT` or `JOINT` as written in the file.
#[derive(Clone, Debug, PartialEq)]
pub struct BvhJoint {
    /// The name (several words joined with `_`); not necessarily unique.
    pub name: String,
    /// The enclosing joint, an index into [`Bvh::joints`] smaller than this joint's own;
    /// `None` for a `ROOT`.
    pub parent: Option<usize>,
    /// `OFFSET`: the rest translation from the parent, in the parent's frame and the
    /// file's length unit.
    pub offset: Vec3,
    /// The channels in file order (0 to 6, each kind at most once).
    pub channels: Vec<Channel>,
    /// Index of this joint's first value within a frame of [`Bvh::motion`]: the number of
    /// channels of the joints before it.
    pub first_channel: usize,
    /// 1-based line of the `ROOT`/`JOINT` keyword.
    pub line: usize,
}

/// An `End Site`: a fixed point (no channels) in its joint's frame.
#[derive(Clone, Debug, PartialEq)]
pub struct BvhEndSite {
    /// The joint whose block holds it, an index into [`Bvh::joints`].
    pub parent: usize,
    /// `OFFSET` from the parent, in the parent's frame and the file's length unit.
    pub offset: Vec3,
    /// 1-based line of the `End Site` keyword.
    pub line: usize,
}

/// A BVH file as written: hierarchy, channel layout and motion values.
///
/// Built by [`parse`]; [`to_asset`] turns it into a rig model (and re-checks the
/// invariants below, since the fields are public).
#[derive(Clone, Debug, PartialEq)]
pub struct Bvh {
    /// The file it came from (for messages).
    pub path: PathBuf,
    /// `ROOT`s and `JOINT`s in file order (depth-first, so parents come first).
    pub joints: Vec<BvhJoint>,
    /// `End Site`s in file order.
    pub end_sites: Vec<BvhEndSite>,
    /// The count `Frames:` declares.
    pub frames_declared: usize,
    /// Complete frames held in [`Bvh::motion`]: `frames_declared`, or fewer when the file
    /// is truncated.
    pub frame_count: usize,
    /// `Frame Time:` in seconds, finite and > 0.
    pub frame_time: f64,
    /// The channel values, flat and frame-major: frame `k` is
    /// `motion[k * C..(k + 1) * C]` with `C` = [`Bvh::channel_count`]; positions in the
    /// file's length unit, rotations in degrees.
    pub motion: Vec<f32>,
    /// 1-based line of the `MOTION` keyword.
    pub motion_line: usize,
    /// What the parse repaired or dropped (multi-word names, truncated or extra frames);
    /// [`to_asset`] passes them on first.
    pub warnings: Vec<Warning>,
}

impl Bvh {
    /// Values per frame: the number of channels of all joints.
    pub fn channel_count(&self) -> usize {
        self.joints.iter().map(|j| j.channels.len()).sum()
    }

    /// Frame `k`'s values ([`Bvh::channel_count`] of them), or `None` past the last frame.
    pub fn frame(&self, k: usize) -> Option<&[f32]> {
        let c = self.channel_count();
        self.motion
            .get(k.checked_mul(c)?..k.checked_add(1)?.checked_mul(c)?)
    }
}

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
/// header is [`Problem::Truncated`].
pub fn parse(text: &str, path: &Path) -> Result<Bvh, ImportError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut p = Parser {
        path,
        cur: Cursor {
            text,
            pos: 0,
            line: 1,
            line_start: 0,
        },
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
        u32::try_from(i).map(JointIndex).map_err(|_| {
            ImportError::invalid(
                Location::file(path),
                format!("{total} joints: more than a skeleton can index"),
            )
        })
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
    if let Err(errors) = asset.validate() {
        let text: Vec<String> = errors.iter().map(ToString::to_string).collect();
        return Err(ImportError::invalid(Location::file(path), text.join("; ")));
    }
    Ok(Imported { asset, warnings })
}

/// Checks the invariants [`parse`] guarantees on a possibly hand-built [`Bvh`]; returns
/// the channel count.
fn check(bvh: &Bvh, at_line: &dyn Fn(usize) -> Location) -> Result<usize, ImportError> {
    let mut channels = 0_usize;
    for (i, j) in bvh.joints.iter().enumerate() {
        if let Some(p) = j.parent {
            if p >= i {
                return Err(ImportError::invalid(
                    at_line(j.line),
                    format!(
                        "joint {i} ({:?}) names parent {p}, which is not an earlier joint",
                        j.name
                    ),
                ));
            }
        }
        if j.first_channel != channels {
            return Err(ImportError::invalid(
                at_line(j.line),
                format!(
                    "joint {:?} starts at channel {} but the joints before it have {channels}",
                    j.name, j.first_channel
                ),
            ));
        }
        for (k, c) in j.channels.iter().enumerate() {
            if j.channels.get(..k).is_some_and(|before| before.contains(c)) {
                return Err(ImportError::invalid(
                    at_line(j.line),
                    format!("joint {:?} lists channel {} twice", j.name, c.name()),
                ));
            }
        }
        channels += j.channels.len();
    }
    if let Some(e) = bvh.end_sites.iter().find(|e| e.parent >= bvh.joints.len()) {
        return Err(ImportError::invalid(
            at_line(e.line),
            format!(
                "the end site names joint {}, but there are {} joints",
                e.parent,
                bvh.joints.len()
            ),
        ));
    }
    if !(bvh.frame_time.is_finite() && bvh.frame_time > 0.0) {
        return Err(ImportError::invalid(
            at_line(bvh.motion_line),
            format!(
                "Frame Time {:?} is not a number of seconds > 0",
                bvh.frame_time
            ),
        ));
    }
    if bvh.frame_count.checked_mul(channels) != Some(bvh.motion.len()) {
        return Err(ImportError::invalid(
            at_line(bvh.motion_line),
            format!(
                "{} motion values for {} frames of {channels} channels",
                bvh.motion.len(),
                bvh.frame_count
            ),
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

/// The clip of a checked [`Bvh`] with at least one frame and one channel.
fn clip(
    name: &str,
    bvh: &Bvh,
    channel_count: usize,
    at_line: &dyn Fn(usize) -> Location,
) -> Result<Clip, ImportError> {
    let frames = bvh.frame_count;
    // Computed in f64 and rounded once, so long clips do not accumulate error.
    let times: Vec<f32> = (0..frames)
        .map(|k| (k as f64 * bvh.frame_time) as f32)
        .collect();
    if times.windows(2).any(|w| w[1] <= w[0]) {
        return Err(ImportError::invalid(
            at_line(bvh.motion_line),
            format!(
                "Frame Time {:?} s is too small for {frames} frames to get increasing f32 key times",
                bvh.frame_time
            ),
        ));
    }
    let broken = |j: &BvhJoint| {
        ImportError::invalid(
            at_line(j.line),
            format!("the motion has no values for joint {:?}", j.name),
        )
    };
    let joints = &bvh.joints;
    // Joints' tracks are independent: a large clip builds them on two threads, the joints
    // split where half the channels are done, and keeps them in joint order.
    let tracks = if bvh.motion.len() >= PARALLEL_TRACK_VALUES && joints.len() >= 2 {
        let half = channel_count / 2;
        let mid = joints
            .iter()
            .position(|j| j.first_channel >= half)
            .unwrap_or(joints.len())
            .clamp(1, joints.len() - 1);
        let (first, second) = joints.split_at(mid);
        let (a, b) = crate::join(
            || joint_tracks(bvh, 0, first, channel_count, &times),
            || joint_tracks(bvh, mid, second, channel_count, &times),
        );
        let mut tracks = a.map_err(broken)?;
        tracks.extend(b.map_err(broken)?);
        tracks
    } else {
        joint_tracks(bvh, 0, joints, channel_count, &times).map_err(broken)?
    };
    Ok(Clip {
        name: name.to_string(),
        tracks,
    })
}

/// Clips of at least this many values build their tracks on two threads.
const PARALLEL_TRACK_VALUES: usize = 16 * 1024;

/// The translation and rotation tracks of `joints`, the joints of `bvh` from index `first`
/// on (in joint order, translation first), keyed at `times`. `Err(joint)`: the joint's
/// channels lie outside the frame values, or its index does not fit a [`JointIndex`].
fn joint_tracks<'b>(
    bvh: &Bvh,
    first: usize,
    joints: &'b [BvhJoint],
    channel_count: usize,
    times: &[f32],
) -> Result<Vec<Track>, &'b BvhJoint> {
    let frames = times.len();
    let mut tracks = Vec::new();
    for (i, joint) in (first..).zip(joints) {
        let index = JointIndex(u32::try_from(i).map_err(|_| joint)?);
        let range = joint.first_channel..joint.first_channel + joint.channels.len();
        // The joint's channels by kind, as (index within the joint's values, axis), in file
        // order: worked out once rather than per frame.
        let positions: Vec<(usize, usize)> = (joint.channels.iter().enumerate())
            .filter(|(_, c)| !c.is_rotation())
            .map(|(k, c)| (k, c.axis()))
            .collect();
        let rotations: Vec<(usize, DVec3)> = (joint.channels.iter().enumerate())
            .filter(|(_, c)| c.is_rotation())
            .map(|(k, c)| (k, AXES[c.axis()]))
            .collect();
        if !positions.is_empty() {
            let mut values = Vec::with_capacity(3 * frames);
            for frame in bvh.motion.chunks_exact(channel_count) {
                let own = frame.get(range.clone()).ok_or(joint)?;
                let mut t = joint.offset.to_array();
                for &(k, axis) in &positions {
                    if let (Some(slot), Some(&v)) = (t.get_mut(axis), own.get(k)) {
                        *slot = v;
                    }
                }
                values.extend_from_slice(&t);
            }
            tracks.push(Track {
                target: TrackTarget::Translation(index),
                interpolation: Interpolation::Linear,
                times: times.to_vec(),
                values,
            });
        }
        if !rotations.is_empty() {
            let mut values = Vec::with_capacity(4 * frames);
            let mut previous = DQuat::IDENTITY;
            for frame in bvh.motion.chunks_exact(channel_count) {
                let own = frame.get(range.clone()).ok_or(joint)?;
                let mut q = DQuat::IDENTITY;
                for &(k, axis) in &rotations {
                    if let Some(&v) = own.get(k) {
                        // The first listed rotation is the outermost: R = R1 · R2 · R3.
                        q *= DQuat::from_axis_angle(axis, f64::from(v).to_radians());
                    }
                }
                q = q.normalize();
                if previous.dot(q) < 0.0 {
                    q = -q;
                }
                previous = q;
                values.extend_from_slice(&q.as_quat().to_array());
            }
            tracks.push(Track {
                target: TrackTarget::Rotation(index),
                interpolation: Interpolation::Linear,
                times: times.to_vec(),
                values,
            });
        }
    }
    Ok(tracks)
}

/// Unit axes by [`Channel::axis`].
const AXES: [DVec3; 3] = [DVec3::X, DVec3::Y, DVec3::Z];

/// A white-space separated token of the hierarchy and where it starts.
#[derive(Clone, Copy, Debug)]
struct Token<'a> {
    text: &'a str,
    /// 1-based line.
    line: usize,
    /// Byte offsets of the line's start and the token's start in the text.
    line_start: usize,
    start: usize,
}

/// A position in the text that reads tokens, counting lines (`\n`; a `\r` is white space).
#[derive(Clone, Copy, Debug)]
struct Cursor<'a> {
    text: &'a str,
    pos: usize,
    line: usize,
    line_start: usize,
}

impl<'a> Cursor<'a> {
    fn token(&mut self, cross_lines: bool) -> Option<Token<'a>> {
        let bytes = self.text.as_bytes();
        while let Some(&b) = bytes.get(self.pos) {
            match b {
                b'\n' if cross_lines => {
                    self.pos += 1;
                    self.line += 1;
                    self.line_start = self.pos;
                }
                b'\n' => break,
                _ if b.is_ascii_whitespace() || b == 0x0b => self.pos += 1,
                _ => break,
            }
        }
        let start = self.pos;
        while bytes
            .get(self.pos)
            .is_some_and(|b| !b.is_ascii_whitespace() && *b != 0x0b)
        {
            self.pos += 1;
        }
        // Token bounds are ASCII bytes, hence char boundaries.
        let text = self.text.get(start..self.pos).filter(|t| !t.is_empty())?;
        Some(Token {
            text,
            line: self.line,
            line_start: self.line_start,
            start,
        })
    }

    /// The next token, on this line or a later one.
    fn next(&mut self) -> Option<Token<'a>> {
        self.token(true)
    }

    /// The next token if it is on the current line.
    fn next_on_line(&mut self) -> Option<Token<'a>> {
        self.token(false)
    }
}

/// Whether `t` is the keyword `word` (ASCII case-insensitive).
fn keyword(t: Token<'_>, word: &str) -> bool {
    t.text.eq_ignore_ascii_case(word)
}

/// 1-based column (in characters) of byte offset `at` on a line starting at `line_start`.
fn column(text: &str, line_start: usize, at: usize) -> usize {
    text.get(line_start..at)
        .map_or(1, |s| s.chars().count() + 1)
}

/// The motion section as read.
struct Motion {
    frames_declared: usize,
    frame_count: usize,
    frame_time: f64,
    values: Vec<f32>,
}

struct Parser<'a, 'p> {
    path: &'p Path,
    cur: Cursor<'a>,
    /// Line of the last token read (where an unexpected end of file is reported).
    last_line: usize,
    joints: Vec<BvhJoint>,
    end_sites: Vec<BvhEndSite>,
    channel_total: usize,
    warnings: Vec<Warning>,
}

impl<'a> Parser<'a, '_> {
    fn next(&mut self) -> Option<Token<'a>> {
        let t = self.cur.next();
        if let Some(t) = t {
            self.last_line = t.line;
        }
        t
    }

    fn next_on_line(&mut self) -> Option<Token<'a>> {
        let t = self.cur.next_on_line();
        if let Some(t) = t {
            self.last_line = t.line;
        }
        t
    }

    /// The next token, or a [`Problem::Truncated`] error naming what was expected.
    fn expect(&mut self, expected: &str) -> Result<Token<'a>, ImportError> {
        self.next().ok_or_else(|| {
            ImportError::new(
                Location::line(self.path, self.last_line),
                Problem::Truncated(format!("the file ends where {expected} was expected")),
            )
        })
    }

    /// The next token on the current line, or an error at `after` (the token the line's
    /// values belong to) naming what is missing.
    fn expect_on_line(
        &mut self,
        after: Token<'_>,
        expected: &str,
    ) -> Result<Token<'a>, ImportError> {
        self.next_on_line().ok_or_else(|| {
            ImportError::invalid(
                self.at(after),
                format!("{} needs {expected} on its line", after.text),
            )
        })
    }

    fn at(&self, t: Token<'_>) -> Location {
        Location::line_column(
            self.path,
            t.line,
            column(self.cur.text, t.line_start, t.start),
        )
    }

    fn syntax(&self, t: Token<'_>, expected: &str) -> ImportError {
        ImportError::syntax(self.at(t), expected, t.text)
    }

    /// A finite `f32`.
    fn number(&self, t: Token<'_>) -> Result<f32, ImportError> {
        let v = number::parse_f32(t.text).ok_or_else(|| self.syntax(t, "a number"))?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(ImportError::invalid(
                self.at(t),
                format!("{} is not a finite number", t.text),
            ))
        }
    }

    /// `OFFSET x y z` with nothing after it on the line.
    fn offset(&mut self) -> Result<Vec3, ImportError> {
        let kw = self.expect("OFFSET")?;
        if !keyword(kw, "OFFSET") {
            return Err(self.syntax(kw, "OFFSET"));
        }
        let mut xyz = [0.0_f32; 3];
        for v in &mut xyz {
            let t = self.expect_on_line(kw, "3 numbers")?;
            *v = self.number(t)?;
        }
        if let Some(t) = self.next_on_line() {
            return Err(self.syntax(t, "the end of the line after OFFSET's 3 numbers"));
        }
        Ok(Vec3::from_array(xyz))
    }

    /// `{`, unless it ended the previous line (`brace_seen`).
    fn open_brace(&mut self, brace_seen: bool) -> Result<(), ImportError> {
        if brace_seen {
            return Ok(());
        }
        let t = self.expect("{")?;
        if t.text == "{" {
            Ok(())
        } else {
            Err(self.syntax(t, "{"))
        }
    }

    /// A `ROOT` block and everything in it, `root` being the `ROOT` token. Iterative, so
    /// deep nesting cannot overflow the stack.
    fn hierarchy(&mut self, root: Token<'a>) -> Result<(), ImportError> {
        let mut open = vec![self.joint(root, None)?];
        while let Some(&j) = open.last() {
            let t = self.next().ok_or_else(|| {
                let (name, line) = self
                    .joints
                    .get(j)
                    .map_or(("", 0), |j| (j.name.as_str(), j.line));
                ImportError::new(
                    Location::line(self.path, self.last_line),
                    Problem::Truncated(format!(
                        "the file ends inside joint {name:?} (line {line}): expected JOINT, End Site or }}"
                    )),
                )
            })?;
            if keyword(t, "JOINT") {
                open.push(self.joint(t, Some(j))?);
            } else if keyword(t, "End") {
                self.end_site(t, j)?;
            } else if t.text == "}" {
                open.pop();
            } else {
                return Err(self.syntax(t, "JOINT, End Site or }"));
            }
        }
        Ok(())
    }

    /// A joint's header: name, `{`, `OFFSET`, optional `CHANNELS`. Returns its index.
    fn joint(&mut self, kw: Token<'a>, parent: Option<usize>) -> Result<usize, ImportError> {
        let mut words = Vec::new();
        while let Some(t) = self.next_on_line() {
            words.push(t);
        }
        let brace_seen = words.last().is_some_and(|t| t.text == "{");
        if brace_seen {
            words.pop();
        }
        if words.is_empty() {
            return Err(ImportError::invalid(
                self.at(kw),
                format!("{} needs a joint name on its line", kw.text),
            ));
        }
        let name = words.iter().map(|t| t.text).collect::<Vec<_>>().join("_");
        if words.len() > 1 {
            let written = words.iter().map(|t| t.text).collect::<Vec<_>>().join(" ");
            self.warnings.push(Warning::Repaired {
                location: format!("{}:{}", self.path.display(), kw.line),
                message: format!(
                    "joint name {written:?} has several words: named {name:?} (as Blender does)"
                ),
            });
        }
        self.open_brace(brace_seen)?;
        let offset = self.offset()?;
        let mut channels = Vec::new();
        let mut peek = self.cur;
        if let Some(t) = peek.next().filter(|t| keyword(*t, "CHANNELS")) {
            self.cur = peek;
            self.last_line = t.line;
            channels = self.channels(t)?;
        }
        let index = self.joints.len();
        self.joints.push(BvhJoint {
            name,
            parent,
            offset,
            first_channel: self.channel_total,
            line: kw.line,
            channels,
        });
        self.channel_total += self.joints.last().map_or(0, |j| j.channels.len());
        Ok(index)
    }

    /// The rest of a `CHANNELS n name...` line, `kw` being `CHANNELS`.
    fn channels(&mut self, kw: Token<'a>) -> Result<Vec<Channel>, ImportError> {
        let count_token = self.expect_on_line(kw, "a channel count")?;
        let count: usize = count_token
            .text
            .parse()
            .map_err(|_| self.syntax(count_token, "a channel count (0 to 6)"))?;
        if count > Channel::ALL.len() {
            return Err(ImportError::invalid(
                self.at(count_token),
                format!(
                    "CHANNELS {count}: a joint has at most 6 channels (3 positions, 3 rotations)"
                ),
            ));
        }
        let mut channels: Vec<Channel> = Vec::with_capacity(count);
        while channels.len() < count {
            let Some(t) = self.next_on_line() else {
                return Err(ImportError::invalid(
                    self.at(kw),
                    format!(
                        "CHANNELS {count} lists {} channel names on its line",
                        channels.len()
                    ),
                ));
            };
            let c = Channel::parse(t.text).ok_or_else(|| {
                self.syntax(
                    t,
                    "a channel name (Xposition, Yposition, Zposition, Xrotation, Yrotation or Zrotation)",
                )
            })?;
            if channels.contains(&c) {
                return Err(ImportError::invalid(
                    self.at(t),
                    format!("channel {} is listed twice", c.name()),
                ));
            }
            channels.push(c);
        }
        if let Some(t) = self.next_on_line() {
            return Err(if Channel::parse(t.text).is_some() {
                ImportError::invalid(
                    self.at(t),
                    format!("CHANNELS {count} lists more than {count} channel names"),
                )
            } else {
                self.syntax(t, "the end of the line after the channel names")
            });
        }
        Ok(channels)
    }

    /// An `End Site` block inside joint `parent`, `kw` being `End`.
    fn end_site(&mut self, kw: Token<'a>, parent: usize) -> Result<(), ImportError> {
        let site = self.expect_on_line(kw, "Site")?;
        if !keyword(site, "Site") {
            return Err(self.syntax(site, "Site"));
        }
        let brace_seen = match self.next_on_line() {
            None => false,
            Some(t) if t.text == "{" => true,
            Some(t) => return Err(self.syntax(t, "the end of the line after End Site")),
        };
        self.open_brace(brace_seen)?;
        let offset = self.offset()?;
        let close = self.expect("}")?;
        if close.text != "}" {
            return Err(self.syntax(close, "}"));
        }
        self.end_sites.push(BvhEndSite {
            parent,
            offset,
            line: kw.line,
        });
        Ok(())
    }

    /// Everything after the `MOTION` line: `rest` starts at the end of that line.
    fn motion(&mut self, rest: &str, motion_line: usize) -> Result<Motion, ImportError> {
        let path = self.path;
        let mut lines = rest.split('\n');
        // What is left of the MOTION line itself (checked blank by the caller).
        lines.next();
        let mut line_no = motion_line;
        // The last line holding text, where a file that ends early is reported.
        let mut last_text_line = motion_line;
        let mut header = |label: &str, expected: &str| {
            for line in lines.by_ref() {
                line_no += 1;
                if !line.trim_ascii().is_empty() {
                    last_text_line = line_no;
                    return header_value(line, label)
                        .map_err(|(col, found)| {
                            ImportError::syntax(
                                Location::line_column(path, line_no, col),
                                expected,
                                found,
                            )
                        })
                        .map(|(value, col)| (value, line_no, col));
                }
            }
            Err(ImportError::new(
                Location::line(path, last_text_line),
                Problem::Truncated(format!("the file ends where {expected} was expected")),
            ))
        };
        let (value, line, col) = header("frames", "`Frames: <count>`")?;
        let frames_declared: usize = value.parse().map_err(|_| {
            ImportError::syntax(
                Location::line_column(path, line, col),
                "a frame count (a whole number >= 0)",
                value,
            )
        })?;
        let (value, line, col) = header("frametime", "`Frame Time: <seconds>`")?;
        let frame_time: f64 = value.parse().map_err(|_| {
            ImportError::syntax(
                Location::line_column(path, line, col),
                "a frame time in seconds",
                value,
            )
        })?;
        if !(frame_time.is_finite() && frame_time > 0.0) {
            return Err(ImportError::invalid(
                Location::line_column(path, line, col),
                format!("Frame Time {value} is not a number of seconds > 0"),
            ));
        }

        let channels = self.channel_total;
        // Large, well-formed motion is read on two threads; anything unusual (a bad or
        // cut-off line, a frame count other than declared) takes the line-by-line path
        // below, which reports it.
        let data = lines
            .clone()
            .next()
            .and_then(|first| rest.get(offset_in(rest, first)?..));
        if let Some(values) = data.and_then(|d| frames_on_two_threads(d, channels, frames_declared))
        {
            return Ok(Motion {
                frames_declared,
                frame_count: frames_declared,
                frame_time,
                values,
            });
        }
        let location = |line: usize| format!("{}:{line}", path.display());
        // Reserve for the declared frames, but never more than the rest of the file can
        // hold (each value takes at least 2 bytes), so a huge `Frames:` cannot exhaust memory.
        let capacity = frames_declared
            .saturating_mul(channels)
            .min(rest.len() / 2 + 1);
        let mut values: Vec<f32> = Vec::with_capacity(capacity);
        // Frames of no values are blank lines: with no channels there is nothing to read,
        // and any text after the header is an extra line.
        let mut frame_count = if channels == 0 { frames_declared } else { 0 };
        let mut cut_off_line = None;
        let mut last_data_line = line_no;
        while frame_count < frames_declared {
            let Some(line) = lines.next() else { break };
            line_no += 1;
            if line.trim_ascii().is_empty() {
                continue;
            }
            let start = values.len();
            match frame_values(line, channels, &mut values) {
                Ok(()) => {
                    frame_count += 1;
                    last_data_line = line_no;
                }
                Err(bad) => {
                    let last = lines.clone().all(|l| l.trim_ascii().is_empty());
                    if last && bad.cut_off(channels) {
                        values.truncate(start);
                        cut_off_line = Some(line_no);
                        break;
                    }
                    return Err(bad.error(path, line_no, line, frame_count + 1, channels));
                }
            }
        }
        if frame_count < frames_declared {
            let dropped = match cut_off_line {
                Some(l) => format!(" (the cut-off frame at line {l} is dropped)"),
                None => String::new(),
            };
            self.warnings.push(Warning::Incomplete {
                location: location(cut_off_line.unwrap_or(last_data_line)),
                message: format!(
                    "`Frames: {frames_declared}` but the file holds {frame_count} complete frames{dropped}: the clip has {frame_count}"
                ),
            });
        } else {
            let mut extra = 0_usize;
            let mut first_extra = None;
            for l in lines {
                line_no += 1;
                if !l.trim_ascii().is_empty() {
                    extra += 1;
                    first_extra.get_or_insert(line_no);
                }
            }
            if let Some(first) = first_extra {
                self.warnings.push(Warning::Repaired {
                    location: location(first),
                    message: format!(
                        "{extra} lines after the {frames_declared} frames `Frames:` declares are ignored"
                    ),
                });
            }
        }
        Ok(Motion {
            frames_declared,
            frame_count,
            frame_time,
            values,
        })
    }
}

/// Motion text of at least this many bytes is read on two threads (below it, starting a
/// thread costs about what it saves).
const PARALLEL_MOTION_BYTES: usize = 64 * 1024;

/// The values of `data` (the frame lines after the motion header) read on two threads, when
/// `data` is large and holds exactly `frames` frame lines of `channels` finite values each
/// plus blank lines; `None` otherwise (the caller then reads it line by line and reports
/// what is wrong). Same values, bit for bit, as the line-by-line reader.
fn frames_on_two_threads(data: &str, channels: usize, frames: usize) -> Option<Vec<f32>> {
    if channels == 0 || data.len() < PARALLEL_MOTION_BYTES {
        return None;
    }
    // Cut after the line break nearest the middle: both halves hold whole lines.
    let mid = data.len() / 2;
    let cut = mid
        + 1
        + data
            .as_bytes()
            .get(mid..)?
            .iter()
            .position(|&b| b == b'\n')?;
    let (first, second) = (data.get(..cut)?, data.get(cut..)?);
    // Every value takes at least two bytes, so a half cannot hold more than len / 2 + 1.
    let capacity = frames.saturating_mul(channels).min(data.len() / 2 + 1);
    let read = |text: &str, capacity: usize| -> Option<(Vec<f32>, usize)> {
        let mut values = Vec::with_capacity(capacity);
        let mut count = 0_usize;
        for line in text.split('\n') {
            if !line.trim_ascii().is_empty() {
                frame_values(line, channels, &mut values).ok()?;
                count += 1;
            }
        }
        Some((values, count))
    };
    let (a, b) = crate::join(
        || read(first, capacity),
        || read(second, capacity.min(second.len() / 2 + 1)),
    );
    let ((mut values, count_a), (rest, count_b)) = (a?, b?);
    if count_a.checked_add(count_b)? != frames {
        return None;
    }
    values.extend_from_slice(&rest);
    Some(values)
}

/// Splits a `Frames: 20` / `Frame Time: 0.033` line: the label (before the first `:`, or
/// every token but the last when there is no colon) must equal `label` ignoring ASCII case
/// and white space, and the value must be one token. Returns the value and its 1-based
/// column, or the column and text to blame.
fn header_value<'l>(line: &'l str, label: &str) -> Result<(&'l str, usize), (usize, &'l str)> {
    let trimmed = line.trim_ascii();
    let (key, value) = match trimmed.split_once(':') {
        Some((key, value)) => (key, value.trim_ascii()),
        None => match trimmed.rsplit_once(|c: char| c.is_ascii_whitespace()) {
            Some((key, value)) => (key, value),
            None => (trimmed, ""),
        },
    };
    let mut key_chars = key.chars().filter(|c| !c.is_ascii_whitespace());
    let label_matches = label
        .chars()
        .all(|l| key_chars.next().is_some_and(|k| k.eq_ignore_ascii_case(&l)))
        && key_chars.next().is_none();
    let col = |s: &str| offset_in(line, s).map_or(1, |o| column(line, 0, o));
    if !label_matches || value.is_empty() || value.contains(|c: char| c.is_ascii_whitespace()) {
        return Err((col(trimmed), trimmed));
    }
    Ok((value, col(value)))
}

/// Byte offset of `sub` (a subslice of `outer`) within `outer`.
fn offset_in(outer: &str, sub: &str) -> Option<usize> {
    (sub.as_ptr() as usize).checked_sub(outer.as_ptr() as usize)
}

/// What is wrong with a frame line.
struct BadFrame<'l> {
    /// How many values the line has (counting all tokens).
    tokens: usize,
    /// The token that does not parse (or is not finite) and whether it is the line's last.
    bad: Option<(&'l str, bool)>,
}

impl BadFrame<'_> {
    /// Whether the line looks like the last line of a file cut short: fewer values than a
    /// frame and nothing wrong but possibly its last value (cut mid-number).
    fn cut_off(&self, channels: usize) -> bool {
        self.tokens <= channels
            && match self.bad {
                None => self.tokens < channels,
                Some((_, last)) => last,
            }
    }

    fn error(
        &self,
        path: &Path,
        line_no: usize,
        line: &str,
        frame: usize,
        channels: usize,
    ) -> ImportError {
        match self.bad {
            Some((token, _)) => {
                let col = offset_in(line, token).map_or(1, |o| column(line, 0, o));
                let location = Location::line_column(path, line_no, col);
                match token.parse::<f32>() {
                    Ok(_) => {
                        ImportError::invalid(location, format!("{token} is not a finite number"))
                    }
                    Err(_) => ImportError::syntax(location, "a number", token),
                }
            }
            None => ImportError::invalid(
                Location::line(path, line_no),
                format!(
                    "frame {frame} has {} values, expected {channels} (one per channel)",
                    self.tokens
                ),
            ),
        }
    }
}

/// Appends the values of one frame line to `out`; on error `out` may hold some of them.
fn frame_values<'l>(
    line: &'l str,
    channels: usize,
    out: &mut Vec<f32>,
) -> Result<(), BadFrame<'l>> {
    // One pass over the bytes: tokens are cut where `split_ascii_whitespace` cuts them and
    // read by `number::leading_f32`, which gives `str::parse::<f32>`'s bits.
    let mut rest = line;
    let mut n = 0_usize;
    loop {
        rest = rest.trim_ascii_start();
        if rest.is_empty() {
            break;
        }
        let (token, value) = number::leading_f32(rest);
        rest = rest.get(token.len()..).unwrap_or_default();
        n += 1;
        match value {
            Some(v) if v.is_finite() => out.push(v),
            _ => {
                let after = rest.split_ascii_whitespace().count();
                return Err(BadFrame {
                    tokens: n + after,
                    bad: Some((token, after == 0)),
                });
            }
        }
    }
    if n == channels {
        Ok(())
    } else {
        Err(BadFrame {
            tokens: n,
            bad: None,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DMat3, DMat4, Mat4, Quat};
    use rigport_model::conventions::EulerOrder;

    const FIXTURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/bvh");
    const CORPUS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared/corpus/4_bvh");
    const CORPUS_FILES: [&str; 4] = [
        "bandai_namco_ds1/dataset-1_dash_normal_001.bvh",
        "bandai_namco_ds1/dataset-1_kick_normal_001.bvh",
        "bandai_namco_ds1/dataset-1_walk_normal_002.bvh",
        "cmu_cgspeed__nobuyuki83_delfem2/walk.bvh",
    ];
    const KICK: &str = "bandai_namco_ds1/dataset-1_kick_normal_001.bvh";

    /// Lines: 1 HIERARCHY, 2 ROOT, 3 {, 4 OFFSET, 5 CHANNELS, 6 JOINT, 7 {, 8 OFFSET,
    /// 9 CHANNELS, 10 End Site, 11 {, 12 OFFSET, 13 }, 14 }, 15 }, 16 MOTION, 17 Frames,
    /// 18 Frame Time, 19-20 frames.
    const BASE: &str = "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 3 Zrotation Xrotation Yrotation\n  JOINT Spine\n  {\n    OFFSET 0 1 0\n    CHANNELS 1 Xrotation\n    End Site\n    {\n      OFFSET 0 1 0\n    }\n  }\n}\nMOTION\nFrames: 2\nFrame Time: 0.5\n1 2 3 4\n5 6 7 8\n";

    /// `BASE` with its 1-based line `n` replaced by `with` (which may hold several lines).
    fn base_with(n: usize, with: &str) -> String {
        BASE.split('\n')
            .enumerate()
            .map(|(i, l)| if i + 1 == n { with } else { l })
            .collect::<Vec<_>>()
            .join("\n")
    }

    fn parse_str(text: &str) -> Result<Bvh, ImportError> {
        parse(text, Path::new("t.bvh"))
    }

    fn err(text: &str) -> String {
        match parse_str(text) {
            Ok(b) => panic!("parsed: {b:?}"),
            Err(e) => e.to_string(),
        }
    }

    fn fixture(name: &str) -> (Bvh, Imported) {
        let path = Path::new(FIXTURES).join(name);
        let text = std::fs::read_to_string(&path).unwrap();
        let bvh = parse(&text, &path).unwrap_or_else(|e| panic!("{e}"));
        let imported = import(&path).unwrap_or_else(|e| panic!("{e}"));
        (bvh, imported)
    }

    /// FORMATS.md evaluated directly from the parsed channels, in f64 matrices: world
    /// positions of the joints, then of the end sites.
    fn reference_positions(bvh: &Bvh, k: usize) -> Vec<DVec3> {
        let frame = bvh.frame(k).unwrap();
        let mut world: Vec<DMat4> = Vec::new();
        for j in &bvh.joints {
            let mut t = j.offset.as_dvec3();
            let mut r = DMat3::IDENTITY;
            for (i, c) in j.channels.iter().enumerate() {
                let v = f64::from(frame[j.first_channel + i]);
                match c {
                    Channel::Xposition => t.x = v,
                    Channel::Yposition => t.y = v,
                    Channel::Zposition => t.z = v,
                    Channel::Xrotation => r *= DMat3::from_rotation_x(v.to_radians()),
                    Channel::Yrotation => r *= DMat3::from_rotation_y(v.to_radians()),
                    Channel::Zrotation => r *= DMat3::from_rotation_z(v.to_radians()),
                }
            }
            let local = DMat4::from_translation(t) * DMat4::from_mat3(r);
            world.push(match j.parent {
                Some(p) => world[p] * local,
                None => local,
            });
        }
        let mut out: Vec<DVec3> = world.iter().map(|m| m.w_axis.truncate()).collect();
        for e in &bvh.end_sites {
            out.push(world[e.parent].transform_point3(e.offset.as_dvec3()));
        }
        out
    }

    /// World positions of every asset joint at key `k`: rest transforms overridden by the
    /// clip's key `k` values, composed in f32.
    fn asset_positions(asset: &Asset, k: usize) -> Vec<Vec3> {
        let mut locals: Vec<Transform> = asset
            .skeleton
            .joints()
            .iter()
            .map(|j| j.rest_local)
            .collect();
        if let Some(clip) = asset.clips.first() {
            for track in &clip.tracks {
                let v = track.key_value(k);
                match track.target {
                    TrackTarget::Translation(j) => {
                        locals[j.get()].translation = Vec3::from_slice(v)
                    }
                    TrackTarget::Rotation(j) => locals[j.get()].rotation = Quat::from_slice(v),
                    _ => panic!("unexpected track {:?}", track.target),
                }
            }
        }
        let mut world: Vec<Mat4> = Vec::new();
        for (joint, local) in asset.skeleton.joints().iter().zip(&locals) {
            let m = local.to_mat4();
            world.push(match joint.parent {
                Some(p) => world[p.get()] * m,
                None => m,
            });
        }
        world.iter().map(|m| m.w_axis.truncate()).collect()
    }

    /// Checks the imported asset against the parsed file on every frame: FK against the
    /// reference, constant bone lengths for joints without position channels, unit and
    /// sign-continuous rotation keys, key times. Returns the largest position error
    /// relative to the figure's extent.
    fn check_asset(bvh: &Bvh, imported: &Imported, label: &str) -> f64 {
        let asset = &imported.asset;
        assert!(asset.validate().is_ok(), "{label}");
        assert_eq!(asset.meters_per_unit, None);
        assert_eq!(
            asset.skeleton.len(),
            bvh.joints.len() + bvh.end_sites.len(),
            "{label}"
        );
        let clip = &asset.clips[0];
        let rotations = bvh
            .joints
            .iter()
            .filter(|j| j.channels.iter().any(|c| c.is_rotation()))
            .count();
        let positions = bvh
            .joints
            .iter()
            .filter(|j| j.channels.iter().any(|c| !c.is_rotation()))
            .count();
        assert_eq!(clip.tracks.len(), rotations + positions, "{label}");
        for track in &clip.tracks {
            assert_eq!(track.interpolation, Interpolation::Linear);
            assert_eq!(track.times.len(), bvh.frame_count, "{label}");
            for (k, t) in track.times.iter().enumerate() {
                assert!(
                    (f64::from(*t) - k as f64 * bvh.frame_time).abs()
                        < 1e-6 * (1.0 + f64::from(*t))
                );
            }
            if let TrackTarget::Rotation(_) = track.target {
                for w in track.values.chunks_exact(4).collect::<Vec<_>>().windows(2) {
                    let (a, b) = (Quat::from_slice(w[0]), Quat::from_slice(w[1]));
                    assert!((b.length() - 1.0).abs() < 1e-6, "{label}: {b}");
                    assert!(a.dot(b) >= 0.0, "{label}: sign flip {a} -> {b}");
                }
            }
        }
        // Which asset joints keep a fixed distance to their parent.
        let rigid: Vec<bool> = bvh
            .joints
            .iter()
            .map(|j| j.parent.is_some() && j.channels.iter().all(|c| c.is_rotation()))
            .chain(bvh.end_sites.iter().map(|_| true))
            .collect();
        let mut worst = 0.0_f64;
        for k in 0..bvh.frame_count {
            let expected = reference_positions(bvh, k);
            let got = asset_positions(asset, k);
            let extent = expected
                .iter()
                .fold(1.0_f64, |m, p| m.max(p.abs().max_element()));
            for (i, (e, g)) in expected.iter().zip(&got).enumerate() {
                let error = (g.as_dvec3() - *e).length() / extent;
                worst = worst.max(error);
                // f32 composition of ~10 transforms of values up to `extent`: a few ulps
                // each (1 ulp = 6e-8 relative).
                assert!(
                    error < 2e-6,
                    "{label} frame {k} joint {i} ({}): {g} vs {e}, relative error {error:e}",
                    asset.skeleton.joints()[i].name
                );
            }
            for (i, joint) in asset.skeleton.joints().iter().enumerate() {
                if let (true, Some(p)) = (rigid[i], joint.parent) {
                    let length = (got[i] - got[p.get()]).length();
                    let rest = joint.rest_local.translation.length();
                    assert!(
                        (length - rest).abs() <= 2e-6 * extent as f32,
                        "{label} frame {k}: bone {} has length {length}, rest {rest}",
                        joint.name
                    );
                }
            }
        }
        worst
    }

    #[test]
    fn fixtures_match_reference_fk() {
        for (name, frames, frame_time) in [
            ("mixed_orders.bvh", 4, 0.04),
            ("crlf_tabs.bvh", 4, 0.04),
            ("joint_positions.bvh", 3, 0.0333333),
            ("end_sites.bvh", 2, 0.1),
            ("multiple_roots.bvh", 2, 0.5),
            ("duplicate_names.bvh", 1, 0.04),
            ("truncated.bvh", 3, 0.04),
            ("extra_frames.bvh", 2, 0.04),
        ] {
            let (bvh, imported) = fixture(name);
            assert_eq!(
                (bvh.frame_count, bvh.frame_time),
                (frames, frame_time),
                "{name}"
            );
            assert_eq!(imported.asset.name, name.trim_end_matches(".bvh"));
            assert_eq!(imported.asset.clips[0].name, imported.asset.name);
            let worst = check_asset(&bvh, &imported, name);
            println!("{name}: largest relative FK error {worst:e}");
        }
    }

    #[test]
    fn quirks_fixture_imports_like_the_plain_one() {
        let (plain_bvh, plain) = fixture("mixed_orders.bvh");
        let (quirky_bvh, quirky) = fixture("crlf_tabs.bvh");
        assert!(plain.warnings.is_empty() && quirky.warnings.is_empty());
        assert_eq!(plain_bvh.motion, quirky_bvh.motion);
        assert_eq!(plain.asset.skeleton, quirky.asset.skeleton);
        assert_eq!(plain.asset.clips[0].tracks, quirky.asset.clips[0].tracks);
        let names: Vec<&str> = plain
            .asset
            .skeleton
            .joints()
            .iter()
            .map(|j| j.name.as_str())
            .collect();
        assert_eq!(
            names,
            [
                "Hips",
                "Spine",
                "Head",
                "LeftLeg",
                "LeftFoot",
                "RightLeg",
                "Head_end",
                "LeftFoot_end",
                "RightLeg_end"
            ]
        );
        let lines: Vec<usize> = plain_bvh.joints.iter().map(|j| j.line).collect();
        assert_eq!(lines, [2, 6, 10, 20, 24, 34]);
        assert_eq!(plain_bvh.motion_line, 44);
    }

    #[test]
    fn rotation_channels_multiply_in_listed_order() {
        // R = Rz(90) · Rx(90): the end site (0, 1, 0) goes to Rz·(0, 0, 1) = (0, 0, 1).
        // The other order, Rx·Rz, would give (-1, 0, 0).
        let text = "HIERARCHY\nROOT A\n{\n OFFSET 0 0 0\n CHANNELS 2 Zrotation Xrotation\n End Site\n {\n  OFFSET 0 1 0\n }\n}\nMOTION\nFrames: 1\nFrame Time: 1\n90 90\n";
        let asset = to_asset("r", &parse_str(text).unwrap()).unwrap().asset;
        let end = asset_positions(&asset, 0)[1];
        assert!(end.abs_diff_eq(Vec3::Z, 1e-6), "{end}");
        // The model's conventions name `Zrotation Xrotation Yrotation` Yxz.
        let (bvh, imported) = fixture("mixed_orders.bvh");
        let hips = &imported.asset.clips[0].tracks[1];
        assert_eq!(hips.target, TrackTarget::Rotation(JointIndex(0)));
        for k in 0..bvh.frame_count {
            let [z, x, y] = bvh.frame(k).unwrap()[3..6] else {
                unreachable!()
            };
            let expected = EulerOrder::Yxz.to_quat_deg([x, y, z]);
            let got = Quat::from_slice(hips.key_value(k));
            assert!(
                got.dot(expected).abs() > 1.0 - 1e-6,
                "{k}: {got} vs {expected}"
            );
        }
    }

    #[test]
    fn position_channels_replace_the_offset() {
        let (bvh, imported) = fixture("joint_positions.bvh");
        let asset = &imported.asset;
        let hips = asset.skeleton.find("Hips").unwrap();
        assert_eq!(
            asset.skeleton.joint(hips).rest_local.translation,
            Vec3::new(0.0, 90.0, -3.0)
        );
        let track = |target| {
            asset.clips[0]
                .tracks
                .iter()
                .find(|t| t.target == target)
                .unwrap()
        };
        assert_eq!(
            track(TrackTarget::Translation(hips)).key_value(1),
            [0.5, 88.0, -2.5]
        );
        // Tail has only Yposition: x and z stay the OFFSET's.
        let tail = asset.skeleton.find("Tail").unwrap();
        assert_eq!(bvh.joints[tail.get()].channels[1], Channel::Yposition);
        assert_eq!(
            track(TrackTarget::Translation(tail)).key_value(1),
            [-10.0, 2.0, 0.0]
        );
        // Its rotation skips the position channel: Zrotation 45, Xrotation -30, Yrotation 60.
        let expected = EulerOrder::Yxz.to_quat_deg([-30.0, 60.0, 45.0]);
        let got = Quat::from_slice(track(TrackTarget::Rotation(tail)).key_value(1));
        assert!(got.dot(expected).abs() > 1.0 - 1e-6, "{got} vs {expected}");
    }

    #[test]
    fn fixture_features() {
        let names = |i: &Imported| -> Vec<String> {
            i.asset
                .skeleton
                .joints()
                .iter()
                .map(|j| j.name.clone())
                .collect()
        };
        let (bvh, ends) = fixture("end_sites.bvh");
        assert!(ends.warnings.is_empty(), "{:?}", ends.warnings);
        assert_eq!(
            names(&ends),
            [
                "Hips",
                "Head",
                "Head_end",
                "Hand",
                "Antenna",
                "Head_end_2",
                "Head_end_end",
                "Hand_end",
                "Hand_end_2"
            ]
        );
        let parents: Vec<usize> = bvh.end_sites.iter().map(|e| e.parent).collect();
        assert_eq!(parents, [1, 2, 3, 3]);
        let skeleton = &ends.asset.skeleton;
        assert_eq!(skeleton.joint(JointIndex(7)).parent, Some(JointIndex(3)));
        assert_eq!(
            skeleton.joint(JointIndex(8)).rest_local.translation,
            Vec3::new(1.0, 1.0, 0.0)
        );

        let (_, roots) = fixture("multiple_roots.bvh");
        let roots: Vec<&str> = roots
            .asset
            .skeleton
            .roots()
            .map(|r| roots.asset.skeleton.joint(r).name.as_str())
            .collect();
        assert_eq!(roots, ["Body", "Prop"]);

        let (_, dup) = fixture("duplicate_names.bvh");
        assert_eq!(
            names(&dup),
            ["Hips", "Arm", "Arm_2", "Arm_end", "Arm_2_end"]
        );
        assert_eq!(dup.warnings.len(), 1);
        assert!(
            dup.warnings[0].to_string().ends_with(
                "duplicate_names.bvh:15: repaired: joint name \"Arm\" is also used at line 6: renamed \"Arm_2\""
            ),
            "{}",
            dup.warnings[0]
        );

        let (bvh, truncated) = fixture("truncated.bvh");
        assert_eq!((bvh.frames_declared, bvh.frame_count), (5, 3));
        assert_eq!(bvh.motion.len(), 27);
        assert_eq!(truncated.warnings.len(), 1);
        let Warning::Incomplete { location, message } = &truncated.warnings[0] else {
            panic!("{:?}", truncated.warnings)
        };
        assert!(location.ends_with("truncated.bvh:22"), "{location}");
        assert_eq!(
            message,
            "`Frames: 5` but the file holds 3 complete frames (the cut-off frame at line 22 is dropped): the clip has 3"
        );

        let (bvh, extra) = fixture("extra_frames.bvh");
        assert_eq!((bvh.frames_declared, bvh.frame_count), (2, 2));
        assert_eq!(bvh.motion, [0.0, 0.0, 0.0, 10.0, 0.0, 0.0]);
        assert_eq!(extra.warnings.len(), 1);
        assert!(
            extra.warnings[0].to_string().ends_with(
                "extra_frames.bvh:17: repaired: 2 lines after the 2 frames `Frames:` declares are ignored"
            ),
            "{}",
            extra.warnings[0]
        );
    }

    #[test]
    fn lenient_where_writers_differ() {
        // Multi-word names are joined as Blender does; `{` may end the name line; labels
        // vary in case and spacing; a frame count of 0 gives a skeleton without a clip.
        let text = "\u{feff}hierarchy\r\nroot Left Hip {\r\n\toffset 1 2 3\r\n\tchannels 1 XROTATION\r\n\tend site {\r\n\t\tOFFSET 0 1 0\r\n\t}\r\n}\r\nmotion\r\nFRAMES:0\r\nFrameTime 0.01\r\n";
        let bvh = parse_str(text).unwrap();
        assert_eq!(bvh.joints[0].name, "Left_Hip");
        assert_eq!(bvh.joints[0].channels, [Channel::Xrotation]);
        assert_eq!((bvh.frames_declared, bvh.frame_time), (0, 0.01));
        assert_eq!(
            bvh.warnings,
            [Warning::Repaired {
                location: "t.bvh:2".into(),
                message: "joint name \"Left Hip\" has several words: named \"Left_Hip\" (as Blender does)".into()
            }]
        );
        let imported = to_asset("x", &bvh).unwrap();
        assert!(imported.asset.clips.is_empty());
        assert_eq!(
            imported.warnings.last().unwrap().to_string(),
            "t.bvh:9: no frames: the asset has no clip"
        );
        // Joints without CHANNELS lines: frames are blank lines.
        let static_only =
            "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\n}\nMOTION\nFrames: 3\nFrame Time: 1\n\n\n\n";
        let bvh = parse_str(static_only).unwrap();
        assert_eq!((bvh.frame_count, bvh.channel_count()), (3, 0));
        let imported = to_asset("s", &bvh).unwrap();
        assert!(imported.asset.clips.is_empty());
        assert_eq!(imported.asset.skeleton.len(), 1);
    }

    #[test]
    fn names_are_made_unique_and_decoded() {
        // A later joint literally named like a renamed one is renamed too.
        let text = "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nJOINT A\n{\nOFFSET 1 0 0\n}\nJOINT A_2\n{\nOFFSET 2 0 0\n}\n}\nMOTION\nFrames: 1\nFrame Time: 1\n\nstray\n";
        let imported = to_asset("n", &parse_str(text).unwrap()).unwrap();
        let names: Vec<&str> = imported
            .asset
            .skeleton
            .joints()
            .iter()
            .map(|j| j.name.as_str())
            .collect();
        assert_eq!(names, ["A", "A_2", "A_2_2"]);
        let warnings: Vec<String> = imported.warnings.iter().map(|w| w.to_string()).collect();
        assert_eq!(
            warnings,
            [
                "t.bvh:18: repaired: 1 lines after the 1 frames `Frames:` declares are ignored",
                "t.bvh:5: repaired: joint name \"A\" is also used at line 2: renamed \"A_2\"",
                "t.bvh:9: repaired: joint name \"A_2\" is also used at line 5: renamed \"A_2_2\"",
                "t.bvh:14: no joint has channels: the asset has no clip",
            ]
        );
        // Latin-1 names: replaced, with a warning at the line.
        let latin1 = b"HIERARCHY\nROOT H\xfcfte\n";
        let (text, warning) = decode(latin1, Path::new("l.bvh"));
        assert_eq!(text, "HIERARCHY\nROOT H\u{fffd}fte\n");
        assert_eq!(
            warning.unwrap().to_string(),
            "l.bvh:2: repaired: not UTF-8: invalid bytes were replaced by U+FFFD"
        );
        assert!(decode(b"ok", Path::new("l.bvh")).1.is_none());
    }

    #[test]
    fn deep_nesting_does_not_overflow() {
        let depth = 20_000;
        let mut text = String::from("HIERARCHY\n");
        for i in 0..depth {
            text += &format!(
                "{} J{i}\n{{\nOFFSET 0 1 0\nCHANNELS 1 Zrotation\n",
                if i == 0 { "ROOT" } else { "JOINT" }
            );
        }
        text += &"}\n".repeat(depth);
        text += "MOTION\nFrames: 1\nFrame Time: 1\n";
        text += &"1 ".repeat(depth);
        let bvh = parse_str(&text).unwrap();
        assert_eq!(bvh.joints.len(), depth);
        assert_eq!(bvh.joints[depth - 1].parent, Some(depth - 2));
        let asset = to_asset("deep", &bvh).unwrap().asset;
        assert_eq!(asset.skeleton.len(), depth);
    }

    #[test]
    fn hierarchy_errors_name_line_and_column() {
        let cases: &[(String, &str)] = &[
            ("".into(), "t.bvh: the file is empty"),
            (" \r\n\n".into(), "t.bvh: the file is empty"),
            ("ROOT Hips\n".into(), "t.bvh:1:1: expected HIERARCHY, found \"ROOT\""),
            (base_with(2, "JOINT Hips"), "t.bvh:2:1: expected ROOT, found \"JOINT\""),
            (base_with(2, "MOTION"), "t.bvh:2:1: expected ROOT, found \"MOTION\""),
            (base_with(2, "ROOT"), "t.bvh:2:1: ROOT needs a joint name on its line"),
            (base_with(2, "ROOT {"), "t.bvh:2:1: ROOT needs a joint name on its line"),
            (base_with(3, "  ["), "t.bvh:3:3: expected {, found \"[\""),
            (base_with(4, "    CHANNELS 0"), "t.bvh:4:5: expected OFFSET, found \"CHANNELS\""),
            (base_with(4, "  OFFSET 0 1.2.3 0"), "t.bvh:4:12: expected a number, found \"1.2.3\""),
            (base_with(4, "  OFFSET 0 inf 0"), "t.bvh:4:12: inf is not a finite number"),
            (base_with(4, "  OFFSET 0 0\n 0"), "t.bvh:4:3: OFFSET needs 3 numbers on its line"),
            (base_with(4, "  OFFSET 0 0 0 0"), "t.bvh:4:16: expected the end of the line after OFFSET's 3 numbers, found \"0\""),
            (base_with(5, "  CHANNELS"), "t.bvh:5:3: CHANNELS needs a channel count on its line"),
            (base_with(5, "  CHANNELS three Zrotation"), "t.bvh:5:12: expected a channel count (0 to 6), found \"three\""),
            (base_with(5, "  CHANNELS 7 Zrotation"), "t.bvh:5:12: CHANNELS 7: a joint has at most 6 channels (3 positions, 3 rotations)"),
            (base_with(5, "  CHANNELS 3 Zrotation Xrotation"), "t.bvh:5:3: CHANNELS 3 lists 2 channel names on its line"),
            (base_with(5, "  CHANNELS 2 Zrotation Xrotation Yrotation"), "t.bvh:5:34: CHANNELS 2 lists more than 2 channel names"),
            (base_with(5, "  CHANNELS 2 Zrotation Xrotation JOINT"), "t.bvh:5:34: expected the end of the line after the channel names, found \"JOINT\""),
            (base_with(5, "  CHANNELS 3 Zrotation Xscale Yrotation"), "t.bvh:5:24: expected a channel name (Xposition, Yposition, Zposition, Xrotation, Yrotation or Zrotation), found \"Xscale\""),
            (base_with(5, "  CHANNELS 3 Zrotation Xrotation zROTATION"), "t.bvh:5:34: channel Zrotation is listed twice"),
            (base_with(6, "  JOIN Spine"), "t.bvh:6:3: expected JOINT, End Site or }, found \"JOIN\""),
            (base_with(10, "    End"), "t.bvh:10:5: End needs Site on its line"),
            (base_with(10, "    End Sight"), "t.bvh:10:9: expected Site, found \"Sight\""),
            (base_with(10, "    End Site Tip"), "t.bvh:10:14: expected the end of the line after End Site, found \"Tip\""),
            (base_with(13, "      CHANNELS 0\n    }"), "t.bvh:13:7: expected }, found \"CHANNELS\""),
            // Unbalanced braces: one too many, one missing (MOTION inside a joint), and
            // the file ending inside a joint.
            (base_with(15, "}\n}"), "t.bvh:16:1: expected ROOT or MOTION, found \"}\""),
            (base_with(15, ""), "t.bvh:16:1: expected JOINT, End Site or }, found \"MOTION\""),
            (BASE.split("}\n}\nMOTION").next().unwrap().to_string(), "t.bvh:13: truncated: the file ends inside joint \"Spine\" (line 6): expected JOINT, End Site or }"),
            (BASE.split("MOTION").next().unwrap().to_string(), "t.bvh:15: truncated: the file ends where ROOT or MOTION was expected"),
            (base_with(16, "MOTION 3"), "t.bvh:16:8: expected the end of the line after MOTION, found \"3\""),
        ];
        for (text, expected) in cases {
            assert_eq!(&err(text), expected, "{text}");
        }
    }

    /// `BASE`'s hierarchy with `frames` frame lines (`Frames:` says `declared`), large
    /// enough past a few thousand frames for the two-thread reader.
    fn long_motion(frames: usize, declared: usize) -> String {
        let mut text = BASE.split("Frames").next().unwrap().to_string();
        text.push_str(&format!("Frames: {declared}\nFrame Time: 0.01\n"));
        for k in 0..frames {
            let a = k as f32 * 0.37;
            text.push_str(&format!("{a} {} -{} {}e-1\r\n", a * 2.0, k % 91, k));
            if k % 1000 == 7 {
                text.push_str("  \n");
            }
        }
        text
    }

    /// Large motion read on two threads equals the line-by-line reading, value for value;
    /// a bad, cut-off or extra line in either half is still reported at its own line.
    #[test]
    fn two_thread_motion_equals_line_by_line() {
        let text = long_motion(6000, 6000);
        let body = &text[text.find("Frame Time").unwrap()..];
        let data = &body[body.find('\n').unwrap() + 1..];
        assert!(data.len() >= 2 * PARALLEL_MOTION_BYTES);
        let fast = frames_on_two_threads(data, 4, 6000).expect("the two-thread path applies");
        let mut slow = Vec::new();
        for line in data.split('\n').filter(|l| !l.trim_ascii().is_empty()) {
            frame_values(line, 4, &mut slow).unwrap_or_else(|_| panic!("{line}"));
        }
        assert_eq!(fast.len(), 6000 * 4);
        assert!(fast
            .iter()
            .zip(&slow)
            .all(|(a, b)| a.to_bits() == b.to_bits()));
        let bvh = parse_str(&text).unwrap();
        assert_eq!((bvh.frames_declared, bvh.frame_count), (6000, 6000));
        assert!(bvh.warnings.is_empty());
        assert!(bvh
            .motion
            .iter()
            .zip(&slow)
            .all(|(a, b)| a.to_bits() == b.to_bits()));

        // Not the declared count, or a bad line in the second half: the line-by-line path
        // takes over and says where.
        assert!(frames_on_two_threads(data, 4, 5999).is_none());
        let bvh = parse_str(&long_motion(6000, 5000)).unwrap();
        assert_eq!(bvh.frame_count, 5000);
        assert!(
            matches!(&bvh.warnings[..], [Warning::Repaired { message, .. }]
            if message.starts_with("1000 lines after the 5000 frames"))
        );
        let bvh = parse_str(&long_motion(5000, 6000)).unwrap();
        assert_eq!(bvh.frame_count, 5000);
        assert!(matches!(&bvh.warnings[..], [Warning::Incomplete { .. }]));
        let lines: Vec<&str> = text.split('\n').collect();
        let bad_line = lines.len() - 100;
        let mut broken = lines.clone();
        broken[bad_line - 1] = "1 2 x 4";
        assert_eq!(
            err(&broken.join("\n")),
            format!("t.bvh:{bad_line}:5: expected a number, found \"x\"")
        );
    }

    #[test]
    fn motion_errors_name_line_and_column() {
        let cases: &[(String, &str)] = &[
            (
                BASE.split("Frames").next().unwrap().to_string(),
                "t.bvh:16: truncated: the file ends where `Frames: <count>` was expected",
            ),
            (
                base_with(17, "Frame: 2"),
                "t.bvh:17:1: expected `Frames: <count>`, found \"Frame: 2\"",
            ),
            (
                base_with(17, "Frames:"),
                "t.bvh:17:1: expected `Frames: <count>`, found \"Frames:\"",
            ),
            (
                base_with(17, "Frames: 2 3"),
                "t.bvh:17:1: expected `Frames: <count>`, found \"Frames: 2 3\"",
            ),
            (
                base_with(17, "Frames:\t-2"),
                "t.bvh:17:9: expected a frame count (a whole number >= 0), found \"-2\"",
            ),
            (
                base_with(17, "Frames: 2.0"),
                "t.bvh:17:9: expected a frame count (a whole number >= 0), found \"2.0\"",
            ),
            (
                base_with(18, "Frame Rate: 0.5"),
                "t.bvh:18:1: expected `Frame Time: <seconds>`, found \"Frame Rate: 0.5\"",
            ),
            (
                base_with(18, "Frame Time: fast"),
                "t.bvh:18:13: expected a frame time in seconds, found \"fast\"",
            ),
            (
                base_with(18, "Frame Time: 0"),
                "t.bvh:18:13: Frame Time 0 is not a number of seconds > 0",
            ),
            (
                base_with(18, "Frame Time: -0.1"),
                "t.bvh:18:13: Frame Time -0.1 is not a number of seconds > 0",
            ),
            (
                base_with(18, "Frame Time: NaN"),
                "t.bvh:18:13: Frame Time NaN is not a number of seconds > 0",
            ),
            (
                base_with(18, "Frame Time: inf"),
                "t.bvh:18:13: Frame Time inf is not a number of seconds > 0",
            ),
            // A wrong value count anywhere but a truncated file's last line.
            (
                base_with(19, "1 2 3"),
                "t.bvh:19: frame 1 has 3 values, expected 4 (one per channel)",
            ),
            (
                base_with(19, "1 2 3 4 5"),
                "t.bvh:19: frame 1 has 5 values, expected 4 (one per channel)",
            ),
            (
                base_with(20, "5 6 7 8 9"),
                "t.bvh:20: frame 2 has 5 values, expected 4 (one per channel)",
            ),
            (
                base_with(19, "1 x 3 4"),
                "t.bvh:19:3: expected a number, found \"x\"",
            ),
            (
                base_with(19, "1 2 NaN 4"),
                "t.bvh:19:5: NaN is not a finite number",
            ),
            (
                base_with(19, "1 2 3 1e39"),
                "t.bvh:19:7: 1e39 is not a finite number",
            ),
            // The last line has a bad value that is not its last: corruption, not a cut.
            (
                base_with(20, "5 6 x 8"),
                "t.bvh:20:5: expected a number, found \"x\"",
            ),
        ];
        for (text, expected) in cases {
            assert_eq!(&err(text), expected, "{text}");
        }
        // A short or cut last line of a truncated file is dropped with a warning.
        for last in ["5 6 7", "5 6 7 8.5e", "5"] {
            let bvh = parse_str(&base_with(20, last)).unwrap();
            assert_eq!((bvh.frames_declared, bvh.frame_count), (2, 1), "{last}");
            assert_eq!(bvh.motion, [1.0, 2.0, 3.0, 4.0]);
            assert_eq!(
                bvh.warnings,
                [Warning::Incomplete {
                    location: "t.bvh:20".into(),
                    message: "`Frames: 2` but the file holds 1 complete frames (the cut-off frame at line 20 is dropped): the clip has 1".into()
                }]
            );
        }
        // The file ends after the header: no frames, an incomplete warning, no clip.
        let bvh = parse_str(BASE.split("1 2 3 4").next().unwrap()).unwrap();
        assert_eq!(bvh.frame_count, 0);
        assert_eq!(
            bvh.warnings[0].to_string(),
            "t.bvh:18: `Frames: 2` but the file holds 0 complete frames: the clip has 0"
        );
        assert!(to_asset("e", &bvh).unwrap().asset.clips.is_empty());
    }

    #[test]
    fn to_asset_rejects_inconsistent_structs() {
        let good = parse_str(BASE).unwrap();
        let reject = |edit: &dyn Fn(&mut Bvh), expected: &str| {
            let mut bvh = good.clone();
            edit(&mut bvh);
            assert_eq!(to_asset("x", &bvh).unwrap_err().to_string(), expected);
        };
        reject(
            &|b| b.joints[0].parent = Some(1),
            "t.bvh:2: joint 0 (\"Hips\") names parent 1, which is not an earlier joint",
        );
        reject(
            &|b| b.joints[1].first_channel = 0,
            "t.bvh:6: joint \"Spine\" starts at channel 0 but the joints before it have 3",
        );
        reject(
            &|b| b.joints[0].channels[2] = Channel::Zrotation,
            "t.bvh:2: joint \"Hips\" lists channel Zrotation twice",
        );
        reject(
            &|b| b.end_sites[0].parent = 2,
            "t.bvh:10: the end site names joint 2, but there are 2 joints",
        );
        reject(
            &|b| b.motion.push(0.0),
            "t.bvh:16: 9 motion values for 2 frames of 4 channels",
        );
        reject(
            &|b| b.frame_time = 0.0,
            "t.bvh:16: Frame Time 0.0 is not a number of seconds > 0",
        );
        reject(
            &|b| b.joints[1].offset.x = f32::NAN,
            "t.bvh: invalid skeleton: joint 1 (\"Spine\") has a non-finite rest transform",
        );
        reject(
            &|b| b.motion[7] = f32::INFINITY,
            "t.bvh: clip \"x\" track 1: has a non-finite value",
        );
        reject(
            &|b| b.frame_time = 1e-46,
            "t.bvh:16: Frame Time 1e-46 s is too small for 2 frames to get increasing f32 key times",
        );
        // Also works on a hand-built struct.
        assert!(to_asset("x", &good).is_ok());
    }

    proptest::proptest! {
        #[test]
        fn never_panics_on_edited_fixtures(
            which in 0_usize..4,
            edits in proptest::collection::vec(
                (proptest::num::usize::ANY, 0_u8..3, proptest::sample::select(
                    b"0123456789 .-+eE{}\n\r\tXYZxyzrotpsinOFSETJMRC:".to_vec()
                )),
                0..6,
            ),
            cut in proptest::num::usize::ANY,
        ) {
            let sources = [
                include_str!("../../../fixtures/bvh/mixed_orders.bvh"),
                include_str!("../../../fixtures/bvh/joint_positions.bvh"),
                include_str!("../../../fixtures/bvh/end_sites.bvh"),
                include_str!("../../../fixtures/bvh/crlf_tabs.bvh"),
            ];
            let mut bytes = sources[which].as_bytes().to_vec();
            for (at, op, byte) in edits {
                let i = at % (bytes.len() + 1);
                match op {
                    0 if i < bytes.len() => bytes[i] = byte,
                    1 => bytes.insert(i, byte),
                    _ if i < bytes.len() => {
                        bytes.remove(i);
                    }
                    _ => {}
                }
            }
            bytes.truncate(cut % (bytes.len() + 1));
            let text = String::from_utf8_lossy(&bytes);
            if let Ok(bvh) = parse(&text, Path::new("p.bvh")) {
                let _ = to_asset("p", &bvh);
            }
        }
    }

    /// `Frames:` and `Frame Time:` read from the text independently of the parser.
    fn header(text: &str) -> (usize, f64) {
        let value = |label: &str| {
            text.lines()
                .find_map(|l| l.trim().strip_prefix(label))
                .unwrap()
                .trim()
                .to_string()
        };
        (
            value("Frames:").parse().unwrap(),
            value("Frame Time:").parse().unwrap(),
        )
    }

    fn corpus_present() -> bool {
        if Path::new(CORPUS).is_dir() {
            return true;
        }
        assert!(
            std::env::var("CI").map_or(true, |v| v.is_empty()),
            "corpus missing at {CORPUS}"
        );
        println!("SKIPPED: no corpus at {CORPUS}");
        false
    }

    #[test]
    fn corpus_files_match_reference_fk() {
        if !corpus_present() {
            return;
        }
        for file in CORPUS_FILES {
            let path = Path::new(CORPUS).join(file);
            let text = std::fs::read_to_string(&path).unwrap();
            let start = std::time::Instant::now();
            let imported = import(&path).unwrap_or_else(|e| panic!("{e}"));
            println!("{file}: import {:?}", start.elapsed());
            assert!(
                imported.warnings.is_empty(),
                "{file}: {:?}",
                imported.warnings
            );
            let bvh = parse(&text, &path).unwrap();
            let (frames, frame_time) = header(&text);
            assert_eq!(bvh.frames_declared, frames, "{file}");
            assert_eq!(bvh.frame_count, frames, "{file}");
            assert_eq!(bvh.frame_time, frame_time, "{file}");
            let frame_lines = text
                .lines()
                .skip_while(|l| !l.trim().starts_with("Frame Time"))
                .skip(1)
                .filter(|l| !l.trim().is_empty())
                .count();
            assert_eq!(frame_lines, frames, "{file}");
            let joint_lines = text
                .lines()
                .filter(|l| matches!(l.split_whitespace().next(), Some("ROOT" | "JOINT")))
                .count();
            let end_lines = text.lines().filter(|l| l.trim() == "End Site").count();
            assert_eq!(
                (bvh.joints.len(), bvh.end_sites.len()),
                (joint_lines, end_lines),
                "{file}"
            );
            let duration = imported.asset.clips[0].duration();
            assert!((f64::from(duration) - (frames - 1) as f64 * frame_time).abs() < 1e-5);
            let worst = check_asset(&bvh, &imported, file);
            println!(
                "  {frames} frames, {} joints, largest relative FK error {worst:e}",
                imported.asset.skeleton.len()
            );
            if file.starts_with("bandai") {
                // Position channels replace the OFFSETs (FORMATS.md): the hips' channels put
                // them 80-95 cm up and the spine chain adds about 41 cm to the head joint.
                // Adding channels to OFFSETs would double every bone and put the hips
                // alone at about 176 cm.
                let head = imported.asset.skeleton.find("Head").unwrap();
                let y = (0..frames)
                    .map(|k| asset_positions(&imported.asset, k)[head.get()].y)
                    .fold(f32::MIN, f32::max);
                println!("  head at most {y} cm up");
                assert!(
                    (100.0..170.0).contains(&y),
                    "{file}: head at most {y} cm up"
                );
            }
        }
        let walk = parse(
            &std::fs::read_to_string(Path::new(CORPUS).join(CORPUS_FILES[3])).unwrap(),
            Path::new("walk.bvh"),
        )
        .unwrap();
        assert_eq!((walk.frame_count, walk.joints.len()), (344, 31));
        assert!((1.0 / walk.frame_time - 120.0).abs() < 1e-2);
    }

    /// Release-mode timing of the largest corpus file:
    /// `cargo test --release -p rigport-import --lib bvh::tests::kick_timing -- --ignored --nocapture`.
    #[test]
    #[ignore = "timing; run in release"]
    fn kick_timing() {
        if !corpus_present() {
            return;
        }
        let path = Path::new(CORPUS).join(KICK);
        let text = std::fs::read_to_string(&path).unwrap();
        let mut parse_times = Vec::new();
        let mut total_times = Vec::new();
        for _ in 0..50 {
            let start = std::time::Instant::now();
            let bvh = parse(&text, &path).unwrap();
            let parsed = start.elapsed();
            let imported = to_asset("kick", &bvh).unwrap();
            total_times.push(start.elapsed());
            parse_times.push(parsed);
            assert_eq!(imported.asset.clips.len(), 1);
        }
        parse_times.sort();
        total_times.sort();
        println!(
            "kick ({} bytes): parse median {:?} (min {:?}), parse + to_asset median {:?} (min {:?})",
            text.len(),
            parse_times[25],
            parse_times[0],
            total_times[25],
            total_times[0]
        );
    }
}
