//! The built-in demo of `rigport demo`: a procedural humanoid in Pinocchio's layout,
//! assembled into an [`Asset`] with its clips (`wave`, `reach`, `twist`) built in Rust, the
//! DQS bake of its twist, a skirt simulated on its wave ([`skirt::bake`]), and its pictures.
//!
//! ```
//! let demo = rigport_demo::build(1)?;
//! let names: Vec<&str> = demo.asset.clips.iter().map(|c| c.name.as_str()).collect();
//! assert_eq!(names, ["wave", "reach", "twist"]);
//! assert_eq!(demo.asset.skeleton.len(), 24);
//! assert!(demo.asset.meshes[0].vertex_count() > 5_000);
//! assert_eq!(demo.asset.clips[0].duration(), 2.0);
//! # Ok::<(), rigport_demo::DemoError>(())
//! ```
//!
//! # The character
//! [`character()`] builds, from no input files, what a Pinocchio run would leave on disk for a
//! human figure: a joint tree (`skeleton.out`), a closed triangle mesh (the OBJ) and one dense
//! weight row per vertex with one column per **bone** (`attachment.out`). Turning it into an
//! [`Asset`] is the Pinocchio importer's job, exactly as for files.
//!
//! # How it is made
//! Files: `skeleton` (the joint table), `sdf` (distance primitives), `body` (the parts and
//! their field on a grid), `surface_nets` (the mesh), `weights` (skin weights), `character`
//! (the steps in order); `clips` (keys and handles), `skirt` (the garment and its
//! simulation), `pictures` (the demo's PNG and GIF),
//! `corpus` (one picture per corpus family).
//!
//! 1. **Skeleton**: a fixed table of 24 joints, about 1.75 m tall, standing on `y = 0`,
//!    facing +Z, in a T-pose (arms along ±X, so hands are far from the hips). Left is +X;
//!    the right side is the left side mirrored in `x`.
//! 2. **Body**: a signed distance field, the polynomial smooth minimum (Quilez, "smooth
//!    minimum", <https://iquilezles.org/articles/smin/>) of 25 round cones (capsules whose
//!    radius varies along the axis) and ellipsoids laid along the bones: pelvis, waist and a
//!    wider chest, tapering limbs, a head with chin and nose, flat feet and mitten hands.
//! 3. **Polygonization**: naive *surface nets* (Gibson 1998, "Constrained elastic surface
//!    nets"), chosen over marching cubes because it needs no case tables and gives fewer,
//!    better-shaped triangles: one vertex per grid cell that the surface crosses (the mean of
//!    the crossings on its 12 edges), one quad per grid edge that the surface crosses
//!    (joining the 4 cells around that edge), split along its shorter diagonal. Grid faces
//!    with an ambiguous (checkerboard) sign pattern, which would make an edge that 4 quads
//!    share, are removed first by moving one near-zero sample to the surface (see
//!    `remove_ambiguous_faces`). Every vertex is then moved onto the surface by one Newton
//!    step and gets the field's normalized gradient as its normal. The grid is swept one `y`
//!    slice at a time (memory `O(nx * nz)`), and each primitive is evaluated only inside its
//!    bounding box grown by its blend radius plus 3 cells, which leaves every value near the
//!    surface exact. The result is indexed (vertices shared), closed and 2-manifold (every
//!    edge in exactly two triangles), and wound counter-clockwise seen from outside.
//! 4. **Weights** (see `skin_weights`): per vertex and bone the distance to the bone's
//!    segment; bones of limbs (center, each arm, each leg) clearly farther than the nearest
//!    limb are masked out, so a thigh never pulls the other thigh nor a hand the hips; weight
//!    `1 / e²` tapering to zero at twice the nearest distance; the best 4 minus the 5th (so
//!    the cut is continuous too), normalized. Every step is continuous in the vertex
//!    position, so the weights vary smoothly over the surface; the root carries none.
//!
//! Everything is single-threaded, iterates in index order and uses only `+ - * /`, `sqrt`,
//! `min`/`max`/`abs`/`floor` on `f32` (exactly rounded by IEEE 754; Rust never fuses them into
//! FMA, and glam's `Vec3` is scalar code): the output is bit-identical on every run and every
//! machine.

mod body;
mod character;
pub mod clips;
pub mod corpus;
mod error;
pub mod pictures;
mod sdf;
mod skeleton;
pub mod skirt;
mod surface_nets;
mod weights;

pub use character::{character, DemoRig, MAX_DETAIL};
pub use error::DemoError;

use rigport_deform::bake::asset::{bake_dqs, DqsBakeOptions, MeshBakeReport};
use rigport_ik::clip::{solve_clip, ClipSolveOptions, HandleTargets};
use rigport_import::{pinocchio, Imported};
use rigport_model::{Asset, Influences, Skeleton, SkinBinding, Warning};

/// The demo: the character as an asset with its clips, and what the pictures need.
#[derive(Clone, Debug)]
pub struct Demo {
    /// The character (one skinned mesh `"demo"`, 24 joints named as in the demo's joint
    /// table) with clips `wave` ([`clips::wave_keys`]), `reach` (IK, [`clips::reach_handles`])
    /// and `twist` ([`clips::twist_keys`]), in this order.
    pub asset: Asset,
    /// Warnings of the IK solve (none expected).
    pub warnings: Vec<Warning>,
    /// The model-space targets the reach was solved for (drawn as markers on its picture).
    pub reach_targets: HandleTargets,
}

/// The character of [`character`]`(detail)` as an imported Pinocchio rig (bone `k` named
/// after the joint it ends at; the root keeps its own name), without clips.
///
/// # Errors
/// [`DemoError::Assemble`] (a rigport bug).
pub fn assemble(rig: DemoRig) -> Result<Imported, DemoError> {
    let skeleton = pinocchio::PinocchioSkeleton {
        positions: rig.joint_positions,
        parents: rig.joint_parents,
    };
    pinocchio::assemble(
        "demo",
        rig.mesh,
        &skeleton,
        Some(&rig.joint_names),
        &rig.bone_weights,
        None,
    )
    .map_err(DemoError::Assemble)
}

/// Builds the demo at `detail` (see [`character`]): the character with its three clips.
///
/// # Errors
/// Any [`DemoError`] (each a rigport bug).
pub fn build(detail: u32) -> Result<Demo, DemoError> {
    let mut imported = assemble(character(detail))?;
    let skeleton = &imported.asset.skeleton;
    let wave = keyed(skeleton, &clips::wave_keys(skeleton)?, "wave")?;
    let handles = clips::reach_handles(skeleton)?;
    let solved = solve_clip(
        skeleton,
        &handles,
        &ClipSolveOptions::default(),
        "reach",
        "reach.handles.json",
    )
    .map_err(DemoError::Reach)?;
    let reach_targets = HandleTargets::new(skeleton, handles.tracks);
    let twist = keyed(skeleton, &clips::twist_keys(skeleton)?, "twist")?;
    imported.warnings.extend(solved.warnings);
    imported.asset.clips.extend([wave, solved.clip, twist]);
    Ok(Demo {
        asset: imported.asset,
        warnings: imported.warnings,
        reach_targets,
    })
}

/// Bakes keys into a clip, naming the clip in errors.
fn keyed(
    skeleton: &Skeleton,
    keys: &rigport_model::PoseKeys,
    name: &str,
) -> Result<rigport_model::Clip, DemoError> {
    rigport_anim::keyed::clip(skeleton, keys, name).map_err(|source| DemoError::Keys {
        clip: name.to_owned(),
        source,
    })
}

/// Influences per vertex of the baked twist (glTF's one `JOINTS_0` set).
pub const DQS_INFLUENCES: u8 = 4;

/// The twist clip alone, its DQS baked into corrective morph targets (`rigport bake`'s
/// code path) so any glTF viewer shows DQS. Sampled at the keys' 30 fps so a viewer's
/// linear morph-weight interpolation between samples stays close to DQS. `influences`
/// limits a skin to what the writer keeps (the CLI passes the glTF writer's rule with
/// [`DQS_INFLUENCES`]); near-singular fallbacks go into `warnings`.
///
/// # Errors
/// [`DemoError::Bake`] (a rigport bug).
pub fn twist_dqs(
    demo: &Demo,
    influences: impl Fn(&Skeleton, &SkinBinding) -> Influences,
    warnings: &mut Vec<Warning>,
) -> Result<(Asset, Vec<MeshBakeReport>), DemoError> {
    let mut asset = demo.asset.clone();
    asset.clips.retain(|c| c.name == "twist");
    let reports = bake_dqs(
        &mut asset,
        &DqsBakeOptions {
            clip: Some("twist"),
            fps: Some(clips::KEY_FPS),
            ..DqsBakeOptions::default()
        },
        influences,
        "demo",
        warnings,
    )
    .map_err(DemoError::Bake)?;
    Ok((asset, reports))
}
