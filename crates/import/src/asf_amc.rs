//! Acclaim ASF skeletons with AMC motions (CMU motion capture).
//!
//! # The files (FORMATS.md "Acclaim ASF/AMC")
//! - Both are line based. Lines end with LF, CRLF or a lone CR; blank lines, indentation,
//!   tabs and trailing white space are fine everywhere. A `#` at the start of a line or
//!   after white space starts a comment that runs to the end of the line (a `#` inside a
//!   token, as in a Windows `-1.#IND`, is not a comment: that token is not a number).
//!   Keywords (`:units`, `begin`, `order`, `TX`, `XYZ`, `dof`, `rx`, `deg`, `:DEGREES`,
//!   `root`, ...) are case-insensitive; bone names are case-sensitive.
//! - ASF ([`parse_asf`]): `:version`, `:name` and `:documentation` are kept as text;
//!   `:units` gives `mass` (kept, unused), `length` and `angle deg|rad` (default `deg`);
//!   `:root` needs `order` (1 to 6 of `TX TY TZ RX RY RZ`), `axis` (an Euler order such as
//!   `XYZ`), `position` and `orientation` (3 numbers each); `:bonedata` holds `begin` ...
//!   `end` blocks with `name`, `direction` (3 numbers), `length` and `axis ax ay az ORDER`
//!   (required), `id`, `dof` (any of `tx ty tz rx ry rz l`, each at most once, in the order
//!   the AMC lists the values) and `limits` (one `(min max)` pair per dof, on the `limits`
//!   line and/or the lines after it; `inf` is allowed), and `bodymass` / `cofmass` (read
//!   and ignored, as `mass` is). `:hierarchy` holds a `begin` ... `end` block of
//!   `parent child child ...` lines. Unknown `:sections` and unknown `:units` entries are
//!   skipped (listed in [`Asf::skipped`], reported as [`Warning::Note`]s).
//! - AMC ([`parse_amc`]): header lines (`:FULLY-SPECIFIED`, `:DEGREES` or `:RADIANS`,
//!   others kept in [`Amc::header`]), then frames: a line holding only the frame number,
//!   followed by `bone v1 v2 ...` lines, one value per dof in the ASF's dof order (the
//!   root's in its `order`). Bones with no dof may be listed with no values. The frame
//!   rate is not in the file (CMU records at [`DEFAULT_FPS`]).
//!
//! # Choices where the format leaves room
//! - A bone that `:hierarchy` never lists as a child is an **error** (at its `name` line),
//!   not silently attached to the root: a bone placed at the root would look plausible and
//!   be wrong.
//! - A bone missing from an AMC frame holds its value from the frame before (the rest pose,
//!   all dofs 0, in the first frame); one [`Warning::Repaired`] per file counts them.
//!   Frame numbers that are not consecutive give one [`Warning::Note`]; the frames keep
//!   the file's order and key `k` is at `k / fps` whatever its number.
//! - Translation dofs (`tx ty tz`) of a bone move the bone's start along the axes of its
//!   frame `C` (so the bone's local translation becomes `parent offset + C · t`).
//! - The length dof `l` is read but **ignored** (its meaning, a new length or a change of
//!   length, differs between writers); a [`Warning::Note`] per such bone says so.
//!
//! # The asset rigport builds ([`to_asset`])
//! - Joints: `root`, then one joint per bone at the bone's **start** (its parent's end; the
//!   root's position for children of the root), each leaf bone followed by a joint
//!   `<bone>_end` at its end, so that every bone has a visible extent. Joints are ordered
//!   parents-first by [`parents_first_order`], which keeps the file order where possible.
//! - Rest pose: every rest rotation is the identity; a bone joint's rest translation is its
//!   parent bone's `direction * length` (zero under the root), an `_end` joint's its own
//!   bone's, the root's the `:root` `position`. Lengths stay in file units;
//!   [`Asset::meters_per_unit`] is `0.0254 / length` when `:units` states `length` (one
//!   file unit is `1 / length` inches).
//! - With identity rest rotations a joint's model-space rotation is FORMATS.md's
//!   `W = W_parent · C · M · C⁻¹`, so the local rotation of a bone's joint is `C · M · C⁻¹`
//!   (`C` from `axis` in its order, `M` from the frame's rotation dofs, first listed applied
//!   first), the root's likewise with `C` from `orientation` in the root `axis` order; the
//!   root's local translation is `position + (TX, TY, TZ)`.
//! - Clips: one per AMC, one key per frame at `k / fps` seconds, linear interpolation; a
//!   translation and a rotation track for the root, a rotation track for every bone with a
//!   rotation dof, a translation track for every bone with a translation dof. Every frame
//!   is kept, also for constant tracks. Quaternions are unit length and sign-continuous
//!   (each key is on the same side as the previous one).
//! - [`Asf`] keeps what the model has no field for yet (dof limits for IK, bone ids, axis
//!   angles).

use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::{DQuat, DVec3, Vec3};
use rigport_model::conventions::EulerOrder;
use rigport_model::{
    parents_first_order, Asset, Clip, Interpolation, Joint, JointIndex, Skeleton, SkeletonProblem,
    Track, TrackTarget, Transform, Warning,
};

use crate::{read_file, utf8, ImportError, Imported, Location, Problem};

/// The frame rate CMU captured at, in frames per second; AMC files do not state a rate.
pub const DEFAULT_FPS: f32 = 120.0;

/// Metres per inch: the ASF `length` unit is inches divided by `length`.
pub const METERS_PER_INCH: f64 = 0.0254;

/// A bone `direction` whose length differs from 1 by more than this gets a
/// [`Warning::Note`] (it is used as written). CMU files write 6 significant digits, so
/// their directions are unit length within 1e-5.
pub const UNIT_DIRECTION_TOLERANCE: f64 = 1e-3;

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
    fn parse(token: &str) -> Option<Self> {
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
    /// Bone length change (bones only; read, then ignored by [`to_asset`]).
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
    /// root (checked by [`parse_asf`]).
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

/// A value an AMC frame did not give, filled from the frame before (see [`parse_amc`]).
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

// ---------------------------------------------------------------------------------------
// Entry points

/// Imports an ASF skeleton and any number of AMC motions of it (one clip each, named after
/// the file stem, in the order given) at `fps` frames per second.
///
/// The asset is named after the ASF's file stem. See the module docs for the mapping.
///
/// # Errors
/// `fps` is not finite and positive (at the ASF); a file cannot be read or is not UTF-8;
/// [`parse_asf`], [`parse_amc`] or [`to_asset`] fails.
pub fn import(asf: &Path, amcs: &[PathBuf], fps: f32) -> Result<Imported, ImportError> {
    check_fps(fps, asf)?;
    let bytes = read_file(asf)?;
    let skeleton = parse_asf(utf8(&bytes, asf)?, asf)?;
    let mut motions = Vec::with_capacity(amcs.len());
    for path in amcs {
        let bytes = read_file(path)?;
        let amc = parse_amc(utf8(&bytes, path)?, path, &skeleton)?;
        motions.push((stem(path), amc));
    }
    to_asset(&stem(asf), &skeleton, &motions, fps)
}

fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn check_fps(fps: f32, path: &Path) -> Result<(), ImportError> {
    if fps.is_finite() && fps > 0.0 {
        Ok(())
    } else {
        Err(ImportError::invalid(
            Location::file(path),
            format!("the frame rate must be finite and positive, got {fps} fps"),
        ))
    }
}

// ---------------------------------------------------------------------------------------
// Lines and tokens

/// The lines of a text with their 1-based numbers; LF, CRLF and a lone CR all end a line.
struct Lines<'a> {
    rest: Option<&'a str>,
    number: usize,
}

impl<'a> Lines<'a> {
    fn new(text: &'a str) -> Self {
        Self {
            rest: Some(text),
            number: 0,
        }
    }
}

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, &'a str);

    fn next(&mut self) -> Option<Self::Item> {
        let rest = self.rest?;
        if rest.is_empty() && self.number > 0 {
            // The text ends with a line break: there is no line after it.
            self.rest = None;
            return None;
        }
        let line = match rest.find(['\n', '\r']) {
            Some(i) => {
                let (line, tail) = rest.split_at(i);
                let skip = if tail.starts_with("\r\n") { 2 } else { 1 };
                self.rest = tail.get(skip..);
                line
            }
            None => {
                self.rest = None;
                rest
            }
        };
        self.number += 1;
        Some((self.number, line))
    }
}

/// The line without its comment and surrounding white space. A `#` starts a comment at the
/// start of the line or after white space only (`-1.#IND` stays one, non-numeric, token).
fn content(raw: &str) -> &str {
    let bytes = raw.as_bytes();
    let end = bytes
        .iter()
        .enumerate()
        .find(|&(i, &b)| {
            b == b'#'
                && (i == 0
                    || bytes
                        .get(i - 1)
                        .is_some_and(|prev| prev.is_ascii_whitespace()))
        })
        .map_or(raw.len(), |(i, _)| i);
    raw.get(..end).unwrap_or(raw).trim_ascii()
}

/// 1-based character column of `token` (a sub-slice of `raw`) in `raw`.
fn column(raw: &str, token: &str) -> usize {
    let offset = (token.as_ptr() as usize).wrapping_sub(raw.as_ptr() as usize);
    raw.get(..offset)
        .map_or(1, |before| before.chars().count() + 1)
}

/// A token-level error at `path:line:column`.
fn syntax(path: &Path, line: usize, raw: &str, token: &str, expected: &str) -> ImportError {
    ImportError::syntax(
        Location::line_column(path, line, column(raw, token)),
        expected,
        token,
    )
}

fn invalid(path: &Path, line: usize, message: impl Into<String>) -> ImportError {
    ImportError::invalid(Location::line(path, line), message)
}

/// A finite number.
fn number(
    path: &Path,
    line: usize,
    raw: &str,
    token: &str,
    what: &str,
) -> Result<f64, ImportError> {
    match token.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(ImportError::invalid(
            Location::line_column(path, line, column(raw, token)),
            format!("{what} is not finite: {token:?}"),
        )),
        Err(_) => Err(syntax(
            path,
            line,
            raw,
            token,
            &format!("a number ({what})"),
        )),
    }
}

/// Exactly three finite numbers after a keyword.
fn vec3(
    path: &Path,
    line: usize,
    raw: &str,
    whole: &str,
    args: &[&str],
    what: &str,
) -> Result<DVec3, ImportError> {
    let [x, y, z] = args else {
        return Err(ImportError::syntax(
            Location::line(path, line),
            format!("3 numbers after `{what}`"),
            whole,
        ));
    };
    Ok(DVec3::new(
        number(path, line, raw, x, what)?,
        number(path, line, raw, y, what)?,
        number(path, line, raw, z, what)?,
    ))
}

/// A dof list: each token a [`Dof`], none repeated, `l` only when `allow_length`.
fn dof_list(
    path: &Path,
    line: usize,
    raw: &str,
    whole: &str,
    args: &[&str],
    allow_length: bool,
) -> Result<Vec<Dof>, ImportError> {
    let expected = if allow_length {
        "a dof (tx ty tz rx ry rz l)"
    } else {
        "a root dof (TX TY TZ RX RY RZ)"
    };
    if args.is_empty() {
        return Err(ImportError::syntax(
            Location::line(path, line),
            format!("at least one dof: {expected}"),
            whole,
        ));
    }
    let mut dofs = Vec::with_capacity(args.len());
    for token in args {
        let dof = Dof::parse(token)
            .filter(|d| allow_length || *d != Dof::L)
            .ok_or_else(|| syntax(path, line, raw, token, expected))?;
        if dofs.contains(&dof) {
            return Err(ImportError::invalid(
                Location::line_column(path, line, column(raw, token)),
                format!("dof {} is listed twice", dof.as_str()),
            ));
        }
        dofs.push(dof);
    }
    Ok(dofs)
}

fn euler_order(
    path: &Path,
    line: usize,
    raw: &str,
    token: &str,
) -> Result<EulerOrder, ImportError> {
    EulerOrder::parse(token).ok_or_else(|| {
        syntax(
            path,
            line,
            raw,
            token,
            "an axis order (XYZ, XZY, YXZ, YZX, ZXY or ZYX)",
        )
    })
}

// ---------------------------------------------------------------------------------------
// ASF

/// Parses an ASF skeleton. `path` is used in messages and kept in [`Asf::path`].
///
/// See the module docs for the syntax accepted. The hierarchy is resolved and checked once
/// the whole file is read, so sections may come in any order.
///
/// # Errors
/// The first problem, at its line (and column for a bad token): text before the first
/// `:keyword`; a section given twice; a malformed `:units`, `:root` or bone line (wrong
/// number of values, a bad or non-finite number, an unknown dof token or axis order, a
/// dof listed twice, `l` in the root's `order`, a negative length, a non-positive unit
/// length, an unknown bone keyword, a malformed `limits` pair or a limits count other than
/// the dof count); a bone block without `name`, `direction`, `length` or `axis`, or not
/// closed by `end`; a duplicate bone name or a bone named `root`; a `:hierarchy` line naming
/// an unknown bone, the root as a child, or a bone that already has a parent; a bone the
/// hierarchy never lists (at its `name` line); a parent cycle (at the first hierarchy line
/// involved); a file without `:root` or `:bonedata` ([`Problem::Truncated`] at its last
/// line); a file with no content at all ([`Problem::Empty`]).
pub fn parse_asf(text: &str, path: &Path) -> Result<Asf, ImportError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut parser = AsfParser::new(path);
    let mut last_line = 0;
    for (line_no, raw) in Lines::new(text) {
        last_line = line_no;
        let line = content(raw);
        if !line.is_empty() {
            parser.line(line_no, raw, line)?;
        }
    }
    parser.finish(last_line)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Section {
    /// Before the first keyword, or after a one-line keyword (`:version`, `:name`).
    None,
    Units,
    Documentation,
    Root,
    BoneData,
    Hierarchy,
    Skipped,
}

#[derive(Default)]
struct RootDraft {
    line: usize,
    order: Option<(Vec<Dof>, usize)>,
    axis: Option<(EulerOrder, usize)>,
    position: Option<(DVec3, usize)>,
    orientation: Option<(DVec3, usize)>,
}

#[derive(Default)]
struct BoneDraft {
    begin_line: usize,
    id: Option<(i64, usize)>,
    name: Option<(String, usize)>,
    direction: Option<(DVec3, usize)>,
    length: Option<(f64, usize)>,
    axis: Option<((DVec3, EulerOrder), usize)>,
    dofs: Option<(Vec<Dof>, usize)>,
    limits: Option<(Vec<(f64, f64)>, usize)>,
    /// Whether the previous line was `limits` or a continuation of it.
    in_limits: bool,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Block {
    NotBegun,
    Open(usize),
    Closed,
}

struct AsfParser<'a, 't> {
    path: &'a Path,
    section: Section,
    /// Known sections seen: lower-case keyword and line.
    seen: Vec<(String, usize)>,
    version: Option<String>,
    name: Option<String>,
    documentation: Vec<String>,
    units: Units,
    units_seen: Vec<(String, usize)>,
    root: Option<RootDraft>,
    bonedata_seen: bool,
    bones: Vec<Bone>,
    names: HashMap<String, usize>,
    draft: Option<BoneDraft>,
    hierarchy: Block,
    hierarchy_lines: Vec<(usize, &'t str, &'t str)>,
    skipped: Vec<Skipped>,
    any: bool,
}

/// Stores a keyed value once: a second occurrence is an error naming the first line.
fn once<T>(
    slot: &mut Option<(T, usize)>,
    value: T,
    path: &Path,
    line: usize,
    key: &str,
    within: &str,
) -> Result<(), ImportError> {
    if let Some((_, first)) = slot {
        return Err(invalid(
            path,
            line,
            format!("`{key}` is given twice in {within} (first on line {first})"),
        ));
    }
    *slot = Some((value, line));
    Ok(())
}

impl<'a, 't> AsfParser<'a, 't> {
    fn new(path: &'a Path) -> Self {
        Self {
            path,
            section: Section::None,
            seen: Vec::new(),
            version: None,
            name: None,
            documentation: Vec::new(),
            units: Units::default(),
            units_seen: Vec::new(),
            root: None,
            bonedata_seen: false,
            bones: Vec::new(),
            names: HashMap::new(),
            draft: None,
            hierarchy: Block::NotBegun,
            hierarchy_lines: Vec::new(),
            skipped: Vec::new(),
            any: false,
        }
    }

    fn line(&mut self, line_no: usize, raw: &'t str, line: &'t str) -> Result<(), ImportError> {
        self.any = true;
        if let Some(rest) = line.strip_prefix(':') {
            return self.keyword(line_no, raw, line, rest);
        }
        match self.section {
            Section::None => Err(ImportError::syntax(
                Location::line(self.path, line_no),
                "a `:keyword` line (`:units`, `:root`, `:bonedata`, `:hierarchy`, ...)",
                line,
            )),
            Section::Skipped => Ok(()),
            Section::Documentation => {
                self.documentation.push(line.to_string());
                Ok(())
            }
            Section::Units => self.units_line(line_no, raw, line),
            Section::Root => self.root_line(line_no, raw, line),
            Section::BoneData => self.bone_line(line_no, raw, line),
            Section::Hierarchy => self.hierarchy_line(line_no, raw, line),
        }
    }

    fn keyword(
        &mut self,
        line_no: usize,
        raw: &str,
        line: &str,
        rest: &str,
    ) -> Result<(), ImportError> {
        self.close_section(line_no, false)?;
        let rest = rest.trim_ascii_start();
        let (keyword, value) = match rest.find(|c: char| c.is_ascii_whitespace()) {
            Some(i) => {
                let (k, v) = rest.split_at(i);
                (k, v.trim_ascii())
            }
            None => (rest, ""),
        };
        let lower = keyword.to_ascii_lowercase();
        let section = match lower.as_str() {
            "version" | "name" => Section::None,
            "units" => Section::Units,
            "documentation" => Section::Documentation,
            "root" => Section::Root,
            "bonedata" => Section::BoneData,
            "hierarchy" => Section::Hierarchy,
            _ => {
                self.skipped.push(Skipped {
                    keyword: line.to_string(),
                    line: line_no,
                });
                self.section = Section::Skipped;
                return Ok(());
            }
        };
        if let Some((_, first)) = self.seen.iter().find(|(k, _)| *k == lower) {
            return Err(invalid(
                self.path,
                line_no,
                format!("`:{lower}` is given twice (first on line {first})"),
            ));
        }
        self.seen.push((lower.clone(), line_no));
        let takes_value = matches!(lower.as_str(), "version" | "name" | "documentation");
        if !takes_value && !value.is_empty() {
            return Err(syntax(
                self.path,
                line_no,
                raw,
                value,
                &format!("nothing after `:{lower}` (its entries go on the next lines)"),
            ));
        }
        match lower.as_str() {
            "version" => self.version = Some(value.to_string()),
            "name" => self.name = Some(value.to_string()),
            "documentation" if !value.is_empty() => self.documentation.push(value.to_string()),
            "root" => {
                self.root = Some(RootDraft {
                    line: line_no,
                    ..RootDraft::default()
                })
            }
            "bonedata" => self.bonedata_seen = true,
            _ => {}
        }
        self.section = section;
        Ok(())
    }

    /// Checks that the section being left is complete. `eof`: the file ends here.
    fn close_section(&mut self, line_no: usize, eof: bool) -> Result<(), ImportError> {
        let ends = if eof {
            "the file ends"
        } else {
            "the next section starts"
        };
        let unclosed = |what: String| {
            if eof {
                ImportError::new(Location::line(self.path, line_no), Problem::Truncated(what))
            } else {
                invalid(self.path, line_no, what)
            }
        };
        match self.section {
            Section::Root => {
                if let Some(root) = &self.root {
                    let missing = [
                        ("order", root.order.is_none()),
                        ("axis", root.axis.is_none()),
                        ("position", root.position.is_none()),
                        ("orientation", root.orientation.is_none()),
                    ];
                    if let Some((key, _)) = missing.iter().find(|(_, m)| *m) {
                        return Err(invalid(
                            self.path,
                            root.line,
                            format!("`:root` has no `{key}` line"),
                        ));
                    }
                }
            }
            Section::BoneData => {
                if let Some(draft) = &self.draft {
                    return Err(unclosed(format!(
                        "the bone block opened on line {} has no `end` before {ends}",
                        draft.begin_line
                    )));
                }
            }
            Section::Hierarchy => match self.hierarchy {
                Block::Open(begin) => {
                    return Err(unclosed(format!(
                        "the `:hierarchy` block opened on line {begin} has no `end` before {ends}"
                    )))
                }
                Block::NotBegun => {
                    return Err(unclosed(format!(
                        "`:hierarchy` has no `begin` ... `end` block before {ends}"
                    )))
                }
                Block::Closed => {}
            },
            _ => {}
        }
        self.section = Section::None;
        Ok(())
    }

    fn units_line(&mut self, line_no: usize, raw: &str, line: &str) -> Result<(), ImportError> {
        let path = self.path;
        let tokens: Vec<&str> = line.split_ascii_whitespace().collect();
        let [key, value] = tokens.as_slice() else {
            return Err(ImportError::syntax(
                Location::line(path, line_no),
                "a `:units` entry `name value` (`mass 1.0`, `length 0.45`, `angle deg`)",
                line,
            ));
        };
        let lower = key.to_ascii_lowercase();
        if let Some((_, first)) = self.units_seen.iter().find(|(k, _)| *k == lower) {
            return Err(invalid(
                path,
                line_no,
                format!("`{lower}` is given twice in `:units` (first on line {first})"),
            ));
        }
        match lower.as_str() {
            "mass" => self.units.mass = Some(number(path, line_no, raw, value, "mass")?),
            "length" => {
                let length = number(path, line_no, raw, value, "length unit")?;
                if length <= 0.0 {
                    return Err(ImportError::invalid(
                        Location::line_column(path, line_no, column(raw, value)),
                        format!("the length unit must be positive, got {length}"),
                    ));
                }
                self.units.length = Some(length);
            }
            "angle" => {
                self.units.angle = AngleUnit::parse(value)
                    .ok_or_else(|| syntax(path, line_no, raw, value, "`deg` or `rad`"))?
            }
            _ => self.skipped.push(Skipped {
                keyword: format!("units {key}"),
                line: line_no,
            }),
        }
        self.units_seen.push((lower, line_no));
        Ok(())
    }

    fn root_line(&mut self, line_no: usize, raw: &str, line: &str) -> Result<(), ImportError> {
        let path = self.path;
        let tokens: Vec<&str> = line.split_ascii_whitespace().collect();
        let Some((key, args)) = tokens.split_first() else {
            return Ok(());
        };
        let Some(root) = self.root.as_mut() else {
            return Ok(());
        };
        let within = "`:root`";
        match key.to_ascii_lowercase().as_str() {
            "order" => {
                let order = dof_list(path, line_no, raw, line, args, false)?;
                once(&mut root.order, order, path, line_no, "order", within)
            }
            "axis" => {
                let [order] = args else {
                    return Err(ImportError::syntax(
                        Location::line(path, line_no),
                        "one axis order after `axis` (e.g. `axis XYZ`)",
                        line,
                    ));
                };
                let order = euler_order(path, line_no, raw, order)?;
                once(&mut root.axis, order, path, line_no, "axis", within)
            }
            "position" => {
                let v = vec3(path, line_no, raw, line, args, "position")?;
                once(&mut root.position, v, path, line_no, "position", within)
            }
            "orientation" => {
                let v = vec3(path, line_no, raw, line, args, "orientation")?;
                once(
                    &mut root.orientation,
                    v,
                    path,
                    line_no,
                    "orientation",
                    within,
                )
            }
            _ => Err(syntax(
                path,
                line_no,
                raw,
                key,
                "`order`, `axis`, `position` or `orientation`",
            )),
        }
    }

    fn bone_line(&mut self, line_no: usize, raw: &str, line: &str) -> Result<(), ImportError> {
        let path = self.path;
        let tokens: Vec<&str> = line.split_ascii_whitespace().collect();
        let Some((key, args)) = tokens.split_first() else {
            return Ok(());
        };
        let lower = key.to_ascii_lowercase();
        let Some(draft) = self.draft.as_mut() else {
            if lower == "begin" && args.is_empty() {
                self.draft = Some(BoneDraft {
                    begin_line: line_no,
                    ..BoneDraft::default()
                });
                return Ok(());
            }
            return Err(ImportError::syntax(
                Location::line(path, line_no),
                "`begin` (a bone block)",
                line,
            ));
        };
        if line.starts_with('(') {
            let Some((limits, _)) = draft.limits.as_mut().filter(|_| draft.in_limits) else {
                return Err(ImportError::syntax(
                    Location::line(path, line_no),
                    "a bone entry (a `(min max)` line continues a `limits` line)",
                    line,
                ));
            };
            return limit_pairs(path, line_no, raw, line, limits);
        }
        draft.in_limits = false;
        let within = "the bone block";
        match lower.as_str() {
            "begin" => Err(invalid(
                path,
                line_no,
                format!(
                    "`begin` inside the bone block opened on line {} (missing `end`)",
                    draft.begin_line
                ),
            )),
            "end" => {
                if let Some(extra) = args.first() {
                    return Err(syntax(path, line_no, raw, extra, "nothing after `end`"));
                }
                let draft = self.draft.take().unwrap_or_default();
                self.finish_bone(draft, line_no)
            }
            "id" => {
                let [id] = args else {
                    return Err(ImportError::syntax(
                        Location::line(path, line_no),
                        "one integer after `id`",
                        line,
                    ));
                };
                let id = id
                    .parse::<i64>()
                    .map_err(|_| syntax(path, line_no, raw, id, "an integer bone id"))?;
                once(&mut draft.id, id, path, line_no, "id", within)
            }
            "name" => {
                let [name] = args else {
                    return Err(ImportError::syntax(
                        Location::line(path, line_no),
                        "one bone name (no spaces) after `name`",
                        line,
                    ));
                };
                if name.eq_ignore_ascii_case("root") {
                    return Err(ImportError::invalid(
                        Location::line_column(path, line_no, column(raw, name)),
                        format!("a bone cannot be named {name:?}: the name is reserved for the root"),
                    ));
                }
                if let Some(first) = self.names.get(*name) {
                    return Err(ImportError::invalid(
                        Location::line_column(path, line_no, column(raw, name)),
                        format!("two bones are named {name:?} (the first on line {first})"),
                    ));
                }
                once(&mut draft.name, name.to_string(), path, line_no, "name", within)?;
                self.names.insert(name.to_string(), line_no);
                Ok(())
            }
            "direction" => {
                let v = vec3(path, line_no, raw, line, args, "direction")?;
                once(&mut draft.direction, v, path, line_no, "direction", within)
            }
            "length" => {
                let [value] = args else {
                    return Err(ImportError::syntax(
                        Location::line(path, line_no),
                        "one number after `length`",
                        line,
                    ));
                };
                let length = number(path, line_no, raw, value, "length")?;
                if length < 0.0 {
                    return Err(ImportError::invalid(
                        Location::line_column(path, line_no, column(raw, value)),
                        format!("a bone length must not be negative, got {length}"),
                    ));
                }
                once(&mut draft.length, length, path, line_no, "length", within)
            }
            "axis" => {
                let [x, y, z, order] = args else {
                    return Err(ImportError::syntax(
                        Location::line(path, line_no),
                        "3 angles and an axis order after `axis` (e.g. `axis 0 0 20 XYZ`)",
                        line,
                    ));
                };
                let angles = DVec3::new(
                    number(path, line_no, raw, x, "axis angle")?,
                    number(path, line_no, raw, y, "axis angle")?,
                    number(path, line_no, raw, z, "axis angle")?,
                );
                let order = euler_order(path, line_no, raw, order)?;
                once(&mut draft.axis, (angles, order), path, line_no, "axis", within)
            }
            "dof" => {
                let dofs = dof_list(path, line_no, raw, line, args, true)?;
                once(&mut draft.dofs, dofs, path, line_no, "dof", within)
            }
            "limits" => {
                let after = line.get(key.len()..).unwrap_or_default();
                let mut limits = Vec::new();
                limit_pairs(path, line_no, raw, after, &mut limits)?;
                once(&mut draft.limits, limits, path, line_no, "limits", within)?;
                draft.in_limits = true;
                Ok(())
            }
            // Acclaim's optional mass properties: read past, as `:units` `mass` is.
            "bodymass" | "cofmass" => Ok(()),
            _ => Err(syntax(
                path,
                line_no,
                raw,
                key,
                "a bone entry (`id`, `name`, `direction`, `length`, `axis`, `dof`, `limits`, `end`)",
            )),
        }
    }

    fn finish_bone(&mut self, draft: BoneDraft, end_line: usize) -> Result<(), ImportError> {
        let missing = |key: &str| {
            invalid(
                self.path,
                end_line,
                format!(
                    "the bone block opened on line {} has no `{key}`",
                    draft.begin_line
                ),
            )
        };
        let (name, line) = draft.name.clone().ok_or_else(|| missing("name"))?;
        let (direction, _) = draft.direction.ok_or_else(|| missing("direction"))?;
        let (length, _) = draft.length.ok_or_else(|| missing("length"))?;
        let ((axis, axis_order), _) = draft.axis.ok_or_else(|| missing("axis"))?;
        let dofs = draft.dofs.map(|(d, _)| d).unwrap_or_default();
        let limits = match draft.limits {
            Some((limits, limits_line)) => {
                if limits.len() != dofs.len() {
                    return Err(invalid(
                        self.path,
                        limits_line,
                        format!(
                            "bone {name:?} has {} limit pairs for {} dofs",
                            limits.len(),
                            dofs.len()
                        ),
                    ));
                }
                limits
            }
            None => Vec::new(),
        };
        self.bones.push(Bone {
            id: draft.id.map(|(id, _)| id),
            name,
            direction,
            length,
            axis,
            axis_order,
            dofs,
            limits,
            parent: None,
            line,
            hierarchy_line: 0,
        });
        Ok(())
    }

    fn hierarchy_line(
        &mut self,
        line_no: usize,
        raw: &'t str,
        line: &'t str,
    ) -> Result<(), ImportError> {
        let lower_is = |word: &str| line.eq_ignore_ascii_case(word);
        match self.hierarchy {
            Block::NotBegun if lower_is("begin") => self.hierarchy = Block::Open(line_no),
            Block::NotBegun => {
                return Err(ImportError::syntax(
                    Location::line(self.path, line_no),
                    "`begin` (the hierarchy block)",
                    line,
                ))
            }
            Block::Open(_) if lower_is("end") => self.hierarchy = Block::Closed,
            Block::Open(_) => self.hierarchy_lines.push((line_no, raw, line)),
            Block::Closed => {
                return Err(ImportError::syntax(
                    Location::line(self.path, line_no),
                    "the next `:section` (the hierarchy block has ended)",
                    line,
                ))
            }
        }
        Ok(())
    }

    fn finish(mut self, last_line: usize) -> Result<Asf, ImportError> {
        self.close_section(last_line, true)?;
        if !self.any {
            return Err(ImportError::new(Location::file(self.path), Problem::Empty));
        }
        let truncated = |what: &str| {
            ImportError::new(
                Location::line(self.path, last_line),
                Problem::Truncated(format!("the file ends without a `{what}` section")),
            )
        };
        let root = self.root.take().ok_or_else(|| truncated(":root"))?;
        if !self.bonedata_seen {
            return Err(truncated(":bonedata"));
        }
        let (Some((order, _)), Some((axis, _)), Some((position, _)), Some((orientation, _))) =
            (root.order, root.axis, root.position, root.orientation)
        else {
            // close_section has checked the `:root` entries.
            return Err(invalid(self.path, root.line, "`:root` is incomplete"));
        };
        let mut asf = Asf {
            path: self.path.to_path_buf(),
            version: self.version,
            name: self.name,
            documentation: self.documentation,
            units: self.units,
            root: Root {
                order,
                axis,
                position,
                orientation,
                line: root.line,
            },
            bones: self.bones,
            skipped: self.skipped,
        };
        resolve_hierarchy(&mut asf, &self.hierarchy_lines)?;
        Ok(asf)
    }
}

/// Parses `(min max)` pairs (commas allowed as separators) onto `out`.
fn limit_pairs(
    path: &Path,
    line_no: usize,
    raw: &str,
    text: &str,
    out: &mut Vec<(f64, f64)>,
) -> Result<(), ImportError> {
    #[derive(Clone, Copy)]
    enum Want {
        Open,
        Min,
        Max(f64),
        Close(f64, f64),
    }
    let mut want = Want::Open;
    let mut tokens = Vec::new();
    let mut start = None;
    for (i, c) in text.char_indices() {
        let separator = c.is_ascii_whitespace() || c == ',';
        let paren = c == '(' || c == ')';
        if separator || paren {
            if let Some(s) = start.take() {
                tokens.push(text.get(s..i).unwrap_or_default());
            }
            if paren {
                tokens.push(text.get(i..i + 1).unwrap_or_default());
            }
        } else if start.is_none() {
            start = Some(i);
        }
    }
    if let Some(s) = start {
        tokens.push(text.get(s..).unwrap_or_default());
    }
    let limit = |token: &str| -> Result<f64, ImportError> {
        match token.parse::<f64>() {
            Ok(v) if !v.is_nan() => Ok(v),
            _ => Err(syntax(
                path,
                line_no,
                raw,
                token,
                "a limit (a number, `inf` or `-inf`)",
            )),
        }
    };
    for token in tokens {
        want = match (want, token) {
            (Want::Open, "(") => Want::Min,
            (Want::Open, _) => return Err(syntax(path, line_no, raw, token, "`(` (a limit pair)")),
            (Want::Min, _) => Want::Max(limit(token)?),
            (Want::Max(min), _) => Want::Close(min, limit(token)?),
            (Want::Close(min, max), ")") => {
                out.push((min, max));
                Want::Open
            }
            (Want::Close(..), _) => {
                return Err(syntax(path, line_no, raw, token, "`)` after two limits"))
            }
        };
    }
    match want {
        Want::Open => Ok(()),
        _ => Err(ImportError::syntax(
            Location::line(path, line_no),
            "a complete `(min max)` pair on one line",
            text.trim_ascii(),
        )),
    }
}

/// Sets every bone's parent from the `:hierarchy` lines and checks the tree.
fn resolve_hierarchy(asf: &mut Asf, lines: &[(usize, &str, &str)]) -> Result<(), ImportError> {
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
                ImportError::invalid(
                    Location::line_column(&path, line_no, column(raw, token)),
                    format!("unknown bone {token:?}: `:bonedata` has no bone of that name"),
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
                return Err(ImportError::invalid(
                    Location::line_column(&path, line_no, column(raw, child_token)),
                    "the root cannot be a child",
                ));
            }
            let child = lookup(child_token)?;
            if parent == Some(child) {
                return Err(ImportError::invalid(
                    Location::line_column(&path, line_no, column(raw, child_token)),
                    format!("bone {child_token:?} is listed as its own child"),
                ));
            }
            let Some(slot) = parents.get_mut(child) else {
                continue;
            };
            if let Some((previous, first)) = *slot {
                let previous = previous
                    .and_then(|p| asf.bones.get(p))
                    .map_or("root", |b| b.name.as_str());
                return Err(ImportError::invalid(
                    Location::line_column(&path, line_no, column(raw, child_token)),
                    format!(
                        "bone {child_token:?} already is a child of {previous:?} (line {first})"
                    ),
                ));
            }
            *slot = Some((parent, line_no));
        }
    }
    for (bone, parent) in asf.bones.iter_mut().zip(&parents) {
        let Some((parent, line)) = *parent else {
            return Err(invalid(
                &path,
                bone.line,
                format!(
                    "bone {:?} is not listed as a child in `:hierarchy`, so it has no place in the skeleton",
                    bone.name
                ),
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
fn hierarchy_error(
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
        let names: Vec<&str> = bones.iter().map(|b| b.name.as_str()).collect();
        return invalid(
            &asf.path,
            line,
            format!(
                "bones {} form a parent cycle, not connected to the root",
                names.join(" -> ")
            ),
        );
    }
    ImportError::new(
        Location::file(&asf.path),
        Problem::Skeleton(problems.to_vec()),
    )
}

// ---------------------------------------------------------------------------------------
// AMC

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
                        return Err(invalid(
                            path,
                            line_no,
                            format!("{line} contradicts the angle unit given on line {angle_line}"),
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
            let number = first.parse::<u64>().map_err(|_| {
                syntax(
                    path,
                    line_no,
                    raw,
                    first,
                    "a frame number that fits 64 bits",
                )
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
            return Err(ImportError::invalid(
                Location::line_column(path, line_no, column(raw, first)),
                format!(
                    "unknown bone {first:?}: the skeleton {} has no bone of that name",
                    asf.path.display()
                ),
            ));
        };
        let Some(frame) = amc.frames.last() else {
            return Err(invalid(
                path,
                line_no,
                format!("the bone line for {first:?} comes before the first frame number"),
            ));
        };
        let frame_number = frame.number;
        if let Some(slot) = given.get_mut(node) {
            if *slot != 0 {
                return Err(invalid(
                    path,
                    line_no,
                    format!(
                        "{first:?} is given twice in frame {frame_number} (first on line {})",
                        *slot
                    ),
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
                *slot = number(path, line_no, raw, token, "a dof value")?;
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
            let names: Vec<&str> = dofs.iter().map(|d| d.as_str()).collect();
            return Err(invalid(
                path,
                line_no,
                format!(
                    "{first:?} has {count} values, but its dofs ({}) need {expected}",
                    if names.is_empty() {
                        "none".to_string()
                    } else {
                        names.join(" ")
                    }
                ),
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

// ---------------------------------------------------------------------------------------
// To the model

/// Builds the asset: the skeleton of `asf` and one clip per motion, named by its string,
/// in the order given, keys at `k / fps` seconds. `name` names the asset.
///
/// See the module docs for the mapping. Warnings come in order: the ASF's skipped parts,
/// bone directions that are not unit length, `l` dofs ignored (only when there are
/// motions), then per motion its unknown header lines, its held values and its frame
/// number gaps.
///
/// # Errors
/// `fps` is not finite and positive (at the ASF); the hierarchy is broken (bones edited
/// into a cycle or naming a parent out of range, at the hierarchy line); a bone name clashes
/// with the `<bone>_end` joint of a leaf bone (at the clashing bone's `name` line); a rest
/// offset or an animated value does not fit `f32` (at the bone's line or the frame's
/// line); an [`Amc`] was parsed against another skeleton (its value count differs) or has
/// no frames; the key times `k / fps` do not fit `f32` as strictly increasing values (at
/// the AMC); the result fails [`Asset::validate`] (at the ASF).
pub fn to_asset(
    name: &str,
    asf: &Asf,
    motions: &[(String, Amc)],
    fps: f32,
) -> Result<Imported, ImportError> {
    check_fps(fps, &asf.path)?;
    let mut warnings = Vec::new();
    let at = |line: usize| format!("{}:{line}", asf.path.display());
    for skipped in &asf.skipped {
        warnings.push(Warning::Note {
            location: at(skipped.line),
            message: format!("skipped `{}`: rigport does not use it", skipped.keyword),
        });
    }
    for bone in &asf.bones {
        let norm = bone.direction.length();
        if (norm - 1.0).abs() > UNIT_DIRECTION_TOLERANCE {
            warnings.push(Warning::Note {
                location: at(bone.line),
                message: format!(
                    "bone {:?}: direction has length {norm}, not 1; used as written (the bone is {} units long)",
                    bone.name,
                    norm * bone.length
                ),
            });
        }
    }
    if !motions.is_empty() {
        for bone in asf.bones.iter().filter(|b| b.dofs.contains(&Dof::L)) {
            warnings.push(Warning::Note {
                location: at(bone.line),
                message: format!(
                    "bone {:?}: the length dof `l` is not supported; its values are ignored",
                    bone.name
                ),
            });
        }
    }
    let rig = build_skeleton(asf)?;
    let mut clips = Vec::with_capacity(motions.len());
    for (clip_name, amc) in motions {
        clips.push(build_clip(asf, &rig, clip_name, amc, fps, &mut warnings)?);
    }
    let asset = Asset {
        name: name.to_string(),
        skeleton: rig.skeleton,
        clips,
        meters_per_unit: asf.units.meters_per_unit(),
        ..Asset::default()
    };
    asset.validate().map_err(|errors| {
        let list: Vec<String> = errors.iter().map(ToString::to_string).collect();
        ImportError::invalid(
            Location::file(&asf.path),
            format!("the imported asset is invalid: {}", list.join("; ")),
        )
    })?;
    Ok(Imported { asset, warnings })
}

/// The skeleton and where each ASF node (0 = root, `1 + b` = bone `b`) went.
struct Rig {
    skeleton: Skeleton,
    node_joint: Vec<JointIndex>,
}

/// One joint before sorting.
struct SourceJoint {
    name: String,
    parent: Option<usize>,
    translation: DVec3,
    /// The node it belongs to (an `_end` joint: its bone's node).
    node: usize,
    /// Whether this is the `<bone>_end` joint of a leaf bone.
    is_end: bool,
}

fn bone_name(asf: &Asf, node: usize) -> &str {
    node.checked_sub(1)
        .and_then(|b| asf.bones.get(b))
        .map_or("root", |b| b.name.as_str())
}

fn node_of(bone: &Bone) -> usize {
    bone.parent.map_or(0, |p| p + 1)
}

fn build_skeleton(asf: &Asf) -> Result<Rig, ImportError> {
    let path = &asf.path;
    let bone_count = asf.bones.len();
    let mut has_children = vec![false; bone_count];
    for bone in &asf.bones {
        if let Some(p) = bone.parent {
            let Some(flag) = has_children.get_mut(p) else {
                return Err(invalid(
                    path,
                    bone.hierarchy_line,
                    format!(
                        "bone {:?} names parent bone #{p}, but there are {bone_count} bones",
                        bone.name
                    ),
                ));
            };
            *flag = true;
        }
    }
    // Source order: the root, then each bone followed by its `_end` joint when it is a leaf.
    let mut node_source = Vec::with_capacity(bone_count + 1);
    node_source.push(0);
    let mut next = 1;
    for &parent in &has_children {
        node_source.push(next);
        next += if parent { 1 } else { 2 };
    }
    let source_of = |node: usize| node_source.get(node).copied().unwrap_or(0);
    let mut source = Vec::with_capacity(next);
    source.push(SourceJoint {
        name: "root".into(),
        parent: None,
        translation: asf.root.position,
        node: 0,
        is_end: false,
    });
    for (b, bone) in asf.bones.iter().enumerate() {
        let translation = bone
            .parent
            .and_then(|p| asf.bones.get(p))
            .map_or(DVec3::ZERO, |p| p.direction * p.length);
        source.push(SourceJoint {
            name: bone.name.clone(),
            parent: Some(source_of(node_of(bone))),
            translation,
            node: b + 1,
            is_end: false,
        });
        if !has_children.get(b).copied().unwrap_or(true) {
            source.push(SourceJoint {
                name: format!("{}_end", bone.name),
                parent: Some(source_of(b + 1)),
                translation: bone.direction * bone.length,
                node: b + 1,
                is_end: true,
            });
        }
    }
    let line_of = |node: usize| {
        node.checked_sub(1)
            .and_then(|b| asf.bones.get(b))
            .map_or(asf.root.line, |b| b.line)
    };
    // Bone names are unique (parse_asf checks), but a bone may take the name of the `_end`
    // joint of a leaf bone.
    let mut names: HashMap<&str, &SourceJoint> = HashMap::with_capacity(source.len());
    for joint in &source {
        if let Some(other) = names.insert(&joint.name, joint) {
            let (end, bone) = if joint.is_end {
                (Some(joint), other)
            } else if other.is_end {
                (Some(other), joint)
            } else {
                (None, joint)
            };
            let message = match end {
                Some(end) => format!(
                    "bone {:?} has the name rigport gives the end joint of leaf bone {:?}",
                    bone.name,
                    bone_name(asf, end.node)
                ),
                None => format!("two bones are named {:?}", bone.name),
            };
            return Err(invalid(path, line_of(bone.node), message));
        }
    }
    let parents: Vec<Option<usize>> = source.iter().map(|j| j.parent).collect();
    let order = parents_first_order(&parents).map_err(|problems| {
        hierarchy_error(asf, &problems, |s| {
            source
                .get(s)
                .filter(|j| !j.is_end)
                .and_then(|j| j.node.checked_sub(1))
        })
    })?;
    let mut new_index = vec![0_u32; source.len()];
    for (k, &s) in order.iter().enumerate() {
        let k = u32::try_from(k).map_err(|_| {
            ImportError::invalid(Location::file(path), "more joints than fit 32-bit indices")
        })?;
        if let Some(slot) = new_index.get_mut(s) {
            *slot = k;
        }
    }
    let mut joints = Vec::with_capacity(order.len());
    for &s in &order {
        let Some(joint) = source.get(s) else {
            continue;
        };
        let translation = joint.translation.as_vec3();
        if !translation.is_finite() {
            return Err(invalid(
                path,
                line_of(joint.node),
                format!(
                    "joint {:?}: its rest offset {} does not fit 32-bit floats",
                    joint.name, joint.translation
                ),
            ));
        }
        joints.push(Joint {
            name: joint.name.clone(),
            parent: joint
                .parent
                .and_then(|p| new_index.get(p))
                .map(|&p| JointIndex(p)),
            rest_local: Transform::from_translation(translation),
        });
    }
    let skeleton = Skeleton::new(joints)
        .map_err(|problems| ImportError::new(Location::file(path), Problem::Skeleton(problems)))?;
    let node_joint = (0..=bone_count)
        .map(|node| JointIndex(new_index.get(source_of(node)).copied().unwrap_or(0)))
        .collect();
    Ok(Rig {
        skeleton,
        node_joint,
    })
}

/// A rotation from Euler angles in radians `[x, y, z]`, the first letter of `order` applied
/// first (`Xyz` = `Rz · Ry · Rx`, FORMATS.md), in `f64`.
fn euler(order: EulerOrder, angles_rad: DVec3) -> DQuat {
    order.as_str().bytes().fold(DQuat::IDENTITY, |q, axis| {
        let r = match axis {
            b'x' => DQuat::from_rotation_x(angles_rad.x),
            b'y' => DQuat::from_rotation_y(angles_rad.y),
            _ => DQuat::from_rotation_z(angles_rad.z),
        };
        r * q
    })
}

/// How one node's frame values become the values of its tracks.
struct NodeTracks<'a> {
    joint: JointIndex,
    range: Range<usize>,
    dofs: &'a [Dof],
    /// The node's frame `C` and its inverse: a local rotation is `C · M · C⁻¹`.
    frame: DQuat,
    frame_inv: DQuat,
    /// The rest translation the dof translation is added to.
    rest: DVec3,
    /// Bones translate along the axes of `C`; the root in its parent (world) frame.
    translate_in_frame: bool,
    rotations: Option<Vec<f32>>,
    translations: Option<Vec<f32>>,
    /// The last rotation key, for sign continuity.
    previous: DQuat,
}

fn build_clip(
    asf: &Asf,
    rig: &Rig,
    name: &str,
    amc: &Amc,
    fps: f32,
    warnings: &mut Vec<Warning>,
) -> Result<Clip, ImportError> {
    let path = &amc.path;
    let at = |line: usize| format!("{}:{line}", path.display());
    let channels = asf.channel_count();
    let frame_count = amc.frames.len();
    if amc.channels != channels || frame_count.checked_mul(channels) != Some(amc.values.len()) {
        return Err(ImportError::invalid(
            Location::file(path),
            format!(
                "the motion has {} values per frame ({} in all for {frame_count} frames), but the skeleton {} has {channels} dofs: it was parsed against another skeleton",
                amc.channels,
                amc.values.len(),
                asf.path.display()
            ),
        ));
    }
    if frame_count == 0 {
        return Err(ImportError::new(
            Location::file(path),
            Problem::Truncated("the motion has no frames".into()),
        ));
    }
    let mut times = Vec::with_capacity(frame_count);
    for k in 0..frame_count {
        let t = (k as f64 / f64::from(fps)) as f32;
        if !t.is_finite() || times.last().is_some_and(|&previous| t <= previous) {
            return Err(ImportError::invalid(
                Location::file(path),
                format!(
                    "frame {k} at {fps} fps has no 32-bit key time after the previous frame's: too many frames for this rate"
                ),
            ));
        }
        times.push(t);
    }

    let unit = amc.angle.unwrap_or(asf.units.angle);
    let asf_radians =
        |v: DVec3| DVec3::from_array(v.to_array().map(|a| asf.units.angle.to_radians(a)));
    let ranges = asf.channel_ranges();
    let node_range = |node: usize| ranges.get(node).cloned().unwrap_or(0..0);
    let node_joint = |node: usize| rig.node_joint.get(node).copied().unwrap_or(JointIndex(0));
    let keys = |wanted: bool, width: usize| wanted.then(|| Vec::with_capacity(width * frame_count));
    let mut nodes = Vec::with_capacity(ranges.len());
    let c_root = euler(asf.root.axis, asf_radians(asf.root.orientation));
    nodes.push(NodeTracks {
        joint: node_joint(0),
        range: node_range(0),
        dofs: &asf.root.order,
        frame: c_root,
        frame_inv: c_root.inverse(),
        rest: asf.root.position,
        translate_in_frame: false,
        rotations: keys(true, 4),
        translations: keys(true, 3),
        previous: DQuat::IDENTITY,
    });
    for (b, bone) in asf.bones.iter().enumerate() {
        let rotates = bone.dofs.iter().any(|d| d.is_rotation());
        let translates = bone.dofs.iter().any(|d| d.is_translation());
        if !rotates && !translates {
            continue;
        }
        let c = euler(bone.axis_order, asf_radians(bone.axis));
        nodes.push(NodeTracks {
            joint: node_joint(b + 1),
            range: node_range(b + 1),
            dofs: &bone.dofs,
            frame: c,
            frame_inv: c.inverse(),
            rest: bone
                .parent
                .and_then(|p| asf.bones.get(p))
                .map_or(DVec3::ZERO, |p| p.direction * p.length),
            translate_in_frame: true,
            rotations: keys(rotates, 4),
            translations: keys(translates, 3),
            previous: DQuat::IDENTITY,
        });
    }

    for (k, frame) in amc.frames.iter().enumerate() {
        let values = amc.frame_values(k).unwrap_or_default();
        for node in &mut nodes {
            let node_values = values.get(node.range.clone()).unwrap_or_default();
            let mut m = DQuat::IDENTITY;
            let mut t = DVec3::ZERO;
            for (&dof, &value) in node.dofs.iter().zip(node_values) {
                // The first listed dof is applied first (FORMATS.md): later ones multiply
                // on the left.
                match dof {
                    Dof::Rx => m = DQuat::from_rotation_x(unit.to_radians(value)) * m,
                    Dof::Ry => m = DQuat::from_rotation_y(unit.to_radians(value)) * m,
                    Dof::Rz => m = DQuat::from_rotation_z(unit.to_radians(value)) * m,
                    Dof::Tx => t.x += value,
                    Dof::Ty => t.y += value,
                    Dof::Tz => t.z += value,
                    Dof::L => {}
                }
            }
            if let Some(out) = node.rotations.as_mut() {
                let mut q = (node.frame * m * node.frame_inv).normalize();
                if q.dot(node.previous) < 0.0 {
                    q = -q;
                }
                node.previous = q;
                out.extend(q.as_quat().to_array());
            }
            if let Some(out) = node.translations.as_mut() {
                let offset = if node.translate_in_frame {
                    node.frame * t
                } else {
                    t
                };
                let p: Vec3 = (node.rest + offset).as_vec3();
                if !p.is_finite() {
                    return Err(invalid(
                        path,
                        frame.line,
                        format!(
                            "frame {}: the translation of joint {:?} does not fit 32-bit floats",
                            frame.number,
                            rig.skeleton
                                .joints()
                                .get(node.joint.get())
                                .map_or("?", |j| j.name.as_str())
                        ),
                    ));
                }
                out.extend(p.to_array());
            }
        }
    }

    nodes.sort_by_key(|n| n.joint);
    let mut tracks = Vec::with_capacity(2 * nodes.len());
    for node in nodes {
        if let Some(values) = node.translations {
            tracks.push(Track {
                target: TrackTarget::Translation(node.joint),
                interpolation: Interpolation::Linear,
                times: times.clone(),
                values,
            });
        }
        if let Some(values) = node.rotations {
            tracks.push(Track {
                target: TrackTarget::Rotation(node.joint),
                interpolation: Interpolation::Linear,
                times: times.clone(),
                values,
            });
        }
    }

    for skipped in &amc.header {
        warnings.push(Warning::Note {
            location: at(skipped.line),
            message: format!(
                "skipped header line `{}`: rigport does not use it",
                skipped.keyword
            ),
        });
    }
    if let Some(first) = amc.held.first() {
        let mut frames: Vec<usize> = amc.held.iter().map(|h| h.frame).collect();
        frames.dedup();
        let frame = amc.frames.get(first.frame);
        warnings.push(Warning::Repaired {
            location: at(frame.map_or(0, |f| f.line)),
            message: format!(
                "{} bone entries were missing from {} frames (the first: {:?} in frame {}); each held its value from the frame before (the rest pose in the first frame)",
                amc.held.len(),
                frames.len(),
                first.bone.and_then(|b| asf.bones.get(b)).map_or("root", |b| b.name.as_str()),
                frame.map_or(0, |f| f.number),
            ),
        });
    }
    let gaps: Vec<(&AmcFrame, &AmcFrame)> = amc
        .frames
        .windows(2)
        .filter_map(|w| match w {
            [a, b] if a.number.checked_add(1) != Some(b.number) => Some((a, b)),
            _ => None,
        })
        .collect();
    if let Some((before, after)) = gaps.first() {
        warnings.push(Warning::Note {
            location: at(after.line),
            message: format!(
                "frame numbers are not consecutive in {} place{} (the first: frame {} after frame {}); kept the file's order, key k at k / {fps} s",
                gaps.len(),
                if gaps.len() == 1 { "" } else { "s" },
                after.number,
                before.number
            ),
        });
    }
    Ok(Clip {
        name: name.to_string(),
        tracks,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DMat3, Mat4, Quat};
    use rigport_model::Clip;

    const FIXTURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../fixtures/asf_amc");
    const CORPUS: &str = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/corpus/3_acclaim_asf_amc"
    );

    fn fixture(name: &str) -> PathBuf {
        Path::new(FIXTURES).join(name)
    }

    /// The corpus folder, or `None` (after printing SKIPPED) when it is absent outside CI.
    fn corpus(sub: &str) -> Option<PathBuf> {
        let dir = Path::new(CORPUS).join(sub);
        if dir.is_dir() {
            return Some(dir);
        }
        assert!(
            std::env::var("CI").map_or(true, |v| v.is_empty()),
            "corpus missing at {}",
            dir.display()
        );
        println!("SKIPPED: no corpus at {}", dir.display());
        None
    }

    fn rot(axis: u8, angle_rad: f64) -> DMat3 {
        match axis {
            b'x' => DMat3::from_rotation_x(angle_rad),
            b'y' => DMat3::from_rotation_y(angle_rad),
            _ => DMat3::from_rotation_z(angle_rad),
        }
    }

    /// FORMATS.md "Acclaim ASF/AMC" applied directly, with rotation matrices and a walk down
    /// the hierarchy: `W = W_parent · C · M · C⁻¹`, a bone starts at its parent's end (the
    /// root's position under the root) and ends at `start + W · direction · length`. The
    /// root: `C` from `orientation` in `axis` order, `M` from the rotation part of `order`,
    /// position `position + (TX, TY, TZ)`. Translation dofs move a bone's start by
    /// `W_parent · C · t` (the module's documented choice). Returns the root's position,
    /// every bone's start under its name, and every leaf bone's end as `<bone>_end`.
    fn reference_positions(asf: &Asf, amc: &Amc, k: usize) -> HashMap<String, DVec3> {
        let amc_unit = amc.angle.unwrap_or(asf.units.angle);
        let c_of = |order: EulerOrder, angles: DVec3| {
            order.as_str().bytes().fold(DMat3::IDENTITY, |c, axis| {
                let a = match axis {
                    b'x' => angles.x,
                    b'y' => angles.y,
                    _ => angles.z,
                };
                rot(axis, asf.units.angle.to_radians(a)) * c
            })
        };
        let motion = |dofs: &[Dof], values: &[f64]| {
            let mut m = DMat3::IDENTITY;
            let mut t = DVec3::ZERO;
            assert_eq!(dofs.len(), values.len());
            for (d, &v) in dofs.iter().zip(values) {
                match d {
                    Dof::Rx => m = rot(b'x', amc_unit.to_radians(v)) * m,
                    Dof::Ry => m = rot(b'y', amc_unit.to_radians(v)) * m,
                    Dof::Rz => m = rot(b'z', amc_unit.to_radians(v)) * m,
                    Dof::Tx => t.x = v,
                    Dof::Ty => t.y = v,
                    Dof::Tz => t.z = v,
                    Dof::L => {}
                }
            }
            (m, t)
        };
        let frame = amc.frame_values(k).unwrap();
        // Slice the frame by walking the dof counts (independently of channel_ranges).
        let mut at = asf.root.order.len();
        let root_values = &frame[..at];
        let mut bone_values = Vec::new();
        for bone in &asf.bones {
            bone_values.push(&frame[at..at + bone.dofs.len()]);
            at += bone.dofs.len();
        }
        assert_eq!(at, frame.len());

        let mut out = HashMap::new();
        let (m_root, t_root) = motion(&asf.root.order, root_values);
        let c_root = c_of(asf.root.axis, asf.root.orientation);
        let w_root = c_root * m_root * c_root.inverse();
        let root_pos = asf.root.position + t_root;
        out.insert("root".to_string(), root_pos);
        let mut stack: Vec<(usize, DVec3, DMat3)> = (0..asf.bones.len())
            .filter(|&b| asf.bones[b].parent.is_none())
            .map(|b| (b, root_pos, w_root))
            .collect();
        while let Some((b, start, w_parent)) = stack.pop() {
            let bone = &asf.bones[b];
            let c = c_of(bone.axis_order, bone.axis);
            let (m, t) = motion(&bone.dofs, bone_values[b]);
            let w = w_parent * c * m * c.inverse();
            let start = start + w_parent * c * t;
            let end = start + w * (bone.direction * bone.length);
            out.insert(bone.name.clone(), start);
            let children: Vec<usize> = (0..asf.bones.len())
                .filter(|&c| asf.bones[c].parent == Some(b))
                .collect();
            if children.is_empty() {
                out.insert(format!("{}_end", bone.name), end);
            }
            for child in children {
                stack.push((child, end, w));
            }
        }
        out
    }

    /// Model-space joint positions from the asset's rest pose with clip key `k` applied.
    fn asset_positions(asset: &Asset, clip: &Clip, k: usize) -> HashMap<String, Vec3> {
        let joints = asset.skeleton.joints();
        let mut local: Vec<Transform> = joints.iter().map(|j| j.rest_local).collect();
        for track in &clip.tracks {
            let v = track.key_value(k);
            match track.target {
                TrackTarget::Translation(j) => local[j.get()].translation = Vec3::from_slice(v),
                TrackTarget::Rotation(j) => local[j.get()].rotation = Quat::from_slice(v),
                other => panic!("unexpected track {other:?}"),
            }
        }
        let mut world: Vec<Mat4> = Vec::with_capacity(joints.len());
        for (j, joint) in joints.iter().enumerate() {
            let m = local[j].to_mat4();
            let model = match joint.parent {
                Some(p) => world[p.get()] * m,
                None => m,
            };
            world.push(model);
        }
        joints
            .iter()
            .zip(&world)
            .map(|(j, m)| (j.name.clone(), m.w_axis.truncate()))
            .collect()
    }

    /// The largest extent of the rest pose's bounding box: the "skeleton height" the FK
    /// tolerance is relative to.
    fn height(asset: &Asset) -> f64 {
        let points: Vec<Vec3> = asset
            .skeleton
            .model_rest_matrices()
            .iter()
            .map(|m| m.w_axis.truncate())
            .collect();
        let min = points.iter().fold(Vec3::splat(f32::MAX), |a, &p| a.min(p));
        let max = points.iter().fold(Vec3::splat(f32::MIN), |a, &p| a.max(p));
        f64::from((max - min).max_element())
    }

    /// Checks clip `clip` of `imported` against [`reference_positions`] on every frame of
    /// `amc` (max deviation <= 1e-5 * height: f32 FK on values up to ~40 units rounds at
    /// ~5e-6), the key times and the quaternions. Returns the largest deviation.
    fn check_fk(asf: &Asf, amc: &Amc, imported: &Imported, clip: usize, fps: f32) -> f64 {
        let asset = &imported.asset;
        let clip = &asset.clips[clip];
        let tolerance = 1e-5 * height(asset);
        let mut worst = 0.0_f64;
        for k in 0..amc.frames.len() {
            let expected = reference_positions(asf, amc, k);
            let got = asset_positions(asset, clip, k);
            assert_eq!(expected.len(), got.len(), "joint count");
            for (name, want) in &expected {
                let have = got[name].as_dvec3();
                let d = have.distance(*want);
                worst = worst.max(d);
                assert!(
                    d <= tolerance,
                    "{}: frame {k} joint {name}: {have} vs {want} (off by {d}, tolerance {tolerance})",
                    amc.path.display()
                );
            }
        }
        for track in &clip.tracks {
            assert_eq!(track.times.len(), amc.frames.len());
            assert_eq!(track.interpolation, Interpolation::Linear);
            for (k, &t) in track.times.iter().enumerate() {
                assert_eq!(t, (k as f64 / f64::from(fps)) as f32);
            }
            if let TrackTarget::Rotation(_) = track.target {
                let mut previous: Option<Quat> = None;
                for k in 0..track.times.len() {
                    let q = Quat::from_slice(track.key_value(k));
                    assert!((q.length() - 1.0).abs() < 1e-6, "{q}");
                    if let Some(p) = previous {
                        assert!(p.dot(q) >= 0.0, "sign flip at key {k}: {p} then {q}");
                    }
                    previous = Some(q);
                }
            }
        }
        worst
    }

    fn frame_line_count(text: &str) -> usize {
        text.lines()
            .filter(|l| {
                let t = l.trim();
                !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit())
            })
            .count()
    }

    /// The ASF a `<stem>[__variant].amc` fixture belongs to.
    fn asf_for(amc: &Path) -> PathBuf {
        let stem = amc.file_stem().unwrap().to_string_lossy();
        let base = stem.split("__").next().unwrap();
        amc.with_file_name(format!("{base}.asf"))
    }

    fn read(path: &Path) -> String {
        std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    }

    #[test]
    fn every_fixture_imports_and_matches_the_formula() {
        let mut entries: Vec<PathBuf> = std::fs::read_dir(FIXTURES)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        entries.sort();
        let mut asfs = 0;
        let mut amcs = 0;
        for path in &entries {
            match path.extension().and_then(|e| e.to_str()) {
                Some("asf") => {
                    asfs += 1;
                    let imported = import(path, &[], DEFAULT_FPS).unwrap_or_else(|e| panic!("{e}"));
                    assert!(imported.asset.clips.is_empty());
                    assert!(imported.asset.validate().is_ok());
                    // One joint per bone, the root, and one per leaf bone.
                    let asf = parse_asf(&read(path), path).unwrap();
                    let leaves = (0..asf.bones.len())
                        .filter(|&b| !asf.bones.iter().any(|c| c.parent == Some(b)))
                        .count();
                    assert_eq!(imported.asset.skeleton.len(), 1 + asf.bones.len() + leaves);
                }
                Some("amc") => {
                    amcs += 1;
                    let asf_path = asf_for(path);
                    let asf = parse_asf(&read(&asf_path), &asf_path).unwrap();
                    let text = read(path);
                    let amc = parse_amc(&text, path, &asf).unwrap_or_else(|e| panic!("{e}"));
                    assert_eq!(amc.frames.len(), frame_line_count(&text));
                    let fps = 30.0;
                    let imported = import(&asf_path, std::slice::from_ref(path), fps)
                        .unwrap_or_else(|e| panic!("{e}"));
                    let clip = &imported.asset.clips[0];
                    assert_eq!(clip.name, path.file_stem().unwrap().to_string_lossy());
                    let worst = check_fk(&asf, &amc, &imported, 0, fps);
                    println!("{}: max FK deviation {worst:e}", path.display());
                    for w in &imported.warnings {
                        println!("  warning: {w}");
                    }
                }
                _ => {}
            }
        }
        assert!(asfs >= 8 && amcs >= 8, "{asfs} ASF and {amcs} AMC fixtures");
    }

    #[test]
    fn chain_skeleton_and_units() {
        let asf = parse_asf(&read(&fixture("chain.asf")), &fixture("chain.asf")).unwrap();
        assert_eq!(asf.version.as_deref(), Some("1.10"));
        assert_eq!(asf.name.as_deref(), Some("chain"));
        assert_eq!(asf.units.length, Some(0.45));
        assert_eq!(asf.units.mass, Some(1.0));
        assert_eq!(asf.units.angle, AngleUnit::Degrees);
        assert_eq!(asf.documentation.len(), 1);
        let shin = &asf.bones[2];
        assert_eq!(shin.name, "shin");
        assert_eq!(shin.id, Some(3));
        assert_eq!(shin.axis, DVec3::new(-35.0, 15.0, 50.0));
        assert_eq!(shin.axis_order, EulerOrder::Zxy);
        assert_eq!(shin.dofs, vec![Dof::Rz, Dof::Rx]);
        assert_eq!(shin.limits, vec![(-90.0, 90.0), (-10.0, 170.0)]);
        assert_eq!(shin.parent, Some(1));
        assert_eq!(shin.line, 37);
        assert_eq!(shin.hierarchy_line, 59);
        let foot = &asf.bones[3];
        assert_eq!(foot.limits[0], (f64::NEG_INFINITY, f64::INFINITY));
        assert_eq!(foot.dofs, vec![Dof::Ry, Dof::Rz, Dof::Rx]);
        assert_eq!(asf.channel_count(), 6 + 3 + 2 + 3);
        assert_eq!(asf.channel_ranges(), vec![0..6, 6..6, 6..9, 9..11, 11..14]);

        let imported = to_asset("chain", &asf, &[], DEFAULT_FPS).unwrap();
        assert!(imported.warnings.is_empty(), "{:?}", imported.warnings);
        let asset = &imported.asset;
        let mpu = asset.meters_per_unit.unwrap();
        assert!((mpu - 0.0254 / 0.45).abs() < 1e-15);
        let s = &asset.skeleton;
        let names: Vec<&str> = s.joints().iter().map(|j| j.name.as_str()).collect();
        assert_eq!(names, ["root", "hip", "thigh", "shin", "foot", "foot_end"]);
        let parents: Vec<Option<u32>> = s.parents().map(|p| p.map(|j| j.0)).collect();
        assert_eq!(parents, [None, Some(0), Some(1), Some(2), Some(3), Some(4)]);
        // Each joint sits at its bone's start: offset = the parent bone's direction*length.
        let t = |name: &str| s.joint(s.find(name).unwrap()).rest_local;
        assert_eq!(t("hip").translation, Vec3::ZERO);
        assert_eq!(t("thigh").translation, Vec3::new(1.2, -1.6, 0.0));
        assert_eq!(t("shin").translation, Vec3::new(0.0, -7.0, 0.0));
        assert_eq!(t("foot_end").translation, Vec3::new(0.0, 0.0, 2.0));
        assert!(s
            .joints()
            .iter()
            .all(|j| j.rest_local.rotation == Quat::IDENTITY));
    }

    #[test]
    fn chain_motion_matches_the_formula_on_every_frame() {
        // The hand-made 3-bone check the mapping rests on: non-trivial axis angles in
        // three axis orders (XYZ, ZXY, YZX), dof orders rx ry rz / rz rx / ry rz rx, and
        // angles up to 179 degrees.
        let asf = parse_asf(&read(&fixture("chain.asf")), &fixture("chain.asf")).unwrap();
        let amc = parse_amc(&read(&fixture("chain.amc")), &fixture("chain.amc"), &asf).unwrap();
        assert_eq!(amc.frames.len(), 4);
        assert!(amc.fully_specified);
        assert_eq!(amc.angle, Some(AngleUnit::Degrees));
        assert_eq!(
            amc.frame_values(0).unwrap(),
            [1.5, 17.25, -3.0, 5.0, 10.0, -15.0, -30.0, 12.0, 8.0, 20.0, 45.0, 10.0, -5.0, 15.0]
        );
        let motions = [("walk".to_string(), amc)];
        let imported = to_asset("chain", &asf, &motions, 60.0).unwrap();
        let worst = check_fk(&asf, &motions[0].1, &imported, 0, 60.0);
        assert!(worst < 1e-5, "{worst}");
        // The formula is not trivially satisfied: the motion moves the foot's end.
        let rest = reference_positions(&asf, &motions[0].1, 3);
        let moved = reference_positions(&asf, &motions[0].1, 2);
        assert!(rest["foot_end"].distance(moved["foot_end"]) > 1.0);
        let clip = &imported.asset.clips[0];
        assert_eq!(clip.name, "walk");
        // Root translation + rotation, and a rotation track per rotating bone.
        assert_eq!(clip.tracks.len(), 2 + 3);
        assert!((clip.duration() - 3.0 / 60.0).abs() < 1e-7);
        // Root translation keys are the frame's TX TY TZ (position is 0).
        let root_t = &clip.tracks[0];
        assert_eq!(root_t.target, TrackTarget::Translation(JointIndex(0)));
        assert_eq!(root_t.key_value(1), [1.75, 17.3, -2.5]);
    }

    #[test]
    fn a_local_rotation_is_c_m_c_inverse() {
        // One bone, one frame, by hand: axis 0 0 90 XYZ (C = Rz(90)), dof rx = 90. In the
        // bone's frame x is the world's y, so the bone turns 90 degrees about world y.
        let text = ":root\n order TX TY TZ RX RY RZ\n axis XYZ\n position 0 0 0\n orientation 0 0 0\n:bonedata\n begin\n name b\n direction 1 0 0\n length 2\n axis 0 0 90 XYZ\n dof rx\n end\n:hierarchy\n begin\n root b\n end\n";
        let asf = parse_asf(text, Path::new("t.asf")).unwrap();
        let amc = parse_amc("1\nroot 0 0 0 0 0 0\nb 90\n", Path::new("t.amc"), &asf).unwrap();
        let imported = to_asset("t", &asf, &[("m".into(), amc)], 1.0).unwrap();
        let got = asset_positions(&imported.asset, &imported.asset.clips[0], 0);
        // World y rotation by 90 degrees takes +x to -z.
        assert!(
            got["b_end"].abs_diff_eq(Vec3::new(0.0, 0.0, -2.0), 1e-6),
            "{}",
            got["b_end"]
        );
    }

    #[test]
    fn root_frame_rest_frame_and_channel_order() {
        let asf_path = fixture("root_frame.asf");
        let asf = parse_asf(&read(&asf_path), &asf_path).unwrap();
        assert_eq!(
            asf.root.order,
            [Dof::Rz, Dof::Ry, Dof::Rx, Dof::Tx, Dof::Ty, Dof::Tz]
        );
        assert_eq!(asf.root.axis, EulerOrder::Zyx);
        assert_eq!(asf.root.position, DVec3::new(1.0, 2.0, 3.0));
        assert_eq!(asf.root.orientation, DVec3::new(10.0, -20.0, 30.0));
        assert_eq!(asf.units.meters_per_unit(), Some(0.0254));
        let imported = import(&asf_path, &[fixture("root_frame.amc")], DEFAULT_FPS).unwrap();
        let asset = &imported.asset;
        // Frame 1 is all zeros: the rest pose, whatever the root's orientation.
        let posed = asset_positions(asset, &asset.clips[0], 0);
        let rest = asset.skeleton.model_rest_matrices();
        for (j, joint) in asset.skeleton.joints().iter().enumerate() {
            let r = rest[j].w_axis.truncate();
            assert!(posed[&joint.name].abs_diff_eq(r, 1e-6), "{}", joint.name);
        }
        assert_eq!(
            asset.skeleton.joint(JointIndex(0)).rest_local.translation,
            Vec3::new(1.0, 2.0, 3.0)
        );
        // Frame 2 translates by the last three values (TX TY TZ come after the rotations).
        let root_t = &asset.clips[0].tracks[0];
        assert_eq!(root_t.key_value(1), [1.5, 1.75, 4.0]);
    }

    #[test]
    fn amc_angle_header_overrides_the_asf() {
        let asf_path = fixture("radians.asf");
        let asf = parse_asf(&read(&asf_path), &asf_path).unwrap();
        assert_eq!(asf.units.angle, AngleUnit::Radians);
        assert_eq!(asf.bones[1].limits, [(-0.17, 2.97)]);
        let rad = parse_amc(
            &read(&fixture("radians.amc")),
            &fixture("radians.amc"),
            &asf,
        )
        .unwrap();
        let deg = parse_amc(
            &read(&fixture("radians__degrees.amc")),
            &fixture("radians__degrees.amc"),
            &asf,
        )
        .unwrap();
        assert_eq!(rad.angle, None);
        assert_eq!(deg.angle, Some(AngleUnit::Degrees));
        let imported = to_asset(
            "radians",
            &asf,
            &[("rad".into(), rad), ("deg".into(), deg)],
            DEFAULT_FPS,
        )
        .unwrap();
        let clips = &imported.asset.clips;
        assert_eq!(clips[0].name, "rad");
        assert_eq!(clips[1].name, "deg");
        for k in 0..2 {
            let a = asset_positions(&imported.asset, &clips[0], k);
            let b = asset_positions(&imported.asset, &clips[1], k);
            for (name, p) in &a {
                assert!(p.abs_diff_eq(b[name], 1e-5), "{name}: {p} vs {}", b[name]);
            }
        }
        // Read as degrees, the radian values would barely move the leg: the unit matters.
        let end = |clip: &Clip| asset_positions(&imported.asset, clip, 0)["lower_end"];
        assert!(end(&clips[0]).distance(Vec3::new(0.0, 0.0, 0.0)) > 1.0);
    }

    #[test]
    fn text_quirks_parse_like_clean_text() {
        let asf_path = fixture("quirks.asf");
        let asf = parse_asf(&read(&asf_path), &asf_path).unwrap();
        assert_eq!(asf.units.length, Some(0.45));
        assert_eq!(asf.units.angle, AngleUnit::Degrees);
        assert_eq!(asf.documentation, ["free text"]);
        assert_eq!(asf.root.axis, EulerOrder::Xyz);
        let names: Vec<&str> = asf.bones.iter().map(|b| b.name.as_str()).collect();
        assert_eq!(names, ["Hip", "Thigh"]);
        assert_eq!(asf.bones[1].axis_order, EulerOrder::Xyz);
        assert_eq!(asf.bones[1].dofs, [Dof::Rx, Dof::Ry, Dof::Rz]);
        assert_eq!(
            asf.bones[1].limits,
            [(-160.0, 20.0), (-70.0, 70.0), (-60.0, 70.0)]
        );
        assert_eq!(asf.bones[1].line, 29);
        let amc = parse_amc(&read(&fixture("quirks.amc")), &fixture("quirks.amc"), &asf).unwrap();
        assert_eq!(amc.frames.len(), 2);
        assert_eq!(
            amc.frames[1],
            AmcFrame {
                number: 2,
                line: 10
            }
        );
        assert_eq!(
            amc.frame_values(1).unwrap(),
            [1.25, 17.1, -2.5, 6.0, 9.0, -14.0, -25.0, 10.0, 5.0]
        );
        assert!(amc.held.is_empty());
    }

    #[test]
    fn unordered_bones_are_sorted_parents_first() {
        let imported = import(
            &fixture("unordered.asf"),
            &[fixture("unordered.amc")],
            DEFAULT_FPS,
        )
        .unwrap();
        let s = &imported.asset.skeleton;
        let names: Vec<&str> = s.joints().iter().map(|j| j.name.as_str()).collect();
        // Every parent before its children.
        for (j, joint) in s.joints().iter().enumerate() {
            if let Some(p) = joint.parent {
                assert!(p.get() < j);
            }
        }
        let parent = |name: &str| {
            let j = s.joint(s.find(name).unwrap());
            s.joint(j.parent.unwrap()).name.clone()
        };
        assert_eq!(parent("pelvis"), "root");
        assert_eq!(parent("spine"), "pelvis");
        assert_eq!(parent("head"), "spine");
        assert_eq!(parent("lfoot"), "lleg");
        assert_eq!(parent("lfoot_end"), "lfoot");
        assert_eq!(parent("rleg_end"), "rleg");
        assert_eq!(names.len(), 1 + 6 + 3);
        // pelvis has no dofs: no track; spine (rz ry) gets one.
        let clip = &imported.asset.clips[0];
        let targets: Vec<TrackTarget> = clip.tracks.iter().map(|t| t.target).collect();
        assert!(!targets.contains(&TrackTarget::Rotation(s.find("pelvis").unwrap())));
        assert!(targets.contains(&TrackTarget::Rotation(s.find("spine").unwrap())));
        // Tracks come in joint order.
        assert!(targets.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn translation_dofs_move_along_the_bone_frame_and_l_is_noted() {
        let imported = import(
            &fixture("translation.asf"),
            &[fixture("translation.amc")],
            DEFAULT_FPS,
        )
        .unwrap();
        let s = &imported.asset.skeleton;
        let clip = &imported.asset.clips[0];
        let slider = s.find("slider").unwrap();
        let track = clip
            .tracks
            .iter()
            .find(|t| t.target == TrackTarget::Translation(slider))
            .unwrap();
        // C = Rz(90): t = (0.5, -1, 2) in the bone frame is (1, 0.5, 2) in the parent's.
        let v = Vec3::from_slice(track.key_value(0));
        assert!(v.abs_diff_eq(Vec3::new(1.0, 0.5, 2.0), 1e-6), "{v}");
        let notes: Vec<String> = imported.warnings.iter().map(ToString::to_string).collect();
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(
            notes[0].ends_with("translation.asf:29: bone \"stretch\": the length dof `l` is not supported; its values are ignored"),
            "{}",
            notes[0]
        );
        // Without motions nothing is lost, so no note.
        let skeleton_only = import(&fixture("translation.asf"), &[], DEFAULT_FPS).unwrap();
        assert!(skeleton_only.warnings.is_empty());
    }

    #[test]
    fn missing_bones_hold_their_previous_value() {
        let asf = parse_asf(&read(&fixture("chain.asf")), &fixture("chain.asf")).unwrap();
        let path = fixture("chain__held.amc");
        let amc = parse_amc(&read(&path), &path, &asf).unwrap();
        assert_eq!(
            amc.held,
            [
                HeldValue {
                    frame: 0,
                    bone: Some(2)
                },
                HeldValue {
                    frame: 2,
                    bone: None
                },
                HeldValue {
                    frame: 2,
                    bone: Some(3)
                },
            ]
        );
        // Frame 1's shin is at rest; frame 3's root and foot are frame 2's.
        assert_eq!(amc.frame_values(0).unwrap()[9..11], [0.0, 0.0]);
        let (f1, f2) = (amc.frame_values(1).unwrap(), amc.frame_values(2).unwrap());
        assert_eq!(f2[..6], f1[..6]);
        assert_eq!(f2[11..], f1[11..]);
        assert_eq!(f2[6..9], [170.0, -80.0, 95.0]);
        let imported = to_asset("chain", &asf, &[("held".into(), amc)], DEFAULT_FPS).unwrap();
        let messages: Vec<String> = imported.warnings.iter().map(ToString::to_string).collect();
        assert_eq!(messages.len(), 1, "{messages:?}");
        assert!(matches!(imported.warnings[0], Warning::Repaired { .. }));
        assert!(
            messages[0].ends_with("chain__held.amc:5: repaired: 3 bone entries were missing from 2 frames (the first: \"shin\" in frame 1); each held its value from the frame before (the rest pose in the first frame)"),
            "{}",
            messages[0]
        );
    }

    #[test]
    fn frame_number_gaps_are_noted_and_keys_stay_in_file_order() {
        let imported = import(
            &fixture("chain.asf"),
            &[fixture("chain__gaps.amc")],
            DEFAULT_FPS,
        )
        .unwrap();
        let messages: Vec<String> = imported.warnings.iter().map(ToString::to_string).collect();
        assert_eq!(messages.len(), 1, "{messages:?}");
        assert!(
            messages[0].ends_with("chain__gaps.amc:14: frame numbers are not consecutive in 1 place (the first: frame 5 after frame 2); kept the file's order, key k at k / 120 s"),
            "{}",
            messages[0]
        );
        let times = &imported.asset.clips[0].tracks[0].times;
        assert_eq!(times.len(), 4);
        assert_eq!(times[2], (2.0_f64 / 120.0) as f32);
    }

    #[test]
    fn no_units_and_skipped_parts() {
        let imported = import(&fixture("no_units.asf"), &[], DEFAULT_FPS).unwrap();
        assert_eq!(imported.asset.meters_per_unit, None);
        assert!(imported.warnings.is_empty());
        let asf = parse_asf(&read(&fixture("no_units.asf")), &fixture("no_units.asf")).unwrap();
        assert_eq!(asf.units, Units::default());

        let imported = import(&fixture("skipped.asf"), &[], DEFAULT_FPS).unwrap();
        let messages: Vec<String> = imported.warnings.iter().map(ToString::to_string).collect();
        assert_eq!(messages.len(), 2, "{messages:?}");
        assert!(
            messages[0].ends_with("skipped.asf:10: skipped `units time`: rigport does not use it"),
            "{}",
            messages[0]
        );
        assert!(
            messages[1].ends_with("skipped.asf:16: skipped `:skin`: rigport does not use it"),
            "{}",
            messages[1]
        );
        assert_eq!(imported.asset.skeleton.len(), 3);
    }

    #[test]
    fn clips_follow_the_amc_order_and_fps_is_checked() {
        let asf = fixture("chain.asf");
        let amcs = [fixture("chain__gaps.amc"), fixture("chain.amc")];
        let imported = import(&asf, &amcs, 24.0).unwrap();
        let names: Vec<&str> = imported
            .asset
            .clips
            .iter()
            .map(|c| c.name.as_str())
            .collect();
        assert_eq!(names, ["chain__gaps", "chain"]);
        assert_eq!(imported.asset.name, "chain");
        for fps in [0.0, -30.0, f32::NAN, f32::INFINITY] {
            let e = import(&asf, &amcs, fps).unwrap_err().to_string();
            assert!(
                e.ends_with(&format!(
                    "chain.asf: the frame rate must be finite and positive, got {fps} fps"
                )),
                "{e}"
            );
        }
        // An AMC parsed against another skeleton is refused, not misread.
        let other = parse_asf(
            &read(&fixture("root_frame.asf")),
            &fixture("root_frame.asf"),
        )
        .unwrap();
        let chain = parse_asf(&read(&asf), &asf).unwrap();
        let amc = parse_amc(&read(&amcs[1]), &amcs[1], &chain).unwrap();
        let e = to_asset("x", &other, &[("m".into(), amc)], 30.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("it was parsed against another skeleton"), "{e}");
    }

    // ------------------------------------------------------------------------------
    // One negative test per invalid field.

    /// A valid ASF; the line numbers below refer to it.
    const BASE: &str = "\
:units
  length 0.45
  angle deg
:root
  order TX TY TZ RX RY RZ
  axis XYZ
  position 0 0 0
  orientation 0 0 0
:bonedata
  begin
    id 1
    name a
    direction 0 1 0
    length 2
    axis 0 0 0 XYZ
    dof rx ry rz
    limits (-10 10)
           (-20 20)
           (-30 30)
  end
  begin
    id 2
    name b
    direction 1 0 0
    length 1
    axis 0 0 10 XYZ
    dof rz
  end
:hierarchy
  begin
    root a
    a b
  end
";

    /// The error for BASE with `old` replaced by `new` (which must occur).
    fn asf_err(old: &str, new: &str) -> String {
        assert!(BASE.contains(old), "{old:?}");
        let text = BASE.replacen(old, new, 1);
        parse_asf(&text, Path::new("t.asf"))
            .expect_err("should fail")
            .to_string()
    }

    #[test]
    fn base_is_valid() {
        let asf = parse_asf(BASE, Path::new("t.asf")).unwrap();
        assert_eq!(asf.bones.len(), 2);
        let imported = to_asset("t", &asf, &[], 30.0).unwrap();
        assert_eq!(imported.asset.skeleton.len(), 4);
    }

    #[test]
    fn asf_errors_name_the_line() {
        let cases: &[(&str, &str, &str)] = &[
            ("direction 0 1 0", "direction 0 x 0", "t.asf:13:17: expected a number (direction), found \"x\""),
            ("direction 0 1 0", "direction 0 1", "t.asf:13: expected 3 numbers after `direction`, found \"direction 0 1\""),
            ("direction 0 1 0", "direction 0 1 0 0", "t.asf:13: expected 3 numbers after `direction`, found \"direction 0 1 0 0\""),
            ("length 2", "length -1.#IND", "t.asf:14:12: expected a number (length), found \"-1.#IND\""),
            ("length 2", "length inf", "t.asf:14:12: length is not finite: \"inf\""),
            ("length 2", "length -2", "t.asf:14:12: a bone length must not be negative, got -2"),
            ("length 2", "length", "t.asf:14: expected one number after `length`, found \"length\""),
            ("dof rz", "dof rq", "t.asf:27:9: expected a dof (tx ty tz rx ry rz l), found \"rq\""),
            ("dof rz", "dof", "t.asf:27: expected at least one dof: a dof (tx ty tz rx ry rz l), found \"dof\""),
            ("dof rx ry rz", "dof rx ry rx", "t.asf:16:15: dof rx is listed twice"),
            ("axis 0 0 10 XYZ", "axis 0 0 10 XYW", "t.asf:26:17: expected an axis order (XYZ, XZY, YXZ, YZX, ZXY or ZYX), found \"XYW\""),
            ("axis 0 0 10 XYZ", "axis 0 0 10", "t.asf:26: expected 3 angles and an axis order after `axis` (e.g. `axis 0 0 20 XYZ`), found \"axis 0 0 10\""),
            ("axis 0 0 10 XYZ", "axis 0 0 1e999 XYZ", "t.asf:26:14: axis angle is not finite: \"1e999\""),
            ("id 2", "id two", "t.asf:22:8: expected an integer bone id, found \"two\""),
            ("id 2", "idx 2", "t.asf:22:5: expected a bone entry (`id`, `name`, `direction`, `length`, `axis`, `dof`, `limits`, `end`), found \"idx\""),
            ("    id 2\n", "    id 2\n    id 3\n", "t.asf:23: `id` is given twice in the bone block (first on line 22)"),
            ("name b", "name a", "t.asf:23:10: two bones are named \"a\" (the first on line 12)"),
            ("name b", "name Root", "t.asf:23:10: a bone cannot be named \"Root\": the name is reserved for the root"),
            ("name b", "name b c", "t.asf:23: expected one bone name (no spaces) after `name`, found \"name b c\""),
            ("           (-30 30)\n", "", "t.asf:17: bone \"a\" has 2 limit pairs for 3 dofs"),
            ("(-20 20)", "(-20 20", "t.asf:18: expected a complete `(min max)` pair on one line, found \"(-20 20\""),
            ("(-20 20)", "(-20 nan)", "t.asf:18:17: expected a limit (a number, `inf` or `-inf`), found \"nan\""),
            ("(-20 20)", "-20 20", "t.asf:18:12: expected a bone entry (`id`, `name`, `direction`, `length`, `axis`, `dof`, `limits`, `end`), found \"-20\""),
            ("limits (-10 10)", "limits -10 10", "t.asf:17:12: expected `(` (a limit pair), found \"-10\""),
            ("limits (-10 10)", "limits (-10 10 5)", "t.asf:17:20: expected `)` after two limits, found \"5\""),
            ("    length 1\n", "", "t.asf:27: the bone block opened on line 21 has no `length`"),
            ("    name b\n", "", "t.asf:27: the bone block opened on line 21 has no `name`"),
            ("    dof rz\n  end\n", "    dof rz\n", "t.asf:28: the bone block opened on line 21 has no `end` before the next section starts"),
            ("  begin\n    id 2", "  begin\n  begin\n    id 2", "t.asf:22: `begin` inside the bone block opened on line 21 (missing `end`)"),
            ("  end\n  begin\n    id 2", "  end\n  start\n    id 2", "t.asf:21: expected `begin` (a bone block), found \"start\""),
            ("  end\n:hierarchy", "  end x\n:hierarchy", "t.asf:28:7: expected nothing after `end`, found \"x\""),
            ("a b\n", "a c\n", "t.asf:32:7: unknown bone \"c\": `:bonedata` has no bone of that name"),
            ("a b\n", "x b\n", "t.asf:32:5: unknown bone \"x\": `:bonedata` has no bone of that name"),
            ("a b\n", "a b root\n", "t.asf:32:9: the root cannot be a child"),
            ("a b\n", "b b\n", "t.asf:32:7: bone \"b\" is listed as its own child"),
            ("root a\n", "root a b\n", "t.asf:32:7: bone \"b\" already is a child of \"root\" (line 31)"),
            ("a b\n", "a\n", "t.asf:23: bone \"b\" is not listed as a child in `:hierarchy`, so it has no place in the skeleton"),
            ("root a\n    a b\n", "b a\n    a b\n", "t.asf:31: bones b -> a form a parent cycle, not connected to the root"),
            ("    a b\n  end\n", "    a b\n", "t.asf:32: truncated: the `:hierarchy` block opened on line 30 has no `end` before the file ends"),
            (":hierarchy\n  begin\n", ":hierarchy\n  start\n", "t.asf:30: expected `begin` (the hierarchy block), found \"start\""),
            ("    a b\n  end\n", "    a b\n  end\n  more\n", "t.asf:34: expected the next `:section` (the hierarchy block has ended), found \"more\""),
            ("  length 0.45", "  length 0", "t.asf:2:10: the length unit must be positive, got 0"),
            ("  length 0.45", "  length 0.45 m", "t.asf:2: expected a `:units` entry `name value` (`mass 1.0`, `length 0.45`, `angle deg`), found \"length 0.45 m\""),
            ("  angle deg", "  angle grad", "t.asf:3:9: expected `deg` or `rad`, found \"grad\""),
            ("  angle deg", "  angle deg\n  ANGLE rad", "t.asf:4: `angle` is given twice in `:units` (first on line 3)"),
            ("order TX TY TZ RX RY RZ", "order TX TY TZ RX RY L", "t.asf:5:24: expected a root dof (TX TY TZ RX RY RZ), found \"L\""),
            ("  axis XYZ\n", "", "t.asf:4: `:root` has no `axis` line"),
            ("  axis XYZ", "  axis XYZ ZYX", "t.asf:6: expected one axis order after `axis` (e.g. `axis XYZ`), found \"axis XYZ ZYX\""),
            ("  position 0 0 0", "  position 0 0", "t.asf:7: expected 3 numbers after `position`, found \"position 0 0\""),
            ("  orientation 0 0 0", "  orientation 0 0 0\n  scale 1", "t.asf:9:3: expected `order`, `axis`, `position` or `orientation`, found \"scale\""),
            (":units\n", "hello\n:units\n", "t.asf:1: expected a `:keyword` line (`:units`, `:root`, `:bonedata`, `:hierarchy`, ...), found \"hello\""),
            (":root\n", ":units\n:root\n", "t.asf:4: `:units` is given twice (first on line 1)"),
            (":root\n", ":root x\n", "t.asf:4:7: expected nothing after `:root` (its entries go on the next lines), found \"x\""),
        ];
        for (old, new, expected) in cases {
            assert_eq!(
                &asf_err(old, new),
                expected,
                "replacing {old:?} with {new:?}"
            );
        }
    }

    #[test]
    fn asf_missing_sections_and_empty_files() {
        let root_only =
            ":root\n  order TX TY TZ RX RY RZ\n  axis XYZ\n  position 0 0 0\n  orientation 0 0 0\n";
        let e = parse_asf(root_only, Path::new("t.asf")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.asf:5: truncated: the file ends without a `:bonedata` section"
        );
        assert!(matches!(e.problem, Problem::Truncated(_)));
        let e = parse_asf(":units\n  length 1\n", Path::new("t.asf")).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.asf:2: truncated: the file ends without a `:root` section"
        );
        let cut = &BASE[..BASE.find("    length 1").unwrap()];
        assert_eq!(
            parse_asf(cut, Path::new("t.asf")).unwrap_err().to_string(),
            "t.asf:24: truncated: the bone block opened on line 21 has no `end` before the file ends"
        );
        for empty in ["", "\n\n", "# only a comment\r\n  \r\n"] {
            let e = parse_asf(empty, Path::new("t.asf")).unwrap_err();
            assert!(matches!(e.problem, Problem::Empty), "{e}");
        }
        // A root with no bones is a valid (one-joint) skeleton.
        let asf = parse_asf(&format!("{root_only}:bonedata\n"), Path::new("t.asf")).unwrap();
        assert_eq!(
            to_asset("t", &asf, &[], 30.0).unwrap().asset.skeleton.len(),
            1
        );
    }

    #[test]
    fn end_joint_names_must_not_clash_with_bones() {
        let text = BASE
            .replacen("name b", "name a_end", 1)
            .replacen("a b\n", "root a_end\n", 1);
        let asf = parse_asf(&text, Path::new("t.asf")).unwrap();
        let e = to_asset("t", &asf, &[], 30.0).unwrap_err().to_string();
        assert_eq!(
            e,
            "t.asf:23: bone \"a_end\" has the name rigport gives the end joint of leaf bone \"a\""
        );
    }

    #[test]
    fn edited_asf_structs_do_not_panic() {
        // `Asf` fields are public: a cycle or a dangling parent edited in is an error.
        let mut asf = parse_asf(BASE, Path::new("t.asf")).unwrap();
        asf.bones[0].parent = Some(1);
        let e = to_asset("t", &asf, &[], 30.0).unwrap_err().to_string();
        assert_eq!(
            e,
            "t.asf:31: bones b -> a form a parent cycle, not connected to the root"
        );
        asf.bones[0].parent = Some(7);
        let e = to_asset("t", &asf, &[], 30.0).unwrap_err().to_string();
        assert_eq!(
            e,
            "t.asf:31: bone \"a\" names parent bone #7, but there are 2 bones"
        );
        let mut asf = parse_asf(BASE, Path::new("t.asf")).unwrap();
        asf.bones[0].length = 1e39;
        let e = to_asset("t", &asf, &[], 30.0).unwrap_err().to_string();
        assert!(
            e.starts_with("t.asf:23: joint \"b\": its rest offset"),
            "{e}"
        );
    }

    const BASE_AMC: &str = ":FULLY-SPECIFIED\n:DEGREES\n1\nroot 0 0 0 0 0 0\na 1 2 3\nb 4\n";

    fn amc_err(old: &str, new: &str) -> String {
        assert!(BASE_AMC.contains(old), "{old:?}");
        let asf = parse_asf(BASE, Path::new("t.asf")).unwrap();
        parse_amc(&BASE_AMC.replacen(old, new, 1), Path::new("t.amc"), &asf)
            .expect_err("should fail")
            .to_string()
    }

    #[test]
    fn amc_errors_name_the_line() {
        let cases: &[(&str, &str, &str)] = &[
            ("a 1 2 3", "a 1 2", "t.amc:5: \"a\" has 2 values, but its dofs (rx ry rz) need 3"),
            ("a 1 2 3", "a 1 2 3 4", "t.amc:5: \"a\" has 4 values, but its dofs (rx ry rz) need 3"),
            ("root 0 0 0 0 0 0", "root 0 0 0", "t.amc:4: \"root\" has 3 values, but its dofs (tx ty tz rx ry rz) need 6"),
            ("b 4", "c 4", "t.amc:6:1: unknown bone \"c\": the skeleton t.asf has no bone of that name"),
            ("b 4", "B 4", "t.amc:6:1: unknown bone \"B\": the skeleton t.asf has no bone of that name"),
            ("b 4", "b 4x", "t.amc:6:3: expected a number (a dof value), found \"4x\""),
            ("b 4", "b nan", "t.amc:6:3: a dof value is not finite: \"nan\""),
            ("b 4", "b 4\na 1 2 3", "t.amc:7: \"a\" is given twice in frame 1 (first on line 5)"),
            ("1\n", "", "t.amc:3: the bone line for \"root\" comes before the first frame number"),
            ("1\n", "-1\n", "t.amc:3:1: expected a frame number (a non-negative integer), found \"-1\""),
            ("1\n", "1.5\n", "t.amc:3:1: expected a frame number (a non-negative integer), found \"1.5\""),
            ("1\n", "99999999999999999999999\n", "t.amc:3:1: expected a frame number that fits 64 bits, found \"99999999999999999999999\""),
            ("b 4\n", "b 4\n:DEGREES\n", "t.amc:7: expected a frame number or a bone line (`:` header lines come before the first frame), found \":DEGREES\""),
            (":DEGREES\n", ":DEGREES\n:radians\n", "t.amc:3: :radians contradicts the angle unit given on line 2"),
        ];
        for (old, new, expected) in cases {
            assert_eq!(
                &amc_err(old, new),
                expected,
                "replacing {old:?} with {new:?}"
            );
        }
        let asf = parse_asf(BASE, Path::new("t.asf")).unwrap();
        let e = parse_amc(":FULLY-SPECIFIED\n:DEGREES\n", Path::new("t.amc"), &asf).unwrap_err();
        assert_eq!(
            e.to_string(),
            "t.amc:2: truncated: the file ends before its first frame"
        );
        let e = parse_amc("\r\n# nothing\n", Path::new("t.amc"), &asf).unwrap_err();
        assert!(matches!(e.problem, Problem::Empty), "{e}");
        // Huge values parse, but a translation beyond f32 is refused at its frame.
        let amc = parse_amc("1\nroot 1e300 0 0 0 0 0\n", Path::new("t.amc"), &asf).unwrap();
        let e = to_asset("t", &asf, &[("m".into(), amc)], 30.0)
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "t.amc:1: frame 1: the translation of joint \"root\" does not fit 32-bit floats"
        );
        // Too many frames for distinct f32 key times at a tiny rate.
        let amc = parse_amc("1\n2\n", Path::new("t.amc"), &asf).unwrap();
        let e = to_asset("t", &asf, &[("m".into(), amc)], 1e-40)
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("t.amc: frame 1 at"), "{e}");
    }

    #[test]
    fn amc_bones_without_dofs_may_be_listed_and_lines_may_break_oddly() {
        let text = "\
:units\n angle deg\n:root\n order TX TY TZ RX RY RZ\n axis XYZ\n position 0 0 0\n orientation 0 0 0\n\
:bonedata\n begin\n name a\n direction 0 1 0\n length 1\n axis 0 0 0 XYZ\n end\n\
:hierarchy\n begin\n root a\n end\n";
        let asf = parse_asf(text, Path::new("t.asf")).unwrap();
        let amc = parse_amc(
            "1\rroot 0 1 0 0 0 0\ra\r2\r\nroot 0 2 0 0 0 0 # comment\n",
            Path::new("t.amc"),
            &asf,
        )
        .unwrap();
        assert_eq!(
            amc.frames,
            [
                AmcFrame { number: 1, line: 1 },
                AmcFrame { number: 2, line: 4 }
            ]
        );
        assert_eq!(
            amc.values,
            [0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0]
        );
        let e = parse_amc("1\na 5\n", Path::new("t.amc"), &asf)
            .unwrap_err()
            .to_string();
        assert_eq!(e, "t.amc:2: \"a\" has 1 values, but its dofs (none) need 0");
    }

    // ------------------------------------------------------------------------------
    // Fuzzing: truncations and byte edits never panic.

    const FUZZ_SEEDS: [(&str, &str); 3] = [
        (
            include_str!("../../../fixtures/asf_amc/chain.asf"),
            include_str!("../../../fixtures/asf_amc/chain.amc"),
        ),
        (
            include_str!("../../../fixtures/asf_amc/quirks.asf"),
            include_str!("../../../fixtures/asf_amc/quirks.amc"),
        ),
        (
            include_str!("../../../fixtures/asf_amc/translation.asf"),
            include_str!("../../../fixtures/asf_amc/translation.amc"),
        ),
    ];

    /// Bytes that steer edits towards the format's own tokens.
    const INTERESTING: &[u8] = b"0123456789 .-+eE\n\r\t#():,xyzXYZrtlLa_";

    fn edit(text: &str, cut: f64, edits: &[(f64, u8, bool, u8)]) -> String {
        let mut bytes = text.as_bytes().to_vec();
        for &(at, byte, interesting, op) in edits {
            let i = ((at * bytes.len() as f64) as usize).min(bytes.len());
            let b = if interesting {
                INTERESTING[byte as usize % INTERESTING.len()]
            } else {
                byte
            };
            match op {
                0 if i < bytes.len() => bytes[i] = b,
                1 => bytes.insert(i, b),
                _ if i < bytes.len() => {
                    bytes.remove(i);
                }
                _ => {}
            }
        }
        bytes.truncate(((cut * bytes.len() as f64) as usize).min(bytes.len()));
        String::from_utf8_lossy(&bytes).into_owned()
    }

    fn run_all(asf_text: &str, amc_text: &str) {
        let Ok(asf) = parse_asf(asf_text, Path::new("f.asf")) else {
            return;
        };
        let _ = to_asset("f", &asf, &[], 30.0);
        if let Ok(amc) = parse_amc(amc_text, Path::new("f.amc"), &asf) {
            let _ = to_asset("f", &asf, &[("m".into(), amc)], 30.0);
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(512))]
        #[test]
        fn truncated_or_edited_files_never_panic(
            seed in 0_usize..FUZZ_SEEDS.len(),
            cut_asf in 0.0_f64..=1.0,
            cut_amc in 0.0_f64..=1.0,
            edits in proptest::collection::vec(
                (0.0_f64..1.0, proptest::prelude::any::<u8>(), proptest::prelude::any::<bool>(), 0_u8..3),
                0..10,
            ),
        ) {
            let (asf, amc) = FUZZ_SEEDS[seed];
            let (asf_edits, amc_edits) = edits.split_at(edits.len() / 2);
            let asf_edited = edit(asf, 1.0, asf_edits);
            let amc_edited = edit(amc, cut_amc, amc_edits);
            // Edited ASF with the pristine motion, pristine ASF with the edited motion,
            // both edited, and a truncated ASF.
            run_all(&asf_edited, amc);
            run_all(asf, &amc_edited);
            run_all(&asf_edited, &amc_edited);
            run_all(&edit(asf, cut_asf, &[]), amc);
        }
    }

    // ------------------------------------------------------------------------------
    // The corpus.

    #[test]
    fn corpus_motions_match_the_formula() {
        let Some(dir) = corpus("usc_csci520_mocapPlayer__shreyabhaumik") else {
            return;
        };
        for (asf_name, amc_name) in [
            ("07-walk.asf", "07_05-walk.amc"),
            ("09-run.asf", "09_06-run.amc"),
            ("131-dance.asf", "131_04-dance.amc"),
        ] {
            let (asf_path, amc_path) = (dir.join(asf_name), dir.join(amc_name));
            let (asf_text, amc_text) = (read(&asf_path), read(&amc_path));
            // Parse + to_asset, timed as the best of 3 runs (the machine is shared).
            let mut best = std::time::Duration::MAX;
            let mut result = None;
            for _ in 0..3 {
                let start = std::time::Instant::now();
                let asf = parse_asf(&asf_text, &asf_path).unwrap_or_else(|e| panic!("{e}"));
                let amc = parse_amc(&amc_text, &amc_path, &asf).unwrap_or_else(|e| panic!("{e}"));
                let motions = [(amc_name.to_string(), amc)];
                let imported = to_asset(asf_name, &asf, &motions, DEFAULT_FPS)
                    .unwrap_or_else(|e| panic!("{e}"));
                best = best.min(start.elapsed());
                result = Some((asf, motions, imported));
            }
            let (asf, motions, imported) = result.unwrap();
            let elapsed = best;
            let amc = &motions[0].1;
            println!(
                "{amc_name}: {} frames, parse + to_asset {elapsed:?}",
                amc.frames.len()
            );
            assert!(imported.warnings.is_empty(), "{:?}", imported.warnings);
            let asset = &imported.asset;
            assert_eq!(asf.bones.len(), 30);
            // 30 bones, the root and 7 leaf ends (toes, head, fingers and thumbs).
            assert_eq!(asset.skeleton.len(), 38);
            assert_eq!(asset.meters_per_unit, Some(0.0254 / 0.45));
            let frames = frame_line_count(&amc_text);
            assert_eq!(amc.frames.len(), frames);
            let clip = &asset.clips[0];
            assert!(clip.tracks.iter().all(|t| t.times.len() == frames));
            // Root translation and rotation plus one rotation per bone with dofs (29 of 30:
            // lhipjoint and rhipjoint have none, so 28... counted from the ASF).
            let rotating = asf.bones.iter().filter(|b| !b.dofs.is_empty()).count();
            assert_eq!(clip.tracks.len(), 2 + rotating);
            let worst = check_fk(&asf, amc, &imported, 0, DEFAULT_FPS);
            println!("  max FK deviation {worst:e} (height {})", height(asset));

            // Physical sanity the formula comparison cannot give (both sides share the
            // conventions): y is up, so the head stays above the root and the toes below
            // it. (Both feet need not reach the same floor: in 07_05 the lowest left and
            // right foot points differ by 1.3 units, also in an independent Python FK.)
            for k in 0..frames {
                let p = asset_positions(asset, clip, k);
                assert!(
                    p["head"].y > p["root"].y && p["root"].y > p["ltoes"].y,
                    "frame {k}"
                );
            }

            // Bone lengths stay constant: every joint keeps its rest distance to its parent.
            let rest: Vec<f32> = asset
                .skeleton
                .joints()
                .iter()
                .map(|j| j.rest_local.translation.length())
                .collect();
            let tolerance = 1e-5 * height(asset) as f32;
            for k in 0..frames {
                let p = asset_positions(asset, clip, k);
                for (j, joint) in asset.skeleton.joints().iter().enumerate() {
                    let Some(parent) = joint.parent else { continue };
                    let parent = &asset.skeleton.joint(parent).name;
                    let d = p[&joint.name].distance(p[parent]);
                    assert!(
                        (d - rest[j]).abs() <= tolerance,
                        "{amc_name} frame {k}: {} is {d} from {parent}, {} at rest",
                        joint.name,
                        rest[j]
                    );
                }
            }
        }
    }

    #[test]
    fn corpus_legs_only_skeleton_imports() {
        let Some(dir) = corpus("lowerbody_edge_case__cvikramk_TimeGAN") else {
            return;
        };
        let imported =
            import(&dir.join("02.asf"), &[], DEFAULT_FPS).unwrap_or_else(|e| panic!("{e}"));
        assert!(imported.warnings.is_empty(), "{:?}", imported.warnings);
        let s = &imported.asset.skeleton;
        let names: Vec<&str> = s.joints().iter().map(|j| j.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "root",
                "lhipjoint",
                "lfemur",
                "ltibia",
                "ltibia_end",
                "rhipjoint",
                "rfemur",
                "rtibia",
                "rtibia_end"
            ]
        );
        assert!(imported.asset.clips.is_empty());
        assert_eq!(imported.asset.meters_per_unit, Some(0.0254 / 0.45));
        // The shin hangs below the knee: ltibia's end is 7.28717 units from its start.
        let end = s
            .joint(s.find("ltibia_end").unwrap())
            .rest_local
            .translation;
        assert!((end.length() - 7.28717).abs() < 1e-5);
    }
}
