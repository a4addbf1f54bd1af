//! Tokens of the hierarchy: white-space separated words with their line and column.

/// A white-space separated token of the hierarchy and where it starts.
#[derive(Clone, Copy, Debug)]
pub(super) struct Token<'a> {
    pub(super) text: &'a str,
    /// 1-based line.
    pub(super) line: usize,
    /// Byte offsets of the line's start and the token's start in the text.
    pub(super) line_start: usize,
    pub(super) start: usize,
}

/// A position in the text that reads tokens, counting lines (`\n`; a `\r` is white space).
#[derive(Clone, Copy, Debug)]
pub(super) struct Cursor<'a> {
    pub(super) text: &'a str,
    pub(super) pos: usize,
    pub(super) line: usize,
    pub(super) line_start: usize,
}

impl<'a> Cursor<'a> {
    fn token(&mut self, cross_lines: bool) -> Option<Token<'a>> {
        let bytes = self.text.as_bytes();
        while let Some(&b) = bytes.get(self.pos) {
            match b {
                b'\n' if cross_lines => {
                    self.pos += 1;
                    self.line += 1;
                    self.line_start = self.pos;
                }
                b'\n' => break,
                _ if b.is_ascii_whitespace() || b == 0x0b => self.pos += 1,
                _ => break,
            }
        }
        let start = self.pos;
        while bytes
            .get(self.pos)
            .is_some_and(|b| !b.is_ascii_whitespace() && *b != 0x0b)
        {
            self.pos += 1;
        }
        // Token bounds are ASCII bytes, hence char boundaries.
        let text = self.text.get(start..self.pos).filter(|t| !t.is_empty())?;
        Some(Token {
            text,
            line: self.line,
            line_start: self.line_start,
            start,
        })
    }

    /// The next token, on this line or a later one.
    pub(super) fn next(&mut self) -> Option<Token<'a>> {
        self.token(true)
    }

    /// The next token if it is on the current line.
    pub(super) fn next_on_line(&mut self) -> Option<Token<'a>> {
        self.token(false)
    }
}

/// Whether `t` is the keyword `word` (ASCII case-insensitive).
pub(super) fn keyword(t: Token<'_>, word: &str) -> bool {
    t.text.eq_ignore_ascii_case(word)
}

/// 1-based column (in characters) of byte offset `at` on a line starting at `line_start`.
pub(super) fn column(text: &str, line_start: usize, at: usize) -> usize {
    text.get(line_start..at)
        .map_or(1, |s| s.chars().count() + 1)
}
