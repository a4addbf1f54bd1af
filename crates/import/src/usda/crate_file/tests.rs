//! Crate-file (`.usdc`) and package (`.usdz`) tests: the corpus, files written by
//! usd-core from the text fixtures (compared with the text import), and corrupt input.

use std::path::{Path, PathBuf};
use std::process::Command;

use super::super::{import, import_slice};
use super::*;

fn corpus(rel: &str) -> Option<PathBuf> {
    let p = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/corpus/6_usd"
    ))
    .join(rel);
    if p.exists() {
        return Some(p);
    }
    assert!(
        std::env::var_os("CI").is_none_or(|v| v.is_empty()),
        "corpus file {} is missing and CI is set",
        p.display()
    );
    eprintln!("SKIPPED: corpus file {} is missing", p.display());
    None
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
