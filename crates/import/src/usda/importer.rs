//! The `Importer` state (layer, composed stage, warnings, stage settings) and the helpers
//! every part of the import shares: errors and warnings naming a prim, typed attribute
//! reads, composition-arc hints, world transforms, primvar values and relationship paths.

use std::path::Path;

use glam::DMat4;
use rigport_model::glam::Mat4;
use rigport_model::{UpAxis, Warning};

use super::layer::{Layer, Value};
use super::stage::{Prim, Prop, Stage};
use super::values::{self, matrices, numbers};
use super::xform::{self, usd_matrix};
use crate::{ImportError, Location};

/// The bound skeleton, as read.
pub(super) struct SkelData {
    /// The Skeleton prim's path.
    pub(super) path: String,
    /// Its joint tokens, in skeleton (= model) order.
    pub(super) tokens: Vec<String>,
    /// Model-space bind matrices (column vectors), when authored.
    pub(super) bind: Option<Vec<DMat4>>,
}

pub(super) struct Importer<'l, 'p> {
    pub(super) path: &'p Path,
    pub(super) layer: &'l Layer,
    pub(super) stage: Stage<'l>,
    pub(super) warnings: Vec<Warning>,
    pub(super) tcps: f64,
    /// The stage's up axis.
    pub(super) up_axis: UpAxis,
    /// World transform of the imported Skeleton prim (model space -> stage), identity
    /// without a skeleton.
    pub(super) skel_world: DMat4,
    /// Blend-shape channels of the imported meshes, for the SkelAnimations' weights.
    pub(super) mesh_shapes: Vec<super::shapes::MeshShapes>,
    /// The package the layer came from (a `.usdz`), whose members textures name.
    pub(super) package: Option<rigport_usd::usdz::Package<'p>>,
}

/// Interpolation of a primvar (`UsdGeomPrimvar`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Interp {
    Constant,
    Uniform,
    Vertex,
    FaceVarying,
}

/// A primvar's values, optional indices and interpolation.
pub(super) struct Primvar<const N: usize> {
    pub(super) values: Vec<[f64; N]>,
    pub(super) indices: Option<Vec<usize>>,
    pub(super) interp: Interp,
}

impl<const N: usize> Primvar<N> {
    /// The value for face `face`, face-vertex (corner) `corner`, point `point`.
    pub(super) fn at(&self, face: usize, corner: usize, point: usize) -> [f64; N] {
        let i = match self.interp {
            Interp::Constant => 0,
            Interp::Uniform => face,
            Interp::Vertex => point,
            Interp::FaceVarying => corner,
        };
        let i = match &self.indices {
            Some(ix) => ix.get(i).copied().unwrap_or(0),
            None => i,
        };
        self.values.get(i).copied().unwrap_or([0.0; N])
    }

    pub(super) fn per_point(&self) -> bool {
        matches!(self.interp, Interp::Constant | Interp::Vertex)
    }
}

pub(super) fn f32_mat(m: &DMat4) -> Mat4 {
    m.as_mat4()
}

/// Resolves a relationship target written relative to the prim that owns the property
/// (`<Animation>`, `<../Skel>`, `<.>`) to an absolute prim path; a property part
/// (`</A.b>`) is dropped.
pub(super) fn resolve_path(owner: &str, target: &str) -> String {
    let target = target
        .split('.')
        .next()
        .filter(|s| !s.is_empty())
        .unwrap_or(".");
    // `<.>` has been cut to "" above and mapped back to "."; `<..>` keeps its dots only
    // through the segment walk below.
    let raw = if target.starts_with('/') {
        target.to_string()
    } else {
        format!("{owner}/{target}")
    };
    let mut parts: Vec<&str> = Vec::new();
    for seg in raw.split('/') {
        match seg {
            "" | "." => {}
            ".." => {
                parts.pop();
            }
            s => parts.push(s),
        }
    }
    format!("/{}", parts.join("/"))
}

impl<'l> Importer<'l, '_> {
    pub(super) fn file(&self) -> Location {
        Location::file(self.path)
    }

    /// An error about prim `prim`: `file: </prim>: message`.
    pub(super) fn err(&self, prim: &str, message: impl std::fmt::Display) -> ImportError {
        ImportError::invalid(self.file().with_prim(prim), message.to_string())
    }

    /// An error about a value written on `line`.
    pub(super) fn err_at(
        &self,
        line: usize,
        prim: &str,
        message: impl std::fmt::Display,
    ) -> ImportError {
        ImportError::invalid(
            Location::line(self.path, line).with_prim(prim),
            message.to_string(),
        )
    }

    pub(super) fn location(&self, prim: &str) -> String {
        self.file().with_prim(prim).to_string()
    }

    pub(super) fn note(&mut self, prim: &str, message: impl Into<String>) {
        let location = self.location(prim);
        self.warnings.push(Warning::Note {
            location,
            message: message.into(),
        });
    }

    /// A warning: the result differs from what USD would make of the input.
    pub(super) fn repaired(&mut self, prim: &str, message: impl Into<String>) {
        let location = self.location(prim);
        self.warnings.push(Warning::Repaired {
            location,
            message: message.into(),
        });
    }

    pub(super) fn incomplete(&mut self, prim: &str, message: impl Into<String>) {
        let location = self.location(prim);
        self.warnings.push(Warning::Incomplete {
            location,
            message: message.into(),
        });
    }

    /// A note on a missing thing that may live behind an unresolved arc on `index` or an
    /// ancestor.
    pub(super) fn behind_arc(&self, index: usize) -> String {
        match self.stage.ancestry(index).find(|p| !p.arcs.is_empty()) {
            Some(p) => format!(
                " (it may come from the {} on <{}>, which rigport does not resolve)",
                p.arcs.join(", "),
                p.path
            ),
            None => String::new(),
        }
    }

    /// The note for a path that does not exist: the nearest existing ancestor with arcs.
    pub(super) fn behind_arc_path(&self, path: &str) -> String {
        let mut cur = path;
        while let Some(cut) = cur.rfind('/') {
            cur = &cur[..cut];
            if let Some(i) = self.stage.index(cur) {
                return self.behind_arc(i);
            }
        }
        String::new()
    }

    // -----------------------------------------------------------------------------------
    // Bindings
    // -----------------------------------------------------------------------------------

    /// The value of attribute `name` of `prim`, read without time (see
    /// [`values::static_value`]), with a note when only time samples exist.
    pub(super) fn static_attr(
        &mut self,
        prim: &Prim<'l>,
        name: &str,
    ) -> Option<(&'l Value, Prop<'l>)> {
        let prop = prim.prop(name)?.clone();
        let (value, sampled) = values::static_value(&prop)?;
        if sampled {
            let path = prim.path.clone();
            self.incomplete(
                &path,
                format!("{name} is only time-sampled: its first sample is used"),
            );
        }
        Some((value, prop))
    }

    pub(super) fn prim(&self, index: usize) -> &Prim<'l> {
        // Indices come from iterating `self.stage.prims`.
        &self.stage.prims[index]
    }

    /// A `matrix4d[]` of `n` finite matrices, as column-vector matrices.
    pub(super) fn matrix_list(
        &self,
        value: &Value,
        prop: &Prop<'_>,
        prim: &str,
        name: &str,
        n: usize,
    ) -> Result<Vec<DMat4>, ImportError> {
        let rows = matrices(value)
            .ok_or_else(|| self.err_at(prop.line, prim, format!("{name} must be a matrix4d[]")))?;
        if rows.len() != n {
            return Err(self.err(
                prim,
                format!("{name} has {} matrices for {n} joints", rows.len()),
            ));
        }
        let out: Vec<DMat4> = rows.iter().map(usd_matrix).collect();
        if let Some(i) = out.iter().position(|m| !m.is_finite()) {
            return Err(self.err(prim, format!("{name}[{i}] is not finite")));
        }
        Ok(out)
    }

    // -----------------------------------------------------------------------------------
    // Meshes
    // -----------------------------------------------------------------------------------

    pub(super) fn int_list(
        &self,
        prim: &Prim<'l>,
        name: &str,
    ) -> Result<Option<Vec<i64>>, ImportError> {
        let Some(prop) = prim.prop(name) else {
            return Ok(None);
        };
        let Some((value, _)) = values::static_value(prop) else {
            return Ok(None);
        };
        let nums = numbers(value).ok_or_else(|| {
            self.err_at(prop.line, &prim.path, format!("{name} must be an int[]"))
        })?;
        nums.iter()
            .map(|&x| {
                if x.fract() == 0.0 && x.abs() < 9.0e15 {
                    Ok(x as i64)
                } else {
                    Err(self.err_at(
                        prop.line,
                        &prim.path,
                        format!("{name} holds {x}, which is not an integer"),
                    ))
                }
            })
            .collect::<Result<Vec<_>, _>>()
            .map(Some)
    }

    /// The world transform of prim `index` at the default time (its ancestors' and its
    /// own `xformOp`s, honouring `!resetXformStack!`), and the paths of prims on the way
    /// whose ops are time-sampled.
    pub(super) fn world(&self, index: usize) -> Result<(DMat4, Vec<String>), ImportError> {
        let mut m = DMat4::IDENTITY;
        let mut animated = Vec::new();
        for p in self.stage.ancestry(index) {
            let local = xform::local(p, None).map_err(|e| self.err(&p.path, e))?;
            if let Some(local) = local {
                m = local.matrix * m;
                if local.animated {
                    animated.push(format!("<{}>", p.path));
                }
                if local.resets {
                    break;
                }
            }
        }
        Ok((m, animated))
    }
}
