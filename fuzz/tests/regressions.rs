//! Replays every input kept in the repo through its fuzz target on the stable toolchain:
//! the fuzzing corpus (`fuzz/corpus/<target>/`, minimized, seeded from `fixtures/`) and
//! the inputs that once crashed or hung a target (`fuzz/regressions/<target>/`).
//! A panic here is a regression.

use std::path::Path;

#[test]
fn every_kept_input_runs_through_its_target() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut total = 0;
    for (name, target) in rigport_fuzz::TARGETS {
        let mut count = 0;
        for folder in ["corpus", "regressions"] {
            let dir = root.join(folder).join(name);
            let Ok(entries) = std::fs::read_dir(&dir) else {
                continue;
            };
            let mut files: Vec<_> = entries.map(|e| e.expect("dir entry").path()).collect();
            files.sort();
            for file in files {
                let data = std::fs::read(&file).expect("read kept input");
                let outcome = std::panic::catch_unwind(|| target(&data));
                assert!(outcome.is_ok(), "{name}: {} panics", file.display());
                count += 1;
            }
        }
        assert!(
            count > 0,
            "{name}: no corpus in fuzz/corpus/{name} (run fuzz/seed.sh)"
        );
        total += count;
    }
    eprintln!("replayed {total} kept inputs");
}
