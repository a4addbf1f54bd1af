//! The JSON inputs rigport reads beside a rig: `POSE.json` ([`pose`]), `KEYS.json`
//! ([`keys`]) and `HANDLES.json` ([`handles`]).
//!
//! Each parser resolves joint names against a skeleton and returns plain data from
//! `rigport_model`; the evaluator turns that into poses, clips and IK solves. Errors name
//! the file and the JSON path of the offending value (`wave.keys.json: at
//! /keys/2/pose/hand_l/euler_deg: [1.0, NaN, 0.0] is not finite`), or the line and column
//! of a syntax error. The formats are described in `rigport animate --help`,
//! `rigport eval --help` and `rigport ik --help`.

pub mod handles;
pub mod keys;
pub mod pose;

use std::path::Path;

use crate::Location;

/// What is wrong with a JSON input.
#[derive(Debug, thiserror::Error)]
pub enum JsonProblem {
    /// The file could not be read.
    #[error("cannot read: {0}")]
    Io(#[source] std::io::Error),
    /// Not JSON, or not the structure the format requires (a missing or unknown field, a
    /// value of the wrong type); serde's message.
    #[error("{0}")]
    Structure(#[source] serde_json::Error),
    /// A joint name the skeleton does not have.
    #[error("the rig has no joint named {0:?}")]
    UnknownJoint(String),
    /// A list that must not be empty is.
    #[error("no {0}")]
    Empty(&'static str),
    /// Numbers that must be finite are not.
    #[error("{0:?} is not finite")]
    NotFinite(Vec<f32>),
    /// A quaternion that cannot be normalized.
    #[error("quaternion {0:?} is zero or not finite")]
    BadQuaternion([f32; 4]),
    /// An entry gives `order` with `quat`.
    #[error("\"order\" goes with \"euler_deg\", not \"quat\"")]
    OrderWithQuat,
    /// An Euler order that is not one of the six.
    #[error("unknown order {0:?}; expected one of xyz, yzx, zxy, xzy, yxz, zyx")]
    UnknownOrder(String),
    /// A rotation entry with neither or both of `quat` and `euler_deg`.
    #[error("give exactly one of \"quat\" [x,y,z,w] or \"euler_deg\" [x,y,z]")]
    RotationChoice,
    /// A frame rate that is not finite and positive.
    #[error("{0} is not a positive frame rate")]
    BadFps(f32),
    /// A key with neither or both of `time` and `frame`.
    #[error("give exactly one of \"time\" (seconds) or \"frame\"")]
    TimeChoice,
    /// A key given by `frame` in a file without `fps`.
    #[error("\"frame\" needs \"fps\" at the top level")]
    FrameNeedsFps,
    /// A key time that is negative or not finite.
    #[error("time {0} must be a finite number of seconds >= 0")]
    BadTime(f32),
    /// Two keys at the same time.
    #[error("keys {first} and {second} are both at {time} s")]
    SameTime {
        /// The first key's position in the file.
        first: usize,
        /// The second key's position in the file.
        second: usize,
        /// Their time, seconds.
        time: f32,
    },
    /// A key time not after the one before it.
    #[error("{0} s does not come after the previous key")]
    NotIncreasing(f32),
    /// A joint with two handles.
    #[error("{0:?} has a handle already")]
    DuplicateHandle(String),
    /// A handle weight that is not finite and positive.
    #[error("{0} must be > 0")]
    BadWeight(f32),
}

/// A JSON input that could not be read: where, and what is wrong.
///
/// Displays as `reach.json: at /handles/0/joint: the rig has no joint named "nope"`, or
/// `pose.json:2:14: EOF while parsing an object at line 2 column 14` for syntax.
#[derive(Debug, thiserror::Error)]
#[error("{location}: {problem}")]
pub struct JsonError {
    /// Where: the file and a JSON path, or a line and column.
    pub location: Box<Location>,
    /// What.
    pub problem: JsonProblem,
}

impl JsonError {
    /// `problem` at `json_path` (`/keys/2/time`) in `path`.
    pub fn at(path: &Path, json_path: impl Into<String>, problem: JsonProblem) -> Self {
        Self {
            location: Box::new(Location::json(path, json_path)),
            problem,
        }
    }
}

/// Reads `path` and deserializes it; syntax and structure errors carry line and column.
pub(crate) fn read<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, JsonError> {
    let text = std::fs::read_to_string(path).map_err(|e| JsonError {
        location: Box::new(Location::file(path)),
        problem: JsonProblem::Io(e),
    })?;
    parse(&text, path)
}

/// Deserializes `text` (the contents of `path`); syntax and structure errors carry line
/// and column.
pub(crate) fn parse<T: serde::de::DeserializeOwned>(
    text: &str,
    path: &Path,
) -> Result<T, JsonError> {
    serde_json::from_str(text).map_err(|e| JsonError {
        location: Box::new(Location::line_column(path, e.line(), e.column())),
        problem: JsonProblem::Structure(e),
    })
}

/// Deserializes a value found at `json_path` of `path`.
pub(crate) fn from_value<T: serde::de::DeserializeOwned>(
    value: serde_json::Value,
    path: &Path,
    json_path: &str,
) -> Result<T, JsonError> {
    serde_json::from_value(value)
        .map_err(|e| JsonError::at(path, json_path, JsonProblem::Structure(e)))
}

/// `name` as one JSON-pointer token (RFC 6901: `~` as `~0`, `/` as `~1`).
pub(crate) fn token(name: &str) -> String {
    name.replace('~', "~0").replace('/', "~1")
}
