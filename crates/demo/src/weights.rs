//! Skin weights: one dense row of bone weights per vertex, from distances to the bones
//! masked by limb, tapered and cut to 4 influences.

use glam::Vec3;

use crate::sdf::smoothstep;
use crate::skeleton::bone_limbs;
/// A limb's claim on a vertex fades out over this many metres as the limb's nearest bone
/// gets farther than the nearest bone of any limb. Smaller than the gap between the thighs
/// a hand's width below the crotch, so each thigh stays off the other.
pub(crate) const LIMB_BLEND: f32 = 0.04;
/// A bone's distance is measured to the bone without this fraction at its head: bones that
/// share a head (chest -> neck and both shoulders) are then no longer equally near to every
/// point around it, and a bone acts less behind its pivot, where it moves skin the wrong way.
pub(crate) const HEAD_TRIM: f32 = 0.25;
/// A bone's weight tapers to zero at this multiple of the nearest effective bone distance.
pub(crate) const REACH: f32 = 2.0;
/// Influences kept per vertex (glTF's one `JOINTS_0` set).
pub(crate) const MAX_INFLUENCES: usize = 4;

/// Distance from `p` to the segment `a`..`b`.
pub(crate) fn segment_distance(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
    p.distance(a + ab * t)
}

/// One dense row of `J - 1` bone weights per vertex.
///
/// Per vertex: `d` = distance to each bone (trimmed at its head, see [`HEAD_TRIM`]); each
/// limb's claim `1 - smoothstep((d_limb - d_nearest) / LIMB_BLEND)`; a bone's mask, the best
/// claim of its limbs; effective distance `e = d / mask`; weight `taper(e / e_min) / e²`
/// with `taper` falling from 1 to 0 between ratio 1 and [`REACH`]; the best
/// [`MAX_INFLUENCES`] minus the next one, normalized. Every step is continuous in the vertex
/// position, so the weights vary smoothly over the surface.
pub(crate) fn skin_weights(
    joints: &[Vec3],
    parents: &[Option<usize>],
    names: &[String],
    positions: &[Vec3],
) -> Vec<Vec<f32>> {
    let bones = joints.len() - 1;
    let limbs = bone_limbs(parents, names);
    let segments: Vec<(Vec3, Vec3)> = (1..joints.len())
        .map(|j| {
            let tail = joints[j];
            let head = parents[j].map_or(tail, |p| joints[p]);
            (head + (tail - head) * HEAD_TRIM, tail)
        })
        .collect();
    let mut dist = vec![0.0f32; bones];
    let mut scored: Vec<(f32, usize)> = Vec::with_capacity(bones);
    positions
        .iter()
        .map(|&p| {
            for (d, &(a, b)) in dist.iter_mut().zip(&segments) {
                *d = segment_distance(p, a, b).max(1e-4);
            }
            let nearest = dist.iter().copied().fold(f32::MAX, f32::min);
            // Claim of each limb (indexed by bit), from its nearest bone.
            let mut limb_dist = [f32::MAX; 32];
            for (&d, &l) in dist.iter().zip(&limbs) {
                let mut bits = l;
                while bits != 0 {
                    let i = bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    limb_dist[i] = limb_dist[i].min(d);
                }
            }
            let claim = limb_dist.map(|d| 1.0 - smoothstep((d - nearest) / LIMB_BLEND));
            scored.clear();
            for (b, (&d, &l)) in dist.iter().zip(&limbs).enumerate() {
                let mut bits = l;
                let mut mask = 0.0f32;
                while bits != 0 {
                    mask = mask.max(claim[bits.trailing_zeros() as usize]);
                    bits &= bits - 1;
                }
                if mask > 0.0 {
                    scored.push((d / mask, b));
                }
            }
            // The nearest bone has mask 1, so `scored` is never empty and e_min is positive.
            let e_min = scored.iter().map(|s| s.0).fold(f32::MAX, f32::min);
            for s in &mut scored {
                let taper = 1.0 - smoothstep((s.0 / e_min - 1.0) / (REACH - 1.0));
                s.0 = taper / (s.0 * s.0);
            }
            // Best first; ties by bone index so the order never depends on anything else.
            scored.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
            let cut = scored.get(MAX_INFLUENCES).map_or(0.0, |s| s.0);
            let mut row = vec![0.0f32; bones];
            let mut sum = 0.0f32;
            for &(w, b) in scored.iter().take(MAX_INFLUENCES) {
                row[b] = w - cut;
                sum += w - cut;
            }
            if sum > 0.0 && sum.is_finite() {
                row.iter_mut().for_each(|w| *w /= sum);
            } else if let Some(&(_, b)) = scored.first() {
                // Only when 5 bones tie exactly: the first of them takes the vertex.
                row.fill(0.0);
                row[b] = 1.0;
            }
            row
        })
        .collect()
}
