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
use rigport_eval::ik::{IkMethod, IkProblem, IkReport, IkScratch, IkSolveJob};

#[allow(dead_code)]
#[path = "../examples/ik_bench.rs"]
mod ik_bench;

use ik_bench::{chain_joints, k_chain, load_rigs, rest, solvers, target_sets};

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

criterion_group! {
    name = ik;
    config = Criterion::default()
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    targets = solvers_on_rigs, rigport_vs_k_on_chains
}
criterion_main!(ik);
