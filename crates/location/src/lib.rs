//! Where in an input file a problem is: the one location type of `rigport-usd` (USD layers)
//! and `rigport-import` (every importer, which also reads USD layers through
//! `rigport-usd`), so that an error passes from one to the other unchanged.
//!
//! ```
//! use std::path::Path;
//! use rigport_location::Location;
//! assert_eq!(Location::line_column(Path::new("walk.bvh"), 12, 5).to_string(), "walk.bvh:12:5");
//! assert_eq!(Location::json(Path::new("a.gltf"), "/skins/0").to_string(), "a.gltf: at /skins/0");
//! assert_eq!(Location::byte(Path::new("a.usdc"), 88).to_string(), "a.usdc: at byte 88");
//! assert_eq!(
//!     Location::line(Path::new("a.usda"), 7).with_prim("/Root/Skel").to_string(),
//!     "a.usda:7: </Root/Skel>"
//! );
//! assert_eq!(
//!     Location::line_column(Path::new("a.dae"), 12, 5).with_element("skin").to_string(),
//!     "a.dae:12:5: element <skin>"
//! );
//! ```
#![warn(missing_docs)]

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in an input a problem is: the file, and a line and column, a JSON path, a byte
/// offset or a USD prim path when known.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    /// The file.
    pub path: PathBuf,
    /// 1-based line number.
    pub line: Option<usize>,
    /// 1-based column (only with `line`).
    pub column: Option<usize>,
    /// JSON pointer-like path (`/skins/0/joints/3`) for JSON-based formats.
    pub json_path: Option<String>,
    /// Byte offset for binary formats.
    pub byte_offset: Option<u64>,
    /// The USD prim (or property) path the problem is about (`/Root/Skel`), for layers.
    pub prim: Option<String>,
    /// The XML element the problem is about (its tag, `skin`), for XML formats (COLLADA).
    pub element: Option<String>,
}

impl Location {
    /// The whole file.
    pub fn file(path: &Path) -> Self {
        Self {
            path: path.to_path_buf(),
            line: None,
            column: None,
            json_path: None,
            byte_offset: None,
            prim: None,
            element: None,
        }
    }

    /// A 1-based line of the file; line 0 (data from a binary file, which has no lines)
    /// names the file only.
    pub fn line(path: &Path, line: usize) -> Self {
        Self {
            line: (line > 0).then_some(line),
            ..Self::file(path)
        }
    }

    /// A 1-based line and column of the file.
    pub fn line_column(path: &Path, line: usize, column: usize) -> Self {
        Self {
            line: Some(line),
            column: Some(column),
            ..Self::file(path)
        }
    }

    /// A JSON path inside the file.
    pub fn json(path: &Path, json_path: impl Into<String>) -> Self {
        Self {
            json_path: Some(json_path.into()),
            ..Self::file(path)
        }
    }

    /// A byte offset inside the file.
    pub fn byte(path: &Path, offset: u64) -> Self {
        Self {
            byte_offset: Some(offset),
            ..Self::file(path)
        }
    }

    /// The same place, about the USD prim (or property) at `prim` (written without the
    /// angle brackets).
    #[must_use]
    pub fn with_prim(self, prim: impl Into<String>) -> Self {
        Self {
            prim: Some(prim.into()),
            ..self
        }
    }
}

impl Location {
    /// The same place, about the XML element with tag `element` (written without the angle
    /// brackets).
    #[must_use]
    pub fn with_element(self, element: impl Into<String>) -> Self {
        Self {
            element: Some(element.into()),
            ..self
        }
    }
}

impl fmt::Display for Location {
    /// `file:line:column`, `file:line`, `file: at /json/path`, `file: at byte N`, or `file`;
    /// then `: </prim/path>` when a prim is named, `: element <tag>` when an XML element is.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(col) = self.column {
                write!(f, ":{col}")?;
            }
        }
        if let Some(p) = &self.json_path {
            write!(f, ": at {p}")?;
        }
        if let Some(b) = self.byte_offset {
            write!(f, ": at byte {b}")?;
        }
        if let Some(prim) = &self.prim {
            write!(f, ": <{prim}>")?;
        }
        if let Some(element) = &self.element {
            write!(f, ": element <{element}>")?;
        }
        Ok(())
    }
}
