//! Errors of reading and writing USD layers: where (file and line, column or byte
//! offset) and what.

use std::path::Path;

pub use rigport_location::Location;

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
