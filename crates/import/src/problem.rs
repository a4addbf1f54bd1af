//! The classes of [`Problem`](crate::Problem) that the text and binary importers share:
//! each an enum of its cases, each case with its data (indices, names, counts, values,
//! lines) rather than a formatted message. Every case keeps the wording its importer has
//! always printed.

use std::fmt;
use std::path::PathBuf;

use glam::DVec3;

/// The joint (or bone) parent structure of a skeleton file is broken.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Hierarchy {
    /// A Pinocchio joint numbered out of file order.
    #[error(
        "joint index {found} where {expected} was expected: joints must be numbered 0, 1, 2, \
         ... in file order"
    )]
    Numbering {
        /// The index written.
        found: usize,
        /// Its place in the file.
        expected: usize,
    },
    /// A Pinocchio parent that is neither `-1` nor a joint index.
    #[error("parent {parent} of joint {joint} is not a joint index (the root's parent is -1)")]
    ParentNotIndex {
        /// The joint.
        joint: usize,
        /// The parent as written.
        parent: i64,
    },
    /// A CSCI 520 parent that is neither `-1` nor a joint index.
    #[error(
        "joint {joint} has parent {parent}: the root's parent is -1, every other is a joint index"
    )]
    ParentNotJoint {
        /// The joint.
        joint: usize,
        /// The parent as written.
        parent: i64,
    },
    /// A parent index past the joints.
    #[error("joint {joint} has parent {parent}, but there are only {count} joints (0..={})", count - 1)]
    ParentBeyond {
        /// The joint.
        joint: usize,
        /// The parent.
        parent: usize,
        /// How many joints there are (at least 1).
        count: usize,
    },
    /// A joint that is its own parent.
    #[error("joint {0} is its own parent")]
    OwnParent(usize),
    /// A second joint with parent `-1`.
    #[error(
        "joint {second} is a second root (parent -1) besides joint {first}: the rig must have \
         exactly one root"
    )]
    SecondRoot {
        /// The first root.
        first: usize,
        /// The second.
        second: usize,
    },
    /// No joint has parent `-1`.
    #[error("no joint has parent -1: the rig has no root")]
    NoRoot,
    /// A BVH joint whose parent is not an earlier joint.
    #[error("joint {joint} ({name:?}) names parent {parent}, which is not an earlier joint")]
    ParentNotEarlier {
        /// The joint.
        joint: usize,
        /// Its name.
        name: String,
        /// The parent it names.
        parent: usize,
    },
    /// A BVH end site whose joint does not exist.
    #[error("the end site names joint {joint}, but there are {count} joints")]
    EndSiteJoint {
        /// The joint named.
        joint: usize,
        /// How many joints there are.
        count: usize,
    },
    /// An ASF bone whose parent bone does not exist.
    #[error("bone {bone:?} names parent bone #{parent}, but there are {count} bones")]
    ParentBone {
        /// The bone.
        bone: String,
        /// The parent bone's number.
        parent: usize,
        /// How many bones there are.
        count: usize,
    },
    /// The ASF root listed as a child.
    #[error("the root cannot be a child")]
    RootAsChild,
    /// An ASF bone listed as its own child.
    #[error("bone {0:?} is listed as its own child")]
    OwnChild(String),
    /// An ASF bone listed as the child of two bones.
    #[error("bone {bone:?} already is a child of {parent:?} (line {line})")]
    SecondParent {
        /// The bone.
        bone: String,
        /// Its first parent.
        parent: String,
        /// The line listing it first.
        line: usize,
    },
    /// An ASF bone not placed in `:hierarchy`.
    #[error(
        "bone {0:?} is not listed as a child in `:hierarchy`, so it has no place in the skeleton"
    )]
    NotListed(String),
    /// ASF bones whose parents form a cycle.
    #[error("bones {} form a parent cycle, not connected to the root", .0.join(" -> "))]
    Cycle(Vec<String>),
    /// A Pinocchio skeleton without joints.
    #[error("the skeleton has no joints")]
    NoJoints,
    /// A Pinocchio parent past the joints.
    #[error(
        "parent {parent} of joint {joint} does not exist: the skeleton has {count} joints (0..={})",
        count - 1
    )]
    ParentMissing {
        /// The joint.
        joint: usize,
        /// Its parent.
        parent: usize,
        /// How many joints there are (at least 1).
        count: usize,
    },
    /// A Pinocchio joint that is its own parent (joint 0 is told it must have parent -1).
    #[error(fmt = own_parent)]
    SelfParent(usize),
    /// A second Pinocchio root.
    #[error(
        "joint {second} is a second root (parent -1) besides joint {first}: a Pinocchio skeleton \
         has exactly one root"
    )]
    SecondPinocchioRoot {
        /// The first root.
        first: usize,
        /// The second.
        second: usize,
    },
    /// A Pinocchio root other than joint 0.
    #[error(
        "joint 0 has parent {parent}, but joint {root} is the root: Pinocchio's root must be \
         joint 0 (weight column k is the bone ending at joint k + 1)"
    )]
    RootNotFirst {
        /// Joint 0's parent.
        parent: usize,
        /// The root.
        root: usize,
    },
    /// A Pinocchio skeleton without a joint of parent `-1`.
    #[error("the skeleton has no root (parent -1)")]
    NoRootJoint,
    /// A Pinocchio skeleton of one joint.
    #[error("the skeleton has only a root: at least one bone (2 joints) is needed")]
    OnlyRoot,
    /// A problem of one joint of a skeleton given as data (not a file with lines).
    #[error("skeleton joint {joint}: {problem}")]
    OfJoint {
        /// The joint.
        joint: usize,
        /// Its problem.
        problem: Box<Hierarchy>,
    },
    /// Two ASF bones with one name, or a bone named as rigport names a leaf bone's end
    /// joint.
    #[error(fmt = same_name)]
    SameName {
        /// The bone.
        bone: String,
        /// The leaf bone whose end joint has that name, if that is the clash.
        leaf: Option<String>,
    },
}

fn own_parent(joint: &usize, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    match joint {
        0 => f.write_str(
            "joint 0 has parent 0, i.e. is its own parent: the root must have parent -1",
        ),
        j => write!(f, "joint {j} has parent {j}, i.e. is its own parent"),
    }
}

fn same_name(bone: &str, leaf: &Option<String>, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    match leaf {
        Some(leaf) => write!(
            f,
            "bone {bone:?} has the name rigport gives the end joint of leaf bone {leaf:?}"
        ),
        None => write!(f, "two bones are named {bone:?}"),
    }
}

/// More than rigport's types hold: indices, 32-bit floats, key times, sums.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Limit {
    /// More OBJ vertices than 32-bit indices number.
    #[error("too many vertices for 32-bit indices")]
    Vertices,
    /// More joints than 32-bit indices number.
    #[error("more joints than fit 32-bit indices")]
    Joints,
    /// More joints than rigport's joint indices number (`{count} joints is more ...`).
    #[error("{0} joints is more than rigport's joint indices hold")]
    JointCount(usize),
    /// More joints than a skeleton indexes (`{count} joints: more ...`).
    #[error("{0} joints: more than a skeleton can index")]
    SkeletonJoints(usize),
    /// An OBJ index beyond `u32`.
    #[error("index {index} in {token:?} is too large")]
    Index {
        /// The index.
        index: i64,
        /// The token holding it.
        token: String,
    },
    /// An ASF rest offset beyond `f32`.
    #[error("joint {joint:?}: its rest offset {offset} does not fit 32-bit floats")]
    RestOffset {
        /// The joint.
        joint: String,
        /// The offset.
        offset: DVec3,
    },
    /// An AMC translation beyond `f32`.
    #[error("frame {frame}: the translation of joint {joint:?} does not fit 32-bit floats")]
    Translation {
        /// The AMC frame number.
        frame: u64,
        /// The joint (`?` when unknown).
        joint: String,
    },
    /// A BVH frame time too small for distinct `f32` key times.
    #[error(
        "Frame Time {frame_time:?} s is too small for {frames} frames to get increasing f32 key \
         times"
    )]
    FrameTime {
        /// Seconds per frame.
        frame_time: f64,
        /// Frames.
        frames: usize,
    },
    /// An AMC frame whose `f32` key time does not increase.
    #[error(
        "frame {frame} at {fps} fps has no 32-bit key time after the previous frame's: too many \
         frames for this rate"
    )]
    KeyTime {
        /// The frame (0-based).
        frame: usize,
        /// The frame rate.
        fps: f32,
    },
    /// A CSCI 520 weight row whose sum overflows `f64`.
    #[error("the weights of vertex {0} sum to more than f64 holds")]
    WeightSum(usize),
    /// A CSCI 520 weight row whose sum is too small to divide by.
    #[error("the weights of vertex {vertex} sum to {sum:e}, too small to renormalize")]
    TinyWeightSum {
        /// The vertex.
        vertex: usize,
        /// The sum.
        sum: f64,
    },
}

/// Two counts in the input that must agree and do not.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Mismatch {
    /// `{found} {what} for {expected} {per}`: `3 root weights for 4 weight rows`.
    #[error("{found} {what} for {expected} {per}")]
    For {
        /// How many there are.
        found: usize,
        /// Of what (plural).
        what: &'static str,
        /// How many there should be.
        expected: usize,
        /// Of what they should match (plural, with any explanation).
        per: &'static str,
    },
    /// Weight rows that do not match the mesh's source vertices.
    #[error("{rows} weight rows for a mesh of {vertices} source vertices")]
    WeightRows {
        /// Weight rows.
        rows: usize,
        /// Source vertices.
        vertices: usize,
    },
    /// More Pinocchio weight rows than OBJ vertices.
    #[error(
        "{} weight rows for {vertices} OBJ vertices (`v` lines): this row and {} more have no \
         vertex", vertices + extra, extra - 1
    )]
    ExtraRows {
        /// OBJ vertices.
        vertices: usize,
        /// Rows past them (at least 1).
        extra: usize,
    },
    /// Fewer Pinocchio weight rows than OBJ vertices.
    #[error(
        "{rows} weight rows for {vertices} OBJ vertices (`v` lines): the rows of vertices \
         {}..={vertices} are missing", rows + 1
    )]
    MissingRows {
        /// Weight rows.
        rows: usize,
        /// OBJ vertices.
        vertices: usize,
    },
    /// Pinocchio weights that do not make rows of one weight per bone.
    #[error("{weights} weights in rows of {row_len}, for {bones} bones")]
    RowLength {
        /// Weights in all.
        weights: usize,
        /// Weights per row.
        row_len: usize,
        /// Bones.
        bones: usize,
    },
    /// One weight row with another count than the bones.
    #[error("weight row {row} has {weights} weights for {bones} bones")]
    RowWeights {
        /// The row.
        row: usize,
        /// Its weights.
        weights: usize,
        /// Bones.
        bones: usize,
    },
    /// A skeleton with more or fewer parents than positions.
    #[error("the skeleton has {positions} positions but {parents} parents")]
    Parents {
        /// Positions.
        positions: usize,
        /// Parents.
        parents: usize,
    },
    /// BVH motion values that do not fill the frames.
    #[error("{values} motion values for {frames} frames of {channels} channels")]
    MotionValues {
        /// Values.
        values: usize,
        /// Frames.
        frames: usize,
        /// Channels per frame.
        channels: usize,
    },
    /// An ASF bone with another number of limits than dofs.
    #[error("bone {bone:?} has {limits} limit pairs for {dofs} dofs")]
    Limits {
        /// The bone.
        bone: String,
        /// Limit pairs.
        limits: usize,
        /// Dofs.
        dofs: usize,
    },
    /// A BVH `CHANNELS` line with another number of names than its count.
    #[error("CHANNELS {count} lists {names} channel names on its line")]
    ChannelNames {
        /// The count.
        count: usize,
        /// Names listed.
        names: usize,
    },
    /// A BVH `CHANNELS` line with more names than its count.
    #[error("CHANNELS {0} lists more than {0} channel names")]
    MoreChannelNames(usize),
    /// A BVH `CHANNELS` count over 6.
    #[error("CHANNELS {0}: a joint has at most 6 channels (3 positions, 3 rotations)")]
    Channels(usize),
    /// A BVH joint whose first channel does not follow the joints before it.
    #[error("joint {joint:?} starts at channel {first} but the joints before it have {before}")]
    FirstChannel {
        /// The joint.
        joint: String,
        /// Its first channel.
        first: usize,
        /// Channels of the joints before.
        before: usize,
    },
    /// A CSCI 520 weights header that disagrees with the mesh or skeleton.
    #[error("the header declares {value} {what}s, but {counted} {expected}")]
    Header {
        /// The count declared.
        value: i64,
        /// What it counts (`row`, `column`).
        what: &'static str,
        /// What has the right count, with its verb (`the mesh has (OBJ `v` lines)`).
        counted: &'static str,
        /// The right count.
        expected: usize,
    },
    /// An AMC motion read against another skeleton.
    #[error(
        "the motion has {per_frame} values per frame ({values} in all for {frames} frames), but \
         the skeleton {} has {dofs} dofs: it was parsed against another skeleton",
        skeleton.display()
    )]
    AmcSkeleton {
        /// Values per frame.
        per_frame: usize,
        /// Values in all.
        values: usize,
        /// Frames.
        frames: usize,
        /// The `.asf`.
        skeleton: PathBuf,
        /// Its dofs.
        dofs: usize,
    },
    /// An AMC bone line with another number of values than its dofs.
    #[error(fmt = bone_values)]
    BoneValues {
        /// The bone (or `root`).
        bone: String,
        /// Values on the line.
        count: usize,
        /// Its dofs' names.
        dofs: Vec<&'static str>,
        /// Values needed.
        expected: usize,
    },
}

fn bone_values(
    bone: &str,
    count: &usize,
    dofs: &[&'static str],
    expected: &usize,
    f: &mut fmt::Formatter<'_>,
) -> fmt::Result {
    let names = if dofs.is_empty() {
        "none".to_string()
    } else {
        dofs.join(" ")
    };
    write!(
        f,
        "{bone:?} has {count} values, but its dofs ({names}) need {expected}"
    )
}

/// Something the format requires is not there.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Missing {
    /// A required CSCI 520 option.
    #[error("the required option *{0} is missing")]
    Option(&'static str),
    /// A CSCI 520 option followed by another option.
    #[error(
        "*{option} has no value: the next line that is not blank or a comment (line {next_line}) \
         starts another option"
    )]
    OptionValue {
        /// The option.
        option: String,
        /// The line starting the next option.
        next_line: usize,
    },
    /// A CSCI 520 option at the end of the file.
    #[error("*{0} has no value: the file ends")]
    OptionValueAtEnd(String),
    /// A line of the ASF `:root` section.
    #[error("`:root` has no `{0}` line")]
    RootLine(&'static str),
    /// The ASF `:root` section.
    #[error("`:root` is incomplete")]
    Root,
    /// An entry of an ASF bone block.
    #[error("the bone block opened on line {begin_line} has no `{key}`")]
    BoneEntry {
        /// The line of its `begin`.
        begin_line: usize,
        /// The entry.
        key: &'static str,
    },
    /// The end of an ASF block.
    #[error(fmt = block_end)]
    BlockEnd {
        /// The block.
        block: Block,
        /// Whether the file ends there (else the next section starts).
        eof: bool,
    },
    /// A BVH joint name.
    #[error("{0} needs a joint name on its line")]
    JointName(String),
    /// More tokens on a BVH line.
    #[error("{keyword} needs {expected} on its line")]
    OnLine {
        /// The keyword.
        keyword: String,
        /// What it needs.
        expected: &'static str,
    },
    /// BVH motion values for a joint.
    #[error("the motion has no values for joint {0:?}")]
    JointValues(String),
    /// OBJ `v` lines.
    #[error("no vertices: the file has no `v` lines")]
    Vertices,
    /// OBJ faces.
    #[error("{}", crate::obj::NO_FACES)]
    Faces,
    /// Pinocchio bones (one joint only).
    #[error("a skeleton of {0} joints has no bone to weight")]
    Bones(usize),
    /// Any weight on a Pinocchio row.
    #[error("weight row {0} has no weight")]
    RowWeight(usize),
    /// A nonzero weight on a Pinocchio row.
    #[error("all weights are zero: the vertex would follow no bone")]
    NonzeroWeight,
    /// The GLB BIN chunk a buffer without a URI refers to.
    #[error("has no uri, so it must be the GLB BIN chunk, but there is none")]
    BinChunk,
}

/// An ASF block ([`Missing::BlockEnd`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Block {
    /// A bone block of `:bonedata`, opened on this line.
    Bone(usize),
    /// The `:hierarchy` block, opened on this line.
    Hierarchy(usize),
    /// `:hierarchy` without its block.
    HierarchyBegin,
}

fn block_end(block: &Block, eof: &bool, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    let ends = if *eof {
        "the file ends"
    } else {
        "the next section starts"
    };
    match block {
        Block::Bone(line) => write!(
            f,
            "the bone block opened on line {line} has no `end` before {ends}"
        ),
        Block::Hierarchy(line) => write!(
            f,
            "the `:hierarchy` block opened on line {line} has no `end` before {ends}"
        ),
        Block::HierarchyBegin => write!(
            f,
            "`:hierarchy` has no `begin` ... `end` block before {ends}"
        ),
    }
}

/// Something the format allows once is given again.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Repeated {
    /// A BVH channel on one `CHANNELS` line.
    #[error("channel {0} is listed twice")]
    Channel(&'static str),
    /// A BVH channel twice for one joint.
    #[error("joint {joint:?} lists channel {channel} twice")]
    JointChannel {
        /// The joint.
        joint: String,
        /// The channel.
        channel: &'static str,
    },
    /// An ASF dof on one `dof` line.
    #[error("dof {0} is listed twice")]
    Dof(&'static str),
    /// Two ASF bones with one name.
    #[error("two bones are named {name:?} (the first on line {first_line})")]
    BoneName {
        /// The name.
        name: String,
        /// The line of the first.
        first_line: usize,
    },
    /// A second GLB chunk of one kind (`JSON`, `BIN`).
    #[error("a second {0} chunk")]
    Chunk(&'static str),
}

/// A well-formed input that breaks a rule of its format.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Rule {
    /// A value that must be a positive number (`timeCodesPerSecond`).
    #[error("{0} must be a positive number")]
    NotPositive(&'static str),
    /// A USD `upAxis` other than `Y` or `Z`.
    #[error("upAxis must be \"Y\" or \"Z\"")]
    UpAxis,
    /// A BVH frame time that is not positive.
    #[error("Frame Time {0} is not a number of seconds > 0")]
    FrameTime(String),
    /// An ASF length unit that is not positive.
    #[error("the length unit must be positive, got {0}")]
    LengthUnit(f64),
    /// A negative ASF bone length.
    #[error("a bone length must not be negative, got {0}")]
    NegativeLength(f64),
    /// An AMC frame rate that is not finite and positive.
    #[error("the frame rate must be finite and positive, got {0} fps")]
    FrameRate(f32),
    /// A Pinocchio joint position that is not finite.
    #[error("joint {0}'s position is not finite")]
    NonFinitePosition(usize),
    /// A Pinocchio weight that is negative or not finite.
    #[error("weight row {row} holds {weight}")]
    Weight {
        /// The row.
        row: usize,
        /// The weight.
        weight: f32,
    },
    /// OBJ index 0.
    #[error("index 0 in {0:?}: OBJ indices start at 1")]
    ZeroIndex(String),
    /// An OBJ relative index before the first element.
    #[error(
        "relative index {index} in {token:?} reaches before the first element: only {count} read \
         so far"
    )]
    RelativeIndex {
        /// The index.
        index: i64,
        /// The token.
        token: String,
        /// Elements read so far.
        count: usize,
    },
    /// An ASF bone named `root`.
    #[error("a bone cannot be named {0:?}: the name is reserved for the root")]
    ReservedName(String),
    /// An AMC angle unit that contradicts an earlier one.
    #[error("{line} contradicts the angle unit given on line {first_line}")]
    AngleUnit {
        /// The line as written.
        line: String,
        /// The line giving the first unit.
        first_line: usize,
    },
    /// An AMC bone line before any frame number.
    #[error("the bone line for {0:?} comes before the first frame number")]
    BeforeFirstFrame(String),
    /// An ASF `begin` inside an open bone block.
    #[error("`begin` inside the bone block opened on line {0} (missing `end`)")]
    BeginInBone(usize),
    /// A CSCI 520 IK joint that does not exist.
    #[error(
        "*IKJointIDs: joint {joint} does not exist: {} has {count} joints (0..={})",
        hierarchy.display(),
        count.saturating_sub(1)
    )]
    IkJoint {
        /// The joint id.
        joint: usize,
        /// The hierarchy file.
        hierarchy: PathBuf,
        /// Its joints.
        count: usize,
    },
    /// A GLB container of another version than 2.
    #[error("GLB container version {0}; only version 2 is supported")]
    GlbVersion(u32),
    /// A GLB whose first chunk is not JSON.
    #[error("the first GLB chunk must be JSON, found {0:?}")]
    FirstChunk(String),
    /// glTF JSON that breaks the schema: the first problem, and how many more there are.
    #[error(fmt = schema)]
    Schema {
        /// The first problem.
        first: Schema,
        /// How many more.
        more: usize,
    },
}

/// What breaks the glTF schema ([`Rule::Schema`]), as the `gltf` crate's validation tells.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Schema {
    /// An index past the array it indexes.
    IndexOutOfRange,
    /// A value the schema does not allow.
    Invalid,
    /// A required value that is absent.
    Missing,
    /// A size beyond this system's limits.
    Oversize,
    /// A required extension rigport does not read.
    Unsupported(String),
}

fn schema(first: &Schema, more: &usize, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    match first {
        Schema::IndexOutOfRange => f.write_str("index out of range")?,
        Schema::Invalid => f.write_str("invalid value")?,
        Schema::Missing => f.write_str("required value missing")?,
        Schema::Oversize => f.write_str("size exceeds this system's limits")?,
        Schema::Unsupported(extension) => {
            write!(f, "required extension {extension} is not supported")?;
        }
    }
    match more {
        0 => Ok(()),
        n => write!(f, " (and {n} more glTF schema problems)"),
    }
}

/// Why the bytes a glTF `uri` names cannot be had.
#[derive(Debug, thiserror::Error)]
pub enum Uri {
    /// A `data:` URI without its comma.
    #[error("malformed data URI: no ','")]
    NoComma,
    /// A `data:` URI that is not base64.
    #[error("data URI {0:?} is not base64-encoded")]
    NotBase64(String),
    /// A `data:` URI whose payload is not valid base64.
    #[error("data URI holds invalid base64")]
    InvalidBase64,
    /// A URI scheme other than `data:` and `file:`.
    #[error("{what} URI {uri:?}: only data: URIs and files are supported")]
    Scheme {
        /// What the URI names (`buffer`, `image`).
        what: &'static str,
        /// The URI.
        uri: String,
    },
    /// A percent-encoded path that is not UTF-8.
    #[error("{what} URI {uri:?} is not UTF-8 once decoded")]
    NotUtf8 {
        /// What the URI names.
        what: &'static str,
        /// The URI.
        uri: String,
    },
    /// A file that cannot be read.
    #[error("cannot read {what} file {}: {error}", file.display())]
    File {
        /// What the URI names.
        what: &'static str,
        /// The file.
        file: PathBuf,
        /// Why.
        error: std::io::Error,
    },
}
