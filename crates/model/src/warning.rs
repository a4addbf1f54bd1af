use std::fmt;

/// A lossy or repairing step that succeeded, reported so the user knows what changed.
///
/// Importers and exporters return these beside their result; the CLI prints them, and
/// `--deny-warnings` makes them fatal.
#[derive(Clone, Debug, PartialEq)]
pub enum Warning {
    /// Weight rows did not sum to 1 and were rescaled.
    WeightsRenormalized {
        /// The file (or mesh) the rows came from.
        source: String,
        /// How many rows were rescaled.
        rows: usize,
        /// The largest `|row sum - 1|` seen.
        max_row_sum_error: f32,
    },
    /// Vertices lost influences to a per-vertex limit or as negligibly small.
    InfluencesDropped {
        /// The mesh.
        mesh: String,
        /// The limit applied.
        max_influences: usize,
        /// How many vertices lost weight.
        vertices: usize,
        /// The largest single weight dropped.
        max_dropped_weight: f32,
    },
    /// Something in the input was malformed but could be repaired unambiguously.
    Repaired {
        /// Where (`file:line` or a JSON path).
        location: String,
        /// What was wrong and what was done.
        message: String,
    },
    /// Part of what the input should hold is absent, and the result lacks it (e.g. a rig
    /// whose weights file is missing imports without a skin).
    Incomplete {
        /// Where.
        location: String,
        /// What is missing and what the result lacks.
        message: String,
    },
    /// A fact about the input the user may want to know (e.g. which layout was detected).
    Note {
        /// Where.
        location: String,
        /// What.
        message: String,
    },
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Warning::WeightsRenormalized {
                source,
                rows,
                max_row_sum_error,
            } => write!(
                f,
                "{source}: renormalized {rows} weight rows (largest row-sum error {max_row_sum_error:.6})"
            ),
            Warning::InfluencesDropped {
                mesh,
                max_influences,
                vertices,
                max_dropped_weight,
            } => write!(
                f,
                "mesh {mesh:?}: {vertices} vertices lost weight to the limit of {max_influences} influences (largest weight dropped {max_dropped_weight:.6}); renormalized"
            ),
            Warning::Repaired { location, message } => write!(f, "{location}: repaired: {message}"),
            Warning::Incomplete { location, message } => write!(f, "{location}: {message}"),
            Warning::Note { location, message } => write!(f, "{location}: {message}"),
        }
    }
}
