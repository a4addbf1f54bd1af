//! Criterion benchmarks of the IK solvers (issue 4, acceptance 1 and 2).
//!
//! `cargo bench --bench ik`. The rigs, target sets, settings and the `k` chains are those
//! of `examples/ik_bench.rs` (included below, so both measure the same thing); rigs whose
//! corpus files are absent are skipped with a message. One iteration is one solve from the
//! rest pose, cycling through 100 target sets; the example prints the success rates and
//! medians for BENCHMARKS.md.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use rigport_ik::{IkMethod, IkProblem, IkReport, IkScratch, IkSolveJob};

#[allow(dead_code)]
#[path = "../examples/ik_bench.rs"]
mod ik_bench;

use ik_bench::{chain_joints, k_chain, load_rigs, rest, solvers, target_sets, Rng};
use rigport_ik::chains::ChainSolver;
use rigport_ik::two_bone::TwoBoneIkJob;
use rigport_ik::IkSettings;
use rigport_model::glam::{Mat4, Quat, Vec3};
use rigport_model::{HandleSet, HandleSolver, HandleTrack, RootMotion};

/// Target sets per rig; each benchmark iteration solves the next one.
const SETS: usize = 100;

fn solvers_on_rigs(c: &mut Criterion) {
    for rig in load_rigs() {
        let Ok(problem) = IkProblem::new(&rig.skeleton, &rig.handles, None, &[]) else {
            eprintln!("SKIPPED {}: not a valid IK problem", rig.name);
            continue;
        };
        let sets = target_sets(&rig, &problem, SETS);
        let start = rest(&rig.skeleton);
        let mut group = c.benchmark_group(format!("ik/{}", rig.name));
        for settings in solvers(rig.height) {
            // The Jacobian transpose needs hundreds of iterations: too slow to sample here
            // (the example reports it).
            if settings.method == IkMethod::Transpose {
                continue;
            }
            let mut scratch = IkScratch::new(&problem);
            let mut report = IkReport::new(&problem);
            let mut pose = start.clone();
            let mut next = 0;
            group.bench_function(BenchmarkId::from_parameter(settings.method.name()), |b| {
                b.iter(|| {
                    pose.copy_from_slice(&start);
                    let targets = &sets[next % sets.len()];
                    next += 1;
                    let result = IkSolveJob {
                        problem: &problem,
                        targets: black_box(targets),
                        settings: &settings,
                        pose: &mut pose,
                        scratch: &mut scratch,
                        report: &mut report,
                    }
                    .run();
                    black_box((result, report.iterations))
                })
            });
        }
        group.finish();
    }
}

fn rigport_vs_k_on_chains(c: &mut Criterion) {
    let constraints = k::Constraints {
        rotation_x: false,
        rotation_y: false,
        rotation_z: false,
        ..Default::default()
    };
    for rig in load_rigs() {
        let (joints, end) = chain_joints(&rig.skeleton, rig.chain_handle);
        let Ok(problem) = IkProblem::new(&rig.skeleton, &[rig.chain_handle], Some(&joints), &[])
        else {
            continue;
        };
        let sets = target_sets(&rig, &problem, SETS);
        let start = rest(&rig.skeleton);
        let settings = solvers(rig.height)[0];
        let mut group = c.benchmark_group(format!("ik_chain/{}", rig.name));
        let mut scratch = IkScratch::new(&problem);
        let mut report = IkReport::new(&problem);
        let mut pose = start.clone();
        let mut next = 0;
        group.bench_function("rigport dls", |b| {
            b.iter(|| {
                pose.copy_from_slice(&start);
                let targets = &sets[next % sets.len()];
                next += 1;
                let result = IkSolveJob {
                    problem: &problem,
                    targets: black_box(targets),
                    settings: &settings,
                    pose: &mut pose,
                    scratch: &mut scratch,
                    report: &mut report,
                }
                .run();
                black_box(result)
            })
        });
        let chain = k_chain(&rig.skeleton, &joints, end);
        let limit = f64::from(ik_bench::SUCCESS_FRACTION * rig.height);
        let solver = k::JacobianIkSolver::new(limit, std::f64::consts::PI, 1.0, 100);
        let zero = vec![0.0; chain.dof()];
        let goals: Vec<_> = sets
            .iter()
            .map(|t| {
                let p = t[0].target.as_dvec3();
                k::Isometry3::from_parts(
                    k::Translation3::new(p.x, p.y, p.z),
                    k::UnitQuaternion::identity(),
                )
            })
            .collect();
        let mut next = 0;
        group.bench_function("k JacobianIkSolver", |b| {
            b.iter(|| {
                chain.set_joint_positions_unchecked(&zero);
                let goal = &goals[next % goals.len()];
                next += 1;
                black_box(k::InverseKinematicsSolver::solve_with_constraints(
                    &solver,
                    &chain,
                    black_box(goal),
                    &constraints,
                ))
            })
        });
        group.finish();
    }
}

/// One analytic two-bone solve (issue 16: target < 0.5 µs): an arm with bent, rotated
/// joints, cycling through 100 reachable targets and poles.
fn two_bone_job(c: &mut Criterion) {
    let mut rng = Rng(16);
    let unit = |rng: &mut Rng| {
        Vec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        )
        .normalize_or(Vec3::X)
    };
    let root =
        Mat4::from_rotation_translation(Quat::from_rotation_y(0.3), Vec3::new(0.2, 1.4, 0.0));
    let mid = root * Mat4::from_rotation_translation(Quat::from_rotation_z(0.4), Vec3::X * 0.3);
    let tip = mid * Mat4::from_translation(Vec3::X * 0.28);
    let jobs: Vec<TwoBoneIkJob> = (0..SETS)
        .map(|_| {
            let target = root.w_axis.truncate() + unit(&mut rng) * rng.range(0.1, 0.55);
            let mut job = TwoBoneIkJob::new(root, mid, tip, target);
            job.pole = unit(&mut rng);
            job.mid_axis = TwoBoneIkJob::bend_axis(root, mid, tip, job.pole);
            job.soften = 0.05;
            job
        })
        .collect();
    let mut next = 0;
    c.bench_function("two_bone/solve", |b| {
        b.iter(|| {
            let job = &jobs[next % jobs.len()];
            next += 1;
            black_box(black_box(job).run())
        })
    });
}

/// One frame of a full-body solve on the CSCI 520 armadillo (issue 16: target < 50 µs
/// median): 4 keyed effectors (hands 15 and 19, head 21, elbow 13; DLS) and 2 pinned feet
/// (4 and 8), free root, from the rest pose; targets cycle through 100 random poses.
fn pinned_full_body_frame(c: &mut Criterion) {
    let Some(rig) = load_rigs()
        .into_iter()
        .find(|r| r.name.contains("armadillo"))
    else {
        eprintln!("SKIPPED ik_chains: no armadillo");
        return;
    };
    let skeleton = &rig.skeleton;
    let joint = |i: u32| skeleton.find(&format!("joint_{i}"));
    let (Some(h15), Some(h19), Some(h21), Some(h13), Some(f4), Some(f8)) = (
        joint(15),
        joint(19),
        joint(21),
        joint(13),
        joint(4),
        joint(8),
    ) else {
        eprintln!("SKIPPED ik_chains: armadillo joints missing");
        return;
    };
    let start = rest(skeleton);
    let mut rng = Rng(160);
    let effectors = [h15, h19, h21, h13];
    let mut positions = vec![Vec::new(); effectors.len()];
    for _ in 0..SETS {
        let mut pose = rigport_eval::Pose::rest(skeleton);
        for l in pose.local.iter_mut().skip(1) {
            let a = |rng: &mut Rng| rng.range(-0.4, 0.4);
            let q = Quat::from_euler(
                rigport_model::glam::EulerRot::XYZ,
                a(&mut rng),
                a(&mut rng),
                a(&mut rng),
            );
            l.rotation = (l.rotation * q).normalize();
        }
        let Ok(model) = pose.model_matrices(skeleton) else {
            return;
        };
        for (list, e) in positions.iter_mut().zip(effectors) {
            list.push(model[e.get()].w_axis.truncate());
        }
    }
    let times: Vec<f32> = (0..SETS).map(|k| k as f32).collect();
    let mut tracks: Vec<HandleTrack> = effectors
        .iter()
        .zip(positions)
        .map(|(&j, p)| HandleTrack::keyed(j, "e", times.clone(), p))
        .collect();
    for foot in [f4, f8] {
        let mut pin = HandleTrack::keyed(foot, "pin", Vec::new(), Vec::new());
        pin.pin = true;
        pin.solver = HandleSolver::Iterative;
        tracks.push(pin);
    }
    let handles = HandleSet {
        fps: None,
        tracks,
        base: None,
        root_motion: Some(RootMotion::Free),
        limits: Vec::new(),
    };
    let settings = IkSettings {
        tolerance: 1e-4 * rig.height,
        free_root_translation: true,
        ..IkSettings::default()
    };
    let Ok(mut solver) = ChainSolver::new(skeleton, &handles, &settings, &start) else {
        eprintln!("SKIPPED ik_chains: setup failed");
        return;
    };
    let mut report = solver.report();
    let mut pose = start.clone();
    let mut next = 0usize;
    c.bench_function("ik_chains/armadillo_4_effectors_2_pins", |b| {
        b.iter(|| {
            pose.copy_from_slice(&start);
            let t = (next % SETS) as f32;
            next += 1;
            black_box(solver.solve_frame(t, &mut pose, &mut report))
        })
    });
}

criterion_group! {
    name = ik;
    config = Criterion::default()
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    targets = solvers_on_rigs, rigport_vs_k_on_chains, two_bone_job, pinned_full_body_frame
}
criterion_main!(ik);
