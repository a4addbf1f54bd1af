//! The XML layer under the COLLADA mapping: the parsed document (roxmltree), elements by
//! `id`, where an element is (line, column, tag), and COLLADA's data: `<float_array>`,
//! `<Name_array>`/`<IDREF_array>`, `<int>` lists (`<p>`, `<v>`, `<vcount>`) and `<source>`
//! with its `<accessor>` (count, stride, offset checked against the array).

use std::collections::HashMap;
use std::path::Path;

use rigport_model::glam::{DMat4, DVec3};

use crate::text::NumberIssue;
use crate::{ImportError, Location, Problem};

/// An element of the document.
pub(super) type Node<'a, 'i> = roxmltree::Node<'a, 'i>;

/// Parses `text` as XML.
///
/// # Errors
/// Not well-formed XML, at roxmltree's position; a file that ends before its root element
/// closes is truncated, at its last line.
pub(super) fn parse<'i>(
    text: &'i str,
    path: &Path,
) -> Result<roxmltree::Document<'i>, ImportError> {
    let options = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..roxmltree::ParsingOptions::default()
    };
    roxmltree::Document::parse_with_options(text, options).map_err(|e| match e {
        roxmltree::Error::UnclosedRootNode | roxmltree::Error::UnexpectedEndOfStream => {
            let line = 1 + text.trim_end().matches('\n').count();
            ImportError::new(
                Location::line(path, line),
                Problem::Truncated(
                    "the file ends before the XML document's root element closes".into(),
                ),
            )
        }
        e => {
            let pos = e.pos();
            ImportError::new(
                Location::line_column(path, pos.row as usize, pos.col as usize),
                Problem::Invalid(format!("not well-formed XML: {e}")),
            )
        }
    })
}

/// The document with its `id` index and the file it came from.
pub(super) struct Doc<'a, 'i> {
    /// The file, for locations.
    pub(super) path: &'a Path,
    xml: &'a roxmltree::Document<'i>,
    ids: HashMap<&'a str, Node<'a, 'i>>,
}

impl<'a, 'i> Doc<'a, 'i> {
    /// Indexes every element's `id` (the first of a repeated id wins).
    pub(super) fn new(xml: &'a roxmltree::Document<'i>, path: &'a Path) -> Self {
        let mut ids = HashMap::new();
        for node in xml.descendants().filter(Node::is_element) {
            if let Some(id) = node.attribute("id") {
                ids.entry(id).or_insert(node);
            }
        }
        Self { path, xml, ids }
    }

    /// The root element.
    pub(super) fn root(&self) -> Node<'a, 'i> {
        self.xml.root_element()
    }

    /// Where `node` starts: line, column and its tag.
    pub(super) fn at(&self, node: Node) -> Location {
        let pos = self.xml.text_pos_at(node.range().start);
        let loc = Location::line_column(self.path, pos.row as usize, pos.col as usize);
        if node.is_element() {
            loc.with_element(node.tag_name().name())
        } else {
            loc
        }
    }

    /// An error at `node`.
    pub(super) fn error(&self, node: Node, problem: impl Into<Problem>) -> ImportError {
        ImportError::new(self.at(node), problem.into())
    }

    /// A [`Problem::Invalid`] at `node`.
    pub(super) fn invalid(&self, node: Node, message: impl Into<String>) -> ImportError {
        self.error(node, Problem::Invalid(message.into()))
    }

    /// The element a URL (`#id`) or a bare id names.
    pub(super) fn by_id(&self, id: &str) -> Option<Node<'a, 'i>> {
        self.ids.get(id.strip_prefix('#').unwrap_or(id)).copied()
    }

    /// The element `from`'s attribute `attr` names (`#id`).
    ///
    /// # Errors
    /// The attribute is missing, or no element has that id.
    pub(super) fn link(
        &self,
        from: Node,
        attr: &str,
        what: &'static str,
    ) -> Result<Node<'a, 'i>, ImportError> {
        let Some(url) = from.attribute(attr) else {
            return Err(self.invalid(from, format!("has no `{attr}` attribute")));
        };
        self.by_id(url).ok_or_else(|| {
            self.error(
                from,
                Problem::UnknownName {
                    what,
                    name: url.to_string(),
                    within: "the document".into(),
                },
            )
        })
    }

    /// The numbers of `node`'s text, as floats.
    ///
    /// # Errors
    /// A token that is not a finite number, at `node`.
    pub(super) fn floats(&self, node: Node) -> Result<Vec<f64>, ImportError> {
        tokens(node)
            .map(|t| match t.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                Ok(_) => Err(self.number(node, t, NumberIssue::NotFinite)),
                Err(_) => Err(self.number(node, t, NumberIssue::NotANumber)),
            })
            .collect()
    }

    /// The integers of `node`'s text.
    ///
    /// # Errors
    /// A token that is not an integer, at `node`.
    pub(super) fn ints(&self, node: Node) -> Result<Vec<i64>, ImportError> {
        tokens(node)
            .map(|t| {
                t.parse::<i64>()
                    .map_err(|_| self.number(node, t, NumberIssue::NotANumber))
            })
            .collect()
    }

    fn number(&self, node: Node, token: &str, issue: NumberIssue) -> ImportError {
        self.error(
            node,
            Problem::Number {
                what: "value",
                found: crate::error::shortened(token),
                issue,
            },
        )
    }

    /// `source` (a `<source>` element, or the data array itself) read through its
    /// accessor.
    ///
    /// # Errors
    /// No data array, an array whose `count` differs from its values, an accessor reaching
    /// past its array.
    pub(super) fn source(&self, source: Node<'a, 'i>) -> Result<Source, ImportError> {
        let array = if is_array(source) {
            source
        } else {
            child_elements(source)
                .find(|n| is_array(*n))
                .ok_or_else(|| self.invalid(source, "has no data array"))?
        };
        let data = if array.tag_name().name() == "float_array" {
            Data::Floats(self.floats(array)?)
        } else {
            Data::Names(tokens(array).map(str::to_string).collect())
        };
        let len = data.len();
        if let Some(count) = array.attribute("count") {
            if count.parse::<usize>().ok() != Some(len) {
                return Err(self.error(
                    array,
                    Problem::Count {
                        what: "values",
                        found: len,
                        expected: format!("{count} (its count)"),
                    },
                ));
            }
        }
        let accessor = child(source, "technique_common").and_then(|t| child(t, "accessor"));
        let Some(accessor) = accessor else {
            return Ok(Source {
                count: len,
                stride: 1,
                offset: 0,
                data,
            });
        };
        let attr = |name: &str, default: usize| -> Result<usize, ImportError> {
            match accessor.attribute(name) {
                None => Ok(default),
                Some(v) => v
                    .trim()
                    .parse()
                    .map_err(|_| self.invalid(accessor, format!("`{name}` {v:?} is not a count"))),
            }
        };
        let count = attr("count", 0)?;
        let stride = attr("stride", 1)?.max(1);
        let offset = attr("offset", 0)?;
        // The last element needs only the values its params read (at least one).
        let params = child_elements(accessor).count().clamp(1, stride);
        let fits = count == 0
            || (count - 1)
                .checked_mul(stride)
                .and_then(|n| n.checked_add(offset + params))
                .is_some_and(|n| n <= len);
        if !fits {
            return Err(self.error(
                accessor,
                Problem::Count {
                    what: "values in its array",
                    found: len,
                    expected: format!("{count} x stride {stride} from offset {offset}"),
                },
            ));
        }
        Ok(Source {
            count,
            stride,
            offset,
            data,
        })
    }
}

/// Whether `node` is a COLLADA data array.
fn is_array(node: Node) -> bool {
    matches!(
        node.tag_name().name(),
        "float_array" | "Name_array" | "IDREF_array" | "SIDREF_array" | "int_array" | "bool_array"
    )
}

/// The white-space separated tokens of `node`'s text.
pub(super) fn tokens<'a>(node: Node<'a, '_>) -> impl Iterator<Item = &'a str> {
    node.text().unwrap_or("").split_ascii_whitespace()
}

/// The child elements of `node`.
pub(super) fn child_elements<'a, 'i>(node: Node<'a, 'i>) -> impl Iterator<Item = Node<'a, 'i>> {
    node.children().filter(Node::is_element)
}

/// The first child element of `node` with tag `name`.
pub(super) fn child<'a, 'i>(node: Node<'a, 'i>, name: &str) -> Option<Node<'a, 'i>> {
    child_elements(node).find(|n| n.tag_name().name() == name)
}

/// The child elements of `node` with tag `name`.
pub(super) fn children<'a, 'i: 'a>(
    node: Node<'a, 'i>,
    name: &'a str,
) -> impl Iterator<Item = Node<'a, 'i>> + 'a {
    child_elements(node).filter(move |n| n.tag_name().name() == name)
}

/// The values of a `<source>`'s array.
#[derive(Clone, Debug)]
pub(super) enum Data {
    /// `<float_array>`.
    Floats(Vec<f64>),
    /// `<Name_array>`, `<IDREF_array>`, ...
    Names(Vec<String>),
}

impl Data {
    fn len(&self) -> usize {
        match self {
            Data::Floats(v) => v.len(),
            Data::Names(v) => v.len(),
        }
    }
}

/// A `<source>` read through its accessor: `count` elements of `stride` values from
/// `offset`. Element reads are bounds-checked by [`Doc::source`].
#[derive(Clone, Debug)]
pub(super) struct Source {
    pub(super) count: usize,
    pub(super) stride: usize,
    pub(super) offset: usize,
    pub(super) data: Data,
}

impl Source {
    /// Component `c` of element `i` (0 when out of range or not numeric).
    pub(super) fn float(&self, i: usize, c: usize) -> f64 {
        match &self.data {
            Data::Floats(v) if c < self.stride => v
                .get(self.offset + i * self.stride + c)
                .copied()
                .unwrap_or(0.0),
            _ => 0.0,
        }
    }

    /// Element `i`'s first three components.
    pub(super) fn vec3(&self, i: usize) -> DVec3 {
        DVec3::new(self.float(i, 0), self.float(i, 1), self.float(i, 2))
    }

    /// Element `i` as a 4x4 matrix (16 values, row-major as COLLADA writes them).
    pub(super) fn mat4(&self, i: usize) -> DMat4 {
        let mut m = [0.0; 16];
        for (k, v) in m.iter_mut().enumerate() {
            *v = self.float(i, k);
        }
        row_major(&m)
    }

    /// Element `i`'s first component as a name.
    pub(super) fn name(&self, i: usize) -> Option<&str> {
        match &self.data {
            Data::Names(v) => v.get(self.offset + i * self.stride).map(String::as_str),
            Data::Floats(_) => None,
        }
    }
}

/// A COLLADA matrix (16 values, row-major, column vectors) as glam's.
pub(super) fn row_major(m: &[f64; 16]) -> DMat4 {
    DMat4::from_cols_array(m).transpose()
}
