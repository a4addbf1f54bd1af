//! IK benchmark table (issue 4, acceptance 1 and 2).
//!
//! `cargo run --release --example ik_bench [-- --sets N] [--passes P]` prints two markdown
//! tables (defaults: 1000 sets, 3 passes):
//!
//! 1. Per rig and solver: success rate, mean iterations and median time per solve over `N`
//!    (default 1000) seeded random target sets, each made by forward kinematics of a random
//!    pose (every joint turned from rest by Euler angles drawn uniformly within ±45° per
//!    axis), solved from the rest pose. A solve succeeds when every handle ends within
//!    `1e-3 · height` of its target, measured by an independent forward-kinematics pass
//!    (`IkProblem::effector_positions`), `height` being the largest side of the bounding
//!    box of the rest joint positions and effectors (the height for the standing armadillo
//!    and humanoid; the hand lies along Z, so its length).
//! 2. rigport `dls` against the `k` crate's `JacobianIkSolver` (openrr; SVD pseudo-inverse
//!    steps) on single serial chains of the same rigs: a `k::SerialChain` with the same
//!    joint offsets and rest rotations, 3 revolute axes (x, y, z) per joint, the same
//!    targets and success test, both from the rest pose, in one run.
//!
//! Rigs (paths relative to the repository's parent, `../shared/corpus/`; a rig whose files
//! are absent is skipped with a message):
//! - CSCI 520 armadillo (`2_csci520_ik_skinning/tydia/armadillo`): the `IKJointIDs`
//!   handles 15, 19 (hands), 4, 8 (feet). Serial chain: joint 15's ancestors (root to
//!   wrist, 7 joints).
//! - CSCI 520 hand (`.../tydia/hand`): the 5 fingertips of `IKJointIDs` (6, 10, 14, 22,
//!   18). Serial chain: fingertip 10's ancestors (6 joints).
//! - Pinocchio humanoid (`1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/
//!   human_model1`): two hands. Pinocchio's human skeleton (`HumanSkeleton` in its
//!   `skeleton.cpp`) numbers the hands 14 and 17, each the end of a 3-bone arm hanging off
//!   the shoulders joint 0 (12→13→14, 15→16→17). A hand is a bone's tail, which rigport's
//!   skeleton has no joint for (see `rigport_import::pinocchio`), so each handle is the
//!   forearm joint `bone_14` / `bone_17` with the effector offset `position[14] -
//!   position[13]` (resp. 17, 16) from `skeleton.out`. The example checks that topology
//!   and skips the rig if it differs. Serial chain: the left arm (root to forearm, 4 joints).
//!
//! Solver settings: tolerance `1e-3 · height`, `max_step_rad` 0.5; at most 100 iterations
//! for `dls` (adaptive damping) and `pinv` (cutoff 1e-3), 1000 for `transpose`, `ccd` and
//! `fabrik`. `k`: `allowable_target_distance` `1e-3 · height`, jacobian multiplier 1 (and
//! 0.5, its documented example value), at most 100 tries, position-only constraints.
//! Times are wall-clock per solve (`Instant` around `IkSolveJob::run`, resp. `k`'s
//! `solve_with_constraints`), median over the sets, on one core; each measurement runs `P`
//! times and the pass with the lowest median is kept (see [`best_of`]).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use k::nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use k::InverseKinematicsSolver;
use rigport_ik::{
    IkEffector, IkHandle, IkMethod, IkProblem, IkReport, IkScratch, IkSettings, IkSolveJob, Lambda,
};
use rigport_import::{csci520, pinocchio};
use rigport_model::glam::{EulerRot, Quat, Vec3};
use rigport_model::{JointIndex, Skeleton, Transform};

/// Seed of every rig's target sets (the same sets for every solver).
pub const SEED: u64 = 520;
/// Random poses turn each joint by up to this much per Euler axis.
pub const MAX_ANGLE_RAD: f32 = std::f32::consts::FRAC_PI_4;
/// Success: every residual below this fraction of the rig's height.
pub const SUCCESS_FRACTION: f32 = 1e-3;

/// A benchmark subject: a skeleton and its IK handles.
pub struct BenchRig {
    /// Display name.
    pub name: String,
    /// The skeleton.
    pub skeleton: Skeleton,
    /// The handles' effectors.
    pub handles: Vec<IkEffector>,
    /// The serial chain for the `k` comparison: a handle's effector.
    pub chain_handle: IkEffector,
    /// Largest side of the rest bounding box (joints and effectors).
    pub height: f32,
}

/// SplitMix64 (Steele, Lea & Flood 2014): seeded, portable, no dependency.
pub struct Rng(pub u64);

impl Rng {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `lo..hi`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        let unit = (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32;
        lo + (hi - lo) * unit
    }
}

/// `../shared/corpus` beside the repository.
pub fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/corpus")
}

fn height(skeleton: &Skeleton, handles: &[IkEffector]) -> f32 {
    let model = skeleton.model_rest_matrices();
    let points = model.iter().map(|m| m.w_axis.truncate()).chain(
        handles
            .iter()
            .map(|e| model[e.joint.get()].transform_point3(e.local_offset)),
    );
    let (lo, hi) = points.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
        (lo.min(p), hi.max(p))
    });
    (hi - lo).max_element()
}

fn csci520_rig(name: &str, folder: &str, chain_handle: u32) -> Option<BenchRig> {
    let config = corpus()
        .join("2_csci520_ik_skinning/tydia")
        .join(folder)
        .join("skin.config");
    if !config.exists() {
        eprintln!("SKIPPED {name}: {} is absent", config.display());
        return None;
    }
    let rig = match csci520::import(&config) {
        Ok(rig) => rig,
        Err(e) => {
            eprintln!("SKIPPED {name}: {e}");
            return None;
        }
    };
    let skeleton = rig.imported.asset.skeleton;
    let handles: Vec<IkEffector> = rig.ik_handles.iter().map(|&j| j.into()).collect();
    // `IKJointIDs` are file indices; the skeleton names joints `joint_<file index>`.
    let chain = skeleton.find(&format!("joint_{chain_handle}"))?;
    Some(BenchRig {
        name: name.to_string(),
        height: height(&skeleton, &handles),
        skeleton,
        handles,
        chain_handle: chain.into(),
    })
}

fn pinocchio_rig() -> Option<BenchRig> {
    let name = "Pinocchio human_model1 (2 hands)";
    let dir = corpus().join("1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1");
    let files = ["Model1.obj", "skeleton.out", "attachment.out"].map(|f| dir.join(f));
    if let Some(missing) = files.iter().find(|f| !f.exists()) {
        eprintln!("SKIPPED {name}: {} is absent", missing.display());
        return None;
    }
    let [mesh, skel, att] = &files;
    let imported = pinocchio::import(mesh, skel, att).ok()?;
    let text = std::fs::read_to_string(skel).ok()?;
    let pino = pinocchio::parse_skeleton(&text, skel).ok()?;
    // Pinocchio's HumanSkeleton: hands 14 and 17 at the end of 0 -> 12 -> 13 -> 14 and
    // 0 -> 15 -> 16 -> 17, and nothing hangs off a hand.
    let parent = |k: usize| pino.parents.get(k).copied().flatten();
    let is_arm = |hand: usize| {
        parent(hand) == Some(hand - 1)
            && parent(hand - 1) == Some(hand - 2)
            && parent(hand - 2) == Some(0)
            && !pino.parents.contains(&Some(hand))
    };
    if pino.positions.len() != 18 || !is_arm(14) || !is_arm(17) {
        eprintln!("SKIPPED {name}: not Pinocchio's 18-joint human skeleton");
        return None;
    }
    let skeleton = imported.asset.skeleton;
    let hand = |k: usize| -> Option<IkEffector> {
        let joint = skeleton.find(&format!("bone_{k}"))?;
        // bone_k's rest rotation is the identity, so model offsets are local offsets.
        Some(IkEffector {
            joint,
            local_offset: pino.positions[k] - pino.positions[k - 1],
        })
    };
    let handles = vec![hand(14)?, hand(17)?];
    Some(BenchRig {
        name: name.to_string(),
        height: height(&skeleton, &handles),
        chain_handle: handles[0],
        skeleton,
        handles,
    })
}

/// The corpus rigs that are present (each absent one is reported on stderr).
pub fn load_rigs() -> Vec<BenchRig> {
    [
        csci520_rig("CSCI 520 armadillo (handles 15,19,4,8)", "armadillo", 15),
        csci520_rig("CSCI 520 hand (5 fingertips)", "hand", 10),
        pinocchio_rig(),
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// The rest pose.
pub fn rest(skeleton: &Skeleton) -> Vec<Transform> {
    skeleton.joints().iter().map(|j| j.rest_local).collect()
}

/// `count` target sets, each the effector positions of a random pose (every joint turned
/// from rest by Euler angles within ±[`MAX_ANGLE_RAD`]).
pub fn target_sets(rig: &BenchRig, problem: &IkProblem, count: usize) -> Vec<Vec<IkHandle>> {
    let mut rng = Rng(SEED);
    (0..count)
        .map(|_| {
            let mut pose = rest(&rig.skeleton);
            for t in &mut pose {
                let (x, y, z) = (
                    rng.range(-MAX_ANGLE_RAD, MAX_ANGLE_RAD),
                    rng.range(-MAX_ANGLE_RAD, MAX_ANGLE_RAD),
                    rng.range(-MAX_ANGLE_RAD, MAX_ANGLE_RAD),
                );
                t.rotation = (t.rotation * Quat::from_euler(EulerRot::ZYX, z, y, x)).normalize();
            }
            let at = problem.effector_positions(&pose).unwrap_or_default();
            problem
                .effectors()
                .iter()
                .zip(at)
                .map(|(e, p)| IkHandle::new(e.joint, p))
                .collect()
        })
        .collect()
}

/// The solvers of the table, with their settings for a rig of this height.
pub fn solvers(height: f32) -> Vec<IkSettings> {
    let base = IkSettings {
        tolerance: SUCCESS_FRACTION * height,
        max_step_rad: 0.5,
        ..IkSettings::default()
    };
    [
        (
            IkMethod::Dls {
                lambda: Lambda::Adaptive,
            },
            100,
        ),
        (IkMethod::Pinv { cutoff: 1e-3 }, 100),
        (IkMethod::Transpose, 1000),
        (IkMethod::Ccd, 1000),
        (IkMethod::Fabrik, 1000),
    ]
    .into_iter()
    .map(|(method, max_iterations)| IkSettings {
        method,
        max_iterations,
        ..base
    })
    .collect()
}

/// Success rate, mean iterations and median time of a batch of solves.
#[derive(Clone, Copy, Debug)]
pub struct Stats {
    /// Fraction of solves that succeeded.
    pub success: f64,
    /// Mean iterations per solve (0 when the solver does not report them).
    pub mean_iterations: f64,
    /// Median wall-clock time per solve.
    pub median: Duration,
}

fn stats(ok: usize, iterations: u64, mut times: Vec<Duration>) -> Stats {
    let n = times.len().max(1);
    times.sort_unstable();
    Stats {
        success: ok as f64 / n as f64,
        mean_iterations: iterations as f64 / n as f64,
        median: times.get(times.len() / 2).copied().unwrap_or_default(),
    }
}

/// Solves every target set from the rest pose with rigport; success is checked by an
/// independent forward-kinematics pass.
pub fn run_rigport(
    rig: &BenchRig,
    problem: &IkProblem,
    sets: &[Vec<IkHandle>],
    settings: &IkSettings,
) -> Stats {
    let mut scratch = IkScratch::new(problem);
    let mut report = IkReport::new(problem);
    let start = rest(&rig.skeleton);
    let mut pose = start.clone();
    let limit = SUCCESS_FRACTION * rig.height;
    let (mut ok, mut iterations, mut times) = (0, 0u64, Vec::with_capacity(sets.len()));
    for targets in sets {
        pose.copy_from_slice(&start);
        let t0 = Instant::now();
        let result = IkSolveJob {
            problem,
            targets,
            settings,
            pose: &mut pose,
            scratch: &mut scratch,
            report: &mut report,
        }
        .run();
        times.push(t0.elapsed());
        if result.is_err() {
            continue;
        }
        iterations += u64::from(report.iterations);
        let reached = problem.effector_positions(&pose).unwrap_or_default();
        if reached.len() == targets.len()
            && reached
                .iter()
                .zip(targets)
                .all(|(p, t)| p.distance(t.target) < limit)
        {
            ok += 1;
        }
    }
    stats(ok, iterations, times)
}

/// The movable joints of the serial chain to `handle` (its ancestors, root first, plus the
/// handle joint itself when the effector has an offset) and the end offset (in the last
/// movable joint's frame).
pub fn chain_joints(skeleton: &Skeleton, handle: IkEffector) -> (Vec<JointIndex>, Vec3) {
    let mut joints: Vec<JointIndex> =
        std::iter::successors(skeleton.joint(handle.joint).parent, |&p| {
            skeleton.joint(p).parent
        })
        .collect();
    joints.reverse();
    if handle.local_offset != Vec3::ZERO {
        joints.push(handle.joint);
        (joints, handle.local_offset)
    } else {
        (joints, skeleton.joint(handle.joint).rest_local.translation)
    }
}

/// A `k` serial chain with the same offsets and rest rotations as the skeleton chain: per
/// joint a node with its rest translation and rotation turning about x, then nodes about y
/// and z, then a fixed end node at the effector offset. Scale is taken as 1 (both corpus
/// importers write scale 1).
pub fn k_chain(skeleton: &Skeleton, joints: &[JointIndex], end: Vec3) -> k::SerialChain<f64> {
    let mut nodes: Vec<k::Node<f64>> = Vec::new();
    for &j in joints {
        let rest = skeleton.joint(j).rest_local;
        let (t, q) = (rest.translation.as_dvec3(), rest.rotation.as_dquat());
        for (i, axis) in [Vector3::x_axis(), Vector3::y_axis(), Vector3::z_axis()]
            .into_iter()
            .enumerate()
        {
            let mut b = k::NodeBuilder::new()
                .name(&format!("{}_{i}", skeleton.joint(j).name))
                .joint_type(k::JointType::Rotational { axis });
            if i == 0 {
                b = b.translation(Translation3::new(t.x, t.y, t.z)).rotation(
                    UnitQuaternion::from_quaternion(Quaternion::new(q.w, q.x, q.y, q.z)),
                );
            }
            nodes.push(b.into_node());
        }
    }
    let e = end.as_dvec3();
    nodes.push(
        k::NodeBuilder::new()
            .name("end")
            .translation(Translation3::new(e.x, e.y, e.z))
            .into_node(),
    );
    for pair in nodes.windows(2) {
        pair[1].set_parent(&pair[0]);
    }
    // `nodes` always ends with the end node pushed above.
    let end = &nodes[nodes.len() - 1];
    k::SerialChain::from_end(end)
}

/// Solves every target set with `k` from zero joint angles (the rest pose); success checked
/// on the chain's own forward kinematics.
pub fn run_k(
    chain: &k::SerialChain<f64>,
    sets: &[Vec<IkHandle>],
    handle: usize,
    height: f32,
    multiplier: f64,
) -> Stats {
    let limit = f64::from(SUCCESS_FRACTION * height);
    let solver = k::JacobianIkSolver::new(limit, std::f64::consts::PI, multiplier, 100);
    let constraints = k::Constraints {
        rotation_x: false,
        rotation_y: false,
        rotation_z: false,
        ..Default::default()
    };
    let zero = vec![0.0; chain.dof()];
    let (mut ok, mut times) = (0, Vec::with_capacity(sets.len()));
    for targets in sets {
        let t = targets[handle].target.as_dvec3();
        let goal =
            Isometry3::from_parts(Translation3::new(t.x, t.y, t.z), UnitQuaternion::identity());
        chain.set_joint_positions_unchecked(&zero);
        let t0 = Instant::now();
        let result = solver.solve_with_constraints(chain, &goal, &constraints);
        times.push(t0.elapsed());
        chain.update_transforms();
        let reached = chain.end_transform().translation.vector;
        let dist = (reached - Vector3::new(t.x, t.y, t.z)).norm();
        if result.is_ok() && dist < limit {
            ok += 1;
        }
    }
    stats(ok, 0, times)
}

/// Runs a measurement `passes` times and keeps the pass with the lowest median: the machine
/// is shared (2 cores, other builds running), and its speed drifts over seconds, so the
/// least-disturbed pass is the one that measures the code. Success and iterations are
/// deterministic and the same in every pass.
pub fn best_of(passes: usize, mut measure: impl FnMut() -> Stats) -> Stats {
    let mut best = measure();
    for _ in 1..passes {
        let s = measure();
        if s.median < best.median {
            best = s;
        }
    }
    best
}

fn micros(d: Duration) -> f64 {
    d.as_secs_f64() * 1e6
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let option = |name: &str, default: usize| -> usize {
        match args.iter().position(|a| a == name) {
            None => default,
            Some(i) => match args.get(i + 1).and_then(|v| v.parse().ok()) {
                Some(n) => n,
                None => {
                    eprintln!("usage: ik_bench [--sets N] [--passes P]");
                    std::process::exit(2);
                }
            },
        }
    };
    let sets_count = option("--sets", 1000);
    let passes = option("--passes", 3).max(1);
    let rigs = load_rigs();
    if rigs.is_empty() {
        println!(
            "no corpus rig found under {}; nothing to measure",
            corpus().display()
        );
        return;
    }
    println!("### IK solvers: {sets_count} random target sets per rig (±45° per joint), from the rest pose; time: median of the fastest of {passes} passes\n");
    println!(
        "| rig | joints | handles | DOF | solver | success | mean iterations | median µs/solve |"
    );
    println!("|---|---:|---:|---:|---|---:|---:|---:|");
    for rig in &rigs {
        let problem = match IkProblem::new(&rig.skeleton, &rig.handles, None, &[]) {
            Ok(p) => p,
            Err(e) => {
                eprintln!("SKIPPED {}: {e}", rig.name);
                continue;
            }
        };
        let sets = target_sets(rig, &problem, sets_count);
        for settings in solvers(rig.height) {
            let s = best_of(passes, || run_rigport(rig, &problem, &sets, &settings));
            println!(
                "| {} | {} | {} | {} | {} | {:.1}% | {:.1} | {:.1} |",
                rig.name,
                rig.skeleton.len(),
                rig.handles.len(),
                3 * problem.movable().len(),
                settings.method.name(),
                100.0 * s.success,
                s.mean_iterations,
                micros(s.median)
            );
        }
    }
    println!("\n### rigport `dls` vs `k` 0.32 `JacobianIkSolver` on single serial chains ({sets_count} target sets, fastest of {passes} passes each)\n");
    println!("| chain | DOF | solver | success | median µs/solve | k / rigport time |");
    println!("|---|---:|---|---:|---:|---:|");
    for rig in &rigs {
        let (joints, end) = chain_joints(&rig.skeleton, rig.chain_handle);
        let Ok(problem) = IkProblem::new(&rig.skeleton, &[rig.chain_handle], Some(&joints), &[])
        else {
            continue;
        };
        let chain = k_chain(&rig.skeleton, &joints, end);
        // The two models agree at rest.
        chain.update_transforms();
        let k_rest = chain.end_transform().translation.vector;
        let ours = problem
            .effector_positions(&rest(&rig.skeleton))
            .unwrap_or_default()
            .first()
            .copied()
            .unwrap_or(Vec3::NAN)
            .as_dvec3();
        let gap = (k_rest - Vector3::new(ours.x, ours.y, ours.z)).norm();
        assert!(
            gap < 1e-4 * f64::from(rig.height),
            "{}: k chain differs at rest by {gap}",
            rig.name
        );
        let name = format!(
            "{}: {} chain ({} joints)",
            rig.name.split(" (").next().unwrap_or(&rig.name),
            rig.skeleton.joint(rig.chain_handle.joint).name,
            joints.len()
        );
        let sets = target_sets(rig, &problem, sets_count);
        let settings = solvers(rig.height)[0];
        let ours = best_of(passes, || run_rigport(rig, &problem, &sets, &settings));
        println!(
            "| {name} | {} | rigport dls | {:.1}% | {:.1} | 1.0 |",
            3 * joints.len(),
            100.0 * ours.success,
            micros(ours.median)
        );
        for multiplier in [1.0, 0.5] {
            let theirs = best_of(passes, || run_k(&chain, &sets, 0, rig.height, multiplier));
            println!(
                "| {name} | {} | k (multiplier {multiplier}) | {:.1}% | {:.1} | {:.1} |",
                3 * joints.len(),
                100.0 * theirs.success,
                micros(theirs.median),
                micros(theirs.median) / micros(ours.median).max(1e-9)
            );
        }
    }
}
