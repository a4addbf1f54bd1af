//! What the ASF and AMC parsers share on top of [`crate::text`]: comments, and errors,
//! numbers, vectors, dof lists and axis orders at a line and column.

use std::path::Path;

use glam::DVec3;
use rigport_model::conventions::EulerOrder;

use crate::problem::Repeated;
pub(super) use crate::text::{column, Lines};
use crate::{text, ImportError, Location, Problem};

use super::types::Dof;

/// The line without its comment and surrounding white space. A `#` starts a comment at the
/// start of the line or after white space only (`-1.#IND` stays one, non-numeric, token).
pub(super) fn content(raw: &str) -> &str {
    let bytes = raw.as_bytes();
    let end = bytes
        .iter()
        .enumerate()
        .find(|&(i, &b)| {
            b == b'#'
                && (i == 0
                    || bytes
                        .get(i - 1)
                        .is_some_and(|prev| prev.is_ascii_whitespace()))
        })
        .map_or(raw.len(), |(i, _)| i);
    raw.get(..end).unwrap_or(raw).trim_ascii()
}

/// A token-level error at `path:line:column`.
pub(super) fn syntax(
    path: &Path,
    line: usize,
    raw: &str,
    token: &str,
    expected: &str,
) -> ImportError {
    ImportError::syntax(
        Location::line_column(path, line, column(raw, token)),
        expected,
        token,
    )
}

/// A [`Problem::Duplicate`] error at `path:line`: `what` was first given on `first_line`.
pub(super) fn duplicate(path: &Path, line: usize, what: String, first_line: usize) -> ImportError {
    ImportError::new(
        Location::line(path, line),
        Problem::Duplicate { what, first_line },
    )
}

/// `problem` at a line of `path`.
pub(super) fn line_error(path: &Path, line: usize, problem: impl Into<Problem>) -> ImportError {
    ImportError::at(Location::line(path, line), problem)
}

/// A finite number.
pub(super) fn number(
    path: &Path,
    line: usize,
    raw: &str,
    token: &str,
    what: &'static str,
) -> Result<f64, ImportError> {
    text::number(token, what, || text::at(path, line, raw, token))
}

/// Exactly three finite numbers after a keyword.
pub(super) fn vec3(
    path: &Path,
    line: usize,
    raw: &str,
    whole: &str,
    args: &[&str],
    what: &'static str,
) -> Result<DVec3, ImportError> {
    let [x, y, z] = args else {
        return Err(ImportError::syntax(
            Location::line(path, line),
            format!("3 numbers after `{what}`"),
            whole,
        ));
    };
    Ok(DVec3::new(
        number(path, line, raw, x, what)?,
        number(path, line, raw, y, what)?,
        number(path, line, raw, z, what)?,
    ))
}

/// A dof list: each token a [`Dof`], none repeated, `l` only when `allow_length`.
pub(super) fn dof_list(
    path: &Path,
    line: usize,
    raw: &str,
    whole: &str,
    args: &[&str],
    allow_length: bool,
) -> Result<Vec<Dof>, ImportError> {
    let expected = if allow_length {
        "a dof (tx ty tz rx ry rz l)"
    } else {
        "a root dof (TX TY TZ RX RY RZ)"
    };
    if args.is_empty() {
        return Err(ImportError::syntax(
            Location::line(path, line),
            format!("at least one dof: {expected}"),
            whole,
        ));
    }
    let mut dofs = Vec::with_capacity(args.len());
    for token in args {
        let dof = Dof::parse(token)
            .filter(|d| allow_length || *d != Dof::L)
            .ok_or_else(|| syntax(path, line, raw, token, expected))?;
        if dofs.contains(&dof) {
            return Err(ImportError::at(
                Location::line_column(path, line, column(raw, token)),
                Repeated::Dof(dof.as_str()),
            ));
        }
        dofs.push(dof);
    }
    Ok(dofs)
}

pub(super) fn euler_order(
    path: &Path,
    line: usize,
    raw: &str,
    token: &str,
) -> Result<EulerOrder, ImportError> {
    EulerOrder::parse(token).ok_or_else(|| {
        syntax(
            path,
            line,
            raw,
            token,
            "an axis order (XYZ, XZY, YXZ, YZX, ZXY or ZYX)",
        )
    })
}
