//! Writing a layer as a sequence of typed calls: a writer describes its stage once, to a
//! [`LayerSink`], and the sink decides what it becomes: `.usda` text printed as the calls
//! come ([`crate::printer::UsdaPrinter`], so a long text never sits whole in memory), or a
//! [`Layer`] ([`LayerBuilder`]) for the crate writer ([`crate::crate_write::write`]).
//!
//! Values are typed ([`Data`]): numbers stay numbers, in the precision the writer has them
//! (`f32` or `f64`), from the writer to the text or to the layer, never formatted and
//! parsed back. Both sinks write a value as given (a `-0` stays `-0`); a writer that wants
//! `0` writes `0`.
//!
//! ```
//! use std::path::Path;
//! use rigport_usd::layer::Specifier;
//! use rigport_usd::printer::UsdaPrinter;
//! use rigport_usd::sink::{AttrDecl, Data, Field, LayerBuilder, LayerSink};
//!
//! fn stage(sink: &mut dyn LayerSink) {
//!     sink.begin_layer(&[Field::new("upAxis", "Z".into())]);
//!     sink.begin_prim(Specifier::Def, Some("Xform"), "A", &[]);
//!     sink.attribute(
//!         AttrDecl::new("float3", "xformOp:translate"),
//!         Some(Data::Float3([1.0, 2.0, 0.1])),
//!         &[],
//!     );
//!     sink.end_prim();
//! }
//! let mut printer = UsdaPrinter::new(String::new());
//! stage(&mut printer);
//! let text = printer.into_inner();
//! assert!(text.contains("    float3 xformOp:translate = (1, 2, 0.1)\n"));
//! let mut builder = LayerBuilder::default();
//! stage(&mut builder);
//! let built = builder.finish();
//! let parsed = rigport_usd::parse::parse(&text, Path::new("a.usda")).unwrap();
//! assert_eq!(built.root.children[0].body.props[0].kind, parsed.root.children[0].body.props[0].kind);
//! ```

use crate::layer::{
    Layer, ListOp, Meta, PrimBody, PrimSpec, PropKind, PropSpec, Specifier, Value, VariantSetSpec,
};
use crate::parse::narrow_to_type;

/// A typed attribute value (or one time sample of it).
///
/// Integers are unsigned `u32` (the ones a writer puts in an `int` attribute are indices
/// and counts); `Matrix4` is one `matrix4d` in USD's row-vector convention, its 16
/// elements row after row as USD writes them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Data<'a> {
    /// One integer (`int`).
    Int(i64),
    /// One `float` (or `half`).
    Float(f32),
    /// One `double`.
    Double(f64),
    /// A string or token, unquoted.
    Str(&'a str),
    /// An asset path, without the `@`s.
    Asset(&'a str),
    /// One 3-tuple of floats (`float3`, `color3f`, `point3f`, ...).
    Float3([f32; 3]),
    /// One 4-tuple of floats (`float4`; `quatf` written `(w, x, y, z)`).
    Float4([f32; 4]),
    /// One `matrix4d`, rows in order.
    Matrix4([f64; 16]),
    /// `int[]`.
    Ints(&'a [u32]),
    /// `float[]`.
    Floats(&'a [f32]),
    /// An array of 2-tuples of floats (`texCoord2f[]`).
    Float2s(&'a [[f32; 2]]),
    /// An array of 3-tuples of floats (`point3f[]`, `half3[]`, ...).
    Float3s(&'a [[f32; 3]]),
    /// An array of 4-tuples of floats (`quatf[]`, written `(w, x, y, z)`).
    Float4s(&'a [[f32; 4]]),
    /// `matrix4d[]`.
    Matrix4s(&'a [[f64; 16]]),
    /// `token[]` or `string[]`, unquoted.
    Strs(&'a [&'a str]),
}

impl Data<'_> {
    /// The value as a layer holds it: every number an `f64` (an `f32` widened exactly).
    pub fn to_value(&self) -> Value {
        fn numbers<T: Copy>(items: &[T], f: impl Fn(T) -> f64) -> Vec<Value> {
            items.iter().map(|&x| Value::Number(f(x))).collect()
        }
        fn tuples<const N: usize>(items: &[[f32; N]]) -> Value {
            Value::List(
                items
                    .iter()
                    .map(|t| Value::Tuple(numbers(t, f64::from)))
                    .collect(),
            )
        }
        fn matrix(m: &[f64; 16]) -> Value {
            Value::Tuple(
                m.chunks_exact(4)
                    .map(|row| Value::Tuple(numbers(row, |x| x)))
                    .collect(),
            )
        }
        match *self {
            Data::Int(i) => Value::Number(i as f64),
            Data::Float(x) => Value::Number(f64::from(x)),
            Data::Double(x) => Value::Number(x),
            Data::Str(s) => Value::Str(s.to_string()),
            Data::Asset(a) => Value::Asset(a.to_string(), None),
            Data::Float3(t) => Value::Tuple(numbers(&t, f64::from)),
            Data::Float4(t) => Value::Tuple(numbers(&t, f64::from)),
            Data::Matrix4(m) => matrix(&m),
            Data::Ints(v) => Value::List(numbers(v, f64::from)),
            Data::Floats(v) => Value::List(numbers(v, f64::from)),
            Data::Float2s(v) => tuples(v),
            Data::Float3s(v) => tuples(v),
            Data::Float4s(v) => tuples(v),
            Data::Matrix4s(v) => Value::List(v.iter().map(matrix).collect()),
            Data::Strs(v) => Value::List(v.iter().map(|s| Value::Str(s.to_string())).collect()),
        }
    }
}

macro_rules! data_from_slices {
    ($($t:ty => $variant:ident),* $(,)?) => {$(
        impl<'a> From<&'a [$t]> for Data<'a> {
            fn from(values: &'a [$t]) -> Self {
                Data::$variant(values)
            }
        }
    )*};
}

data_from_slices!(
    u32 => Ints,
    f32 => Floats,
    [f32; 2] => Float2s,
    [f32; 3] => Float3s,
    [f32; 4] => Float4s,
    [f64; 16] => Matrix4s,
);

/// An attribute's declaration: `[uniform] type name`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AttrDecl<'a> {
    /// The value type name (`point3f[]`, with its `[]`).
    pub type_name: &'a str,
    /// The full property name (`primvars:skel:jointIndices`).
    pub name: &'a str,
    /// Declared `uniform`.
    pub uniform: bool,
}

impl<'a> AttrDecl<'a> {
    /// A varying attribute `type_name name`.
    pub fn new(type_name: &'a str, name: &'a str) -> Self {
        Self {
            type_name,
            name,
            uniform: false,
        }
    }

    /// A `uniform` attribute.
    pub fn uniform(type_name: &'a str, name: &'a str) -> Self {
        Self {
            uniform: true,
            ..Self::new(type_name, name)
        }
    }
}

/// One metadata field a writer gives: `[op] key = value`. Dictionary entries are typed by
/// their values when printed (a number `double`, a string `string`), as the crate writer
/// types them.
#[derive(Clone, Debug, PartialEq)]
pub struct Field<'a> {
    /// The list operation (`prepend apiSchemas`), [`ListOp::Explicit`] for `key = value`.
    pub op: ListOp,
    /// The field name (`doc` for the documentation string).
    pub key: &'a str,
    /// The value.
    pub value: Value,
}

impl<'a> Field<'a> {
    /// `key = value`.
    pub fn new(key: &'a str, value: Value) -> Self {
        Self {
            op: ListOp::Explicit,
            key,
            value,
        }
    }

    /// `prepend key = value`.
    pub fn prepend(key: &'a str, value: Value) -> Self {
        Self {
            op: ListOp::Prepend,
            ..Self::new(key, value)
        }
    }

    fn to_meta(&self) -> Meta {
        Meta {
            key: self.key.to_string(),
            op: self.op,
            value: self.value.clone(),
            line: 0,
        }
    }
}

/// A relationship's targets, absolute prim or property paths without the `<>`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Targets<'a> {
    /// One target, written `<path>`.
    One(&'a str),
    /// A list of targets, written `[<a>, <b>]` (even with one).
    List(&'a [String]),
}

/// Receives a layer as a sequence of calls, in the order of the text: the layer's
/// metadata, then prims (each opened, filled with properties, child prims and variant
/// sets, and closed). Calls must nest: every `begin_*` has its `end_*`, properties go
/// inside a prim or variant, variants inside a variant set.
pub trait LayerSink {
    /// Starts the layer with its metadata; called once, first.
    fn begin_layer(&mut self, meta: &[Field<'_>]);

    /// Opens a prim inside the current prim or variant (or at the root).
    fn begin_prim(
        &mut self,
        specifier: Specifier,
        type_name: Option<&str>,
        name: &str,
        meta: &[Field<'_>],
    );

    /// Closes the prim opened last.
    fn end_prim(&mut self);

    /// An attribute: its default value (`None`: declared without one) and metadata.
    fn attribute(&mut self, decl: AttrDecl<'_>, value: Option<Data<'_>>, meta: &[Field<'_>]);

    /// An attribute connected to `target` (`decl.connect = <target>`).
    fn connection(&mut self, decl: AttrDecl<'_>, target: &str);

    /// Starts the time samples of an attribute (`decl.timeSamples`); the samples follow
    /// one by one, so a long animation is never held whole by a streaming sink.
    fn begin_time_samples(&mut self, decl: AttrDecl<'_>);

    /// One time sample, at `time` (a time code), after [`LayerSink::begin_time_samples`].
    fn time_sample(&mut self, time: f64, value: Data<'_>);

    /// Ends the time samples.
    fn end_time_samples(&mut self);

    /// A relationship and its targets.
    fn relationship(&mut self, name: &str, targets: Targets<'_>);

    /// Opens a variant set of the current prim.
    fn begin_variant_set(&mut self, name: &str);

    /// Opens a variant of the open variant set; its body takes properties and prims.
    fn begin_variant(&mut self, name: &str, meta: &[Field<'_>]);

    /// Closes the variant opened last.
    fn end_variant(&mut self);

    /// Closes the variant set opened last.
    fn end_variant_set(&mut self);

    /// A layout hint for text: an empty line here. The layer is the same without it.
    fn blank_line(&mut self) {}
}

/// What a [`LayerBuilder`] has open.
#[derive(Debug)]
enum Open {
    Prim(PrimSpec),
    Set(VariantSetSpec),
    Variant(String, Vec<Meta>, PrimBody),
}

/// A [`LayerSink`] that builds the [`Layer`] the `.usda` text of the same calls parses to
/// (the same specs, fields and values; line numbers 0), `float` and `half` numbers narrowed
/// to their types as the parser narrows them.
///
/// Calls that do not nest are kept where they fit best rather than refused (a property
/// outside any prim goes to the layer's root body; [`LayerBuilder::finish`] closes what is
/// still open).
#[derive(Debug, Default)]
pub struct LayerBuilder {
    layer: Layer,
    open: Vec<Open>,
    samples: Option<PropSpec>,
}

impl LayerBuilder {
    /// The layer, closing whatever is still open.
    pub fn finish(mut self) -> Layer {
        self.end_time_samples();
        while !self.open.is_empty() {
            match self.open.last() {
                Some(Open::Prim(_)) => self.end_prim(),
                Some(Open::Variant(..)) => self.end_variant(),
                _ => self.end_variant_set(),
            }
        }
        self.layer
    }

    /// The body properties and prims go to now.
    fn body(&mut self) -> &mut PrimBody {
        match self.open.last_mut() {
            Some(Open::Prim(p)) => &mut p.body,
            Some(Open::Variant(_, _, body)) => body,
            Some(Open::Set(_)) | None => &mut self.layer.root,
        }
    }

    fn push_prop(&mut self, name: &str, kind: PropKind, meta: &[Field<'_>]) {
        let prop = PropSpec {
            name: name.to_string(),
            kind,
            meta: meta.iter().map(Field::to_meta).collect(),
            line: 0,
            column: 0,
        };
        self.body().props.push(prop);
    }
}

/// An attribute's kind with nothing but its declaration.
fn attr_kind(decl: &AttrDecl<'_>) -> PropKind {
    PropKind::Attr {
        type_name: decl.type_name.to_string(),
        uniform: decl.uniform,
        default: None,
        samples: None,
        other_field: None,
        connect: None,
    }
}

/// `data` as the layer holds it for an attribute of type `type_name`.
fn typed_value(data: &Data<'_>, type_name: &str) -> Value {
    let mut v = data.to_value();
    narrow_to_type(&mut v, type_name);
    v
}

impl LayerSink for LayerBuilder {
    fn begin_layer(&mut self, meta: &[Field<'_>]) {
        self.layer.meta = meta.iter().map(Field::to_meta).collect();
    }

    fn begin_prim(
        &mut self,
        specifier: Specifier,
        type_name: Option<&str>,
        name: &str,
        meta: &[Field<'_>],
    ) {
        self.open.push(Open::Prim(PrimSpec {
            specifier,
            type_name: type_name.map(str::to_string),
            name: name.to_string(),
            meta: meta.iter().map(Field::to_meta).collect(),
            body: PrimBody::default(),
            line: 0,
        }));
    }

    fn end_prim(&mut self) {
        if let Some(Open::Prim(_)) = self.open.last() {
            if let Some(Open::Prim(prim)) = self.open.pop() {
                self.body().children.push(prim);
            }
        }
    }

    fn attribute(&mut self, decl: AttrDecl<'_>, value: Option<Data<'_>>, meta: &[Field<'_>]) {
        let mut kind = attr_kind(&decl);
        if let (PropKind::Attr { default, .. }, Some(v)) = (&mut kind, value) {
            *default = Some(typed_value(&v, decl.type_name));
        }
        self.push_prop(decl.name, kind, meta);
    }

    fn connection(&mut self, decl: AttrDecl<'_>, target: &str) {
        let mut kind = attr_kind(&decl);
        if let PropKind::Attr {
            connect,
            other_field,
            ..
        } = &mut kind
        {
            *connect = Some(vec![target.to_string()]);
            *other_field = Some("connect");
        }
        self.push_prop(decl.name, kind, &[]);
    }

    fn begin_time_samples(&mut self, decl: AttrDecl<'_>) {
        self.end_time_samples();
        let mut kind = attr_kind(&decl);
        if let PropKind::Attr { samples, .. } = &mut kind {
            *samples = Some(Vec::new());
        }
        self.samples = Some(PropSpec {
            name: decl.name.to_string(),
            kind,
            meta: Vec::new(),
            line: 0,
            column: 0,
        });
    }

    fn time_sample(&mut self, time: f64, value: Data<'_>) {
        if let Some(PropSpec {
            kind:
                PropKind::Attr {
                    type_name,
                    samples: Some(samples),
                    ..
                },
            ..
        }) = &mut self.samples
        {
            samples.push((time, typed_value(&value, type_name)));
        }
    }

    fn end_time_samples(&mut self) {
        if let Some(prop) = self.samples.take() {
            self.body().props.push(prop);
        }
    }

    fn relationship(&mut self, name: &str, targets: Targets<'_>) {
        let targets = match targets {
            Targets::One(t) => vec![t.to_string()],
            Targets::List(ts) => ts.to_vec(),
        };
        self.push_prop(
            name,
            PropKind::Rel {
                targets: Some(targets),
            },
            &[],
        );
    }

    fn begin_variant_set(&mut self, name: &str) {
        self.open.push(Open::Set(VariantSetSpec {
            name: name.to_string(),
            variants: Vec::new(),
            line: 0,
        }));
    }

    fn begin_variant(&mut self, name: &str, meta: &[Field<'_>]) {
        self.open.push(Open::Variant(
            name.to_string(),
            meta.iter().map(Field::to_meta).collect(),
            PrimBody::default(),
        ));
    }

    fn end_variant(&mut self) {
        if let Some(Open::Variant(..)) = self.open.last() {
            if let Some(Open::Variant(name, meta, body)) = self.open.pop() {
                if let Some(Open::Set(set)) = self.open.last_mut() {
                    set.variants.push((name, meta, body));
                }
            }
        }
    }

    fn end_variant_set(&mut self) {
        if let Some(Open::Set(_)) = self.open.last() {
            if let Some(Open::Set(set)) = self.open.pop() {
                self.body().variant_sets.push(set);
            }
        }
    }
}

#[cfg(test)]
mod tests;
