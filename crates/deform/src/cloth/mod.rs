//! Cloth on the animated body: a garment simulated with XPBD against a skinned character,
//! pinned vertices following the skin, colliding with capsules fitted to the bones.
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
//!   (interpolated linearly between frames) and capsule collisions
//!   ([`collide::fit_capsules`]) with a thickness as the last step of every substep.
//!   Same inputs, same bytes, whatever the thread count.
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
mod garment;
mod output;
mod solver;

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use rigport_model::{Asset, NoSuchClip, Transform, UpAxis, Warning};

pub use garment::{scene_height, Garment, PinSelection, CONTROL_POINTS};
pub use output::{add_garment, GarmentBake};

use attach::{nearest_point, SurfacePoint};
use collide::{fit_capsules, BoneCapsule, Capsule};
use rigport_eval::sample::{CompiledClip, FrameGrid, SampleError, SampleJob};
use rigport_eval::{EvalError, Pose, Rig, RigOutput};
use solver::{Params, Solver};

/// Standard gravity, m/s².
pub const GRAVITY: f64 = 9.80665;

/// Substeps per second when [`ClothOptions::substeps`] is not given (20 per frame at 60
/// fps): Macklin et al. 2019 show small substeps with one iteration each converge better
/// than many iterations of one step.
pub const SUBSTEPS_PER_SECOND: f32 = 1200.0;

/// Rounds of constraint projection that settle the starting shape after the first
/// collision push ([`solver::Solver::relax`]).
const RELAX_ITERATIONS: u32 = 200;

/// Frames simulated per parallel skinning batch (bounds memory on long clips).
const BATCH: usize = 64;

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
    /// Collide with capsules fitted to the bones (default true).
    pub collisions: bool,
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
    /// How far the deepest colliding particle (free, not one edge from a pin) is inside a
    /// capsule grown by the thickness (0 when none is).
    pub max_penetration: f32,
    /// How far the deepest garment vertex of any kind (pinned and next to a pin included)
    /// is inside a capsule itself, not grown (0 when none is): the issue's "no garment
    /// vertex inside a collider by more than the thickness".
    pub max_depth: f32,
}

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
                max_penetration: a.max_penetration.max(s.max_penetration),
                max_depth: a.max_depth.max(s.max_depth),
            })
    }
}

/// The skinned meshes of an asset as one surface: bind positions and triangles.
struct Body {
    meshes: Vec<usize>,
    bind: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

impl Body {
    fn new(asset: &Asset, rig: &Rig<'_>) -> Self {
        let mut body = Body {
            meshes: Vec::new(),
            bind: Vec::new(),
            triangles: Vec::new(),
        };
        for (mi, mesh) in asset.meshes.iter().enumerate() {
            if rig.skin_of_mesh(mi).is_none() {
                continue;
            }
            let base = body.bind.len() as u32;
            body.meshes.push(mi);
            body.bind.extend_from_slice(&mesh.positions);
            body.triangles
                .extend(mesh.triangles.iter().map(|t| t.map(|i| i + base)));
        }
        body
    }

    fn gather(&self, out: &RigOutput, dst: &mut Vec<Vec3>) {
        dst.clear();
        for &mi in &self.meshes {
            dst.extend_from_slice(out.positions.get(mi).map_or(&[][..], Vec::as_slice));
        }
    }
}

/// Pin targets and capsules of one frame.
struct FrameBody {
    pins: Vec<Vec3>,
    capsules: Vec<Capsule>,
}

/// Gravity in model space: [`GRAVITY`] m/s² down the scene's up axis, in model units.
pub fn default_gravity(asset: &Asset) -> Vec3 {
    let up = match asset.frame.up_axis {
        UpAxis::Z => DVec3::Z,
        _ => DVec3::Y,
    };
    let mpu = asset
        .meters_per_unit
        .filter(|m| m.is_finite() && *m > 0.0)
        .unwrap_or(1.0);
    let scene = -up * (GRAVITY / mpu);
    let m = glam::DMat3::from_mat4(asset.frame.model_to_scene);
    let inv = m.inverse();
    let g = if inv.is_finite() { inv * scene } else { scene };
    g.as_vec3()
}

fn check_options(opts: &ClothOptions<'_>) -> Result<(), ClothError> {
    let bad = |name, value: f32, expected| ClothError::BadOption {
        name,
        value,
        expected,
    };
    let positive = "a positive finite number";
    let non_negative = "a finite number, 0 or more";
    for (name, v) in [("fps", opts.fps), ("seconds", opts.seconds)] {
        if let Some(v) = v {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(name, v, positive));
            }
        }
    }
    for (name, v) in [
        ("damping", Some(opts.damping)),
        ("stretch compliance", Some(opts.stretch_compliance)),
        ("bend compliance", Some(opts.bend_compliance)),
        ("thickness", opts.thickness),
    ] {
        if let Some(v) = v {
            if !(v.is_finite() && v >= 0.0) {
                return Err(bad(name, v, non_negative));
            }
        }
    }
    if let Some(s) = opts.substeps {
        if s == 0 || s > 10_000 {
            return Err(bad("substeps", s as f32, "1 to 10000"));
        }
    }
    if opts.iterations == 0 || opts.iterations > 1000 {
        return Err(bad("iterations", opts.iterations as f32, "1 to 1000"));
    }
    if let Some(g) = opts.gravity {
        if !g.is_finite() {
            return Err(ClothError::NonFinite {
                what: "gravity".into(),
            });
        }
    }
    Ok(())
}

/// Simulates `garment` on the skinned meshes of `asset` playing one clip (see the module
/// docs). Lossy or suspicious inputs (pins far from the skin, a garment starting inside a
/// collider) go into `warnings`; `progress(done, total)` is called after every frame.
///
/// # Errors
/// Bad options or garment ([`ClothError::BadOption`], [`ClothError::NonFinite`],
/// [`ClothError::NoPins`], ...), no skinned mesh, no such clip, a clip that does not fit
/// the skeleton, and [`ClothError::Diverged`] rather than a non-finite position.
pub fn simulate(
    asset: &Asset,
    garment: &Garment,
    opts: &ClothOptions<'_>,
    warnings: &mut Vec<Warning>,
    mut progress: impl FnMut(usize, usize),
) -> Result<Simulation, ClothError> {
    check_options(opts)?;
    let n = garment.positions.len();
    if garment.triangles.is_empty() {
        return Err(ClothError::EmptyGarment {
            garment: String::new(),
        });
    }
    if garment.positions.iter().any(|p| !p.is_finite()) {
        return Err(ClothError::NonFinite {
            what: "garment positions".into(),
        });
    }
    if let Some(&bad) = garment
        .triangles
        .iter()
        .flatten()
        .find(|&&i| i as usize >= n)
    {
        return Err(ClothError::PinVertex {
            garment: "triangle".into(),
            vertex: bad,
            count: n,
        });
    }
    let mut pinned = garment.pinned.clone();
    pinned.sort_unstable();
    pinned.dedup();
    if pinned.is_empty() {
        return Err(ClothError::NoPins {
            garment: String::new(),
        });
    }
    if let Some(&bad) = pinned.iter().find(|&&i| i as usize >= n) {
        return Err(ClothError::PinVertex {
            garment: String::new(),
            vertex: bad,
            count: n,
        });
    }

    let clip_index = asset.clip_index(opts.clip)?.ok_or(ClothError::NoClip)?;
    let compiled = CompiledClip::new(&asset.clips[clip_index], &asset.skeleton)?;
    let rig = Rig::new(asset)?;
    let body = Body::new(asset, &rig);
    if body.triangles.is_empty() {
        return Err(ClothError::NoBody);
    }
    let diagonal = {
        let lo = body
            .bind
            .iter()
            .fold(Vec3::splat(f32::INFINITY), |a, p| a.min(*p));
        let hi = body
            .bind
            .iter()
            .fold(Vec3::splat(f32::NEG_INFINITY), |a, p| a.max(*p));
        (hi - lo).length()
    };
    if !diagonal.is_finite() {
        return Err(ClothError::NonFinite {
            what: "body positions".into(),
        });
    }
    let thickness = opts.thickness.unwrap_or(0.01 * diagonal);

    // Frame times.
    let fps = opts
        .fps
        .or_else(|| compiled.fps().filter(|&f| f >= 24.0))
        .unwrap_or(30.0);
    let start = compiled.start();
    let duration = compiled.duration();
    let (times, looping) = match opts.seconds {
        Some(s) if s > duration => (FrameGrid::new(start, start + s, fps)?.into_times(), true),
        Some(s) => (FrameGrid::new(start, start + s, fps)?.into_times(), false),
        None => (
            FrameGrid::new(start, compiled.end(), fps)?.into_times(),
            false,
        ),
    };
    // The grid ends on the clip's end even off the grid; an end within a thousandth of a
    // frame of the last grid time (f32 noise) is the same frame.
    let mut times = times;
    if let [.., a, b] = times.as_slice() {
        if (b - a) * fps < 1e-3 {
            times.pop();
        }
    }
    let clip_time = |t: f32| {
        if looping && duration > 0.0 {
            start + (t - start).rem_euclid(duration)
        } else {
            t
        }
    };
    let substeps = opts
        .substeps
        .unwrap_or_else(|| (SUBSTEPS_PER_SECOND / fps).ceil().clamp(1.0, 10_000.0) as u32);
    let gravity = opts.gravity.unwrap_or_else(|| default_gravity(asset));
    let params = Params {
        gravity: gravity.as_dvec3(),
        damping: f64::from(opts.damping),
        stretch_compliance: f64::from(opts.stretch_compliance),
        bend_compliance: f64::from(opts.bend_compliance),
        thickness: f64::from(thickness),
        iterations: opts.iterations,
    };

    // Bind each pin to the nearest point of the body at bind time.
    let mut pins = Vec::with_capacity(pinned.len());
    let mut far = Vec::new();
    for &p in &pinned {
        let at = garment.positions[p as usize];
        let (sp, d) = nearest_point(at, &body.bind, &body.triangles).ok_or(ClothError::NoBody)?;
        if d > thickness {
            far.push((p, d));
        }
        pins.push((p, sp));
    }
    if !far.is_empty() {
        let worst = far.iter().map(|f| f.1).fold(0.0f32, f32::max);
        warnings.push(Warning::Repaired {
            location: "garment".into(),
            message: format!(
                "{} pinned vertices are farther than the thickness ({thickness:.4}) from the body (up to {worst:.4}); they move onto the nearest skin point",
                far.len()
            ),
        });
    }
    let capsules = if opts.collisions {
        fit_capsules(asset, None, diagonal)
    } else {
        Vec::new()
    };
    {
        let rest = asset.skeleton.model_rest_matrices();
        let placed: Vec<Capsule> = capsules.iter().map(|c| Capsule::place(c, &rest)).collect();
        let mut inside = 0usize;
        let mut deepest = 0.0f32;
        for (i, p) in garment.positions.iter().enumerate() {
            if pinned.binary_search(&(i as u32)).is_ok() {
                continue;
            }
            let d = placed
                .iter()
                .map(|c| c.depth(p.as_dvec3(), 0.0) as f32)
                .fold(f32::NEG_INFINITY, f32::max);
            if d > thickness {
                inside += 1;
                deepest = deepest.max(d);
            }
        }
        if inside > 0 {
            warnings.push(Warning::Repaired {
                location: "garment".into(),
                message: format!(
                    "{inside} garment vertices start inside the body's collision capsules (up to {deepest:.4} deep); the first substep pushes them out"
                ),
            });
        }
    }

    // Per frame: sample, pose, skin (in parallel), then the pin targets and capsules.
    let rest = Pose::rest(&asset.skeleton);
    let joints = asset.skeleton.len();
    let eval_frame = |t: f32| -> Result<(FrameBody, Vec<Transform>), ClothError> {
        let mut pose = rest.clone();
        SampleJob {
            clip: &compiled,
            time: clip_time(t),
            rest: &rest.local,
            output: &mut pose.local,
        }
        .run()?;
        let mut out = RigOutput::default();
        rig.evaluate(&pose, &mut out)?;
        let mut skinned = Vec::with_capacity(body.bind.len());
        body.gather(&out, &mut skinned);
        let pins = pins.iter().map(|(_, sp)| sp.eval(&skinned)).collect();
        let capsules = capsules
            .iter()
            .map(|c| Capsule::place(c, &out.joint_model))
            .collect();
        Ok((FrameBody { pins, capsules }, pose.local))
    };

    let mut solver = Solver::new(&garment.positions, &garment.triangles, &pinned);
    let frames = times.len();
    let mut positions = Vec::with_capacity(frames * n);
    let mut stats = Vec::with_capacity(frames);
    let mut looped_poses = looping.then(|| Vec::with_capacity(frames * joints));
    let mut previous: Option<FrameBody> = None;
    let mut pin_targets = vec![DVec3::ZERO; pins.len()];
    let mut caps = vec![Capsule::default(); capsules.len()];
    for (batch_index, batch) in times.chunks(BATCH).enumerate() {
        let evaluated: Vec<(FrameBody, Vec<Transform>)> = batch
            .par_iter()
            .map(|&t| eval_frame(t))
            .collect::<Result<_, _>>()?;
        for (k, (fb, local)) in evaluated.into_iter().enumerate() {
            let f = batch_index * BATCH + k;
            match &previous {
                None => {
                    // Frame 0: the garment at rest, pins on the skin, pushed out of the body
                    // and relaxed.
                    for (&p, &t) in solver.pinned().to_vec().iter().zip(&fb.pins) {
                        solver.x[p as usize] = t.as_dvec3();
                    }
                    solver.relax(&fb.capsules, params.thickness, RELAX_ITERATIONS);
                }
                Some(prev) => {
                    // The frame's own span: the last frame may end off the grid.
                    let span = f64::from(times[f]) - f64::from(times[f - 1]);
                    let h = span / f64::from(substeps);
                    for s in 1..=substeps {
                        let a = f64::from(s) / f64::from(substeps);
                        for ((dst, p0), p1) in pin_targets.iter_mut().zip(&prev.pins).zip(&fb.pins)
                        {
                            *dst = p0.as_dvec3().lerp(p1.as_dvec3(), a);
                        }
                        for ((dst, c0), c1) in caps.iter_mut().zip(&prev.capsules).zip(&fb.capsules)
                        {
                            *dst = Capsule {
                                a: c0.a.lerp(c1.a, a),
                                b: c0.b.lerp(c1.b, a),
                                radius: c1.radius,
                            };
                        }
                        if s == substeps {
                            // Land exactly on the frame's skin.
                            for (dst, p) in pin_targets.iter_mut().zip(&fb.pins) {
                                *dst = p.as_dvec3();
                            }
                            caps.copy_from_slice(&fb.capsules);
                        }
                        solver.substep(h, &params, &pin_targets, &caps);
                    }
                }
            }
            if solver.x.iter().any(|p| !p.is_finite()) {
                return Err(ClothError::Diverged {
                    frame: f,
                    time: times[f],
                });
            }
            stats.push(measure(&solver, &fb.capsules, params.thickness));
            positions.extend(solver.x.iter().map(|p| p.as_vec3()));
            if let Some(lp) = &mut looped_poses {
                lp.extend_from_slice(&local);
            }
            previous = Some(fb);
            progress(f + 1, frames);
        }
    }
    Ok(Simulation {
        clip: clip_index,
        times,
        particles: n,
        positions,
        pins,
        capsules,
        stats,
        thickness,
        substeps,
        diagonal,
        looped_poses,
    })
}

/// The frame's stretch, kinetic energy and penetration.
fn measure(solver: &Solver, capsules: &[Capsule], thickness: f64) -> FrameStats {
    let mut s = FrameStats::default();
    for c in &solver.stretch {
        if c.rest > 0.0 {
            let len = (solver.x[c.i as usize] - solver.x[c.j as usize]).length();
            s.max_stretch = s.max_stretch.max(((len - c.rest) / c.rest) as f32);
        }
    }
    let mut ke = 0.0f64;
    let mut free = 0usize;
    for (i, (x, v)) in solver.x.iter().zip(&solver.v).enumerate() {
        for c in capsules {
            s.max_depth = s.max_depth.max(c.depth(*x, 0.0) as f32);
        }
        if !solver.is_free(i) {
            continue;
        }
        free += 1;
        ke += v.length_squared();
        if solver.collides(i) {
            for c in capsules {
                s.max_penetration = s.max_penetration.max(c.depth(*x, thickness) as f32);
            }
        }
    }
    s.kinetic_energy = (0.5 * ke / free.max(1) as f64) as f32;
    s
}

#[cfg(test)]
mod tests;
