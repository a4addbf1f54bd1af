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
pub use rigport_testkit::{corpus, corpus_dir, require};

/// The Pinocchio rigs of the corpus: (label, mesh, skeleton, attachment).
pub const PINOCCHIO_RIGS: [(&str, &str, &str, &str); 4] = [
    (
        "arma2",
        "1_pinocchio/edinburgh_cav_arma2__gpfvic_CAV1/arma2.obj",
        "1_pinocchio/edinburgh_cav_arma2__gpfvic_CAV1/skeleton2.out",
        "1_pinocchio/edinburgh_cav_arma2__gpfvic_CAV1/attachment2.out",
    ),
    (
        "keepon",
        "1_pinocchio/berkeley_cs184__icheung_Keepon/keepon/keepon.obj",
        "1_pinocchio/berkeley_cs184__icheung_Keepon/keepon/skeleton.out",
        "1_pinocchio/berkeley_cs184__icheung_Keepon/keepon/attachment.out",
    ),
    (
        "armadillo",
        "1_pinocchio/berkeley_cs184__icheung_Keepon/armadillo/Armadillo.obj",
        "1_pinocchio/berkeley_cs184__icheung_Keepon/armadillo/skeleton.out",
        "1_pinocchio/berkeley_cs184__icheung_Keepon/armadillo/attachment.out",
    ),
    (
        "model1",
        "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1/Model1.obj",
        "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1/skeleton.out",
        "1_pinocchio/berkeley_cs184__severus-snape_mobius-ants/human_model1/attachment.out",
    ),
];

/// The glTF samples of the corpus.
pub const GLTF_SAMPLES: [&str; 5] = [
    "5_gltf/khronos_samples__nobuyuki83_delfem2/RiggedSimple.glb",
    "5_gltf/khronos_samples__nobuyuki83_delfem2/RiggedFigure.glb",
    "5_gltf/khronos_samples__nobuyuki83_delfem2/CesiumMan.glb",
    "5_gltf/bevy_assets__bevyengine_bevy/SimpleSkin.gltf",
    "5_gltf/blender_io_roundtrip__KhronosGroup/03_skinned_cylinder.gltf",
];

/// A scratch folder, removed at drop.
pub fn scratch() -> tempfile::TempDir {
    tempfile::tempdir().expect("temp dir")
}
