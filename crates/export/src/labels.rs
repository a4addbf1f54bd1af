//! Format-neutral naming and palette rules that the glTF and USD writers share: how
//! messages name a mesh, and which palette joint holds a vertex without influences.

use rigport_model::{Mesh, Skeleton};

/// How warnings name a mesh: its name, or `#index` when it has none.
pub(crate) fn mesh_label(index: usize, mesh: &Mesh) -> String {
    if mesh.name.is_empty() {
        format!("#{index}")
    } else {
        mesh.name.clone()
    }
}

/// The palette index a vertex without influence is bound to: the first palette joint whose
/// parent is not in the palette, i.e. the root of (the first tree of) the skin. Such a vertex
/// then follows the skeleton as a whole rather than an arbitrary bone.
pub(crate) fn fallback_palette_index(
    skeleton: &Skeleton,
    palette: &[rigport_model::JointIndex],
) -> usize {
    let mut in_palette = vec![false; skeleton.len()];
    for j in palette {
        in_palette[j.get()] = true;
    }
    palette
        .iter()
        .position(|j| match skeleton.joint(*j).parent {
            None => true,
            Some(p) => !in_palette[p.get()],
        })
        .unwrap_or(0)
}
