//! Shared helpers for the end-to-end tests: running the CLI, finding the corpus, running
//! Khronos glTF-Validator, reading glTF back with the independent `gltf` crate.

use std::path::PathBuf;
use std::process::{Command, Output};

/// The repository root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs `rigport` with `args`.
pub fn rigport(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rigport"))
        .args(args)
        .output()
        .expect("rigport runs")
}

/// Runs `rigport` and asserts success, returning stderr.
pub fn rigport_ok(args: &[&str]) -> String {
    let out = rigport(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(
        out.status.success(),
        "rigport {args:?} failed ({:?}):\n{stderr}",
        out.status.code()
    );
    stderr
}

// The corpus with its CI rule, the validator runner and `.npy` reading live in
// rigport-testkit, shared with the crates' tests.
pub use rigport_testkit::gltf_validator::{assert_valid, validate};
pub use rigport_testkit::npy::{read_npy, read_npz, NpyArray};
pub use rigport_testkit::{corpus, corpus_dir, require, PINOCCHIO_RIGS};

/// The glTF samples of the corpus.
pub const GLTF_SAMPLES: [&str; 5] = [
    "5_gltf/khronos_samples__nobuyuki83_delfem2/RiggedSimple.glb",
    "5_gltf/khronos_samples__nobuyuki83_delfem2/RiggedFigure.glb",
    "5_gltf/khronos_samples__nobuyuki83_delfem2/CesiumMan.glb",
    "5_gltf/bevy_assets__bevyengine_bevy/SimpleSkin.gltf",
    "5_gltf/blender_io_roundtrip__KhronosGroup/03_skinned_cylinder.gltf",
];

/// The corpus files of one `MANIFEST.tsv` section (its first column, e.g. `7_fbx`), in
/// manifest order; `None` when the corpus is absent (see [`corpus`]). A section without
/// rows is a failure: the manifest changed under the test.
pub fn corpus_section(section: &str) -> Option<Vec<PathBuf>> {
    let manifest = corpus("MANIFEST.tsv")?;
    let root = manifest.parent().expect("the corpus folder").to_path_buf();
    let text = std::fs::read_to_string(&manifest).expect("MANIFEST.tsv reads");
    let files: Vec<PathBuf> = text
        .lines()
        .filter_map(|l| {
            let mut fields = l.split('\t');
            (fields.next() == Some(section)).then(|| root.join(fields.next().unwrap_or("")))
        })
        .collect();
    assert!(
        !files.is_empty(),
        "no {section} rows in {}",
        manifest.display()
    );
    Some(files)
}

/// A scratch folder, removed at drop.
pub fn scratch() -> tempfile::TempDir {
    tempfile::tempdir().expect("temp dir")
}
