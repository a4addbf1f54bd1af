//! `rigport skin`: automatic skin weights (bone heat) for a mesh and a skeleton, written as
//! Pinocchio's `attachment.out` or as a whole rig.
//!
//! The mesh is an OBJ. The skeleton is either a Pinocchio `skeleton.out`, already in the
//! mesh's space (the weights then go to Pinocchio's bones, as its own attachment step
//! would give them, and `.out` writes them as an `attachment.out`), or any rig rigport
//! reads, motion capture included (BVH, ASF/AMC, glTF, FBX, ...), whose rest pose is
//! placed in the mesh's space by [`SkinOptions::placement`]: the mesh is carried into the
//! skeleton's model space, so the rig plays the skeleton's clips in the skeleton's units.

use std::fmt::Write as _;

use rigport_model::glam::Vec3;

use crate::load::{Input, Source, plan};
use crate::outputs::{check_not_read, check_request, extension, write_file};
use crate::progress::{Progress, step};
use crate::write::{Output, write_output};
use crate::{PipelineError, Report};

/// Where a skeleton's rest pose sits in its mesh's space: a joint at `p` in the skeleton's
/// model space is at `scale * p + offset` in the mesh's.
///
/// ```
/// use rigport_model::glam::Vec3;
/// use rigport_pipeline::skin::Placement;
/// // A BVH in centimetres, its hips on the floor, in a mesh in metres whose feet are 2 cm up.
/// let placement = Placement { offset: Vec3::new(0.0, 0.02, 0.0), scale: 0.01 };
/// assert_ne!(placement, Placement::default());
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Added after scaling, in the mesh's units.
    pub offset: Vec3,
    /// Mesh units per skeleton unit (positive).
    pub scale: f32,
}

impl Default for Placement {
    fn default() -> Self {
        Self {
            offset: Vec3::ZERO,
            scale: 1.0,
        }
    }
}

/// What `skin` writes, and where the skeleton sits.
///
/// ```
/// use rigport_pipeline::{skin::SkinOptions, write::Output};
/// // Pinocchio's attachment.out, by its extension.
/// let options = SkinOptions { output: Output::new("attachment.out"), ..Default::default() };
/// assert_eq!(options.placement.scale, 1.0);
/// ```
#[derive(Clone, Debug, Default)]
pub struct SkinOptions {
    /// `.out`: the weights as a Pinocchio `attachment.out` (Pinocchio skeletons only);
    /// anything else: the rig, written as `convert` writes it.
    pub output: Output,
    /// The skeleton's place in the mesh's space (not for a Pinocchio skeleton).
    pub placement: Placement,
}

/// Computes the weights of the mesh and skeleton `input` names (with or without
/// `Inputs::auto_weights`) and writes them.
///
/// ```
/// use rigport_pipeline::{skin, skin::SkinOptions, load::Input, progress::Silent, write::Output};
///
/// let dir = tempfile::tempdir()?;
/// let out = dir.path().join("attachment.out");
/// let rig = "../../fixtures/pinocchio";
/// let input = Input::new(vec![format!("{rig}/branch.obj").into(), format!("{rig}/branch_skeleton.out").into()]);
/// let report = skin(&input, &SkinOptions { output: Output::new(&out), ..Default::default() }, &Silent)?;
/// assert!(report.log[0].starts_with("wrote "), "{:?}", report.log);
/// let rows = std::fs::read_to_string(&out)?;
/// // One row per OBJ vertex, each summing to 1.
/// for row in rows.lines() {
///     let sum: f32 = row.split(' ').map(|w| w.parse::<f32>().unwrap()).sum();
///     assert!((sum - 1.0).abs() < 1e-4, "{row}");
/// }
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// Inputs that are not a mesh and a skeleton; a placement for a Pinocchio skeleton, or an
/// `.out` for another; as the importers, bone heat and [`write_output`].
pub fn run(
    input: &Input,
    options: &SkinOptions,
    progress: &dyn Progress,
) -> Result<Report, PipelineError> {
    let path = &options.output.path;
    let attachment = extension(path) == "out";
    match attachment {
        true => check_not_read(input, path, &[])?,
        false => drop(check_request(input, path, &[])?),
    }
    let mut files = input.files.clone();
    files.auto_weights = true;
    let placed = options.placement != Placement::default();
    match plan(&files)?.as_slice() {
        [Source::PinocchioUnweighted { mesh, skeleton }] => {
            if placed {
                return Err(PipelineError::Usage(
                    "a Pinocchio skeleton is in its mesh's space already: it takes no \
                     placement (offset, scale)"
                        .into(),
                ));
            }
            let (imported, rows) = step(progress, "computing weights by bone heat", || {
                crate::weights::auto_rig_rows(mesh, skeleton, progress)
            })?;
            if attachment {
                progress.warnings(&imported.warnings)?;
                write_file(path, attachment_text(&rows).as_bytes())?;
                let bones = rows.first().map_or(0, Vec::len);
                let line = format!(
                    "wrote {}: {} vertices x {bones} bones",
                    path.display(),
                    rows.len()
                );
                return Ok(Report::logged(line));
            }
            let mut imported = imported;
            crate::units::apply(
                &mut imported,
                input.units,
                input.force_units,
                &mesh.display().to_string(),
            )?;
            let line = write_output(
                imported.asset,
                imported.warnings,
                &options.output,
                &input.budget,
                progress,
            )?;
            Ok(Report::logged(line))
        }
        [Source::Obj(mesh), skeleton] | [skeleton, Source::Obj(mesh)] => {
            if attachment {
                return Err(PipelineError::Usage(
                    "an attachment.out holds the weights of a Pinocchio skeleton's bones: \
                     write this rig as .glb, .gltf, .usda, .usdc or .usdz"
                        .into(),
                ));
            }
            let rig_input = Input {
                bone_mesh: false,
                ..input.clone()
            };
            let mut rig = step(progress, &format!("reading {}", skeleton.label()), || {
                rig_input.load(skeleton, progress)
            })?;
            let body =
                crate::load::load(&Source::Obj(mesh.clone()), false, &input.budget, progress)?;
            place(&mut rig, body, options.placement);
            step(progress, "computing weights by bone heat", || {
                crate::weights::bind_unskinned(&mut rig, &mesh.display().to_string(), progress)
            })?;
            let line = write_output(
                rig.asset,
                rig.warnings,
                &options.output,
                &input.budget,
                progress,
            )?;
            Ok(Report::logged(line))
        }
        _ => Err(PipelineError::Usage(
            "skin takes a mesh (.obj) and a skeleton: a Pinocchio skeleton.out, or a rig \
             (BVH, ASF with its motions, glTF, USD, FBX, COLLADA)"
                .into(),
        )),
    }
}

/// The body's meshes added to the rig, carried from the mesh's space into the skeleton's
/// model space (the inverse of `placement`); its materials come along when the rig has
/// none.
fn place(rig: &mut rigport_import::Imported, body: rigport_import::Imported, placement: Placement) {
    let asset = &mut rig.asset;
    let materials = asset.materials.is_empty();
    if materials {
        asset.materials = body.asset.materials;
        asset.images = body.asset.images;
    }
    for mut mesh in body.asset.meshes {
        for p in &mut mesh.positions {
            *p = (*p - placement.offset) / placement.scale;
        }
        if !materials {
            mesh.material = None;
        }
        asset.meshes.push(mesh);
    }
    rig.warnings.extend(body.warnings);
}

/// Rows of weights as Pinocchio writes `attachment.out`: one line per vertex, the weights
/// separated by spaces (each the shortest text that reads back as the same `f32`).
fn attachment_text(rows: &[Vec<f32>]) -> String {
    let mut text = String::with_capacity(rows.len() * rows.first().map_or(1, Vec::len) * 4);
    for row in rows {
        for (k, w) in row.iter().enumerate() {
            let sep = if k == 0 { "" } else { " " };
            let _ = write!(text, "{sep}{w}");
        }
        text.push('\n');
    }
    text
}
