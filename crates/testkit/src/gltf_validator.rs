//! Khronos glTF-Validator (`tools/validate_gltf.mjs`, installed by `bash tools/setup.sh`).

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::{repo, require};

/// One file's validator verdict.
#[derive(Debug)]
pub struct Verdict {
    /// Errors reported.
    pub errors: u64,
    /// Warnings reported.
    pub warnings: u64,
    /// Infos reported.
    pub infos: u64,
    /// The validator's whole JSON report.
    pub raw: serde_json::Value,
}

/// Runs Khronos glTF-Validator (tools/validate_gltf.mjs) on `file`; `None` (skip) when the
/// validator is not installed (run `bash tools/setup.sh`), failure in CI.
/// `RIGPORT_GLTF_VALIDATOR` names another runner script.
///
/// # Panics
/// The validator is missing in CI, or does not run or print its JSON verdict.
pub fn validate(file: &Path) -> Option<Verdict> {
    let runner = std::env::var_os("RIGPORT_GLTF_VALIDATOR")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo().join("tools/validate_gltf.mjs"));
    let installed = repo().join("tools/node_modules/gltf-validator").exists()
        || std::env::var_os("RIGPORT_GLTF_VALIDATOR").is_some();
    require(
        "glTF-Validator (bash tools/setup.sh)",
        installed.then_some(()),
    )?;
    let out = Command::new("node")
        .arg(&runner)
        .arg("--json")
        .arg(file)
        .output()
        .expect("node runs");
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text.lines().next().unwrap_or_else(|| {
        panic!(
            "validator printed nothing for {}: {}",
            file.display(),
            String::from_utf8_lossy(&out.stderr)
        )
    });
    let raw: serde_json::Value = serde_json::from_str(line).expect("validator JSON");
    Some(Verdict {
        errors: raw["errors"].as_u64().expect("errors"),
        warnings: raw["warnings"].as_u64().expect("warnings"),
        infos: raw["infos"].as_u64().unwrap_or(0),
        raw,
    })
}

/// Asserts 0 errors and 0 warnings (when the validator is available).
///
/// # Panics
/// As [`validate`], or the file has errors or warnings.
pub fn assert_valid(file: &Path) {
    if let Some(v) = validate(file) {
        assert!(
            v.errors == 0 && v.warnings == 0,
            "{}: {} errors, {} warnings:\n{:#}",
            file.display(),
            v.errors,
            v.warnings,
            v.raw["messages"]
        );
        if v.infos > 0 {
            eprintln!("{}: validator infos: {}", file.display(), v.infos);
        }
    }
}
