//! The tokens of the USD text format (`.usda`), read on demand with one token of
//! look-ahead.
//!
//! Follows the lexical rules of OpenUSD's `Sdf` text file format (the grammar in
//! `pxr/usd/sdf/textFileFormat.yy` / `textParserGrammar.h`): `#`, `//` and `/* */`
//! comments; identifiers with `:`-separated namespaces (`primvars:skel:jointIndices`);
//! numbers with optional sign, fraction and exponent (`-1.5e-05`, `.01`) plus `inf`, `-inf`
//! and `nan`; single-, double- and triple-quoted strings with C escapes; asset paths
//! `@...@` and `@@@...@@@`; prim and property paths `<...>`; and the punctuation
//! `( ) [ ] { } = , ; : .`. New lines are insignificant (the parser accepts a statement
//! separator wherever `Sdf` requires a new line or `;`). A line ends at LF, CRLF or a lone
//! CR (classic Mac OS files), for comments, strings and the line numbers of messages alike.

use std::path::Path;

use crate::error::{Location, UsdError};

/// What a token is.
#[derive(Clone, Debug, PartialEq)]
pub enum Tok<'a> {
    /// An identifier or keyword, namespaces included (`primvars:skel:jointIndices`).
    Ident(&'a str),
    /// A number (integers too; `inf`, `-inf` and `nan` included).
    Number(f64),
    /// A quoted string, escapes resolved.
    Str(String),
    /// An asset path `@...@`, without the delimiters.
    Asset(String),
    /// A path `<...>`, without the delimiters.
    Path(&'a str),
    /// One punctuation character.
    Punct(char),
    /// The end of the text.
    Eof,
}

/// A token and where it is in the text.
#[derive(Clone, Debug)]
pub struct Token<'a> {
    /// What.
    pub tok: Tok<'a>,
    /// Byte offset of its first character.
    pub start: usize,
    /// Byte offset just after it.
    pub end: usize,
    /// 1-based line of its first character.
    pub line: usize,
}

/// Reads tokens from a `.usda` text.
pub struct Lexer<'a> {
    text: &'a str,
    bytes: &'a [u8],
    pos: usize,
    line: usize,
    peeked: Option<Token<'a>>,
    path: &'a Path,
}

/// The line ends in `bytes`: LF, CRLF (once) and lone CR.
fn line_ends(bytes: &[u8]) -> usize {
    bytes
        .iter()
        .enumerate()
        .filter(|&(i, &b)| b == b'\n' || (b == b'\r' && bytes.get(i + 1) != Some(&b'\n')))
        .count()
}

fn is_ident_start(b: u8) -> bool {
    b.is_ascii_alphabetic() || b == b'_'
}

fn is_ident_char(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_'
}

impl<'a> Lexer<'a> {
    /// A lexer at the start of `text` (a byte-order mark is skipped); `path` names the file
    /// in errors.
    pub fn new(text: &'a str, path: &'a Path) -> Self {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        Self {
            text,
            bytes: text.as_bytes(),
            pos: 0,
            line: 1,
            peeked: None,
            path,
        }
    }

    /// The text being read (without a byte-order mark).
    pub fn text(&self) -> &'a str {
        self.text
    }

    /// The file name used in errors.
    pub fn path(&self) -> &'a Path {
        self.path
    }

    /// The location of byte offset `at`: its line and 1-based column in characters.
    pub fn location(&self, at: usize) -> Location {
        let at = at.min(self.text.len());
        let before = self.text.get(..at).unwrap_or_default();
        let line = 1 + line_ends(before.as_bytes());
        let line_start = before.rfind(['\n', '\r']).map_or(0, |i| i + 1);
        let column = 1 + before.get(line_start..).unwrap_or_default().chars().count();
        Location::line_column(self.path, line, column)
    }

    /// The source text of a token, shortened for messages (`end of file` at the end).
    pub fn describe(&self, token: &Token<'_>) -> String {
        if token.tok == Tok::Eof {
            return "end of file".into();
        }
        let text = self.text.get(token.start..token.end).unwrap_or_default();
        // Long tokens (a triple-quoted doc string) are cut at their first line.
        text.split(['\n', '\r'])
            .next()
            .unwrap_or_default()
            .to_string()
    }

    /// A syntax error at `token`.
    pub fn expected(&self, token: &Token<'_>, expected: &str) -> UsdError {
        UsdError::syntax(self.location(token.start), expected, &self.describe(token))
    }

    /// The next token, without consuming it.
    ///
    /// # Errors
    /// A malformed token (unterminated string, stray character, bad number).
    pub fn peek(&mut self) -> Result<&Token<'a>, UsdError> {
        if self.peeked.is_none() {
            let t = self.lex()?;
            self.peeked = Some(t);
        }
        // Just filled above.
        self.peeked
            .as_ref()
            .ok_or_else(|| UsdError::invalid(Location::file(self.path), "lexer state"))
    }

    /// The next token, consumed.
    ///
    /// # Errors
    /// As [`Lexer::peek`].
    pub fn next_token(&mut self) -> Result<Token<'a>, UsdError> {
        match self.peeked.take() {
            Some(t) => Ok(t),
            None => self.lex(),
        }
    }

    /// 1 if byte `i` ends a line (LF, or a CR not followed by LF), else 0.
    fn line_end_at(&self, i: usize) -> usize {
        match self.bytes.get(i) {
            Some(b'\n') => 1,
            Some(b'\r') => usize::from(self.bytes.get(i + 1) != Some(&b'\n')),
            _ => 0,
        }
    }

    fn error_at(&self, at: usize, expected: &str, found: &str) -> UsdError {
        UsdError::syntax(self.location(at), expected, found)
    }

    fn skip_space_and_comments(&mut self) -> Result<(), UsdError> {
        loop {
            let Some(&b) = self.bytes.get(self.pos) else {
                return Ok(());
            };
            match b {
                b'\n' | b'\r' => {
                    self.line += self.line_end_at(self.pos);
                    self.pos += 1;
                }
                b' ' | b'\t' | 0x0c => self.pos += 1,
                b'#' => self.skip_line(),
                b'/' if self.bytes.get(self.pos + 1) == Some(&b'/') => self.skip_line(),
                b'/' if self.bytes.get(self.pos + 1) == Some(&b'*') => {
                    let start = self.pos;
                    let Some(len) = self.text.get(self.pos + 2..).and_then(|t| t.find("*/")) else {
                        return Err(self.error_at(start, "the end of a /* comment */", "/*"));
                    };
                    let end = self.pos + 2 + len + 2;
                    self.line += line_ends(&self.bytes[self.pos..end]);
                    self.pos = end;
                }
                _ => return Ok(()),
            }
        }
    }

    fn skip_line(&mut self) {
        while let Some(&b) = self.bytes.get(self.pos) {
            if b == b'\n' || b == b'\r' {
                return;
            }
            self.pos += 1;
        }
    }

    fn lex(&mut self) -> Result<Token<'a>, UsdError> {
        self.skip_space_and_comments()?;
        let start = self.pos;
        let line = self.line;
        let token = |tok, end| Token {
            tok,
            start,
            end,
            line,
        };
        let Some(&b) = self.bytes.get(start) else {
            return Ok(token(Tok::Eof, start));
        };
        let tok = match b {
            b'(' | b')' | b'[' | b']' | b'{' | b'}' | b'=' | b',' | b';' | b':' => {
                self.pos += 1;
                Tok::Punct(b as char)
            }
            b'.' if !self.bytes.get(start + 1).is_some_and(u8::is_ascii_digit) => {
                self.pos += 1;
                Tok::Punct('.')
            }
            b'"' | b'\'' => Tok::Str(self.string(b)?),
            b'@' => Tok::Asset(self.asset()?),
            b'<' => {
                let Some(len) = self.text.get(start + 1..).and_then(|t| t.find(['>', '\n'])) else {
                    return Err(self.error_at(start, "a path ending in >", "<"));
                };
                let end = start + 1 + len;
                if self.bytes.get(end) != Some(&b'>') {
                    return Err(self.error_at(start, "a path ending in >", &self.text[start..end]));
                }
                self.pos = end + 1;
                Tok::Path(&self.text[start + 1..end])
            }
            b'-' | b'+' | b'0'..=b'9' | b'.' => self.number()?,
            b if is_ident_start(b) => {
                self.ident();
                Tok::Ident(&self.text[start..self.pos])
            }
            _ => {
                let c = self.text.get(start..).and_then(|t| t.chars().next());
                return Err(self.error_at(
                    start,
                    "a token",
                    &c.map(String::from).unwrap_or_default(),
                ));
            }
        };
        Ok(token(tok, self.pos))
    }

    /// An identifier with `:`-joined namespaces (`a:b:c`); `self.pos` is at its start.
    fn ident(&mut self) {
        loop {
            while self.bytes.get(self.pos).is_some_and(|&b| is_ident_char(b)) {
                self.pos += 1;
            }
            // A namespace separator only when an identifier follows right after it, so that
            // `1: value` and `key : value` stay punctuation.
            if self.bytes.get(self.pos) == Some(&b':')
                && self
                    .bytes
                    .get(self.pos + 1)
                    .is_some_and(|&b| is_ident_start(b))
            {
                self.pos += 1;
            } else {
                return;
            }
        }
    }

    fn number(&mut self) -> Result<Tok<'a>, UsdError> {
        let start = self.pos;
        let mut i = start;
        let negative = self.bytes.get(i) == Some(&b'-');
        if matches!(self.bytes.get(i), Some(b'-' | b'+')) {
            i += 1;
        }
        // `-inf`, `+inf`, `-nan` as written by Sdf for non-finite values.
        for (word, value) in [("inf", f64::INFINITY), ("nan", f64::NAN)] {
            if self.text.get(i..i + word.len()) == Some(word)
                && !self
                    .bytes
                    .get(i + word.len())
                    .is_some_and(|&b| is_ident_char(b))
            {
                self.pos = i + word.len();
                return Ok(Tok::Number(if negative { -value } else { value }));
            }
        }
        let digits = |i: &mut usize| {
            let from = *i;
            while self.bytes.get(*i).is_some_and(u8::is_ascii_digit) {
                *i += 1;
            }
            *i > from
        };
        let mut any = digits(&mut i);
        if self.bytes.get(i) == Some(&b'.') {
            i += 1;
            any |= digits(&mut i);
        }
        if !any {
            let end = (i + 1).min(self.text.len());
            return Err(self.error_at(
                start,
                "a number",
                self.text.get(start..end).unwrap_or_default(),
            ));
        }
        if matches!(self.bytes.get(i), Some(b'e' | b'E')) {
            let mut j = i + 1;
            if matches!(self.bytes.get(j), Some(b'-' | b'+')) {
                j += 1;
            }
            if digits(&mut j) {
                i = j;
            }
        }
        if self.bytes.get(i).is_some_and(|&b| is_ident_char(b)) {
            let mut end = i;
            while self.bytes.get(end).is_some_and(|&b| is_ident_char(b)) {
                end += 1;
            }
            return Err(self.error_at(start, "a number", &self.text[start..end]));
        }
        let text = &self.text[start..i];
        let value: f64 = text
            .parse()
            .map_err(|_| self.error_at(start, "a number", text))?;
        self.pos = i;
        Ok(Tok::Number(value))
    }

    /// A quoted string starting at `self.pos` with quote `q` (single or triple).
    fn string(&mut self, q: u8) -> Result<String, UsdError> {
        let start = self.pos;
        let triple = self.bytes.get(start + 1) == Some(&q) && self.bytes.get(start + 2) == Some(&q);
        let mut i = start + if triple { 3 } else { 1 };
        let mut out = String::new();
        loop {
            let Some(&b) = self.bytes.get(i) else {
                return Err(self.error_at(start, "the end of a string", "end of file"));
            };
            if b == q {
                if !triple {
                    i += 1;
                    break;
                }
                if self.bytes.get(i + 1) == Some(&q) && self.bytes.get(i + 2) == Some(&q) {
                    i += 3;
                    break;
                }
            }
            if b == b'\n' || b == b'\r' {
                if !triple {
                    return Err(self.error_at(
                        start,
                        "the end of a string on its line",
                        "a new line",
                    ));
                }
                self.line += self.line_end_at(i);
            }
            if b == b'\\' {
                let Some(&e) = self.bytes.get(i + 1) else {
                    return Err(self.error_at(start, "the end of a string", "end of file"));
                };
                i += 2;
                match e {
                    b'n' => out.push('\n'),
                    b't' => out.push('\t'),
                    b'r' => out.push('\r'),
                    b'a' => out.push('\u{7}'),
                    b'b' => out.push('\u{8}'),
                    b'f' => out.push('\u{c}'),
                    b'v' => out.push('\u{b}'),
                    b'\\' | b'"' | b'\'' => out.push(e as char),
                    b'\n' => self.line += 1,
                    b'x' => {
                        let mut value = 0u32;
                        let mut n = 0;
                        while n < 2 {
                            match self.bytes.get(i).and_then(|&h| (h as char).to_digit(16)) {
                                Some(d) => value = value * 16 + d,
                                None => break,
                            }
                            i += 1;
                            n += 1;
                        }
                        out.push(char::from_u32(value).unwrap_or('\u{fffd}'));
                    }
                    b'0'..=b'7' => {
                        let mut value = u32::from(e - b'0');
                        let mut n = 1;
                        while n < 3 {
                            match self.bytes.get(i) {
                                Some(&d @ b'0'..=b'7') => value = value * 8 + u32::from(d - b'0'),
                                _ => break,
                            }
                            i += 1;
                            n += 1;
                        }
                        out.push(char::from_u32(value).unwrap_or('\u{fffd}'));
                    }
                    // Sdf keeps an unknown escape's character.
                    _ => {
                        i -= 1;
                    }
                }
                continue;
            }
            // Copy one whole UTF-8 character.
            let ch_len = self
                .text
                .get(i..)
                .and_then(|t| t.chars().next())
                .map_or(1, char::len_utf8);
            out.push_str(self.text.get(i..i + ch_len).unwrap_or_default());
            i += ch_len;
        }
        self.pos = i;
        Ok(out)
    }

    /// `@path@` or `@@@path@@@` (which may hold `@`), starting at `self.pos`.
    fn asset(&mut self) -> Result<String, UsdError> {
        let start = self.pos;
        let rest = self.text.get(start..).unwrap_or_default();
        let (open, close) = if rest.starts_with("@@@") {
            (3, "@@@")
        } else {
            (1, "@")
        };
        let body = rest.get(open..).unwrap_or_default();
        let Some(len) = body.find(close) else {
            return Err(self.error_at(start, "an asset path ending in @", "end of file"));
        };
        let value = &body[..len];
        if value.contains(['\n', '\r']) {
            return Err(self.error_at(
                start,
                "an asset path ending in @ on its line",
                "a new line",
            ));
        }
        self.pos = start + open + len + close.len();
        Ok(value.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all(text: &str) -> Vec<Tok<'_>> {
        let mut lx = Lexer::new(text, Path::new("t.usda"));
        let mut out = Vec::new();
        loop {
            let t = lx.next_token().unwrap();
            if t.tok == Tok::Eof {
                return out;
            }
            out.push(t.tok);
        }
    }

    #[test]
    fn tokens_of_the_format() {
        let toks = all(
            "#usda 1.0\nint[] primvars:skel:jointIndices = [1, -2] # c\n\
             quatf[] r.timeSamples = { 1: [(0.5, -1.5e-05, .01, inf)], -2.5: -inf }\n\
             /* block\n comment */ rel a = </A/B> // c\n\
             asset x = @./a@ @@@a@b@@@ 'it''s' \"q\\\"\\n\\x41\\101\" \"\"\"multi\nline\"\"\" -nan nan",
        );
        assert_eq!(toks[0], Tok::Ident("int"));
        assert_eq!(toks[3], Tok::Ident("primvars:skel:jointIndices"));
        assert!(toks.contains(&Tok::Number(-2.0)));
        assert!(toks.contains(&Tok::Ident("timeSamples")));
        assert!(toks.contains(&Tok::Number(-1.5e-5)));
        assert!(toks.contains(&Tok::Number(0.01)));
        // A bare `inf` is an identifier the value parser reads as a number.
        assert!(toks.contains(&Tok::Ident("inf")));
        assert!(toks.contains(&Tok::Number(-2.5)));
        assert!(toks.contains(&Tok::Number(f64::NEG_INFINITY)));
        assert!(toks.contains(&Tok::Path("/A/B")));
        assert!(toks.contains(&Tok::Asset("./a".into())));
        assert!(toks.contains(&Tok::Asset("a@b".into())));
        assert!(toks.contains(&Tok::Str("it".into())));
        assert!(toks.contains(&Tok::Str("q\"\nAA".into())));
        assert!(toks.contains(&Tok::Str("multi\nline".into())));
        assert_eq!(toks.last(), Some(&Tok::Ident("nan")));
        assert!(
            toks.iter()
                .any(|t| matches!(t, Tok::Number(n) if n.is_nan())),
            "-nan"
        );
        // `1:` is a number then a colon, not a namespaced identifier.
        assert!(toks
            .windows(2)
            .any(|w| w == [Tok::Number(1.0), Tok::Punct(':')]));
    }

    #[test]
    fn errors_carry_line_and_column() {
        let mut lx = Lexer::new("a\n  \"open", Path::new("t.usda"));
        lx.next_token().unwrap();
        let e = lx.next_token().unwrap_err().to_string();
        assert!(
            e.starts_with("t.usda:2:3: expected the end of a string"),
            "{e}"
        );
        let mut lx = Lexer::new("x = 1e5q", Path::new("t.usda"));
        lx.next_token().unwrap();
        lx.next_token().unwrap();
        let e = lx.next_token().unwrap_err().to_string();
        assert_eq!(e, "t.usda:1:5: expected a number, found \"1e5q\"");
        let mut lx = Lexer::new("é $", Path::new("t.usda"));
        let e = lx.next_token().unwrap_err().to_string();
        assert_eq!(e, "t.usda:1:1: expected a token, found \"é\"");
    }

    #[test]
    fn lone_cr_and_crlf_end_lines() {
        let lf = "#usda 1.0\n# comment\ndef X \"a\" {\n  /* a\n b */ float y = 1\n}\n\"open";
        for text in [
            lf.to_string(),
            lf.replace('\n', "\r"),
            lf.replace('\n', "\r\n"),
        ] {
            let mut lx = Lexer::new(&text, Path::new("t.usda"));
            let mut toks = Vec::new();
            let e = loop {
                match lx.next_token() {
                    Ok(t) => toks.push((t.tok, t.line)),
                    Err(e) => break e.to_string(),
                }
            };
            assert_eq!(toks[0], (Tok::Ident("def"), 3), "{text:?}");
            assert_eq!(toks[3], (Tok::Punct('{'), 3), "{text:?}");
            assert_eq!(toks[4], (Tok::Ident("float"), 5), "{text:?}");
            assert_eq!(toks.len(), 9, "{text:?}: {toks:?}");
            assert!(
                e.starts_with("t.usda:7:1: expected the end of a string"),
                "{e}"
            );
        }
    }
}
