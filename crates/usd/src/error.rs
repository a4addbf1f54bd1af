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
    /// Bytes that are not UTF-8 in a text layer.
    #[error("not UTF-8 text")]
    NotUtf8,
    /// An index past the table it indexes: `token index 9 out of range (4 tokens)`.
    #[error(fmt = index_out_of_range)]
    IndexOutOfRange {
        /// What is indexed (`token`, `path`).
        what: &'static str,
        /// The index as the file holds it.
        index: i64,
        /// Whether an index inside the table may also name an empty slot (`or unset`).
        may_be_unset: bool,
        /// How many entries there are, when the message says.
        count: Option<usize>,
        /// The entries' plural after the count (`tokens`), or `""` for the bare count.
        plural: &'static str,
    },
    /// Nesting deeper than rigport follows (a guard against runaway recursion).
    #[error(fmt = nested_too_deep)]
    NestedTooDeep {
        /// What is nested.
        what: Nesting,
        /// The deepest level followed.
        limit: usize,
    },
    /// More elements than fit the sizes rigport works in: `{count} {what} is too many`, or
    /// `too many {what}` without a count.
    #[error(fmt = too_many)]
    TooMany {
        /// What is counted (plural: `elements`, `fields`).
        what: &'static str,
        /// How many, when known.
        count: Option<u64>,
    },
    /// An offset that points outside the file: `value offset -8 out of the file`.
    #[error(fmt = offset_out_of_file)]
    OffsetOutOfFile {
        /// What the offset locates (`value`, `time samples`).
        what: &'static str,
        /// The offset as the file holds it, when the message shows it.
        offset: Option<i64>,
    },
    /// A compressed stream that does not decode.
    #[error(transparent)]
    Compression(#[from] crate::crate_file::CodingError),
    /// A crate file whose structure is inconsistent.
    #[error(transparent)]
    Crate(#[from] CrateProblem),
    /// A `.usdz` package that cannot be read or written.
    #[error(transparent)]
    Package(#[from] PackageProblem),
    /// A layer that the `.usdc` writer cannot write.
    #[error(transparent)]
    Write(#[from] WriteProblem),
}

/// What is nested too deep ([`Problem::NestedTooDeep`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Nesting {
    /// Blocks of `.usda` text: `nested more than 64 levels deep`.
    Text,
    /// Values inside crate-file values: `values nested more than 64 deep`.
    Values,
    /// A prim or variant spec of a crate file: `</A/B> is nested more than 64 deep`.
    Spec(String),
}

fn index_out_of_range(
    what: &'static str,
    index: &i64,
    may_be_unset: &bool,
    count: &Option<usize>,
    plural: &'static str,
    f: &mut std::fmt::Formatter<'_>,
) -> std::fmt::Result {
    write!(f, "{what} index {index} out of range")?;
    if *may_be_unset {
        f.write_str(" or unset")?;
    }
    match (count, plural) {
        (Some(n), "") => write!(f, " ({n})"),
        (Some(n), plural) => write!(f, " ({n} {plural})"),
        (None, _) => Ok(()),
    }
}

fn nested_too_deep(
    what: &Nesting,
    limit: &usize,
    f: &mut std::fmt::Formatter<'_>,
) -> std::fmt::Result {
    match what {
        Nesting::Text => write!(f, "nested more than {limit} levels deep"),
        Nesting::Values => write!(f, "values nested more than {limit} deep"),
        Nesting::Spec(path) => write!(f, "<{path}> is nested more than {limit} deep"),
    }
}

fn too_many(
    what: &'static str,
    count: &Option<u64>,
    f: &mut std::fmt::Formatter<'_>,
) -> std::fmt::Result {
    match count {
        Some(n) => write!(f, "{n} {what} is too many"),
        None => write!(f, "too many {what}"),
    }
}

fn offset_out_of_file(
    what: &'static str,
    offset: &Option<i64>,
    f: &mut std::fmt::Formatter<'_>,
) -> std::fmt::Result {
    match offset {
        Some(o) => write!(f, "{what} offset {o} out of the file"),
        None => write!(f, "{what} offset out of the file"),
    }
}

/// What is inconsistent in a crate file's structure ([`Problem::Crate`]).
#[derive(Debug, thiserror::Error)]
pub enum CrateProblem {
    /// The file does not start with the crate header.
    #[error("not a USD crate file (no PXR-USDC header)")]
    NotCrate,
    /// A crate version rigport does not read.
    #[error(
        "crate version {}.{}.{} is not supported (rigport reads 0.4.0 and later; re-save the \
         file with a current USD)",
        .0.0, .0.1, .0.2
    )]
    Version((u8, u8, u8)),
    /// Counts that would decode more than the file can hold.
    #[error(
        "the file claims more data than it can hold ({claimed} more elements; at most \
         {budget} are decoded for a file of {file_len} bytes)"
    )]
    OverBudget {
        /// Elements asked for.
        claimed: u64,
        /// Elements decoded at most for a file of this size.
        budget: u64,
        /// The file's size in bytes.
        file_len: usize,
    },
    /// A count too large for this machine's sizes.
    #[error("count {0} is too large")]
    CountTooLarge(u64),
    /// A table of contents with more sections than a crate file has.
    #[error("{0} sections in the table of contents")]
    Sections(u64),
    /// The tokens section holds fewer tokens than it claims.
    #[error("the tokens section holds {found} tokens, {claimed} claimed")]
    Tokens {
        /// Tokens found.
        found: usize,
        /// Tokens claimed.
        claimed: usize,
    },
    /// The path tree's jumps visit a path twice.
    #[error("the path tree's jumps revisit paths")]
    PathsRevisited,
    /// The path tree refers past its entries.
    #[error("the path tree refers to entry {entry} of {count}")]
    PathEntry {
        /// The entry.
        entry: usize,
        /// How many entries there are.
        count: usize,
    },
    /// A jump to a sibling before the first path.
    #[error("a negative path jump")]
    NegativePathJump,
    /// The spec at `/` is not the pseudo-root.
    #[error("the spec at </> is not the layer's pseudo-root")]
    PseudoRoot,
    /// A spec whose field set runs past the field sets.
    #[error("field set {field_set} of <{path}> runs past the field sets")]
    FieldSet {
        /// The field set's index.
        field_set: u32,
        /// The spec's path (`?` when unknown).
        path: String,
    },
    /// An array of a value type that has no elements.
    #[error("value type {0} has no elements")]
    NoElements(u8),
    /// A float array with an unknown coding letter.
    #[error("unknown float array coding {0:?}")]
    FloatCoding(char),
    /// Time-sample times that are not what the format stores.
    #[error("time sample times are not {0}")]
    SampleTimes(&'static str),
    /// Time samples with more or fewer values than times.
    #[error("{values} time sample values for {times} times")]
    SampleValues {
        /// Values.
        values: usize,
        /// Times.
        times: usize,
    },
}

/// Why a `.usdz` package cannot be read or written ([`Problem::Package`]).
#[derive(Debug, thiserror::Error)]
pub enum PackageProblem {
    /// The root layer is itself a package.
    #[error("the root layer of a .usdz is itself a package")]
    Nested,
    /// The zip archive cannot be read.
    #[error("not a readable .usdz: {0}")]
    Unreadable(zip::result::ZipError),
    /// The package holds no file.
    #[error("the .usdz package is empty (it needs a root layer)")]
    Empty,
    /// The first file is not a layer.
    #[error("the first file of a .usdz must be its root layer (.usda/.usdc), found {0:?}")]
    FirstNotLayer(String),
    /// A member that cannot be read.
    #[error("cannot read {name:?} from the package: {error}")]
    Member {
        /// The member's name.
        name: String,
        /// Why.
        error: std::io::Error,
    },
    /// A member name a package cannot hold (empty, absolute, `..`, backslashes).
    #[error("{0:?} cannot be a member of a .usdz")]
    BadName(String),
    /// A member given twice.
    #[error("{0:?} is given twice for the .usdz")]
    Twice(String),
    /// A member (`Some(name)`) or the whole package (`None`) past the 4 GiB of zip
    /// without zip64.
    #[error(fmt = over_4_gib)]
    Over4Gib(Option<String>),
    /// A member name longer than zip holds.
    #[error("{0:?} is too long a name")]
    NameTooLong(String),
}

fn over_4_gib(member: &Option<String>, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
    match member {
        Some(name) => write!(f, "{name:?} is over 4 GiB (zip64 is not written)"),
        None => f.write_str("the package is over 4 GiB (zip64 is not written)"),
    }
}

/// Why the `.usdc` writer cannot write a layer ([`Problem::Write`]).
#[derive(Debug, thiserror::Error)]
pub enum WriteProblem {
    /// Two statements of one prim in one scope.
    #[error("prim {0:?} is written twice in one scope (merge the statements)")]
    PrimTwice(String),
    /// Metadata the writer does not write.
    #[error("{0} cannot be written to a .usdc by rigport (not supported)")]
    Unsupported(String),
    /// `variants` metadata that is not a dictionary.
    #[error("variants must be a dictionary")]
    VariantsNotDictionary,
    /// A field whose value cannot be written as its type.
    #[error("{field}: {message}")]
    Field {
        /// The field.
        field: String,
        /// What is wrong with the value.
        message: String,
    },
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
        UsdError::new(Location::line(path, line), Problem::NotUtf8)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The typed problems word their messages as the free-text ones they replaced.
    #[test]
    fn typed_problems_keep_their_wording() {
        let cases: [(Problem, &str); 8] = [
            (
                Problem::IndexOutOfRange {
                    what: "path",
                    index: 7,
                    may_be_unset: true,
                    count: Some(3),
                    plural: "paths",
                },
                "path index 7 out of range or unset (3 paths)",
            ),
            (
                Problem::IndexOutOfRange {
                    what: "path",
                    index: 7,
                    may_be_unset: false,
                    count: Some(3),
                    plural: "",
                },
                "path index 7 out of range (3)",
            ),
            (
                Problem::IndexOutOfRange {
                    what: "field",
                    index: 9,
                    may_be_unset: false,
                    count: None,
                    plural: "",
                },
                "field index 9 out of range",
            ),
            (
                Problem::NestedTooDeep {
                    what: Nesting::Spec("/A".into()),
                    limit: 4,
                },
                "</A> is nested more than 4 deep",
            ),
            (
                Problem::TooMany {
                    what: "fields",
                    count: None,
                },
                "too many fields",
            ),
            (
                Problem::OffsetOutOfFile {
                    what: "value",
                    offset: Some(-8),
                },
                "value offset -8 out of the file",
            ),
            (
                CrateProblem::Version((0, 3, 0)).into(),
                "crate version 0.3.0 is not supported (rigport reads 0.4.0 and later; re-save \
                 the file with a current USD)",
            ),
            (
                PackageProblem::Over4Gib(None).into(),
                "the package is over 4 GiB (zip64 is not written)",
            ),
        ];
        for (problem, text) in cases {
            assert_eq!(problem.to_string(), text);
        }
    }
}
