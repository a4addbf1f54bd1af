//! A USD layer as typed data: metadata, prim specs, properties, variant sets and values.
//!
//! The text reader ([`crate::parse`]) and the crate reader ([`crate::crate_file`]) make
//! these; [`crate::sink::LayerBuilder`] builds them from a writer's calls; the crate
//! writer ([`crate::crate_write`]) writes them. Line numbers are those of the text a layer
//! was read from (0 in a built layer: it has no text).

/// A value as written.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    /// `None`: a blocked value.
    None,
    /// A number (`true`/`false` are kept as identifiers).
    Number(f64),
    /// A bare identifier (`true`, a token written without quotes, ...).
    Ident(String),
    /// A quoted string (or token).
    Str(String),
    /// `@path@`, with the prim path of a reference (`@a.usda@</A>`) if one follows.
    Asset(String, Option<String>),
    /// `</a/b>`.
    Path(String),
    /// `( ... )`.
    Tuple(Vec<Value>),
    /// `[ ... ]`.
    List(Vec<Value>),
    /// `{ type key = value ... }`.
    Dict(Vec<(String, Value)>),
}

/// A list-editing operation on a metadata field or property (`prepend apiSchemas = ...`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ListOp {
    /// Plain `key = value`.
    Explicit,
    /// `prepend`.
    Prepend,
    /// `append`.
    Append,
    /// `add`.
    Add,
    /// `delete`.
    Delete,
    /// `reorder`.
    Reorder,
}

impl ListOp {
    /// The operation a keyword names (`prepend`, ...); `None` for other words.
    pub(crate) fn from_word(word: &str) -> Option<Self> {
        Some(match word {
            "prepend" => Self::Prepend,
            "append" => Self::Append,
            "add" => Self::Add,
            "delete" => Self::Delete,
            "reorder" => Self::Reorder,
            _ => return None,
        })
    }
}

/// One metadata field (`key = value`; a bare doc string has the key `doc`).
#[derive(Clone, Debug, PartialEq)]
pub struct Meta {
    /// The field name.
    pub key: String,
    /// The list operation it is written with.
    pub op: ListOp,
    /// The value.
    pub value: Value,
    /// 1-based line.
    pub line: usize,
}

/// `def`, `over` or `class`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Specifier {
    /// `def`: defines the prim.
    Def,
    /// `over`: only overrides opinions.
    Over,
    /// `class`: an abstract prim other prims inherit from.
    Class,
}

/// A prim as written in the layer.
#[derive(Clone, Debug, PartialEq)]
pub struct PrimSpec {
    /// `def`, `over` or `class`.
    pub specifier: Specifier,
    /// The schema type (`Mesh`, `Skeleton`, ...), if written.
    pub type_name: Option<String>,
    /// The prim name.
    pub name: String,
    /// Prim metadata in file order.
    pub meta: Vec<Meta>,
    /// Properties, children and variant sets.
    pub body: PrimBody,
    /// 1-based line of the `def`/`over`/`class`.
    pub line: usize,
}

/// What a prim (or a variant) holds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PrimBody {
    /// Property statements in file order (one property may be written several times:
    /// `points` and `points.timeSamples`).
    pub props: Vec<PropSpec>,
    /// Child prims in file order.
    pub children: Vec<PrimSpec>,
    /// Variant sets in file order.
    pub variant_sets: Vec<VariantSetSpec>,
}

/// `variantSet "name" = { "a" { ... } "b" { ... } }`.
#[derive(Clone, Debug, PartialEq)]
pub struct VariantSetSpec {
    /// The set's name.
    pub name: String,
    /// Each variant: name, metadata, body.
    pub variants: Vec<(String, Vec<Meta>, PrimBody)>,
    /// 1-based line.
    pub line: usize,
}

/// One property statement.
#[derive(Clone, Debug, PartialEq)]
pub struct PropSpec {
    /// Full name (`primvars:skel:jointIndices`).
    pub name: String,
    /// Attribute or relationship data.
    pub kind: PropKind,
    /// Metadata in file order.
    pub meta: Vec<Meta>,
    /// 1-based line.
    pub line: usize,
    /// 1-based column of the name.
    pub column: usize,
}

/// Attribute or relationship.
#[derive(Clone, Debug, PartialEq)]
pub enum PropKind {
    /// An attribute.
    Attr {
        /// Value type (`point3f[]`; `[]` kept).
        type_name: String,
        /// Written `uniform`.
        uniform: bool,
        /// `= value` (`Value::None` when blocked).
        default: Option<Value>,
        /// `.timeSamples = { t: v, ... }`, in file order (`Value::None` blocks a sample).
        samples: Option<Vec<(f64, Value)>>,
        /// Whether the statement had `.connect` or `.spline` (those values are not kept).
        other_field: Option<&'static str>,
        /// `.connect = <path>` (or a list): the connection target paths as written
        /// (shading networks: `inputs:diffuseColor.connect = <.../Tex.outputs:rgb>`).
        connect: Option<Vec<String>>,
    },
    /// A relationship: its targets as written (relative paths unresolved); `None` when
    /// declared without `=`.
    Rel {
        /// The target paths.
        targets: Option<Vec<String>>,
    },
}

/// A layer: read from text or a crate file, or built.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Layer {
    /// Layer metadata in file order.
    pub meta: Vec<Meta>,
    /// Root prims (and any root-level statements `Sdf` allows there).
    pub root: PrimBody,
}

impl From<&str> for Value {
    /// A string (or token) value.
    fn from(s: &str) -> Self {
        Value::Str(s.to_string())
    }
}

impl From<f64> for Value {
    /// A number.
    fn from(x: f64) -> Self {
        Value::Number(x)
    }
}
