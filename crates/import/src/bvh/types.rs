//! The file as written: channels, joints, end sites and motion values (re-exported by the
//! parent module).

use std::path::PathBuf;

use glam::Vec3;
use rigport_model::Warning;

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
/// Built by [`parse`](crate::bvh::parse); [`to_asset`](crate::bvh::to_asset) turns it into a rig model (and re-checks the
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
    /// [`to_asset`](crate::bvh::to_asset) passes them on first.
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
