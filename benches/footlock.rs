//! Criterion benchmark of foot locking (issue 16): one corpus clip, whole pipeline step
//! (sampling, detection, pins, per-frame two-bone solves, bake, report).
//!
//! `cargo bench --bench footlock`; skipped with a message when the corpus is absent.

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{criterion_group, criterion_main, Criterion};
use rigport_ik::footlock::{find_feet, footlock, up_in_model, FootlockOptions};

fn bench(c: &mut Criterion) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/corpus/3_acclaim_asf_amc/usc_csci520_mocapPlayer__shreyabhaumik");
    let (asf, amc) = (dir.join("07-walk.asf"), dir.join("07_05-walk.amc"));
    if !(asf.exists() && amc.exists()) {
        eprintln!("SKIPPED: corpus clip {} is absent", amc.display());
        return;
    }
    let asset = rigport_import::asf_amc::import(&asf, &[amc], 120.0)
        .expect("imports")
        .asset;
    let (legs, _) = find_feet(&asset.skeleton).expect("CMU feet");
    let up = up_in_model(&asset.frame);
    let options = FootlockOptions::default();
    c.bench_function("footlock/07_05-walk_517_frames", |b| {
        b.iter(|| {
            footlock(
                &asset.skeleton,
                black_box(&asset.clips[0]),
                &legs,
                up,
                &options,
            )
            .expect("locks")
        })
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(20);
    targets = bench
}
criterion_main!(benches);
