//! FBX importer (binary and ASCII, FBX 6.x-7.7) over [ufbx](https://github.com/ufbx/ufbx),
//! to a rig [`Asset`].
//!
//! ufbx parses the file and evaluates what makes FBX hard (pivots, pre/post rotation,
//! rotation order, geometric transforms, inherit types, animation layers); this module
//! maps its evaluated scene onto the model:
//!
//! | FBX (as ufbx evaluates it) | model |
//! |---|---|
//! | `GlobalSettings` axes | converted by ufbx on load to right-handed +Y up (`target_axes`, `space_conversion = ModifyGeometry`: a signed axis permutation applied to transforms, geometry and keys), so [`Asset::frame`] is the default |
//! | `GlobalSettings.UnitScaleFactor` | kept: [`Asset::meters_per_unit`] = ufbx's `unit_meters` (0.01 for centimetres), numbers as in the file |
//! | bone nodes (`LimbNode`, ...), skin clusters' nodes, animated nodes, and every node between them and the scene root | one [`Joint`] each, parents first, rest = the node's evaluated local transform (segment scale compensate folded in by ufbx's `Compensate` inherit handling, helper nodes where that is not exact) |
//! | each material part of a mesh node | one [`Mesh`]: triangles (polygons kept in [`Mesh::polygons`] when ufbx's triangulation is a fan), normals, every UV set, its material |
//! | skin deformer | a [`SkinBinding`]: mesh points at bind time from the clusters (`TransformLink` times geometry-to-bone, not ufbx's `geometry_to_world`, which poses them by the loaded `Lcl` pose), inverse bind = the clusters' `bind_to_world` inverted (the clusters win over the BindPose and the rest pose), every influence kept |
//! | blend shape channels | morph targets (the full-weight shape; in-betweens left out with a warning) |
//! | each animation stack | one [`Clip`] named after it, sampled by ufbx's `bake_anim` (see `anim.rs`) |
//!
//! [`Joint`]: rigport_model::Joint
//! [`Mesh`]: rigport_model::Mesh
//! [`Mesh::polygons`]: rigport_model::Mesh::polygons
//! [`Clip`]: rigport_model::Clip
//! [`SkinBinding`]: rigport_model::SkinBinding

mod anim;
mod blend;
mod load;
mod material;
mod mesh;
mod skeleton;
#[cfg(test)]
mod tests;

use std::collections::HashSet;
use std::path::Path;

use rigport_model::{Asset, SceneFrame, Warning};

use crate::{check_asset, read_file, ImportError, Imported, Location, Problem};

pub use self::load::{is_fbx, ASCII_MAGIC, BINARY_MAGIC};

/// Imports an FBX file (binary or ASCII); external textures are read relative to its
/// folder.
///
/// # Errors
/// The file cannot be read; ufbx rejects it (truncated, not FBX, unsupported version; at
/// the file's end for a truncated file: the byte offset for binary, the line for ASCII);
/// the evaluated scene breaks a model rule (e.g. a cyclic or empty hierarchy).
pub fn import(path: &Path) -> Result<Imported, ImportError> {
    let bytes = read_file(path)?;
    import_slice(&bytes, path)
}

/// Imports FBX from bytes; `path` names the input in errors and warnings, and external
/// textures are looked up beside it.
///
/// # Errors
/// As [`import`].
pub fn import_slice(bytes: &[u8], path: &Path) -> Result<Imported, ImportError> {
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(ImportError::new(Location::file(path), Problem::Empty));
    }
    let scene = load::load(bytes, path)?;
    // The stacks bake on a second thread while the skeleton, materials and meshes are
    // built from the nodes the stacks' curves name, which are the nodes ufbx bakes unless
    // inherit types make it bake more (then they are built again with those).
    let guess = anim::curve_nodes(&scene);
    let (baked, built) = std::thread::scope(|s| {
        let baking = (!scene.anim_stacks.is_empty()).then(|| s.spawn(|| anim::bake(&scene, path)));
        let built = structure(&scene, &guess, path);
        let baked = baking.map_or(Ok(Vec::new()), |b| {
            b.join().unwrap_or_else(|p| std::panic::resume_unwind(p))
        });
        (baked, built)
    });
    let baked = baked?;
    let animated = anim::animated_nodes(&baked);
    let (skel, mats, built, mut warnings) = match built {
        Ok(built) if animated == guess => built,
        _ => structure(&scene, &animated, path)?,
    };
    // Once, whichever way the structure was built (it reads the file again).
    if let Some(drift) = scale_helper_warning(&scene, bytes, path) {
        warnings.insert(0, drift);
    }
    let clips = anim::clips(&baked, &skel, &built);
    let unit = scene.settings.unit_meters;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let asset = Asset {
        name,
        skeleton: skel.skeleton,
        meshes: built.meshes,
        skins: built.skins,
        clips,
        meters_per_unit: (unit.is_finite() && unit > 0.0).then_some(unit),
        frame: SceneFrame::default(),
        materials: mats.materials,
        images: mats.images,
        ..Asset::default()
    };
    check_asset(&asset, || Location::file(path))?;
    Ok(Imported { asset, warnings })
}

/// The skeleton (with `animated` nodes among its joints), materials and meshes of `scene`,
/// and the warnings found building them.
///
/// # Errors
/// As `skeleton::build`.
fn structure(
    scene: &ufbx::Scene,
    animated: &HashSet<u32>,
    path: &Path,
) -> Result<
    (
        skeleton::Skel,
        material::Materials,
        mesh::Built,
        Vec<Warning>,
    ),
    ImportError,
> {
    let mut warnings = Vec::new();
    let skel = skeleton::build(scene, animated, path)?;
    let mats = material::build(scene, path, &mut warnings);
    let built = mesh::build(scene, &skel, path, &mut warnings);
    Ok((skel, mats, built, warnings))
}

/// The W004 warning for a node ufbx's scale helper places away from the file's definition
/// (`load::scale_helper_drift`) by more than 1e-4 of the skeleton's size, if any.
fn scale_helper_warning(scene: &ufbx::Scene, bytes: &[u8], path: &Path) -> Option<Warning> {
    let (node, drift, size) = load::scale_helper_drift(bytes, scene)?;
    (drift > 1e-4 * size).then(|| {
        incomplete(
            path,
            &node,
            format!(
                "placed {drift:.3e} units ({:.2}% of the skeleton's size) from where the \
                 file puts it: a non-uniform scale above a node that inherits it its own \
                 way (InheritType 0, RrSs, or 2, Rrs: segment scale compensate) and has a \
                 scaling pivot or rotation offset has no exact joint transform (ufbx's \
                 scale helper drops the offset)",
                100.0 * drift / size
            ),
        )
    })
}

/// A warning at the file, about one named FBX element.
fn incomplete(path: &Path, element: &str, message: String) -> Warning {
    Warning::Incomplete {
        location: format!("{}: {element}", Location::file(path)),
        message,
    }
}
