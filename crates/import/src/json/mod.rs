//! The JSON inputs rigport reads beside a rig: `POSE.json` ([`pose`]), `KEYS.json`
//! ([`keys`]), `HANDLES.json` ([`handles`]) and retargeting's `MAP.json` ([`map`]).
//!
//! Each parser resolves joint names against a skeleton and returns plain data from
//! `rigport_model`; the evaluator turns that into poses, clips and IK solves. Errors name
//! the file and the JSON path of the offending value (`wave.keys.json: at
//! /keys/2/pose/hand_l/euler_deg: [1.0, NaN, 0.0] is not finite`), or the line and column
//! of a syntax error. The formats are described in `rigport animate --help`,
//! `rigport eval --help` and `rigport ik --help`.

pub mod handles;
pub mod keys;
pub mod map;
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
    /// A word that is not one of the allowed ones.
    #[error("unknown value {found:?}; expected {expected}")]
    UnknownWord {
        /// The word given.
        found: String,
        /// The allowed ones.
        expected: &'static str,
    },
    /// A handle's `root` that is not an ancestor of its joint.
    #[error("{root:?} is not an ancestor of {joint:?}")]
    NotAncestor {
        /// The root given.
        root: String,
        /// The handle joint.
        joint: String,
    },
    /// A two-bone handle whose chain does not fit.
    #[error("two-bone chain: {0}")]
    TwoBoneChain(String),
    /// A field that needs another one.
    #[error("{0} needs {1}")]
    Needs(&'static str, &'static str),
    /// A value that must be within 0..=1.
    #[error("{0} must be within 0..=1")]
    OutOfUnit(f32),
    /// A pole target on the chain's root joint.
    #[error("the pole is at the chain's root joint, so it defines no plane")]
    PoleAtRoot,
    /// A limit pair that is not `[min, max]` in degrees within ±180 with min <= max.
    #[error("limit {0:?}: expected [min_deg, max_deg], finite, within -180..=180, min <= max")]
    BadLimit([f32; 2]),
    /// A joint map names a joint the source or target lacks.
    #[error("the {side} has no joint named {name:?}")]
    MapUnknownJoint {
        /// `"source"` or `"target"`.
        side: &'static str,
        /// The name given.
        name: String,
    },
    /// Two source joints drive one target joint.
    #[error("two source joints onto one target: {target:?} is driven by {first:?} already")]
    MappedTwice {
        /// The target joint.
        target: String,
        /// The source joint given first.
        first: String,
    },
    /// A pair whose hierarchy is the reverse of another pair's.
    #[error("a cycle: {:?} -> {:?} reverses the hierarchy of {:?} -> {:?} (one is above the other in the source, below it in the target)", pair[0], pair[1], other[0], other[1])]
    MapCycle {
        /// The pair: source and target names.
        pair: [String; 2],
        /// The earlier pair it conflicts with.
        other: [String; 2],
    },
    /// A clip name the input does not have.
    #[error(transparent)]
    UnknownClip(rigport_model::NoSuchClip),
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

#[cfg(test)]
mod tests {
    use std::path::Path;

    use rigport_model::{Joint, JointIndex, Skeleton, Transform};

    /// `root` -> `arm` -> `hand`.
    fn skeleton() -> Skeleton {
        let joint = |name: &str, parent: Option<u32>| Joint {
            name: name.into(),
            parent: parent.map(JointIndex),
            rest_local: Transform::IDENTITY,
        };
        Skeleton::new(vec![
            joint("root", None),
            joint("arm", Some(0)),
            joint("hand", Some(1)),
        ])
        .expect("a chain")
    }

    /// Writes `text` to a scratch file named `name` and returns the parser's message.
    fn message(name: &str, text: &str, parse: fn(&Path, &Skeleton) -> Option<String>) -> String {
        let dir = std::env::temp_dir().join(format!("rigport-json-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch folder");
        let path = dir.join(name);
        std::fs::write(&path, text).expect("scratch file");
        let m = parse(&path, &skeleton()).unwrap_or_default();
        let _ = std::fs::remove_dir_all(&dir);
        m
    }

    fn pose(path: &Path, s: &Skeleton) -> Option<String> {
        super::pose::read(path, s).err().map(|e| e.to_string())
    }
    fn keys(path: &Path, s: &Skeleton) -> Option<String> {
        super::keys::read(path, s).err().map(|e| e.to_string())
    }
    fn handles(path: &Path, s: &Skeleton) -> Option<String> {
        super::handles::read(path, s).err().map(|e| e.to_string())
    }

    #[test]
    fn pose_errors_name_the_json_path() {
        for (text, expected) in [
            (r#"{"nope": {"quat": [0,0,0,1]}}"#, r#"p.json: at /nope: the rig has no joint named "nope""#),
            (r#"{"arm": {"quat": [0,0,0,0]}}"#, "p.json: at /arm/quat: quaternion [0.0, 0.0, 0.0, 0.0] is zero or not finite"),
            (r#"{"arm": {"quat": [0,0,0,1], "order": "xyz"}}"#, "p.json: at /arm/order: \"order\" goes with \"euler_deg\", not \"quat\""),
            (r#"{"arm": {"euler_deg": [0,0,1], "order": "abc"}}"#, "p.json: at /arm/order: unknown order \"abc\"; expected one of xyz, yzx, zxy, xzy, yxz, zyx"),
            (r#"{"arm": {}}"#, "p.json: at /arm: give exactly one of \"quat\" [x,y,z,w] or \"euler_deg\" [x,y,z]"),
            (r#"{"a/b": {"quat": [0,0,0,1]}}"#, r#"p.json: at /a~1b: the rig has no joint named "a/b""#),
        ] {
            assert!(message("p.json", text, pose).ends_with(expected), "{text}: {}", message("p.json", text, pose));
        }
        assert!(message("p.json", "{\"arm\":\n {", pose).contains("p.json:2:"));
        assert!(message("p.json", r#"{"arm": {"euler": [0,0,1]}}"#, pose)
            .contains("p.json: at /arm: unknown field `euler`"));
    }

    fn map(path: &Path, s: &Skeleton) -> Option<String> {
        super::map::read(path, s, s).err().map(|e| e.to_string())
    }

    #[test]
    fn map_errors_name_the_json_path() {
        for (text, expected) in [
            (r#"{"joints": {}}"#, "m.json: at /joints: no joints"),
            (r#"{"joints": {"nope": "arm"}}"#, "m.json: at /joints/nope: the source has no joint named \"nope\""),
            (r#"{"joints": {"arm": ["arm", "nope"]}}"#, "m.json: at /joints/arm/1: the target has no joint named \"nope\""),
            (r#"{"joints": {"arm": "arm", "hand": "arm"}}"#, "m.json: at /joints/hand: two source joints onto one target: \"arm\" is driven by \"arm\" already"),
            (r#"{"joints": {"arm": "arm", "root": "hand"}}"#, "m.json: at /joints/root: a cycle: \"root\" -> \"hand\" reverses the hierarchy of \"arm\" -> \"arm\" (one is above the other in the source, below it in the target)"),
            (r#"{"joints": {"arm": "arm"}, "pelvis": {"source": "arm", "target": "nope"}}"#, "m.json: at /pelvis/target: the target has no joint named \"nope\""),
            (r#"{"joints": {"arm": 3}}"#, "m.json: at /joints/arm: data did not match any variant of untagged enum Targets"),
        ] {
            let got = message("m.json", text, map);
            assert!(got.ends_with(expected), "{text}: {got}");
        }
        assert!(message("m.json", r#"{"joint": {}}"#, map).contains("m.json:1:"));
    }

    #[test]
    fn keys_errors_name_the_json_path() {
        for (text, expected) in [
            (r#"{"keys": []}"#, "k.json: at /keys: no keys"),
            (
                r#"{"fps": 0, "keys": [{"time": 0}]}"#,
                "k.json: at /fps: 0 is not a positive frame rate",
            ),
            (
                r#"{"keys": [{"frame": 1}]}"#,
                "k.json: at /keys/0: \"frame\" needs \"fps\" at the top level",
            ),
            (
                r#"{"keys": [{"time": 0, "frame": 1}]}"#,
                "k.json: at /keys/0: give exactly one of \"time\" (seconds) or \"frame\"",
            ),
            (
                r#"{"keys": [{"time": -1}]}"#,
                "k.json: at /keys/0: time -1 must be a finite number of seconds >= 0",
            ),
            (
                r#"{"keys": [{"time": 1}, {"time": 1}]}"#,
                "k.json: at /keys: keys 0 and 1 are both at 1 s",
            ),
            (
                r#"{"keys": [{"time": 0}, {"time": 1, "pose": {"hand": {"euler_deg": [0, 0, 1e39]}}}]}"#,
                "k.json: at /keys/1/pose/hand/euler_deg: [0.0, 0.0, inf] is not finite",
            ),
        ] {
            assert!(
                message("k.json", text, keys).ends_with(expected),
                "{text}: {}",
                message("k.json", text, keys)
            );
        }
    }

    #[test]
    fn handles_errors_name_the_json_path() {
        let key = r#"{"time": 0, "position": [0, 0, 0]}"#;
        for (text, expected) in [
            (
                r#"{"handles": []}"#.to_string(),
                "h.json: at /handles: no handles",
            ),
            (
                format!(r#"{{"handles": [{{"joint": "nope", "keys": [{key}]}}]}}"#),
                "h.json: at /handles/0/joint: the rig has no joint named \"nope\"",
            ),
            (
                format!(
                    r#"{{"handles": [{{"joint": "hand", "keys": [{key}]}}, {{"joint": "hand", "keys": [{key}]}}]}}"#
                ),
                "h.json: at /handles/1/joint: \"hand\" has a handle already",
            ),
            (
                r#"{"handles": [{"joint": "hand", "keys": []}]}"#.to_string(),
                "h.json: at /handles/0/keys: no keys",
            ),
            (
                format!(r#"{{"handles": [{{"joint": "hand", "weight": 0, "keys": [{key}]}}]}}"#),
                "h.json: at /handles/0/weight: 0 must be > 0",
            ),
            (
                format!(r#"{{"handles": [{{"joint": "hand", "keys": [{key}, {key}]}}]}}"#),
                "h.json: at /handles/0/keys/1/time: 0 s does not come after the previous key",
            ),
        ] {
            assert!(
                message("h.json", &text, handles).ends_with(expected),
                "{text}: {}",
                message("h.json", &text, handles)
            );
        }
    }

    #[test]
    fn chain_fields_errors_name_the_json_path() {
        let key = r#"{"time": 0, "position": [0, 0, 0]}"#;
        let one = |fields: &str| {
            format!(r#"{{"handles": [{{"joint": "hand", {fields} "keys": [{key}]}}]}}"#)
        };
        for (text, expected) in [
            (one(r#""root": "nope","#), "c.json: at /handles/0/root: the rig has no joint named \"nope\""),
            (
                format!(r#"{{"handles": [{{"joint": "arm", "root": "hand", "keys": [{key}]}}]}}"#),
                "c.json: at /handles/0/root: \"hand\" is not an ancestor of \"arm\"",
            ),
            (
                one(r#""solver": "two_bone", "pole": [0, 0, 0],"#),
                "c.json: at /handles/0/pole: the pole is at the chain's root joint, so it defines no plane",
            ),
            (
                r#"{"handles": [{"joint": "hand", "solver": "two_bone", "keys": [{"time": 0, "position": [0, 0, 0], "pole": [0, 0, 0]}]}]}"#.to_string(),
                "c.json: at /handles/0/keys/0/pole: the pole is at the chain's root joint, so it defines no plane",
            ),
            (one(r#""pole": [0, 1, 0],"#), "c.json: at /handles/0/pole: this field needs \"solver\": \"two_bone\""),
            (one(r#""solver": "three_bone","#), "c.json: at /handles/0/solver: unknown value \"three_bone\"; expected \"two_bone\" or \"iterative\""),
            (one(r#""solver": "two_bone", "soften": 2,"#), "c.json: at /handles/0/soften: 2 must be within 0..=1"),
            (one(r#""solver": "two_bone", "weight": 1.5,"#), "c.json: at /handles/0/weight: 1.5 must be within 0..=1"),
            (one(r#""solver": "two_bone", "root": "arm","#), "c.json: at /handles/0/root: two-bone chain: a two-bone chain's root is the grandparent of \"hand\", \"root\""),
            (
                format!(r#"{{"handles": [{{"joint": "arm", "solver": "two_bone", "keys": [{key}]}}]}}"#),
                "c.json: at /handles/0/solver: two-bone chain: \"arm\" needs a parent and a grandparent",
            ),
            (one(r#""orient": true,"#), "c.json: at /handles/0/orient: \"orient\" needs \"pin\": true"),
            (one(r#""pin": true,"#), "c.json: at /handles/0/keys: keys needs no \"pin\""),
            (
                r#"{"handles": [{"joint": "hand", "keys": [{"time": 0, "position": [0, 0, 0], "rotation": [0, 0, 0, 0]}]}]}"#.to_string(),
                "c.json: at /handles/0/keys/0/rotation: quaternion [0.0, 0.0, 0.0, 0.0] is zero or not finite",
            ),
            (
                format!(r#"{{"root_motion": "wobbly", "handles": [{{"joint": "hand", "keys": [{key}]}}]}}"#),
                "c.json: at /root_motion: unknown value \"wobbly\"; expected \"locked\" or \"free\"",
            ),
            (
                format!(r#"{{"limits": {{"arm": {{"x": [10, -10]}}}}, "handles": [{{"joint": "hand", "keys": [{key}]}}]}}"#),
                "c.json: at /limits/arm/x: limit [10.0, -10.0]: expected [min_deg, max_deg], finite, within -180..=180, min <= max",
            ),
            (
                format!(r#"{{"limits": {{"arm": {{"z": [-200, 10]}}}}, "handles": [{{"joint": "hand", "keys": [{key}]}}]}}"#),
                "c.json: at /limits/arm/z: limit [-200.0, 10.0]: expected [min_deg, max_deg], finite, within -180..=180, min <= max",
            ),
            (
                format!(r#"{{"limits": {{"nope": {{"x": [0, 10]}}}}, "handles": [{{"joint": "hand", "keys": [{key}]}}]}}"#),
                "c.json: at /limits/nope: the rig has no joint named \"nope\"",
            ),
            (
                format!(r#"{{"limits": {{"arm": {{"x": [0, 10], "order": "abc"}}}}, "handles": [{{"joint": "hand", "keys": [{key}]}}]}}"#),
                "c.json: at /limits/arm/order: unknown order \"abc\"; expected one of xyz, yzx, zxy, xzy, yxz, zyx",
            ),
        ] {
            let got = message("c.json", &text, handles);
            assert!(got.ends_with(expected), "{text}: {got}");
        }
    }

    #[test]
    fn chain_fields_parse() {
        let dir = std::env::temp_dir().join(format!("rigport-json-{}-chain", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch folder");
        let path = dir.join("h.json");
        std::fs::write(&path, r#"{"base": "walk", "root_motion": "free", "limits": {"arm": {"y": [-10, 20]}},
            "handles": [{"joint": "hand", "solver": "two_bone", "pole": [0, 1, 0], "twist_deg": 5, "soften": 0.1, "weight": 0.5,
                         "keys": [{"time": 0, "position": [1, 0, 0], "rotation": [0, 0, 0, 2]}, {"time": 1, "position": [1, 1, 0], "pole": [0, 0, 1]}]},
                        {"joint": "arm", "pin": true, "orient": true, "root": "root"}]}"#).expect("write");
        let h = super::handles::read(&path, &skeleton()).expect("valid handles");
        let _ = std::fs::remove_dir_all(&dir);
        assert_eq!(h.base.as_deref(), Some("walk"));
        assert_eq!(h.root_motion, Some(rigport_model::RootMotion::Free));
        assert_eq!(h.limits.len(), 1);
        assert!((h.limits[0].max_rad.y - 20f32.to_radians()).abs() < 1e-6);
        assert!((h.limits[0].max_rad.x - std::f32::consts::PI).abs() < 1e-6);
        let t = &h.tracks[0];
        assert_eq!(t.solver, rigport_model::HandleSolver::TwoBone);
        assert_eq!(
            t.poles,
            [rigport_model::glam::Vec3::Y, rigport_model::glam::Vec3::Z]
        );
        assert_eq!(t.rotations[0], Some(rigport_model::glam::Quat::IDENTITY));
        assert_eq!(t.rotations[1], None);
        assert!(h.tracks[1].pin && h.tracks[1].orient && h.tracks[1].times.is_empty());
        assert_eq!(h.tracks[1].root, Some(JointIndex(0)));
        let clips = |names: &[&str]| -> Vec<rigport_model::Clip> {
            names
                .iter()
                .map(|n| rigport_model::Clip {
                    name: (*n).into(),
                    tracks: Vec::new(),
                })
                .collect()
        };
        assert!(super::handles::check_base(&path, &h, &clips(&["walk"])).is_ok());
        let e = super::handles::check_base(&path, &h, &clips(&["run", "jump"]))
            .expect_err("no such clip");
        assert!(
            e.to_string()
                .ends_with("at /base: no clip named \"walk\"; clips are \"run\", \"jump\""),
            "{e}"
        );
    }

    #[test]
    fn valid_files_parse() {
        let dir = std::env::temp_dir().join(format!("rigport-json-{}-ok", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch folder");
        let path = dir.join("k.json");
        std::fs::write(&path, r#"{"fps": 10, "keys": [{"frame": 5, "pose": {"arm": {"euler_deg": [0, 0, 90]}}}, {"frame": 0, "translation": [0, 1, 0]}]}"#).expect("write");
        let k = super::keys::read(&path, &skeleton()).expect("valid keys");
        assert_eq!(
            k.keys.iter().map(|k| (k.time, k.index)).collect::<Vec<_>>(),
            [(0.0, 1), (0.5, 0)]
        );
        assert_eq!(k.keys[1].rotations[0].joint, JointIndex(1));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
