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
//! prim nesting is limited like the text parser's, nested values to
//! `layout::MAX_VALUE_DEPTH`, and all decoded elements together to
//! `layout::element_budget` of the file size.
//!
//! # Modules
//! The dependencies go one way: `layout` reads the container (header, table of
//! contents, structural sections) with checked primitive reads and uses only `coding`;
//! `value` decodes value representations with those reads; this module uses both to
//! walk the specs into a [`Layer`].

mod coding;
mod layout;
mod value;

use std::path::Path;

pub use self::coding::CodingError;
pub(crate) use self::layout::child_path;
use self::layout::CrateFile;
pub use self::layout::MAGIC;
use self::value::Decoded;
use super::layer::{
    Layer, ListOp, Meta, PrimBody, PrimSpec, PropKind, PropSpec, Specifier, Value, VariantSetSpec,
};
use super::parse::MAX_DEPTH;
use crate::error::{CrateProblem, Nesting, Problem, UsdError};

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
pub fn read(bytes: &[u8], path: &Path) -> Result<Layer, UsdError> {
    let file = CrateFile::open(bytes, path)?;
    file.layer()
}

/// The spec walk: specs to the layer's prims, properties and variants.
impl CrateFile<'_> {
    /// The value of a field that holds a token list (`primChildren`, `properties`, ...).
    fn names(&self, fields: &[(&str, u64)], key: &str) -> Result<Vec<String>, UsdError> {
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

    /// The spec at `path` is deeper than [`MAX_DEPTH`].
    fn nested_error(&self, path: &str) -> UsdError {
        let problem = Problem::NestedTooDeep {
            what: Nesting::Spec(path.to_string()),
            limit: MAX_DEPTH,
        };
        self.error(0, problem)
    }

    fn layer(&self) -> Result<Layer, UsdError> {
        let mut layer = Layer::default();
        let Some(root) = self.spec("/") else {
            return Ok(layer);
        };
        if root.kind != spec_type::PSEUDO_ROOT {
            return Err(self.error(0, CrateProblem::PseudoRoot));
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
    fn metadata(&self, fields: &[(&str, u64)], skip: &[&str]) -> Result<Vec<Meta>, UsdError> {
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
    ) -> Result<Option<PrimSpec>, UsdError> {
        let Some(spec) = self.spec(path) else {
            return Ok(None);
        };
        if spec.kind != spec_type::PRIM || !walk.enter(path) {
            return Ok(None);
        }
        if depth > MAX_DEPTH {
            return Err(self.nested_error(path));
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
    ) -> Result<PrimBody, UsdError> {
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
                return Err(self.nested_error(&set_path));
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

    fn property(&self, path: &str, name: String) -> Result<Option<PropSpec>, UsdError> {
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
                    connect: match field("connectionPaths")
                        .map(|r| self.value(r, 0))
                        .transpose()?
                    {
                        Some(Decoded::ListOp(ops)) => Some(list_op_paths(ops)),
                        _ => None,
                    },
                }
            }
            spec_type::RELATIONSHIP => {
                let targets = match field("targetPaths").map(|r| self.value(r, 0)).transpose()? {
                    Some(Decoded::ListOp(ops)) => Some(list_op_paths(ops)),
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

/// The paths a path list op holds: its explicit items, else the prepended, added and
/// appended ones (relationship targets, attribute connections).
fn list_op_paths(ops: Vec<(ListOp, Vec<Value>)>) -> Vec<String> {
    let explicit = ops.iter().find(|(op, _)| *op == ListOp::Explicit);
    let items: Vec<Value> = match explicit {
        Some((_, items)) => items.clone(),
        None => ops
            .into_iter()
            .filter(|(op, _)| matches!(op, ListOp::Prepend | ListOp::Add | ListOp::Append))
            .flat_map(|(_, v)| v)
            .collect(),
    };
    items
        .into_iter()
        .filter_map(|v| match v {
            Value::Path(p) => Some(p),
            _ => None,
        })
        .collect()
}

/// The reader's decoders, for the writer's tests to check its encoders against.
#[cfg(test)]
pub(crate) mod coding_for_tests {
    pub(crate) use crate::crate_file::coding::half_to_f32;

    /// `TfFastCompression` decoding of at most `max` bytes.
    pub(crate) fn decompress(input: &[u8], max: usize) -> Result<Vec<u8>, String> {
        crate::crate_file::coding::decompress_prefix(input, max).map_err(|e| e.to_string())
    }

    /// 32-bit integer decoding.
    pub(crate) fn decode_ints(data: &[u8], n: usize) -> Result<Vec<i64>, String> {
        use crate::crate_file::coding::{decode_ints, Width};
        decode_ints(data, n, Width::W32).map_err(|e| e.to_string())
    }
}
