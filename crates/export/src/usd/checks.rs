//! What makes an asset unexportable to USD.

use rigport_model::Asset;

use crate::Problem;

/// Everything that makes an asset unexportable to USD: the glTF exporter's checks
/// ([`Asset::validate`] and the rest), minus the two that are glTF limits only (an empty
/// mesh is a valid USD Mesh; UsdSkel joint indices are `int`, not `UNSIGNED_SHORT`).
pub(super) fn check(asset: &Asset) -> Vec<Problem> {
    crate::gltf::document::check(asset)
        .into_iter()
        .filter(|p| {
            !matches!(
                p,
                Problem::EmptyMesh { .. } | Problem::PaletteTooLarge { .. }
            )
        })
        .collect()
}
