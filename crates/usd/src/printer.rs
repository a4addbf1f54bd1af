//! `.usda` text printed from [`LayerSink`] calls as they come, line by line, into a
//! [`TextOut`] (a `String`, or a writer's own buffer that it may empty at any line end).
//!
//! Layout (what `usdcat` writes): four spaces per level; `def Type "name"` with its
//! metadata in `( ... )` on lines of their own and the body's `{` on its own line; one
//! property per line, its metadata in `( ... )` after the value; time samples one per line
//! (`time: value,`); dictionaries one entry per line, typed by the value. Numbers are
//! Rust's shortest round-trip form of their precision (`f32` or `f64`; never exponents:
//! `1e-8` prints `0.00000001`, which the grammar reads as well), so the text reads back to
//! the same numbers. Empty lines only where the writer asks ([`LayerSink::blank_line`]).

use std::fmt::{Display, Write as _};

use crate::layer::{ListOp, Specifier, Value};
use crate::sink::{AttrDecl, Data, Field, LayerSink, Targets};

/// Spaces per indentation level.
const INDENT: &str = "    ";

/// Where a [`UsdaPrinter`] writes: a text it appends whole lines to.
pub trait TextOut {
    /// The text to append to.
    fn text(&mut self) -> &mut String;

    /// Called after each line (its `\n` appended): the text may be moved elsewhere and
    /// emptied here.
    fn line_done(&mut self) {}
}

impl TextOut for String {
    fn text(&mut self) -> &mut String {
        self
    }
}

/// A [`LayerSink`] printing `.usda` text into `O`.
#[derive(Debug, Default)]
pub struct UsdaPrinter<O> {
    out: O,
    depth: usize,
}

impl<O: TextOut> UsdaPrinter<O> {
    /// A printer appending to `out`.
    pub fn new(out: O) -> Self {
        Self { out, depth: 0 }
    }

    /// The output.
    pub fn into_inner(self) -> O {
        self.out
    }

    /// Starts a line at the current indentation.
    fn start(&mut self) -> &mut String {
        let depth = self.depth;
        let text = self.out.text();
        for _ in 0..depth {
            text.push_str(INDENT);
        }
        text
    }

    /// Ends the current line.
    fn end(&mut self) {
        self.out.text().push('\n');
        self.out.line_done();
    }

    fn line(&mut self, s: &str) {
        self.start().push_str(s);
        self.end();
    }

    /// Metadata fields, one a line at the current depth.
    fn fields(&mut self, meta: &[Field<'_>]) {
        for f in meta {
            let line = self.start();
            if let Some(op) = list_op_word(f.op) {
                line.push_str(op);
                line.push(' ');
            }
            line.push_str(f.key);
            line.push_str(" = ");
            self.value(&f.value);
            self.end();
        }
    }

    /// A metadata value on the current line; a dictionary continues on lines of its own.
    fn value(&mut self, v: &Value) {
        let Value::Dict(entries) = v else {
            inline_value(self.out.text(), v);
            return;
        };
        self.out.text().push('{');
        self.end();
        self.depth += 1;
        for (key, value) in entries {
            let line = self.start();
            line.push_str(dict_type(value));
            line.push(' ');
            line.push_str(key);
            line.push_str(" = ");
            self.value(value);
            self.end();
        }
        self.depth -= 1;
        self.start().push('}');
    }

    /// `[uniform] type name`.
    fn decl(&mut self, decl: &AttrDecl<'_>) -> &mut String {
        let line = self.start();
        if decl.uniform {
            line.push_str("uniform ");
        }
        line.push_str(decl.type_name);
        line.push(' ');
        line.push_str(decl.name);
        line
    }

    /// `header (` metadata `)` and the rest of the closing line, or `header rest` alone.
    fn with_meta(&mut self, header: &str, meta: &[Field<'_>], after: &str) {
        if meta.is_empty() {
            let line = self.start();
            line.push_str(header);
            line.push_str(after);
            self.end();
            return;
        }
        let line = self.start();
        line.push_str(header);
        line.push_str(" (");
        self.end();
        self.depth += 1;
        self.fields(meta);
        self.depth -= 1;
        let line = self.start();
        line.push(')');
        line.push_str(after);
        self.end();
    }

    fn close(&mut self) {
        self.depth = self.depth.saturating_sub(1);
        self.line("}");
    }
}

impl<O: TextOut> LayerSink for UsdaPrinter<O> {
    fn begin_layer(&mut self, meta: &[Field<'_>]) {
        self.line("#usda 1.0");
        if !meta.is_empty() {
            self.line("(");
            self.depth += 1;
            self.fields(meta);
            self.depth -= 1;
            self.line(")");
        }
        self.end();
    }

    fn begin_prim(
        &mut self,
        specifier: Specifier,
        type_name: Option<&str>,
        name: &str,
        meta: &[Field<'_>],
    ) {
        let mut header = String::from(match specifier {
            Specifier::Def => "def ",
            Specifier::Over => "over ",
            Specifier::Class => "class ",
        });
        if let Some(t) = type_name {
            header.push_str(t);
            header.push(' ');
        }
        quoted(&mut header, name);
        self.with_meta(&header, meta, "");
        self.line("{");
        self.depth += 1;
    }

    fn end_prim(&mut self) {
        self.close();
    }

    fn attribute(&mut self, decl: AttrDecl<'_>, value: Option<Data<'_>>, meta: &[Field<'_>]) {
        let line = self.decl(&decl);
        if let Some(v) = value {
            line.push_str(" = ");
            data(line, &v);
        }
        if meta.is_empty() {
            self.end();
            return;
        }
        self.out.text().push_str(" (");
        self.end();
        self.depth += 1;
        self.fields(meta);
        self.depth -= 1;
        self.line(")");
    }

    fn connection(&mut self, decl: AttrDecl<'_>, target: &str) {
        let line = self.decl(&decl);
        line.push_str(".connect = ");
        path(line, target);
        self.end();
    }

    fn begin_time_samples(&mut self, decl: AttrDecl<'_>) {
        self.decl(&decl).push_str(".timeSamples = {");
        self.end();
        self.depth += 1;
    }

    fn time_sample(&mut self, time: f64, value: Data<'_>) {
        let line = self.start();
        put(line, time);
        line.push_str(": ");
        data(line, &value);
        line.push(',');
        self.end();
    }

    fn end_time_samples(&mut self) {
        self.close();
    }

    fn relationship(&mut self, name: &str, targets: Targets<'_>) {
        let line = self.start();
        line.push_str("rel ");
        line.push_str(name);
        line.push_str(" = ");
        match targets {
            Targets::One(t) => path(line, t),
            Targets::List(ts) => array(line, ts, |s, t| path(s, t)),
        }
        self.end();
    }

    fn begin_variant_set(&mut self, name: &str) {
        let line = self.start();
        line.push_str("variantSet ");
        quoted(line, name);
        line.push_str(" = {");
        self.end();
        self.depth += 1;
    }

    fn begin_variant(&mut self, name: &str, meta: &[Field<'_>]) {
        let mut header = String::new();
        quoted(&mut header, name);
        self.with_meta(&header, meta, " {");
        self.depth += 1;
    }

    fn end_variant(&mut self) {
        self.close();
    }

    fn end_variant_set(&mut self) {
        self.close();
    }

    fn blank_line(&mut self) {
        self.end();
    }
}

fn list_op_word(op: ListOp) -> Option<&'static str> {
    Some(match op {
        ListOp::Explicit => return None,
        ListOp::Prepend => "prepend",
        ListOp::Append => "append",
        ListOp::Add => "add",
        ListOp::Delete => "delete",
        ListOp::Reorder => "reorder",
    })
}

/// The type a dictionary entry is printed with, from its value (as the crate writer types
/// it).
fn dict_type(v: &Value) -> &'static str {
    match v {
        Value::Number(_) => "double",
        Value::Ident(s) if s == "true" || s == "false" => "bool",
        Value::Ident(_) => "token",
        Value::Dict(_) => "dictionary",
        Value::List(_) => "string[]",
        Value::Asset(..) => "asset",
        _ => "string",
    }
}

/// Appends a displayable value.
fn put(out: &mut String, value: impl Display) {
    // Writing to a String cannot fail.
    let _ = write!(out, "{value}");
}

/// Appends `<path>`.
fn path(out: &mut String, p: &str) {
    out.push('<');
    out.push_str(p);
    out.push('>');
}

/// Appends `[item, item, ...]`, each item written by `each`.
fn array<T>(out: &mut String, items: &[T], mut each: impl FnMut(&mut String, &T)) {
    out.push('[');
    for (i, item) in items.iter().enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        each(out, item);
    }
    out.push(']');
}

/// Appends `(a, b, ...)`.
fn tuple<T: Display + Copy>(out: &mut String, values: &[T]) {
    out.push('(');
    for (i, v) in values.iter().enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        put(out, *v);
    }
    out.push(')');
}

/// Appends a `matrix4d`: `( (row), (row), (row), (row) )`.
fn matrix(out: &mut String, m: &[f64; 16]) {
    out.push_str("( ");
    for (i, row) in m.chunks_exact(4).enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        tuple(out, row);
    }
    out.push_str(" )");
}

/// Appends a typed value.
fn data(out: &mut String, v: &Data<'_>) {
    match *v {
        Data::Int(i) => put(out, i),
        Data::Float(x) => put(out, x),
        Data::Double(x) => put(out, x),
        Data::Str(s) => quoted(out, s),
        Data::Asset(a) => {
            out.push('@');
            out.push_str(a);
            out.push('@');
        }
        Data::Float3(t) => tuple(out, &t),
        Data::Float4(t) => tuple(out, &t),
        Data::Matrix4(m) => matrix(out, &m),
        Data::Ints(v) => array(out, v, |s, x| put(s, x)),
        Data::Floats(v) => array(out, v, |s, x| put(s, x)),
        Data::Float2s(v) => array(out, v, |s, t| tuple(s, t)),
        Data::Float3s(v) => array(out, v, |s, t| tuple(s, t)),
        Data::Float4s(v) => array(out, v, |s, t| tuple(s, t)),
        Data::Matrix4s(v) => array(out, v, matrix),
        Data::Strs(v) => array(out, v, |s, t| quoted(s, t)),
    }
}

/// Appends a metadata value that fits on one line (not a dictionary).
fn inline_value(out: &mut String, v: &Value) {
    match v {
        Value::None => out.push_str("None"),
        Value::Number(x) => put(out, x),
        Value::Ident(s) => out.push_str(s),
        Value::Str(s) => quoted(out, s),
        Value::Asset(a, target) => {
            out.push('@');
            out.push_str(a);
            out.push('@');
            if let Some(t) = target {
                path(out, t);
            }
        }
        Value::Path(p) => path(out, p),
        Value::Tuple(items) => {
            out.push('(');
            for (i, item) in items.iter().enumerate() {
                if i > 0 {
                    out.push_str(", ");
                }
                inline_value(out, item);
            }
            out.push(')');
        }
        Value::List(items) => array(out, items, inline_value),
        Value::Dict(entries) => {
            out.push_str("{ ");
            for (key, value) in entries {
                out.push_str(dict_type(value));
                out.push(' ');
                out.push_str(key);
                out.push_str(" = ");
                inline_value(out, value);
                out.push_str("; ");
            }
            out.push('}');
        }
    }
}

/// Appends a quoted USDA string or token, escaping `"`, `\` and control characters.
pub fn quoted(out: &mut String, s: &str) {
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => put(out, format_args!("\\x{:02x}", u32::from(c))),
            c => out.push(c),
        }
    }
    out.push('"');
}

#[cfg(test)]
mod tests;
