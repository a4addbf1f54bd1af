//! Criterion benchmark of `rigport verify` (issue 31's speed goal: human_model1's glb
//! against its usdz over a 100-frame clip in under 2 s on 2 cores).
//!
//! `cargo bench --bench verify`. The rig and the walk come from `../shared/corpus`
//! (skipped with a message when absent): the CMU walk retargeted onto Model1 (13,336
//! vertices, 18 joints), re-timed to 100 frames, written as `.glb` and as `.usdz` by the
//! `rigport` binary; the benchmark is the whole `rigport_pipeline::verify` of one against
//! the other (both files read, rest fit, vertex maps, 100 frames of both skinned and
//! compared). Figures go to BENCHMARKS.md with the command that made them.

use std::path::{Path, PathBuf};
use std::process::Command;

use criterion::{criterion_group, criterion_main, Criterion};
use rigport_pipeline::load::Input;
use rigport_pipeline::progress::Silent;
use rigport_pipeline::verify::VerifyOptions;

/// Runs the `rigport` binary, which must succeed.
fn rigport(args: &[&str]) {
    let status = Command::new(env!("CARGO_BIN_EXE_rigport"))
        .args(args)
        .arg("-q")
        .status()
        .expect("rigport runs");
    assert!(status.success(), "rigport {args:?}");
}

/// The 100-frame Model1 walk as `.glb` and `.usdz` in `dir`, or `None` without the corpus.
fn model1_walk(dir: &Path) -> Option<(PathBuf, PathBuf)> {
    let corpus = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/corpus");
    let rig = corpus.join("1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1");
    let walk = corpus.join("4_bvh/cmu_cgspeed__nobuyuki83_delfem2/walk.bvh");
    if !rig.exists() || !walk.exists() {
        eprintln!("SKIPPED: the corpus ({}) is absent", corpus.display());
        return None;
    }
    let s = |p: &Path| p.to_str().expect("UTF-8 path").to_string();
    let (moved, glb, usdz) = (
        dir.join("walk.glb"),
        dir.join("walk100.glb"),
        dir.join("walk100.usdz"),
    );
    rigport(&["retarget", &s(&walk), "--onto", &s(&rig), "-o", &s(&moved)]);
    rigport(&["retime", &s(&moved), "--frames", "100", "-o", &s(&glb)]);
    rigport(&["convert", &s(&glb), "-o", &s(&usdz)]);
    Some((glb, usdz))
}

fn verify(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("a scratch folder");
    let Some((glb, usdz)) = model1_walk(dir.path()) else {
        return;
    };
    let reference = Input::new(vec![glb]);
    let options = VerifyOptions::new(Input::new(vec![usdz]));
    c.bench_function("model1_walk100/verify_glb_against_usdz", |b| {
        b.iter(|| {
            let verdict =
                rigport_pipeline::verify(&reference, &options, &Silent).expect("verifies");
            assert!(verdict.passed);
        })
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = verify
}
criterion_main!(benches);
