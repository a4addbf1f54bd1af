pub use rigport_location::Location;

use rigport_model::{AssetError, SkeletonProblem};

use crate::problem::{Hierarchy, Limit, Mismatch, Missing, Repeated, Rule, Uri};

/// What is wrong with an input.
#[derive(Debug, thiserror::Error)]
pub enum Problem {
    /// The file could not be read.
    #[error("cannot read: {0}")]
    Io(#[source] std::io::Error),
    /// The file is empty (or holds only blank lines and comments).
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
    /// A well-formed value that breaks a rule of the format (out of range, NaN, negative
    /// weight, wrong count, ...).
    #[error("{0}")]
    Invalid(String),
    /// The skeleton's parent structure is broken; every problem is listed.
    #[error("invalid skeleton: {}", join(.0))]
    Skeleton(Vec<SkeletonProblem>),
    /// The file is truncated: it ends before the data it declares.
    #[error("truncated: {0}")]
    Truncated(String),
    /// The file ends where the format requires more.
    #[error("truncated: the file ends where {expected} was expected")]
    UnexpectedEnd {
        /// What the format requires next.
        expected: &'static str,
    },
    /// A token that must be a number is not one, is out of its type's range, or is not
    /// finite (one wording for every text importer).
    #[error("{what} {found:?} {issue}")]
    Number {
        /// What the number is (`coordinate`, `weight`, `Frame Time`).
        what: &'static str,
        /// The token as written (shortened if long).
        found: String,
        /// What is wrong with it.
        issue: NumberIssue,
    },
    /// A count that differs from the one the file (or format) requires.
    #[error("{found} {what}, expected {expected}")]
    Count {
        /// What is counted (plural: `weights`, `values`).
        what: &'static str,
        /// How many the file has.
        found: usize,
        /// How many are required (or the rule: `3`, `1 to 3`, `at least 3`).
        expected: String,
    },
    /// A name, key or item given twice.
    #[error("{what} is given twice (first on line {first_line})")]
    Duplicate {
        /// What is repeated, as written (`*skinWeights`, `bone "arm"`).
        what: String,
        /// The line of its first occurrence.
        first_line: usize,
    },
    /// An index beyond the elements it refers to.
    #[error("{what} index {index} is out of range: there are {count} {plural}")]
    IndexOutOfRange {
        /// The kind of element (`vertex`, `joint`).
        what: &'static str,
        /// Its plural (`vertices`, `joints`).
        plural: &'static str,
        /// The index as the file numbers it.
        index: i64,
        /// How many there are.
        count: usize,
    },
    /// A name that refers to nothing.
    #[error("unknown {what} {name:?}: {within} has no {what} of that name")]
    UnknownName {
        /// The kind of thing named (`bone`, `joint`).
        what: &'static str,
        /// The name.
        name: String,
        /// Where names are looked up (`:bonedata`, `the skeleton "walk"`).
        within: String,
    },
    /// A value that must not be negative is.
    #[error("{what} {found} is negative")]
    Negative {
        /// What the value is.
        what: &'static str,
        /// The value as written.
        found: String,
    },
    /// Bytes that are not UTF-8 in a text format.
    #[error("not UTF-8 text")]
    NotUtf8,
    /// The parent structure of the joints or bones is broken (as the file numbers them).
    #[error(transparent)]
    Hierarchy(#[from] Hierarchy),
    /// More than rigport's types hold (32-bit indices and floats, key times).
    #[error(transparent)]
    Limit(#[from] Limit),
    /// Two counts in the input that must agree and do not.
    #[error(transparent)]
    Mismatch(#[from] Mismatch),
    /// Something the format requires is not there.
    #[error(transparent)]
    Missing(#[from] Missing),
    /// Something the format allows once is given again.
    #[error(transparent)]
    Repeated(#[from] Repeated),
    /// A well-formed input that breaks a rule of its format.
    #[error(transparent)]
    Rule(#[from] Rule),
    /// The bytes a glTF `uri` names cannot be had.
    #[error(transparent)]
    Uri(#[from] Uri),
    /// A USD layer that cannot be read ([`rigport_usd::Problem`]; its empty-file, syntax,
    /// truncation and free-text problems map to this enum's).
    #[error(transparent)]
    Usd(rigport_usd::Problem),
    /// The imported asset breaks the model's invariants ([`rigport_model::Asset::validate`]);
    /// every problem is listed. Reported rather than trusted: a parse that succeeded
    /// should never get here.
    #[error("the imported asset is invalid: {}", join(.0))]
    Asset(Vec<AssetError>),
}

/// `found` as an error shows it: at most 40 characters, then `...`.
pub(crate) fn shortened(found: &str) -> String {
    if found.chars().count() > 40 {
        found.chars().take(40).collect::<String>() + "..."
    } else {
        found.to_string()
    }
}

/// Checks `asset` with [`rigport_model::Asset::validate`], the one place every importer
/// (and any caller that builds or edits an asset) maps its problems to an error.
///
/// # Errors
/// [`Problem::Asset`] with every problem, at `location()` (usually the file).
pub fn check_asset(
    asset: &rigport_model::Asset,
    location: impl FnOnce() -> Location,
) -> Result<(), ImportError> {
    asset
        .validate()
        .map_err(|problems| ImportError::new(location(), Problem::Asset(problems)))
}

fn join(problems: &[impl ToString]) -> String {
    problems
        .iter()
        .map(ToString::to_string)
        .collect::<Vec<_>>()
        .join("; ")
}

/// An input that could not be imported: where, and what is wrong.
///
/// Displays as `walk.bvh:12:5: expected OFFSET, found "CHANNELS"`.
#[derive(Debug, thiserror::Error)]
#[error("{location}: {problem}")]
pub struct ImportError {
    /// Where (boxed: keeps `Result<_, ImportError>` small on the happy path).
    pub location: Box<Location>,
    /// What.
    pub problem: Problem,
}

impl ImportError {
    /// An error at `location`.
    pub fn new(location: Location, problem: Problem) -> Self {
        Self {
            location: Box::new(location),
            problem,
        }
    }

    /// A typed problem (any class of [`Problem`]) at `location`.
    pub fn at(location: Location, problem: impl Into<Problem>) -> Self {
        Self::new(location, problem.into())
    }

    /// An [`Problem::Invalid`] error at `location`.
    pub fn invalid(location: Location, message: impl Into<String>) -> Self {
        Self::new(location, Problem::Invalid(message.into()))
    }

    /// A [`Problem::Syntax`] error at `location`.
    pub fn syntax(location: Location, expected: impl Into<String>, found: &str) -> Self {
        Self::new(
            location,
            Problem::Syntax {
                expected: expected.into(),
                found: shortened(found),
            },
        )
    }

    /// A [`Problem::Count`] error at `location`.
    pub fn count(
        location: Location,
        what: &'static str,
        found: usize,
        expected: impl ToString,
    ) -> Self {
        Self::new(
            location,
            Problem::Count {
                what,
                found,
                expected: expected.to_string(),
            },
        )
    }
}

/// Why a token is not the number a format requires.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum NumberIssue {
    /// Not a number at all.
    #[error("is not a number")]
    NotANumber,
    /// A number beyond the range of the type it is read into (`1e39` for `f32`, an
    /// integer with too many digits).
    #[error("is out of range for {0}")]
    OutOfRange(&'static str),
    /// `nan`, `inf` or `infinity`.
    #[error("is not finite")]
    NotFinite,
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn displays_file_line_column() {
        let e = ImportError::syntax(
            Location::line_column(Path::new("walk.bvh"), 12, 5),
            "OFFSET",
            "CHANNELS",
        );
        assert_eq!(
            e.to_string(),
            "walk.bvh:12:5: expected OFFSET, found \"CHANNELS\""
        );
        let e = ImportError::invalid(Location::json(Path::new("a.gltf"), "/skins/0"), "bad");
        assert_eq!(e.to_string(), "a.gltf: at /skins/0: bad");
    }
}
