//! USD's binary "crate" format (`.usdc`) read into the same [`Layer`] the text parser
//! builds, so composition and the UsdSkel mapping are shared.
//!
//! # Why our own reader
//! The `openusd` crate was measured first (see the report of issue 22): its releases that
//! read what we need (0.7, 0.8) require Rust 1.96, and the last one that builds on our
//! 1.95 (0.6.0) aborts the whole process on a corrupt file (it allocates a length taken
//! from the file before checking it: a one-byte change asked for 7.7e18 bytes) and
//! panics (`todo!`) on crate versions before 0.4. It is also a full USD stack (100k lines,
//! its own composition, six minutes of release build) whose data would still have to be
//! mapped onto our layer. The format is small and well specified, so this module reads
//! it directly with every offset, count and index checked.
//!
//! # The format (OpenUSD `pxr/usd/usd/crateFile.{h,cpp}`, versions 0.4.0 and later)
//! - An 88-byte bootstrap: `"PXR-USDC"`, version bytes (major, minor, patch), the byte
//!   offset of the table of contents.
//! - The table of contents: named sections `TOKENS` (LZ4-compressed, NUL-separated),
//!   `STRINGS` (token indices), `FIELDS` (token index + 64-bit value representation each),
//!   `FIELDSETS` (runs of field indices ended by `!0`), `PATHS` (a tree encoded as path
//!   indices, element tokens, negative for properties, and sibling/child jumps) and
//!   `SPECS` (path, field set, spec type). Integer tables use `Usd_IntegerCompression`.
//! - A value representation packs a type, "array", "inlined" and "compressed" flags and
//!   a 48-bit payload: the value itself (small scalars, token/string/path indices, vectors
//!   of small integers, diagonal matrices) or the byte offset of its data.
//!
//! Files before 0.4.0 (written by USD releases before 2017) are refused with a message.
//! Numbers become `f64` as the text parser keeps them; quaternions are turned from the
//! file's `(x, y, z, w)` into the text's `(w, x, y, z)`; list ops become one metadata item
//! per operation (`prepend apiSchemas`, ...), as the text writes them. A binary layer has
//! no lines: its line numbers are 0.
//!
//! Measured (release build, one core of the 2-core dev machine): a usd-core export of a
//! 90k-point skinned grid with 60 joints and 240 frames (1.3 MB `.usdc`, 7.8 MB as
//! `.usda`) imports in 210 ms from `.usdc` against 630 ms from `.usda`; the corpus's
//! small `.usdc`/`.usdz` files take 0.02 to 1.1 ms each, including the UsdSkel mapping.
//!
//! # Limits
//! No input can make the reader loop, recurse without bound or allocate without bound:
//! prim nesting is limited like the text parser's, nested values to [`MAX_VALUE_DEPTH`],
//! and all decoded elements together to [`element_budget`] of the file size.

mod coding;
mod value;

use std::collections::HashMap;
use std::path::Path;

use self::coding::Width;
use self::value::Decoded;
use super::parse::{
    Layer, ListOp, Meta, PrimBody, PrimSpec, PropKind, PropSpec, Specifier, Value, VariantSetSpec,
    MAX_DEPTH,
};
use crate::{ImportError, Location, Problem};

/// The 8 bytes every crate file starts with.
pub(crate) const MAGIC: &[u8; 8] = b"PXR-USDC";

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

/// `SdfSpecType` values used here.
mod spec_type {
    pub const ATTRIBUTE: u32 = 1;
    pub const PRIM: u32 = 6;
    pub const PSEUDO_ROOT: u32 = 7;
    pub const RELATIONSHIP: u32 = 8;
    pub const VARIANT: u32 = 10;
    pub const VARIANT_SET: u32 = 11;
}

/// Reads a crate file into a layer.
///
/// # Errors
/// A truncated file, an offset or index out of range, corrupt compressed data or an
/// unsupported version, at the byte offset where it was found.
pub(crate) fn read(bytes: &[u8], path: &Path) -> Result<Layer, ImportError> {
    let file = CrateFile::open(bytes, path)?;
    file.layer()
}

/// A spec: where it is and what it holds.
#[derive(Clone, Copy, Debug)]
struct Spec {
    path: u32,
    field_set: u32,
    kind: u32,
}

/// The structural sections of an open crate file.
struct CrateFile<'a> {
    data: &'a [u8],
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
struct Cursor {
    pos: u64,
}

impl<'a> CrateFile<'a> {
    /// Reads the bootstrap, the table of contents and every structural section.
    fn open(data: &'a [u8], path: &'a Path) -> Result<Self, ImportError> {
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
            return Err(file.invalid(0, "not a USD crate file (no PXR-USDC header)"));
        }
        let v = data.get(8..11).unwrap_or_default();
        file.version = (
            v.first().copied().unwrap_or(0),
            v.get(1).copied().unwrap_or(0),
            v.get(2).copied().unwrap_or(0),
        );
        let (major, minor, patch) = file.version;
        if major != 0 || minor < 4 {
            return Err(file.invalid(
                8,
                format!(
                    "crate version {major}.{minor}.{patch} is not supported (rigport reads \
                     0.4.0 and later; re-save the file with a current USD)"
                ),
            ));
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

    fn invalid(&self, at: u64, message: impl Into<String>) -> ImportError {
        ImportError::invalid(Location::byte(self.path, at), message)
    }

    fn truncated(&self, at: u64, need: u64, what: &str) -> ImportError {
        ImportError::new(
            Location::byte(self.path, at),
            Problem::Truncated(format!(
                "{what} needs {need} bytes here, the file has {} in all",
                self.data.len()
            )),
        )
    }

    /// Takes `n` elements from the decoding budget.
    fn spend(&self, at: u64, n: u64) -> Result<(), ImportError> {
        let left = self.budget.get();
        if n > left {
            return Err(self.invalid(
                at,
                format!(
                    "the file claims more data than it can hold ({n} more elements; at most \
                     {} are decoded for a file of {} bytes)",
                    element_budget(self.data.len()),
                    self.data.len()
                ),
            ));
        }
        self.budget.set(left - n);
        Ok(())
    }

    /// `n` bytes at the cursor, which moves past them.
    fn bytes(&self, c: &mut Cursor, n: u64, what: &str) -> Result<&'a [u8], ImportError> {
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

    fn array<const N: usize>(&self, c: &mut Cursor) -> Result<[u8; N], ImportError> {
        let b = self.bytes(c, N as u64, "a value")?;
        b.try_into()
            .map_err(|_| self.truncated(c.pos, N as u64, "a value"))
    }

    fn u8(&self, c: &mut Cursor) -> Result<u8, ImportError> {
        Ok(self.array::<1>(c)?[0])
    }
    fn u16(&self, c: &mut Cursor) -> Result<u16, ImportError> {
        Ok(u16::from_le_bytes(self.array(c)?))
    }
    fn u32(&self, c: &mut Cursor) -> Result<u32, ImportError> {
        Ok(u32::from_le_bytes(self.array(c)?))
    }
    fn i32(&self, c: &mut Cursor) -> Result<i32, ImportError> {
        Ok(i32::from_le_bytes(self.array(c)?))
    }
    fn u64(&self, c: &mut Cursor) -> Result<u64, ImportError> {
        Ok(u64::from_le_bytes(self.array(c)?))
    }
    fn i64(&self, c: &mut Cursor) -> Result<i64, ImportError> {
        Ok(i64::from_le_bytes(self.array(c)?))
    }
    fn f32(&self, c: &mut Cursor) -> Result<f32, ImportError> {
        Ok(f32::from_le_bytes(self.array(c)?))
    }
    fn f64(&self, c: &mut Cursor) -> Result<f64, ImportError> {
        Ok(f64::from_le_bytes(self.array(c)?))
    }

    /// A count read at the cursor, checked against the budget.
    fn count(&self, c: &mut Cursor, wide: bool) -> Result<usize, ImportError> {
        let at = c.pos;
        let n = if wide {
            self.u64(c)?
        } else {
            u64::from(self.u32(c)?)
        };
        self.spend(at, n)?;
        usize::try_from(n).map_err(|_| self.invalid(at, format!("count {n} is too large")))
    }

    fn version_at_least(&self, minor: u8) -> bool {
        self.version.1 >= minor
    }

    fn token(&self, at: u64, index: u32) -> Result<&str, ImportError> {
        self.tokens
            .get(index as usize)
            .map(String::as_str)
            .ok_or_else(|| {
                self.invalid(
                    at,
                    format!(
                        "token index {index} out of range ({} tokens)",
                        self.tokens.len()
                    ),
                )
            })
    }

    fn string(&self, at: u64, index: u32) -> Result<&str, ImportError> {
        let token = self.strings.get(index as usize).ok_or_else(|| {
            self.invalid(
                at,
                format!(
                    "string index {index} out of range ({} strings)",
                    self.strings.len()
                ),
            )
        })?;
        self.token(at, *token)
    }

    fn path_at(&self, at: u64, index: u32) -> Result<&str, ImportError> {
        match self.paths.get(index as usize) {
            Some(Some(p)) => Ok(p),
            _ => Err(self.invalid(
                at,
                format!(
                    "path index {index} out of range or unset ({} paths)",
                    self.paths.len()
                ),
            )),
        }
    }

    /// Reads `count` compressed integers (`_CompressedIntsReader`): a `u64` compressed
    /// size, then the LZ4-compressed coded integers.
    fn compressed_ints(
        &self,
        c: &mut Cursor,
        count: usize,
        width: Width,
    ) -> Result<Vec<i64>, ImportError> {
        let at = c.pos;
        let size = self.u64(c)?;
        let bytes = self.bytes(c, size, "compressed integers")?;
        let encoded = coding::encoded_size(count, width)
            .ok_or_else(|| self.invalid(at, format!("{count} integers is too many")))?;
        self.spend(at, encoded as u64 / 4)?;
        // The encoder writes at most `encoded` bytes; the stream may decode to fewer.
        let raw = decompress_up_to(bytes, encoded).map_err(|e| self.invalid(at, e.0))?;
        coding::decode_ints(&raw, count, width).map_err(|e| self.invalid(at, e.0))
    }

    // -------------------------------------------------------------------------------
    // Structural sections
    // -------------------------------------------------------------------------------

    fn sections(&self, toc: u64) -> Result<Vec<(String, u64)>, ImportError> {
        let mut c = Cursor { pos: toc };
        let n = self.u64(&mut c)?;
        if n > 64 {
            return Err(self.invalid(toc, format!("{n} sections in the table of contents")));
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

    fn read_tokens(&mut self, start: u64) -> Result<(), ImportError> {
        let mut c = Cursor { pos: start };
        let count = self.count(&mut c, true)?;
        let raw_len = self.count(&mut c, true)?;
        let size = self.u64(&mut c)?;
        let at = c.pos;
        let packed = self.bytes(&mut c, size, "the tokens")?;
        let chars = coding::decompress(packed, raw_len).map_err(|e| self.invalid(at, e.0))?;
        let mut tokens: Vec<String> = chars
            .split(|&b| b == 0)
            .take(count)
            .map(|t| String::from_utf8_lossy(t).into_owned())
            .collect();
        if tokens.len() < count {
            return Err(self.invalid(
                at,
                format!(
                    "the tokens section holds {} tokens, {count} claimed",
                    tokens.len()
                ),
            ));
        }
        tokens.shrink_to_fit();
        self.tokens = tokens;
        Ok(())
    }

    fn read_strings(&mut self, start: u64) -> Result<(), ImportError> {
        let mut c = Cursor { pos: start };
        let count = self.count(&mut c, true)?;
        let mut strings = Vec::with_capacity(count.min(self.data.len() / 4));
        for _ in 0..count {
            strings.push(self.u32(&mut c)?);
        }
        self.strings = strings;
        Ok(())
    }

    fn read_fields(&mut self, start: u64) -> Result<(), ImportError> {
        let mut c = Cursor { pos: start };
        let count = self.count(&mut c, true)?;
        let names = self.compressed_ints(&mut c, count, Width::W32)?;
        let size = self.u64(&mut c)?;
        let at = c.pos;
        let packed = self.bytes(&mut c, size, "the field values")?;
        let raw_len = count
            .checked_mul(8)
            .ok_or_else(|| self.invalid(at, "too many fields"))?;
        let raw = coding::decompress(packed, raw_len).map_err(|e| self.invalid(at, e.0))?;
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

    fn read_field_sets(&mut self, start: u64) -> Result<(), ImportError> {
        let mut c = Cursor { pos: start };
        let count = self.count(&mut c, true)?;
        let sets = self.compressed_ints(&mut c, count, Width::W32)?;
        self.field_sets = sets.into_iter().map(|i| i as u32).collect();
        Ok(())
    }

    fn read_paths(&mut self, start: u64) -> Result<(), ImportError> {
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
                    return Err(self.invalid(at, "the path tree's jumps revisit paths"));
                }
                let (Some(&index), Some(&element), Some(&jump)) =
                    (indices.get(this), elements.get(this), jumps.get(this))
                else {
                    return Err(self.invalid(
                        at,
                        format!("the path tree refers to entry {this} of {encoded}"),
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
                    .ok_or_else(|| {
                        self.invalid(at, format!("path index {index} out of range ({count})"))
                    })?;
                *slot = Some(path.clone());
                let has_child = jump > 0 || jump == -1;
                let has_sibling = jump >= 0;
                if has_child {
                    if has_sibling {
                        let sibling = usize::try_from(this as i64 + jump)
                            .map_err(|_| self.invalid(at, "a negative path jump"))?;
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

    fn read_specs(&mut self, start: u64) -> Result<(), ImportError> {
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
    // Specs to the layer
    // -------------------------------------------------------------------------------

    /// The spec at `path`, if any.
    fn spec(&self, path: &str) -> Option<Spec> {
        self.by_path
            .get(path)
            .and_then(|&i| self.specs.get(i))
            .copied()
    }

    /// The fields of a spec: (name, value representation), in file order.
    fn fields(&self, spec: Spec) -> Result<Vec<(&str, u64)>, ImportError> {
        let mut out = Vec::new();
        let mut i = spec.field_set as usize;
        loop {
            let Some(&f) = self.field_sets.get(i) else {
                return Err(self.invalid(
                    0,
                    format!(
                        "field set {} of <{}> runs past the field sets",
                        spec.field_set,
                        self.paths
                            .get(spec.path as usize)
                            .and_then(|p| p.as_deref())
                            .unwrap_or("?")
                    ),
                ));
            };
            if f == FIELD_SET_END {
                return Ok(out);
            }
            let &(name, rep) = self
                .fields
                .get(f as usize)
                .ok_or_else(|| self.invalid(0, format!("field index {f} out of range")))?;
            out.push((self.token(0, name)?, rep));
            i += 1;
        }
    }

    /// The value of a field that holds a token list (`primChildren`, `properties`, ...).
    fn names(&self, fields: &[(&str, u64)], key: &str) -> Result<Vec<String>, ImportError> {
        let Some(&(_, rep)) = fields.iter().find(|(k, _)| *k == key) else {
            return Ok(Vec::new());
        };
        let mut out: Vec<String> = Vec::new();
        if let Decoded::Value(Value::List(items)) = self.value(rep, 0)? {
            for item in items {
                if let Value::Str(s) = item {
                    // A name listed twice is one child (and must not be read twice).
                    if !out.contains(&s) {
                        out.push(s);
                    }
                }
            }
        }
        Ok(out)
    }

    fn layer(&self) -> Result<Layer, ImportError> {
        let mut layer = Layer::default();
        let Some(root) = self.spec("/") else {
            return Ok(layer);
        };
        if root.kind != spec_type::PSEUDO_ROOT {
            return Err(self.invalid(0, "the spec at </> is not the layer's pseudo-root"));
        }
        let fields = self.fields(root)?;
        layer.meta = self.metadata(&fields, &["primChildren"])?;
        let mut walk = Walk::default();
        for name in self.names(&fields, "primChildren")? {
            let child = child_path("/", &name);
            if let Some(prim) = self.prim(&child, name, 1, &mut walk)? {
                layer.root.children.push(prim);
            }
        }
        Ok(layer)
    }

    /// Metadata items of a spec, all fields but `skip`, with the text format's names.
    fn metadata(&self, fields: &[(&str, u64)], skip: &[&str]) -> Result<Vec<Meta>, ImportError> {
        let mut out = Vec::new();
        for &(key, rep) in fields {
            if skip.contains(&key) {
                continue;
            }
            let key = match key {
                "documentation" | "comment" => "doc",
                "variantSelection" => "variants",
                "variantSetNames" => "variantSets",
                other => other,
            };
            let meta = |op, value| Meta {
                key: key.to_string(),
                op,
                value,
                line: 0,
            };
            match self.value(rep, 0)? {
                Decoded::Value(v) => out.push(meta(ListOp::Explicit, v)),
                Decoded::ListOp(ops) => {
                    for (op, items) in ops {
                        out.push(meta(op, Value::List(items)));
                    }
                }
                // Time samples are not metadata; unknown types are left out.
                Decoded::Samples(_) | Decoded::Unsupported(_) => {}
            }
        }
        Ok(out)
    }

    fn prim(
        &self,
        path: &str,
        name: String,
        depth: usize,
        walk: &mut Walk,
    ) -> Result<Option<PrimSpec>, ImportError> {
        let Some(spec) = self.spec(path) else {
            return Ok(None);
        };
        if spec.kind != spec_type::PRIM || !walk.enter(path) {
            return Ok(None);
        }
        if depth > MAX_DEPTH {
            return Err(self.invalid(0, format!("<{path}> is nested more than {MAX_DEPTH} deep")));
        }
        let fields = self.fields(spec)?;
        let specifier = match fields.iter().find(|(k, _)| *k == "specifier") {
            Some(&(_, rep)) => match self.value(rep, 0)? {
                Decoded::Value(Value::Ident(s)) if s == "def" => Specifier::Def,
                Decoded::Value(Value::Ident(s)) if s == "class" => Specifier::Class,
                _ => Specifier::Over,
            },
            None => Specifier::Over,
        };
        let type_name = match fields.iter().find(|(k, _)| *k == "typeName") {
            Some(&(_, rep)) => match self.value(rep, 0)? {
                Decoded::Value(Value::Str(s)) if !s.is_empty() => Some(s),
                _ => None,
            },
            None => None,
        };
        let meta = self.metadata(&fields, PRIM_STRUCTURE)?;
        let body = self.body(path, &fields, depth, walk)?;
        Ok(Some(PrimSpec {
            specifier,
            type_name,
            name,
            meta,
            body,
            line: 0,
        }))
    }

    /// The properties, children and variant sets of a prim or variant at `path`.
    fn body(
        &self,
        path: &str,
        fields: &[(&str, u64)],
        depth: usize,
        walk: &mut Walk,
    ) -> Result<PrimBody, ImportError> {
        let mut body = PrimBody::default();
        for name in self.names(fields, "properties")? {
            let prop_path = format!("{path}.{name}");
            if let Some(prop) = self.property(&prop_path, name)? {
                body.props.push(prop);
            }
        }
        for name in self.names(fields, "primChildren")? {
            let child = child_path(path, &name);
            if let Some(prim) = self.prim(&child, name, depth + 1, walk)? {
                body.children.push(prim);
            }
        }
        for set in self.names(fields, "variantSetChildren")? {
            let set_path = format!("{path}{{{set}=}}");
            let Some(set_spec) = self.spec(&set_path) else {
                continue;
            };
            if set_spec.kind != spec_type::VARIANT_SET || !walk.enter(&set_path) {
                continue;
            }
            if depth + 1 > MAX_DEPTH {
                return Err(self.invalid(
                    0,
                    format!("<{set_path}> is nested more than {MAX_DEPTH} deep"),
                ));
            }
            let set_fields = self.fields(set_spec)?;
            let mut variants = Vec::new();
            for variant in self.names(&set_fields, "variantChildren")? {
                let variant_path = format!("{path}{{{set}={variant}}}");
                let Some(v_spec) = self.spec(&variant_path) else {
                    continue;
                };
                if v_spec.kind != spec_type::VARIANT || !walk.enter(&variant_path) {
                    continue;
                }
                let v_fields = self.fields(v_spec)?;
                let meta = self.metadata(&v_fields, PRIM_STRUCTURE)?;
                let v_body = self.body(&variant_path, &v_fields, depth + 1, walk)?;
                variants.push((variant, meta, v_body));
            }
            body.variant_sets.push(VariantSetSpec {
                name: set,
                variants,
                line: 0,
            });
        }
        Ok(body)
    }

    fn property(&self, path: &str, name: String) -> Result<Option<PropSpec>, ImportError> {
        let Some(spec) = self.spec(path) else {
            return Ok(None);
        };
        let fields = self.fields(spec)?;
        let field = |key: &str| fields.iter().find(|(k, _)| *k == key).map(|&(_, r)| r);
        let kind = match spec.kind {
            spec_type::ATTRIBUTE => {
                let type_name = match field("typeName").map(|r| self.value(r, 0)).transpose()? {
                    Some(Decoded::Value(Value::Str(s))) => s,
                    _ => String::new(),
                };
                let uniform = matches!(
                    field("variability").map(|r| self.value(r, 0)).transpose()?,
                    Some(Decoded::Value(Value::Ident(v))) if v == "uniform"
                );
                let default = match field("default").map(|r| self.value(r, 0)).transpose()? {
                    Some(Decoded::Value(v)) => Some(v),
                    Some(Decoded::ListOp(ops)) => {
                        Some(Value::List(ops.into_iter().flat_map(|(_, v)| v).collect()))
                    }
                    _ => None,
                };
                let samples = match field("timeSamples").map(|r| self.value(r, 0)).transpose()? {
                    Some(Decoded::Samples(s)) => Some(s),
                    _ => None,
                };
                let other_field = if field("connectionPaths").is_some() {
                    Some("connect")
                } else if field("spline").is_some() {
                    Some("spline")
                } else {
                    None
                };
                PropKind::Attr {
                    type_name,
                    uniform,
                    default,
                    samples,
                    other_field,
                }
            }
            spec_type::RELATIONSHIP => {
                let targets = match field("targetPaths").map(|r| self.value(r, 0)).transpose()? {
                    Some(Decoded::ListOp(ops)) => {
                        let explicit = ops.iter().find(|(op, _)| *op == ListOp::Explicit);
                        let items: Vec<Value> = match explicit {
                            Some((_, items)) => items.clone(),
                            None => ops
                                .into_iter()
                                .filter(|(op, _)| {
                                    matches!(op, ListOp::Prepend | ListOp::Add | ListOp::Append)
                                })
                                .flat_map(|(_, v)| v)
                                .collect(),
                        };
                        Some(
                            items
                                .into_iter()
                                .filter_map(|v| match v {
                                    Value::Path(p) => Some(p),
                                    _ => None,
                                })
                                .collect(),
                        )
                    }
                    _ => None,
                };
                PropKind::Rel { targets }
            }
            _ => return Ok(None),
        };
        let meta = self.metadata(&fields, PROP_STRUCTURE)?;
        Ok(Some(PropSpec {
            name,
            kind,
            meta,
            line: 0,
            column: 0,
        }))
    }
}

/// Fields of prims and variants that the text format writes as structure, not metadata.
const PRIM_STRUCTURE: &[&str] = &[
    "specifier",
    "typeName",
    "primChildren",
    "properties",
    "variantSetChildren",
    "variantChildren",
];

/// Fields of properties that the text format writes as structure, not metadata.
const PROP_STRUCTURE: &[&str] = &[
    "typeName",
    "variability",
    "custom",
    "default",
    "timeSamples",
    "connectionPaths",
    "targetPaths",
    "targetChildren",
    "connectionChildren",
    "spline",
];

/// Specs already turned into layer items: each is read once, so a corrupt file that lists
/// a child twice or under two parents cannot multiply the work.
#[derive(Default)]
struct Walk {
    seen: std::collections::HashSet<String>,
}

impl Walk {
    fn enter(&mut self, path: &str) -> bool {
        self.seen.insert(path.to_string())
    }
}

/// The path of prim `name` under `parent` (`/`, a prim, or a variant selection).
fn child_path(parent: &str, name: &str) -> String {
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

#[cfg(test)]
mod tests;
