use crate::{JointIndex, MeshIndex};

/// How a track's values are interpolated between keys (glTF's three modes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Hold each key's value until the next key.
    Step,
    /// Lerp for vectors, shortest-path slerp for rotations.
    Linear,
    /// Cubic Hermite spline; values hold `[in_tangent, value, out_tangent]` per key.
    CubicSpline,
}

/// What a track animates.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum TrackTarget {
    /// A joint's local translation (3 components per value).
    Translation(JointIndex),
    /// A joint's local rotation (4 components per value, xyzw).
    Rotation(JointIndex),
    /// A joint's local scale (3 components per value).
    Scale(JointIndex),
    /// A mesh's morph weights (one component per morph target).
    MorphWeights(MeshIndex),
}

/// One animated property: key times and values.
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    /// What is animated.
    pub target: TrackTarget,
    /// How values between keys are found.
    pub interpolation: Interpolation,
    /// Key times in seconds, strictly increasing.
    pub times: Vec<f32>,
    /// Values, flat: `times.len() * components` floats (three times that for cubic splines).
    pub values: Vec<f32>,
}

impl Track {
    /// Floats per value element (3 translation/scale, 4 rotation, targets for weights),
    /// derived from the value count for morph weights.
    pub fn components(&self) -> usize {
        match self.target {
            TrackTarget::Translation(_) | TrackTarget::Scale(_) => 3,
            TrackTarget::Rotation(_) => 4,
            TrackTarget::MorphWeights(_) => {
                let per_key = if self.interpolation == Interpolation::CubicSpline {
                    3
                } else {
                    1
                };
                self.values
                    .len()
                    .checked_div(self.times.len() * per_key)
                    .unwrap_or(0)
            }
        }
    }

    /// Floats stored per key (three values per key for cubic splines).
    pub fn floats_per_key(&self) -> usize {
        let per_key = if self.interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        };
        self.components() * per_key
    }

    /// The value at key `k` (the middle element for cubic splines).
    pub fn key_value(&self, k: usize) -> &[f32] {
        let c = self.components();
        let start = if self.interpolation == Interpolation::CubicSpline {
            (3 * k + 1) * c
        } else {
            k * c
        };
        &self.values[start..start + c]
    }
}

/// A named animation: a set of tracks that play together.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Clip {
    /// Name (may be empty).
    pub name: String,
    /// The tracks, in no particular order.
    pub tracks: Vec<Track>,
}

impl Clip {
    /// Time of the last key of any track, in seconds (0 for an empty clip).
    pub fn duration(&self) -> f32 {
        self.tracks
            .iter()
            .filter_map(|t| t.times.last().copied())
            .fold(0.0, f32::max)
    }
}
