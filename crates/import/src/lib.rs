//! rigport importers: source files to a [`rigport_model::Asset`].
//!
//! One module per format. Every entry point returns an [`Imported`] (the asset plus the
//! [`Warning`]s of any lossy or repairing step) or an [`ImportError`] that names the file and
//! the line (or JSON path, or byte offset) of the first problem. No entry point panics on
//! any input.
#![warn(missing_docs)]

pub mod asf_amc;
pub mod bone_mesh;
pub mod bvh;
pub mod collada;
pub mod csci520;
pub mod detect;
mod error;
pub mod fbx;
pub mod gather;
pub mod gltf;
pub mod json;
pub mod mtl;
mod names;
mod number;
pub mod obj;
pub mod pinocchio;
pub mod problem;
mod text;
pub mod usda;
pub mod weights_fit;

pub use detect::detect;
pub use error::{check_asset, ImportError, Location, Problem};
pub use text::NumberIssue;

use rigport_model::{Asset, Warning};

/// An imported asset and what was repaired or lost on the way.
#[derive(Clone, Debug)]
pub struct Imported {
    /// The asset, valid by [`Asset::validate`].
    pub asset: Asset,
    /// Lossy or repairing steps, in the order they happened.
    pub warnings: Vec<Warning>,
}

/// Runs `a` on the calling thread and `b` on a scoped helper thread, and returns both
/// results. A panic on the helper is a bug: it is resumed on the caller.
pub(crate) fn join<A, B>(a: impl FnOnce() -> A, b: impl FnOnce() -> B + Send) -> (A, B)
where
    B: Send,
{
    std::thread::scope(|scope| {
        let helper = scope.spawn(b);
        let a = a();
        match helper.join() {
            Ok(b) => (a, b),
            Err(panic) => std::panic::resume_unwind(panic),
        }
    })
}

/// Reads a whole file, mapping failure to an [`ImportError`] that names it.
pub(crate) fn read_file(path: &std::path::Path) -> Result<Vec<u8>, ImportError> {
    std::fs::read(path).map_err(|e| ImportError::new(Location::file(path), Problem::Io(e)))
}

/// The file as UTF-8 text (parsers strip a byte-order mark themselves).
///
/// # Errors
/// At the line holding the first invalid byte.
pub(crate) fn utf8<'a>(bytes: &'a [u8], path: &std::path::Path) -> Result<&'a str, ImportError> {
    std::str::from_utf8(bytes).map_err(|e| {
        let before = bytes.get(..e.valid_up_to()).unwrap_or_default();
        let line = 1 + before.iter().filter(|&&b| b == b'\n').count();
        ImportError::new(Location::line(path, line), Problem::NotUtf8)
    })
}

/// The white-space separated fields of a line, when there are exactly `N`.
pub(crate) fn exact_fields<const N: usize>(line: &str) -> Option<[&str; N]> {
    let mut fields = [""; N];
    let mut n = 0;
    for token in line.split_ascii_whitespace() {
        *fields.get_mut(n)? = token;
        n += 1;
    }
    (n == N).then_some(fields)
}
