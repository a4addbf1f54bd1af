//! The USD text format (`.usda`) read into a [`crate::layer::Layer`]: metadata, prim
//! specs, properties, variant sets, with every value kept as written (numbers as `f64`).
//!
//! The grammar is OpenUSD's `Sdf` text file format (`pxr/usd/sdf/textFileFormat.yy`), for
//! the statements a layer holds, not only those rigport uses:
//! ```text
//! layer      := "#usda 1.0" [ "(" metadata* ")" ] prim*
//! prim       := ("def" | "over" | "class") [TypeName] "name" [ "(" metadata* ")" ]
//!               "{" ( prim | property | variantSet | reorder )* "}"
//! metadata   := "doc string" | [listop] key "=" value
//! listop     := "prepend" | "append" | "add" | "delete" | "reorder"
//! property   := [listop] ["custom"] ["uniform" | "varying" | "config"] type ["[]"] name
//!               [ "." ("timeSamples" | "connect" | "spline" | "default") ] [ "=" value ]
//!               [ "(" metadata* ")" ]
//!             | [listop] ["custom"] ["varying"] "rel" name [ "=" value ] [ "(" metadata* ")" ]
//! variantSet := "variantSet" "name" "=" "{" ( "variant" [ "(" metadata* ")" ] "{" ... "}" )* "}"
//! value      := number | identifier | string | @asset@ [<path>] | <path>
//!             | "(" values ")" | "[" values "]" | "{" dictionary or time samples "}"
//! ```
//! Statements may be separated by `;`, which `Sdf` requires between items on one line;
//! this reader accepts white space there too. Nesting is limited to [`MAX_DEPTH`] so no
//! input can exhaust the stack.

use std::path::Path;

use super::lex::{Lexer, Tok, Token};
use super::precision::{is_float_type, is_half_type, round_to_half};
use crate::error::{Location, Nesting, Problem, UsdError};
use crate::layer::{
    Layer, ListOp, Meta, PrimBody, PrimSpec, PropKind, PropSpec, Specifier, Value, VariantSetSpec,
};

/// Deepest nesting of prims, variants and values accepted. Real layers nest prims a few
/// dozen levels and values three (a matrix in a list); 200 is far beyond both and keeps
/// the recursion well inside a 2 MiB thread stack.
pub const MAX_DEPTH: usize = 200;

/// Parses a whole `.usda` text.
///
/// # Errors
/// The first syntax error, at its line and column; a missing `#usda 1.0` header at 1:1.
pub fn parse(text: &str, path: &Path) -> Result<Layer, UsdError> {
    let mut p = Parser {
        lx: Lexer::new(text, path),
        depth: 0,
    };
    p.header()?;
    let mut layer = Layer::default();
    if p.is_punct('(')? {
        p.lx.next_token()?;
        layer.meta = p.metadata_block()?;
    }
    loop {
        let t = p.lx.peek()?.clone();
        match &t.tok {
            Tok::Eof => break,
            Tok::Ident("def" | "over" | "class") => {
                let prim = p.prim()?;
                layer.root.children.push(prim);
            }
            Tok::Punct(';') => {
                p.lx.next_token()?;
            }
            _ => return Err(p.lx.expected(&t, "def, over or class")),
        }
    }
    Ok(layer)
}

struct Parser<'a> {
    lx: Lexer<'a>,
    depth: usize,
}

impl<'a> Parser<'a> {
    fn header(&mut self) -> Result<(), UsdError> {
        let text = self.lx.text();
        let first = text.lines().next().unwrap_or_default();
        let mut words = first.split_ascii_whitespace();
        if words.next() != Some("#usda") {
            let shown = if text.trim().is_empty() {
                return Err(UsdError::new(
                    Location::file(self.lx.path()),
                    Problem::Empty,
                ));
            } else {
                first
            };
            return Err(UsdError::syntax(
                Location::line_column(self.lx.path(), 1, 1),
                "the header #usda 1.0",
                shown,
            ));
        }
        match words.next() {
            Some(v) if v.starts_with("1.") => Ok(()),
            other => Err(UsdError::syntax(
                Location::line_column(self.lx.path(), 1, 7),
                "version 1.0 after #usda",
                other.unwrap_or("end of line"),
            )),
        }
    }

    fn is_punct(&mut self, c: char) -> Result<bool, UsdError> {
        Ok(self.lx.peek()?.tok == Tok::Punct(c))
    }

    fn expect_punct(&mut self, c: char) -> Result<Token<'a>, UsdError> {
        let t = self.lx.next_token()?;
        if t.tok == Tok::Punct(c) {
            Ok(t)
        } else {
            Err(self.lx.expected(&t, &format!("{c:?}")))
        }
    }

    fn ident(&mut self, what: &str) -> Result<(&'a str, Token<'a>), UsdError> {
        let t = self.lx.next_token()?;
        match t.tok {
            Tok::Ident(s) => Ok((s, t)),
            _ => Err(self.lx.expected(&t, what)),
        }
    }

    fn string(&mut self, what: &str) -> Result<String, UsdError> {
        let t = self.lx.next_token()?;
        match t.tok {
            Tok::Str(s) => Ok(s),
            _ => Err(self.lx.expected(&t, what)),
        }
    }

    fn enter(&mut self, at: &Token<'_>) -> Result<(), UsdError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(UsdError::new(
                self.lx.location(at.start),
                Problem::NestedTooDeep {
                    what: Nesting::Text,
                    limit: MAX_DEPTH,
                },
            ));
        }
        Ok(())
    }

    /// Skips `;` separators.
    fn separators(&mut self) -> Result<(), UsdError> {
        while self.is_punct(';')? {
            self.lx.next_token()?;
        }
        Ok(())
    }

    /// Metadata items up to and including `)`; the `(` is consumed.
    fn metadata_block(&mut self) -> Result<Vec<Meta>, UsdError> {
        let mut out = Vec::new();
        loop {
            self.separators()?;
            let t = self.lx.next_token()?;
            match t.tok {
                Tok::Punct(')') => return Ok(out),
                Tok::Str(doc) => out.push(Meta {
                    key: "doc".into(),
                    op: ListOp::Explicit,
                    value: Value::Str(doc),
                    line: t.line,
                }),
                Tok::Ident(word) => {
                    let (op, key) = match ListOp::from_word(word) {
                        Some(op) if matches!(self.lx.peek()?.tok, Tok::Ident(_)) => {
                            (op, self.ident("a metadata name")?.0)
                        }
                        _ => (ListOp::Explicit, word),
                    };
                    // `displayUnit = ...` and every other field: `key = value`.
                    self.expect_punct('=')?;
                    let value = self.value()?;
                    out.push(Meta {
                        key: key.to_string(),
                        op,
                        value,
                        line: t.line,
                    });
                }
                _ => return Err(self.lx.expected(&t, "a metadata field or )")),
            }
        }
    }

    /// `def|over|class [Type] "name" [( meta )] { body }`.
    fn prim(&mut self) -> Result<PrimSpec, UsdError> {
        let (word, start) = self.ident("def, over or class")?;
        self.enter(&start)?;
        let specifier = match word {
            "def" => Specifier::Def,
            "over" => Specifier::Over,
            _ => Specifier::Class,
        };
        let t = self.lx.next_token()?;
        let (type_name, name) = match t.tok {
            Tok::Ident(ty) => (Some(ty.to_string()), self.string("a quoted prim name")?),
            Tok::Str(name) => (None, name),
            _ => return Err(self.lx.expected(&t, "a prim type or a quoted prim name")),
        };
        let meta = if self.is_punct('(')? {
            self.lx.next_token()?;
            self.metadata_block()?
        } else {
            Vec::new()
        };
        self.expect_punct('{')?;
        let body = self.body()?;
        self.depth -= 1;
        Ok(PrimSpec {
            specifier,
            type_name,
            name,
            meta,
            body,
            line: start.line,
        })
    }

    /// Prim body items up to and including `}`; the `{` is consumed.
    fn body(&mut self) -> Result<PrimBody, UsdError> {
        let mut body = PrimBody::default();
        loop {
            self.separators()?;
            let t = self.lx.peek()?.clone();
            match t.tok {
                Tok::Punct('}') => {
                    self.lx.next_token()?;
                    return Ok(body);
                }
                Tok::Ident("def" | "over" | "class") => body.children.push(self.prim()?),
                Tok::Ident("variantSet") => body.variant_sets.push(self.variant_set()?),
                Tok::Ident("reorder")
                    if matches!(
                        self.peek_second()?,
                        Some("nameChildren" | "properties" | "rootPrims")
                    ) =>
                {
                    // `reorder nameChildren = [...]` only changes the order of a listing.
                    self.lx.next_token()?;
                    self.lx.next_token()?;
                    self.expect_punct('=')?;
                    self.value()?;
                }
                Tok::Ident(_) => body.props.push(self.property()?),
                _ => {
                    return Err(self
                        .lx
                        .expected(&t, "a prim, a property, a variantSet or }"))
                }
            }
        }
    }

    /// The identifier after the peeked one, when the peeked token is `reorder`: only
    /// `reorder nameChildren` / `reorder properties` need two tokens of look-ahead, so this
    /// re-lexes from the peeked token's end instead of keeping a second buffer.
    fn peek_second(&mut self) -> Result<Option<&'a str>, UsdError> {
        let end = self.lx.peek()?.end;
        let rest = self.lx.text().get(end..).unwrap_or_default();
        let word = rest
            .trim_start()
            .split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
            .next()
            .unwrap_or_default();
        Ok((!word.is_empty()).then(|| {
            let at = rest.len() - rest.trim_start().len();
            &rest[at..at + word.len()]
        }))
    }

    fn variant_set(&mut self) -> Result<VariantSetSpec, UsdError> {
        let (_, start) = self.ident("variantSet")?;
        self.enter(&start)?;
        let name = self.string("a quoted variant set name")?;
        self.expect_punct('=')?;
        self.expect_punct('{')?;
        let mut variants = Vec::new();
        loop {
            self.separators()?;
            let t = self.lx.next_token()?;
            match t.tok {
                Tok::Punct('}') => break,
                Tok::Str(variant) => {
                    let meta = if self.is_punct('(')? {
                        self.lx.next_token()?;
                        self.metadata_block()?
                    } else {
                        Vec::new()
                    };
                    let open = self.expect_punct('{')?;
                    self.enter(&open)?;
                    let body = self.body()?;
                    self.depth -= 1;
                    variants.push((variant, meta, body));
                }
                _ => return Err(self.lx.expected(&t, "a quoted variant name or }")),
            }
        }
        self.depth -= 1;
        Ok(VariantSetSpec {
            name,
            variants,
            line: start.line,
        })
    }

    fn property(&mut self) -> Result<PropSpec, UsdError> {
        let (mut word, first) = self.ident("a property")?;
        if ListOp::from_word(word).is_some() {
            word = self.ident("a property after the list operation")?.0;
        }
        let mut uniform = false;
        loop {
            match word {
                "custom" | "varying" | "config" => {}
                "uniform" => uniform = true,
                _ => break,
            }
            word = self.ident("a property type or rel")?.0;
        }
        if word == "rel" {
            let (name, name_tok) = self.ident("a relationship name")?;
            // `rel x.default = </t>` is an old spelling of `rel x = </t>`.
            if self.is_punct('.')? {
                self.lx.next_token()?;
                self.ident("default")?;
            }
            let targets = if self.is_punct('=')? {
                self.lx.next_token()?;
                let at = self.lx.peek()?.clone();
                Some(match self.value()? {
                    Value::None => Vec::new(),
                    Value::Path(p) => vec![p],
                    Value::List(items) => items
                        .into_iter()
                        .map(|v| match v {
                            Value::Path(p) => Ok(p),
                            _ => Err(self.lx.expected(&at, "relationship target paths </...>")),
                        })
                        .collect::<Result<_, _>>()?,
                    _ => {
                        return Err(self
                            .lx
                            .expected(&at, "a target path </...> or a list of them"))
                    }
                })
            } else {
                None
            };
            let meta = self.optional_metadata()?;
            let column = self.lx.location(name_tok.start).column.unwrap_or(1);
            return Ok(PropSpec {
                name: name.to_string(),
                kind: PropKind::Rel { targets },
                meta,
                line: first.line,
                column,
            });
        }
        let mut type_name = word.to_string();
        if self.is_punct('[')? {
            self.lx.next_token()?;
            self.expect_punct(']')?;
            type_name.push_str("[]");
        }
        let (name, name_tok) = self.ident("an attribute name")?;
        let column = self.lx.location(name_tok.start).column.unwrap_or(1);
        let mut field = None;
        if self.is_punct('.')? {
            self.lx.next_token()?;
            let (f, t) = self.ident("timeSamples, connect, spline or default")?;
            field = Some(match f {
                "timeSamples" => "timeSamples",
                "connect" => "connect",
                "spline" => "spline",
                "default" => "default",
                _ => {
                    return Err(self
                        .lx
                        .expected(&t, "timeSamples, connect, spline or default"))
                }
            });
        }
        let mut default = None;
        let mut samples = None;
        let mut other_field = None;
        let mut connect = None;
        if self.is_punct('=')? {
            self.lx.next_token()?;
            match field {
                Some("timeSamples") => samples = Some(self.time_samples()?),
                Some(other @ ("connect" | "spline")) => {
                    let value = self.value()?;
                    if other == "connect" {
                        connect = Some(match value {
                            Value::Path(p) => vec![p],
                            Value::List(items) => items
                                .into_iter()
                                .filter_map(|v| match v {
                                    Value::Path(p) => Some(p),
                                    _ => None,
                                })
                                .collect(),
                            _ => Vec::new(),
                        });
                    }
                    other_field = Some(other);
                }
                _ => default = Some(self.value()?),
            }
        } else if let Some(other @ ("connect" | "spline" | "timeSamples")) = field {
            other_field = Some(other);
        }
        let meta = self.optional_metadata()?;
        // USD holds the value in the declared type: narrow `float` and `half` numbers now,
        // so a text layer gives the numbers the binary encoding of it holds.
        if let Some(v) = default.as_mut() {
            narrow_to_type(v, &type_name);
        }
        for (_, v) in samples.iter_mut().flatten() {
            narrow_to_type(v, &type_name);
        }
        Ok(PropSpec {
            name: name.to_string(),
            kind: PropKind::Attr {
                type_name,
                uniform,
                default,
                samples,
                other_field,
                connect,
            },
            meta,
            line: first.line,
            column,
        })
    }

    fn optional_metadata(&mut self) -> Result<Vec<Meta>, UsdError> {
        if self.is_punct('(')? {
            self.lx.next_token()?;
            self.metadata_block()
        } else {
            Ok(Vec::new())
        }
    }

    /// `{ time: value, ... }` after `.timeSamples =`.
    fn time_samples(&mut self) -> Result<Vec<(f64, Value)>, UsdError> {
        let open = self.expect_punct('{')?;
        self.enter(&open)?;
        let mut out = Vec::new();
        loop {
            let t = self.lx.next_token()?;
            match t.tok {
                Tok::Punct('}') => break,
                Tok::Punct(',' | ';') => continue,
                Tok::Number(time) => {
                    self.expect_punct(':')?;
                    out.push((time, self.value()?));
                }
                _ => return Err(self.lx.expected(&t, "a time code, or } after the samples")),
            }
        }
        self.depth -= 1;
        Ok(out)
    }

    fn value(&mut self) -> Result<Value, UsdError> {
        let t = self.lx.next_token()?;
        Ok(match t.tok {
            Tok::Number(n) => Value::Number(n),
            Tok::Ident("None") => Value::None,
            Tok::Ident("inf") => Value::Number(f64::INFINITY),
            Tok::Ident("nan") => Value::Number(f64::NAN),
            Tok::Ident(word) => Value::Ident(word.to_string()),
            Tok::Str(s) => Value::Str(s),
            Tok::Path(p) => Value::Path(p.to_string()),
            Tok::Asset(a) => {
                let target = match self.lx.peek()?.tok {
                    Tok::Path(p) => {
                        self.lx.next_token()?;
                        Some(p.to_string())
                    }
                    _ => None,
                };
                // A layer offset `( offset = 1; scale = 2 )` after a reference or sublayer.
                if self.is_punct('(')? {
                    self.lx.next_token()?;
                    self.metadata_block()?;
                }
                Value::Asset(a, target)
            }
            Tok::Punct(open @ ('(' | '[')) => {
                self.enter(&t)?;
                let close = if open == '(' { ')' } else { ']' };
                let mut items = Vec::new();
                loop {
                    if self.is_punct(close)? {
                        self.lx.next_token()?;
                        break;
                    }
                    items.push(self.value()?);
                    let sep = self.lx.next_token()?;
                    match sep.tok {
                        Tok::Punct(',') => {}
                        Tok::Punct(c) if c == close => break,
                        _ => {
                            return Err(self.lx.expected(&sep, &format!("',' or '{close}'")));
                        }
                    }
                }
                self.depth -= 1;
                if open == '(' {
                    Value::Tuple(items)
                } else {
                    Value::List(items)
                }
            }
            Tok::Punct('{') => {
                self.enter(&t)?;
                let dict = self.dictionary()?;
                self.depth -= 1;
                dict
            }
            _ => return Err(self.lx.expected(&t, "a value")),
        })
    }

    /// `{ type key = value ... }` (the `{` consumed); keys may be quoted.
    fn dictionary(&mut self) -> Result<Value, UsdError> {
        let mut entries = Vec::new();
        loop {
            self.separators()?;
            let t = self.lx.next_token()?;
            match t.tok {
                Tok::Punct('}') => return Ok(Value::Dict(entries)),
                Tok::Punct(',') => continue,
                Tok::Ident(_) => {
                    if self.is_punct('[')? {
                        self.lx.next_token()?;
                        self.expect_punct(']')?;
                    }
                    let k = self.lx.next_token()?;
                    let key = match k.tok {
                        Tok::Ident(s) => s.to_string(),
                        Tok::Str(s) => s,
                        _ => return Err(self.lx.expected(&k, "a dictionary key")),
                    };
                    self.expect_punct('=')?;
                    entries.push((key, self.value()?));
                }
                _ => return Err(self.lx.expected(&t, "a typed dictionary entry or }")),
            }
        }
    }
}

/// A parsed value narrowed to the precision its attribute type holds: numbers of `half`
/// types rounded to binary16 and of `float` types to binary32, as USD stores them when it
/// reads a layer (so text and binary layers give the same numbers). Other types are kept.
pub fn narrow_to_type(value: &mut Value, type_name: &str) {
    let round: fn(f64) -> f64 = if is_half_type(type_name) {
        |x| f64::from(round_to_half(x as f32))
    } else if is_float_type(type_name) {
        |x| f64::from(x as f32)
    } else {
        return;
    };
    fn walk(v: &mut Value, round: fn(f64) -> f64) {
        match v {
            Value::Number(x) => *x = round(*x),
            Value::Tuple(items) | Value::List(items) => {
                items.iter_mut().for_each(|i| walk(i, round));
            }
            _ => {}
        }
    }
    walk(value, round);
}

#[cfg(test)]
mod tests {
    use super::*;

    const SAMPLE: &str = r#"#usda 1.0
(
    "layer doc"
    defaultPrim = "Root"
    metersPerUnit = .01
    upAxis = 'Z'
    customLayerData = { string a = "b"; dictionary d = { double x = 1 } }
    subLayers = [@a.usda@ (offset = 2; scale = 1), @b.usda@]
)

def SkelRoot "Root" (
    kind = "component"
    prepend apiSchemas = ["SkelBindingAPI"]
    variants = { string clip = "walk" }
    prepend variantSets = "clip"
    references = @other.usda@</Thing>
)
{
    rel skel:skeleton = </Root/Skel>
    custom uniform double3 xformOp:translate = (1, 2, 3e1)
    quatf[] rotations.timeSamples = {
        1: [(1, 0, 0, 0)],
        2.5: None,
    }
    int[] primvars:skel:jointIndices = [0, 1] (interpolation = "vertex"; elementSize = 2)
    rel empty
    prepend rel targets = [</A>, </B>]
    float x.connect = </Root.y>
    reorder properties = ["a"]
    variantSet "clip" = {
        "walk" (doc = "w") { def SkelAnimation "Walk" { } }
        "run" { }
    }
    over "Child" { }
}
"#;

    #[test]
    fn reads_every_statement_kind() {
        let layer = parse(SAMPLE, Path::new("s.usda")).unwrap();
        let keys: Vec<&str> = layer.meta.iter().map(|m| m.key.as_str()).collect();
        assert_eq!(
            keys,
            [
                "doc",
                "defaultPrim",
                "metersPerUnit",
                "upAxis",
                "customLayerData",
                "subLayers"
            ]
        );
        assert_eq!(layer.meta[2].value, Value::Number(0.01));
        let root = &layer.root.children[0];
        assert_eq!(root.type_name.as_deref(), Some("SkelRoot"));
        assert_eq!(root.name, "Root");
        assert_eq!(root.line, 11);
        assert_eq!(root.meta[1].op, ListOp::Prepend);
        assert_eq!(
            root.meta[4].value,
            Value::Asset("other.usda".into(), Some("/Thing".into()))
        );
        let names: Vec<&str> = root.body.props.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "skel:skeleton",
                "xformOp:translate",
                "rotations",
                "primvars:skel:jointIndices",
                "empty",
                "targets",
                "x"
            ]
        );
        let PropKind::Attr {
            samples: Some(samples),
            type_name,
            ..
        } = &root.body.props[2].kind
        else {
            panic!("time samples expected");
        };
        assert_eq!(type_name, "quatf[]");
        assert_eq!(samples.len(), 2);
        assert_eq!(samples[1], (2.5, Value::None));
        let ji = &root.body.props[3];
        assert_eq!(ji.meta[1].key, "elementSize");
        assert_eq!(ji.meta[1].value, Value::Number(2.0));
        assert_eq!((ji.line, ji.column), (25, 11));
        assert_eq!(
            root.body.props[5].kind,
            PropKind::Rel {
                targets: Some(vec!["/A".into(), "/B".into()])
            }
        );
        let vs = &root.body.variant_sets[0];
        assert_eq!(vs.name, "clip");
        assert_eq!(vs.variants.len(), 2);
        assert_eq!(vs.variants[0].2.children[0].name, "Walk");
        assert_eq!(root.body.children[0].specifier, Specifier::Over);
    }

    #[test]
    fn syntax_errors_name_line_and_column() {
        let cases = [
            ("", "the file is empty"),
            ("#usda 2.0\n", "s.usda:1:7: expected version 1.0"),
            (
                "hello\n",
                "s.usda:1:1: expected the header #usda 1.0, found \"hello\"",
            ),
            (
                "#usda 1.0\ndef Mesh \"M\" {\n  point3f[] points = [(1, 2, 3) (4, 5, 6)]\n}\n",
                "s.usda:3:33: expected ',' or ']', found \"(\"",
            ),
            (
                "#usda 1.0\ndef Mesh \"M\" {\n  int x = \n",
                "s.usda:4:1: expected a value, found \"end of file\"",
            ),
            (
                "#usda 1.0\ndef \"M\" { float a.bogus = 1 }\n",
                "s.usda:2:19: expected timeSamples, connect, spline or default",
            ),
        ];
        for (text, want) in cases {
            let e = parse(text, Path::new("s.usda")).unwrap_err().to_string();
            assert!(e.contains(want), "{text:?}: {e}");
        }
    }

    #[test]
    fn deep_nesting_is_an_error_not_a_crash() {
        let text = format!(
            "#usda 1.0\ndef \"A\" {{ int[] x = {} }}",
            "[".repeat(100_000)
        );
        let e = parse(&text, Path::new("d.usda")).unwrap_err().to_string();
        assert!(e.contains("nested more than"), "{e}");
    }
}
