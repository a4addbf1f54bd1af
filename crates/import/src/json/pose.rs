//! `POSE.json`: per-joint rotations applied in each joint's rest frame.
//!
//! ```json
//! {"bone_1": {"quat": [0, 0, 0.3827, 0.9239]},
//!  "bone_2": {"euler_deg": [0, 0, 45], "order": "xyz"}}
//! ```
//! Each entry gives exactly one of `quat` (`[x, y, z, w]`, normalized here) or `euler_deg`
//! (degrees, applied in `order`, default `xyz`; see `rigport_model::conventions`).

/// The POSE.json format as a user writes it (the CLI's `eval` help shows it).
pub const FORMAT: &str = "POSE.json maps joint names to a rotation applied in the joint's rest frame \
    (local = rest_local * delta):\n  \
    {\"bone_5\": {\"quat\": [x, y, z, w]}, \"bone_7\": {\"euler_deg\": [x, y, z], \"order\": \"xyz\"}}\n\
    \"xyz\" lists the axes in the order they are applied: R = Rz * Ry * Rx.";

use std::path::Path;

use rigport_model::conventions::EulerOrder;
use rigport_model::glam::Quat;
use rigport_model::{RestRotation, Skeleton};
use serde::Deserialize;

use super::{from_value, token, JsonError, JsonProblem};

/// One joint's entry: a quaternion or Euler angles.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    quat: Option<[f32; 4]>,
    euler_deg: Option<[f32; 3]>,
    order: Option<String>,
}

/// Reads a pose file for `skeleton`: one rotation per entry, in the file's key order.
///
/// # Errors
/// Unreadable file, JSON syntax (with line and column), an unknown joint, an entry with
/// neither or both of `quat`/`euler_deg`, a zero or non-finite quaternion, non-finite
/// angles, an unknown order, `order` with `quat`.
///
/// ```
/// # use rigport_model::{Joint, Skeleton, Transform};
/// let skeleton = Skeleton::new(vec![Joint {
///     name: "root".into(),
///     parent: None,
///     rest_local: Transform::IDENTITY,
/// }])
/// .expect("one root");
/// let dir = std::env::temp_dir().join(format!("rigport-pose-doc-{}", std::process::id()));
/// std::fs::create_dir_all(&dir)?;
/// let path = dir.join("bad.pose.json");
/// std::fs::write(&path, r#"{"root": {"euler_deg": [0, 0, 90], "order": "abc"}}"#)?;
/// let err = rigport_import::json::pose::read(&path, &skeleton).unwrap_err();
/// assert!(err.to_string().ends_with("at /root/order: unknown order \"abc\"; expected one of xyz, yzx, zxy, xzy, yxz, zyx"));
/// std::fs::write(&path, r#"{"root": {"euler_deg": [0, 0, 90]}}"#)?;
/// let pose = rigport_import::json::pose::read(&path, &skeleton)?;
/// assert_eq!(pose.len(), 1);
/// # std::fs::remove_dir_all(&dir)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn read(path: &Path, skeleton: &Skeleton) -> Result<Vec<RestRotation>, JsonError> {
    let entries: serde_json::Map<String, serde_json::Value> = super::read(path)?;
    entries_of(entries, skeleton, path, "")
}

/// Reads the text of a pose file for `skeleton`; `origin` names it in errors (a file, or
/// what the text came from).
///
/// # Errors
/// As [`read`], but for reading the file.
///
/// ```
/// # use rigport_model::{Joint, Skeleton, Transform};
/// let skeleton = Skeleton::new(vec![Joint {
///     name: "root".into(),
///     parent: None,
///     rest_local: Transform::IDENTITY,
/// }])
/// .expect("one root");
/// let origin = std::path::Path::new("pose");
/// let pose = rigport_import::json::pose::parse(r#"{"root": {"quat": [0, 0, 0, 1]}}"#, origin, &skeleton)?;
/// assert_eq!(pose.len(), 1);
/// let err = rigport_import::json::pose::parse(r#"{"hips": {"quat": [0, 0, 0, 1]}}"#, origin, &skeleton);
/// assert!(err.unwrap_err().to_string().starts_with("pose: at /hips"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn parse(
    text: &str,
    origin: &Path,
    skeleton: &Skeleton,
) -> Result<Vec<RestRotation>, JsonError> {
    let entries: serde_json::Map<String, serde_json::Value> = super::parse(text, origin)?;
    entries_of(entries, skeleton, origin, "")
}

/// The rotations of pose entries (joint name -> `{"quat"}` or `{"euler_deg", "order"}`),
/// found at `json_path` (`""` for a whole file, `/keys/2/pose`) in `path`.
pub(crate) fn entries_of(
    entries: serde_json::Map<String, serde_json::Value>,
    skeleton: &Skeleton,
    path: &Path,
    json_path: &str,
) -> Result<Vec<RestRotation>, JsonError> {
    let mut rotations = Vec::with_capacity(entries.len());
    for (joint, value) in entries {
        let at = format!("{json_path}/{}", token(&joint));
        let err = |field: &str, problem| JsonError::at(path, format!("{at}{field}"), problem);
        let entry: Entry = from_value(value, path, &at)?;
        let rotation = match (entry.quat, entry.euler_deg) {
            (Some(q), None) => {
                // The length in f64: an f32 length of [1e38, 0, 0, 1e38] overflows to
                // infinity and would normalize to zero.
                let q64 = glam::DVec4::from_array(q.map(f64::from));
                let length = q64.length();
                if !q64.is_finite() || length < 1e-6 {
                    return Err(err("/quat", JsonProblem::BadQuaternion(q)));
                }
                if entry.order.is_some() {
                    return Err(err("/order", JsonProblem::OrderWithQuat));
                }
                let unit = (q64 / length).as_vec4();
                Quat::from_vec4(unit).normalize()
            }
            (None, Some(angles)) => {
                if angles.iter().any(|a| !a.is_finite()) {
                    return Err(err("/euler_deg", JsonProblem::NotFinite(angles.to_vec())));
                }
                let order = entry.order.as_deref().unwrap_or("xyz");
                let Some(order) = EulerOrder::parse(order) else {
                    return Err(err("/order", JsonProblem::UnknownOrder(order.to_string())));
                };
                order.to_quat_deg(angles)
            }
            _ => return Err(err("", JsonProblem::RotationChoice)),
        };
        let Some(joint) = skeleton.find(&joint) else {
            return Err(err("", JsonProblem::UnknownJoint(joint)));
        };
        rotations.push(RestRotation { joint, rotation });
    }
    Ok(rotations)
}
