//! Format-neutral naming, palette and weight rules that the glTF and USD writers share: how
//! messages name a mesh, the file names of images written beside the asset and which of
//! them are used, which palette joint holds a vertex without influences, and when a weight
//! row's sum counts as off.

use rigport_model::{Asset, Mesh, Skeleton};

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

/// File names for the images of an asset written beside `<stem>.gltf` or `<stem>.usda`:
/// `<stem>_<image name or index>.<ext>`, the name reduced to `[A-Za-z0-9_-]` and made
/// unique. Index `k` is image `k`.
pub(crate) fn image_file_names(stem: &str, asset: &Asset) -> Vec<String> {
    let mut taken = std::collections::BTreeSet::new();
    asset
        .images
        .iter()
        .enumerate()
        .map(|(k, image)| {
            let base = image
                .name
                .rsplit_once('.')
                .map_or(image.name.as_str(), |(b, _)| b);
            let clean: String = base
                .chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                        c
                    } else {
                        '_'
                    }
                })
                .collect();
            let part = if clean.trim_matches('_').is_empty() {
                format!("image{k}")
            } else {
                clean
            };
            let mut name = format!("{stem}_{part}.{}", image.extension());
            let mut n = 1;
            while !taken.insert(name.clone()) {
                n += 1;
                name = format!("{stem}_{part}_{n}.{}", image.extension());
            }
            name
        })
        .collect()
}

/// Whether image `k` is used by a material's texture (only those are written).
pub(crate) fn image_used(asset: &Asset, k: usize) -> bool {
    asset
        .materials
        .iter()
        .any(|m| m.textures().any(|(_, t)| t.image.get() == k))
}

/// An input row whose weight sum differs from 1 by more than this is reported as
/// renormalized. Summing up to a few dozen `f32` weights that were normalized in `f32`
/// accumulates at most ~32 · 2⁻²⁴ ≈ 2e-6 of rounding error, so 1e-5 only flags rows whose
/// source really did not sum to 1 (e.g. Pinocchio's 4-decimal rows).
pub(crate) const ROW_SUM_TOLERANCE: f64 = 1e-5;
