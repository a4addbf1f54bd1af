//! The `MOTION` section: the `Frames:` and `Frame Time:` header, then the frame lines (read
//! on two threads when large).

use std::path::Path;

use rigport_model::Warning;

use crate::problem::Rule;
use crate::text::{self, column, Lines, Number};
use crate::{number, ImportError, Location, Problem};

use super::parser::Parser;

/// The motion section as read.
pub(super) struct Motion {
    pub(super) frames_declared: usize,
    pub(super) frame_count: usize,
    pub(super) frame_time: f64,
    pub(super) values: Vec<f32>,
}

impl<'a> Parser<'a, '_> {
    /// Everything after the `MOTION` line: `rest` starts at the end of that line.
    pub(super) fn motion(&mut self, rest: &str, motion_line: usize) -> Result<Motion, ImportError> {
        let path = self.path;
        let mut lines = Lines::new(rest).map(|(_, line)| line);
        // What is left of the MOTION line itself (checked blank by the caller).
        lines.next();
        let mut line_no = motion_line;
        // The last line holding text, where a file that ends early is reported.
        let mut last_text_line = motion_line;
        let mut header = |label: &str, expected: &'static str| {
            for line in lines.by_ref() {
                line_no += 1;
                if !line.trim_ascii().is_empty() {
                    last_text_line = line_no;
                    return header_value(line, label)
                        .map_err(|(col, found)| {
                            ImportError::syntax(
                                Location::line_column(path, line_no, col),
                                expected,
                                found,
                            )
                        })
                        .map(|(value, col)| (value, line_no, col));
                }
            }
            Err(ImportError::new(
                Location::line(path, last_text_line),
                Problem::UnexpectedEnd { expected },
            ))
        };
        let (value, line, col) = header("frames", "`Frames: <count>`")?;
        let frames_declared: usize = text::number(value, "frame count", || {
            Location::line_column(path, line, col)
        })?;
        let (value, line, col) = header("frametime", "`Frame Time: <seconds>`")?;
        let frame_time: f64 = text::number(value, "Frame Time", || {
            Location::line_column(path, line, col)
        })?;
        if frame_time <= 0.0 {
            return Err(ImportError::at(
                Location::line_column(path, line, col),
                Rule::FrameTime(value.to_string()),
            ));
        }

        let channels = self.channel_total;
        // Large, well-formed motion is read on two threads; anything unusual (a bad or
        // cut-off line, a frame count other than declared) takes the line-by-line path
        // below, which reports it.
        let data = lines
            .clone()
            .next()
            .and_then(|first| rest.get(offset_in(rest, first)?..));
        if let Some(values) = data.and_then(|d| frames_on_two_threads(d, channels, frames_declared))
        {
            return Ok(Motion {
                frames_declared,
                frame_count: frames_declared,
                frame_time,
                values,
            });
        }
        let location = |line: usize| format!("{}:{line}", path.display());
        // Reserve for the declared frames, but never more than the rest of the file can
        // hold (each value takes at least 2 bytes), so a huge `Frames:` cannot exhaust memory.
        let capacity = frames_declared
            .saturating_mul(channels)
            .min(rest.len() / 2 + 1);
        let mut values: Vec<f32> = Vec::with_capacity(capacity);
        // Frames of no values are blank lines: with no channels there is nothing to read,
        // and any text after the header is an extra line.
        let mut frame_count = if channels == 0 { frames_declared } else { 0 };
        let mut cut_off_line = None;
        let mut last_data_line = line_no;
        while frame_count < frames_declared {
            let Some(line) = lines.next() else { break };
            line_no += 1;
            if line.trim_ascii().is_empty() {
                continue;
            }
            let start = values.len();
            match frame_values(line, channels, &mut values) {
                Ok(()) => {
                    frame_count += 1;
                    last_data_line = line_no;
                }
                Err(bad) => {
                    let last = lines.clone().all(|l| l.trim_ascii().is_empty());
                    if last && bad.cut_off(channels) {
                        values.truncate(start);
                        cut_off_line = Some(line_no);
                        break;
                    }
                    return Err(bad.error(path, line_no, line, channels));
                }
            }
        }
        if frame_count < frames_declared {
            let dropped = match cut_off_line {
                Some(l) => format!(" (the cut-off frame at line {l} is dropped)"),
                None => String::new(),
            };
            self.warnings.push(Warning::Incomplete {
                location: location(cut_off_line.unwrap_or(last_data_line)),
                message: format!(
                    "`Frames: {frames_declared}` but the file holds {frame_count} complete frames{dropped}: the clip has {frame_count}"
                ),
            });
        } else {
            let mut extra = 0_usize;
            let mut first_extra = None;
            for l in lines {
                line_no += 1;
                if !l.trim_ascii().is_empty() {
                    extra += 1;
                    first_extra.get_or_insert(line_no);
                }
            }
            if let Some(first) = first_extra {
                self.warnings.push(Warning::Repaired {
                    location: location(first),
                    message: format!(
                        "{extra} lines after the {frames_declared} frames `Frames:` declares are ignored"
                    ),
                });
            }
        }
        Ok(Motion {
            frames_declared,
            frame_count,
            frame_time,
            values,
        })
    }
}

/// Motion text of at least this many bytes is read on two threads (below it, starting a
/// thread costs about what it saves).
pub(super) const PARALLEL_MOTION_BYTES: usize = 64 * 1024;

/// The values of `data` (the frame lines after the motion header) read on two threads, when
/// `data` is large and holds exactly `frames` frame lines of `channels` finite values each
/// plus blank lines; `None` otherwise (the caller then reads it line by line and reports
/// what is wrong). Same values, bit for bit, as the line-by-line reader.
pub(super) fn frames_on_two_threads(
    data: &str,
    channels: usize,
    frames: usize,
) -> Option<Vec<f32>> {
    if channels == 0 || data.len() < PARALLEL_MOTION_BYTES {
        return None;
    }
    // Cut after the line break nearest the middle: both halves hold whole lines.
    let mid = data.len() / 2;
    let cut = mid
        + 1
        + data
            .as_bytes()
            .get(mid..)?
            .iter()
            .position(|&b| b == b'\n')?;
    let (first, second) = (data.get(..cut)?, data.get(cut..)?);
    // Every value takes at least two bytes, so a half cannot hold more than len / 2 + 1.
    let capacity = frames.saturating_mul(channels).min(data.len() / 2 + 1);
    let read = |text: &str, capacity: usize| -> Option<(Vec<f32>, usize)> {
        let mut values = Vec::with_capacity(capacity);
        let mut count = 0_usize;
        for (_, line) in Lines::new(text) {
            if !line.trim_ascii().is_empty() {
                frame_values(line, channels, &mut values).ok()?;
                count += 1;
            }
        }
        Some((values, count))
    };
    let (a, b) = crate::join(
        || read(first, capacity),
        || read(second, capacity.min(second.len() / 2 + 1)),
    );
    let ((mut values, count_a), (rest, count_b)) = (a?, b?);
    if count_a.checked_add(count_b)? != frames {
        return None;
    }
    values.extend_from_slice(&rest);
    Some(values)
}

/// Splits a `Frames: 20` / `Frame Time: 0.033` line: the label (before the first `:`, or
/// every token but the last when there is no colon) must equal `label` ignoring ASCII case
/// and white space, and the value must be one token. Returns the value and its 1-based
/// column, or the column and text to blame.
fn header_value<'l>(line: &'l str, label: &str) -> Result<(&'l str, usize), (usize, &'l str)> {
    let trimmed = line.trim_ascii();
    let (key, value) = match trimmed.split_once(':') {
        Some((key, value)) => (key, value.trim_ascii()),
        None => match trimmed.rsplit_once(|c: char| c.is_ascii_whitespace()) {
            Some((key, value)) => (key, value),
            None => (trimmed, ""),
        },
    };
    let mut key_chars = key.chars().filter(|c| !c.is_ascii_whitespace());
    let label_matches = label
        .chars()
        .all(|l| key_chars.next().is_some_and(|k| k.eq_ignore_ascii_case(&l)))
        && key_chars.next().is_none();
    let col = |s: &str| column(line, s);
    if !label_matches || value.is_empty() || value.contains(|c: char| c.is_ascii_whitespace()) {
        return Err((col(trimmed), trimmed));
    }
    Ok((value, col(value)))
}

/// Byte offset of `sub` (a subslice of `outer`) within `outer`.
fn offset_in(outer: &str, sub: &str) -> Option<usize> {
    (sub.as_ptr() as usize).checked_sub(outer.as_ptr() as usize)
}

/// What is wrong with a frame line.
pub(super) struct BadFrame<'l> {
    /// How many values the line has (counting all tokens).
    tokens: usize,
    /// The token that does not parse (or is not finite) and whether it is the line's last.
    bad: Option<(&'l str, bool)>,
}

impl BadFrame<'_> {
    /// Whether the line looks like the last line of a file cut short: fewer values than a
    /// frame and nothing wrong but possibly its last value (cut mid-number).
    fn cut_off(&self, channels: usize) -> bool {
        self.tokens <= channels
            && match self.bad {
                None => self.tokens < channels,
                Some((_, last)) => last,
            }
    }

    fn error(&self, path: &Path, line_no: usize, line: &str, channels: usize) -> ImportError {
        match self.bad {
            Some((token, _)) => {
                let location = text::at(path, line_no, line, token);
                let issue = f32::read(token)
                    .err()
                    .unwrap_or(text::NumberIssue::NotANumber);
                text::number_error(location, "motion value", token, issue)
            }
            None => ImportError::count(
                Location::line(path, line_no),
                "values",
                self.tokens,
                format_args!("{channels} (one per channel)"),
            ),
        }
    }
}

/// Appends the values of one frame line to `out`; on error `out` may hold some of them.
pub(super) fn frame_values<'l>(
    line: &'l str,
    channels: usize,
    out: &mut Vec<f32>,
) -> Result<(), BadFrame<'l>> {
    // One pass over the bytes: tokens are cut where `split_ascii_whitespace` cuts them and
    // read by `number::leading_f32`, which gives `str::parse::<f32>`'s bits.
    let mut rest = line;
    let mut n = 0_usize;
    loop {
        rest = rest.trim_ascii_start();
        if rest.is_empty() {
            break;
        }
        let (token, value) = number::leading_f32(rest);
        rest = rest.get(token.len()..).unwrap_or_default();
        n += 1;
        match value {
            Some(v) if v.is_finite() => out.push(v),
            _ => {
                let after = rest.split_ascii_whitespace().count();
                return Err(BadFrame {
                    tokens: n + after,
                    bad: Some((token, after == 0)),
                });
            }
        }
    }
    if n == channels {
        Ok(())
    } else {
        Err(BadFrame {
            tokens: n,
            bad: None,
        })
    }
}
