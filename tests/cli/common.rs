//! Shared helpers for the end-to-end tests: running the CLI, finding the corpus, running
//! Khronos glTF-Validator, reading glTF back with the independent `gltf` crate.

use std::path::{Path, PathBuf};
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

fn in_ci() -> bool {
    std::env::var_os("CI").is_some_and(|v| !v.is_empty())
}

/// Skips (returns `None` with a message) when something optional is absent, but fails in CI.
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

/// A corpus file or folder (`../shared/corpus/<rel>`), or `None` (skip) when absent.
pub fn corpus(rel: &str) -> Option<PathBuf> {
    let p = repo().join("../shared/corpus").join(rel);
    require(
        &format!("corpus file {}", p.display()),
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

/// The glTF samples of the corpus.
pub const GLTF_SAMPLES: [&str; 5] = [
    "5_gltf/khronos_samples__nobuyuki83_delfem2/RiggedSimple.glb",
    "5_gltf/khronos_samples__nobuyuki83_delfem2/RiggedFigure.glb",
    "5_gltf/khronos_samples__nobuyuki83_delfem2/CesiumMan.glb",
    "5_gltf/bevy_assets__bevyengine_bevy/SimpleSkin.gltf",
    "5_gltf/blender_io_roundtrip__KhronosGroup/03_skinned_cylinder.gltf",
];

/// One file's validator verdict.
#[derive(Debug)]
pub struct Verdict {
    pub errors: u64,
    pub warnings: u64,
    pub infos: u64,
    pub raw: serde_json::Value,
}

/// Runs Khronos glTF-Validator (tools/validate_gltf.mjs) on `file`; `None` (skip) when the
/// validator is not installed (run `bash tools/setup.sh`), failure in CI.
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

/// A scratch folder, removed at drop.
pub fn scratch() -> tempfile::TempDir {
    tempfile::tempdir().expect("temp dir")
}

/// Reads a `.npz` written by `rigport eval`: name -> (shape, f64 values or strings).
pub fn read_npz(path: &Path) -> std::collections::BTreeMap<String, NpyArray> {
    let bytes = std::fs::read(path).expect("npz exists");
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes)).expect("npz is a zip");
    let mut out = std::collections::BTreeMap::new();
    for i in 0..zip.len() {
        use std::io::Read;
        let mut f = zip.by_index(i).expect("entry");
        let name = f.name().trim_end_matches(".npy").to_string();
        let mut data = Vec::new();
        f.read_to_end(&mut data).expect("read entry");
        out.insert(name, parse_npy(&data));
    }
    out
}

/// Reads one `.npy` file.
pub fn read_npy(path: &Path) -> NpyArray {
    parse_npy(&std::fs::read(path).expect("npy exists"))
}

/// One `.npy` array.
#[derive(Debug)]
pub struct NpyArray {
    pub shape: Vec<usize>,
    pub numbers: Vec<f64>,
    pub strings: Vec<String>,
}

fn parse_npy(data: &[u8]) -> NpyArray {
    assert_eq!(&data[..6], b"\x93NUMPY");
    let hlen = u16::from_le_bytes([data[8], data[9]]) as usize;
    let header = std::str::from_utf8(&data[10..10 + hlen]).expect("ascii header");
    let body = &data[10 + hlen..];
    let descr = header
        .split("'descr': '")
        .nth(1)
        .expect("descr")
        .split('\'')
        .next()
        .expect("descr");
    let shape_text = header
        .split("'shape': (")
        .nth(1)
        .expect("shape")
        .split(')')
        .next()
        .expect("shape");
    let shape: Vec<usize> = shape_text
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|s| s.trim().parse().expect("dim"))
        .collect();
    let mut arr = NpyArray {
        shape,
        numbers: Vec::new(),
        strings: Vec::new(),
    };
    match descr {
        "<f4" => {
            arr.numbers = body
                .chunks_exact(4)
                .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
                .collect()
        }
        "<i4" => {
            arr.numbers = body
                .chunks_exact(4)
                .map(|c| i32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
                .collect()
        }
        d if d.starts_with("<U") => {
            let width: usize = d[2..].parse().expect("width");
            arr.strings = body
                .chunks_exact(4 * width)
                .map(|c| {
                    c.chunks_exact(4)
                        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                        .take_while(|&u| u != 0)
                        .filter_map(char::from_u32)
                        .collect()
                })
                .collect()
        }
        other => panic!("unexpected dtype {other}"),
    }
    arr
}
