//! The exporters' error type.

use std::fmt;
use std::path::PathBuf;

use rigport_model::{AssetError, JointIndex};

/// Why an export failed. No output file is left behind when this is returned.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The asset breaks a rule of the model or of glTF; every problem found is listed.
    #[error("the asset cannot be exported: {}", ProblemList(problems))]
    Invalid {
        /// Every problem found, model-level ones ([`Problem::Asset`]) first.
        problems: Vec<Problem>,
    },
    /// [`crate::GltfOptions::max_influences`] is outside `1..=8`.
    #[error(
        "max_influences must be between 1 and 8 (two glTF sets of four), got {max_influences}"
    )]
    MaxInfluences {
        /// The value given.
        max_influences: usize,
    },
    /// The output path's extension is neither `.glb` nor `.gltf`.
    #[error("{}: unsupported output extension (expected .glb or .gltf)", path.display())]
    UnsupportedExtension {
        /// The path given.
        path: PathBuf,
    },
    /// The binary data does not fit in a GLB container (32-bit chunk lengths).
    #[error("the binary data is {bytes} bytes, more than a GLB file can hold (4 GiB); write .gltf instead")]
    TooLarge {
        /// Size of the binary buffer in bytes.
        bytes: u64,
    },
    /// The glTF JSON could not be serialized.
    #[error("cannot serialize the glTF JSON")]
    Json(#[from] serde_json::Error),
    /// The USD layer could not be encoded as a `.usdc` / `.usdz`.
    #[error("cannot encode the USD layer")]
    Usd(#[from] rigport_usd::UsdError),
    /// Writing an output file failed.
    #[error("cannot write {}", path.display())]
    Io {
        /// The file being written.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
}

/// One reason an asset cannot be exported, as listed by [`ExportError::Invalid`].
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Problem {
    /// A problem found by [`rigport_model::Asset::validate`], or one of the same kind the
    /// exporter checks in addition (normals, UVs, morph normals, default morph weights).
    #[error(transparent)]
    Asset(AssetError),
    /// Two skin bindings name the same mesh; glTF stores joints and weights in the mesh.
    #[error("mesh {mesh} is bound by skins {first_skin} and {second_skin}")]
    SharedSkinMesh {
        /// Mesh index.
        mesh: usize,
        /// The first skin naming it.
        first_skin: usize,
        /// The second skin naming it.
        second_skin: usize,
    },
    /// A skin binding has no joints (glTF requires at least one).
    #[error("skin {skin} has an empty joint palette")]
    EmptyPalette {
        /// Skin index.
        skin: usize,
    },
    /// A joint appears twice in one palette (glTF requires `skin.joints` to be unique).
    #[error("skin {skin} lists {joint} twice in its palette")]
    DuplicatePaletteJoint {
        /// Skin index.
        skin: usize,
        /// The repeated joint.
        joint: JointIndex,
    },
    /// A palette is larger than `JOINTS_n` can address (`UNSIGNED_SHORT`).
    #[error("skin {skin} has {joints} palette joints; glTF JOINTS_n address at most 65536")]
    PaletteTooLarge {
        /// Skin index.
        skin: usize,
        /// Palette size.
        joints: usize,
    },
    /// A mesh has no vertices or no triangles (a glTF accessor needs at least one element).
    #[error("mesh {mesh} has {vertices} vertices and {triangles} triangles; glTF needs both")]
    EmptyMesh {
        /// Mesh index.
        mesh: usize,
        /// Vertex count.
        vertices: usize,
        /// Triangle count.
        triangles: usize,
    },
    /// `Mesh::morph_weights` is neither empty nor one weight per target.
    #[error("mesh {mesh} has {found} default morph weights for {expected} targets")]
    MorphWeightCount {
        /// Mesh index.
        mesh: usize,
        /// Number of default weights.
        found: usize,
        /// Number of morph targets.
        expected: usize,
    },
    /// A joint's rest rotation has (near) zero length and cannot be normalized.
    #[error("joint {joint} ({name:?}) has a zero-length rest rotation")]
    DegenerateRestRotation {
        /// Joint index.
        joint: usize,
        /// Joint name.
        name: String,
    },
    /// A rotation key has (near) zero length and cannot be normalized.
    #[error("clip {clip:?} track {track} key {key}: zero-length rotation")]
    DegenerateRotationKey {
        /// Clip name.
        clip: String,
        /// Track index in the clip.
        track: usize,
        /// Key index.
        key: usize,
    },
}

/// Formats a problem list as `N problems: a; b; c`.
struct ProblemList<'a>(&'a [Problem]);

impl fmt::Display for ProblemList<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = self.0.len();
        write!(f, "{n} problem{}", if n == 1 { "" } else { "s" })?;
        for (i, p) in self.0.iter().enumerate() {
            write!(f, "{}{p}", if i == 0 { ": " } else { "; " })?;
        }
        Ok(())
    }
}
