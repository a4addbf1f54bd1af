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
//!   model space through its world transform. `model_to_scene` is the value at the
//!   default time (else the first sample); time-sampled ops on the Skeleton or above it
//!   become root motion, tracks of the root joints sampled at every time code between
//!   the ops' samples, in every clip (a clip of their own without a SkelAnimation; see
//!   `root_motion.rs`), with a [`Warning::Note`]. A static mesh under time-sampled ops
//!   keeps its points in its own space and is attached to a root joint of its own, named
//!   after it, whose tracks are its transform in model space, sampled the same way (a
//!   clip of their own when there is no SkelAnimation), with a [`Warning::Note`].
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
//! - **Blend shapes** (`skel:blendShapes` + `skel:blendShapeTargets` on a Mesh, skinned or
//!   not): each `BlendShape` (`offsets`, `normalOffsets`, sparse `pointIndices`) is a
//!   morph target named after its channel, its inbetweens (`inbetweens:<name>`, `weight`
//!   metadata) further targets `<channel>_<name>`; offsets take the linear part of the
//!   points' transform (geomBindTransform, or a static mesh's world transform; normal
//!   offsets the same, exact for rigid transforms), and go to every vertex split from a
//!   point. Normal offsets need per-point (`vertex`) normals, as UsdSkel's; otherwise they
//!   are dropped with a warning. A SkelAnimation's `blendShapes` / `blendShapeWeights`
//!   become a morph-weight track per mesh (channels matched by token, missing ones 0):
//!   UsdSkel's sub-shape weights (null shape at 0, primary at 1, inbetweens at their
//!   weights, linear between neighbours, the end segments extended) are computed at every
//!   sample and at every time the linearly interpolated channel weight crosses an inner
//!   sub-shape weight, so the LINEAR track equals UsdSkel at every time (`blend.rs`). An
//!   animation with blend-shape weights but no joint transforms, and a Skeleton without
//!   joints, import (the skeleton stays at rest).
//! - **Implicit surfaces** (`Cube`, `Sphere`, `Cylinder`, `Capsule`, `Cone`) are
//!   tessellated (`implicit.rs`: the schemas' sizes and `axis`, 32 segments around, 16
//!   rings pole to pole, flat faces with their own points) and imported like Meshes:
//!   skinned (Pixar's bake tests bind them with constant influences, which UsdSkel applies
//!   as a rigid transform: the tessellation follows it exactly), or static. Other
//!   skinnable prims (`BasisCurves`, `Points`) are left out with a warning naming the prim.
//! - **Polygons**: the face sizes are kept in [`Mesh::polygons`] (the triangles are their
//!   fans), so the USD writer gives the source's faces back.
//! - **Time-sampled points** (a point cache, a baked simulation) become one morph target
//!   per sample and a weight track in every clip that plays them as USD interpolates them
//!   (`points.rs`), with a [`Warning::Note`].
//!
//! # Errors
//! Syntax errors carry `file:line:column`. UsdSkel errors name the prim path:
//! `arm.usda: </Root/Arm/Mesh>: primvars:skel:jointIndices has elementSize 3 but 7 values
//! for 3 points`: bad `elementSize` or interpolation, joint index out of range, a bound mesh
//! without a skeleton, weights and indices of different lengths, negative or non-finite
//! values, joints not parents-first, animation arrays of the wrong size, attributes of the
//! wrong type.
//!
//! # Files
//! Reading a layer is `rigport-usd`'s: the text parser, the crate-file (`.usdc`) and
//! package (`.usdz`) readers, one layer composed (`stage`), typed values (`values`).
//! Building the asset: `importer.rs` (the `Importer` state and shared helpers),
//! `assemble.rs` (`Importer::run`), `metadata.rs` (layer metadata, composition warnings),
//! `xform.rs` (transforms), `skeleton.rs`, `skin.rs` (bindings, influence primvars),
//! `blend.rs` (blend shapes and their weights; `shapes.rs` the channels they share with
//! the importer state), `mesh.rs` (topology, primvars, static meshes), `anim.rs`
//! (SkelAnimations to clips), `root_motion.rs` (animated transforms above the skeleton)
//! and `implicit.rs` (implicit surfaces as polygons); `crate_tests.rs` checks the import
//! of binary and packaged layers against their text.
//!
//! [`Warning::Incomplete`]: rigport_model::Warning::Incomplete
//! [`Joint`]: rigport_model::Joint
//! [`Warning::Repaired`]: rigport_model::Warning::Repaired
//! [`Joint::rest_local`]: rigport_model::Joint::rest_local
//! [`SkinBinding::inv_bind`]: rigport_model::SkinBinding::inv_bind
//! [`Mesh`]: rigport_model::Mesh
//! [`SkinBinding`]: rigport_model::SkinBinding
//! [`Clip`]: rigport_model::Clip
//! [`Asset::frame`]: rigport_model::Asset::frame
//! [`Asset::meters_per_unit`]: rigport_model::Asset::meters_per_unit
//! [`SceneFrame::model_to_scene`]: rigport_model::SceneFrame::model_to_scene
//! [`SceneFrame::up_axis`]: rigport_model::SceneFrame::up_axis
//! [`Warning::Note`]: rigport_model::Warning::Note
//! [`Mesh::source_vertex`]: rigport_model::Mesh::source_vertex
//! [`SkinBinding::method`]: rigport_model::SkinBinding::method
//! [`Mesh::polygons`]: rigport_model::Mesh::polygons
//! [`Asset::validate`]: rigport_model::Asset::validate

mod anim;
mod assemble;
mod blend;
#[cfg(test)]
mod crate_tests;
mod implicit;
mod importer;
mod material;
mod mesh;
mod metadata;
mod points;
mod root_motion;
mod shapes;
mod skeleton;
mod skin;
#[cfg(test)]
mod tests;
mod xform;

// The generic layer code lives in `rigport-usd`; these names keep the mapping's paths.
use rigport_usd::{layer, stage, usdz, values};

use std::path::Path;

use glam::DMat4;
use rigport_model::UpAxis;

use self::importer::Importer;
pub use self::metadata::{DEFAULT_METERS_PER_UNIT, DEFAULT_TIME_CODES_PER_SECOND};
use self::stage::Stage;
use crate::{read_file, ImportError, Imported, Problem};

/// Imports a `.usda` file.
///
/// See the module docs for what is read and how it maps onto the model.
///
/// # Errors
/// The file cannot be read or is not UTF-8; a syntax error (at its `file:line:column`);
/// invalid UsdSkel data (naming the prim path); the resulting asset fails
/// [`Asset::validate`](rigport_model::Asset::validate).
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
        mesh_shapes: Vec::new(),
        package: usdz::Package::open(bytes, path)?,
    };
    let asset = importer.run()?;
    Ok(Imported {
        asset,
        warnings: importer.warnings,
    })
}

impl From<rigport_usd::UsdError> for ImportError {
    /// The same location (one type: [`rigport_location::Location`]) and problem.
    fn from(e: rigport_usd::UsdError) -> Self {
        let problem = match e.problem {
            rigport_usd::Problem::Empty => Problem::Empty,
            rigport_usd::Problem::Syntax { expected, found } => Problem::Syntax { expected, found },
            rigport_usd::Problem::Invalid(m) => Problem::Invalid(m),
            rigport_usd::Problem::Truncated(m) => Problem::Truncated(m),
            p => Problem::Usd(p),
        };
        ImportError {
            location: e.location,
            problem,
        }
    }
}
