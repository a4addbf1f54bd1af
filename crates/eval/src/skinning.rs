//! Linear blend skinning.

use glam::{Mat4, Vec3, Vec4};
use rigport_model::{Influences, JointIndex};

use crate::EvalError;

/// Fills `out[p] = model[palette[p]] * inv_bind[p]`: the skinning matrix of each palette
/// joint, mapping bind-space points to posed model-space points.
///
/// # Errors
/// [`EvalError::Length`] if `inv_bind` or `out` differ in length from `palette`,
/// [`EvalError::Index`] if a palette entry is not in `model`.
pub fn skinning_matrices(
    model: &[Mat4],
    palette: &[JointIndex],
    inv_bind: &[Mat4],
    out: &mut [Mat4],
) -> Result<(), EvalError> {
    for (what, found) in [("inv_bind", inv_bind.len()), ("out", out.len())] {
        if found != palette.len() {
            return Err(EvalError::Length {
                what,
                expected: palette.len(),
                found,
            });
        }
    }
    for (p, joint) in palette.iter().enumerate() {
        let m = model.get(joint.get()).ok_or(EvalError::Index {
            what: "palette",
            index: p,
        })?;
        out[p] = *m * inv_bind[p];
    }
    Ok(())
}

/// Linear blend skinning: `p' = Σ wᵢ · S[jᵢ] · p` for every vertex.
///
/// Weights are used as given (importers and exporters normalize); a vertex with no
/// influence keeps its rest position. Normals are transformed by the blended matrix's
/// upper 3x3 and renormalized.
pub struct LbsJob<'a> {
    /// Skinning matrix per palette joint (see [`skinning_matrices`]).
    pub skin_matrices: &'a [Mat4],
    /// Influences per vertex; joint values index `skin_matrices`.
    pub influences: &'a Influences,
    /// Bind-space positions, one per vertex.
    pub rest_positions: &'a [Vec3],
    /// Bind-space unit normals, one per vertex (optional).
    pub rest_normals: Option<&'a [Vec3]>,
    /// Output: skinned model-space positions (same length as `rest_positions`).
    pub out_positions: &'a mut [Vec3],
    /// Output: skinned unit normals (required when `rest_normals` is given).
    pub out_normals: Option<&'a mut [Vec3]>,
}

impl LbsJob<'_> {
    /// Checks every length and every influence's joint index.
    ///
    /// # Errors
    /// [`EvalError::Length`] or [`EvalError::Index`].
    pub fn validate(&self) -> Result<(), EvalError> {
        let n = self.rest_positions.len();
        let mut lengths = vec![
            ("influences", self.influences.vertex_count()),
            ("out_positions", self.out_positions.len()),
        ];
        match (&self.rest_normals, &self.out_normals) {
            (Some(r), Some(o)) => {
                lengths.push(("rest_normals", r.len()));
                lengths.push(("out_normals", o.len()));
            }
            (None, None) => {}
            (Some(_), None) => {
                return Err(EvalError::Length {
                    what: "out_normals",
                    expected: n,
                    found: 0,
                })
            }
            (None, Some(o)) => {
                return Err(EvalError::Length {
                    what: "rest_normals",
                    expected: o.len(),
                    found: 0,
                })
            }
        }
        for (what, found) in lengths {
            if found != n {
                return Err(EvalError::Length {
                    what,
                    expected: n,
                    found,
                });
            }
        }
        if let Some(bad) = self
            .influences
            .entries()
            .iter()
            .find(|i| i.joint as usize >= self.skin_matrices.len())
        {
            return Err(EvalError::Index {
                what: "influences",
                index: bad.joint as usize,
            });
        }
        Ok(())
    }

    /// Runs the job. Allocates nothing.
    ///
    /// # Errors
    /// As [`LbsJob::validate`], which it calls first.
    pub fn run(&mut self) -> Result<(), EvalError> {
        self.validate()?;
        for (v, row) in self.influences.rows().enumerate() {
            let p = self.rest_positions[v];
            if row.is_empty() {
                self.out_positions[v] = p;
                if let (Some(rn), Some(on)) = (self.rest_normals, self.out_normals.as_deref_mut()) {
                    on[v] = rn[v];
                }
                continue;
            }
            let mut m = Mat4::ZERO;
            for inf in row {
                m += self.skin_matrices[inf.joint as usize] * inf.weight;
            }
            self.out_positions[v] = (m * Vec4::from((p, 1.0))).truncate();
            if let (Some(rn), Some(on)) = (self.rest_normals, self.out_normals.as_deref_mut()) {
                on[v] = m.transform_vector3(rn[v]).try_normalize().unwrap_or(rn[v]);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;
    use proptest::prelude::*;
    use rigport_model::Influence;

    /// Scalar reference: blends the transformed points instead of the matrices.
    fn naive(skin: &[Mat4], infl: &Influences, rest: &[Vec3]) -> Vec<Vec3> {
        rest.iter()
            .enumerate()
            .map(|(v, p)| {
                let row = infl.vertex(v);
                if row.is_empty() {
                    return *p;
                }
                row.iter()
                    .map(|i| skin[i.joint as usize].transform_point3(*p) * i.weight)
                    .sum()
            })
            .collect()
    }

    fn matrix() -> impl Strategy<Value = Mat4> {
        (
            prop::array::uniform3(-3.0f32..3.0),
            prop::array::uniform3(-3.2f32..3.2),
        )
            .prop_map(|(t, r)| {
                Mat4::from_rotation_translation(
                    Quat::from_euler(glam::EulerRot::XYZ, r[0], r[1], r[2]),
                    Vec3::from(t),
                )
            })
    }

    proptest! {
        #[test]
        fn matches_naive_and_single_influence_is_exact(
            skin in prop::collection::vec(matrix(), 1..8),
            rows in prop::collection::vec(prop::collection::vec((0u32..8, 0.01f32..1.0), 0..5), 1..40),
            pts in prop::collection::vec(prop::array::uniform3(-2.0f32..2.0), 40),
        ) {
            let n = skin.len() as u32;
            let infl = Influences::from_rows(rows.iter().map(|r| {
                let sum: f32 = r.iter().map(|x| x.1).sum();
                r.iter().map(move |&(j, w)| Influence { joint: j % n, weight: w / sum }).collect::<Vec<_>>()
            }));
            let rest: Vec<Vec3> = pts[..rows.len()].iter().map(|p| Vec3::from(*p)).collect();
            let mut out = vec![Vec3::ZERO; rest.len()];
            LbsJob { skin_matrices: &skin, influences: &infl, rest_positions: &rest, rest_normals: None, out_positions: &mut out, out_normals: None }.run().unwrap();
            for (v, (a, b)) in out.iter().zip(naive(&skin, &infl, &rest)).enumerate() {
                prop_assert!(a.abs_diff_eq(b, 1e-4), "vertex {v}: {a} vs {b}");
            }
            // Single influence: exactly that joint's matrix.
            let single = Influences::from_rows(rest.iter().enumerate().map(|(v, _)| [Influence { joint: v as u32 % n, weight: 1.0 }]));
            LbsJob { skin_matrices: &skin, influences: &single, rest_positions: &rest, rest_normals: None, out_positions: &mut out, out_normals: None }.run().unwrap();
            for (v, p) in rest.iter().enumerate() {
                let expect = skin[v % n as usize].transform_point3(*p);
                prop_assert!(out[v].abs_diff_eq(expect, 1e-5), "vertex {v}: {} vs {expect}", out[v]);
            }
        }
    }

    #[test]
    fn rejects_bad_joint_index() {
        let infl = Influences::from_rows([[Influence {
            joint: 3,
            weight: 1.0,
        }]]);
        let mut out = [Vec3::ZERO];
        let job = LbsJob {
            skin_matrices: &[Mat4::IDENTITY],
            influences: &infl,
            rest_positions: &[Vec3::ZERO],
            rest_normals: None,
            out_positions: &mut out,
            out_normals: None,
        };
        assert_eq!(
            job.validate(),
            Err(EvalError::Index {
                what: "influences",
                index: 3
            })
        );
    }
}
