//! USD text files (`.usda`) with UsdSkel skeletons, bindings and animations.
//!
//! # Reading
//! A real `.usda` parser (it follows OpenUSD's `Sdf` text grammar: layer and
//! prim metadata, `def`/`over`/`class` prims, typed attributes with defaults and
//! `.timeSamples`, relationships, variant sets, comments, escapes, `inf`/`nan`). One layer
//! is composed: the selected variants apply beneath local opinions, and a property written
//! twice keeps its last statement (as `Sdf` reads a layer; a [`Warning::Note`] says so).
//! References, payloads, inherits, specializes and sublayers are **not** resolved: each
//! prim carrying one gets a [`Warning::Incomplete`], and it is an error when the skeleton,
//! a bound mesh or the bound animation is missing data that may live behind one. The
//! same layer is read from the binary crate format (`.usdc`, own reader in `crate_file/`)
//! and from a package's root layer (`.usdz`); the bytes, not the name, pick the reader.
//! Values of `float` and `half` attributes are narrowed to those types when read, as USD
//! holds them, so a `.usda` and its `.usdc` give equal assets.
//!
//! # The asset rigport builds (UsdSkel, `pxr/usd/usdSkel` docs)
//! | USD | model |
//! |---|---|
//! | `Skeleton.joints` (path tokens) | one [`Joint`] each, named by the last path element (made unique with `_2`, ... and a [`Warning::Repaired`]); parent = the longest proper prefix in the list. UsdSkel requires parents before children: any other order is an error |
//! | `restTransforms` (local, row vectors) | [`Joint::rest_local`] (transposed to column vectors, decomposed to TRS; shear is lost with a warning); when absent, from `bindTransforms` relative to the parent, with a note |
//! | `bindTransforms` (skeleton space) | [`SkinBinding::inv_bind`], their inverses (computed in `f64`) |
//! | `Mesh` with `primvars:skel:jointIndices`/`jointWeights` under a `SkelRoot`, bound by `skel:skeleton` (inherited) | one [`Mesh`] and one [`SkinBinding`] whose palette is the skeleton joints it uses; indices go through the mesh's `skel:joints` when authored; `constant` interpolation binds every point rigidly to the same influences |
//! | `primvars:skel:geomBindTransform` | applied to points and normals, which are then in skeleton space at bind time (UsdSkel applies it before the skinning transforms) |
//! | `SkelAnimation` | one [`Clip`] (named after the prim), LINEAR tracks at the authored samples; the bound one (`skel:animationSource`, inherited) first, then every other one in document order, then those only found in unselected variants |
//! | `Mesh` without skinning primvars | a static [`Mesh`], points moved to model space |
//! | stage `upAxis`, `xformOp`s above the Skeleton | [`Asset::frame`] |
//! | stage `metersPerUnit` | [`Asset::meters_per_unit`] (USD's fallback 0.01 when absent) |
//!
//! Details:
//! - **One skeleton.** The first skeleton a mesh binds to (in document order; without
//!   bindings, the first `Skeleton`) is imported; meshes bound to other skeletons are left
//!   out with a [`Warning::Incomplete`] naming them.
//! - **Space.** Model space is the Skeleton's space, where UsdSkel skins points. The
//!   `xformOp`s of the Skeleton prim and every prim above it (`translate`, `scale`,
//!   `rotateX`.., `rotateXYZ`.., `orient`, `transform`, `!invert!`, `!resetXformStack!`;
//!   see `xform.rs`) give [`SceneFrame::model_to_scene`]; the stage's `upAxis` gives
//!   [`SceneFrame::up_axis`]. Nothing is converted: exporters place the model from the
//!   frame. A static (unskinned) mesh's points and normals are moved from its own space to
//!   model space through its world transform. Time-sampled ops are evaluated at the
//!   default time (else their first sample) with a [`Warning::Incomplete`] (they are not
//!   yet turned into root motion).
//! - **Weights** are kept as authored, as UsdSkel skins with them (it does not normalize):
//!   zero weights are dropped, a joint listed twice for a point is merged, and rows that do
//!   not sum to 1 get a [`Warning::Note`].
//! - **Mesh topology.** n-gons become triangle fans; `leftHanded` orientation is flipped
//!   to counter-clockwise; normals (`primvars:normals` or `normals`) and UVs
//!   (`primvars:st`, else the first `texCoord2*` primvar; indexed primvars too) of any
//!   interpolation. Output vertex `i < points` is point `i`; `faceVarying`/`uniform` values
//!   that differ from a point's first corner split it into further vertices whose
//!   [`Mesh::source_vertex`] is the point index. UVs are flipped to the glTF convention
//!   (`v' = 1 - v`).
//! - **Time.** A time code `t` is `t / timeCodesPerSecond` seconds (the layer's value, else
//!   `framesPerSecond`, else 24, as `UsdStage::GetTimeCodesPerSecond`), not shifted by
//!   `startTimeCode`; when a clip has negative times, the whole clip is shifted to start
//!   at 0 with a [`Warning::Repaired`]. An attribute with only a default value is one key
//!   at the clip's first sample time. UsdSkel ignores an animation that lacks any of
//!   `translations`, `rotations` and `scales`; so does rigport, with a warning.
//! - **Rotations** are read `(w, x, y, z)` and stored `xyzw`, normalized and made
//!   sign-continuous along each track; `half` values (`half3[] scales`) are rounded to
//!   binary16 as USD stores them.
//! - `primvars:skel:skinningMethod` (inherited) is the skin's
//!   [`SkinBinding::method`]; an unknown token is skinned linearly with a warning.
//! - Blend shapes are not imported (a [`Warning::Incomplete`]); non-`Mesh` skinnable prims
//!   (curves, points, implicit shapes) are left out with a warning.
//!
//! # Errors
//! Syntax errors carry `file:line:column`. UsdSkel errors name the prim path:
//! `arm.usda: </Root/Arm/Mesh>: primvars:skel:jointIndices has elementSize 3 but 7 values
//! for 3 points`: bad `elementSize` or interpolation, joint index out of range, a bound mesh
//! without a skeleton, weights and indices of different lengths, negative or non-finite
//! values, joints not parents-first, animation arrays of the wrong size, attributes of the
//! wrong type.

mod crate_file;
mod lex;
mod parse;
mod stage;
#[cfg(test)]
mod tests;
mod usdz;
mod values;
mod xform;

use std::collections::{BTreeSet, HashMap};
use std::path::Path;

use glam::{DMat3, DMat4, DVec3};
use rigport_model::glam::{Mat4, Quat, Vec2, Vec3};
use rigport_model::{
    Asset, Clip, Influence, Influences, Interpolation, Joint, JointIndex, Mesh, MeshIndex,
    SceneFrame, Skeleton, SkinBinding, SkinningMethod, Track, TrackTarget, Transform, UpAxis,
    Warning,
};

use self::parse::{Layer, PrimSpec, Value};
use self::stage::{Prim, Prop, Stage};
use self::values::{
    is_half_type, matrices, matrix, number, numbers, round_to_half, token, tokens, tuples,
};
use crate::{read_file, ImportError, Imported, Location, Problem};

/// USD's fallback `metersPerUnit` when a stage does not author it (centimetres,
/// `UsdGeomLinearUnits` / `UsdGeomGetStageMetersPerUnit`).
pub const DEFAULT_METERS_PER_UNIT: f64 = 0.01;

/// USD's fallback `timeCodesPerSecond` (`SdfSchema`, 24).
pub const DEFAULT_TIME_CODES_PER_SECOND: f64 = 24.0;

/// Largest `|Σ weights - 1|` of a point reported as normalized: weights written with 6
/// or more digits sum to 1 within 1e-5; 1e-3 flags only rows that are visibly off.
const WEIGHT_SUM_TOLERANCE: f64 = 1e-3;

/// Largest element difference (relative to the largest element of the 3x3 part, and at
/// least 1) between a rest matrix and its TRS decomposition before the matrix counts as
/// sheared. Decomposition of an `f64` matrix to `f32` TRS is exact to about 1e-7.
const MATRIX_TOLERANCE: f64 = 1e-5;

/// Imports a `.usda` file.
///
/// See the module docs for what is read and how it maps onto the model.
///
/// # Errors
/// The file cannot be read or is not UTF-8; a syntax error (at its `file:line:column`);
/// invalid UsdSkel data (naming the prim path); the resulting asset fails
/// [`Asset::validate`].
pub fn import(path: &Path) -> Result<Imported, ImportError> {
    let bytes = read_file(path)?;
    import_slice(&bytes, path)
}

/// Imports `.usda` text held in memory; `path` names it in errors and warnings, and its
/// stem names the asset.
///
/// # Errors
/// As [`import`], less the file system.
pub fn import_slice(bytes: &[u8], path: &Path) -> Result<Imported, ImportError> {
    // `.usda` text, a `.usdc` crate file or a `.usdz` package, by their first bytes.
    let layer = usdz::read_layer(bytes, path)?;
    let mut importer = Importer {
        path,
        layer: &layer,
        stage: Stage::compose(&layer.root, None),
        warnings: Vec::new(),
        tcps: DEFAULT_TIME_CODES_PER_SECOND,
        up_axis: UpAxis::Y,
        skel_world: DMat4::IDENTITY,
    };
    let asset = importer.run()?;
    Ok(Imported {
        asset,
        warnings: importer.warnings,
    })
}

/// The bound skeleton, as read.
struct SkelData {
    /// The Skeleton prim's path.
    path: String,
    /// Its joint tokens, in skeleton (= model) order.
    tokens: Vec<String>,
    /// Model-space bind matrices (column vectors), when authored.
    bind: Option<Vec<DMat4>>,
}

struct Importer<'l, 'p> {
    path: &'p Path,
    layer: &'l Layer,
    stage: Stage<'l>,
    warnings: Vec<Warning>,
    tcps: f64,
    /// The stage's up axis.
    up_axis: UpAxis,
    /// World transform of the imported Skeleton prim (model space -> stage), identity
    /// without a skeleton.
    skel_world: DMat4,
}

/// Interpolation of a primvar (`UsdGeomPrimvar`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Interp {
    Constant,
    Uniform,
    Vertex,
    FaceVarying,
}

/// A primvar's values, optional indices and interpolation.
struct Primvar<const N: usize> {
    values: Vec<[f64; N]>,
    indices: Option<Vec<usize>>,
    interp: Interp,
}

impl<const N: usize> Primvar<N> {
    /// The value for face `face`, face-vertex (corner) `corner`, point `point`.
    fn at(&self, face: usize, corner: usize, point: usize) -> [f64; N] {
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

    fn per_point(&self) -> bool {
        matches!(self.interp, Interp::Constant | Interp::Vertex)
    }
}

/// The column-vector matrix of a USD row-vector `matrix4d` as written (rows): USD's row
/// `i` is the column `i` of the column-vector matrix (translation in the last row there,
/// the last column here).
fn usd_matrix(rows: &[[f64; 4]; 4]) -> DMat4 {
    DMat4::from_cols_array_2d(rows)
}

fn f32_mat(m: &DMat4) -> Mat4 {
    m.as_mat4()
}

impl<'l> Importer<'l, '_> {
    fn file(&self) -> Location {
        Location::file(self.path)
    }

    /// An error about prim `prim`: `file: </prim>: message`.
    fn err(&self, prim: &str, message: impl std::fmt::Display) -> ImportError {
        ImportError::invalid(self.file(), format!("<{prim}>: {message}"))
    }

    /// An error about a value written on `line`.
    fn err_at(&self, line: usize, prim: &str, message: impl std::fmt::Display) -> ImportError {
        ImportError::invalid(
            Location::line(self.path, line),
            format!("<{prim}>: {message}"),
        )
    }

    fn location(&self, prim: &str) -> String {
        format!("{}: <{prim}>", self.path.display())
    }

    fn note(&mut self, prim: &str, message: impl Into<String>) {
        let location = self.location(prim);
        self.warnings.push(Warning::Note {
            location,
            message: message.into(),
        });
    }

    /// A warning: the result differs from what USD would make of the input.
    fn repaired(&mut self, prim: &str, message: impl Into<String>) {
        let location = self.location(prim);
        self.warnings.push(Warning::Repaired {
            location,
            message: message.into(),
        });
    }

    fn incomplete(&mut self, prim: &str, message: impl Into<String>) {
        let location = self.location(prim);
        self.warnings.push(Warning::Incomplete {
            location,
            message: message.into(),
        });
    }

    fn run(&mut self) -> Result<Asset, ImportError> {
        self.layer_metadata()?;
        let meters_per_unit = self.meters_per_unit()?;
        self.composition_warnings();

        // Skinnable prims and their bindings, in document order.
        let mut skinnable: Vec<(usize, Option<usize>)> = Vec::new();
        for i in 0..self.stage.prims.len() {
            let Some(prim) = self.stage.prims.get(i) else {
                continue;
            };
            if !self.stage.in_scene(i) || !has_skin_primvars(prim) {
                continue;
            }
            if matches!(
                prim.type_name,
                Some("Skeleton" | "SkelAnimation" | "SkelRoot")
            ) {
                continue;
            }
            let under_root = self
                .stage
                .ancestry(i)
                .skip(1)
                .any(|p| p.type_name == Some("SkelRoot"));
            if !under_root {
                let path = prim.path.clone();
                self.incomplete(
                    &path,
                    "has joint influences but no SkelRoot above it: UsdSkel does not skin it, \
                     so it is imported unskinned",
                );
                continue;
            }
            let skel = self.bound_skeleton(i)?;
            skinnable.push((i, Some(skel)));
        }

        // The one skeleton to import.
        let is_mesh = |i: usize| self.stage.prims.get(i).and_then(|p| p.type_name) == Some("Mesh");
        let chosen = match skinnable
            .iter()
            .find(|&&(m, _)| is_mesh(m))
            .or(skinnable.first())
            .and_then(|&(_, s)| s)
        {
            Some(s) => Some(s),
            None => (0..self.stage.prims.len()).find(|&i| {
                self.stage.in_scene(i)
                    && self.stage.prims.get(i).and_then(|p| p.type_name) == Some("Skeleton")
            }),
        };
        let mut others: Vec<(usize, usize)> = Vec::new();
        for &(_, s) in &skinnable {
            if let Some(s) = s.filter(|&s| Some(s) != chosen) {
                match others.iter_mut().find(|(o, _)| *o == s) {
                    Some((_, n)) => *n += 1,
                    None => others.push((s, 1)),
                }
            }
        }
        for (s, n) in others {
            let path = self
                .stage
                .prims
                .get(s)
                .map(|p| p.path.clone())
                .unwrap_or_default();
            self.incomplete(
                &path,
                format!(
                    "a second skeleton, bound by {n} mesh(es): not imported (rigport imports \
                     one skeleton per file, the first one bound); those meshes are left out"
                ),
            );
        }

        let (skeleton, skel) = match chosen {
            Some(s) => {
                let (skeleton, data) = self.skeleton(s)?;
                (skeleton, Some((s, data)))
            }
            None => (Skeleton::default(), None),
        };
        if let Some((s, _)) = &skel {
            let (world, animated) = self.world(*s)?;
            self.skel_world = world;
            if !animated.is_empty() {
                let path = self.prim(*s).path.clone();
                self.incomplete(
                    &path,
                    format!(
                        "time-sampled transforms (xformOp) on {} are not imported as root \
                         motion: their value at the default time is used",
                        animated.join(", ")
                    ),
                );
            }
        }

        // Meshes.
        let mut meshes = Vec::new();
        let mut skins = Vec::new();
        for i in 0..self.stage.prims.len() {
            let Some(prim) = self.stage.prims.get(i) else {
                continue;
            };
            if !self.stage.in_scene(i) {
                continue;
            }
            let binding = skinnable.iter().find(|(m, _)| *m == i).map(|&(_, s)| s);
            let is_mesh = prim.type_name == Some("Mesh");
            if !is_mesh {
                if binding.is_some() {
                    let (path, ty) = (prim.path.clone(), prim.type_name.unwrap_or("untyped"));
                    self.incomplete(
                        &path,
                        format!("a skinnable {ty} prim is not a Mesh: not imported"),
                    );
                }
                continue;
            }
            let skin_to = match (binding, &skel) {
                (Some(Some(s)), Some((chosen, data))) if s == *chosen => Some(data),
                (Some(_), _) => continue, // bound to another skeleton: warned above
                (None, _) => None,
            };
            if let Some((mesh, skin)) = self.mesh(i, skin_to)? {
                let index = MeshIndex(meshes.len() as u32);
                meshes.push(mesh);
                if let Some(mut skin) = skin {
                    skin.mesh = index;
                    skins.push(skin);
                }
            }
        }

        // Clips.
        let clips = match &skel {
            Some((s, data)) => self.clips(*s, data)?,
            None => Vec::new(),
        };

        let asset = Asset {
            frame: SceneFrame {
                up_axis: self.up_axis,
                model_to_scene: self.skel_world,
            },
            name: self
                .path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            skeleton,
            meshes,
            skins,
            clips,
            meters_per_unit: Some(meters_per_unit),
            ik_handles: Vec::new(),
        };
        asset.validate().map_err(|problems| {
            ImportError::invalid(
                self.file(),
                problems
                    .iter()
                    .map(ToString::to_string)
                    .collect::<Vec<_>>()
                    .join("; "),
            )
        })?;
        Ok(asset)
    }

    // -----------------------------------------------------------------------------------
    // Layer
    // -----------------------------------------------------------------------------------

    fn layer_meta(&self, key: &str) -> Option<&'l parse::Meta> {
        self.layer.meta.iter().rev().find(|m| m.key == key)
    }

    fn layer_metadata(&mut self) -> Result<(), ImportError> {
        let rate = |key: &str| -> Result<Option<f64>, ImportError> {
            let Some(m) = self.layer_meta(key) else {
                return Ok(None);
            };
            match number(&m.value) {
                Some(n) if n.is_finite() && n > 0.0 => Ok(Some(n)),
                _ => Err(ImportError::invalid(
                    Location::line(self.path, m.line),
                    format!("{key} must be a positive number"),
                )),
            }
        };
        // UsdStage::GetTimeCodesPerSecond: the layer's timeCodesPerSecond, else its
        // framesPerSecond, else 24.
        self.tcps = match (rate("timeCodesPerSecond")?, rate("framesPerSecond")?) {
            (Some(t), _) | (None, Some(t)) => t,
            (None, None) => DEFAULT_TIME_CODES_PER_SECOND,
        };
        if let Some(m) = self.layer_meta("upAxis") {
            match token(&m.value) {
                Some("Y") => self.up_axis = UpAxis::Y,
                Some("Z") => self.up_axis = UpAxis::Z,
                _ => {
                    return Err(ImportError::invalid(
                        Location::line(self.path, m.line),
                        "upAxis must be \"Y\" or \"Z\"",
                    ))
                }
            }
        }
        if let Some(m) = self.layer_meta("subLayers") {
            let n = stage::list_items(&m.value).len();
            if n > 0 {
                self.warnings.push(Warning::Incomplete {
                    location: Location::line(self.path, m.line).to_string(),
                    message: format!(
                        "{n} sublayer(s) not read: rigport reads a single .usda layer"
                    ),
                });
            }
        }
        Ok(())
    }

    fn meters_per_unit(&self) -> Result<f64, ImportError> {
        match self.layer_meta("metersPerUnit") {
            None => Ok(DEFAULT_METERS_PER_UNIT),
            Some(m) => match number(&m.value) {
                Some(n) if n.is_finite() && n > 0.0 => Ok(n),
                _ => Err(ImportError::invalid(
                    Location::line(self.path, m.line),
                    "metersPerUnit must be a positive number",
                )),
            },
        }
    }

    /// Notes for unresolved arcs and properties written twice.
    fn composition_warnings(&mut self) {
        let mut notes = Vec::new();
        for (i, prim) in self.stage.prims.iter().enumerate() {
            if !self.stage.in_scene(i) && prim.defined {
                continue;
            }
            if !prim.arcs.is_empty() {
                notes.push((
                    prim.path.clone(),
                    true,
                    format!(
                        "{} not resolved (rigport reads a single .usda layer): what they bring \
                         is missing",
                        prim.arcs.join(", ")
                    ),
                ));
            }
            for (name, prop) in &prim.props {
                if prop.rewritten > 0 {
                    notes.push((
                        prim.path.clone(),
                        false,
                        format!(
                            "{name} is written {} times; the last statement (line {}) wins",
                            prop.rewritten + 1,
                            prop.line
                        ),
                    ));
                }
            }
        }
        for (path, incomplete, message) in notes {
            if incomplete {
                self.incomplete(&path, message);
            } else {
                self.note(&path, message);
            }
        }
    }

    /// A note on a missing thing that may live behind an unresolved arc on `index` or an
    /// ancestor.
    fn behind_arc(&self, index: usize) -> String {
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
    fn behind_arc_path(&self, path: &str) -> String {
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

    /// The Skeleton a skinnable prim binds to (`skel:skeleton` on it or the nearest
    /// ancestor, UsdSkelBindingAPI's inherited binding).
    fn bound_skeleton(&self, index: usize) -> Result<usize, ImportError> {
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

    /// The value of attribute `name` of `prim`, read without time (see
    /// [`values::static_value`]), with a note when only time samples exist.
    fn static_attr(&mut self, prim: &Prim<'l>, name: &str) -> Option<(&'l Value, Prop<'l>)> {
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

    fn skeleton(&mut self, index: usize) -> Result<(Skeleton, SkelData), ImportError> {
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

    fn prim(&self, index: usize) -> &Prim<'l> {
        // Indices come from iterating `self.stage.prims`.
        &self.stage.prims[index]
    }

    /// A `matrix4d[]` of `n` finite matrices, as column-vector matrices.
    fn matrix_list(
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

    fn int_list(&self, prim: &Prim<'l>, name: &str) -> Result<Option<Vec<i64>>, ImportError> {
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

    /// A primvar of `N`-tuples (`N = 1` reads plain numbers) with its indices.
    fn primvar<const N: usize>(
        &self,
        prim: &Prim<'l>,
        name: &str,
        default_interp: Interp,
    ) -> Result<Option<Primvar<N>>, ImportError> {
        let Some(prop) = prim.prop(name) else {
            return Ok(None);
        };
        let Some((value, _)) = values::static_value(prop) else {
            return Ok(None);
        };
        let half = prop.type_name.is_some_and(is_half_type);
        let mut values: Vec<[f64; N]> = if N == 1 {
            numbers(value).map(|v| {
                v.into_iter()
                    .map(|x| {
                        let mut a = [0.0; N];
                        if let Some(s) = a.first_mut() {
                            *s = x;
                        }
                        a
                    })
                    .collect()
            })
        } else {
            tuples::<N>(value)
        }
        .ok_or_else(|| {
            self.err_at(
                prop.line,
                &prim.path,
                format!(
                    "{name} must be an array of {N}-component values, not {}",
                    prop.type_name.unwrap_or("?")
                ),
            )
        })?;
        if half {
            for v in &mut values {
                for x in v.iter_mut() {
                    *x = f64::from(round_to_half(*x as f32));
                }
            }
        }
        if values.iter().flatten().any(|x| !x.is_finite()) {
            return Err(self.err(&prim.path, format!("{name} holds a non-finite value")));
        }
        let interp = match prop.meta("interpolation").map(token) {
            None => default_interp,
            Some(Some("constant")) => Interp::Constant,
            Some(Some("uniform")) => Interp::Uniform,
            Some(Some("vertex" | "varying")) => Interp::Vertex,
            Some(Some("faceVarying")) => Interp::FaceVarying,
            Some(other) => {
                return Err(self.err(
                    &prim.path,
                    format!(
                        "{name} has an unknown interpolation {:?}",
                        other.unwrap_or("?")
                    ),
                ))
            }
        };
        let indices = match self.int_list(prim, &format!("{name}:indices"))? {
            None => None,
            Some(ix) => Some(
                ix.into_iter()
                    .map(|i| {
                        usize::try_from(i)
                            .ok()
                            .filter(|&i| i < values.len())
                            .ok_or_else(|| {
                                self.err(
                                    &prim.path,
                                    format!(
                                        "{name}:indices holds {i}, out of range for {} values",
                                        values.len()
                                    ),
                                )
                            })
                    })
                    .collect::<Result<Vec<_>, _>>()?,
            ),
        };
        Ok(Some(Primvar {
            values,
            indices,
            interp,
        }))
    }

    /// Checks that a primvar has one element per interpolation site.
    fn check_primvar<const N: usize>(
        &self,
        prim: &str,
        name: &str,
        pv: &Primvar<N>,
        faces: usize,
        points: usize,
        corners: usize,
    ) -> Result<(), ImportError> {
        let (expected, what) = match pv.interp {
            Interp::Constant => (1, "constant interpolation"),
            Interp::Uniform => (faces, "faces (uniform interpolation)"),
            Interp::Vertex => (points, "points (vertex interpolation)"),
            Interp::FaceVarying => (corners, "face corners (faceVarying interpolation)"),
        };
        let found = pv.indices.as_ref().map_or(pv.values.len(), Vec::len);
        if found != expected {
            return Err(self.err(
                prim,
                format!("{name} has {found} elements for {expected} {what}"),
            ));
        }
        Ok(())
    }

    /// Builds one Mesh prim (and its skin when `skel` is given).
    fn mesh(
        &mut self,
        index: usize,
        skel: Option<&SkelData>,
    ) -> Result<Option<(Mesh, Option<SkinBinding>)>, ImportError> {
        let prim = self.prim(index).clone();
        let path = prim.path.clone();
        let Some((points_value, points_prop)) = self.static_attr(&prim, "points") else {
            if !self.behind_arc(index).is_empty() && skel.is_some() {
                return Err(self.err(
                    &path,
                    format!("the bound Mesh has no points{}", self.behind_arc(index)),
                ));
            }
            self.incomplete(&path, "a Mesh without points: not imported");
            return Ok(None);
        };
        let half = points_prop.type_name.is_some_and(is_half_type);
        let mut points = tuples::<3>(points_value)
            .ok_or_else(|| self.err_at(points_prop.line, &path, "points must be a point3f[]"))?;
        if half {
            for p in &mut points {
                for x in p.iter_mut() {
                    *x = f64::from(round_to_half(*x as f32));
                }
            }
        }
        if points.iter().flatten().any(|x| !x.is_finite()) {
            return Err(self.err(&path, "points holds a non-finite value"));
        }
        let n_points = points.len();
        let counts = self.int_list(&prim, "faceVertexCounts")?;
        let indices = self.int_list(&prim, "faceVertexIndices")?;
        let (counts, indices) = match (counts, indices) {
            (Some(c), Some(i)) => (c, i),
            (None, None) => (Vec::new(), Vec::new()),
            (Some(_), None) => {
                return Err(self.err(&path, "faceVertexCounts without faceVertexIndices"))
            }
            (None, Some(_)) => {
                return Err(self.err(&path, "faceVertexIndices without faceVertexCounts"))
            }
        };
        let mut total = 0usize;
        for (f, &c) in counts.iter().enumerate() {
            let c = usize::try_from(c)
                .map_err(|_| self.err(&path, format!("faceVertexCounts[{f}] is negative ({c})")))?;
            total = total.saturating_add(c);
        }
        if total != indices.len() {
            return Err(self.err(
                &path,
                format!(
                    "faceVertexCounts add up to {total} but faceVertexIndices has {} entries",
                    indices.len()
                ),
            ));
        }
        let corner_points: Vec<usize> = indices
            .iter()
            .enumerate()
            .map(|(k, &i)| {
                usize::try_from(i).ok().filter(|&i| i < n_points).ok_or_else(|| {
                    self.err(
                        &path,
                        format!("faceVertexIndices[{k}] = {i} is out of range for {n_points} points"),
                    )
                })
            })
            .collect::<Result<_, _>>()?;
        let n_faces = counts.len();
        let n_corners = corner_points.len();
        let left_handed = match prim.prop("orientation").and_then(values::static_value) {
            Some((v, _)) => token(v) == Some("leftHanded"),
            None => false,
        };

        let normals_name = if prim.prop("primvars:normals").is_some() {
            "primvars:normals"
        } else {
            "normals"
        };
        // UsdGeomPointBased: `normals` interpolates per vertex unless it says otherwise;
        // a primvar's fallback interpolation is constant.
        let normals_default = if normals_name == "normals" {
            Interp::Vertex
        } else {
            Interp::Constant
        };
        let normals = self.primvar::<3>(&prim, normals_name, normals_default)?;
        let uv_name = if prim.prop("primvars:st").is_some() {
            Some("primvars:st".to_string())
        } else {
            prim.props
                .iter()
                .find(|(n, p)| {
                    n.starts_with("primvars:")
                        && !n.ends_with(":indices")
                        && p.type_name.is_some_and(|t| t.starts_with("texCoord2"))
                })
                .map(|(n, _)| n.to_string())
        };
        let uvs = match &uv_name {
            Some(name) => self.primvar::<2>(&prim, name, Interp::Constant)?,
            None => None,
        };
        if let Some(pv) = &normals {
            self.check_primvar(&path, normals_name, pv, n_faces, n_points, n_corners)?;
        }
        if let (Some(pv), Some(name)) = (&uvs, &uv_name) {
            self.check_primvar(&path, name, pv, n_faces, n_points, n_corners)?;
        }

        // geomBindTransform: into skeleton space at bind time.
        let geom_bind = match (skel, prim.prop("primvars:skel:geomBindTransform")) {
            (Some(_), Some(prop)) => match values::static_value(prop) {
                Some((v, _)) => {
                    let m = matrix(v).map(|r| usd_matrix(&r)).ok_or_else(|| {
                        self.err_at(
                            prop.line,
                            &path,
                            "primvars:skel:geomBindTransform must be a matrix4d",
                        )
                    })?;
                    if !m.is_finite() {
                        return Err(
                            self.err(&path, "primvars:skel:geomBindTransform is not finite")
                        );
                    }
                    m
                }
                None => DMat4::IDENTITY,
            },
            _ => DMat4::IDENTITY,
        };
        let normal_matrix = DMat3::from_mat4(geom_bind).inverse().transpose();
        let to_normal = |n: [f64; 3]| -> Vec3 {
            let v = if normal_matrix.is_finite() {
                normal_matrix * DVec3::from_array(n)
            } else {
                DVec3::from_array(n)
            };
            v.try_normalize().map_or(Vec3::Y, |v| v.as_vec3())
        };
        let to_uv = |t: [f64; 2]| Vec2::new(t[0] as f32, (1.0 - t[1]) as f32);

        // Output vertices: points first, then splits.
        let mut positions: Vec<Vec3> = points
            .iter()
            .map(|p| geom_bind.transform_point3(DVec3::from_array(*p)).as_vec3())
            .collect();
        let mut source_vertex: Vec<u32> = (0..n_points as u32).collect();
        let mut out_normals: Option<Vec<Vec3>> = normals.as_ref().map(|_| vec![Vec3::Y; n_points]);
        let mut out_uvs: Option<Vec<Vec2>> = uvs.as_ref().map(|_| vec![Vec2::ZERO; n_points]);
        let per_point = normals.as_ref().is_none_or(Primvar::per_point)
            && uvs.as_ref().is_none_or(Primvar::per_point);
        let mut corner_vertex: Vec<u32> = Vec::with_capacity(n_corners);
        {
            // The face of each corner.
            let mut face_of = Vec::with_capacity(n_corners);
            for (f, &c) in counts.iter().enumerate() {
                face_of.extend(std::iter::repeat_n(f, c as usize));
            }
            let attrs = |k: usize, p: usize| {
                let f = face_of.get(k).copied().unwrap_or(0);
                (
                    normals.as_ref().map(|pv| to_normal(pv.at(f, k, p))),
                    uvs.as_ref().map(|pv| to_uv(pv.at(f, k, p))),
                )
            };
            if per_point {
                for p in 0..n_points {
                    let (n, t) = attrs(0, p);
                    if let (Some(out), Some(n)) = (&mut out_normals, n) {
                        out[p] = n;
                    }
                    if let (Some(out), Some(t)) = (&mut out_uvs, t) {
                        out[p] = t;
                    }
                }
                corner_vertex.extend(corner_points.iter().map(|&p| p as u32));
            } else {
                let mut assigned = vec![false; n_points];
                let mut splits: HashMap<(usize, [u32; 5]), u32> = HashMap::new();
                let bits = |n: Option<Vec3>, t: Option<Vec2>| {
                    let n = n.unwrap_or(Vec3::ZERO);
                    let t = t.unwrap_or(Vec2::ZERO);
                    [n.x, n.y, n.z, t.x, t.y].map(f32::to_bits)
                };
                for (k, &p) in corner_points.iter().enumerate() {
                    let (n, t) = attrs(k, p);
                    if !assigned[p] {
                        assigned[p] = true;
                        if let (Some(out), Some(n)) = (&mut out_normals, n) {
                            out[p] = n;
                        }
                        if let (Some(out), Some(t)) = (&mut out_uvs, t) {
                            out[p] = t;
                        }
                        corner_vertex.push(p as u32);
                        continue;
                    }
                    let have = bits(
                        out_normals.as_ref().map(|o| o[p]),
                        out_uvs.as_ref().map(|o| o[p]),
                    );
                    let want = bits(n, t);
                    if have == want {
                        corner_vertex.push(p as u32);
                        continue;
                    }
                    let v = *splits.entry((p, want)).or_insert_with(|| {
                        let v = positions.len() as u32;
                        positions.push(positions[p]);
                        source_vertex.push(p as u32);
                        if let (Some(out), Some(n)) = (&mut out_normals, n) {
                            out.push(n);
                        }
                        if let (Some(out), Some(t)) = (&mut out_uvs, t) {
                            out.push(t);
                        }
                        v
                    });
                    corner_vertex.push(v);
                }
            }
        }
        let mut triangles = Vec::with_capacity(n_corners);
        let mut start = 0usize;
        let mut degenerate = 0usize;
        for &c in &counts {
            let c = c as usize;
            let face = corner_vertex.get(start..start + c).unwrap_or_default();
            start += c;
            if c < 3 {
                degenerate += 1;
                continue;
            }
            for k in 1..c - 1 {
                let (a, b, d) = (face[0], face[k], face[k + 1]);
                triangles.push(if left_handed { [a, d, b] } else { [a, b, d] });
            }
        }
        if degenerate > 0 {
            self.repaired(
                &path,
                format!("{degenerate} face(s) with fewer than 3 vertices skipped"),
            );
        }
        if prim.prop("skel:blendShapes").is_some() || prim.prop("skel:blendShapeTargets").is_some()
        {
            self.incomplete(&path, "blend shapes are not imported");
        }
        let mesh = Mesh {
            name: prim.name.to_string(),
            positions,
            normals: out_normals,
            uvs: out_uvs,
            triangles,
            source_vertex,
            morph_targets: Vec::new(),
            morph_weights: Vec::new(),
            attached_to: None,
        };
        let mut mesh = mesh;
        let skin = match skel {
            Some(skel) => Some(self.skin(index, skel, n_points, &mesh.source_vertex)?),
            None => {
                // UsdSkel ignores a skinned mesh's own transform; a static mesh keeps it:
                // its points go to model space (the skeleton's), which the scene frame
                // places in the stage.
                let (world, animated) = self.world(index)?;
                if !animated.is_empty() {
                    self.incomplete(
                        &path,
                        format!(
                            "a static mesh under time-sampled transforms (xformOp) on {}: \
                             their value at the default time is used",
                            animated.join(", ")
                        ),
                    );
                }
                let m = self.skel_world.inverse() * world;
                if m != DMat4::IDENTITY {
                    for p in &mut mesh.positions {
                        *p = m.transform_point3(p.as_dvec3()).as_vec3();
                    }
                    let n = DMat3::from_mat4(m).inverse().transpose();
                    if let Some(normals) = &mut mesh.normals {
                        for v in normals {
                            *v = (n * v.as_dvec3()).normalize_or_zero().as_vec3();
                        }
                    }
                    if m.determinant() < 0.0 {
                        for t in &mut mesh.triangles {
                            t.swap(1, 2);
                        }
                    }
                }
                None
            }
        };
        Ok(Some((mesh, skin)))
    }

    // -----------------------------------------------------------------------------------
    // Skin
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

    fn skin(
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

    /// Every clip: the bound animation first, then the other SkelAnimations in document
    /// order, then those only found in unselected variants.
    fn clips(&mut self, skel_index: usize, skel: &SkelData) -> Result<Vec<Clip>, ImportError> {
        let bound = self.stage.ancestry(skel_index).find_map(|p| {
            let targets = p.prop("skel:animationSource")?.targets?;
            Some((p.path.clone(), targets.first().cloned()))
        });
        let mut order: Vec<usize> = Vec::new();
        if let Some((owner, Some(target))) = &bound {
            let target = resolve_path(owner, target);
            match self.stage.index(&target) {
                Some(a)
                    if self.stage.in_scene(a)
                        && self.stage.prims.get(a).and_then(|p| p.type_name)
                            == Some("SkelAnimation") =>
                {
                    order.push(a)
                }
                Some(a) => {
                    return Err(self.err(
                        owner,
                        format!(
                            "skel:animationSource targets <{target}>, which is not a defined \
                             SkelAnimation{}",
                            self.behind_arc(a)
                        ),
                    ))
                }
                None => {
                    return Err(self.err(
                        owner,
                        format!(
                            "skel:animationSource targets <{target}>, which does not exist{}",
                            self.behind_arc_path(&target)
                        ),
                    ))
                }
            }
        }
        for i in 0..self.stage.prims.len() {
            if !order.contains(&i)
                && self.stage.in_scene(i)
                && self.stage.prims.get(i).and_then(|p| p.type_name) == Some("SkelAnimation")
            {
                order.push(i);
            }
        }
        let mut clips = Vec::new();
        let mut names: HashMap<String, usize> = HashMap::new();
        for a in order {
            let prim = self.prim(a).clone();
            if let Some(clip) = self.clip(&prim, skel)? {
                clips.push(unique_clip(clip, &mut names));
            }
        }
        // SkelAnimations that only unselected variants define.
        let layer = self.layer;
        let mut alternatives: Vec<(String, String, String)> = Vec::new();
        for (i, prim) in self.stage.prims.iter().enumerate() {
            if !self.stage.in_scene(i) {
                continue;
            }
            for (set, variants) in &prim.variant_sets {
                let chosen = prim
                    .selections
                    .iter()
                    .find(|(s, _)| s == set)
                    .map(|(_, v)| *v);
                for v in variants {
                    if Some(*v) != chosen
                        && variant_defines_animation(&layer.root, &prim.path, set, v)
                    {
                        alternatives.push((prim.path.clone(), set.to_string(), v.to_string()));
                    }
                }
            }
        }
        for (path, set, variant) in alternatives {
            let alt = Stage::compose(&layer.root, Some((&path, &set, &variant)));
            for (i, prim) in alt.prims.iter().enumerate() {
                let known = self
                    .stage
                    .index(&prim.path)
                    .is_some_and(|k| self.stage.in_scene(k));
                if known || prim.type_name != Some("SkelAnimation") || !alt.in_scene(i) {
                    continue;
                }
                let prim = prim.clone();
                if let Some(clip) = self.clip(&prim, skel)? {
                    clips.push(unique_clip(clip, &mut names));
                }
            }
        }
        Ok(clips)
    }

    /// One SkelAnimation as a clip; `None` (with a warning) when UsdSkel would ignore it.
    fn clip(&mut self, prim: &Prim<'l>, skel: &SkelData) -> Result<Option<Clip>, ImportError> {
        let path = prim.path.clone();
        let Some((joints_value, joints_prop)) = self.static_attr(prim, "joints") else {
            self.incomplete(&path, "a SkelAnimation without joints: no clip");
            return Ok(None);
        };
        let anim_tokens = tokens(joints_value)
            .ok_or_else(|| self.err_at(joints_prop.line, &path, "joints must be a token[]"))?;
        let n = anim_tokens.len();
        let translations = self.anim_attr::<3>(prim, "translations", n)?;
        let rotations = self.anim_attr::<4>(prim, "rotations", n)?;
        let scales = self.anim_attr::<3>(prim, "scales", n)?;
        let (Some(translations), Some(rotations), Some(scales)) = (translations, rotations, scales)
        else {
            let missing: Vec<&str> = [
                ("translations", prim.prop("translations")),
                ("rotations", prim.prop("rotations")),
                ("scales", prim.prop("scales")),
            ]
            .iter()
            .filter(|(_, p)| p.and_then(values::static_value).is_none())
            .map(|(n, _)| *n)
            .collect();
            self.incomplete(
                &path,
                format!(
                    "no {}: UsdSkel ignores a SkelAnimation without translations, rotations and \
                     scales, so it is not imported{}",
                    missing.join(" or "),
                    self.behind_arc_path(&format!("{path}/x"))
                ),
            );
            return Ok(None);
        };
        if prim.prop("blendShapeWeights").is_some() {
            self.incomplete(&path, "blendShapeWeights are not imported");
        }
        let map: Vec<Option<usize>> = anim_tokens
            .iter()
            .map(|t| skel.tokens.iter().position(|s| s == t))
            .collect();
        let unknown: Vec<&str> = anim_tokens
            .iter()
            .zip(&map)
            .filter(|(_, m)| m.is_none())
            .map(|(t, _)| *t)
            .collect();
        if !unknown.is_empty() {
            self.incomplete(
                &path,
                format!(
                    "{} joint(s) not in the Skeleton <{}> ignored: {}",
                    unknown.len(),
                    skel.path,
                    unknown.join(", ")
                ),
            );
        }
        // Key times: constant attributes get one key at the first sampled time.
        let first = [&translations.times, &rotations.times, &scales.times]
            .iter()
            .filter_map(|t| t.as_ref()?.first().copied())
            .fold(None, |acc: Option<f64>, t| {
                Some(acc.map_or(t, |a| a.min(t)))
            });
        let start = first.unwrap_or(0.0);
        let shift = if start < 0.0 { -start } else { 0.0 };
        if shift > 0.0 {
            self.warnings.push(Warning::Repaired {
                location: self.location(&path),
                message: format!(
                    "samples start at time code {start}: the clip is shifted by {} s to start at 0",
                    shift / self.tcps
                ),
            });
        }
        let seconds = |tc: f64| ((tc + shift) / self.tcps) as f32;
        let key_times = |times: &Option<Vec<f64>>| -> Vec<f32> {
            match times {
                Some(t) => t.iter().map(|&tc| seconds(tc)).collect(),
                None => vec![seconds(start)],
            }
        };
        let mut tracks = Vec::new();
        for (a, joint) in map.iter().enumerate() {
            let Some(j) = joint.map(|j| JointIndex(j as u32)) else {
                continue;
            };
            let t_times = key_times(&translations.times);
            let r_times = key_times(&rotations.times);
            let s_times = key_times(&scales.times);
            let mut t_vals = Vec::with_capacity(t_times.len() * 3);
            for sample in &translations.values {
                let v = sample.get(a).copied().unwrap_or_default();
                t_vals.extend(v.iter().map(|&x| x as f32));
            }
            let mut r_vals = Vec::with_capacity(r_times.len() * 4);
            let mut prev: Option<Quat> = None;
            for sample in &rotations.values {
                let [w, x, y, z] = sample.get(a).copied().unwrap_or([1.0, 0.0, 0.0, 0.0]);
                let q = glam::DQuat::from_xyzw(x, y, z, w);
                let len = q.length();
                if len.is_nan() || len <= 1e-12 {
                    return Err(self.err(
                        &path,
                        format!(
                            "rotations of joint {:?} hold a zero quaternion",
                            anim_tokens.get(a).copied().unwrap_or("")
                        ),
                    ));
                }
                let mut q = (q / len).as_quat();
                // Sign-continuous: the shorter way from the previous key.
                if prev.is_some_and(|p| p.dot(q) < 0.0) {
                    q = -q;
                }
                prev = Some(q);
                r_vals.extend(q.to_array());
            }
            let mut s_vals = Vec::with_capacity(s_times.len() * 3);
            for sample in &scales.values {
                let v = sample.get(a).copied().unwrap_or([1.0; 3]);
                s_vals.extend(v.iter().map(|&x| x as f32));
            }
            for (target, times, values) in [
                (TrackTarget::Translation(j), t_times, t_vals),
                (TrackTarget::Rotation(j), r_times, r_vals),
                (TrackTarget::Scale(j), s_times, s_vals),
            ] {
                let (times, values) = dedup_keys(times, values);
                tracks.push(Track {
                    target,
                    interpolation: Interpolation::Linear,
                    times,
                    values,
                });
            }
        }
        Ok(Some(Clip {
            name: prim.name.to_string(),
            tracks,
        }))
    }

    /// A SkelAnimation array attribute: its samples (each `n` long) or its default.
    /// `None` when it has no value.
    fn anim_attr<const N: usize>(
        &self,
        prim: &Prim<'l>,
        name: &str,
        n: usize,
    ) -> Result<Option<AnimAttr<N>>, ImportError> {
        let Some(prop) = prim.prop(name) else {
            return Ok(None);
        };
        let half = prop.type_name.is_some_and(is_half_type);
        let read = |v: &Value, at: Option<f64>| -> Result<Vec<[f64; N]>, ImportError> {
            let when = at.map_or(String::new(), |t| format!(" at time {t}"));
            let mut vals = tuples::<N>(v).ok_or_else(|| {
                self.err_at(
                    prop.line,
                    &prim.path,
                    format!("{name}{when} must be an array of {N}-component values"),
                )
            })?;
            if vals.len() != n {
                return Err(self.err(
                    &prim.path,
                    format!("{name}{when} has {} values for {n} joints", vals.len()),
                ));
            }
            if half {
                for v in &mut vals {
                    for x in v.iter_mut() {
                        *x = f64::from(round_to_half(*x as f32));
                    }
                }
            }
            if vals.iter().flatten().any(|x| !x.is_finite()) {
                return Err(self.err(&prim.path, format!("{name}{when} holds a non-finite value")));
            }
            Ok(vals)
        };
        if let Some(samples) = &prop.samples {
            let live: Vec<&(f64, &Value)> =
                samples.iter().filter(|(_, v)| **v != Value::None).collect();
            if !live.is_empty() {
                let mut times = Vec::with_capacity(live.len());
                let mut values = Vec::with_capacity(live.len());
                for (t, v) in live {
                    if !t.is_finite() {
                        return Err(
                            self.err(&prim.path, format!("{name} has a non-finite time code"))
                        );
                    }
                    times.push(*t);
                    values.push(read(v, Some(*t))?);
                }
                return Ok(Some(AnimAttr {
                    times: Some(times),
                    values,
                }));
            }
        }
        match prop.default {
            Some(v) if *v != Value::None => Ok(Some(AnimAttr {
                times: None,
                values: vec![read(v, None)?],
            })),
            _ => Ok(None),
        }
    }

    /// The world transform of prim `index` at the default time (its ancestors' and its
    /// own `xformOp`s, honouring `!resetXformStack!`), and the paths of prims on the way
    /// whose ops are time-sampled.
    fn world(&self, index: usize) -> Result<(DMat4, Vec<String>), ImportError> {
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

/// An animation attribute: sample times (time codes; `None` for a default value) and
/// one array per sample.
struct AnimAttr<const N: usize> {
    times: Option<Vec<f64>>,
    values: Vec<Vec<[f64; N]>>,
}

/// Drops keys whose `f32` time equals the previous one (distinct time codes that round to
/// the same second), keeping the later value, so times stay strictly increasing.
fn dedup_keys(times: Vec<f32>, values: Vec<f32>) -> (Vec<f32>, Vec<f32>) {
    let c = values.len().checked_div(times.len()).unwrap_or(0);
    if times.windows(2).all(|w| w[0] < w[1]) || c == 0 {
        return (times, values);
    }
    let mut out_t: Vec<f32> = Vec::with_capacity(times.len());
    let mut out_v: Vec<f32> = Vec::with_capacity(values.len());
    for (k, &t) in times.iter().enumerate() {
        let v = values.get(k * c..(k + 1) * c).unwrap_or_default();
        if out_t.last().is_some_and(|&l| l >= t) {
            out_v.truncate(out_v.len() - c);
            out_t.pop();
        }
        out_t.push(t);
        out_v.extend_from_slice(v);
    }
    (out_t, out_v)
}

/// Renames a clip `name_2`, `name_3`, ... when its name is taken.
fn unique_clip(mut clip: Clip, names: &mut HashMap<String, usize>) -> Clip {
    let base = clip.name.clone();
    let mut k = 1;
    while names.contains_key(&clip.name) {
        k += 1;
        clip.name = format!("{base}_{k}");
    }
    names.insert(clip.name.clone(), 1);
    clip
}

/// Whether the prim has UsdSkel influence primvars.
fn has_skin_primvars(prim: &Prim<'_>) -> bool {
    ["primvars:skel:jointIndices", "primvars:skel:jointWeights"]
        .iter()
        .any(|n| prim.prop(n).and_then(values::static_value).is_some())
}

/// Resolves a relationship target written relative to the prim that owns the property
/// (`<Animation>`, `<../Skel>`, `<.>`) to an absolute prim path; a property part
/// (`</A.b>`) is dropped.
fn resolve_path(owner: &str, target: &str) -> String {
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

/// Whether variant `variant` of set `set` on the prim at `prim_path` defines a
/// SkelAnimation (found by walking the layer's specs, so unselected variants are only
/// composed when they hold one).
fn variant_defines_animation(
    root: &parse::PrimBody,
    prim_path: &str,
    set: &str,
    variant: &str,
) -> bool {
    fn defines(body: &parse::PrimBody) -> bool {
        body.children
            .iter()
            .any(|c| c.type_name.as_deref() == Some("SkelAnimation") || defines(&c.body))
            || body
                .variant_sets
                .iter()
                .any(|s| s.variants.iter().any(|(_, _, b)| defines(b)))
    }
    fn find<'a>(body: &'a parse::PrimBody, rest: &[&str], out: &mut Vec<&'a PrimSpec>) {
        let Some((first, tail)) = rest.split_first() else {
            return;
        };
        let mut bodies = vec![body];
        // Prims may also be defined inside variants of the parent.
        let mut k = 0;
        while let Some(b) = bodies.get(k).copied() {
            k += 1;
            for s in &b.variant_sets {
                for (_, _, vb) in &s.variants {
                    bodies.push(vb);
                }
            }
        }
        for b in bodies {
            for c in b.children.iter().filter(|c| c.name == *first) {
                if tail.is_empty() {
                    out.push(c);
                } else {
                    find(&c.body, tail, out);
                }
            }
        }
    }
    let parts: Vec<&str> = prim_path.split('/').filter(|s| !s.is_empty()).collect();
    let mut specs = Vec::new();
    find(root, &parts, &mut specs);
    specs.iter().any(|spec| {
        spec.body.variant_sets.iter().any(|s| {
            s.name == set
                && s.variants
                    .iter()
                    .any(|(v, _, b)| v == variant && defines(b))
        })
    })
}

/// A matrix as TRS (shear is lost).
fn trs_of(m: &DMat4) -> Transform {
    let (scale, rotation, translation) = m.to_scale_rotation_translation();
    Transform {
        translation: translation.as_vec3(),
        rotation: rotation.normalize().as_quat(),
        scale: scale.as_vec3(),
    }
}

/// Whether `t` reproduces `m` (no shear lost).
fn matches_trs(m: &DMat4, t: &Transform) -> bool {
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
