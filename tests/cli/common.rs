//! Shared helpers for the end-to-end tests: running the CLI, finding the corpus, running
//! Khronos glTF-Validator, reading glTF back with the independent `gltf` crate.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::UNIX_EPOCH;

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

/// The folder of `rigport demo --no-corpus`'s outputs, written once per build of the CLI and
/// shared by the tests that only read them: nextest runs every test in a process of its
/// own, so the outputs are shared on disk (under cargo's `CARGO_TARGET_TMPDIR`, named by
/// the binary's modification time and size). The first callers each write the demo into a
/// folder of their own and rename it into place; a rename onto a folder that another
/// caller placed first fails, and that caller's folder is used. Read it, never write into
/// it: a test's own files go to its [`scratch`] folder. The demo's own tests (`demo.rs`)
/// run the demo themselves.
pub fn demo_outputs() -> PathBuf {
    let exe = Path::new(env!("CARGO_BIN_EXE_rigport"));
    let meta = std::fs::metadata(exe).expect("the rigport binary exists");
    let stamp = meta
        .modified()
        .ok()
        .and_then(|t| t.duration_since(UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos());
    let root = PathBuf::from(env!("CARGO_TARGET_TMPDIR"));
    let name = format!("demo-{stamp:x}-{:x}", meta.len());
    let dir = root.join(&name);
    if dir.exists() {
        return dir;
    }
    std::fs::create_dir_all(&root).expect("CARGO_TARGET_TMPDIR");
    // Outputs of earlier builds go.
    for old in std::fs::read_dir(&root)
        .expect("CARGO_TARGET_TMPDIR lists")
        .flatten()
    {
        let old_name = old.file_name().to_string_lossy().into_owned();
        if old_name.starts_with("demo-") && !old_name.starts_with(&name) {
            let _ = std::fs::remove_dir_all(old.path());
        }
    }
    let part = root.join(format!("{name}.{}", std::process::id()));
    rigport_ok(&[
        "demo",
        "--no-corpus",
        "--quiet",
        "-o",
        part.to_str().unwrap(),
    ]);
    if std::fs::rename(&part, &dir).is_err() {
        assert!(dir.exists(), "{} cannot be renamed", part.display());
        let _ = std::fs::remove_dir_all(&part);
    }
    dir
}
