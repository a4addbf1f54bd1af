//! The container level of a crate file: the bootstrap header, the table of contents and
//! the structural sections (tokens, strings, fields, field sets, paths, specs), with the
//! checked primitive reads and the decoding budget that value decoding builds on.
//!
//! This module knows nothing of values: [`super::value`] decodes value representations
//! with the reads defined here, and the parent module walks the specs into a layer.

use std::collections::HashMap;
use std::path::Path;

use super::coding::{self, Width};
use crate::error::{CrateProblem, Location, Problem, UsdError};

/// The 8 bytes every crate file starts with.
pub const MAGIC: &[u8; 8] = b"PXR-USDC";

/// Size of the bootstrap header (ident, version, TOC offset, 8 reserved words).
const BOOTSTRAP_LEN: usize = 88;

/// Deepest nesting of values inside values (dictionaries in dictionaries, `VtValue`s).
pub(crate) const MAX_VALUE_DEPTH: usize = 64;

/// The field index that ends a field set (`FieldIndex()` is `~0`).
const FIELD_SET_END: u32 = u32::MAX;

/// How many elements (scalars, indices, bytes of tokens) the reader decodes at most for a
/// file of `len` bytes: 16 Mi plus 256 per byte. Honest files stay far below (a point
/// takes 12 bytes for 3 elements; integer compression reaches about 4 elements per byte
/// before LZ4), while a small corrupt file cannot claim gigabytes.
pub(crate) fn element_budget(len: usize) -> u64 {
    (16 << 20) + 256 * len as u64
}

/// A spec: where it is and what it holds.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Spec {
    path: u32,
    field_set: u32,
    pub(crate) kind: u32,
}

/// The structural sections of an open crate file.
pub(crate) struct CrateFile<'a> {
    pub(crate) data: &'a [u8],
    path: &'a Path,
    version: (u8, u8, u8),
    tokens: Vec<String>,
    strings: Vec<u32>,
    /// (token index of the name, value representation).
    fields: Vec<(u32, u64)>,
    field_sets: Vec<u32>,
    paths: Vec<Option<String>>,
    specs: Vec<Spec>,
    by_path: HashMap<String, usize>,
    budget: std::cell::Cell<u64>,
}

/// A position in the file for sequential reads.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cursor {
    pub(crate) pos: u64,
}

impl<'a> CrateFile<'a> {
    /// Reads the bootstrap, the table of contents and every structural section.
    pub(crate) fn open(data: &'a [u8], path: &'a Path) -> Result<Self, UsdError> {
        let mut file = CrateFile {
            data,
            path,
            version: (0, 0, 0),
            tokens: Vec::new(),
            strings: Vec::new(),
            fields: Vec::new(),
            field_sets: Vec::new(),
            paths: Vec::new(),
            specs: Vec::new(),
            by_path: HashMap::new(),
            budget: std::cell::Cell::new(element_budget(data.len())),
        };
        if data.len() < BOOTSTRAP_LEN {
            return Err(file.truncated(0, BOOTSTRAP_LEN as u64, "the 88-byte header"));
        }
        if !data.starts_with(MAGIC) {
            return Err(file.error(0, CrateProblem::NotCrate));
        }
        let v = data.get(8..11).unwrap_or_default();
        file.version = (
            v.first().copied().unwrap_or(0),
            v.get(1).copied().unwrap_or(0),
            v.get(2).copied().unwrap_or(0),
        );
        let (major, minor, patch) = file.version;
        if major != 0 || minor < 4 {
            return Err(file.error(8, CrateProblem::Version((major, minor, patch))));
        }
        let toc = file.u64(&mut Cursor { pos: 16 })?;
        let sections = file.sections(toc)?;
        let find = |name: &str| sections.iter().find(|(n, _)| n == name).map(|&(_, s)| s);
        if let Some(start) = find("TOKENS") {
            file.read_tokens(start)?;
        }
        if let Some(start) = find("STRINGS") {
            file.read_strings(start)?;
        }
        if let Some(start) = find("FIELDS") {
            file.read_fields(start)?;
        }
        if let Some(start) = find("FIELDSETS") {
            file.read_field_sets(start)?;
        }
        if let Some(start) = find("PATHS") {
            file.read_paths(start)?;
        }
        if let Some(start) = find("SPECS") {
            file.read_specs(start)?;
        }
        for (i, spec) in file.specs.iter().enumerate() {
            if let Some(Some(p)) = file.paths.get(spec.path as usize) {
                file.by_path.entry(p.clone()).or_insert(i);
            }
        }
        Ok(file)
    }

    // -------------------------------------------------------------------------------
    // Errors and primitive reads
    // -------------------------------------------------------------------------------

    /// `problem` at byte `at` of the file.
    pub(crate) fn error(&self, at: u64, problem: impl Into<Problem>) -> UsdError {
        UsdError::new(Location::byte(self.path, at), problem.into())
    }

    /// An index past the `count` entries of a table.
    pub(crate) fn index_error(
        &self,
        at: u64,
        what: &'static str,
        index: i64,
        count: Option<usize>,
        plural: &'static str,
    ) -> UsdError {
        self.error(
            at,
            Problem::IndexOutOfRange {
                what,
                index,
                may_be_unset: false,
                count,
                plural,
            },
        )
    }

    pub(crate) fn truncated(&self, at: u64, need: u64, what: &str) -> UsdError {
        UsdError::new(
            Location::byte(self.path, at),
            Problem::Truncated(format!(
                "{what} needs {need} bytes here, the file has {} in all",
                self.data.len()
            )),
        )
    }

    /// Takes `n` elements from the decoding budget.
    pub(crate) fn spend(&self, at: u64, n: u64) -> Result<(), UsdError> {
        let left = self.budget.get();
        if n > left {
            return Err(self.error(
                at,
                CrateProblem::OverBudget {
                    claimed: n,
                    budget: element_budget(self.data.len()),
                    file_len: self.data.len(),
                },
            ));
        }
        self.budget.set(left - n);
        Ok(())
    }

    /// `n` bytes at the cursor, which moves past them.
    fn bytes(&self, c: &mut Cursor, n: u64, what: &str) -> Result<&'a [u8], UsdError> {
        let start = usize::try_from(c.pos).ok();
        let end = start
            .zip(usize::try_from(n).ok())
            .and_then(|(s, n)| s.checked_add(n));
        match start.zip(end).and_then(|(s, e)| self.data.get(s..e)) {
            Some(b) => {
                c.pos += n;
                Ok(b)
            }
            None => Err(self.truncated(c.pos, n, what)),
        }
    }

    fn array<const N: usize>(&self, c: &mut Cursor) -> Result<[u8; N], UsdError> {
        let b = self.bytes(c, N as u64, "a value")?;
        b.try_into()
            .map_err(|_| self.truncated(c.pos, N as u64, "a value"))
    }

    pub(crate) fn u8(&self, c: &mut Cursor) -> Result<u8, UsdError> {
        Ok(self.array::<1>(c)?[0])
    }
    pub(crate) fn u16(&self, c: &mut Cursor) -> Result<u16, UsdError> {
        Ok(u16::from_le_bytes(self.array(c)?))
    }
    pub(crate) fn u32(&self, c: &mut Cursor) -> Result<u32, UsdError> {
        Ok(u32::from_le_bytes(self.array(c)?))
    }
    pub(crate) fn i32(&self, c: &mut Cursor) -> Result<i32, UsdError> {
        Ok(i32::from_le_bytes(self.array(c)?))
    }
    pub(crate) fn u64(&self, c: &mut Cursor) -> Result<u64, UsdError> {
        Ok(u64::from_le_bytes(self.array(c)?))
    }
    pub(crate) fn i64(&self, c: &mut Cursor) -> Result<i64, UsdError> {
        Ok(i64::from_le_bytes(self.array(c)?))
    }
    pub(crate) fn f32(&self, c: &mut Cursor) -> Result<f32, UsdError> {
        Ok(f32::from_le_bytes(self.array(c)?))
    }
    pub(crate) fn f64(&self, c: &mut Cursor) -> Result<f64, UsdError> {
        Ok(f64::from_le_bytes(self.array(c)?))
    }

    /// A count read at the cursor, checked against the budget.
    pub(crate) fn count(&self, c: &mut Cursor, wide: bool) -> Result<usize, UsdError> {
        let at = c.pos;
        let n = if wide {
            self.u64(c)?
        } else {
            u64::from(self.u32(c)?)
        };
        self.spend(at, n)?;
        usize::try_from(n).map_err(|_| self.error(at, CrateProblem::CountTooLarge(n)))
    }

    pub(crate) fn version_at_least(&self, minor: u8) -> bool {
        self.version.1 >= minor
    }

    pub(crate) fn token(&self, at: u64, index: u32) -> Result<&str, UsdError> {
        self.tokens
            .get(index as usize)
            .map(String::as_str)
            .ok_or_else(|| {
                let count = Some(self.tokens.len());
                self.index_error(at, "token", index.into(), count, "tokens")
            })
    }

    pub(crate) fn string(&self, at: u64, index: u32) -> Result<&str, UsdError> {
        let token = self.strings.get(index as usize).ok_or_else(|| {
            let count = Some(self.strings.len());
            self.index_error(at, "string", index.into(), count, "strings")
        })?;
        self.token(at, *token)
    }

    pub(crate) fn path_at(&self, at: u64, index: u32) -> Result<&str, UsdError> {
        match self.paths.get(index as usize) {
            Some(Some(p)) => Ok(p),
            _ => Err(self.error(
                at,
                Problem::IndexOutOfRange {
                    what: "path",
                    index: index.into(),
                    may_be_unset: true,
                    count: Some(self.paths.len()),
                    plural: "paths",
                },
            )),
        }
    }

    /// Reads `count` compressed integers (`_CompressedIntsReader`): a `u64` compressed
    /// size, then the LZ4-compressed coded integers.
    pub(crate) fn compressed_ints(
        &self,
        c: &mut Cursor,
        count: usize,
        width: Width,
    ) -> Result<Vec<i64>, UsdError> {
        let at = c.pos;
        let size = self.u64(c)?;
        let bytes = self.bytes(c, size, "compressed integers")?;
        let encoded = coding::encoded_size(count, width).ok_or_else(|| {
            self.error(
                at,
                Problem::TooMany {
                    what: "integers",
                    count: Some(count as u64),
                },
            )
        })?;
        self.spend(at, encoded as u64 / 4)?;
        // The encoder writes at most `encoded` bytes; the stream may decode to fewer.
        let raw = decompress_up_to(bytes, encoded).map_err(|e| self.error(at, e))?;
        coding::decode_ints(&raw, count, width).map_err(|e| self.error(at, e))
    }

    // -------------------------------------------------------------------------------
    // Structural sections
    // -------------------------------------------------------------------------------

    fn sections(&self, toc: u64) -> Result<Vec<(String, u64)>, UsdError> {
        let mut c = Cursor { pos: toc };
        let n = self.u64(&mut c)?;
        if n > 64 {
            return Err(self.error(toc, CrateProblem::Sections(n)));
        }
        let mut out = Vec::new();
        for _ in 0..n {
            let name = self.bytes(&mut c, 16, "a section name")?;
            let end = name.iter().position(|&b| b == 0).unwrap_or(16);
            let name = String::from_utf8_lossy(name.get(..end).unwrap_or_default()).into_owned();
            let start = self.u64(&mut c)?;
            let _size = self.u64(&mut c)?;
            out.push((name, start));
        }
        Ok(out)
    }

    fn read_tokens(&mut self, start: u64) -> Result<(), UsdError> {
        let mut c = Cursor { pos: start };
        let count = self.count(&mut c, true)?;
        let raw_len = self.count(&mut c, true)?;
        let size = self.u64(&mut c)?;
        let at = c.pos;
        let packed = self.bytes(&mut c, size, "the tokens")?;
        let chars = coding::decompress(packed, raw_len).map_err(|e| self.error(at, e))?;
        let mut tokens: Vec<String> = chars
            .split(|&b| b == 0)
            .take(count)
            .map(|t| String::from_utf8_lossy(t).into_owned())
            .collect();
        if tokens.len() < count {
            return Err(self.error(
                at,
                CrateProblem::Tokens {
                    found: tokens.len(),
                    claimed: count,
                },
            ));
        }
        tokens.shrink_to_fit();
        self.tokens = tokens;
        Ok(())
    }

    fn read_strings(&mut self, start: u64) -> Result<(), UsdError> {
        let mut c = Cursor { pos: start };
        let count = self.count(&mut c, true)?;
        let mut strings = Vec::with_capacity(count.min(self.data.len() / 4));
        for _ in 0..count {
            strings.push(self.u32(&mut c)?);
        }
        self.strings = strings;
        Ok(())
    }

    fn read_fields(&mut self, start: u64) -> Result<(), UsdError> {
        let mut c = Cursor { pos: start };
        let count = self.count(&mut c, true)?;
        let names = self.compressed_ints(&mut c, count, Width::W32)?;
        let size = self.u64(&mut c)?;
        let at = c.pos;
        let packed = self.bytes(&mut c, size, "the field values")?;
        let raw_len = count.checked_mul(8).ok_or_else(|| {
            let too_many = Problem::TooMany {
                what: "fields",
                count: None,
            };
            self.error(at, too_many)
        })?;
        let raw = coding::decompress(packed, raw_len).map_err(|e| self.error(at, e))?;
        self.fields = names
            .iter()
            .zip(raw.chunks_exact(8))
            .map(|(&name, rep)| {
                let mut word = [0_u8; 8];
                word.copy_from_slice(rep);
                (name as u32, u64::from_le_bytes(word))
            })
            .collect();
        Ok(())
    }

    fn read_field_sets(&mut self, start: u64) -> Result<(), UsdError> {
        let mut c = Cursor { pos: start };
        let count = self.count(&mut c, true)?;
        let sets = self.compressed_ints(&mut c, count, Width::W32)?;
        self.field_sets = sets.into_iter().map(|i| i as u32).collect();
        Ok(())
    }

    fn read_paths(&mut self, start: u64) -> Result<(), UsdError> {
        let mut c = Cursor { pos: start };
        let count = self.count(&mut c, true)?;
        let at = c.pos;
        let encoded = self.count(&mut c, true)?;
        let indices = self.compressed_ints(&mut c, encoded, Width::W32)?;
        let elements = self.compressed_ints(&mut c, encoded, Width::W32)?;
        let jumps = self.compressed_ints(&mut c, encoded, Width::W32)?;
        let mut paths: Vec<Option<String>> = vec![None; count];
        // The tree is stored depth first; a node with both a child and a sibling stores
        // the sibling's distance. Walk it with an explicit stack, visiting each encoded
        // path once at most (a corrupt jump table cannot make the walk longer).
        let mut stack: Vec<(usize, Option<String>)> = vec![(0, None)];
        let mut steps = 0_usize;
        while let Some((mut cur, mut parent)) = stack.pop() {
            loop {
                let this = cur;
                cur += 1;
                steps += 1;
                if steps > encoded {
                    return Err(self.error(at, CrateProblem::PathsRevisited));
                }
                let (Some(&index), Some(&element), Some(&jump)) =
                    (indices.get(this), elements.get(this), jumps.get(this))
                else {
                    return Err(self.error(
                        at,
                        CrateProblem::PathEntry {
                            entry: this,
                            count: encoded,
                        },
                    ));
                };
                let path = match &parent {
                    None => "/".to_string(),
                    Some(parent) => {
                        let token = self.token(at, element.unsigned_abs() as u32)?;
                        append_path(parent, token, element < 0)
                    }
                };
                let slot = usize::try_from(index)
                    .ok()
                    .and_then(|i| paths.get_mut(i))
                    .ok_or_else(|| self.index_error(at, "path", index, Some(count), ""))?;
                *slot = Some(path.clone());
                let has_child = jump > 0 || jump == -1;
                let has_sibling = jump >= 0;
                if has_child {
                    if has_sibling {
                        let sibling = usize::try_from(this as i64 + jump)
                            .map_err(|_| self.error(at, CrateProblem::NegativePathJump))?;
                        stack.push((sibling, parent.clone()));
                    }
                    parent = Some(path);
                }
                if !(has_child || has_sibling) {
                    break;
                }
            }
        }
        self.paths = paths;
        Ok(())
    }

    fn read_specs(&mut self, start: u64) -> Result<(), UsdError> {
        let mut c = Cursor { pos: start };
        let count = self.count(&mut c, true)?;
        let paths = self.compressed_ints(&mut c, count, Width::W32)?;
        let sets = self.compressed_ints(&mut c, count, Width::W32)?;
        let kinds = self.compressed_ints(&mut c, count, Width::W32)?;
        self.specs = paths
            .iter()
            .zip(&sets)
            .zip(&kinds)
            .map(|((&p, &s), &k)| Spec {
                path: p as u32,
                field_set: s as u32,
                kind: k as u32,
            })
            .collect();
        Ok(())
    }

    // -------------------------------------------------------------------------------
    // Spec lookups
    // -------------------------------------------------------------------------------

    /// The spec at `path`, if any.
    pub(crate) fn spec(&self, path: &str) -> Option<Spec> {
        self.by_path
            .get(path)
            .and_then(|&i| self.specs.get(i))
            .copied()
    }

    /// The fields of a spec: (name, value representation), in file order.
    pub(crate) fn fields(&self, spec: Spec) -> Result<Vec<(&str, u64)>, UsdError> {
        let mut out = Vec::new();
        let mut i = spec.field_set as usize;
        loop {
            let Some(&f) = self.field_sets.get(i) else {
                let path = self
                    .paths
                    .get(spec.path as usize)
                    .and_then(|p| p.as_deref())
                    .unwrap_or("?");
                return Err(self.error(
                    0,
                    CrateProblem::FieldSet {
                        field_set: spec.field_set,
                        path: path.to_string(),
                    },
                ));
            };
            if f == FIELD_SET_END {
                return Ok(out);
            }
            let &(name, rep) = self
                .fields
                .get(f as usize)
                .ok_or_else(|| self.index_error(0, "field", f.into(), None, ""))?;
            out.push((self.token(0, name)?, rep));
            i += 1;
        }
    }
}

/// The path of prim `name` under `parent` (`/`, a prim, or a variant selection).
pub(crate) fn child_path(parent: &str, name: &str) -> String {
    if parent == "/" || parent.ends_with('}') {
        format!("{parent}{name}")
    } else {
        format!("{parent}/{name}")
    }
}

/// `SdfPath::AppendElementToken` / `AppendProperty` as strings.
fn append_path(parent: &str, element: &str, property: bool) -> String {
    if property {
        format!("{parent}.{element}")
    } else if element.starts_with('{') || element.starts_with('[') || element.starts_with('.') {
        format!("{parent}{element}")
    } else {
        child_path(parent, element)
    }
}

/// LZ4-decompresses integer codes whose exact size is unknown (at most `max` bytes).
fn decompress_up_to(input: &[u8], max: usize) -> Result<Vec<u8>, coding::CodingError> {
    // The coded size depends on the values; decompress into the largest size and keep
    // what was written.
    coding::decompress_prefix(input, max)
}
