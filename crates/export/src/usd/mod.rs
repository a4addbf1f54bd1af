//! Asset -> a USD stage with UsdSkel, described once to a `rigport-usd`
//! [`LayerSink`](rigport_usd::sink::LayerSink): printed as text (`.usda`) by its
//! [`UsdaPrinter`], or built as a typed [`Layer`](rigport_usd::Layer) by its
//! [`LayerBuilder`] and written as a crate file (`.usdc`) or a package (`.usdz`, with the
//! textures; `encode.rs`). No text is parsed back: the layer holds the numbers themselves.
//!
//! What the stage holds (`<root>` is the asset name made an identifier, `rig` when empty):
//! - layer metadata: `defaultPrim = "<root>"`, `upAxis` (the asset's
//!   [`frame`](rigport_model::Asset::frame) up axis, or [`UsdOptions::up_axis`]),
//!   `metersPerUnit` (the asset's [`meters_per_unit`](rigport_model::Asset::meters_per_unit);
//!   **1 when unknown**, the same assumption the glTF exporter makes, since glTF's unit is
//!   the metre, rather than USD's fallback of 0.01; or [`UsdOptions::meters_per_unit`]),
//!   and with clips `timeCodesPerSecond`, `startTimeCode`, `endTimeCode` (see "Time"
//!   below);
//! - the data stays in model space (the skeleton's): the root prim carries
//!   `matrix4d xformOp:transform` = the asset's
//!   [`model_to_scene`](rigport_model::SceneFrame::model_to_scene), preceded by the
//!   up-axis rotation and unit scale when the options ask for another frame; nothing is
//!   authored when that is the identity;
//! - `def SkelRoot "<root>"` when the asset has joints or morph targets (else an `Xform`
//!   holding plain meshes; morph targets without joints get a Skeleton with no joints,
//!   which drives their blend shapes), with:
//!   - `Skeleton "Skeleton"`: `joints` as path tokens in skeleton order (parents first;
//!     several roots are fine for UsdSkel), names not valid as USD identifiers sanitized and
//!     made unique with a warning; `bindTransforms` in model space (the inverse of the
//!     first skin's inverse bind matrix naming the joint, else the joint's rest model
//!     matrix); `restTransforms` in the parent's space. Matrices are transposed to USD's
//!     row-vector convention and computed in `f64`. A skin whose bind pose disagrees with
//!     these (beyond a common geomBindTransform) gets a second Skeleton prim
//!     `Skeleton_1` with the same joints and animations;
//!   - `Scope "Animations"` with one `SkelAnimation` per clip: `joints` (the joints the clip
//!     animates, in skeleton order; the others, and those whose tracks only hold the rest
//!     value, keep `restTransforms`), `translations` (`float3[]`), `rotations` (`quatf[]`,
//!     written `(w, x, y, z)`), `scales` (`half3[]`, UsdSkel's type: values not
//!     representable in half precision are reported), each with its rest-pose default
//!     value and time samples; `blendShapes` /
//!     `blendShapeWeights` (default: the meshes' default morph weights) when there are
//!     morph targets;
//!   - one `Mesh` per model mesh, in asset order (see below), named after it (sanitized,
//!     unique);
//!   - without clips but with non-zero default morph weights, a `SkelAnimation "rest"`
//!     bound directly, since UsdSkel reads blend-shape weights only from an animation;
//!   - a variant set `clip` on the SkelRoot, one variant per clip named after its
//!     SkelAnimation prim, each binding `skel:animationSource` on the Skeleton(s) and, when
//!     the clips' time ranges differ, carrying its own time range as `customData = { double startTimeCode,
//!     double endTimeCode }` on the SkelRoot (layer metadata cannot vary per variant; the
//!     stage's `startTimeCode`/`endTimeCode` are the selected, first, clip's); the
//!     selection is the first clip. **Other clips are reached by switching the variant**
//!     (usdview: the prim's Variants; Python: `prim.GetVariantSet("clip").SetVariantSelection("idle")`).
//!
//! Each Mesh: `points`, `faceVertexCounts` / `faceVertexIndices` (counter-clockwise, USD's
//! default `rightHanded` orientation: the source's polygons rebuilt from their triangle
//! fans when the model has them, [`Mesh::polygons`](rigport_model::Mesh::polygons), a
//! left-handed source's corners reversed; else the model's triangles), `normals`
//! (computed when the model has none), `extent`, `subdivisionScheme = "none"`,
//! `texCoord2f[] primvars:st` (`t = 1 - v`, since the model's UVs have glTF's top-left
//! origin and USD's bottom-left). Points are the source's vertices: vertices split on
//! seams (face-varying normals or UVs) are merged back through
//! [`Mesh::source_vertex`](rigport_model::Mesh::source_vertex) when the copies agree on
//! position, influences and morph deltas, and normals and `st` are then `faceVarying`
//! where a point's copies differ (else `vertex`), so a USD -> USD conversion keeps the
//! point count and point-indexed data; when they cannot be merged, the vertices are the
//! points and `int[] primvars:rigport:sourceVertex` (vertex) maps them to the source
//! vertices, so a checker can compare with `rigport eval` dumps. Bound
//! meshes apply `SkelBindingAPI` and relate `skel:skeleton`:
//! - skinned: `primvars:skel:jointIndices` / `jointWeights`, vertex interpolation,
//!   `elementSize` = the most influences on one point (no limit; rows zero-padded with
//!   index 0 weight 0), indices into the Skeleton's `joints`, weights merged per joint,
//!   noise below 1e-6 of the row dropped, sorted, renormalized (reported when a row's sum
//!   was off); a point without influence is bound to the skin's root joint (reported);
//!   `primvars:skel:geomBindTransform` (identity unless the skin needs one); with
//!   [`SkinningMethod::Dqs`] `uniform token primvars:skel:skinningMethod = "dualQuaternion"`;
//! - attached to a joint ([`Mesh::attached_to`](rigport_model::Mesh::attached_to)): points
//!   stay in the joint's space, a rigid binding (`jointIndices = [j]`, `jointWeights =
//!   [1]`, constant interpolation, `elementSize = 1`) with `geomBindTransform` = the
//!   joint's bind matrix, so the mesh follows the joint exactly; except when that joint
//!   is a root without children that no skin uses and the asset has at most one clip (a
//!   USD source's animated static mesh, a glTF node animation): then the Mesh prim is not
//!   bound and carries the joint's transform as its own `xformOp:translate` / `orient` /
//!   `scale`, time-sampled at the clip's time codes (the joint stays in the Skeleton,
//!   driving nothing);
//! - morph targets: `BlendShape` children (`offsets`, `normalOffsets`, `pointIndices` when
//!   sparse), `skel:blendShapes` / `skel:blendShapeTargets`; an unskinned mesh with morph
//!   targets is bound for its blend shapes only. A USD source's inbetweens arrive as
//!   further morph targets whose weight tracks are keyed at every inbetween crossing
//!   (see the importer), so they are written as plain BlendShapes that UsdSkel evaluates
//!   like the source at every time. With [`UsdOptions::morphs_as_points`] morph targets are
//!   written as `points.timeSamples` instead (no binding).
//!
//! # Time
//! `timeCodesPerSecond` comes from the first clip's key times: when three or more keys are
//! evenly spaced at 24 or more per second, that rate (`1 / spacing`, an integer when within
//! `f32` noise of one; BVH's `Frame Time: 0.0333333` gives 30.00003 so key k is time code k
//! exactly); else the rate of the smallest key interval refined over the clip's span when
//! it is `n/k` (k <= 8) within `f32` noise (a reduced clip at 37.5 keys/s gets 37.5), then
//! the rate the smallest key interval suggests rounded, 24, 25, 30, 48,
//! 50, 60, 100, 120, 240 (and for sparse keys a multiple of theirs from 24 up) that puts
//! every key within 1e-3 frames of a frame; else 1000 (millisecond time codes); 24 (USD's
//! default) when the first clip has fewer than two keys. Every clip is sampled at time code
//! = seconds × that rate, snapped to the integer when within 1e-3 frames (`check_usd.py`
//! maps dump times the same way), at every key time of the clip, all three joint
//! attributes at every time. Between samples USD interpolates linearly (quaternions: slerp),
//! as rigport's LINEAR tracks do; clips with STEP or CUBICSPLINE tracks are also sampled at
//! every frame of that rate (30 fps when no rate was found) between their first and last
//! key, and this is reported. The sampler is the exporter's own (glTF semantics, rotation
//! keys normalized and sign-continuous as the glTF exporter writes them); unanimated
//! channels take the rest pose. SkelAnimation `scales` are `half3[]` in UsdSkel's schema:
//! scales that half precision cannot hold (1.2 becomes 1.2001953) are rounded and reported.
//!
//! Output is deterministic: the same asset and options give the same bytes (fixed order,
//! shortest round-trip number formatting, no hash order, no time stamps).
//!
//! ```
//! use rigport_export::{to_usda, UsdOptions};
//! use rigport_model::{glam::Vec3, Asset, Mesh};
//!
//! let asset = Asset {
//!     name: "tri".into(),
//!     meshes: vec![Mesh {
//!         positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
//!         triangles: vec![[0, 1, 2]],
//!         source_vertex: vec![0, 1, 2],
//!         ..Default::default()
//!     }],
//!     ..Default::default()
//! };
//! let out = to_usda(&asset, &UsdOptions::default())?;
//! assert!(out.text.starts_with("#usda 1.0\n"));
//! assert!(out.text.contains("def Xform \"tri\""));
//! assert!(out.text.contains("int[] faceVertexIndices = [0, 1, 2]"));
//! # Ok::<(), rigport_export::ExportError>(())
//! ```

mod anim;
mod encode;
mod material;
mod mesh;
mod names;
mod sampler;
mod skeleton;
mod skin;
mod stage;
#[cfg(test)]
mod tests;
mod text;
mod topology;
mod values;

use std::path::{Path, PathBuf};

use rigport_model::{Asset, OutputFormat, SkinningMethod, UpAxis, Warning};

use self::text::{Finished, Usda};
use crate::ExportError;
use rigport_atomic::TempFile;
use rigport_usd::printer::UsdaPrinter;
use rigport_usd::sink::{LayerBuilder, LayerSink};

pub(crate) use self::text::SPILL_BYTES;

/// Whether `path` asks for USD text (`.usda`), which is streamed when long.
pub(crate) fn encode_is_text(path: &Path) -> bool {
    OutputFormat::of_path(path) == Ok(OutputFormat::Usda)
}

/// Options for the USD exporter.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct UsdOptions {
    /// Skinning method of every skinned mesh; `None` (the default) keeps each skin's own
    /// [`SkinBinding::method`](rigport_model::SkinBinding::method). `Lbs` writes nothing
    /// (UsdSkel's default `classicLinear`); `Dqs` writes
    /// `uniform token primvars:skel:skinningMethod = "dualQuaternion"` (USD >= 23.02).
    pub skinning: Option<SkinningMethod>,
    /// The stage's `upAxis`; `None` keeps the asset's ([`rigport_model::SceneFrame::up_axis`]).
    pub up_axis: Option<UpAxis>,
    /// The stage's `metersPerUnit`; `None` keeps the asset's (1 when it states none).
    /// Lengths are converted by the root prim's transform, not in the data.
    pub meters_per_unit: Option<f64>,
    /// Write unskinned meshes that are attached to no joint and have morph targets as a
    /// point cache: `points.timeSamples` (the rest points plus the targets weighted by the
    /// first clip's morph-weight track of the mesh, at every time code of that clip)
    /// instead of BlendShapes, e.g. a simulated garment (`rigport cloth`).
    pub morphs_as_points: bool,
}

/// A `.usda` file in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct ExportedUsd {
    /// The complete USDA text (UTF-8, `\n` line ends, ends with a newline).
    pub text: String,
    /// The texture files the materials refer to (`asset inputs:file = @./<uri>@`), to be
    /// written beside the `.usda`: `<stem>_<image name>.<ext>`, `<stem>` the asset's
    /// name ([`to_usda`]) or the output file's stem ([`prepare_usd`]).
    pub images: Vec<crate::ImageFile>,
    /// Lossy or repairing steps taken (renamed prims and joints, dropped tracks, unbound
    /// vertices, renormalized weights, resampled tracks, half-precision scales...), in the
    /// order they happened.
    pub warnings: Vec<Warning>,
}

/// Exports `asset` as USDA text in memory.
///
/// The asset is checked first ([`Asset::validate`] plus the exporter's own rules, the same
/// as the glTF exporter's except the glTF-only limits on empty meshes and palette size);
/// nothing is built unless it passes.
///
/// # Errors
/// [`ExportError::Invalid`] listing every problem found.
pub fn to_usda(asset: &Asset, options: &UsdOptions) -> Result<ExportedUsd, ExportError> {
    let stem = if asset.name.is_empty() {
        "rig"
    } else {
        &asset.name
    };
    to_usda_with_stem(asset, options, stem)
}

/// As [`to_usda`], the texture files named `<stem>_<image>.<ext>`.
fn to_usda_with_stem(
    asset: &Asset,
    options: &UsdOptions,
    stem: &str,
) -> Result<ExportedUsd, ExportError> {
    let mut printer = UsdaPrinter::new(String::new());
    let (images, warnings) = build_body(asset, options, stem, &mut printer)?;
    Ok(ExportedUsd {
        text: printer.into_inner(),
        images,
        warnings,
    })
}

/// Describes the stage to `doc`; returns the texture files it names and the warnings.
fn build_body(
    asset: &Asset,
    options: &UsdOptions,
    stem: &str,
    doc: &mut dyn LayerSink,
) -> Result<(Vec<crate::ImageFile>, Vec<Warning>), ExportError> {
    let names = crate::labels::image_file_names(stem, asset);
    let warnings = stage::build(asset, options, &names, doc)?;
    let images = names
        .into_iter()
        .zip(&asset.images)
        .enumerate()
        .filter(|(k, _)| crate::labels::image_used(asset, *k))
        .map(|(_, (uri, image))| crate::ImageFile {
            uri,
            bytes: image.bytes.clone(),
        })
        .collect();
    Ok((images, warnings))
}

/// An export to a USD file, built and not yet in place, so that the caller can look at the
/// warnings (and, say, refuse to write under `--deny-warnings`) before any file changes.
///
/// A `.usda` text is built in memory, except a long one (over 64 MiB: a clip of millions
/// of frames; the environment variable `RIGPORT_TEST_USD_SPILL_BYTES` sets another size,
/// for tests), which is streamed into a hidden temporary file beside the output as it is
/// built and renamed over the output by [`PreparedUsd::write`] (or removed when this is
/// dropped), so its memory does not grow with the file. `.usdc` and `.usdz` are encoded in
/// memory.
#[derive(Debug)]
pub struct PreparedUsd {
    path: PathBuf,
    body: Body,
    images: Vec<crate::ImageFile>,
    warnings: Vec<Warning>,
}

/// What [`PreparedUsd::write`] puts at the output.
#[derive(Debug)]
enum Body {
    /// USDA text.
    Text(String),
    /// A `.usdc` or `.usdz` file's bytes.
    Encoded(Vec<u8>),
    /// USDA text already in a temporary file beside the target (a link's final target).
    Staged {
        file: TempFile,
        target: PathBuf,
        len: u64,
    },
}

/// Builds the export of `asset` to `path`. The extension must be `.usda` or `.usd`
/// (case-insensitive; a `.usd` file may hold text), `.usdc` (the same layer as a crate
/// file) or `.usdz` (a package: that crate file as `<stem>.usdc`, then the textures).
/// Nothing at `path` changes until [`PreparedUsd::write`].
///
/// # Errors
/// [`ExportError::UnsupportedExtension`] for any other extension (checked before any
/// work), the errors of [`to_usda`], and [`ExportError::Io`] when a long text cannot be
/// staged beside `path` (its folder is missing or not writable, the output is not a
/// regular file, the disk is full).
pub fn prepare_usd(
    asset: &Asset,
    path: &Path,
    options: &UsdOptions,
) -> Result<PreparedUsd, ExportError> {
    // For tests of the streaming path on small files (as `RIGPORT_TEST_RENAME_DELAY_MS`).
    let spill_at = std::env::var("RIGPORT_TEST_USD_SPILL_BYTES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(SPILL_BYTES);
    prepare_usd_spilling_at(asset, path, options, spill_at)
}

/// [`prepare_usd`], a text staged once it holds `spill_at` bytes.
fn prepare_usd_spilling_at(
    asset: &Asset,
    path: &Path,
    options: &UsdOptions,
    spill_at: usize,
) -> Result<PreparedUsd, ExportError> {
    let encoding = match OutputFormat::of_path(path) {
        Ok(format) if format.is_usd() => format,
        _ => {
            return Err(ExportError::UnsupportedExtension {
                path: path.to_path_buf(),
            })
        }
    };
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let io_error = |source| ExportError::Io {
        path: path.to_path_buf(),
        source,
    };
    let (body, images, warnings) = match encoding {
        OutputFormat::Usda => {
            // Where a long text goes: the file a link at `path` leads to. A path that
            // cannot be written is reported when the text would be staged, else by `write`.
            let doc = match rigport_atomic::check_output(path) {
                Ok(target) => Usda::spilling_to(&target, spill_at),
                Err(_) => Usda::default(),
            };
            let mut printer = UsdaPrinter::new(doc);
            let (images, warnings) = build_body(asset, options, &stem, &mut printer)?;
            let body = match printer.into_inner().finish().map_err(io_error)? {
                Finished::Text(text) => Body::Text(text),
                Finished::Staged { file, target, len } => Body::Staged { file, target, len },
            };
            (body, images, warnings)
        }
        _ => {
            let mut builder = LayerBuilder::default();
            let (images, warnings) = build_body(asset, options, &stem, &mut builder)?;
            let layer = builder.finish();
            if encoding == OutputFormat::Usdc {
                (
                    Body::Encoded(encode::crate_file(&layer, path)?),
                    images,
                    warnings,
                )
            } else {
                // A package holds its textures.
                let package = encode::package(&layer, &images, &stem, path)?;
                (Body::Encoded(package), Vec::new(), warnings)
            }
        }
    };
    Ok(PreparedUsd {
        path: path.to_path_buf(),
        body,
        images,
        warnings,
    })
}

impl PreparedUsd {
    /// The bytes [`PreparedUsd::write`] writes, over every file (a long text staged beside
    /// the output included).
    pub fn byte_len(&self) -> u64 {
        let body = match &self.body {
            Body::Text(text) => text.len() as u64,
            Body::Encoded(bytes) => bytes.len() as u64,
            Body::Staged { len, .. } => *len,
        };
        body + self
            .images
            .iter()
            .map(|i| i.bytes.len() as u64)
            .sum::<u64>()
    }

    /// Lossy or repairing steps taken, as [`ExportedUsd::warnings`].
    pub fn warnings(&self) -> &[Warning] {
        &self.warnings
    }

    /// The output file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The USDA text that [`PreparedUsd::write`] writes, when it is in memory: `None` for a
    /// `.usdc` or `.usdz` and for a long text already staged in its temporary file.
    pub fn text(&self) -> Option<&str> {
        match &self.body {
            Body::Text(text) => Some(text),
            Body::Encoded(_) | Body::Staged { .. } => None,
        }
    }

    /// Writes the file atomically (a temporary file in the same directory, renamed over the
    /// target; see [`crate::write_atomic`]).
    ///
    /// # Errors
    /// [`ExportError::Io`] naming the file; the target is then unchanged and no temporary
    /// file is left.
    pub fn write(self) -> Result<(), ExportError> {
        // Textures first (each atomically), so the new `.usda` never names a missing file.
        for image in &self.images {
            let path = self.path.with_file_name(&image.uri);
            crate::write_atomic(&path, &image.bytes)
                .map_err(|source| ExportError::Io { path, source })?;
        }
        let io_error = |source| ExportError::Io {
            path: self.path.clone(),
            source,
        };
        match self.body {
            Body::Text(text) => crate::write_atomic(&self.path, text.as_bytes()).map_err(io_error),
            Body::Encoded(bytes) => crate::write_atomic(&self.path, &bytes).map_err(io_error),
            Body::Staged { file, target, .. } => file.persist(&target).map_err(io_error),
        }
    }
}
