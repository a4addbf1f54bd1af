//! The text toolkit every line- or token-based importer shares (OBJ, MTL, Pinocchio,
//! CSCI 520, ASF/AMC, BVH): lines with their 1-based numbers, character columns, a token
//! cursor across lines, and typed number parsing with one wording for every bad number.
//!
//! Line ends: LF, CRLF and a lone CR (classic Mac OS) each end one line, everywhere. A text
//! that ends with a line end has no empty line after it. Columns count characters (not
//! bytes) from 1. White space between tokens is ASCII white space plus the vertical tab
//! (what Python's `str.split()` cuts at, as the BVH exporters that write it assume).
//!
//! Numbers: `f32` is read by [`crate::number`] (bit for bit as `str::parse::<f32>`), `f64`
//! and the integers by `str::parse`; [`number`] returns the value or a [`NumberIssue`]
//! (not a number, out of the type's range, not finite), which [`Problem::Number`] words
//! once for every importer.

use std::path::Path;

pub use crate::error::NumberIssue;
use crate::{ImportError, Location, Problem};

/// The lines of a text and their 1-based numbers, without their line ends (LF, CRLF or a
/// lone CR).
///
/// Fast where it matters: a line is found with one `memchr` for `\n` (as `str::split`), and
/// a second scan for a lone `\r` runs only over texts that hold a `\r` at all.
#[derive(Clone, Debug)]
pub(crate) struct Lines<'a> {
    rest: Option<&'a str>,
    number: usize,
    /// Whether the text holds any `\r`.
    cr: bool,
}

impl<'a> Lines<'a> {
    /// The lines of `text`.
    pub(crate) fn new(text: &'a str) -> Self {
        Self {
            rest: Some(text),
            number: 0,
            cr: text.as_bytes().contains(&b'\r'),
        }
    }
}

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, &'a str);

    #[inline]
    fn next(&mut self) -> Option<Self::Item> {
        let rest = self.rest?;
        if rest.is_empty() && self.number > 0 {
            // The text ends with a line end: there is no line after it.
            self.rest = None;
            return None;
        }
        let (line, tail) = match rest.find('\n') {
            Some(i) => (rest.get(..i).unwrap_or(rest), rest.get(i + 1..)),
            None => (rest, None),
        };
        let (line, tail) = if self.cr {
            let crlf = line.strip_suffix('\r').unwrap_or(line);
            match crlf.find('\r') {
                // A lone CR ends the line; what follows it is the next line.
                Some(j) => (crlf.get(..j).unwrap_or(crlf), rest.get(j + 1..)),
                None => (crlf, tail),
            }
        } else {
            (line, tail)
        };
        self.rest = tail;
        self.number += 1;
        Some((self.number, line))
    }
}

/// Whether `b` separates tokens: ASCII white space or the vertical tab.
#[inline]
pub(crate) fn is_space(b: u8) -> bool {
    b.is_ascii_whitespace() || b == 0x0b
}

/// The 1-based character column of `token` in `line`, where `token` is a sub-slice of
/// `line` (anything else gives column 1).
pub(crate) fn column(line: &str, token: &str) -> usize {
    let offset = (token.as_ptr() as usize).wrapping_sub(line.as_ptr() as usize);
    if offset.saturating_add(token.len()) > line.len() {
        return 1;
    }
    line.get(..offset)
        .map_or(1, |before| before.chars().count() + 1)
}

/// `path:line:column` of `token` (a sub-slice of `line`).
pub(crate) fn at(path: &Path, number: usize, line: &str, token: &str) -> Location {
    Location::line_column(path, number, column(line, token))
}

/// A white-space separated token and where it starts.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Token<'a> {
    /// The token's text (never empty).
    pub(crate) text: &'a str,
    /// 1-based line.
    pub(crate) line: usize,
    /// Byte offsets of the token's line and of the token in the cursor's text.
    pub(crate) line_start: usize,
    pub(crate) start: usize,
}

/// A position in a text that reads white-space separated tokens and counts lines.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Cursor<'a> {
    /// The whole text.
    pub(crate) text: &'a str,
    /// Byte offset of the next unread byte.
    pub(crate) pos: usize,
    /// 1-based line of `pos`.
    pub(crate) line: usize,
    /// Byte offset where that line starts.
    pub(crate) line_start: usize,
}

impl<'a> Cursor<'a> {
    /// A cursor at the start of `text` (line 1).
    pub(crate) fn new(text: &'a str) -> Self {
        Self {
            text,
            pos: 0,
            line: 1,
            line_start: 0,
        }
    }

    /// Skips white space; crosses line ends only when `cross_lines`.
    pub(crate) fn skip_space(&mut self, cross_lines: bool) {
        let bytes = self.text.as_bytes();
        while let Some(&b) = bytes.get(self.pos) {
            match b {
                b'\n' | b'\r' if cross_lines => {
                    self.pos += 1;
                    if b == b'\r' && bytes.get(self.pos) == Some(&b'\n') {
                        self.pos += 1;
                    }
                    self.line += 1;
                    self.line_start = self.pos;
                }
                b'\n' | b'\r' => break,
                _ if is_space(b) => self.pos += 1,
                _ => break,
            }
        }
    }

    fn token(&mut self, cross_lines: bool) -> Option<Token<'a>> {
        self.skip_space(cross_lines);
        let bytes = self.text.as_bytes();
        let start = self.pos;
        while bytes.get(self.pos).is_some_and(|&b| !is_space(b)) {
            self.pos += 1;
        }
        // Token bounds are ASCII bytes or the ends, hence char boundaries.
        let text = self.text.get(start..self.pos).filter(|t| !t.is_empty())?;
        Some(Token {
            text,
            line: self.line,
            line_start: self.line_start,
            start,
        })
    }

    /// The next token, on this line or a later one.
    pub(crate) fn next_token(&mut self) -> Option<Token<'a>> {
        self.token(true)
    }

    /// The next token if it is on the current line.
    pub(crate) fn next_on_line(&mut self) -> Option<Token<'a>> {
        self.token(false)
    }

    /// The 1-based character column of byte offset `at` on the line starting at
    /// `line_start`.
    pub(crate) fn column_of(&self, line_start: usize, at: usize) -> usize {
        self.text
            .get(line_start..at)
            .map_or(1, |s| s.chars().count() + 1)
    }

    /// `path:line:column` of `token`.
    pub(crate) fn location(&self, path: &Path, token: Token<'_>) -> Location {
        Location::line_column(
            path,
            token.line,
            self.column_of(token.line_start, token.start),
        )
    }
}

/// A number type the text importers read.
pub(crate) trait Number: Sized + Copy {
    /// The type's name in messages.
    const NAME: &'static str;
    /// The value of `token`, or why it has none. Floats must be finite.
    fn read(token: &str) -> Result<Self, NumberIssue>;
}

/// A float's issue: a finite value, an overflow (`1e39`), or a `nan`/`inf` literal.
fn float_issue(token: &str, finite: bool, name: &'static str) -> NumberIssue {
    let digits = token
        .trim_start_matches(['+', '-'])
        .starts_with(|c: char| c.is_ascii_digit() || c == '.');
    match (finite, digits) {
        (false, true) => NumberIssue::OutOfRange(name),
        _ => NumberIssue::NotFinite,
    }
}

impl Number for f32 {
    const NAME: &'static str = "f32";
    #[inline]
    fn read(token: &str) -> Result<Self, NumberIssue> {
        match crate::number::parse_f32(token) {
            Some(v) if v.is_finite() => Ok(v),
            Some(_) => Err(float_issue(token, false, Self::NAME)),
            None => Err(NumberIssue::NotANumber),
        }
    }
}

impl Number for f64 {
    const NAME: &'static str = "f64";
    #[inline]
    fn read(token: &str) -> Result<Self, NumberIssue> {
        match token.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            Ok(_) => Err(float_issue(token, false, Self::NAME)),
            Err(_) => Err(NumberIssue::NotANumber),
        }
    }
}

macro_rules! integer {
    ($($t:ty),*) => {$(
        impl Number for $t {
            const NAME: &'static str = stringify!($t);
            #[inline]
            fn read(token: &str) -> Result<Self, NumberIssue> {
                use std::num::IntErrorKind;
                token.parse::<$t>().map_err(|e| match e.kind() {
                    IntErrorKind::PosOverflow | IntErrorKind::NegOverflow => {
                        NumberIssue::OutOfRange(Self::NAME)
                    }
                    // A negative whole number for an unsigned type.
                    _ if token.strip_prefix('-').is_some_and(|d| {
                        !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit())
                    }) => NumberIssue::OutOfRange(Self::NAME),
                    _ => NumberIssue::NotANumber,
                })
            }
        }
    )*};
}
integer!(i64, u64, usize, u32);

/// Reads `token` as a `T`; on failure, the one error every importer gives for a bad
/// number: `file:line:column: <what> "<token>" is not a number` (or `is out of range for
/// f32`, `is not finite`).
///
/// # Errors
/// [`Problem::Number`] at `location()`.
#[inline]
pub(crate) fn number<T: Number>(
    token: &str,
    what: &'static str,
    location: impl FnOnce() -> Location,
) -> Result<T, ImportError> {
    T::read(token).map_err(|issue| number_error(location(), what, token, issue))
}

/// The [`Problem::Number`] error for `token`.
#[cold]
pub(crate) fn number_error(
    location: Location,
    what: &'static str,
    token: &str,
    issue: NumberIssue,
) -> ImportError {
    ImportError::new(
        location,
        Problem::Number {
            what,
            found: crate::error::shortened(token),
            issue,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lines(text: &str) -> Vec<(usize, &str)> {
        Lines::new(text).collect()
    }

    #[test]
    fn lines_end_at_lf_crlf_and_lone_cr() {
        assert_eq!(
            lines("a\nb\r\nc\rd"),
            [(1, "a"), (2, "b"), (3, "c"), (4, "d")]
        );
        assert_eq!(lines("a\n"), [(1, "a")]);
        assert_eq!(lines("a\r\n"), [(1, "a")]);
        assert_eq!(lines("a\r"), [(1, "a")]);
        assert_eq!(lines(""), [(1, "")]);
        assert_eq!(lines("\n\n"), [(1, ""), (2, "")]);
        assert_eq!(lines("\r\r\n\r"), [(1, ""), (2, ""), (3, "")]);
        assert_eq!(lines("x\r\ry"), [(1, "x"), (2, ""), (3, "y")]);
    }

    #[test]
    fn cursor_counts_every_line_end_once() {
        let mut c = Cursor::new("a b\r\nc\rd\n é e");
        let mut seen = Vec::new();
        while let Some(t) = c.next_token() {
            seen.push((t.text, t.line, c.column_of(t.line_start, t.start)));
        }
        assert_eq!(
            seen,
            [
                ("a", 1, 1),
                ("b", 1, 3),
                ("c", 2, 1),
                ("d", 3, 1),
                ("é", 4, 2),
                ("e", 4, 4)
            ]
        );
        let mut c = Cursor::new("a\x0bb\nc");
        assert_eq!(c.next_on_line().map(|t| t.text), Some("a"));
        assert_eq!(c.next_on_line().map(|t| t.text), Some("b"));
        assert!(c.next_on_line().is_none());
        assert_eq!(c.next_token().map(|t| (t.text, t.line)), Some(("c", 2)));
    }

    #[test]
    fn columns_count_characters() {
        let line = "é  x";
        assert_eq!(column(line, &line[4..]), 4);
        assert_eq!(
            column(line, "a token from elsewhere, longer than the line"),
            1
        );
    }

    #[test]
    fn numbers_have_one_wording() {
        let path = Path::new("f.txt");
        let err = |token: &str| {
            number::<f32>(token, "weight", || Location::line_column(path, 3, 7))
                .map(|_| ())
                .unwrap_err()
                .to_string()
        };
        assert_eq!(err("x"), "f.txt:3:7: weight \"x\" is not a number");
        assert_eq!(err("nan"), "f.txt:3:7: weight \"nan\" is not finite");
        assert_eq!(err("-inf"), "f.txt:3:7: weight \"-inf\" is not finite");
        assert_eq!(
            err("1e39"),
            "f.txt:3:7: weight \"1e39\" is out of range for f32"
        );
        assert_eq!(
            i64::read("99999999999999999999"),
            Err(NumberIssue::OutOfRange("i64"))
        );
        assert_eq!(u64::read("-1"), Err(NumberIssue::OutOfRange("u64")));
        assert_eq!(u64::read("-x"), Err(NumberIssue::NotANumber));
        assert_eq!(f64::read("1e309"), Err(NumberIssue::OutOfRange("f64")));
        assert_eq!(f64::read("0.25"), Ok(0.25));
        assert_eq!(f32::read("-0.0881862"), Ok(-0.0881862));
    }
}
