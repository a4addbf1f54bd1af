//! Chain-aware IK clips (`rigport_ik::chains`, `solve_clip_on`) on corpus rigs:
//! orientation targets, IK layered over a BVH walk, limits, pins.
//!
//! `cargo test -p rigport-eval --test ik_chains -- --nocapture` prints the figures.

use std::path::PathBuf;

mod common;
use common::{arm_chain, corpus, open};

use rigport_eval::sample::{CompiledClip, SampleJob};
use rigport_eval::Pose;
use rigport_ik::clip::{solve_clip_on, ClipSolveOptions};
use rigport_ik::{IkMethod, JointLimit};
use rigport_model::glam::{Quat, Vec3, Vec4};
use rigport_model::{
    Asset, Clip, HandleSet, HandleSolver, HandleTrack, JointIndex, RotationLimit, Skeleton,
    Transform,
};

fn set(tracks: Vec<HandleTrack>) -> HandleSet {
    HandleSet {
        fps: Some(10.0),
        tracks,
        base: None,
        root_motion: None,
        limits: Vec::new(),
    }
}

fn height(skeleton: &Skeleton) -> f32 {
    let rest = skeleton.model_rest_matrices();
    let (lo, hi) = rest.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), m| {
        (lo.min(m.w_axis.truncate()), hi.max(m.w_axis.truncate()))
    });
    (hi - lo).max_element()
}

/// Local poses of `clip` at `times`.
fn sample(skeleton: &Skeleton, clip: &Clip, times: &[f32]) -> Vec<Vec<Transform>> {
    let compiled = CompiledClip::new(clip, skeleton).expect("clip fits");
    let rest: Vec<Transform> = skeleton.joints().iter().map(|j| j.rest_local).collect();
    times
        .iter()
        .map(|&t| {
            let mut out = rest.clone();
            SampleJob {
                clip: &compiled,
                time: t,
                rest: &rest,
                output: &mut out,
            }
            .run()
            .expect("samples");
            out
        })
        .collect()
}

/// Reachable position and rotation targets for the arm's tip: the tip's pose under random
/// bends of the chain.
fn reachable_targets(skeleton: &Skeleton, chain: [JointIndex; 3]) -> (Vec<Vec3>, Vec<Quat>) {
    let mut positions = Vec::new();
    let mut rotations = Vec::new();
    for k in 0..4 {
        let mut pose = Pose::rest(skeleton);
        let a = 0.3 + 0.15 * k as f32;
        for (i, j) in [chain[0], chain[1], chain[2]].into_iter().enumerate() {
            let l = &mut pose.local[j.get()];
            let axis = Vec3::new(1.0, 0.5 * i as f32, 0.3 * k as f32).normalize();
            l.rotation = (l.rotation * Quat::from_axis_angle(axis, a)).normalize();
        }
        let model = pose.model_matrices(skeleton).expect("pose fits");
        let (_, r, p) = model[chain[2].get()].to_scale_rotation_translation();
        positions.push(p);
        rotations.push(r.normalize());
    }
    (positions, rotations)
}

fn orientation_case(label: &str, asset: &Asset) {
    let skeleton = &asset.skeleton;
    let chain = arm_chain(skeleton);
    let (positions, rotations) = reachable_targets(skeleton, chain);
    let times: Vec<f32> = (0..positions.len()).map(|k| k as f32).collect();
    let name = skeleton.joints()[chain[2].get()].name.clone();
    for solver in [HandleSolver::TwoBone, HandleSolver::Iterative] {
        let mut track = HandleTrack::keyed(chain[2], &name, times.clone(), positions.clone());
        track.rotations = rotations.iter().copied().map(Some).collect();
        track.solver = solver;
        track.root = Some(chain[0]);
        let options = ClipSolveOptions {
            fps: Some(1.0),
            ..ClipSolveOptions::default()
        };
        let solved =
            solve_clip_on(skeleton, &[], &set(vec![track]), &options, "o", label).expect("solves");
        let h = &solved.handles[0];
        println!(
            "{label} {solver:?}: position {:.2e} of the height, rotation {:.2e} deg",
            h.max_residual / height(skeleton),
            h.max_orientation_residual_deg
        );
        assert!(
            h.max_orientation_residual_deg < 0.1,
            "{label} {solver:?}: {h:?}"
        );
        assert!(
            h.max_residual < 1e-4 * height(skeleton),
            "{label} {solver:?}: {h:?}"
        );
    }
}

#[test]
fn orientation_targets_on_the_armadillos() {
    let Some(c) = corpus() else { return };
    let csci = open(&[c.join("2_csci520_ik_skinning/tydia/armadillo/skin.config")]);
    orientation_case("csci520 armadillo", &csci);
    let pin: Vec<PathBuf> = ["Armadillo.obj", "skeleton.out", "attachment.out"]
        .iter()
        .map(|f| {
            c.join("1_pinocchio/berkeley_cs184__icheung_Keepon/armadillo")
                .join(f)
        })
        .collect();
    orientation_case("pinocchio armadillo", &open(&pin));
}

/// A BVH walk with the right hand (two-bone) on a moving target over the walk: every
/// joint outside the arm equals the source clip; the hand meets its target.
#[test]
fn ik_on_a_base_clip_keeps_the_rest_of_the_walk() {
    let Some(c) = corpus() else { return };
    let asset = open(&[c.join("4_bvh/cmu_cgspeed__nobuyuki83_delfem2/walk.bvh")]);
    let skeleton = &asset.skeleton;
    let base = &asset.clips[0];
    let chain = arm_chain(skeleton);
    // The target: where the walk puts the hand, pushed forward and up, moving.
    let src_times: Vec<f32> = (0..=10)
        .map(|k| k as f32 * base.duration() / 10.0)
        .collect();
    let src = sample(skeleton, base, &src_times);
    let h = height(skeleton);
    let positions: Vec<Vec3> = src
        .iter()
        .enumerate()
        .map(|(k, local)| {
            let model = Pose {
                local: local.clone(),
            }
            .model_matrices(skeleton)
            .expect("fits");
            let shoulder = model[chain[0].get()].w_axis.truncate();
            let hand = model[chain[2].get()].w_axis.truncate();
            // Pull the hand a little towards the shoulder and sideways: reachable.
            hand + (shoulder - hand) * 0.2 + Vec3::Y * (0.02 * h * (k as f32 * 0.7).sin())
        })
        .collect();
    let name = skeleton.joints()[chain[2].get()].name.clone();
    let mut track = HandleTrack::keyed(chain[2], &name, src_times.clone(), positions);
    track.solver = HandleSolver::TwoBone;
    let handles = HandleSet {
        fps: None,
        base: Some(base.name.clone()),
        ..set(vec![track])
    };
    let solved = solve_clip_on(
        skeleton,
        &asset.clips,
        &handles,
        &ClipSolveOptions::default(),
        "ik",
        "walk",
    )
    .expect("solves");
    let times: Vec<f32> = (0..solved.frames)
        .map(|f| f as f32 / solved.fps)
        .map(|t| t.min(solved.clip.duration()))
        .collect();
    let before = sample(skeleton, base, &times);
    let after = sample(skeleton, &solved.clip, &times);
    let in_chain = |j: usize| j == chain[0].get() || j == chain[1].get();
    let mut worst = 0.0f32;
    for (a, b) in before.iter().zip(&after) {
        for (j, (x, y)) in a.iter().zip(b).enumerate().filter(|(j, _)| !in_chain(*j)) {
            let d = (x.translation - y.translation)
                .abs()
                .max_element()
                .max({
                    let (p, q) = (Vec4::from(x.rotation), Vec4::from(y.rotation));
                    (p - q).abs().max_element().min((p + q).abs().max_element())
                })
                .max((x.scale - y.scale).abs().max_element());
            assert!(
                d <= 1e-5 * x.translation.length().max(1.0),
                "joint {j}: {x:?} vs {y:?}"
            );
            worst = worst.max(d);
        }
    }
    let hand = &solved.handles[0];
    let reached = hand.reached.as_ref().expect("two-bone report");
    println!(
        "walk: {} frames at {} fps, outside the arm worst {worst:.2e}, hand residual {:.2e} of the height, reached {}/{}",
        solved.frames,
        solved.fps,
        hand.max_residual / h,
        reached.iter().filter(|&&r| r).count(),
        reached.len()
    );
    assert!(hand.max_residual < 1e-5 * h, "{hand:?}");
    assert!(reached.iter().all(|&r| r));
}

/// Limits from the handles (and the ASF's own dof/limits) hold on every frame, for every
/// solver.
#[test]
fn limits_hold_on_every_frame() {
    let Some(c) = corpus() else { return };
    let asset =
        open(&[c.join("3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07-walk.asf")]);
    let skeleton = &asset.skeleton;
    assert!(
        !skeleton.limits().is_empty(),
        "the ASF's limits are carried"
    );
    let chain = arm_chain(skeleton);
    let rest = skeleton.model_rest_matrices();
    let tip = rest[chain[2].get()].w_axis.truncate();
    let shoulder = rest[chain[0].get()].w_axis.truncate();
    let l = shoulder.distance(tip);
    let positions = vec![
        tip,
        shoulder + Vec3::new(0.3, 0.6, 0.5) * l,
        shoulder + Vec3::new(-0.5, -0.2, 0.6) * l,
        shoulder + Vec3::new(0.1, 0.9, -0.3) * l,
    ];
    let name = skeleton.joints()[chain[2].get()].name.clone();
    let deg = |v: f32| v.to_radians();
    let handle_limits = vec![
        RotationLimit {
            joint: chain[1],
            frame: Quat::IDENTITY,
            order: rigport_model::conventions::EulerOrder::Xyz,
            min_rad: Vec3::new(deg(-20.0), deg(-30.0), deg(-10.0)),
            max_rad: Vec3::new(deg(20.0), deg(30.0), deg(10.0)),
        },
        RotationLimit {
            joint: chain[0],
            frame: Quat::IDENTITY,
            order: rigport_model::conventions::EulerOrder::Zyx,
            min_rad: Vec3::splat(deg(-35.0)),
            max_rad: Vec3::splat(deg(35.0)),
        },
    ];
    let limited: Vec<(usize, JointLimit)> = skeleton
        .limits()
        .iter()
        .chain(&handle_limits)
        .map(|l| (l.joint.get(), JointLimit::from(l)))
        .collect();
    let rest_rot: Vec<Quat> = skeleton
        .joints()
        .iter()
        .map(|j| j.rest_local.rotation)
        .collect();
    for (solver, method) in [
        (HandleSolver::TwoBone, "dls"),
        (HandleSolver::Iterative, "dls"),
        (HandleSolver::Iterative, "ccd"),
        (HandleSolver::Iterative, "fabrik"),
        (HandleSolver::Iterative, "pinv"),
        (HandleSolver::Iterative, "transpose"),
    ] {
        let mut track =
            HandleTrack::keyed(chain[2], &name, vec![0.0, 1.0, 2.0, 3.0], positions.clone());
        track.solver = solver;
        track.root = Some(chain[0]);
        let handles = HandleSet {
            limits: handle_limits.clone(),
            ..set(vec![track])
        };
        let options = ClipSolveOptions {
            method: IkMethod::from_name(method).expect("a method"),
            ..ClipSolveOptions::default()
        };
        let solved =
            solve_clip_on(skeleton, &[], &handles, &options, "lim", "asf").expect("solves");
        let times: Vec<f32> = (0..solved.frames).map(|f| f as f32 / solved.fps).collect();
        let mut worst = 0.0f32;
        for pose in sample(skeleton, &solved.clip, &times) {
            // The last limit of a joint wins, as in the solver.
            for (j, limit) in &limited {
                if limited.iter().rev().find(|(k, _)| k == j).map(|(_, l)| l) != Some(limit) {
                    continue;
                }
                let delta = rest_rot[*j].conjugate() * pose[*j].rotation;
                worst = worst.max(limit.excess_rad(delta));
            }
        }
        println!("limits {solver:?} {method}: worst excess {worst:.2e} rad");
        assert!(worst <= 1e-4, "{solver:?} {method}: {worst}");
    }
}

/// Pins hold while another handle pulls on the same chain root: the pinned effector stays
/// at its first-frame position.
#[test]
fn pins_hold() {
    let Some(c) = corpus() else { return };
    let asset = open(&[c.join("2_csci520_ik_skinning/tydia/armadillo/skin.config")]);
    let skeleton = &asset.skeleton;
    let chain = arm_chain(skeleton);
    let name = skeleton.joints()[chain[2].get()].name.clone();
    let mid_name = skeleton.joints()[chain[1].get()].name.clone();
    let rest = skeleton.model_rest_matrices();
    let tip = rest[chain[2].get()].w_axis.truncate();
    let h = height(skeleton);
    let mut pull = HandleTrack::keyed(
        chain[2],
        &name,
        vec![0.0, 1.0],
        vec![tip, tip + Vec3::new(0.05, 0.1, 0.05) * h],
    );
    pull.root = Some(chain[0]);
    let mut pin = HandleTrack::keyed(chain[1], &mid_name, Vec::new(), Vec::new());
    pin.pin = true;
    pin.root = Some(chain[0]);
    let solved = solve_clip_on(
        skeleton,
        &[],
        &set(vec![pull, pin]),
        &ClipSolveOptions::default(),
        "pin",
        "armadillo",
    )
    .expect("solves");
    println!(
        "pin: elbow moved {:.2e} of the height, hand residual {:.2e}",
        solved.handles[1].max_residual / h,
        solved.handles[0].max_residual / h
    );
    assert!(
        solved.handles[1].max_residual < 1e-3 * h,
        "{:?}",
        solved.handles[1]
    );
}
