//! The parser's state and the token helpers both sections use (`expect`, numbers, errors
//! at a token).

use std::path::Path;

use rigport_model::Warning;

use super::types::{BvhEndSite, BvhJoint};
use crate::problem::Missing;
use crate::text::{self, Cursor, Token};
use crate::{ImportError, Location, Problem};

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
        let t = self.cur.next_token();
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

    /// The next token, or a [`Problem::UnexpectedEnd`] error naming what was expected.
    pub(super) fn expect(&mut self, expected: &'static str) -> Result<Token<'a>, ImportError> {
        self.next().ok_or_else(|| {
            ImportError::new(
                Location::line(self.path, self.last_line),
                Problem::UnexpectedEnd { expected },
            )
        })
    }

    /// The next token on the current line, or an error at `after` (the token the line's
    /// values belong to) naming what is missing.
    pub(super) fn expect_on_line(
        &mut self,
        after: Token<'_>,
        expected: &'static str,
    ) -> Result<Token<'a>, ImportError> {
        self.next_on_line().ok_or_else(|| {
            let keyword = after.text.to_string();
            ImportError::at(self.at(after), Missing::OnLine { keyword, expected })
        })
    }

    pub(super) fn at(&self, t: Token<'_>) -> Location {
        self.cur.location(self.path, t)
    }

    pub(super) fn syntax(&self, t: Token<'_>, expected: &str) -> ImportError {
        ImportError::syntax(self.at(t), expected, t.text)
    }

    /// A finite `f32`, `what` naming it in the error.
    pub(super) fn number(&self, t: Token<'_>, what: &'static str) -> Result<f32, ImportError> {
        text::number(t.text, what, || self.at(t))
    }
}

/// Whether `t` is the keyword `word` (ASCII case-insensitive).
pub(super) fn keyword(t: Token<'_>, word: &str) -> bool {
    t.text.eq_ignore_ascii_case(word)
}
