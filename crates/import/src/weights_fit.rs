//! Whether skin weights fit their mesh. A weights file that belongs to another mesh with the
//! same vertex count (two Pinocchio runs side by side, a renamed `attachment.out`) reads
//! cleanly, and the mesh explodes when it moves. Weights made for a mesh put each vertex's
//! heaviest weight on a bone near it, so rigport measures the share of vertices whose
//! heaviest bone is near them and warns ([`Warning::Suspect`]) when it is low.
//!
//! A joint's bone is the segments from it to its parent and to each child, so the measure
//! holds whichever end of a bone a format binds the bone's weights to. "Near" is within
//! 1.5 times the distance to the nearest bone plus 1% of the skeleton's size: a vertex
//! between two bones counts for both. Measured on the corpus: every vertex is near on each
//! rig whose weights belong to it (four Pinocchio rigs, two CSCI 520 rigs); 29% are for
//! the Armadillo with the human scan's weights (`weights_fit/tests.rs`).

use glam::Vec3;
use rigport_model::{Asset, SkinBinding, Warning};

/// Below this share of near vertices the weights are suspect.
pub const MIN_NEAR_SHARE: f64 = 0.5;

/// Fewer weighted vertices than this say too little to judge (a test's handful).
pub const MIN_VERTICES: usize = 50;

/// The share of `skin`'s vertices (0..=1) whose heaviest influence is on a bone near them;
/// `None` for a skin with fewer than [`MIN_VERTICES`] weighted vertices or a skeleton of
/// one joint.
pub fn near_share(asset: &Asset, skin: &SkinBinding) -> Option<f64> {
    let mesh = asset.meshes.get(skin.mesh.get())?;
    let skeleton = &asset.skeleton;
    if skeleton.len() < 2 {
        return None;
    }
    // Joint positions in the bind pose: the skin's bind matrices where it has them, the
    // rest pose elsewhere.
    let mut at: Vec<Vec3> = skeleton
        .model_rest_matrices()
        .iter()
        .map(|m| m.w_axis.truncate())
        .collect();
    for (j, ib) in skin.joints.iter().zip(&skin.inv_bind) {
        if let Some(p) = at.get_mut(j.get()) {
            *p = ib.inverse().w_axis.truncate();
        }
    }
    let (lo, hi) = at.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    let size = (hi - lo).length();
    // Each joint's bone: the segments to its parent and to its children.
    let mut bones: Vec<Vec<(Vec3, Vec3)>> = vec![Vec::new(); at.len()];
    for (j, parent) in skeleton.parents().enumerate() {
        if let Some(p) = parent {
            let segment = (at[p.get()], at[j]);
            bones[j].push(segment);
            bones[p.get()].push(segment);
        }
    }
    let distance = |j: usize, v: Vec3| -> f32 {
        bones[j]
            .iter()
            .map(|&(a, b)| segment_distance(v, a, b))
            .fold(f32::INFINITY, f32::min)
    };
    let (mut near, mut weighted) = (0usize, 0usize);
    for (v, row) in skin.influences.rows().enumerate() {
        let Some(heaviest) = row.iter().max_by(|a, b| a.weight.total_cmp(&b.weight)) else {
            continue;
        };
        let (Some(&p), Some(joint)) = (
            mesh.positions.get(v),
            skin.joints.get(heaviest.joint as usize),
        ) else {
            continue;
        };
        weighted += 1;
        let nearest = (0..at.len())
            .map(|j| distance(j, p))
            .fold(f32::INFINITY, f32::min);
        if distance(joint.get(), p) <= 1.5 * nearest + 0.01 * size {
            near += 1;
        }
    }
    (weighted >= MIN_VERTICES).then(|| near as f64 / weighted as f64)
}

/// A [`Warning::Suspect`] at `location` for each skin of `asset` whose
/// [`near_share`] is under [`MIN_NEAR_SHARE`].
pub fn check(asset: &Asset, location: &str) -> Vec<Warning> {
    asset
        .skins
        .iter()
        .filter_map(|skin| {
            let share = near_share(asset, skin)?;
            (share < MIN_NEAR_SHARE).then(|| Warning::Suspect {
                location: location.to_string(),
                message: format!(
                    "the heaviest weight of only {:.0}% of the vertices is on a bone near them \
                     (weights made for the mesh give nearly 100%): the weights may belong to \
                     another mesh",
                    share * 100.0
                ),
            })
        })
        .collect()
}

/// The distance from `p` to the segment `a`-`b`.
fn segment_distance(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let len2 = ab.length_squared();
    let t = if len2 > 0.0 {
        ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t).distance(p)
}

#[cfg(test)]
mod tests;
