//! The `Skeleton` prim: joints from the path tokens (parents first), rest transforms
//! (from `restTransforms`, else `bindTransforms`) and bind matrices.

use std::collections::HashMap;

use glam::{DMat3, DMat4};
use rigport_model::{Joint, JointIndex, Skeleton, Transform, Warning};

use super::importer::{Importer, SkelData};
use super::values::tokens;
use crate::{ImportError, Problem};

/// Largest element difference (relative to the largest element of the 3x3 part, and at
/// least 1) between a rest matrix and its TRS decomposition before the matrix counts as
/// sheared. Decomposition of an `f64` matrix to `f32` TRS is exact to about 1e-7.
const MATRIX_TOLERANCE: f64 = 1e-5;

/// A matrix as TRS (shear is lost).
pub(super) fn trs_of(m: &DMat4) -> Transform {
    let (scale, rotation, translation) = m.to_scale_rotation_translation();
    Transform {
        translation: translation.as_vec3(),
        rotation: rotation.normalize().as_quat(),
        scale: scale.as_vec3(),
    }
}

/// Whether `t` reproduces `m` (no shear lost).
pub(super) fn matches_trs(m: &DMat4, t: &Transform) -> bool {
    let back = t.to_mat4().as_dmat4();
    let scale = DMat3::from_mat4(*m)
        .to_cols_array()
        .iter()
        .fold(1.0f64, |a, x| a.max(x.abs()));
    m.to_cols_array()
        .iter()
        .zip(back.to_cols_array())
        .all(|(a, b)| (a - b).abs() <= MATRIX_TOLERANCE * scale.max(a.abs().max(1.0)))
}

impl<'l> Importer<'l, '_> {
    pub(super) fn skeleton(&mut self, index: usize) -> Result<(Skeleton, SkelData), ImportError> {
        let prim = self.prim(index).clone();
        let path = prim.path.clone();
        let tokens: Vec<String> = match self.static_attr(&prim, "joints") {
            Some((joints_value, joints_prop)) => tokens(joints_value)
                .ok_or_else(|| self.err_at(joints_prop.line, &path, "joints must be a token[]"))?
                .into_iter()
                .map(str::to_string)
                .collect(),
            None => {
                let arc = self.behind_arc(index);
                if !arc.is_empty() {
                    return Err(self.err(&path, format!("the Skeleton has no joints{arc}")));
                }
                // A Skeleton without joints is valid UsdSkel (blend shapes only).
                self.note(&path, "the Skeleton has no joints");
                Vec::new()
            }
        };
        let n = tokens.len();
        let mut at: HashMap<&str, usize> = HashMap::with_capacity(n);
        for (i, t) in tokens.iter().enumerate() {
            if t.is_empty() || t.starts_with('/') || t.ends_with('/') || t.contains("//") {
                return Err(self.err(&path, format!("joint {i} has an invalid path token {t:?}")));
            }
            if let Some(first) = at.insert(t, i) {
                return Err(self.err(&path, format!("joints {first} and {i} are both {t:?}")));
            }
        }
        // Parent: the longest proper prefix (at a '/') that is itself a joint
        // (UsdSkelTopology).
        let mut parents: Vec<Option<usize>> = Vec::with_capacity(n);
        for t in &tokens {
            let mut parent = None;
            let mut cur = t.as_str();
            while let Some(cut) = cur.rfind('/') {
                cur = &cur[..cut];
                if let Some(&p) = at.get(cur) {
                    parent = Some(p);
                    break;
                }
            }
            parents.push(parent);
        }
        if let Some((i, p)) = parents
            .iter()
            .enumerate()
            .find_map(|(i, p)| p.filter(|&p| p > i).map(|p| (i, p)))
        {
            return Err(self.err(
                &path,
                format!(
                    "joints are not parents-first (UsdSkel requires it): joint {i} {:?} comes \
                     before its parent {p} {:?}",
                    tokens.get(i).map_or("", String::as_str),
                    tokens.get(p).map_or("", String::as_str)
                ),
            ));
        }

        let bind = match self.static_attr(&prim, "bindTransforms") {
            None => None,
            Some((v, prop)) => Some(self.matrix_list(v, &prop, &path, "bindTransforms", n)?),
        };
        let rest_local: Vec<DMat4> = match self.static_attr(&prim, "restTransforms") {
            Some((v, prop)) => self.matrix_list(v, &prop, &path, "restTransforms", n)?,
            // No joints, nothing to place (a blend-shape-only Skeleton).
            None if n == 0 => Vec::new(),
            None => {
                let Some(bind) = &bind else {
                    return Err(self.err(
                        &path,
                        format!(
                            "the Skeleton has neither restTransforms nor bindTransforms{}",
                            self.behind_arc(index)
                        ),
                    ));
                };
                self.note(
                    &path,
                    "no restTransforms: the rest pose is the bind pose (bindTransforms relative \
                     to each parent)",
                );
                let mut out = Vec::with_capacity(n);
                for (i, p) in parents.iter().enumerate() {
                    let m = bind.get(i).copied().unwrap_or(DMat4::IDENTITY);
                    out.push(match p.and_then(|p| bind.get(p)) {
                        Some(pm) => pm.inverse() * m,
                        None => m,
                    });
                }
                if out.iter().any(|m| !m.is_finite()) {
                    return Err(self.err(
                        &path,
                        "a parent's bindTransform cannot be inverted to find the rest pose",
                    ));
                }
                out
            }
        };

        // Names: the last path element, made unique.
        let mut used: HashMap<String, usize> = HashMap::new();
        let mut renamed = Vec::new();
        let mut joints = Vec::with_capacity(n);
        let mut sheared = Vec::new();
        for (i, t) in tokens.iter().enumerate() {
            let base = t.rsplit('/').next().unwrap_or(t).to_string();
            let mut name = base.clone();
            let mut k = 1;
            while used.contains_key(&name) {
                k += 1;
                name = format!("{base}_{k}");
            }
            if k > 1 {
                renamed.push(format!("{t:?} -> {name:?}"));
            }
            used.insert(name.clone(), i);
            let m = rest_local.get(i).copied().unwrap_or(DMat4::IDENTITY);
            let rest = trs_of(&m);
            if !matches_trs(&m, &rest) {
                sheared.push(t.clone());
            }
            joints.push(Joint {
                name,
                parent: parents
                    .get(i)
                    .copied()
                    .flatten()
                    .map(|p| JointIndex(p as u32)),
                rest_local: rest,
            });
        }
        if !renamed.is_empty() {
            self.warnings.push(Warning::Repaired {
                location: self.location(&path),
                message: format!(
                    "joint names (the last element of each joint path) made unique: {}",
                    renamed.join(", ")
                ),
            });
        }
        if !sheared.is_empty() {
            self.warnings.push(Warning::Repaired {
                location: self.location(&path),
                message: format!(
                    "restTransforms of {} joint(s) hold shear, which a TRS rest pose cannot: \
                     decomposed, shear dropped ({})",
                    sheared.len(),
                    sheared.join(", ")
                ),
            });
        }
        let skeleton = Skeleton::new(joints)
            .map_err(|problems| ImportError::new(self.file(), Problem::Skeleton(problems)))?;
        Ok((skeleton, SkelData { path, tokens, bind }))
    }
}
