//! A [`Layer`] written as a USD crate file (`.usdc`, version 0.8.0), the specs and fields
//! `Sdf`'s text parser would make of the same text, so usd-core reads the `.usdc` to the
//! same layer as the `.usda` it came from.
//!
//! # What is written (OpenUSD `pxr/usd/sdf/crateFile.cpp`, `textParserHelpers.cpp`)
//! - The bootstrap, the value heap, the sections `TOKENS` (LZ4), `STRINGS`, `FIELDS`
//!   (integer-coded names, LZ4 value representations), `FIELDSETS`, `PATHS` (the path
//!   tree, depth first) and `SPECS` (all integer-coded), and the table of contents.
//! - Specs: the pseudo-root (layer metadata, `primChildren`), prims (`specifier`,
//!   `typeName`, metadata, `properties`, `primChildren`, `variantSetChildren`), attributes
//!   (`typeName`, `custom`, `variability`, `default`, `timeSamples`, `connectionPaths`
//!   with `connectionChildren` and a connection spec per target, metadata),
//!   relationships (`targetPaths` with `targetChildren` and a target spec per target),
//!   variant sets (`variantChildren`) and variants (metadata, children, properties).
//! - Values are typed by the attribute's type name; metadata by `Sdf`'s schema for the
//!   fields it registers (`documentation`, `kind`, `upAxis`, `metersPerUnit`,
//!   `elementSize`, `interpolation`, `apiSchemas`, `variants`, `customData`, ...); other
//!   metadata by its value (numbers double, strings string, `true`/`false` bool).
//!
//! # Limits
//! References, payloads, sublayers and relocates are not written (rigport's layers have
//! none): a layer holding one is an error naming its line, never a silent gap. A
//! property written in several statements (`points` and `points.timeSamples`) becomes
//! one spec, the later statement winning per field, as `Sdf` reads the text.
//! Dictionary entries are typed by their values (the text parser does not keep the
//! declared types): a `double` written in text stays a `double`, an `int` becomes one too.

mod encode;
mod tables;
mod values;

use std::path::Path;

use self::tables::Tables;
use self::values::ty;
use crate::crate_file::child_path;
use crate::error::{Location, UsdError, WriteProblem};
use crate::layer::{Layer, ListOp, Meta, PrimBody, PrimSpec, PropKind, PropSpec, Specifier, Value};

/// `SdfSpecType` values.
mod spec_type {
    pub const ATTRIBUTE: u32 = 1;
    pub const CONNECTION: u32 = 2;
    pub const PRIM: u32 = 6;
    pub const PSEUDO_ROOT: u32 = 7;
    pub const RELATIONSHIP: u32 = 8;
    pub const RELATIONSHIP_TARGET: u32 = 9;
    pub const VARIANT: u32 = 10;
    pub const VARIANT_SET: u32 = 11;
}

/// Writes `layer` as a crate file; `path` names the source in errors.
///
/// # Errors
/// A value that does not fit its declared type, an unknown value type name, or a
/// composition arc the writer does not support, at the line of its statement.
pub fn write(layer: &Layer, path: &Path) -> Result<Vec<u8>, UsdError> {
    let mut w = Writer {
        t: Tables::new(),
        path,
    };
    let mut fields = w.metadata(&layer.meta, 0)?;
    let names = child_names(&layer.root, 0, &w)?;
    if !names.is_empty() {
        fields.push(w.field("primChildren", |t| Ok(t.token_vector(&names)), 0)?);
    }
    w.t.spec("/", spec_type::PSEUDO_ROOT, &fields);
    for child in &layer.root.children {
        w.prim("/", child)?;
    }
    Ok(w.t.finish())
}

struct Writer<'a> {
    t: Tables,
    path: &'a Path,
}

/// The names of a body's child prims, each once (a prim written twice is an error).
fn child_names<'l>(
    body: &'l PrimBody,
    line: usize,
    w: &Writer<'_>,
) -> Result<Vec<&'l str>, UsdError> {
    let mut names: Vec<&str> = Vec::new();
    for c in &body.children {
        if names.contains(&c.name.as_str()) {
            return Err(w.error(c.line.max(line), WriteProblem::PrimTwice(c.name.clone())));
        }
        names.push(&c.name);
    }
    Ok(names)
}

impl Writer<'_> {
    fn error(&self, line: usize, problem: WriteProblem) -> UsdError {
        UsdError::new(Location::line(self.path, line), problem.into())
    }

    /// A field: its name's token and the representation `make` writes.
    fn field(
        &mut self,
        name: &str,
        make: impl FnOnce(&mut Tables) -> Result<u64, String>,
        line: usize,
    ) -> Result<(u32, u64), UsdError> {
        let token = self.t.token(name);
        let rep = make(&mut self.t).map_err(|message| {
            let field = name.to_string();
            self.error(line, WriteProblem::Field { field, message })
        })?;
        Ok((token, rep))
    }

    /// A prim spec under `parent` (the pseudo-root, a prim or a variant) and everything
    /// beneath it.
    fn prim(&mut self, parent: &str, spec: &PrimSpec) -> Result<(), UsdError> {
        let path = child_path(parent, &spec.name);
        let line = spec.line;
        let specifier = match spec.specifier {
            Specifier::Def => 0,
            Specifier::Over => 1,
            Specifier::Class => 2,
        };
        let mut fields = vec![self.field(
            "specifier",
            |_| Ok(values::rep(ty::SPECIFIER, false, true, specifier)),
            line,
        )?];
        if let Some(type_name) = &spec.type_name {
            fields.push(self.field(
                "typeName",
                |t| t.scalar(ty::TOKEN, &Value::Str(type_name.clone())),
                line,
            )?);
        }
        fields.extend(self.metadata(&spec.meta, line)?);
        self.body(&path, &spec.body, fields, spec_type::PRIM, line)
    }

    /// The spec of a prim or variant at `path` with its `fields` plus those of its body,
    /// then the specs of its properties, children and variant sets.
    fn body(
        &mut self,
        path: &str,
        body: &PrimBody,
        mut fields: Vec<(u32, u64)>,
        kind: u32,
        line: usize,
    ) -> Result<(), UsdError> {
        let mut props: Vec<(&str, Vec<&PropSpec>)> = Vec::new();
        for p in &body.props {
            match props.iter_mut().find(|(n, _)| *n == p.name) {
                Some((_, statements)) => statements.push(p),
                None => props.push((&p.name, vec![p])),
            }
        }
        if !props.is_empty() {
            let names: Vec<&str> = props.iter().map(|(n, _)| *n).collect();
            fields.push(self.field("properties", |t| Ok(t.token_vector(&names)), line)?);
        }
        let names = child_names(body, line, self)?;
        if !names.is_empty() {
            fields.push(self.field("primChildren", |t| Ok(t.token_vector(&names)), line)?);
        }
        if !body.variant_sets.is_empty() {
            let sets: Vec<&str> = body.variant_sets.iter().map(|s| s.name.as_str()).collect();
            fields.push(self.field("variantSetChildren", |t| Ok(t.token_vector(&sets)), line)?);
        }
        self.t.spec(path, kind, &fields);
        for (name, statements) in props {
            self.property(path, name, &statements)?;
        }
        for child in &body.children {
            self.prim(path, child)?;
        }
        for set in &body.variant_sets {
            let set_path = format!("{path}{{{}=}}", set.name);
            let variants: Vec<&str> = set.variants.iter().map(|(v, _, _)| v.as_str()).collect();
            let f = self.field(
                "variantChildren",
                |t| Ok(t.token_vector(&variants)),
                set.line,
            )?;
            self.t.spec(&set_path, spec_type::VARIANT_SET, &[f]);
            for (variant, meta, v_body) in &set.variants {
                let v_path = format!("{path}{{{}={variant}}}", set.name);
                let fields = self.metadata(meta, set.line)?;
                self.body(&v_path, v_body, fields, spec_type::VARIANT, set.line)?;
            }
        }
        Ok(())
    }

    /// One property from its statements (later statements win per field).
    fn property(
        &mut self,
        prim: &str,
        name: &str,
        statements: &[&PropSpec],
    ) -> Result<(), UsdError> {
        let path = format!("{prim}.{name}");
        let line = statements.last().map_or(0, |s| s.line);
        let metas: Vec<Meta> = statements
            .iter()
            .flat_map(|s| s.meta.iter().cloned())
            .collect();
        let first = statements.first().map(|s| &s.kind);
        let mut fields = Vec::new();
        let mut children: Vec<String> = Vec::new();
        let kind = match first {
            Some(PropKind::Attr { type_name, .. }) => {
                let mut uniform = false;
                let mut default = None;
                let mut samples = None;
                let mut connect = None;
                for s in statements {
                    if let PropKind::Attr {
                        uniform: u,
                        default: d,
                        samples: ts,
                        connect: c,
                        ..
                    } = &s.kind
                    {
                        uniform |= *u;
                        default = d.as_ref().or(default);
                        samples = ts.as_ref().or(samples);
                        connect = c.as_ref().or(connect);
                    }
                }
                fields.push(self.field(
                    "typeName",
                    |t| t.scalar(ty::TOKEN, &Value::Str(type_name.clone())),
                    line,
                )?);
                fields.push(self.field(
                    "custom",
                    |_| Ok(values::rep(ty::BOOL, false, true, 0)),
                    line,
                )?);
                fields.push(self.field(
                    "variability",
                    |_| {
                        Ok(values::rep(
                            ty::VARIABILITY,
                            false,
                            true,
                            u64::from(uniform),
                        ))
                    },
                    line,
                )?);
                if let Some(d) = default {
                    fields.push(self.field("default", |t| t.attr_value(type_name, d), line)?);
                }
                if let Some(s) = samples {
                    let mut sorted: Vec<(f64, Value)> = Vec::new();
                    for (time, v) in s {
                        match sorted.iter_mut().find(|(t, _)| t == time) {
                            Some(slot) => slot.1 = v.clone(),
                            None => sorted.push((*time, v.clone())),
                        }
                    }
                    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
                    fields.push(self.field(
                        "timeSamples",
                        |t| t.time_samples(type_name, &sorted),
                        line,
                    )?);
                }
                if let Some(targets) = connect {
                    children = targets.iter().map(|p| absolute(prim, p)).collect();
                    fields.extend(self.targets(
                        "connectionPaths",
                        "connectionChildren",
                        &children,
                        line,
                    )?);
                }
                spec_type::ATTRIBUTE
            }
            Some(PropKind::Rel { .. }) => {
                let targets = statements.iter().rev().find_map(|s| match &s.kind {
                    PropKind::Rel { targets } => targets.as_ref(),
                    PropKind::Attr { .. } => None,
                });
                // `Sdf`'s text parser gives a relationship without a keyword `uniform`.
                fields.push(self.field(
                    "variability",
                    |_| Ok(values::rep(ty::VARIABILITY, false, true, 1)),
                    line,
                )?);
                if let Some(targets) = targets {
                    children = targets.iter().map(|p| absolute(prim, p)).collect();
                    fields.extend(self.targets(
                        "targetPaths",
                        "targetChildren",
                        &children,
                        line,
                    )?);
                }
                spec_type::RELATIONSHIP
            }
            None => return Ok(()),
        };
        fields.extend(self.metadata(&metas, line)?);
        self.t.spec(&path, kind, &fields);
        let child_kind = if kind == spec_type::ATTRIBUTE {
            spec_type::CONNECTION
        } else {
            spec_type::RELATIONSHIP_TARGET
        };
        for target in &children {
            self.t.spec(&format!("{path}[{target}]"), child_kind, &[]);
        }
        Ok(())
    }

    /// The explicit path list op of a relationship's targets or an attribute's
    /// connections, and its children field (an empty list writes no children).
    fn targets(
        &mut self,
        list: &str,
        children: &str,
        paths: &[String],
        line: usize,
    ) -> Result<Vec<(u32, u64)>, UsdError> {
        let items: Vec<Value> = paths.iter().map(|p| Value::Path(p.clone())).collect();
        let mut out = vec![self.field(
            list,
            |t| t.list_op(ty::PATH_LIST_OP, &[(ListOp::Explicit, items)]),
            line,
        )?];
        if !paths.is_empty() {
            out.push(self.field(children, |t| Ok(t.path_vector(paths)), line)?);
        }
        Ok(out)
    }

    /// Metadata items as fields: list ops of one key merged into one field, other keys
    /// the last statement's value.
    fn metadata(&mut self, metas: &[Meta], line: usize) -> Result<Vec<(u32, u64)>, UsdError> {
        let mut keys: Vec<&str> = Vec::new();
        for m in metas {
            if !keys.contains(&m.key.as_str()) {
                keys.push(&m.key);
            }
        }
        let mut fields = Vec::new();
        for key in keys {
            let items: Vec<&Meta> = metas.iter().filter(|m| m.key == key).collect();
            let at = items.last().map_or(line, |m| m.line.max(line));
            let Some(last) = items.last() else { continue };
            let list_op = |t: u8| {
                let items = &items;
                move |tables: &mut Tables| {
                    let ops: Vec<(ListOp, Vec<Value>)> = items
                        .iter()
                        .map(|m| match &m.value {
                            Value::List(v) => (m.op, v.clone()),
                            Value::None => (m.op, Vec::new()),
                            other => (m.op, vec![other.clone()]),
                        })
                        .collect();
                    tables.list_op(t, &ops)
                }
            };
            let value = &last.value;
            let field = match key {
                "apiSchemas" => self.field(key, list_op(ty::TOKEN_LIST_OP), at)?,
                "variantSets" => self.field("variantSetNames", list_op(ty::STRING_LIST_OP), at)?,
                "inherits" | "specializes" => self.field(key, list_op(ty::PATH_LIST_OP), at)?,
                "references" | "payload" | "subLayers" | "relocates" => {
                    return Err(self.error(at, WriteProblem::Unsupported(key.to_string())))
                }
                "variants" => match value {
                    Value::Dict(entries) => {
                        self.field("variantSelection", |t| t.variant_selection(entries), at)?
                    }
                    _ => return Err(self.error(at, WriteProblem::VariantsNotDictionary)),
                },
                _ => {
                    let (name, t) = metadata_type(key, value);
                    match (t, value) {
                        (ty::DICTIONARY, Value::Dict(entries)) => {
                            self.field(name, |tables| tables.dictionary(entries), at)?
                        }
                        (ty::TOKEN_VECTOR, Value::List(items)) => {
                            let names: Vec<&str> = items
                                .iter()
                                .filter_map(|i| match i {
                                    Value::Str(s) | Value::Ident(s) => Some(s.as_str()),
                                    _ => None,
                                })
                                .collect();
                            self.field(name, |tables| Ok(tables.token_vector(&names)), at)?
                        }
                        (ty::STRING_VECTOR, _) => {
                            self.field(name, |tables| tables.attr_value("string[]", value), at)?
                        }
                        _ => self.field(name, |tables| tables.scalar(t, value), at)?,
                    }
                }
            };
            fields.push(field);
        }
        Ok(fields)
    }
}

/// The field name and crate type of a metadata key as `Sdf`'s schema registers it; for
/// keys it does not know, the type of the value.
fn metadata_type<'k>(key: &'k str, value: &Value) -> (&'k str, u8) {
    let t = match key {
        "doc" => return ("documentation", ty::STRING),
        "comment" | "displayName" | "displayGroup" | "documentation" => ty::STRING,
        "kind" | "defaultPrim" | "upAxis" | "interpolation" | "colorSpace" | "connectability"
        | "renderType" => ty::TOKEN,
        "metersPerUnit" | "kilogramsPerUnit" | "timeCodesPerSecond" | "framesPerSecond"
        | "startTimeCode" | "endTimeCode" => ty::DOUBLE,
        "elementSize" => ty::INT,
        "active" | "hidden" | "instanceable" => ty::BOOL,
        "customData" | "customLayerData" | "assetInfo" => ty::DICTIONARY,
        "allowedTokens" => ty::TOKEN_VECTOR,
        _ => match value {
            Value::Number(_) => ty::DOUBLE,
            Value::Ident(s) if s == "true" || s == "false" => ty::BOOL,
            Value::Ident(_) => ty::TOKEN,
            Value::Dict(_) => ty::DICTIONARY,
            Value::List(_) => ty::STRING_VECTOR,
            _ => ty::STRING,
        },
    };
    (key, t)
}

/// A target path made absolute: relative paths (`<../B>`, `<.x>`, `<C>`) are anchored at
/// the owning prim, as `Sdf`'s text parser anchors them.
fn absolute(prim: &str, target: &str) -> String {
    if target.starts_with('/') {
        return target.to_string();
    }
    let mut base = prim.to_string();
    let mut rest = target;
    loop {
        if let Some(r) = rest.strip_prefix("../") {
            let cut = base.rfind('/').unwrap_or(0);
            base.truncate(cut.max(1));
            rest = r;
        } else if rest == ".." {
            let cut = base.rfind('/').unwrap_or(0);
            base.truncate(cut.max(1));
            return base;
        } else if let Some(r) = rest.strip_prefix("./") {
            rest = r;
        } else {
            break;
        }
    }
    if rest.starts_with('.') {
        format!("{base}{rest}")
    } else {
        child_path(&base, rest)
    }
}

#[cfg(test)]
mod tests;
