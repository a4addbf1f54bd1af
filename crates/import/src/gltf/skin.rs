//! Skins: joint palettes, inverse bind matrices, and influences from every
//! `JOINTS_n`/`WEIGHTS_n` set.

use std::collections::BTreeSet;

use ::gltf::accessor::Dimensions;
use ::gltf::Semantic;
use rigport_model::glam::Mat4;
use rigport_model::{Influence, Influences, JointIndex, Warning};

use crate::{ImportError, Location};

use super::accessor::FLOAT;
use super::importer::Importer;

/// Largest `|Σ weights - 1|` of a vertex reported as normalized. The validator's own bound
/// is 2e-7 per non-zero weight; 1e-3 only flags rows that are visibly off.
const WEIGHT_SUM_TOLERANCE: f32 = 1e-3;

/// A mesh's shared skin data, converted once per glTF skin.
#[derive(Clone)]
pub(super) struct SkinData {
    pub(super) joints: Vec<JointIndex>,
    pub(super) inv_bind: Vec<Mat4>,
}

impl<'a> Importer<'a> {
    pub(super) fn skin_data(
        &mut self,
        skin: &::gltf::Skin<'a>,
        node_joint: &[Option<JointIndex>],
    ) -> Result<SkinData, ImportError> {
        let at = format!("/skins/{}", skin.index());
        let mut joints = Vec::new();
        for (k, node) in skin.joints().enumerate() {
            match node_joint.get(node.index()).copied().flatten() {
                Some(j) => joints.push(j),
                None => {
                    return Err(self.err(
                        format!("{at}/joints/{k}"),
                        format!(
                            "joint node {} is not part of the imported scene",
                            node.index()
                        ),
                    ))
                }
            }
        }
        let inv_bind = match skin.inverse_bind_matrices() {
            // glTF 2.0 §5.27.1: without inverseBindMatrices each is the identity.
            None => vec![Mat4::IDENTITY; joints.len()],
            Some(acc) => {
                let ibm_at = format!("{at}/inverseBindMatrices");
                let count = self.check(&acc, Dimensions::Mat4, FLOAT, &ibm_at)?;
                if count < joints.len() {
                    return Err(self.err(
                        ibm_at,
                        format!("{count} matrices for {} joints", joints.len()),
                    ));
                }
                let mut mats: Vec<Mat4> = if Self::zero_filled(&acc) {
                    vec![Mat4::ZERO; count]
                } else {
                    skin.reader(self.data())
                        .read_inverse_bind_matrices()
                        .ok_or_else(|| self.err(&ibm_at, "data unavailable"))?
                        .map(|m| Mat4::from_cols_array_2d(&m))
                        .collect()
                };
                if let Some(k) = mats.iter().position(|m| !m.is_finite()) {
                    return Err(self.err(ibm_at, format!("matrix {k} is not finite")));
                }
                if mats.len() > joints.len() {
                    self.repaired(
                        &ibm_at,
                        format!(
                            "{} matrices for {} joints; extra ones ignored",
                            mats.len(),
                            joints.len()
                        ),
                    );
                    mats.truncate(joints.len());
                }
                mats
            }
        };
        Ok(SkinData { joints, inv_bind })
    }

    /// Influences from every `JOINTS_n`/`WEIGHTS_n` set: zero weights dropped, repeated
    /// joints merged, rows rescaled to sum to 1 (a warning reports rows visibly off).
    pub(super) fn influences(
        &mut self,
        prim: &::gltf::Primitive<'a>,
        base: &str,
        n: usize,
        palette_len: usize,
        skin_index: usize,
    ) -> Result<Influences, ImportError> {
        let mut sets = BTreeSet::new();
        for (semantic, _) in prim.attributes() {
            if let Semantic::Joints(s) | Semantic::Weights(s) = semantic {
                sets.insert(s);
            }
        }
        let mut rows: Vec<Vec<Influence>> = vec![Vec::new(); n];
        let mut merged = vec![false; n];
        for s in sets {
            let j_at = format!("{base}/attributes/JOINTS_{s}");
            let w_at = format!("{base}/attributes/WEIGHTS_{s}");
            let (Some(j_acc), Some(w_acc)) = (
                prim.get(&Semantic::Joints(s)),
                prim.get(&Semantic::Weights(s)),
            ) else {
                self.repaired(
                    &format!("{base}/attributes"),
                    format!("JOINTS_{s} and WEIGHTS_{s} must come in pairs; set {s} ignored"),
                );
                continue;
            };
            let joints = self.read_joints(&j_acc, &j_at)?;
            let weights = self.read_weights(&w_acc, &w_at)?;
            if joints.len() != n {
                return Err(self.err(
                    j_at,
                    format!("has {} elements for {n} vertices", joints.len()),
                ));
            }
            if weights.len() != n {
                return Err(self.err(
                    w_at,
                    format!("has {} elements for {n} vertices", weights.len()),
                ));
            }
            for (v, ((js, ws), row)) in joints.iter().zip(&weights).zip(&mut rows).enumerate() {
                for (k, (&j, &w)) in js.iter().zip(ws).enumerate() {
                    if !w.is_finite() || w < 0.0 {
                        return Err(self.err(
                            &w_at,
                            format!("vertex {v} weight {k} is {w}; weights must be >= 0"),
                        ));
                    }
                    if w == 0.0 {
                        continue;
                    }
                    if usize::from(j) >= palette_len {
                        return Err(self.err(
                            &j_at,
                            format!(
                                "vertex {v} influence {k} names joint {j}, but skin \
                                 {skin_index} has {palette_len} joints"
                            ),
                        ));
                    }
                    let joint = u32::from(j);
                    match row.iter_mut().find(|e| e.joint == joint) {
                        Some(e) => {
                            e.weight += w;
                            merged[v] = true;
                        }
                        None => row.push(Influence { joint, weight: w }),
                    }
                }
            }
        }
        let merged_count = merged.iter().filter(|&&m| m).count();
        if merged_count > 0 {
            self.repaired(
                &format!("{base}/attributes"),
                format!(
                    "{merged_count} vertices list the same joint more than once; weights merged"
                ),
            );
        }
        // glTF 2.0 §3.7.3.3: weights must sum to 1. Rows that do not are rescaled, so what
        // rigport evaluates is what every file it writes holds (both exporters normalize);
        // rows visibly off are reported.
        let mut influences = Influences::from_rows(rows);
        let (off, worst) = influences.normalize(WEIGHT_SUM_TOLERANCE);
        if off > 0 {
            self.warnings.push(Warning::WeightsRenormalized {
                source: Location::json(self.path, format!("{base}/attributes/WEIGHTS_0"))
                    .to_string(),
                rows: off,
                max_row_sum_error: worst,
            });
        }
        Ok(influences)
    }
}
