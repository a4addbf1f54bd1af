//! USDA text output: indentation, numbers, tuples, matrices and arrays.
//!
//! Numbers use Rust's shortest round-trip representation (`{}`): an `f32` written this way
//! and read back by USD as a double, then stored as a float, is the same `f32`; an `f64`
//! reads back bit for bit. Rust never uses exponent notation here (`1e-8` prints as
//! `0.00000001`), which the USDA grammar accepts as well as the exponent form.
//! Everything is written in a fixed order, so the same input gives the same bytes.

use std::fmt::{Display, Write as _};
use std::fs::File;
use std::io::{self, BufWriter, Write as _};
use std::path::{Path, PathBuf};

use glam::DMat4;

use rigport_atomic::TempFile;

/// Spaces per indentation level (what `usdcat` writes).
const INDENT: &str = "    ";

/// Text held in memory before a spilling document moves it to its temporary file (and the
/// size of each later write): long clips become files of gigabytes that never sit in memory
/// whole, while every smaller file is built in memory as before.
pub(crate) const SPILL_BYTES: usize = 64 << 20;

/// A USDA document being written: in memory, or (with [`Usda::spilling_to`]) streamed to
/// a temporary file beside the output once it outgrows [`SPILL_BYTES`].
#[derive(Debug, Default)]
pub(crate) struct Usda {
    out: String,
    depth: usize,
    spill: Option<Spill>,
}

/// Where a spilling document goes.
#[derive(Debug)]
struct Spill {
    /// The output the temporary file will be renamed to (links already followed).
    target: PathBuf,
    /// Text held before a spill ([`SPILL_BYTES`] but in tests).
    at: usize,
    /// Created at the first spill.
    file: Option<(TempFile, BufWriter<File>)>,
    /// The first I/O error; the text after it is dropped, since the export has failed.
    error: Option<io::Error>,
}

/// A finished document.
#[derive(Debug)]
pub(crate) enum Finished {
    /// All of it, in memory.
    Text(String),
    /// Written to a temporary file beside `target`, to be renamed over it.
    Staged {
        /// The temporary file (removed on drop unless persisted).
        file: TempFile,
        /// The output it replaces.
        target: PathBuf,
    },
}

impl Usda {
    /// A document that moves its text to a temporary file beside `target` (the output;
    /// links already followed, see [`rigport_atomic::check_output`]) once it holds more than
    /// `at` bytes ([`SPILL_BYTES`]).
    pub(crate) fn spilling_to(target: &Path, at: usize) -> Self {
        Self {
            spill: Some(Spill {
                target: target.to_path_buf(),
                at,
                file: None,
                error: None,
            }),
            ..Self::default()
        }
    }

    /// The text of a document made without a spill target ([`Usda::default`]); for a
    /// spilling one, the part not yet spilled.
    pub(crate) fn into_text(self) -> String {
        self.out
    }

    /// The document: its text, or its temporary file when it spilled.
    ///
    /// # Errors
    /// The first I/O error creating or writing the temporary file (then removed).
    pub(crate) fn finish(mut self) -> io::Result<Finished> {
        let Some(mut spill) = self.spill.take() else {
            return Ok(Finished::Text(self.out));
        };
        if let Some(e) = spill.error.take() {
            return Err(e);
        }
        match spill.file.take() {
            None => Ok(Finished::Text(self.out)),
            Some((file, mut writer)) => {
                writer.write_all(self.out.as_bytes())?;
                writer.flush()?;
                drop(writer);
                Ok(Finished::Staged {
                    file,
                    target: spill.target,
                })
            }
        }
    }

    /// The text in memory when it ends a line, spilling it if it grew past [`SPILL_BYTES`].
    fn maybe_spill(&mut self) {
        let Some(spill) = self.spill.as_mut() else {
            return;
        };
        if self.out.len() < spill.at {
            return;
        }
        if spill.error.is_none() {
            let result = match spill.file.as_mut() {
                Some((_, writer)) => writer.write_all(self.out.as_bytes()),
                None => TempFile::create_beside_open(&spill.target).and_then(|(tmp, file)| {
                    let mut writer = BufWriter::with_capacity(1 << 20, file);
                    writer.write_all(self.out.as_bytes())?;
                    spill.file = Some((tmp, writer));
                    Ok(())
                }),
            };
            if let Err(e) = result {
                spill.error = Some(e);
                // The temporary file goes now; the export fails at `finish`.
                spill.file = None;
            }
        }
        self.out.clear();
    }

    /// Starts a line at the current indentation; the caller appends and ends it with
    /// [`Usda::end`].
    pub(crate) fn start(&mut self) -> &mut String {
        for _ in 0..self.depth {
            self.out.push_str(INDENT);
        }
        &mut self.out
    }

    /// Ends the current line.
    pub(crate) fn end(&mut self) {
        self.out.push('\n');
        self.maybe_spill();
    }

    /// One whole line.
    pub(crate) fn line(&mut self, text: &str) {
        self.start().push_str(text);
        self.end();
    }

    /// An empty line.
    pub(crate) fn blank(&mut self) {
        self.out.push('\n');
        self.maybe_spill();
    }

    /// Writes `header`, then `{` on its own line, and indents.
    pub(crate) fn open(&mut self, header: &str) {
        self.line(header);
        self.line("{");
        self.depth += 1;
    }

    /// Writes `header (` and indents, for a metadata block closed with [`Usda::close_meta`].
    pub(crate) fn open_meta(&mut self, header: &str) {
        self.start().push_str(header);
        self.out.push_str(" (");
        self.end();
        self.depth += 1;
    }

    /// Closes a metadata block: `)`.
    pub(crate) fn close_meta(&mut self) {
        self.depth = self.depth.saturating_sub(1);
        self.line(")");
    }

    /// Closes a block: `}`.
    pub(crate) fn close(&mut self) {
        self.depth = self.depth.saturating_sub(1);
        self.line("}");
    }

    /// `{` on its own line after a metadata block, and indents.
    pub(crate) fn open_body(&mut self) {
        self.line("{");
        self.depth += 1;
    }
}

/// Appends a displayable value (numbers, tokens).
pub(crate) fn put(out: &mut String, value: impl Display) {
    // Writing to a String cannot fail.
    let _ = write!(out, "{value}");
}

/// Appends an `f32` in shortest round-trip form, `-0` as `0` (`x + 0.0` is `+0` for both
/// zeros and `x` otherwise).
pub(crate) fn float(out: &mut String, x: f32) {
    put(out, x + 0.0);
}

/// Appends `(a, b, ...)` of `f32`s.
pub(crate) fn tuple(out: &mut String, values: &[f32]) {
    out.push('(');
    for (i, v) in values.iter().enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        float(out, *v);
    }
    out.push(')');
}

/// Appends `[item, item, ...]`, each item written by `each`.
pub(crate) fn array<T>(out: &mut String, items: &[T], mut each: impl FnMut(&mut String, &T)) {
    out.push('[');
    for (i, item) in items.iter().enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        each(out, item);
    }
    out.push(']');
}

/// Appends a `matrix4d` in USD's row-vector convention.
///
/// rigport matrices act on column vectors (`p' = M p`, translation in the last column);
/// USD's act on row vectors (`p' = p M`, translation in the last row), so the USD matrix is
/// the transpose. Its rows are therefore glam's columns, written in glam's storage order.
pub(crate) fn matrix(out: &mut String, m: &DMat4) {
    out.push_str("( ");
    for (i, col) in m.to_cols_array_2d().iter().enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        out.push('(');
        for (k, v) in col.iter().enumerate() {
            if k > 0 {
                out.push_str(", ");
            }
            put(out, v + 0.0);
        }
        out.push(')');
    }
    out.push_str(" )");
}

/// Appends a quoted USDA string or token, escaping `"` and `\` and control characters.
pub(crate) fn quoted(out: &mut String, s: &str) {
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => put(out, format_args!("\\x{:02x}", u32::from(c))),
            c => out.push(c),
        }
    }
    out.push('"');
}

/// The nearest IEEE 754 half-precision value of `x`, as an `f32` (round to nearest, ties to
/// even; overflow to infinity). SkelAnimation `scales` are `half3[]` (UsdSkel schema), so
/// this is what a reader gets back.
pub(crate) fn to_half(x: f32) -> f32 {
    if !x.is_finite() || x == 0.0 {
        return x;
    }
    let a = x.abs();
    // Half: 10 fraction bits, exponents -14..=15, subnormals down to 2^-24.
    const MAX_HALF: f32 = 65504.0;
    // Values at or above the midpoint between 65504 and 2^16 round to infinity.
    if a >= 65520.0 {
        return f32::INFINITY.copysign(x);
    }
    // The binary exponent, read from the bits (exact, unlike log2); subnormal halfs share
    // the exponent -14.
    let exp = (((a.to_bits() >> 23) & 0xff) as i32 - 127).max(-14);
    // Spacing of halfs at this magnitude: 2^(exp - 10), a power of two, so `a / ulp` is
    // exact.
    let ulp = 2f32.powi(exp - 10);
    let q = a / ulp;
    let r = q.round();
    // `round` sends ties away from zero; IEEE wants ties to even.
    let r = if q - q.floor() == 0.5 && r % 2.0 != 0.0 {
        r - 1.0
    } else {
        r
    };
    (r * ulp).min(MAX_HALF).copysign(x)
}

/// Writes `decl = [m, m, ...]` of matrices.
pub(crate) fn write_matrices(doc: &mut Usda, decl: &str, ms: &[DMat4]) {
    let line = doc.start();
    line.push_str(decl);
    line.push_str(" = ");
    array(line, ms, matrix);
    doc.end();
}

/// Writes `decl = ( (..), .. )`, one matrix (transposed to USD's row vectors).
pub(crate) fn write_matrices_one(doc: &mut Usda, decl: &str, m: &DMat4) {
    let line = doc.start();
    line.push_str(decl);
    line.push_str(" = ");
    matrix(line, m);
    doc.end();
}

/// Writes `decl = ["a", "b", ...]`.
pub(crate) fn write_tokens(doc: &mut Usda, decl: &str, tokens: &[String]) {
    let line = doc.start();
    line.push_str(decl);
    line.push_str(" = ");
    array(line, tokens, |s, t| quoted(s, t));
    doc.end();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_round_trip_and_matrices_are_transposed() {
        let mut s = String::new();
        tuple(&mut s, &[1.0, -0.5, 0.1, 1e-8]);
        assert_eq!(s, "(1, -0.5, 0.1, 0.00000001)");
        let back: Vec<f32> = s
            .trim_matches(|c| c == '(' || c == ')')
            .split(", ")
            .map(|v| v.parse::<f64>().unwrap() as f32)
            .collect();
        assert_eq!(back, vec![1.0, -0.5, 0.1, 1e-8]);
        let mut s = String::new();
        let m = DMat4::from_translation(glam::DVec3::new(1.0, 2.0, 3.0));
        matrix(&mut s, &m);
        assert_eq!(
            s,
            "( (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (1, 2, 3, 1) )"
        );
    }

    #[test]
    fn strings_are_escaped() {
        let mut s = String::new();
        quoted(&mut s, "a\"b\\c\nd");
        assert_eq!(s, r#""a\"b\\c\nd""#);
    }

    #[test]
    fn half_rounding() {
        assert_eq!(to_half(1.0), 1.0);
        assert_eq!(to_half(0.5), 0.5);
        // 1.2 lies between halfs 1.19921875 and 1.2001953125; the latter is nearer.
        assert_eq!(to_half(1.2), 1.200_195_3);
        assert_eq!(to_half(-1.2), -1.200_195_3);
        // Ties to even: 1 + 2^-11 is halfway between 1 and 1 + 2^-10.
        assert_eq!(to_half(1.0 + 2f32.powi(-11)), 1.0);
        assert_eq!(
            to_half(1.0 + 3.0 * 2f32.powi(-11)),
            1.0 + 2.0 * 2f32.powi(-10)
        );
        assert_eq!(to_half(65504.0), 65504.0);
        assert_eq!(to_half(1e6), f32::INFINITY);
        // Subnormal halfs: multiples of 2^-24.
        assert_eq!(to_half(2f32.powi(-24)), 2f32.powi(-24));
        assert_eq!(to_half(2f32.powi(-26)), 0.0);
        // Every half survives.
        for bits in (0_u32..0x7c00).step_by(7) {
            let h = half_bits_to_f32(bits as u16);
            assert_eq!(to_half(h), h, "{bits:#x}");
        }
    }

    /// Reference decoder of half bit patterns (positive, finite).
    fn half_bits_to_f32(bits: u16) -> f32 {
        let exp = i32::from((bits >> 10) & 0x1f);
        let frac = f32::from(bits & 0x3ff);
        if exp == 0 {
            frac * 2f32.powi(-24)
        } else {
            (1.0 + frac / 1024.0) * 2f32.powi(exp - 15)
        }
    }
}
