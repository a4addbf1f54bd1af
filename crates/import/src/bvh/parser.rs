//! The parser's state and the token helpers both sections use (`expect`, numbers, errors
//! at a token).

use std::path::Path;

use rigport_model::Warning;

use crate::{number, ImportError, Location, Problem};

use super::tokens::{column, Cursor, Token};
use super::types::{BvhEndSite, BvhJoint};

/// The parser: a cursor over the text and what has been read so far.
pub(super) struct Parser<'a, 'p> {
    pub(super) path: &'p Path,
    pub(super) cur: Cursor<'a>,
    /// Line of the last token read (where an unexpected end of file is reported).
    pub(super) last_line: usize,
    pub(super) joints: Vec<BvhJoint>,
    pub(super) end_sites: Vec<BvhEndSite>,
    pub(super) channel_total: usize,
    pub(super) warnings: Vec<Warning>,
}

impl<'a> Parser<'a, '_> {
    pub(super) fn next(&mut self) -> Option<Token<'a>> {
        let t = self.cur.next();
        if let Some(t) = t {
            self.last_line = t.line;
        }
        t
    }

    pub(super) fn next_on_line(&mut self) -> Option<Token<'a>> {
        let t = self.cur.next_on_line();
        if let Some(t) = t {
            self.last_line = t.line;
        }
        t
    }

    /// The next token, or a [`Problem::Truncated`] error naming what was expected.
    pub(super) fn expect(&mut self, expected: &str) -> Result<Token<'a>, ImportError> {
        self.next().ok_or_else(|| {
            ImportError::new(
                Location::line(self.path, self.last_line),
                Problem::Truncated(format!("the file ends where {expected} was expected")),
            )
        })
    }

    /// The next token on the current line, or an error at `after` (the token the line's
    /// values belong to) naming what is missing.
    pub(super) fn expect_on_line(
        &mut self,
        after: Token<'_>,
        expected: &str,
    ) -> Result<Token<'a>, ImportError> {
        self.next_on_line().ok_or_else(|| {
            ImportError::invalid(
                self.at(after),
                format!("{} needs {expected} on its line", after.text),
            )
        })
    }

    pub(super) fn at(&self, t: Token<'_>) -> Location {
        Location::line_column(
            self.path,
            t.line,
            column(self.cur.text, t.line_start, t.start),
        )
    }

    pub(super) fn syntax(&self, t: Token<'_>, expected: &str) -> ImportError {
        ImportError::syntax(self.at(t), expected, t.text)
    }

    /// A finite `f32`.
    pub(super) fn number(&self, t: Token<'_>) -> Result<f32, ImportError> {
        let v = number::parse_f32(t.text).ok_or_else(|| self.syntax(t, "a number"))?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(ImportError::invalid(
                self.at(t),
                format!("{} is not a finite number", t.text),
            ))
        }
    }
}
