//! The blend-shape channels of imported meshes, which the SkelAnimations' weights address
//! (filled by `blend.rs`, kept in the `Importer` state).

use rigport_model::MeshIndex;

/// One `skel:blendShapes` channel of a mesh.
#[derive(Clone, Debug)]
pub(super) struct Channel {
    /// The token a SkelAnimation's `blendShapes` names it by.
    pub(super) token: String,
    /// Sub-shapes sorted by weight: the null shape (`None`) at 0, the primary at 1 and the
    /// inbetweens, each with the index of its morph target in the mesh.
    pub(super) knots: Vec<(f64, Option<usize>)>,
}

/// The blend-shape channels of one imported mesh.
#[derive(Clone, Debug)]
pub(super) struct MeshShapes {
    pub(super) mesh: MeshIndex,
    /// Morph targets of the mesh (channels' sub-shapes, flattened).
    pub(super) targets: usize,
    pub(super) channels: Vec<Channel>,
}
