//! `POSE.json`: per-joint rotations applied in each joint's rest frame.

use std::path::Path;

use anyhow::{bail, Context, Result};
use rigport_eval::Pose;
use rigport_model::conventions::EulerOrder;
use rigport_model::glam::Quat;
use rigport_model::Skeleton;
use serde::Deserialize;

/// One joint's entry: a quaternion or Euler angles.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    quat: Option<[f32; 4]>,
    euler_deg: Option<[f32; 3]>,
    order: Option<String>,
}

/// Reads a pose file and applies it to the rest pose of `skeleton`.
///
/// # Errors
/// Unreadable file, JSON syntax (with line and column), an unknown joint, an entry with
/// neither or both of `quat`/`euler_deg`, a zero or non-finite quaternion, an unknown order.
pub fn load(path: &Path, skeleton: &Skeleton) -> Result<Pose> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read", path.display()))?;
    let entries: serde_json::Map<String, serde_json::Value> = serde_json::from_str(&text)
        .map_err(|e| anyhow::anyhow!("{}:{}:{}: {e}", path.display(), e.line(), e.column()))?;
    from_entries(entries, skeleton, &format!("{}: at ", path.display()))
}

/// Applies pose entries (joint name -> `{"quat"}` or `{"euler_deg", "order"}`) to the rest
/// pose. `at` prefixes the JSON path in messages (`file: at /keys/2/pose`).
///
/// # Errors
/// As [`load`].
pub fn from_entries(
    entries: serde_json::Map<String, serde_json::Value>,
    skeleton: &Skeleton,
    at: &str,
) -> Result<Pose> {
    let mut pose = Pose::rest(skeleton);
    for (joint, value) in entries {
        let at = format!("{at}/{joint}");
        let entry: Entry = serde_json::from_value(value).with_context(|| at.clone())?;
        let delta = match (entry.quat, entry.euler_deg) {
            (Some(q), None) => {
                let q = Quat::from_array(q);
                if !q.is_finite() || q.length() < 1e-6 {
                    bail!("{at}: quaternion {:?} is zero or not finite", q.to_array());
                }
                if entry.order.is_some() {
                    bail!("{at}: \"order\" goes with \"euler_deg\", not \"quat\"");
                }
                q.normalize()
            }
            (None, Some(angles)) => {
                if angles.iter().any(|a| !a.is_finite()) {
                    bail!("{at}: euler_deg {angles:?} is not finite");
                }
                let order = entry.order.as_deref().unwrap_or("xyz");
                let order = EulerOrder::parse(order).with_context(|| {
                    format!("{at}: unknown order {order:?}; expected one of xyz, yzx, zxy, xzy, yxz, zyx")
                })?;
                order.to_quat_deg(angles)
            }
            _ => bail!("{at}: give exactly one of \"quat\" [x,y,z,w] or \"euler_deg\" [x,y,z]"),
        };
        pose.rotate_named(skeleton, &joint, delta)
            .with_context(|| at.clone())?;
    }
    Ok(pose)
}
