//! How meshes are bound to the skeleton, and the UsdSkel influence primvars of skinned ones.

use std::collections::BTreeMap;

use glam::DMat4;
use rigport_model::conventions::WEIGHT_EPSILON;
use rigport_model::{Asset, SkinBinding, Warning};

use crate::labels::fallback_palette_index;
use crate::labels::ROW_SUM_TOLERANCE;

/// How a mesh is bound to the skeleton.
#[derive(Clone, Copy, Debug)]
pub(super) enum Binding {
    /// Not bound: a plain Mesh (model space).
    None,
    /// Skinned by skin `skin`, with Skeleton prim `skeleton` and this geomBindTransform.
    Skinned {
        skin: usize,
        skeleton: usize,
        geom_bind: DMat4,
    },
    /// Rigidly attached to a joint: constant joint influence, geomBindTransform = the
    /// joint's bind matrix (the points are in the joint's space).
    Rigid { joint: usize },
    /// Only blend shapes (no joint influence): bound to Skeleton 0 for its animation.
    MorphOnly,
}

/// Flattened UsdSkel influences of one skinned mesh.
pub(super) struct SkinRows {
    /// Influences per point (the largest row), at least 1.
    pub(super) element_size: usize,
    /// Skeleton joint indices, `element_size` per point, zero-padded.
    pub(super) indices: Vec<u32>,
    /// Weights, `element_size` per point, summing to 1 per point, zero-padded.
    pub(super) weights: Vec<f32>,
}

/// The influences of `skin` as UsdSkel primvars: palette entries mapped to skeleton joint
/// indices, entries of one joint merged, weights below [`WEIGHT_EPSILON`] of the row's
/// total dropped (arithmetic noise, as for glTF), sorted by weight (largest first, ties by
/// joint), renormalized in `f64`. No limit on the count. A point without influence is bound
/// with weight 1 to the skin's root joint (UsdSkel would move it to the origin), and
/// reported, as is every row whose sum was off by more than the glTF exporter's tolerance.
pub(super) fn skin_rows(
    asset: &Asset,
    si: usize,
    skin: &SkinBinding,
    label: &str,
    warnings: &mut Vec<Warning>,
) -> SkinRows {
    let fallback_palette = fallback_palette_index(&asset.skeleton, &skin.joints);
    let fallback = skin.joints.get(fallback_palette).map_or(0, |j| j.0);
    let mut rows: Vec<Vec<(u32, f64)>> = Vec::with_capacity(skin.influences.vertex_count());
    let (mut unbound, mut renormalized, mut max_error) = (0_usize, 0_usize, 0.0_f64);
    for row in skin.influences.rows() {
        let mut merged: BTreeMap<u32, f64> = BTreeMap::new();
        for inf in row {
            if let Some(j) = skin.joints.get(inf.joint as usize) {
                *merged.entry(j.0).or_default() += f64::from(inf.weight);
            }
        }
        let total: f64 = merged.values().sum();
        let mut kept: Vec<(u32, f64)> = merged
            .into_iter()
            .filter(|&(_, w)| total > 0.0 && w / total >= f64::from(WEIGHT_EPSILON))
            .collect();
        if kept.is_empty() {
            unbound += 1;
            rows.push(vec![(fallback, 1.0)]);
            continue;
        }
        let kept_total: f64 = kept.iter().map(|&(_, w)| w).sum();
        let error = (kept_total - 1.0).abs();
        if error > ROW_SUM_TOLERANCE {
            renormalized += 1;
            max_error = max_error.max(error);
        }
        kept.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
        for entry in &mut kept {
            entry.1 /= kept_total;
        }
        rows.push(kept);
    }
    let element_size = rows.iter().map(Vec::len).max().unwrap_or(0).max(1);
    let mut indices = Vec::with_capacity(rows.len() * element_size);
    let mut weights = Vec::with_capacity(rows.len() * element_size);
    for row in &rows {
        for slot in 0..element_size {
            let (j, w) = row.get(slot).copied().unwrap_or((0, 0.0));
            indices.push(j);
            weights.push(w as f32);
        }
    }
    if renormalized > 0 {
        warnings.push(Warning::WeightsRenormalized {
            source: format!("mesh {label:?} (skin {si})"),
            rows: renormalized,
            max_row_sum_error: max_error as f32,
        });
    }
    if unbound > 0 {
        let root = asset
            .skeleton
            .joints()
            .get(fallback as usize)
            .map(|j| j.name.as_str())
            .unwrap_or_default();
        warnings.push(Warning::Repaired {
            location: format!("mesh {label:?} (skin {si})"),
            message: format!(
                "{unbound} {} had no influence; bound with weight 1 to the skin's root joint {root:?}",
                if unbound == 1 { "vertex" } else { "vertices" }
            ),
        });
    }
    SkinRows {
        element_size,
        indices,
        weights,
    }
}
