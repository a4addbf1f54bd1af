//! [`simulate`]: the clip (after a pre-roll) on a fixed frame grid, the body skinned per
//! frame in parallel, the solver stepped serially, every output frame measured and held to
//! the stability limits.

use glam::{DVec3, Mat4, Vec3};
use rayon::prelude::*;
use rigport_model::{Asset, Transform, UpAxis, Warning};

use super::attach::nearest_point;
use super::collide::{fit_capsules, Capsule};
use super::cuts;
use super::limits::{body_reference, past_limit};
use super::preroll;
use super::region::colliding_joints;
use super::solver::{Collider, Params, Solver};
use super::surface::{Posed, Surface};
use super::{
    ClothError, ClothOptions, FrameStats, Garment, Simulation, BATCH, GRAVITY, ON_SURFACE, PREROLL,
    PREROLL_BLEND, RELAX_ITERATIONS, SUBSTEPS_PER_SECOND,
};
use rigport_eval::sample::{CompiledClip, FrameGrid, SampleJob};
use rigport_eval::{Pose, Rig, RigOutput};

/// How far from the body surface, as a fraction of the body's diagonal, the measurements
/// look for it: a vertex farther away is outside (no body is that thick: a person's
/// diagonal is over 1.7 m and their torso under 0.4 m deep).
const MEASURE_REACH: f32 = 0.15;

/// How deep below the thickness a particle is still pushed out of the body surface in a
/// substep: the thickness, or this fraction of the body's diagonal when more. A particle
/// deeper than that is left to the capsules: the nearest surface point of a point deep in
/// a limb may be on its far side, and pushing it out there throws it through the limb.
const SURFACE_REACH: f32 = 0.005;

/// The skinned meshes of an asset as one surface: bind positions and triangles.
struct Body {
    meshes: Vec<usize>,
    bind: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    /// Per vertex: its heaviest joint (skeleton index).
    heaviest: Vec<Option<usize>>,
}

impl Body {
    fn new(asset: &Asset, rig: &Rig<'_>) -> Self {
        let mut body = Body {
            meshes: Vec::new(),
            bind: Vec::new(),
            triangles: Vec::new(),
            heaviest: Vec::new(),
        };
        for (mi, mesh) in asset.meshes.iter().enumerate() {
            if rig.skin_of_mesh(mi).is_none() {
                continue;
            }
            let base = body.bind.len() as u32;
            body.meshes.push(mi);
            body.bind.extend_from_slice(&mesh.positions);
            let skin = asset.skins.iter().find(|s| s.mesh.get() == mi);
            body.heaviest.extend((0..mesh.positions.len()).map(|v| {
                let skin = skin?;
                let row = skin.influences.vertex(v);
                let best = row.iter().max_by(|a, b| a.weight.total_cmp(&b.weight))?;
                skin.joints.get(best.joint as usize).map(|j| j.get())
            }));
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

/// The body at one frame: pin targets, capsules, the skinned surface and its outward
/// vertex normals, and the local pose.
struct FrameBody {
    pins: Vec<Vec3>,
    capsules: Vec<Capsule>,
    skinned: Vec<Vec3>,
    normals: Vec<Vec3>,
    local: Vec<Transform>,
}

/// The pose a body frame shows.
#[derive(Clone, Copy, Debug)]
enum Moment {
    /// Step `step` of the settling frames of a [`Transition`] (the pre-roll is transition
    /// 0, each settled cut one more).
    Settle { transition: usize, step: usize },
    /// The clip at this output frame.
    Clip(usize),
}

/// A settling: the body blends from one pose to another and holds it while the garment
/// settles (see `preroll`); the garment is first carried by the roots' jump.
struct Transition {
    from: Vec<Transform>,
    to: Vec<Transform>,
    carry: Mat4,
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
    if let Some(p) = opts.preroll {
        if !(p.is_finite() && (0.0..=3600.0).contains(&p)) {
            return Err(bad("preroll", p, "0 to 3600 seconds"));
        }
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
    // The parts of the body the garment collides with (`region`).
    let parents: Vec<Option<usize>> = asset
        .skeleton
        .joints()
        .iter()
        .map(|j| j.parent.map(|p| p.get()))
        .collect();
    let kept = (!opts.collide_all).then(|| {
        colliding_joints(
            &garment.positions,
            &body.bind,
            &body.heaviest,
            &parents,
            diagonal,
        )
    });
    let collides_with = |j: Option<usize>| match (&kept, j) {
        (None, _) => true,
        (Some(k), Some(j)) => k.get(j).copied().unwrap_or(false),
        (Some(_), None) => false,
    };
    let capsules = if opts.collisions {
        fit_capsules(asset, None, diagonal)
            .into_iter()
            .filter(|c| collides_with(Some(c.from)))
            .collect()
    } else {
        Vec::new()
    };
    // The parts the garment collides with, and the rest of the body (which pushes it only
    // softly: `Collider::others`).
    let (collide_triangles, other_triangles): (Vec<[u32; 3]>, Vec<[u32; 3]>) = body
        .triangles
        .iter()
        .partition(|t| t.iter().any(|&i| collides_with(body.heaviest[i as usize])));
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

    // The pre-roll and the cuts (`cuts`): the poses each settles between, the garment
    // carried by the root's move, the frames.
    let rest = Pose::rest(&asset.skeleton);
    let pose_at = |t: f32| -> Result<Vec<Transform>, ClothError> {
        let mut local = rest.local.clone();
        SampleJob {
            clip: &compiled,
            time: clip_time(t),
            rest: &rest.local,
            output: &mut local,
        }
        .run()?;
        Ok(local)
    };
    let first = pose_at(start)?;
    let carry = preroll::carry(&asset.skeleton, &rest.local, &first);
    let preroll_seconds = opts.preroll.unwrap_or(PREROLL);
    let preroll_frames = if preroll_seconds > 0.0 {
        ((preroll_seconds * fps).round() as usize).max(1)
    } else {
        0
    };
    let joint_track: Vec<Vec<Vec3>> = times
        .par_iter()
        .map(|&t| -> Result<Vec<Vec3>, ClothError> {
            let pose = Pose { local: pose_at(t)? };
            let model = pose.model_matrices(&asset.skeleton)?;
            Ok(model.iter().map(|m| m.w_axis.truncate()).collect())
        })
        .collect::<Result<_, _>>()?;
    let cuts = cuts::find(&joint_track, diagonal);
    let mut transitions = vec![Transition {
        from: rest.local.clone(),
        to: first,
        carry,
    }];
    let mut moments = Vec::with_capacity(preroll_frames * (1 + cuts.len()) + times.len());
    let settle = |transition: usize| {
        (0..preroll_frames).map(move |step| Moment::Settle { transition, step })
    };
    moments.extend(settle(0));
    for (f, &t) in times.iter().enumerate() {
        if preroll_frames > 0 && cuts.iter().any(|c| c.frame == f) {
            let (from, to) = (rest.local.clone(), pose_at(t)?);
            transitions.push(Transition {
                carry: preroll::carry(&asset.skeleton, &from, &to),
                from,
                to,
            });
            moments.extend(settle(transitions.len() - 1));
        }
        moments.push(Moment::Clip(f));
    }

    // Per frame: pose, skin (in parallel), then the pin targets, capsules and normals.
    // The whole body (normals, measurements) and the parts the garment collides with.
    let whole_template = Surface::new(&body.bind, &body.triangles);
    let surface_template = Surface::new(&body.bind, &collide_triangles);
    let others_template = (opts.collisions && !other_triangles.is_empty())
        .then(|| Surface::new(&body.bind, &other_triangles).inside_as(&whole_template));
    let joints = asset.skeleton.len();
    let eval_frame = |m: Moment| -> Result<FrameBody, ClothError> {
        let mut pose = rest.clone();
        match m {
            Moment::Settle { transition, step } => {
                let tr = &transitions[transition];
                preroll::blend(
                    &asset.skeleton,
                    &tr.from,
                    &tr.to,
                    preroll::weight(step as f32 / preroll_frames as f32),
                    &mut pose.local,
                )
            }
            Moment::Clip(f) => pose.local = pose_at(times[f])?,
        }
        let mut out = RigOutput::default();
        rig.evaluate(&pose, &mut out)?;
        let mut skinned = Vec::with_capacity(body.bind.len());
        body.gather(&out, &mut skinned);
        let mut normals = Vec::new();
        whole_template.normals(&skinned, &mut normals);
        Ok(FrameBody {
            pins: pins.iter().map(|(_, sp)| sp.eval(&skinned)).collect(),
            capsules: capsules
                .iter()
                .map(|c| Capsule::place(c, &out.joint_model))
                .collect(),
            skinned,
            normals,
            local: pose.local,
        })
    };

    let mut solver = Solver::new(&garment.positions, &garment.triangles, &pinned);
    if carry != Mat4::IDENTITY {
        let m = carry.as_dmat4();
        for x in &mut solver.x {
            *x = m.transform_point3(*x);
        }
    }
    let mut stepper = Stepper {
        surface: surface_template.clone(),
        others: others_template.clone(),
        collisions: opts.collisions,
        reach: thickness.max(SURFACE_REACH * diagonal),
        substeps,
        pin_targets: vec![DVec3::ZERO; pins.len()],
        caps: vec![Capsule::default(); capsules.len()],
        peak: 0.0,
    };
    let mut whole = whole_template.clone();
    let mut settle_residual = 0.0f32;
    let preroll_span = if preroll_frames > 0 {
        f64::from(preroll_seconds) / preroll_frames as f64
    } else {
        0.0
    };
    let frames = times.len();
    let mut positions = Vec::with_capacity(frames * n);
    let mut stats = Vec::with_capacity(frames);
    let mut looped_poses = looping.then(|| Vec::with_capacity(frames * joints));
    let mut previous: Option<(Moment, FrameBody)> = None;
    // The first frame past a limit (frame, measure, value, limit) and how many were.
    let mut unstable = None;
    let mut unstable_frames = 0usize;
    let mut body_speed = 0.0f32;
    for batch in moments.chunks(BATCH) {
        let evaluated: Vec<FrameBody> = batch
            .par_iter()
            .map(|&m| eval_frame(m))
            .collect::<Result<_, _>>()?;
        for (j, fb) in evaluated.into_iter().enumerate() {
            let moment = batch[j];
            let output = match moment {
                Moment::Clip(f) => Some(f),
                Moment::Settle { .. } => None,
            };
            match (&previous, moment) {
                (None, _) => stepper.start(&mut solver, &fb, params.thickness),
                // A cut: the garment jumps with the roots, at rest, onto the new body.
                (
                    Some(_),
                    Moment::Settle {
                        transition,
                        step: 0,
                    },
                ) => {
                    let m = transitions[transition].carry.as_dmat4();
                    for (x, p) in solver.x.iter_mut().zip(&garment.positions) {
                        *x = m.transform_point3(p.as_dvec3());
                    }
                    solver.v.iter_mut().for_each(|v| *v = DVec3::ZERO);
                    stepper.peak = 0.0;
                    stepper.start(&mut solver, &fb, params.thickness);
                }
                (Some((prev_moment, prev)), _) => {
                    let (span, settle) = match (prev_moment, moment) {
                        // The frame's own span: the last frame may end off the grid.
                        (Moment::Clip(_), Moment::Clip(f)) => {
                            (f64::from(times[f]) - f64::from(times[f - 1]), false)
                        }
                        // Settling frames (the last lands on a clip frame): settling once
                        // the body holds.
                        (_, Moment::Settle { step, .. }) => (
                            preroll_span,
                            step as f32 > PREROLL_BLEND * preroll_frames as f32,
                        ),
                        (_, Moment::Clip(_)) => (preroll_span, true),
                    };
                    let before = (output == Some(0)).then(|| solver.x.clone());
                    stepper.frame(&mut solver, prev, &fb, span, &params, settle);
                    if let Some(before) = before {
                        settle_residual = before
                            .iter()
                            .zip(&solver.x)
                            .map(|(a, b)| (*b - *a).length())
                            .fold(0.0f64, f64::max)
                            as f32
                            / span as f32;
                    }
                    let fastest = prev
                        .skinned
                        .iter()
                        .zip(&fb.skinned)
                        .map(|(a, b)| (*b - *a).length())
                        .fold(0.0f32, f32::max)
                        / span as f32;
                    body_speed = body_reference(body_speed, fastest, span as f32);
                }
            }
            if solver.x.iter().any(|p| !p.is_finite()) {
                let f = output.unwrap_or(0);
                return Err(ClothError::Diverged {
                    frame: f,
                    time: times[f],
                });
            }
            if let Some(f) = output {
                whole.refit(&fb.skinned, &fb.skinned);
                let st = measure(&solver, &fb, &whole, params.thickness, diagonal);
                if let Some((measure, value, limit)) = past_limit(&st, diagonal, body_speed) {
                    if !opts.allow_unstable {
                        return Err(ClothError::Unstable {
                            frame: f,
                            time: times[f],
                            measure,
                            value,
                            limit,
                        });
                    }
                    unstable.get_or_insert((f, measure, value, limit));
                    unstable_frames += 1;
                }
                stats.push(st);
                positions.extend(solver.x.iter().map(|p| p.as_vec3()));
                if let Some(lp) = &mut looped_poses {
                    lp.extend_from_slice(&fb.local);
                }
                progress(f + 1, frames);
            }
            previous = Some((moment, fb));
        }
    }
    if let Some((f, measure, value, limit)) = unstable {
        warnings.push(Warning::Unstable {
            location: "cloth".into(),
            message: format!(
                "the simulation went past its stability limits on {unstable_frames} of {frames} frames, first at frame {f} (time {} s): {measure} reached {value}, past the limit of {limit}; the result was kept",
                times[f]
            ),
        });
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
        preroll: preroll_frames as f32 * preroll_span as f32,
        settle_residual,
        cuts: if preroll_frames > 0 { cuts } else { Vec::new() },
        looped_poses,
    })
}

/// Steps the solver from one body frame to the next.
struct Stepper {
    /// The body surface's tree (boxes around the frame being stepped).
    surface: Surface,
    /// The rest of the body's (see `Collider::others`), when collisions are on.
    others: Option<Surface>,
    collisions: bool,
    /// How far below the thickness the surface pushes ([`SURFACE_REACH`]).
    reach: f32,
    substeps: u32,
    pin_targets: Vec<DVec3>,
    caps: Vec<Capsule>,
    /// While settling: the kinetic energy after the last substep (see `preroll`).
    peak: f64,
}

impl Stepper {
    /// The first frame: pins on the skin, the garment pushed out of the body and relaxed.
    fn start(&mut self, solver: &mut Solver, fb: &FrameBody, thickness: f64) {
        for (&p, &t) in solver.pinned().to_vec().iter().zip(&fb.pins) {
            solver.x[p as usize] = t.as_dvec3();
        }
        self.refit(&fb.skinned, &fb.skinned);
        // Anywhere inside: the garment may start deep in the body.
        let posed = Posed::at(&fb.skinned, &fb.normals);
        let collider = self.collider(&fb.capsules, posed, f32::INFINITY);
        solver.relax(&collider, thickness, RELAX_ITERATIONS);
    }

    /// Fits the body surfaces' boxes around `from` and `to`.
    fn refit(&mut self, from: &[Vec3], to: &[Vec3]) {
        self.surface.refit(from, to);
        if let Some(o) = &mut self.others {
            o.refit(from, to);
        }
    }

    /// The colliders at one instant: `capsules`, and the body surfaces posed as `posed` when
    /// collisions are on.
    fn collider<'a>(
        &'a self,
        capsules: &'a [Capsule],
        posed: Posed<'a>,
        reach: f32,
    ) -> Collider<'a> {
        Collider {
            capsules,
            surface: self.collisions.then_some((&self.surface, posed)),
            others: self.others.as_ref().map(|o| (o, posed)),
            reach,
        }
    }

    /// The substeps from `prev` to `cur` over `span` seconds: pins and capsules lerped,
    /// the surface lerped inside boxes fitted around both ends. `settle`: kinetic damping
    /// (velocities zeroed when the kinetic energy has passed a peak).
    fn frame(
        &mut self,
        solver: &mut Solver,
        prev: &FrameBody,
        cur: &FrameBody,
        span: f64,
        params: &Params,
        settle: bool,
    ) {
        self.refit(&prev.skinned, &cur.skinned);
        let h = span / f64::from(self.substeps);
        for s in 1..=self.substeps {
            let a = f64::from(s) / f64::from(self.substeps);
            if s == self.substeps {
                // Land exactly on the frame's skin.
                for (dst, p) in self.pin_targets.iter_mut().zip(&cur.pins) {
                    *dst = p.as_dvec3();
                }
                self.caps.copy_from_slice(&cur.capsules);
            } else {
                for ((dst, p0), p1) in self.pin_targets.iter_mut().zip(&prev.pins).zip(&cur.pins) {
                    *dst = p0.as_dvec3().lerp(p1.as_dvec3(), a);
                }
                for ((dst, c0), c1) in self.caps.iter_mut().zip(&prev.capsules).zip(&cur.capsules) {
                    *dst = Capsule {
                        a: c0.a.lerp(c1.a, a),
                        b: c0.b.lerp(c1.b, a),
                        radius: c1.radius,
                    };
                }
            }
            let posed = Posed {
                from: &prev.skinned,
                to: &cur.skinned,
                from_normals: &prev.normals,
                to_normals: &cur.normals,
                a: a as f32,
            };
            let collider = self.collider(&self.caps, posed, self.reach);
            solver.substep(h, params, &self.pin_targets, &collider);
            if settle {
                let ke: f64 = solver.v.iter().map(|v| v.length_squared()).sum();
                if ke < self.peak {
                    solver.v.iter_mut().for_each(|v| *v = DVec3::ZERO);
                    self.peak = 0.0;
                } else {
                    self.peak = ke;
                }
            }
        }
    }
}

/// The frame's stretch, kinetic energy, speed and penetrations (capsules and the body
/// surface; `surface`'s boxes must hold the frame).
fn measure(
    solver: &Solver,
    fb: &FrameBody,
    surface: &Surface,
    thickness: f64,
    diagonal: f32,
) -> FrameStats {
    let mut s = FrameStats::default();
    for c in &solver.stretch {
        if c.rest > 0.0 {
            let len = (solver.x[c.i as usize] - solver.x[c.j as usize]).length();
            s.max_stretch = s.max_stretch.max(((len - c.rest) / c.rest) as f32);
        }
    }
    let posed = Posed::at(&fb.skinned, &fb.normals);
    let mut ke = 0.0f64;
    let mut free = 0usize;
    for (i, (x, v)) in solver.x.iter().zip(&solver.v).enumerate() {
        for c in &fb.capsules {
            s.max_depth = s.max_depth.max(c.depth(*x, 0.0) as f32);
        }
        if let Some(hit) = surface.nearest(&posed, x.as_vec3(), MEASURE_REACH * diagonal) {
            let depth = -hit.signed;
            if depth > ON_SURFACE * diagonal {
                s.body_inside += 1;
                s.body_depth = s.body_depth.max(depth);
            }
        }
        if !solver.is_free(i) {
            continue;
        }
        free += 1;
        ke += v.length_squared();
        s.max_speed = s.max_speed.max(v.length() as f32);
        if solver.collides(i) {
            for c in &fb.capsules {
                s.max_penetration = s.max_penetration.max(c.depth(*x, thickness) as f32);
            }
        }
    }
    s.kinetic_energy = (0.5 * ke / free.max(1) as f64) as f32;
    s
}
