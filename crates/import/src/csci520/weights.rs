//! `jointWeights.txt`: sparse `vertex joint weight` triplets to sorted, normalized rows.

use std::path::Path;

use rigport_model::{Influence, Influences, Warning};

use crate::problem::{Limit, Mismatch};
use crate::text::{self, Lines};
use crate::{exact_fields, ImportError, Location, Problem};

/// A row of weights whose sum differs from 1 by more than this is renormalized with a
/// [`Warning::WeightsRenormalized`]. The corpus rows sum to 1 within 2e-12 (13-digit
/// decimals); hand-edited files with 4-decimal weights stay within 1e-4.
pub const ROW_SUM_TOLERANCE: f64 = 1e-4;

/// Parses `jointWeights.txt` for a mesh of `vertex_count` OBJ `v` lines and
/// `joint_count` joints.
///
/// Returns one influence row per OBJ `v` line, whose [`Influence::joint`] is the joint's
/// index **in the files** (not yet the skeleton's), sorted by descending weight (ties by
/// joint). Blank lines are skipped; CRLF, trailing spaces and a missing final newline are
/// fine. Entries with weight 0 are dropped (they have no effect). Warnings, in order:
/// a [`Warning::Note`] when duplicate `(vertex, joint)` entries were summed; one
/// [`Warning::WeightsRenormalized`] when rows whose sum differs from 1 by more than
/// [`ROW_SUM_TOLERANCE`] were rescaled to 1 (other rows are kept as written); a
/// [`Warning::Note`] counting the vertices without any entry, which are kept with no
/// influence.
///
/// # Errors
/// At the offending line: a header count that is not an integer, a row count other than
/// `vertex_count` or a column count other than `joint_count`, anything after `rows cols`
/// on the header's line; an entry line without exactly 3 fields, an index that is not an
/// integer or is out of range, a weight that does not parse or is NaN, infinite or
/// negative; a row whose sum overflows (at its first entry). A file without the two
/// header counts is [`Problem::Empty`] or [`Problem::UnexpectedEnd`].
pub fn parse_weights(
    text: &str,
    path: &Path,
    vertex_count: usize,
    joint_count: usize,
) -> Result<(Influences, Vec<Warning>), ImportError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = Lines::new(text)
        .map(|(n, l)| (n, l.trim_ascii()))
        .filter(|(_, l)| !l.is_empty());

    // Header: `rows cols` on one line or two.
    let mut header: Vec<(usize, &str)> = Vec::with_capacity(2);
    while header.len() < 2 {
        let Some((line_no, line)) = lines.next() else {
            return Err(match header.first() {
                None => ImportError::new(Location::file(path), Problem::Empty),
                Some(&(line, _)) => ImportError::new(
                    Location::line(path, line),
                    Problem::UnexpectedEnd {
                        expected: "the column count of the header `rows cols`",
                    },
                ),
            });
        };
        for token in line.split_ascii_whitespace() {
            if header.len() == 2 {
                return Err(ImportError::syntax(
                    Location::line(path, line_no),
                    "the end of the header line (`rows cols`; entries start on the next line)",
                    token,
                ));
            }
            header.push((line_no, token));
        }
    }
    let header_count =
        |index: usize, what: &'static str, expected: usize, counted: &'static str| {
            let (line, token) = header.get(index).copied().unwrap_or((0, ""));
            let at = || Location::line(path, line);
            let count = if index == 0 {
                "row count"
            } else {
                "column count"
            };
            let value: i64 = text::number(token, count, at)?;
            if usize::try_from(value).ok() != Some(expected) {
                return Err(ImportError::at(
                    at(),
                    Mismatch::Header {
                        value,
                        what,
                        counted,
                        expected,
                    },
                ));
            }
            Ok(())
        };
    header_count(0, "row", vertex_count, "the mesh has (OBJ `v` lines)")?;
    header_count(1, "column", joint_count, "the hierarchy has joints:")?;

    // Entries: (vertex, joint, weight, line).
    let mut entries: Vec<(u32, u32, f64, usize)> =
        Vec::with_capacity(vertex_count.saturating_mul(4));
    for (line_no, line) in lines {
        let at = || Location::line(path, line_no);
        let Some([vertex, joint, weight]) = exact_fields::<3>(line) else {
            return Err(ImportError::syntax(
                at(),
                "an entry `vertex joint weight`",
                line,
            ));
        };
        let at_token = |token: &str| text::at(path, line_no, line, token);
        let index = |token: &str,
                     (what, plural): (&'static str, &'static str),
                     count: usize|
         -> Result<u32, ImportError> {
            let value: i64 = text::number(token, what, || at_token(token))?;
            match usize::try_from(value) {
                Ok(v) if v < count => Ok(v as u32),
                _ => Err(ImportError::new(
                    at_token(token),
                    Problem::IndexOutOfRange {
                        what,
                        plural,
                        index: value,
                        count,
                    },
                )),
            }
        };
        let vertex = index(vertex, ("vertex", "vertices"), vertex_count)?;
        let joint = index(joint, ("joint", "joints"), joint_count)?;
        let value: f64 = text::number(weight, "weight", || at_token(weight))?;
        if value < 0.0 {
            return Err(ImportError::new(
                at_token(weight),
                Problem::Negative {
                    what: "weight",
                    found: crate::error::shortened(weight),
                },
            ));
        }
        if value > 0.0 {
            entries.push((vertex, joint, value, line_no));
        }
    }

    // Sum duplicates: sort by (vertex, joint), stable so the first line stays first.
    entries.sort_by_key(|&(v, j, _, _)| (v, j));
    let mut merged: Vec<(u32, u32, f64, usize)> = Vec::with_capacity(entries.len());
    let mut duplicates = 0_usize;
    let mut first_duplicate_line = usize::MAX;
    for entry in entries {
        match merged.last_mut() {
            Some(last) if last.0 == entry.0 && last.1 == entry.1 => {
                last.2 += entry.2;
                duplicates += 1;
                first_duplicate_line = first_duplicate_line.min(entry.3);
            }
            _ => merged.push(entry),
        }
    }

    // Rows, in vertex order.
    let mut influences: Vec<Influence> = Vec::with_capacity(merged.len());
    let mut ends: Vec<usize> = Vec::with_capacity(vertex_count);
    let mut rescaled = 0_usize;
    let mut max_error = 0.0_f64;
    let mut empty = 0_usize;
    let mut first_empty = None;
    let mut pos = 0;
    for v in 0..vertex_count {
        let start = influences.len();
        let begin = pos;
        // `merged` is sorted by vertex and every vertex is below vertex_count.
        while merged.get(pos).is_some_and(|e| e.0 as usize == v) {
            pos += 1;
        }
        let row = merged.get(begin..pos).unwrap_or_default();
        let sum: f64 = row.iter().map(|e| e.2).sum();
        let first_line = row.first().map_or(0, |e| e.3);
        if row.is_empty() {
            empty += 1;
            first_empty.get_or_insert(v);
            ends.push(start);
            continue;
        }
        if !sum.is_finite() {
            return Err(ImportError::at(
                Location::line(path, first_line),
                Limit::WeightSum(v),
            ));
        }
        let error = (sum - 1.0).abs();
        let scale = if error > ROW_SUM_TOLERANCE {
            rescaled += 1;
            max_error = max_error.max(error);
            1.0 / sum
        } else {
            1.0
        };
        if !scale.is_finite() {
            // A sum below 1 / f64::MAX (a lone `1e-320`) cannot be renormalized.
            return Err(ImportError::at(
                Location::line(path, first_line),
                Limit::TinyWeightSum { vertex: v, sum },
            ));
        }
        for &(_, joint, w, _) in row {
            let weight = (w * scale) as f32;
            // A weight below f32's range has no effect, as a written 0 has none.
            if weight > 0.0 {
                influences.push(Influence { joint, weight });
            }
        }
        sort_row(influences.get_mut(start..).unwrap_or_default());
        ends.push(influences.len());
    }

    let mut warnings = Vec::new();
    let source = path.display().to_string();
    if duplicates > 0 {
        warnings.push(Warning::Note {
            location: format!("{source}:{first_duplicate_line}"),
            message: format!(
                "{duplicates} duplicate (vertex, joint) entries were added to the first entry of their pair"
            ),
        });
    }
    if rescaled > 0 {
        warnings.push(Warning::WeightsRenormalized {
            source: source.clone(),
            rows: rescaled,
            max_row_sum_error: max_error as f32,
        });
    }
    if let Some(first) = first_empty {
        warnings.push(Warning::Note {
            location: source,
            message: format!(
                "{empty} of {vertex_count} vertices (the first is vertex {first}) have no weight entry: they are bound to no joint"
            ),
        });
    }
    Ok((rows_from_ends(&influences, &ends), warnings))
}

/// Sorts one vertex's influences by descending weight, ties by joint index.
pub(super) fn sort_row(row: &mut [Influence]) {
    row.sort_by(|a, b| b.weight.total_cmp(&a.weight).then(a.joint.cmp(&b.joint)));
}

/// [`Influences`] from flat entries and each row's end offset.
pub(super) fn rows_from_ends(entries: &[Influence], ends: &[usize]) -> Influences {
    Influences::from_rows(ends.iter().scan(0, |start, &end| {
        let row = entries.get(*start..end).unwrap_or_default().iter().copied();
        *start = end;
        Some(row)
    }))
}
