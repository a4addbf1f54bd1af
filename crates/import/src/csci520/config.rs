//! `skin.config` (Vega `ConfigFile`) and its integer lists (Vega `ListIO`).

use std::path::Path;

use rigport_model::Warning;

use crate::problem::Missing;
use crate::{ImportError, Location, Problem};

use super::types::{ConfigEntry, SkinConfig};

/// `IKJointIDs` lists (after expanding ranges) longer than this are rejected, so a typo
/// such as `0:4000000000` cannot exhaust memory. Real rigs have tens of joints.
pub const MAX_LIST_LEN: usize = 1 << 16;

/// Parses a `skin.config`.
///
/// Lines are trimmed first (CRLF, indentation); blank lines and lines starting with `#`
/// are skipped everywhere, also between an option and its value. An option's value is the
/// whole trimmed line. Returns the options and a [`Warning::Note`] per unknown option.
///
/// # Errors
/// At the offending line: a line that is neither an option, a comment nor a value
/// following an option; `*` without a name, or with something after the name (the value
/// goes on the next line); an option given twice; an option without a value (followed by
/// another option or the end of the file, at the option's line); an `IKJointIDs` value
/// that is not a `ListIO` list of non-negative integers (see [`parse_joint_list`]).
pub fn parse_config(text: &str, path: &Path) -> Result<(SkinConfig, Vec<Warning>), ImportError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut cfg = SkinConfig::default();
    let mut warnings = Vec::new();
    // The option waiting for its value: name as written, line.
    let mut pending: Option<(&str, usize)> = None;
    // Lower-case names seen, with their lines.
    let mut seen: Vec<(String, usize)> = Vec::new();
    for (line_no, raw) in crate::text::Lines::new(text) {
        let line = raw.trim_ascii();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let at = || Location::line(path, line_no);
        if let Some(name) = line.strip_prefix('*') {
            if let Some((previous, previous_line)) = pending {
                return Err(ImportError::at(
                    Location::line(path, previous_line),
                    Missing::OptionValue {
                        option: previous.to_string(),
                        next_line: line_no,
                    },
                ));
            }
            let name = name.trim_ascii();
            if name.is_empty() {
                return Err(ImportError::syntax(at(), "an option name after `*`", line));
            }
            if name.bytes().any(|b| b.is_ascii_whitespace()) {
                return Err(ImportError::syntax(
                    at(),
                    "an option name alone on its line (the value goes on the next line)",
                    line,
                ));
            }
            let lower = name.to_ascii_lowercase();
            if let Some((_, first)) = seen.iter().find(|(n, _)| *n == lower) {
                return Err(ImportError::new(
                    at(),
                    Problem::Duplicate {
                        what: format!("*{name}"),
                        first_line: *first,
                    },
                ));
            }
            seen.push((lower, line_no));
            pending = Some((name, line_no));
            continue;
        }
        let Some((name, option_line)) = pending.take() else {
            return Err(ImportError::syntax(
                at(),
                "an `*option` line, a `#` comment or a blank line",
                line,
            ));
        };
        let entry = ConfigEntry {
            value: line.to_string(),
            line: line_no,
        };
        match name.to_ascii_lowercase().as_str() {
            "meshfilename" => cfg.mesh_filename = Some(entry),
            "jointhierarchyfilename" => cfg.joint_hierarchy_filename = Some(entry),
            "jointresttransformsfilename" => cfg.joint_rest_transforms_filename = Some(entry),
            "jointweightsfilename" => cfg.joint_weights_filename = Some(entry),
            "ikjointids" => {
                let ids = parse_joint_list(line).map_err(|message| {
                    ImportError::invalid(at(), format!("*IKJointIDs: {message}"))
                })?;
                cfg.ik_joint_ids = Some(ConfigEntry {
                    value: ids,
                    line: line_no,
                });
            }
            // Cosmetic options of the course's driver: kept, nothing to say.
            "alllightsintensity" | "screenshotbasename" => {
                cfg.other.push((name.to_string(), entry));
            }
            _ => {
                warnings.push(Warning::Note {
                    location: format!("{}:{option_line}", path.display()),
                    message: format!("unknown option *{name} ignored"),
                });
                cfg.other.push((name.to_string(), entry));
            }
        }
    }
    if let Some((name, line)) = pending {
        return Err(ImportError::at(
            Location::line(path, line),
            Missing::OptionValueAtEnd(name.to_string()),
        ));
    }
    Ok((cfg, warnings))
}

/// Parses an integer list in Vega `ListIO` syntax: non-negative integers separated by
/// commas and/or white space, `a:b` (blanks allowed around `:`) meaning `a, a+1, ..., b`.
/// Empty entries (`1,,2`, a trailing comma as `ListIO` writes) are allowed; an empty text
/// gives an empty list.
///
/// # Errors
/// A message (without location) for: a character other than digits, `,`, `:` and white
/// space; a negative or too large number; a `:` without a number on either side; a range
/// that runs backwards (`5:3`); more than [`MAX_LIST_LEN`] values.
pub fn parse_joint_list(text: &str) -> Result<Vec<usize>, String> {
    #[derive(Clone, Copy)]
    enum Token {
        Number(usize),
        Comma,
        Colon,
    }
    let mut tokens = Vec::new();
    let bytes = text.as_bytes();
    let mut i = 0;
    while let Some(&b) = bytes.get(i) {
        match b {
            b',' => tokens.push(Token::Comma),
            b':' => tokens.push(Token::Colon),
            b if b.is_ascii_whitespace() => {}
            b'0'..=b'9' | b'-' | b'+' => {
                let start = i;
                i += 1;
                while bytes.get(i).is_some_and(u8::is_ascii_digit) {
                    i += 1;
                }
                let token = text.get(start..i).unwrap_or_default();
                let value: i64 = token
                    .parse()
                    .map_err(|_| format!("{token:?} is not a joint index"))?;
                let value = usize::try_from(value).map_err(|_| {
                    format!("joint index {value} is negative (indices are 0-based)")
                })?;
                tokens.push(Token::Number(value));
                continue;
            }
            _ => {
                let rest: String = text.get(i..).unwrap_or_default().chars().take(20).collect();
                return Err(format!(
                    "expected a joint index, `,` or `:`, found {rest:?}"
                ));
            }
        }
        i += 1;
    }
    let mut out: Vec<usize> = Vec::new();
    let mut tokens = tokens.into_iter().peekable();
    while let Some(token) = tokens.next() {
        match token {
            Token::Comma => {}
            Token::Colon => return Err("a `:` range needs a number before it".into()),
            Token::Number(a) => {
                let b = if matches!(tokens.peek(), Some(Token::Colon)) {
                    tokens.next();
                    match tokens.next() {
                        Some(Token::Number(b)) if b >= a => b,
                        Some(Token::Number(b)) => {
                            return Err(format!("the range {a}:{b} runs backwards"))
                        }
                        _ => return Err(format!("the range {a}: needs a number after `:`")),
                    }
                } else {
                    a
                };
                if b - a >= MAX_LIST_LEN.saturating_sub(out.len()) {
                    return Err(format!("more than {MAX_LIST_LEN} joint indices"));
                }
                out.extend(a..=b);
            }
        }
    }
    Ok(out)
}
