//! Crate-file (`.usdc`) and package (`.usdz`) tests: the corpus, files written by
//! usd-core from the text fixtures (compared with the text import), and corrupt input.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::{import, import_slice};
use rigport_usd::crate_file::{read, MAGIC};
use rigport_usd::layer::{ListOp, PropKind, Specifier, Value};

fn corpus(rel: &str) -> Option<PathBuf> {
    rigport_testkit::corpus(&format!("6_usd/{rel}"))
}

fn files_with(dir: &Path, ext: &str) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|d| {
            d.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == ext))
                .collect()
        })
        .unwrap_or_default();
    out.sort();
    out
}

#[test]
fn corpus_crate_files_import() {
    let Some(dir) = corpus("tinyusdz_tests__lighttransport") else {
        return;
    };
    let files = files_with(&dir, "usdc");
    assert!(files.len() >= 4, "{files:?}");
    for p in files {
        let bytes = std::fs::read(&p).unwrap();
        let layer = read(&bytes, &p).unwrap_or_else(|e| panic!("{e}"));
        assert!(!layer.root.children.is_empty(), "{}", p.display());
        match import(&p) {
            Ok(imported) => eprintln!(
                "{}: {} joints, {} meshes, {} clips, {} warnings",
                p.display(),
                imported.asset.skeleton.len(),
                imported.asset.meshes.len(),
                imported.asset.clips.len(),
                imported.warnings.len()
            ),
            Err(e) => panic!("{e}"),
        }
    }
}

#[test]
fn corpus_packages_import() {
    let Some(dir) = corpus("usdz_test_assets__usd-wg") else {
        return;
    };
    let files = files_with(&dir, "usdz");
    assert!(files.len() >= 3, "{files:?}");
    for p in files {
        let imported = import(&p).unwrap_or_else(|e| panic!("{e}"));
        assert!(!imported.asset.meshes.is_empty(), "{}", p.display());
    }
}

// ---------------------------------------------------------------------------------------
// Files written by usd-core from the text fixtures: the binary import equals the text one.
// ---------------------------------------------------------------------------------------

/// The venv's Python (`RIGPORT_PYTHON`, else `tools/.venv/bin/python`), or `None` when
/// absent; absent tools fail the test when `CI` is set.
fn python() -> Option<PathBuf> {
    let path = std::env::var_os("RIGPORT_PYTHON")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/.venv/bin/python")
        });
    if path.exists() {
        return Some(path);
    }
    assert!(
        std::env::var_os("CI").is_none_or(|v| v.is_empty()),
        "{} is missing and CI is set: run bash tools/setup.sh",
        path.display()
    );
    eprintln!(
        "SKIPPED: {} not found (run bash tools/setup.sh)",
        path.display()
    );
    None
}

/// Writes, for each `.usda` given, `c/X.usdc` (Sdf's export), `z/X.usdz` (that `.usdc` as
/// the root layer of a package) and `za/X.usdz` (the text as the root layer).
const CONVERT: &str = r#"
import os, shutil, sys
from pxr import Sdf
out = sys.argv[1]
for src in sys.argv[2:]:
    stem = os.path.splitext(os.path.basename(src))[0]
    for d in ("c", "z", "za"):
        os.makedirs(os.path.join(out, d), exist_ok=True)
    usdc = os.path.join(out, "c", stem + ".usdc")
    assert Sdf.Layer.FindOrOpen(src).Export(usdc), src
    for d, member in (("z", usdc), ("za", src)):
        cwd = os.getcwd()
        os.chdir(os.path.dirname(member))
        w = Sdf.ZipFileWriter.CreateNew(os.path.join(out, d, stem + ".usdz"))
        w.AddFile(os.path.basename(member))
        w.Save()
        os.chdir(cwd)
"#;

fn convert(python: &Path, out: &Path, sources: &[PathBuf]) {
    let status = Command::new(python)
        .arg("-c")
        .arg(CONVERT)
        .arg(out)
        .args(sources)
        .status()
        .expect("run usd-core");
    assert!(status.success(), "usd-core conversion failed");
}

fn fixture_sources() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures");
    let mut out = files_with(&root.join("usda"), "usda");
    out.push(root.join("usdc/all_types.usda"));
    out
}

/// Warnings as text, with the file named the same whatever its encoding and no line.
fn warning_texts(warnings: &[rigport_model::Warning], path: &Path) -> Vec<String> {
    let stem = path.file_stem().unwrap_or_default().to_string_lossy();
    warnings
        .iter()
        .map(|w| {
            let mut s = w
                .to_string()
                .replace(&path.display().to_string(), &format!("{stem}.usda"));
            // `X.usda:12` -> `X.usda` (a binary layer has no lines).
            let key = format!("{stem}.usda:");
            while let Some(at) = s.find(&key) {
                let digits_from = at + key.len();
                let end = s[digits_from..]
                    .find(|c: char| !c.is_ascii_digit())
                    .map_or(s.len(), |n| digits_from + n);
                s.replace_range(at + key.len() - 1..end, "");
            }
            s
        })
        .collect()
}

#[test]
fn binary_imports_equal_text_imports() {
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let sources = fixture_sources();
    convert(&python, dir.path(), &sources);
    for src in &sources {
        let stem = src.file_stem().unwrap().to_string_lossy().into_owned();
        let text = import(src);
        for sub in ["c", "z", "za"] {
            let ext = if sub == "c" { "usdc" } else { "usdz" };
            let bin_path = dir.path().join(sub).join(format!("{stem}.{ext}"));
            let bin = import(&bin_path);
            match (&text, &bin) {
                (Ok(t), Ok(b)) => {
                    assert!(t.asset == b.asset, "{}: assets differ", bin_path.display());
                    assert_eq!(
                        warning_texts(&t.warnings, src),
                        warning_texts(&b.warnings, &bin_path),
                        "{}",
                        bin_path.display()
                    );
                }
                (Err(t), Err(b)) => {
                    assert_eq!(t.problem.to_string(), b.problem.to_string(), "{stem}");
                }
                (t, b) => panic!(
                    "{}: text {:?} but binary {:?}",
                    bin_path.display(),
                    t.as_ref().err().map(ToString::to_string),
                    b.as_ref().err().map(ToString::to_string)
                ),
            }
        }
    }
}

/// Numbers as the attribute type holds them (`float` and `half` types are narrower than
/// the text parser's `f64`).
fn normalized(v: &Value, type_name: &str) -> Value {
    let base = type_name.trim_end_matches("[]");
    let half = rigport_usd::values::is_half_type(type_name);
    let double = base == "double"
        || base == "timecode"
        || (base.ends_with('d') && base != "float" && !base.starts_with("bool"));
    match v {
        Value::Number(x) if half => {
            Value::Number(f64::from(rigport_usd::values::round_to_half(*x as f32)))
        }
        Value::Number(x) if !double => Value::Number(f64::from(*x as f32)),
        Value::Ident(s) if s != "true" && s != "false" => Value::Str(s.clone()),
        Value::Tuple(items) => {
            Value::Tuple(items.iter().map(|i| normalized(i, type_name)).collect())
        }
        Value::List(items) => Value::List(items.iter().map(|i| normalized(i, type_name)).collect()),
        other => other.clone(),
    }
}

/// Every prim, property value, time sample, target and metadata item of the composed
/// text and binary layers agree (also for what the UsdSkel mapping does not read yet:
/// blend shapes, inbetweens, dictionaries, connections, list ops).
#[test]
fn binary_layer_equals_text_layer_for_every_value_type() {
    let Some(python) = python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/usdc/all_types.usda");
    convert(&python, dir.path(), std::slice::from_ref(&src));
    let text_layer =
        rigport_usd::parse::parse(&std::fs::read_to_string(&src).unwrap(), &src).unwrap();
    let usdc = dir.path().join("c/all_types.usdc");
    let bin_layer = read(&std::fs::read(&usdc).unwrap(), &usdc).unwrap();
    for key in [
        "metersPerUnit",
        "upAxis",
        "timeCodesPerSecond",
        "defaultPrim",
    ] {
        let t = text_layer
            .meta
            .iter()
            .find(|m| m.key == key)
            .map(|m| &m.value);
        let b = bin_layer
            .meta
            .iter()
            .find(|m| m.key == key)
            .map(|m| &m.value);
        assert_eq!(
            t.map(|v| normalized(v, "double")),
            b.map(|v| normalized(v, "double"))
        );
    }
    let mut forced: Vec<Option<(&str, &str, &str)>> = vec![None];
    forced.push(Some(("/Rig", "clip", "run")));
    forced.push(Some(("/Rig", "look", "bold")));
    for force in forced {
        let t = rigport_usd::stage::Stage::compose(&text_layer.root, force);
        let b = rigport_usd::stage::Stage::compose(&bin_layer.root, force);
        let paths = |s: &rigport_usd::stage::Stage<'_>| -> Vec<String> {
            s.prims.iter().map(|p| p.path.clone()).collect()
        };
        let mut tp = paths(&t);
        let mut bp = paths(&b);
        tp.sort();
        bp.sort();
        assert_eq!(tp, bp);
        let mut checked = 0;
        for tprim in &t.prims {
            let bprim = &b.prims[b.index(&tprim.path).unwrap()];
            assert_eq!(tprim.type_name, bprim.type_name, "{}", tprim.path);
            assert_eq!(tprim.defined, bprim.defined, "{}", tprim.path);
            assert_eq!(tprim.api_schemas, bprim.api_schemas, "{}", tprim.path);
            assert_eq!(tprim.arcs, bprim.arcs, "{}", tprim.path);
            assert_eq!(tprim.selections, bprim.selections, "{}", tprim.path);
            assert_eq!(tprim.variant_sets, bprim.variant_sets, "{}", tprim.path);
            let tnames: Vec<&str> = tprim.props.iter().map(|(n, _)| *n).collect();
            let bnames: Vec<&str> = bprim.props.iter().map(|(n, _)| *n).collect();
            assert_eq!(tnames, bnames, "{}", tprim.path);
            for (name, tprop) in &tprim.props {
                let at = format!("{}.{name}", tprim.path);
                let bprop = bprim.prop(name).unwrap();
                let ty = tprop.type_name.unwrap_or("");
                assert_eq!(tprop.type_name, bprop.type_name, "{at}");
                assert_eq!(
                    tprop.default.map(|v| normalized(v, ty)),
                    bprop.default.map(|v| normalized(v, ty)),
                    "{at}"
                );
                let samples = |p: &rigport_usd::stage::Prop<'_>| {
                    p.samples.as_ref().map(|s| {
                        s.iter()
                            .map(|(t, v)| (*t, normalized(v, ty)))
                            .collect::<Vec<_>>()
                    })
                };
                assert_eq!(samples(tprop), samples(bprop), "{at}");
                assert_eq!(tprop.targets, bprop.targets, "{at}");
                for key in ["interpolation", "elementSize", "weight"] {
                    assert_eq!(
                        tprop.meta(key).map(|v| normalized(v, "float")),
                        bprop.meta(key).map(|v| normalized(v, "float")),
                        "{at} {key}"
                    );
                }
                checked += 1;
            }
        }
        assert!(checked > 40, "{checked} properties compared");
    }
}

#[test]
fn corpus_crate_files_equal_their_text_export() {
    let Some(python) = python() else { return };
    let Some(dir) = corpus("tinyusdz_tests__lighttransport") else {
        return;
    };
    let out = tempfile::tempdir().unwrap();
    for usdc in files_with(&dir, "usdc") {
        let stem = usdc.file_stem().unwrap().to_string_lossy().into_owned();
        let usda = out.path().join(format!("{stem}.usda"));
        let status = Command::new(&python)
            .arg("-c")
            .arg("import sys; from pxr import Sdf; assert Sdf.Layer.FindOrOpen(sys.argv[1]).Export(sys.argv[2])")
            .arg(&usdc)
            .arg(&usda)
            .status()
            .unwrap();
        assert!(status.success());
        let t = import(&usda).unwrap();
        let b = import(&usdc).unwrap();
        if t.asset != b.asset {
            let (ta, ba) = (format!("{:#?}", t.asset), format!("{:#?}", b.asset));
            let first = ta
                .lines()
                .zip(ba.lines())
                .position(|(x, y)| x != y)
                .unwrap_or(0);
            let show = |s: &str| {
                s.lines()
                    .skip(first.saturating_sub(8))
                    .take(12)
                    .collect::<Vec<_>>()
                    .join("\n")
            };
            panic!(
                "{stem}: assets differ at line {first}:\n{}\n----\n{}",
                show(&ta),
                show(&ba)
            );
        }
        assert_eq!(
            warning_texts(&t.warnings, &usda),
            warning_texts(&b.warnings, &usdc),
            "{stem}"
        );
    }
}

// ---------------------------------------------------------------------------------------
// The committed fixture, and corrupt files: errors with byte offsets, never a panic.
// ---------------------------------------------------------------------------------------

const ALL_TYPES_USDA: &str = include_str!("../../../../fixtures/usdc/all_types.usda");
const ALL_TYPES_USDC: &[u8] = include_bytes!("../../../../fixtures/usdc/all_types.usdc");
const ALL_TYPES_USDZ: &[u8] = include_bytes!("../../../../fixtures/usdc/all_types.usdz");

#[test]
fn committed_fixture_imports_like_its_text() {
    let text = import_slice(ALL_TYPES_USDA.as_bytes(), Path::new("all_types.usda")).unwrap();
    for (bytes, name) in [
        (ALL_TYPES_USDC, "all_types.usdc"),
        (ALL_TYPES_USDZ, "all_types.usdz"),
        // A `.usd` file may hold either encoding: the bytes decide.
        (ALL_TYPES_USDC, "all_types.usd"),
    ] {
        let bin = import_slice(bytes, Path::new(name)).unwrap_or_else(|e| panic!("{e}"));
        assert!(bin.asset == text.asset, "{name}");
        assert_eq!(bin.warnings.len(), text.warnings.len(), "{name}");
    }
    let a = &text.asset;
    assert_eq!(a.skeleton.len(), 5);
    assert_eq!(a.meshes[0].source_vertex_count(), 38);
    let clips: Vec<&str> = a.clips.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(clips, ["Walk", "Still", "Run"]);
}

#[test]
fn layer_of_the_committed_fixture() {
    let layer = read(ALL_TYPES_USDC, Path::new("all_types.usdc")).unwrap();
    let rig = &layer.root.children[0];
    assert_eq!(rig.name, "Rig");
    assert_eq!(rig.specifier, Specifier::Def);
    let sets: Vec<&str> = rig
        .body
        .variant_sets
        .iter()
        .map(|s| s.name.as_str())
        .collect();
    assert_eq!(sets, ["clip", "look"]);
    let api = rig.meta.iter().find(|m| m.key == "apiSchemas").unwrap();
    assert_eq!(api.op, ListOp::Prepend);
    assert_eq!(
        api.value,
        Value::List(vec![Value::Str("SkelBindingAPI".into())])
    );
    let body = rig.body.children.iter().find(|p| p.name == "Body").unwrap();
    let prop = |name: &str| body.body.props.iter().find(|p| p.name == name).unwrap();
    let PropKind::Attr {
        default: Some(Value::List(q)),
        type_name,
        ..
    } = &prop("primvars:quats").kind
    else {
        panic!("quats");
    };
    assert_eq!(type_name, "quatf[]");
    // (w, x, y, z) as the text writes it; the file holds the float nearest 0.7071068.
    let c = f64::from("0.7071068".parse::<f32>().unwrap());
    assert_eq!(
        q[1],
        Value::Tuple(vec![
            Value::Number(c),
            Value::Number(c),
            Value::Number(0.0),
            Value::Number(0.0)
        ])
    );
    let PropKind::Attr {
        default: Some(Value::List(u)),
        ..
    } = &prop("primvars:uints").kind
    else {
        panic!("uints");
    };
    assert_eq!(u[3], Value::Number(4e9));
    let PropKind::Attr {
        default: Some(Value::None),
        ..
    } = &prop("blocked").kind
    else {
        panic!("blocked");
    };
}

fn read_err(bytes: &[u8]) -> String {
    match read(bytes, Path::new("x.usdc")) {
        Ok(_) => panic!("read a corrupt file"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn corrupt_headers_and_offsets_name_the_byte() {
    assert!(read_err(b"PXR-USDC").contains("x.usdc: at byte 0: truncated"));
    let mut old = ALL_TYPES_USDC.to_vec();
    old[9] = 3;
    assert!(read_err(&old).contains("at byte 8: crate version 0.3.0 is not supported"));
    // The table of contents past the end.
    let mut toc = ALL_TYPES_USDC.to_vec();
    toc[16..24].copy_from_slice(&(1_u64 << 40).to_le_bytes());
    let e = read_err(&toc);
    assert!(
        e.contains(&format!("at byte {}: truncated", 1_u64 << 40)),
        "{e}"
    );
    // Every section start moved past the end.
    let at = u64::from_le_bytes(ALL_TYPES_USDC[16..24].try_into().unwrap()) as usize;
    let mut sections = ALL_TYPES_USDC.to_vec();
    let n = u64::from_le_bytes(sections[at..at + 8].try_into().unwrap()) as usize;
    for k in 0..n {
        let start = at + 8 + k * 32 + 16;
        sections[start..start + 8]
            .copy_from_slice(&(ALL_TYPES_USDC.len() as u64 + 5).to_le_bytes());
    }
    let e = read_err(&sections);
    assert!(
        e.contains(&format!("at byte {}", ALL_TYPES_USDC.len() + 5)),
        "{e}"
    );
}

#[test]
fn every_truncation_is_an_error() {
    for len in 0..ALL_TYPES_USDC.len() {
        let e = read_err(&ALL_TYPES_USDC[..len]);
        assert!(e.starts_with("x.usdc: at byte "), "{len}: {e}");
    }
    for len in (0..ALL_TYPES_USDZ.len()).step_by(7) {
        assert!(import_slice(&ALL_TYPES_USDZ[..len], Path::new("x.usdz")).is_err());
    }
}

#[test]
fn usdz_errors() {
    let e = import_slice(b"PK\x03\x04garbage", Path::new("x.usdz")).unwrap_err();
    assert!(
        e.to_string().starts_with("x.usdz: not a readable .usdz"),
        "{e}"
    );
    // A changed root layer fails the member's checksum, at the member's data.
    let mut z = ALL_TYPES_USDZ.to_vec();
    let at = z.windows(8).position(|w| w == MAGIC).unwrap();
    z[at + 16..at + 24].copy_from_slice(&(1_u64 << 40).to_le_bytes());
    let e = import_slice(&z, Path::new("x.usdz"))
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with(&format!(
            "x.usdz: at byte {at}: cannot read \"all_types.usdc\""
        )),
        "{e}"
    );
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(2048))]
    #[test]
    fn never_panics_on_mutated_crate_files(
        which in 0_usize..2,
        edits in proptest::collection::vec(
            (proptest::num::usize::ANY, proptest::num::u8::ANY, 0_u8..4),
            1..12,
        ),
        cut in proptest::num::usize::ANY,
    ) {
        let mut bytes = [ALL_TYPES_USDC, ALL_TYPES_USDZ][which].to_vec();
        for (at, byte, op) in edits {
            let i = at % bytes.len();
            match op {
                0 => bytes[i] = byte,
                1 => bytes[i] ^= 1 << (byte % 8),
                // Small and large values in 8-byte words: counts and offsets.
                2 => {
                    let j = i - i % 8;
                    if j + 8 <= bytes.len() {
                        let v = if byte % 2 == 0 { u64::from(byte) } else { u64::MAX - u64::from(byte) };
                        bytes[j..j + 8].copy_from_slice(&v.to_le_bytes());
                    }
                }
                _ => bytes[i] = bytes[i].wrapping_add(1),
            }
        }
        if cut % 4 == 0 {
            bytes.truncate(cut / 4 % (bytes.len() + 1));
        }
        let _ = import_slice(&bytes, Path::new("m.usdc"));
    }
}
