//! The ASF parser: sections, `:units`, `:root` and the `:bonedata` blocks.

use std::collections::HashMap;
use std::path::Path;

use glam::DVec3;
use rigport_model::conventions::EulerOrder;

use crate::problem::{Mismatch, Missing, Repeated, Rule};
use crate::{text, ImportError, Location, Problem};

use super::hierarchy::resolve_hierarchy;
use super::lines::{
    column, content, dof_list, duplicate, euler_order, line_error, number, syntax, vec3, Lines,
};
use super::types::{AngleUnit, Asf, Bone, Dof, Root, Skipped, Units};

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
        return Err(duplicate(
            path,
            line,
            format!("`{key}` in {within}"),
            *first,
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
            return Err(duplicate(self.path, line_no, format!("`:{lower}`"), *first));
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
                ImportError::invalid(Location::line(self.path, line_no), what)
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
                        return Err(line_error(self.path, root.line, Missing::RootLine(key)));
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
            return Err(duplicate(
                path,
                line_no,
                format!("`{lower}` in `:units`"),
                *first,
            ));
        }
        match lower.as_str() {
            "mass" => self.units.mass = Some(number(path, line_no, raw, value, "mass")?),
            "length" => {
                let length = number(path, line_no, raw, value, "length unit")?;
                if length <= 0.0 {
                    return Err(ImportError::at(
                        Location::line_column(path, line_no, column(raw, value)),
                        Rule::LengthUnit(length),
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
            "begin" => Err(line_error(
                path,
                line_no,
                Rule::BeginInBone(draft.begin_line),
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
                let id: i64 =
                    text::number(id, "bone id", || text::at(path, line_no, raw, id))?;
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
                    return Err(ImportError::at(
                        Location::line_column(path, line_no, column(raw, name)),
                        Rule::ReservedName(name.to_string()),
                    ));
                }
                if let Some(first) = self.names.get(*name) {
                    return Err(ImportError::at(
                        Location::line_column(path, line_no, column(raw, name)),
                        Repeated::BoneName {
                            name: name.to_string(),
                            first_line: *first,
                        },
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
                    return Err(ImportError::at(
                        Location::line_column(path, line_no, column(raw, value)),
                        Rule::NegativeLength(length),
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
        let missing = |key: &'static str| {
            let begin_line = draft.begin_line;
            line_error(self.path, end_line, Missing::BoneEntry { begin_line, key })
        };
        let (name, line) = draft.name.clone().ok_or_else(|| missing("name"))?;
        let (direction, _) = draft.direction.ok_or_else(|| missing("direction"))?;
        let (length, _) = draft.length.ok_or_else(|| missing("length"))?;
        let ((axis, axis_order), _) = draft.axis.ok_or_else(|| missing("axis"))?;
        let dofs = draft.dofs.map(|(d, _)| d).unwrap_or_default();
        let limits = match draft.limits {
            Some((limits, limits_line)) => {
                if limits.len() != dofs.len() {
                    return Err(line_error(
                        self.path,
                        limits_line,
                        Mismatch::Limits {
                            bone: name,
                            limits: limits.len(),
                            dofs: dofs.len(),
                        },
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
            return Err(line_error(self.path, root.line, Missing::Root));
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
