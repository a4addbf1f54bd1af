//! What the parsers return: the ASF skeleton and the AMC motions as written, in file units
//! (re-exported by the parent module).

use std::ops::Range;
use std::path::PathBuf;

use glam::DVec3;
use rigport_model::conventions::EulerOrder;

/// Metres per inch: the ASF `length` unit is inches divided by `length`.
pub const METERS_PER_INCH: f64 = 0.0254;

/// The unit of an angle in the files.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AngleUnit {
    /// Degrees (`angle deg`, `:DEGREES`; the default).
    #[default]
    Degrees,
    /// Radians (`angle rad`, `:RADIANS`).
    Radians,
}

impl AngleUnit {
    /// `value` (in this unit) in radians.
    pub fn to_radians(self, value: f64) -> f64 {
        match self {
            AngleUnit::Degrees => value.to_radians(),
            AngleUnit::Radians => value,
        }
    }

    /// `deg`, `degree`, `degrees`, `rad`, `radian`, `radians`, any case.
    pub(super) fn parse(token: &str) -> Option<Self> {
        let is = |names: &[&str]| names.iter().any(|n| n.eq_ignore_ascii_case(token));
        if is(&["deg", "degree", "degrees"]) {
            Some(AngleUnit::Degrees)
        } else if is(&["rad", "radian", "radians"]) {
            Some(AngleUnit::Radians)
        } else {
            None
        }
    }
}

/// One degree of freedom (one AMC value) of the root or of a bone.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Dof {
    /// Translation along x (file length units).
    Tx,
    /// Translation along y.
    Ty,
    /// Translation along z.
    Tz,
    /// Rotation about x (AMC angle unit).
    Rx,
    /// Rotation about y.
    Ry,
    /// Rotation about z.
    Rz,
    /// Bone length change (bones only; read, then ignored by [`to_asset`](crate::asf_amc::to_asset)).
    L,
}

impl Dof {
    /// Every dof, in the order of their names `tx ty tz rx ry rz l`.
    pub const ALL: [Dof; 7] = [Dof::Tx, Dof::Ty, Dof::Tz, Dof::Rx, Dof::Ry, Dof::Rz, Dof::L];

    /// Parses `tx`, `RZ`, `l`, ... (case-insensitive).
    pub fn parse(token: &str) -> Option<Self> {
        Self::ALL
            .into_iter()
            .find(|d| d.as_str().eq_ignore_ascii_case(token))
    }

    /// The lower-case name (`"rx"`).
    pub fn as_str(self) -> &'static str {
        match self {
            Dof::Tx => "tx",
            Dof::Ty => "ty",
            Dof::Tz => "tz",
            Dof::Rx => "rx",
            Dof::Ry => "ry",
            Dof::Rz => "rz",
            Dof::L => "l",
        }
    }

    /// Whether this is `rx`, `ry` or `rz`.
    pub fn is_rotation(self) -> bool {
        matches!(self, Dof::Rx | Dof::Ry | Dof::Rz)
    }

    /// Whether this is `tx`, `ty` or `tz`.
    pub fn is_translation(self) -> bool {
        matches!(self, Dof::Tx | Dof::Ty | Dof::Tz)
    }
}

/// The `:units` section.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Units {
    /// `mass`, when given (unused by rigport).
    pub mass: Option<f64>,
    /// `length` `L`, when given: one file unit is `1 / L` inches (CMU: 0.45). Positive.
    pub length: Option<f64>,
    /// `angle`: the unit of the ASF's angles (root `orientation`, bone `axis`, rotation
    /// limits) and of the AMC values unless the AMC header says otherwise.
    pub angle: AngleUnit,
}

impl Units {
    /// Metres per file length unit, `0.0254 / length`, when `length` is given.
    pub fn meters_per_unit(&self) -> Option<f64> {
        self.length.map(|l| METERS_PER_INCH / l)
    }
}

/// The `:root` section.
#[derive(Clone, Debug, PartialEq)]
pub struct Root {
    /// `order`: the root's dofs in the order the AMC lists its values (no `l`), no repeats.
    pub order: Vec<Dof>,
    /// `axis`: the Euler order of `orientation` (first letter applied first).
    pub axis: EulerOrder,
    /// `position`, in file length units: the root's translation at rest, to which the AMC
    /// `TX TY TZ` are added.
    pub position: DVec3,
    /// `orientation`: the root frame `C` as Euler angles `[x, y, z]` in
    /// [`Units::angle`], applied in `axis` order.
    pub orientation: DVec3,
    /// 1-based line of `:root`.
    pub line: usize,
}

/// One `begin` ... `end` block of `:bonedata`, with its place in `:hierarchy`.
#[derive(Clone, Debug, PartialEq)]
pub struct Bone {
    /// `id`, when given (not used to link anything: the hierarchy names bones).
    pub id: Option<i64>,
    /// `name`: unique, not `root` (in any case).
    pub name: String,
    /// `direction`: the bone's rest direction in the world frame, as written (nominally
    /// unit length).
    pub direction: DVec3,
    /// `length`, in file length units, non-negative.
    pub length: f64,
    /// `axis` angles `[x, y, z]` in [`Units::angle`]: the bone's frame `C`.
    pub axis: DVec3,
    /// The Euler order of `axis` (first letter applied first).
    pub axis_order: EulerOrder,
    /// `dof`: the order of this bone's AMC values; empty when the bone has no `dof` line.
    pub dofs: Vec<Dof>,
    /// `limits`: one `(min, max)` per dof, in dof order, in [`Units::angle`] for rotations
    /// and file length units otherwise; may be infinite. Empty when not given.
    pub limits: Vec<(f64, f64)>,
    /// The parent bone (an index into [`Asf::bones`]), `None` for a child of the root.
    pub parent: Option<usize>,
    /// 1-based line of `name`.
    pub line: usize,
    /// 1-based line of the `:hierarchy` entry that lists this bone as a child.
    pub hierarchy_line: usize,
}

/// A part of the file rigport does not use and skipped: an unknown section or an unknown
/// `:units` entry.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Skipped {
    /// The keyword as written (`:skin`, `units foo`, an AMC header line).
    pub keyword: String,
    /// 1-based line.
    pub line: usize,
}

/// A parsed ASF skeleton.
#[derive(Clone, Debug, PartialEq)]
pub struct Asf {
    /// The file it was read from (for messages).
    pub path: PathBuf,
    /// `:version`, as written.
    pub version: Option<String>,
    /// `:name`, as written.
    pub name: Option<String>,
    /// The `:documentation` lines, trimmed.
    pub documentation: Vec<String>,
    /// `:units` (defaults when absent: no mass or length, degrees).
    pub units: Units,
    /// `:root`.
    pub root: Root,
    /// The bones in file order, each with its parent. The parents form a tree under the
    /// root (checked by [`parse_asf`](crate::asf_amc::parse_asf)).
    pub bones: Vec<Bone>,
    /// What was skipped, in file order.
    pub skipped: Vec<Skipped>,
}

impl Asf {
    /// Values per AMC frame: the root's `order` length plus every bone's dof count.
    pub fn channel_count(&self) -> usize {
        self.root.order.len() + self.bones.iter().map(|b| b.dofs.len()).sum::<usize>()
    }

    /// Where each node's values sit in a frame of [`Amc::values`]: entry 0 is the root's,
    /// entry `1 + b` bone `b`'s (length `1 + bones.len()`).
    pub fn channel_ranges(&self) -> Vec<Range<usize>> {
        let mut out = Vec::with_capacity(self.bones.len() + 1);
        let mut start = self.root.order.len();
        out.push(0..start);
        for bone in &self.bones {
            out.push(start..start + bone.dofs.len());
            start += bone.dofs.len();
        }
        out
    }

    /// The index in [`Asf::bones`] of the bone with this name.
    pub fn bone_index(&self, name: &str) -> Option<usize> {
        self.bones.iter().position(|b| b.name == name)
    }
}

/// One frame of an AMC file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AmcFrame {
    /// The frame number as written.
    pub number: u64,
    /// 1-based line of the frame number.
    pub line: usize,
}

/// A value an AMC frame did not give, filled from the frame before (see [`parse_amc`](crate::asf_amc::parse_amc)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HeldValue {
    /// The frame (index into [`Amc::frames`]).
    pub frame: usize,
    /// The bone (index into [`Asf::bones`]); `None` for the root.
    pub bone: Option<usize>,
}

/// A parsed AMC motion, laid out for the [`Asf`] it was parsed against.
#[derive(Clone, Debug, PartialEq)]
pub struct Amc {
    /// The file it was read from (for messages).
    pub path: PathBuf,
    /// The angle unit the header states (`:DEGREES` / `:RADIANS`), which overrides the
    /// ASF's; `None` when it states none.
    pub angle: Option<AngleUnit>,
    /// Whether the header has `:FULLY-SPECIFIED`.
    pub fully_specified: bool,
    /// Other `:` header lines, as written.
    pub header: Vec<Skipped>,
    /// The frames in file order.
    pub frames: Vec<AmcFrame>,
    /// Values per frame ([`Asf::channel_count`] of the skeleton it was parsed against).
    pub channels: usize,
    /// `frames.len() * channels` values, frame after frame, each frame laid out by
    /// [`Asf::channel_ranges`]; angles in [`Amc::angle`] (or the ASF's unit), lengths in
    /// file units. Values a frame did not give are filled in (see [`Amc::held`]).
    pub values: Vec<f64>,
    /// The values that were missing and held, in file order.
    pub held: Vec<HeldValue>,
}

impl Amc {
    /// Frame `k`'s values (`channels` long), laid out by [`Asf::channel_ranges`].
    pub fn frame_values(&self, k: usize) -> Option<&[f64]> {
        let start = k.checked_mul(self.channels)?;
        self.values.get(start..start.checked_add(self.channels)?)
    }
}
