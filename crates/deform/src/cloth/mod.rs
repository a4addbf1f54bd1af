//! Cloth on the animated body: a garment simulated with XPBD against a skinned character,
//! pinned vertices following the skin, colliding with the skinned body surface.
//!
//! - [`Garment`]: particles (one per source vertex of the garment mesh), triangles and pins
//!   ([`PinSelection`]: a per-vertex value such as the USTC course's `ControlPoints`, a
//!   vertex list, or a height).
//! - [`simulate`]: samples the clip on a fixed frame grid, skins the body at every frame
//!   (in parallel: frames are independent, so the order cannot matter), binds each pinned
//!   vertex at rest (the bind pose) to the nearest point of the skinned body surface
//!   ([`attach::SurfacePoint`], a triangle and barycentric weights) and steps the
//!   XPBD solver (`solver`) serially: substeps per frame, stretch and bending constraints,
//!   gravity along the scene's down axis, damping, pins moved to their bound points
//!   (interpolated linearly between frames) and collisions with a thickness as the last
//!   step of every substep: capsules fitted to the bones ([`collide::fit_capsules`], the
//!   coarse phase, which also catches a particle deep in the body) and then the posed body
//!   surface itself (`surface`: an AABB tree over the skinned triangles, the nearest
//!   triangle and which side of it the particle is on). Same inputs, same bytes, whatever
//!   the thread count.
//! - A pre-roll ([`ClothOptions::preroll`], `preroll`) settles the garment before frame 0:
//!   the body blends from its rest pose (the garment's) to the clip's first pose and holds
//!   it, so frame 0 does not pop.
//!   Cuts in the clip ([`Cut`], `cuts`: a reference pose before the motion, a looped clip
//!   starting over) are settled into the same way.
//! - The garment collides with the body parts it was modelled near and the bones above
//!   them (`region`; [`ClothOptions::collide_all`]: the whole body), and the bones' axes
//!   are kept out of its triangles as well as its vertices out of the body (`faces`).
//! - Every output frame is measured ([`FrameStats`]: stretch, kinetic energy, speed,
//!   depth below the body surface); past a stability limit ([`Measure`]) the simulation
//!   fails with [`ClothError::Unstable`] naming the frame, or, with
//!   [`ClothOptions::allow_unstable`], goes on with a warning.
//! - [`add_garment`]: the result as morph targets on the garment mesh (one per frame, or a
//!   compressed basis as the DQS bake does) and a morph-weight track on the clip, which the
//!   glTF writer stores as sparse targets and the USD writer as `points` time samples.
//!
//! ```
//! use rigport_deform::cloth::{simulate, ClothOptions, Garment};
//! use rigport_model::glam::Vec3;
//!
//! let rig = rigport_demo::character(1);
//! let skeleton = rigport_import::pinocchio::PinocchioSkeleton {
//!     positions: rig.joint_positions.clone(),
//!     parents: rig.joint_parents.clone(),
//! };
//! let mut asset = rigport_import::pinocchio::assemble(
//!     "demo", rig.mesh, &skeleton, Some(&rig.joint_names), &rig.bone_weights, None,
//! )?
//! .asset;
//! let keys = rigport_model::PoseKeys { name: Some("still".into()), keys: vec![
//!     rigport_model::PoseKey { time: 0.0, index: 0, rotations: vec![], translation: None },
//!     rigport_model::PoseKey { time: 0.2, index: 1, rotations: vec![], translation: None },
//! ] };
//! asset.clips.push(rigport_anim::keyed::clip(&asset.skeleton, &keys, "still")?);
//! // A 3 x 3 flag sticking out forwards from the chest's front-most point (its first row
//! // is pinned there), free to fall.
//! let chest = asset.meshes[0].positions.iter().copied().filter(|p| p.y > 1.2);
//! let front = chest.fold(Vec3::ZERO, |a, p| if p.z > a.z { p } else { a });
//! let positions: Vec<Vec3> = (0..9).map(|k| front + Vec3::new((k % 3) as f32 * 0.02, 0.0, 0.03 * (k / 3) as f32)).collect();
//! let garment = Garment {
//!     positions,
//!     triangles: vec![[0, 3, 1], [1, 3, 4], [1, 4, 2], [2, 4, 5], [3, 6, 4], [4, 6, 7], [4, 7, 5], [5, 7, 8]],
//!     pinned: vec![0, 1, 2],
//! };
//! let mut warnings = Vec::new();
//! let sim = simulate(&asset, &garment, &ClothOptions { fps: Some(30.0), ..ClothOptions::default() }, &mut warnings, |_, _| {})?;
//! assert_eq!(sim.times.len(), 7);
//! assert!(sim.positions.iter().all(|p| p.is_finite()));
//! // The free corner fell; the pins stayed on the skin.
//! assert!(sim.frame(6)[8].y < front.y - 0.01);
//! // Frame 0 holds the pins' snap onto the skin; the solver then evens the edges out.
//! assert!(sim.stats[6].max_stretch < 0.05);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod asset;
pub mod attach;
pub mod collide;
mod cuts;
mod faces;
mod garment;
mod limits;
mod output;
mod preroll;
mod region;
mod simulation;
mod solver;
mod surface;

use glam::Vec3;
use rigport_model::{NoSuchClip, Transform};

pub use cuts::{Cut, CUT_MIN, CUT_RATIO};
pub use garment::{scene_height, Garment, PinSelection, CONTROL_POINTS};
pub use limits::{Measure, BODY_MEMORY, UNSTABLE_MEAN_SPEED, UNSTABLE_SPEED, UNSTABLE_STRETCH};
pub use output::{add_garment, GarmentBake};
pub use preroll::{PREROLL, PREROLL_BLEND};
pub use region::NEAR;
pub use simulation::{default_gravity, simulate};

use attach::SurfacePoint;
use collide::BoneCapsule;
use rigport_eval::sample::SampleError;
use rigport_eval::EvalError;

/// Standard gravity, m/s².
pub const GRAVITY: f64 = 9.80665;

/// Substeps per second when [`ClothOptions::substeps`] is not given (20 per frame at 60
/// fps): Macklin et al. 2019 show small substeps with one iteration each converge better
/// than many iterations of one step.
pub const SUBSTEPS_PER_SECOND: f32 = 1200.0;

/// Rounds of constraint projection that settle the starting shape after the first
/// collision push ([`solver::Solver::relax`]).
pub(crate) const RELAX_ITERATIONS: u32 = 200;

/// Frames simulated per parallel skinning batch (bounds memory on long clips).
pub(crate) const BATCH: usize = 64;

/// Why a simulation could not run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ClothError {
    /// The garment has no triangle.
    #[error("garment {garment:?} has no triangles")]
    EmptyGarment {
        /// The garment mesh.
        garment: String,
    },
    /// Nothing is pinned: the garment would fall off the body.
    #[error("garment {garment:?} has no pinned vertex (pin some by vertex or by height)")]
    NoPins {
        /// The garment mesh.
        garment: String,
    },
    /// A pinned vertex the garment does not have.
    #[error("garment {garment:?}: pinned vertex {vertex} is out of range for {count} vertices")]
    PinVertex {
        /// The garment mesh.
        garment: String,
        /// The vertex asked for.
        vertex: u32,
        /// Its vertex count.
        count: usize,
    },
    /// The garment has no per-vertex values of that name.
    #[error("garment {garment:?} has no per-vertex values named {name:?}")]
    NoValues {
        /// The garment mesh.
        garment: String,
        /// The name.
        name: String,
    },
    /// A NaN or infinite input.
    #[error("{what} is not finite")]
    NonFinite {
        /// What.
        what: String,
    },
    /// An option out of range.
    #[error("cloth option {name} = {value}: {expected}")]
    BadOption {
        /// The option.
        name: &'static str,
        /// Its value.
        value: f32,
        /// What it must be.
        expected: &'static str,
    },
    /// The input has no unskinned mesh of that name.
    #[error("no unskinned mesh named {name:?} to use as the garment; unskinned meshes: {meshes}")]
    NoGarment {
        /// The name asked for.
        name: String,
        /// The unskinned meshes there are, quoted, or empty.
        meshes: String,
    },
    /// No skinned mesh to collide with and pin to.
    #[error("the rig has no skinned mesh to put the garment on")]
    NoBody,
    /// No clip of that name.
    #[error(transparent)]
    NoSuchClip(#[from] NoSuchClip),
    /// No clip at all.
    #[error("no clip to simulate; the rig has none")]
    NoClip,
    /// The simulation went past a stability limit ([`Measure`]) at an output frame, and
    /// [`ClothOptions::allow_unstable`] was not set.
    #[error("the simulation diverged at frame {frame} (time {time} s): {measure} reached {value}, past the limit of {limit}")]
    Unstable {
        /// The first output frame past a limit.
        frame: usize,
        /// Its time, seconds.
        time: f32,
        /// What went past its limit.
        measure: Measure,
        /// Its value at that frame (units of the measure: a fraction, units²/s², units/s).
        value: f32,
        /// The limit at that frame.
        limit: f32,
    },
    /// The simulation produced a non-finite position (reported, never written).
    #[error("the simulation diverged at frame {frame} (time {time} s): a position is not finite")]
    Diverged {
        /// The frame.
        frame: usize,
        /// Its time, seconds.
        time: f32,
    },
    /// Sampling the clip failed.
    #[error(transparent)]
    Sample(#[from] SampleError),
    /// Evaluating the rig failed.
    #[error(transparent)]
    Eval(#[from] EvalError),
}

/// What [`simulate`] simulates, and how. Lengths are model units, times seconds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClothOptions<'a> {
    /// The clip (default: the first).
    pub clip: Option<&'a str>,
    /// Output frames per second (default: the clip's key rate when 24 or more, else 30).
    pub fps: Option<f32>,
    /// Simulate this long, looping the clip (default: the clip once).
    pub seconds: Option<f32>,
    /// Substeps per frame (default: [`SUBSTEPS_PER_SECOND`] / fps, rounded up).
    pub substeps: Option<u32>,
    /// Constraint iterations per substep (default 2: with one, the demo's skirt gained
    /// energy over a 10 s loop of its wave clip and stretched 14%; with two it stays at
    /// 3.6% with a kinetic energy below 0.1 m²/s² per kg).
    pub iterations: u32,
    /// Gravity, model units/s² (default: [`GRAVITY`] down the scene's up axis, converted
    /// by the asset's units, metres when it states none).
    pub gravity: Option<Vec3>,
    /// Velocity damping rate, 1/s (velocities scale by `exp(-damping h)` per substep).
    pub damping: f32,
    /// Stretch compliance (inverse stiffness; 0 = inextensible), XPBD units with unit
    /// particle masses.
    pub stretch_compliance: f32,
    /// Bending compliance.
    pub bend_compliance: f32,
    /// Collision thickness (default: 1% of the body's bounding-box diagonal).
    pub thickness: Option<f32>,
    /// Collide with the skinned body surface, and with capsules fitted to the bones
    /// (default true).
    pub collisions: bool,
    /// Seconds of pre-roll before the clip's first frame (default [`PREROLL`]): the body
    /// blends from its rest pose to the clip's first pose, then holds it, while the
    /// garment settles ([`PREROLL_BLEND`]). 0 starts the garment on the first pose directly.
    pub preroll: Option<f32>,
    /// Collide with the whole body, not only the parts near the garment at rest (within
    /// [`NEAR`] of the body's diagonal of its bounding box; default false).
    pub collide_all: bool,
    /// Keep going past the stability limits ([`Measure`]) with a warning instead of
    /// failing with [`ClothError::Unstable`] (default false).
    pub allow_unstable: bool,
}

impl Default for ClothOptions<'_> {
    fn default() -> Self {
        Self {
            clip: None,
            fps: None,
            seconds: None,
            substeps: None,
            iterations: 2,
            gravity: None,
            damping: 1.0,
            stretch_compliance: 0.0,
            bend_compliance: 1e-3,
            thickness: None,
            collisions: true,
            preroll: None,
            collide_all: false,
            allow_unstable: false,
        }
    }
}

/// Measurements of one output frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameStats {
    /// The largest edge stretch, `(length - rest) / rest` (0 when no edge is longer).
    pub max_stretch: f32,
    /// Kinetic energy per unit mass, `½ mean |v|²` over free particles (units²/s²).
    pub kinetic_energy: f32,
    /// The fastest free particle's speed, units/s.
    pub max_speed: f32,
    /// How far the deepest colliding particle (free, not one edge from a pin) is inside a
    /// capsule grown by the thickness (0 when none is). With the body surface as collider
    /// the capsules are not grown (they only keep particles out of the body's core), so
    /// this can reach the thickness.
    pub max_penetration: f32,
    /// How far the deepest garment vertex of any kind (pinned and next to a pin included)
    /// is inside a capsule itself, not grown (0 when none is).
    pub max_depth: f32,
    /// How far the deepest garment vertex of any kind is below the skinned body surface
    /// (0 when none is): the issue's "no vertex inside the body deeper than the
    /// thickness".
    pub body_depth: f32,
    /// How many garment vertices are below the skinned body surface (by more than
    /// [`ON_SURFACE`] of the body's diagonal: pins sit on it).
    pub body_inside: u32,
}

/// How far below the body surface, as a fraction of the body's diagonal, a garment vertex
/// still counts as on it (`f32` rounding of a pin evaluated on the skin).
pub const ON_SURFACE: f32 = 1e-5;

/// A finished simulation.
#[derive(Clone, Debug, PartialEq)]
pub struct Simulation {
    /// Index of the simulated clip in the asset.
    pub clip: usize,
    /// Output frame times, seconds (from the clip's start; past its end when looping).
    pub times: Vec<f32>,
    /// Particles per frame.
    pub particles: usize,
    /// `frames × particles` model-space positions, frame-major.
    pub positions: Vec<Vec3>,
    /// Each pinned particle and the body point it follows (concatenated skinned meshes in
    /// asset order).
    pub pins: Vec<(u32, SurfacePoint)>,
    /// The collision capsules.
    pub capsules: Vec<BoneCapsule>,
    /// Per frame measurements.
    pub stats: Vec<FrameStats>,
    /// Collision thickness used.
    pub thickness: f32,
    /// Substeps per frame used.
    pub substeps: u32,
    /// The body's bind-pose bounding-box diagonal.
    pub diagonal: f32,
    /// Seconds of pre-roll simulated before frame 0.
    pub preroll: f32,
    /// How fast the garment still moved at the end of the pre-roll: its largest
    /// displacement over the last pre-roll frame divided by that frame's span (units/s; 0
    /// without a pre-roll).
    pub settle_residual: f32,
    /// The cuts in the clip where the garment was settled again (none without a
    /// pre-roll; see [`Cut`]).
    pub cuts: Vec<Cut>,
    /// When the clip looped: the local joint transforms at every frame (`frames × joints`),
    /// for baking a clip that covers the whole simulation.
    pub looped_poses: Option<Vec<Transform>>,
}

impl Simulation {
    /// The particle positions of frame `f` (empty past the end).
    pub fn frame(&self, f: usize) -> &[Vec3] {
        self.positions
            .get(f * self.particles..(f + 1) * self.particles)
            .unwrap_or(&[])
    }

    /// The largest of each [`FrameStats`] field over all frames.
    pub fn worst(&self) -> FrameStats {
        self.stats
            .iter()
            .fold(FrameStats::default(), |a, s| FrameStats {
                max_stretch: a.max_stretch.max(s.max_stretch),
                kinetic_energy: a.kinetic_energy.max(s.kinetic_energy),
                max_speed: a.max_speed.max(s.max_speed),
                max_penetration: a.max_penetration.max(s.max_penetration),
                max_depth: a.max_depth.max(s.max_depth),
                body_depth: a.body_depth.max(s.body_depth),
                body_inside: a.body_inside.max(s.body_inside),
            })
    }
}

#[cfg(test)]
mod tests;
