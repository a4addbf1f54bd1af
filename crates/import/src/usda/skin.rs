//! Skinning: which skeleton a prim binds (`skel:skeleton`), the influence primvars
//! (`primvars:skel:jointIndices`/`jointWeights`), `skel:joints` and the skinning method,
//! turned into a [`SkinBinding`] and per-vertex influences.

use std::collections::BTreeSet;

use glam::DMat4;
use rigport_model::{
    Influence, Influences, JointIndex, MeshIndex, SkinBinding, SkinningMethod, Warning,
};

use super::importer::{f32_mat, resolve_path, Importer, SkelData};
use super::stage::Prim;
use super::values::{self, number, numbers, token, tokens};
use crate::ImportError;

/// Largest `|Σ weights - 1|` of a point reported as normalized: weights written with 6
/// or more digits sum to 1 within 1e-5; 1e-3 flags only rows that are visibly off.
const WEIGHT_SUM_TOLERANCE: f64 = 1e-3;

/// Whether the prim has UsdSkel influence primvars.
pub(super) fn has_skin_primvars(prim: &Prim<'_>) -> bool {
    ["primvars:skel:jointIndices", "primvars:skel:jointWeights"]
        .iter()
        .any(|n| prim.prop(n).and_then(values::static_value).is_some())
}

impl<'l> Importer<'l, '_> {
    /// The Skeleton a skinnable prim binds to (`skel:skeleton` on it or the nearest
    /// ancestor, UsdSkelBindingAPI's inherited binding).
    pub(super) fn bound_skeleton(&self, index: usize) -> Result<usize, ImportError> {
        let prim_path = self
            .stage
            .prims
            .get(index)
            .map(|p| p.path.as_str())
            .unwrap_or("");
        let binding = self.stage.ancestry(index).find_map(|p| {
            let targets = p.prop("skel:skeleton")?.targets?;
            Some((p, targets))
        });
        let Some((owner, targets)) = binding else {
            return Err(self.err(
                prim_path,
                format!(
                    "has joint influences (primvars:skel:jointIndices) but no skeleton: no \
                     skel:skeleton binding on it or an ancestor{}",
                    self.behind_arc(index)
                ),
            ));
        };
        let Some(target) = targets.first() else {
            return Err(self.err(
                &owner.path,
                format!("skel:skeleton has no target, so <{prim_path}> has no skeleton"),
            ));
        };
        let target = resolve_path(&owner.path, target);
        let Some(skel) = self.stage.index(&target) else {
            return Err(self.err(
                &owner.path,
                format!(
                    "skel:skeleton targets <{target}>, which does not exist, so <{prim_path}> \
                     has no skeleton{}",
                    self.behind_arc_path(&target)
                ),
            ));
        };
        let ty = self.stage.prims.get(skel).and_then(|p| p.type_name);
        if ty != Some("Skeleton") || !self.stage.in_scene(skel) {
            return Err(self.err(
                &owner.path,
                format!(
                    "skel:skeleton targets <{target}>, which is not a defined Skeleton ({}), \
                     so <{prim_path}> has no skeleton{}",
                    ty.unwrap_or("untyped"),
                    self.behind_arc(skel)
                ),
            ));
        }
        Ok(skel)
    }

    // -----------------------------------------------------------------------------------
    // Skeleton
    // -----------------------------------------------------------------------------------

    /// Reads an influence primvar's values, interpolation and elementSize.
    fn influence_primvar(
        &self,
        prim: &Prim<'l>,
        name: &str,
    ) -> Result<(Vec<f64>, &'static str, usize), ImportError> {
        let path = &prim.path;
        let prop = prim.prop(name).ok_or_else(|| {
            let other = if name.ends_with("Indices") {
                "primvars:skel:jointWeights"
            } else {
                "primvars:skel:jointIndices"
            };
            self.err(path, format!("has {other} but no {name}"))
        })?;
        let values = match values::static_value(prop) {
            Some((v, _)) => numbers(v).ok_or_else(|| {
                self.err_at(
                    prop.line,
                    path,
                    format!("{name} must be an array of numbers"),
                )
            })?,
            None => Vec::new(),
        };
        // UsdGeomPrimvar: unauthored interpolation is constant, elementSize 1.
        let interp = match prop.meta("interpolation").map(token) {
            None | Some(Some("constant")) => "constant",
            Some(Some("vertex")) => "vertex",
            Some(other) => {
                return Err(self.err(
                    path,
                    format!(
                        "{name} has interpolation {:?}; UsdSkel accepts \"vertex\" or \"constant\"",
                        other.unwrap_or("?")
                    ),
                ))
            }
        };
        let element_size = match prop.meta("elementSize") {
            None => 1,
            Some(v) => match number(v) {
                Some(n) if n >= 1.0 && n.fract() == 0.0 && n <= 1e6 => n as usize,
                other => {
                    // The value as written (`2147483647`, `2.5`), not its Rust debug form.
                    let shown = match other {
                        Some(n) if n.fract() == 0.0 && n.abs() < 1e15 => format!("{}", n as i64),
                        Some(n) => format!("{n}"),
                        None => "that is not a number".to_string(),
                    };
                    return Err(self.err(
                        path,
                        format!("{name} has elementSize {shown}; it must be a positive integer"),
                    ));
                }
            },
        };
        Ok((values, interp, element_size))
    }

    pub(super) fn skin(
        &mut self,
        index: usize,
        skel: &SkelData,
        n_points: usize,
        source_vertex: &[u32],
    ) -> Result<SkinBinding, ImportError> {
        let prim = self.prim(index).clone();
        let path = prim.path.clone();
        const IDX: &str = "primvars:skel:jointIndices";
        const WTS: &str = "primvars:skel:jointWeights";
        let (indices, i_interp, i_size) = self.influence_primvar(&prim, IDX)?;
        let (weights, w_interp, w_size) = self.influence_primvar(&prim, WTS)?;
        if indices.len() != weights.len() {
            return Err(self.err(
                &path,
                format!(
                    "{IDX} has {} values but {WTS} has {}",
                    indices.len(),
                    weights.len()
                ),
            ));
        }
        if (i_interp, i_size) != (w_interp, w_size) {
            return Err(self.err(
                &path,
                format!(
                    "{IDX} ({i_interp}, elementSize {i_size}) and {WTS} ({w_interp}, \
                     elementSize {w_size}) must have the same interpolation and elementSize"
                ),
            ));
        }
        let es = i_size;
        let rows_expected = if i_interp == "vertex" { n_points } else { 1 };
        if indices.len() != es.saturating_mul(rows_expected) {
            let what = if i_interp == "vertex" {
                format!("{n_points} points")
            } else {
                "constant interpolation (one element for the whole mesh)".into()
            };
            return Err(self.err(
                &path,
                format!(
                    "{IDX} has elementSize {es} but {} values for {what}",
                    indices.len()
                ),
            ));
        }
        // The mesh's joint order (skel:joints), else the skeleton's.
        let order: Vec<usize> = match prim.prop("skel:joints").and_then(values::static_value) {
            Some((v, _)) => {
                let toks =
                    tokens(v).ok_or_else(|| self.err(&path, "skel:joints must be a token[]"))?;
                toks.iter()
                    .map(|t| {
                        skel.tokens.iter().position(|s| s == t).ok_or_else(|| {
                            self.err(
                                &path,
                                format!(
                                    "skel:joints names {t:?}, which the Skeleton <{}> does not have",
                                    skel.path
                                ),
                            )
                        })
                    })
                    .collect::<Result<_, _>>()?
            }
            None => (0..skel.tokens.len()).collect(),
        };
        let order_what = if prim.prop("skel:joints").is_some() {
            format!("skel:joints lists {}", order.len())
        } else {
            format!("the Skeleton <{}> has {}", skel.path, order.len())
        };
        let mut rows: Vec<Vec<(usize, f64)>> = Vec::with_capacity(rows_expected);
        for r in 0..rows_expected {
            let mut row: Vec<(usize, f64)> = Vec::with_capacity(es);
            for k in r * es..(r + 1) * es {
                let (Some(&ji), Some(&w)) = (indices.get(k), weights.get(k)) else {
                    continue;
                };
                if !w.is_finite() {
                    return Err(self.err(&path, format!("{WTS}[{k}] is not finite")));
                }
                if w < 0.0 {
                    return Err(self.err(&path, format!("{WTS}[{k}] is negative ({w})")));
                }
                let joint = (ji.fract() == 0.0 && ji >= 0.0)
                    .then_some(ji as usize)
                    .and_then(|i| order.get(i).copied())
                    .ok_or_else(|| {
                        self.err(
                            &path,
                            format!("{IDX}[{k}] = {ji} is out of range: {order_what} joint(s)"),
                        )
                    })?;
                if w == 0.0 {
                    continue;
                }
                match row.iter_mut().find(|(j, _)| *j == joint) {
                    Some((_, acc)) => *acc += w,
                    None => row.push((joint, w)),
                }
            }
            rows.push(row);
        }
        let Some(bind) = &skel.bind else {
            return Err(self.err(
                &skel.path,
                format!("the Skeleton has no bindTransforms, which the skinned <{path}> needs"),
            ));
        };
        let used: BTreeSet<usize> = rows.iter().flatten().map(|&(j, _)| j).collect();
        let palette: Vec<usize> = used.into_iter().collect();
        let mut palette_of = vec![u32::MAX; skel.tokens.len()];
        for (k, &j) in palette.iter().enumerate() {
            if let Some(slot) = palette_of.get_mut(j) {
                *slot = k as u32;
            }
        }
        let mut inv_bind = Vec::with_capacity(palette.len());
        for &j in &palette {
            let m = bind.get(j).copied().unwrap_or(DMat4::IDENTITY);
            let inv = m.inverse();
            if m.determinant().abs() < 1e-300 || !inv.is_finite() {
                return Err(self.err(
                    &skel.path,
                    format!("bindTransforms[{j}] cannot be inverted"),
                ));
            }
            inv_bind.push(f32_mat(&inv));
        }
        let (mut off, mut empty, mut worst) = (0usize, 0usize, 0.0f64);
        for row in &rows {
            let sum: f64 = row.iter().map(|&(_, w)| w).sum();
            if row.is_empty() {
                empty += 1;
            } else if (sum - 1.0).abs() > WEIGHT_SUM_TOLERANCE {
                off += 1;
                worst = worst.max((sum - 1.0).abs());
            }
        }
        let rows_scale = if rows_expected == 1 { n_points } else { 1 };
        if off > 0 {
            self.note(
                &path,
                format!(
                    "{} point(s) have weights that do not sum to 1 (largest error {worst:.6}); \
                     kept as authored, as UsdSkel skins with them",
                    off * rows_scale
                ),
            );
        }
        if empty > 0 {
            self.repaired(
                &path,
                format!(
                    "{} point(s) have no non-zero weight: UsdSkel moves them to the origin, \
                     rigport leaves them at rest",
                    empty * rows_scale
                ),
            );
        }
        let point_rows: Vec<Vec<Influence>> = rows
            .iter()
            .map(|row| {
                row.iter()
                    .map(|&(j, w)| Influence {
                        joint: palette_of.get(j).copied().unwrap_or(0),
                        weight: w as f32,
                    })
                    .collect()
            })
            .collect();
        // One row per output vertex, through the vertex's point (constant: the only row).
        let influences = Influences::from_rows(source_vertex.iter().map(|&p| {
            let r = if rows_expected == 1 { 0 } else { p as usize };
            point_rows.get(r).cloned().unwrap_or_default()
        }));
        if !prim.api_schemas.contains(&"SkelBindingAPI") {
            self.repaired(
                &path,
                "SkelBindingAPI is not applied: usd-core 23.08 and later ignore its skinning \
                 primvars (rigport reads them)",
            );
        }
        let mut method = SkinningMethod::Lbs;
        if let Some(token) = self.skinning_method(index) {
            match SkinningMethod::from_usd_token(token) {
                Some(m) => method = m,
                None => {
                    let location = self.location(&path);
                    self.warnings.push(Warning::Repaired {
                        location,
                        message: format!(
                            "unknown primvars:skel:skinningMethod {token:?}: skinned linearly"
                        ),
                    });
                }
            }
        }
        Ok(SkinBinding {
            method,
            mesh: MeshIndex(0),
            joints: palette.iter().map(|&j| JointIndex(j as u32)).collect(),
            inv_bind,
            influences,
        })
    }

    /// `primvars:skel:skinningMethod` on the prim or inherited from an ancestor (constant
    /// primvars inherit down namespace).
    fn skinning_method(&self, index: usize) -> Option<&'l str> {
        self.stage.ancestry(index).find_map(|p| {
            let prop = p.prop("primvars:skel:skinningMethod")?;
            values::static_value(prop).and_then(|(v, _)| token(v))
        })
    }

    // -----------------------------------------------------------------------------------
    // Animation
    // -----------------------------------------------------------------------------------
}
