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
    /// The input reads cleanly but is probably wrong: its parts measure as if they did not
    /// belong together (skin weights whose heaviest bone is far from most vertices, as when
    /// a weights file belongs to another mesh with the same vertex count).
    Suspect {
        /// Where.
        location: String,
        /// What was measured, and what it suggests.
        message: String,
    },
    /// Foot locking found no contact in a clip, so it left the clip as it was; the message
    /// says why (no foot slows under the contact speed, or none is low then), and whether
    /// the feet's speeds suggest the clip plays at the wrong frame rate.
    NoContacts {
        /// Where (the clip).
        location: String,
        /// Why, with the measured speeds.
        message: String,
        /// The frame rate the clip was likely recorded at, when its speeds say that the
        /// stated rate is wrong (frames per second).
        suggested_fps: Option<f32>,
    },
    /// A simulation went past its stability limits and its result was kept anyway, as
    /// asked (e.g. cloth whose stretch or speed diverged).
    Unstable {
        /// Where (the simulation).
        location: String,
        /// Which limit, from which frame, by how much.
        message: String,
    },
    /// A skeleton stands implausibly tall for metres and its file states no unit: it is
    /// read as metres, and is probably in another unit.
    UnitsUnknown {
        /// The input.
        location: String,
        /// How tall the skeleton stands, in the file's units.
        height: f32,
        /// The unit it is almost certainly in (metres per unit), when its shape says so (a
        /// human 100 to 250 units tall: centimetres).
        guess: Option<f64>,
    },
    /// A fact about the input the user may want to know (e.g. which layout was detected).
    Note {
        /// Where.
        location: String,
        /// What.
        message: String,
    },
}

/// Every warning code with its kebab-case name and meaning, in code order (the table
/// `docs/WARNINGS.md` documents). A code never changes meaning once released.
pub const WARNING_CODES: [(&str, &str, &str); 9] = [
    (
        "W001",
        "weights-renormalized",
        "weight rows did not sum to 1 and were rescaled",
    ),
    (
        "W002",
        "influences-dropped",
        "vertices lost influences to a per-vertex limit or as negligibly small",
    ),
    (
        "W003",
        "repaired",
        "something malformed was repaired unambiguously",
    ),
    (
        "W004",
        "incomplete",
        "part of what the input should hold is absent, and the result lacks it",
    ),
    (
        "W005",
        "suspect",
        "the input reads cleanly but measures as probably wrong (e.g. weights of another mesh)",
    ),
    (
        "W006",
        "no-contacts",
        "foot locking found no contact in a clip and left it as it was (says why)",
    ),
    (
        "W007",
        "unstable",
        "a simulation went past its stability limits and the result was kept",
    ),
    (
        "W008",
        "units-unknown",
        "a skeleton stands too tall for metres and its file states no unit",
    ),
    (
        "N001",
        "note",
        "a fact about the input (nothing lost or repaired); never fatal",
    ),
];

impl Warning {
    /// The stable code of this kind of warning (`W001`..; `N001` for a [`Warning::Note`]),
    /// one row of [`WARNING_CODES`].
    pub fn code(&self) -> &'static str {
        self.code_row().0
    }

    /// The stable kebab-case name of this kind of warning (`weights-renormalized`, ...).
    pub fn name(&self) -> &'static str {
        self.code_row().1
    }

    /// Whether this is a [`Warning::Note`]: a fact, nothing lost or repaired.
    pub fn is_note(&self) -> bool {
        matches!(self, Warning::Note { .. })
    }

    /// `warning` or `note`: the word the CLI prints before the code.
    pub fn severity(&self) -> &'static str {
        if self.is_note() {
            "note"
        } else {
            "warning"
        }
    }

    /// The warning as the CLI prints and reports it: `warning[W003]: obj.obj:4: repaired: ...`
    /// (`note[N001]: ...` for a note).
    pub fn labelled(&self) -> String {
        format!("{}[{}]: {self}", self.severity(), self.code())
    }

    fn code_row(&self) -> (&'static str, &'static str, &'static str) {
        let i = match self {
            Warning::WeightsRenormalized { .. } => 0,
            Warning::InfluencesDropped { .. } => 1,
            Warning::Repaired { .. } => 2,
            Warning::Incomplete { .. } => 3,
            Warning::Suspect { .. } => 4,
            Warning::NoContacts { .. } => 5,
            Warning::Unstable { .. } => 6,
            Warning::UnitsUnknown { .. } => 7,
            Warning::Note { .. } => 8,
        };
        WARNING_CODES[i]
    }
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
            Warning::Suspect { location, message } => write!(f, "{location}: suspect: {message}"),
            Warning::NoContacts {
                location, message, ..
            } => write!(f, "{location}: {message}"),
            Warning::Unstable { location, message } => write!(f, "{location}: {message}"),
            Warning::UnitsUnknown {
                location,
                height,
                guess,
            } => {
                write!(
                    f,
                    "{location}: the skeleton stands {height:.1} units tall and the file states no \
                     unit: read as metres, it is {height:.1} m tall"
                )?;
                match guess {
                    Some(g) => write!(
                        f,
                        "; as a human figure it is almost certainly in units of {g} m ({:.2} m tall)",
                        f64::from(*height) * g
                    ),
                    None => Ok(()),
                }
            }
            Warning::Note { location, message } => write!(f, "{location}: {message}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_unique_and_labelled() {
        let mut codes: Vec<&str> = WARNING_CODES.iter().map(|r| r.0).collect();
        codes.sort_unstable();
        codes.dedup();
        assert_eq!(codes.len(), WARNING_CODES.len());
        let w = Warning::Repaired {
            location: "a.obj:4".into(),
            message: "x".into(),
        };
        assert_eq!(w.code(), "W003");
        assert_eq!(w.name(), "repaired");
        assert_eq!(w.labelled(), "warning[W003]: a.obj:4: repaired: x");
        let n = Warning::Note {
            location: "a".into(),
            message: "b".into(),
        };
        assert_eq!(n.labelled(), "note[N001]: a: b");
    }
}
