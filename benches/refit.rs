//! Criterion benchmark of the influence refit (issue 17): 4 influences per vertex fitted
//! over the range-of-motion pose set `rigport convert --influences-fit refit` uses for a
//! rig without clips, on a rayon pool of 2 threads.
//!
//! `cargo bench --bench refit`. Two inputs, skipped with a message when the corpus is absent:
//! - `model1`: the largest skinned rig of the shared corpus, the Pinocchio rig
//!   `human_model1` (13,336 vertices, 18 joints, up to 13 weights per vertex);
//! - `model1_40k`: the same rig with edge midpoints added (weights: the mean of the two
//!   ends' rows) until it has 40,000 vertices.

use std::collections::BTreeMap;
use std::num::NonZeroUsize;

use criterion::{criterion_group, criterion_main, Criterion};
use rigport_deform::refit::asset::{ROM_BENT_JOINTS, ROM_RANDOM_POSES, ROM_SEED};
use rigport_deform::refit::{range_of_motion, RefitJob};
use rigport_eval::skinning::rayon;
use rigport_eval::skinning_matrices;
use rigport_model::glam::{Mat4, Vec3};
use rigport_model::{Asset, Influence, Influences};

/// One input: bind positions, influences, and the fit set's skinning matrices.
struct Input {
    name: &'static str,
    positions: Vec<Vec3>,
    influences: Influences,
    matrices: Vec<Mat4>,
    palette_len: usize,
}

fn model1() -> Option<Asset> {
    let dir = rigport_testkit::corpus(
        "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1",
    )?;
    let imported = rigport_import::pinocchio::import(
        &dir.join("Model1.obj"),
        &dir.join("skeleton.out"),
        &dir.join("attachment.out"),
    )
    .expect("corpus rig imports");
    Some(imported.asset)
}

fn input(name: &'static str, asset: &Asset, positions: Vec<Vec3>, influences: Influences) -> Input {
    let skin = &asset.skins[0];
    let poses = range_of_motion(&asset.skeleton, ROM_RANDOM_POSES, ROM_BENT_JOINTS, ROM_SEED);
    let n = skin.joints.len();
    let mut matrices = Vec::with_capacity(poses.len() * n);
    let mut palette = vec![Mat4::IDENTITY; n];
    for pose in &poses {
        let model = pose.model_matrices(&asset.skeleton).expect("pose fits");
        skinning_matrices(&model, &skin.joints, &skin.inv_bind, &mut palette).expect("fits");
        matrices.extend_from_slice(&palette);
    }
    Input {
        name,
        positions,
        influences,
        matrices,
        palette_len: n,
    }
}

/// Adds edge midpoints (in triangle order) until there are `target` vertices.
fn subdivided(asset: &Asset, target: usize) -> (Vec<Vec3>, Influences) {
    let skin = &asset.skins[0];
    let mesh = &asset.meshes[skin.mesh.get()];
    let mut positions = mesh.positions.clone();
    let mut rows: Vec<Vec<Influence>> = skin.influences.rows().map(<[_]>::to_vec).collect();
    let mut seen = std::collections::BTreeSet::new();
    'edges: for tri in &mesh.triangles {
        for (a, b) in [(tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])] {
            if positions.len() >= target {
                break 'edges;
            }
            if !seen.insert((a.min(b), a.max(b))) {
                continue;
            }
            let (a, b) = (a as usize, b as usize);
            positions.push((positions[a] + positions[b]) * 0.5);
            let mut mean: BTreeMap<u32, f32> = BTreeMap::new();
            for i in rows[a].iter().chain(&rows[b]) {
                *mean.entry(i.joint).or_default() += 0.5 * i.weight;
            }
            rows.push(
                mean.into_iter()
                    .map(|(joint, weight)| Influence { joint, weight })
                    .collect(),
            );
        }
    }
    (positions, Influences::from_rows(rows))
}

fn bench(c: &mut Criterion) {
    let Some(asset) = model1() else {
        return;
    };
    let skin = &asset.skins[0];
    let positions = asset.meshes[skin.mesh.get()].positions.clone();
    let (p40, i40) = subdivided(&asset, 40_000);
    let inputs = [
        input("model1", &asset, positions, skin.influences.clone()),
        input("model1_40k", &asset, p40, i40),
    ];
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("a pool of 2 threads");
    let mut group = c.benchmark_group("refit_k4_2threads");
    group.sample_size(10);
    for input in &inputs {
        let job = RefitJob {
            positions: &input.positions,
            influences: &input.influences,
            pose_matrices: &input.matrices,
            palette_len: input.palette_len,
            max_influences: NonZeroUsize::new(4).expect("4 > 0"),
        };
        group.bench_function(input.name, |b| {
            b.iter(|| pool.install(|| job.run().expect("valid")));
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
