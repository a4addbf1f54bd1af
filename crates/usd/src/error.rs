//! Errors of reading and writing USD layers: where (file and line, column or byte
//! offset) and what.

use std::fmt;
use std::path::{Path, PathBuf};

/// Where in a layer a problem is: the file, and a line and column or a byte offset when
/// known.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    /// The file.
    pub path: PathBuf,
    /// 1-based line number.
    pub line: Option<usize>,
    /// 1-based column (only with `line`).
    pub column: Option<usize>,
    /// Byte offset for binary layers.
    pub byte_offset: Option<u64>,
}

impl Location {
    /// The whole file.
    pub fn file(path: &Path) -> Self {
        Self {
            path: path.to_path_buf(),
            line: None,
            column: None,
            byte_offset: None,
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

    /// A byte offset inside the file.
    pub fn byte(path: &Path, offset: u64) -> Self {
        Self {
            byte_offset: Some(offset),
            ..Self::file(path)
        }
    }
}

impl fmt::Display for Location {
    /// `file:line:column`, `file:line`, `file: at byte N`, or `file`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(col) = self.column {
                write!(f, ":{col}")?;
            }
        }
        if let Some(b) = self.byte_offset {
            write!(f, ": at byte {b}")?;
        }
        Ok(())
    }
}

/// What is wrong with a layer.
#[derive(Debug, thiserror::Error)]
pub enum Problem {
    /// The file is empty.
    #[error("the file is empty")]
    Empty,
    /// A token was not what the format requires here.
    #[error("expected {expected}, found {found:?}")]
    Syntax {
        /// What the format requires.
        expected: String,
        /// What the file has (as written, shortened if long).
        found: String,
    },
    /// A well-formed value that breaks a rule of the format.
    #[error("{0}")]
    Invalid(String),
    /// The file ends before the data it declares.
    #[error("truncated: {0}")]
    Truncated(String),
}

/// A layer that could not be read or written: where, and what is wrong.
///
/// Displays as `a.usda:12:5: expected "=", found "}"`.
#[derive(Debug, thiserror::Error)]
#[error("{location}: {problem}")]
pub struct UsdError {
    /// Where (boxed: keeps `Result<_, UsdError>` small on the happy path).
    pub location: Box<Location>,
    /// What.
    pub problem: Problem,
}

impl UsdError {
    /// An error at `location`.
    pub fn new(location: Location, problem: Problem) -> Self {
        Self {
            location: Box::new(location),
            problem,
        }
    }

    /// A [`Problem::Invalid`] error at `location`.
    pub fn invalid(location: Location, message: impl Into<String>) -> Self {
        Self::new(location, Problem::Invalid(message.into()))
    }

    /// A [`Problem::Syntax`] error at `location`.
    pub fn syntax(location: Location, expected: impl Into<String>, found: &str) -> Self {
        let mut found = found.to_string();
        if found.chars().count() > 40 {
            found = found.chars().take(40).collect::<String>() + "...";
        }
        Self::new(
            location,
            Problem::Syntax {
                expected: expected.into(),
                found,
            },
        )
    }
}

/// The bytes as UTF-8 text.
///
/// # Errors
/// At the line holding the first invalid byte.
pub fn utf8<'a>(bytes: &'a [u8], path: &Path) -> Result<&'a str, UsdError> {
    std::str::from_utf8(bytes).map_err(|e| {
        let before = bytes.get(..e.valid_up_to()).unwrap_or_default();
        let line = 1 + before.iter().filter(|&&b| b == b'\n').count();
        UsdError::invalid(Location::line(path, line), "not UTF-8 text")
    })
}
