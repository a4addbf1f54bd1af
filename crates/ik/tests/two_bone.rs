//! Analytic two-bone IK (`rigport_ik::two_bone`) against a test-only reference, on
//! synthetic limbs and on an arm chain of each corpus family (Pinocchio, CSCI 520, ASF,
//! BVH, glTF).
//!
//! The reference is an independent construction: it places the elbow in the pole
//! half-plane by bisection on the shoulder angle (no law of cosines, no quaternions), and
//! the check applies the job's `f32` corrections through `f64` forward kinematics.
//!
//! Corpus rigs skip with a message when `../shared/corpus` is absent (fail when `CI` is set).
//! `cargo test -p rigport-eval --test two_bone -- --nocapture` prints the figures.

use std::path::PathBuf;

mod common;
use common::{arm_chain, corpus, open};

use rigport_eval::Pose;
use rigport_ik::two_bone::{TwoBoneIkJob, TwoBoneIkOutput};
use rigport_model::glam::{DMat4, DQuat, DVec3, Mat4, Quat, Vec3};
use rigport_model::JointIndex;

/// xorshift64*: deterministic, no dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
    fn unit(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let l = v.length();
            if l > 0.1 && l <= 1.0 {
                return v / l;
            }
        }
    }
    fn rotation(&mut self, max_angle: f64) -> Quat {
        DQuat::from_axis_angle(self.unit(), self.range(-max_angle, max_angle)).as_quat()
    }
}

fn pos(m: &DMat4) -> DVec3 {
    m.w_axis.truncate()
}

/// The reference elbow and tip for a reachable target: the elbow on the sphere of radius
/// `l1` about the root, in the half-plane of the root-to-target line `u` and the pole,
/// found by bisection on its angle from `u` (the elbow-to-target distance grows with it).
fn reference(r: DVec3, l1: f64, l2: f64, target: DVec3, pole: DVec3) -> (DVec3, DVec3) {
    let u = (target - r).normalize();
    let w = (pole - pole.dot(u) * u).normalize();
    let elbow = |a: f64| r + l1 * (a.cos() * u + a.sin() * w);
    let (mut lo, mut hi) = (0.0f64, std::f64::consts::PI);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if elbow(mid).distance(target) < l2 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (elbow(0.5 * (lo + hi)), target)
}

/// The chain's model matrices after the corrections, in `f64`.
fn corrected(job: &TwoBoneIkJob, out: &TwoBoneIkOutput) -> (DMat4, DMat4, DMat4) {
    let d = |m: Mat4| m.as_dmat4();
    let q = |q: Quat| DMat4::from_quat(q.as_dquat());
    let (root, mid, tip) = (d(job.root_model), d(job.mid_model), d(job.tip_model));
    let root2 = root * q(out.root_correction);
    let mid2 = root2 * (root.inverse() * mid) * q(out.mid_correction);
    let tip2 = mid2 * (mid.inverse() * tip);
    (root2, mid2, tip2)
}

#[derive(Default, Debug)]
struct Worst {
    tip: f64,
    elbow_ref: f64,
    plane: f64,
    solves: usize,
}

/// Solves one random reachable target and returns the errors relative to the chain length.
fn check_reachable(rng: &mut Rng, root: Mat4, mid: Mat4, tip: Mat4, worst: &mut Worst) {
    let d = |m: &Mat4| m.w_axis.truncate().as_dvec3();
    let (r, m, t) = (d(&root), d(&mid), d(&tip));
    let (l1, l2) = (r.distance(m), m.distance(t));
    let full = l1 + l2;
    let near = (l1 - l2).abs();
    let dist = rng.range(near + 0.02 * full, 0.98 * full);
    let target = (r + rng.unit() * dist).as_vec3();
    let pole = rng.unit().as_vec3();
    let mut job = TwoBoneIkJob::new(root, mid, tip, target);
    job.pole = pole;
    job.mid_axis = TwoBoneIkJob::bend_axis(root, mid, tip, pole);
    let out = job.run().expect("valid job");
    assert!(out.reached, "{dist} within [{near}, {full}]");
    let (_, mid2, tip2) = corrected(&job, &out);
    let target = target.as_dvec3();
    let (ref_elbow, ref_tip) = reference(r, l1, l2, target, pole.as_dvec3());
    let tip_err = pos(&tip2).distance(ref_tip) / full;
    let elbow_err = pos(&mid2).distance(ref_elbow) / full;
    let u = (target - r).normalize();
    let normal = u.cross(pole.as_dvec3()).normalize();
    let plane_err = (pos(&mid2) - r).dot(normal).abs() / full;
    let side = (pos(&mid2) - r).dot(pole.as_dvec3() - pole.as_dvec3().dot(u) * u);
    assert!(
        side >= -1e-6 * full * full,
        "elbow on the far side of the pole"
    );
    // The mid correction turns about the hinge only.
    let (axis, angle) = out.mid_correction.to_axis_angle();
    if angle.abs() > 1e-4 {
        assert!(
            axis.cross(job.mid_axis).length() < 1e-3,
            "{axis} vs {}",
            job.mid_axis
        );
    }
    worst.tip = worst.tip.max(tip_err);
    worst.elbow_ref = worst.elbow_ref.max(elbow_err);
    worst.plane = worst.plane.max(plane_err);
    worst.solves += 1;
}

/// Out-of-reach targets: without softening a straight limb pointing at the target, with
/// softening a limb that approaches full extension smoothly; `reached == false` both ways.
fn check_unreachable(rng: &mut Rng, root: Mat4, mid: Mat4, tip: Mat4) {
    let d = |m: &Mat4| m.w_axis.truncate().as_dvec3();
    let (r, m, t) = (d(&root), d(&mid), d(&tip));
    let (l1, l2) = (r.distance(m), m.distance(t));
    let full = l1 + l2;
    let u = rng.unit();
    let pole = rng.unit().as_vec3();
    let solve = |dist: f64, soften: f32| {
        let target = (r + u * dist).as_vec3();
        let mut job = TwoBoneIkJob::new(root, mid, tip, target);
        job.pole = pole;
        job.mid_axis = TwoBoneIkJob::bend_axis(root, mid, tip, pole);
        job.soften = soften;
        let out = job.run().expect("valid job");
        let (_, mid2, tip2) = corrected(&job, &out);
        (out.reached, pos(&mid2), pos(&tip2))
    };
    // Hard: straight at full reach, along the line.
    let (reached, elbow, tip2) = solve(1.5 * full, 0.0);
    assert!(!reached);
    assert!(tip2.distance(r + u * full) < 1e-5 * full, "straight tip");
    assert!(elbow.distance(r + u * l1) < 1e-3 * full, "straight elbow");
    // Soft: the tip stays on the line, short of full reach, its distance increasing with
    // the target's and continuous at the start of softening.
    let soften = 0.1;
    let start = (1.0 - f64::from(soften)) * full;
    let mut last = 0.0;
    for k in 0..=40 {
        let dist = start + f64::from(k) * 0.05 * full;
        let (reached, _, tip2) = solve(dist, soften);
        let got = tip2.distance(r);
        assert!(got < full * (1.0 + 1e-6), "soft tip {got} beyond {full}");
        assert!(
            (tip2 - r).normalize().dot(u) > 1.0 - 1e-9,
            "soft tip on the line"
        );
        assert!(
            got + 1e-6 * full >= last,
            "soft distance decreases: {got} < {last}"
        );
        if k == 0 {
            assert!((got - dist).abs() < 1e-5 * full, "continuous at the start");
        } else {
            assert!(!reached);
            assert!(got < dist);
        }
        last = got;
    }
}

#[test]
fn synthetic_limbs_match_the_reference() {
    let mut rng = Rng(0x1234_5678_9abc_def1);
    let mut worst = Worst::default();
    for _ in 0..2000 {
        let root = Mat4::from_rotation_translation(
            rng.rotation(3.0),
            (rng.unit() * rng.range(0.0, 3.0)).as_vec3(),
        ) * Mat4::from_scale(Vec3::splat(rng.range(0.5, 2.0) as f32));
        let mid = root
            * Mat4::from_rotation_translation(
                rng.rotation(3.0),
                (rng.unit() * rng.range(0.2, 1.5)).as_vec3(),
            );
        let tip = mid * Mat4::from_translation((rng.unit() * rng.range(0.2, 1.5)).as_vec3());
        check_reachable(&mut rng, root, mid, tip, &mut worst);
    }
    for _ in 0..50 {
        let root = Mat4::from_quat(rng.rotation(3.0));
        let mid = root * Mat4::from_translation(Vec3::X);
        let tip = mid * Mat4::from_rotation_translation(rng.rotation(1.0), 0.7 * Vec3::X);
        check_unreachable(&mut rng, root, mid, tip);
    }
    println!("synthetic: {worst:?}");
    assert!(worst.tip < 1e-6 && worst.elbow_ref < 1e-6 && worst.plane < 1e-6);
}

#[test]
fn weight_and_validation() {
    let root = Mat4::IDENTITY;
    let mid = Mat4::from_translation(Vec3::X);
    let tip = Mat4::from_translation(2.0 * Vec3::X);
    let mut job = TwoBoneIkJob::new(root, mid, tip, Vec3::new(0.5, 1.0, 0.0));
    job.pole = Vec3::Y;
    job.mid_axis = TwoBoneIkJob::bend_axis(root, mid, tip, job.pole);
    let full = job.run().expect("valid");
    job.weight = 0.0;
    let none = job.run().expect("valid");
    assert_eq!(none.root_correction, Quat::IDENTITY);
    assert!(!none.reached);
    job.weight = 0.5;
    let half = job.run().expect("valid");
    assert!(!half.reached);
    let angle = |q: Quat| q.to_axis_angle().1;
    assert!((angle(half.root_correction) - 0.5 * angle(full.root_correction)).abs() < 1e-5);
    job.weight = 1.5;
    assert!(job.run().is_err());
    job.weight = 1.0;
    job.mid_axis = Vec3::new(0.0, 0.0, 2.0);
    assert!(job.run().is_err());
    job.mid_axis = Vec3::Z;
    job.target = Vec3::NAN;
    assert!(job.run().is_err());
    // A target at the root: the equal bones fold onto it; finite corrections.
    job.target = Vec3::ZERO;
    let out = job.run().expect("valid");
    assert!(out.root_correction.is_finite() && out.mid_correction.is_finite() && out.reached);
    // Closer than the bones' difference: not reached, finite.
    let short = Mat4::from_translation(1.5 * Vec3::X);
    let mut job = TwoBoneIkJob::new(root, mid, short, Vec3::new(0.1, 0.0, 0.0));
    job.mid_axis = TwoBoneIkJob::bend_axis(root, mid, short, Vec3::Y);
    let out = job.run().expect("valid");
    assert!(out.root_correction.is_finite() && out.mid_correction.is_finite() && !out.reached);
}

#[test]
fn corpus_arm_chains_match_the_reference() {
    let Some(c) = corpus() else { return };
    let rigs: [(&str, Vec<PathBuf>); 5] = [
        (
            "pinocchio",
            ["Armadillo.obj", "skeleton.out", "attachment.out"]
                .iter()
                .map(|f| {
                    c.join("1_pinocchio/berkeley_cs184__icheung_Keepon/armadillo")
                        .join(f)
                })
                .collect(),
        ),
        (
            "csci520",
            vec![c.join("2_csci520_ik_skinning/tydia/armadillo/skin.config")],
        ),
        (
            "asf",
            vec![c.join("3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik/07-walk.asf")],
        ),
        (
            "bvh",
            vec![c.join("4_bvh/cmu_cgspeed__nobuyuki83_delfem2/walk.bvh")],
        ),
        (
            "gltf",
            vec![c.join("5_gltf/khronos_samples__nobuyuki83_delfem2/CesiumMan.glb")],
        ),
    ];
    let mut rng = Rng(0xfeed_beef_cafe_f00d);
    for (label, paths) in rigs {
        let asset = open(&paths);
        let skeleton = &asset.skeleton;
        let [root, mid, tip] = arm_chain(skeleton);
        let mut worst = Worst::default();
        for k in 0..300 {
            // Random bends of the chain's own joints over the rest pose.
            let mut pose = Pose::rest(skeleton);
            if k > 0 {
                for j in [root, mid] {
                    let l = &mut pose.local[j.get()];
                    l.rotation = (l.rotation * rng.rotation(1.2)).normalize();
                }
            }
            let model = pose.model_matrices(skeleton).expect("pose fits");
            let (r, m, t) = (model[root.get()], model[mid.get()], model[tip.get()]);
            check_reachable(&mut rng, r, m, t, &mut worst);
            if k % 10 == 0 {
                check_unreachable(&mut rng, r, m, t);
            }
        }
        let name = |j: JointIndex| &skeleton.joints()[j.get()].name;
        println!(
            "{label}: chain {} -> {} -> {}: {worst:?}",
            name(root),
            name(mid),
            name(tip)
        );
        assert!(
            worst.tip < 1e-6 && worst.elbow_ref < 1e-6 && worst.plane < 1e-6,
            "{label}: {worst:?}"
        );
    }
}
