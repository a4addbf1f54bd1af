//! Criterion benchmarks of the conversion pipeline's stages.
//!
//! `cargo bench --bench pipeline`. The corpus rig (Model1: 13k vertices, 17 dense weight
//! columns) is read from `../shared/corpus`; its benchmarks are skipped with a message when
//! the corpus is absent. Figures go to BENCHMARKS.md with the command that made them.

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{criterion_group, criterion_main, Criterion};
use rigport_demo as demo;
use rigport_eval::{Pose, Rig, RigOutput};
use rigport_export::{to_glb, GltfOptions};
use rigport_import::pinocchio;
use rigport_model::glam::Quat;

fn model1() -> Option<[PathBuf; 3]> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(
        "../shared/corpus/1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1",
    );
    let files = ["Model1.obj", "skeleton.out", "attachment.out"].map(|f| dir.join(f));
    if files.iter().all(|f| f.exists()) {
        Some(files)
    } else {
        eprintln!("SKIPPED: corpus rig {} is absent", dir.display());
        None
    }
}

fn pipeline(c: &mut Criterion) {
    if let Some([mesh, skel, att]) = model1() {
        c.bench_function("model1/import_pinocchio", |b| {
            b.iter(|| pinocchio::import(black_box(&mesh), &skel, &att).expect("imports"))
        });
        let asset = pinocchio::import(&mesh, &skel, &att)
            .expect("imports")
            .asset;
        c.bench_function("model1/export_glb_in_memory", |b| {
            b.iter(|| to_glb(black_box(&asset), &GltfOptions::default()).expect("exports"))
        });
        let rig = Rig::new(&asset).expect("compiles");
        let mut pose = Pose::rest(&asset.skeleton);
        for (i, l) in pose.local.iter_mut().enumerate().skip(1) {
            l.rotation = Quat::from_rotation_x(0.05 * i as f32);
        }
        let mut out = RigOutput::default();
        c.bench_function("model1/evaluate_lbs_one_pose", |b| {
            b.iter(|| rig.evaluate(black_box(&pose), &mut out).expect("evaluates"))
        });
    }
    c.bench_function("demo/character_detail_1", |b| {
        b.iter(|| demo::character(black_box(1)))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = pipeline
}
criterion_main!(benches);
