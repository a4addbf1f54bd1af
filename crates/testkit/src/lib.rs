//! What rigport's tests repeat, in one place (a dev-dependency only, never published):
//!
//! - [`corpus`]: a file of the shared corpus (`../shared/corpus` beside the repository),
//!   with the one CI rule of [`require`]: skip with a printed message when it is absent,
//!   fail when the environment variable `CI` is set (non-empty);
//! - [`gltf_validator`]: Khronos glTF-Validator (`tools/validate_gltf.mjs`) on a file;
//! - [`npy`]: reading `.npy` arrays and `.npz` archives (what `rigport eval` writes);
//! - [`approx`]: approximate asserts that print both values and the difference.
//!
//! ```
//! // Absent corpus files skip (None) outside CI.
//! if std::env::var_os("CI").is_none() {
//!     assert!(rigport_testkit::corpus("no/such/file").is_none());
//! }
//! rigport_testkit::approx::assert_close(1.0, 1.0 + 1e-7, 1e-6, "one");
//! ```
#![warn(missing_docs)]

pub mod approx;
pub mod gltf_validator;
pub mod npy;

use std::path::{Path, PathBuf};

/// The repository root.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The shared corpus folder (`../shared/corpus` beside the repository); it may not exist.
pub fn corpus_dir() -> PathBuf {
    repo().join("../shared/corpus")
}

/// Whether the tests run in CI (`CI` set and non-empty): optional inputs must be present.
pub fn in_ci() -> bool {
    std::env::var_os("CI").is_some_and(|v| !v.is_empty())
}

/// Skips (returns `None` with a printed message) when something optional is absent, but
/// fails in CI.
///
/// # Panics
/// `value` is `None` and [`in_ci`].
pub fn require<T>(what: &str, value: Option<T>) -> Option<T> {
    if value.is_none() {
        assert!(
            !in_ci(),
            "{what} is missing and CI is set: this test must run in CI"
        );
        eprintln!("SKIPPED: {what} is missing");
    }
    value
}

/// A corpus file or folder (`../shared/corpus/<rel>`), or `None` (skip, see [`require`])
/// when absent.
///
/// # Panics
/// It is absent and [`in_ci`].
pub fn corpus(rel: &str) -> Option<PathBuf> {
    let p = corpus_dir().join(rel);
    require(
        &format!("corpus file {}", p.display()),
        p.exists().then_some(p),
    )
}

/// Python with Blender's `bpy` module (Blender 4.5): `RIGPORT_BLENDER_PYTHON`, else
/// `tools/.venv-blender/bin/python` (`bash tools/setup.sh --blender`), or `None` (skip, see
/// [`require`]) when absent.
///
/// # Panics
/// It is absent and [`in_ci`].
pub fn blender_python() -> Option<PathBuf> {
    let p = std::env::var_os("RIGPORT_BLENDER_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo().join("tools/.venv-blender/bin/python"));
    require(
        "Blender's Python module bpy (tools/.venv-blender: bash tools/setup.sh --blender; \
         or RIGPORT_BLENDER_PYTHON)",
        p.exists().then_some(p),
    )
}

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
