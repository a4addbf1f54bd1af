//! The importer's state, shared by every step: the input path, the parsed document, its
//! buffers and the warnings so far.

use std::borrow::Cow;
use std::path::Path;

use rigport_model::Warning;

use crate::{ImportError, Location};

/// Largest `|length - 1|` of a rotation quaternion accepted without a warning: the
/// Khronos glTF-Validator's unit-quaternion tolerance (also in `FORMATS.md`).
pub(super) const UNIT_QUAT_TOLERANCE: f32 = 0.00769;

/// One import: what every step reads, and the warnings it adds.
pub(super) struct Importer<'a> {
    pub(super) path: &'a Path,
    pub(super) doc: &'a ::gltf::Document,
    pub(super) buffers: &'a [Cow<'a, [u8]>],
    pub(super) warnings: Vec<Warning>,
}

impl<'a> Importer<'a> {
    pub(super) fn err(&self, at: impl Into<String>, message: impl Into<String>) -> ImportError {
        ImportError::invalid(Location::json(self.path, at), message)
    }

    pub(super) fn note(&mut self, at: &str, message: String) {
        self.warnings.push(Warning::Note {
            location: Location::json(self.path, at).to_string(),
            message,
        });
    }

    pub(super) fn repaired(&mut self, at: &str, message: String) {
        self.warnings.push(Warning::Repaired {
            location: Location::json(self.path, at).to_string(),
            message,
        });
    }

    /// The buffer lookup the `gltf` readers take.
    pub(super) fn data(&self) -> impl Clone + Fn(::gltf::Buffer<'_>) -> Option<&'a [u8]> + 'a {
        let buffers = self.buffers;
        move |buffer: ::gltf::Buffer<'_>| buffers.get(buffer.index()).map(|b| &**b)
    }
}
