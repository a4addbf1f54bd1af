//! Helpers shared by the corpus tests of this crate.
#![allow(dead_code, reason = "each test binary uses a subset")]

use std::path::{Path, PathBuf};

use rigport_model::glam::Vec3;
use rigport_model::{Asset, JointIndex, Skeleton};

/// The corpus folder, or `None` (with a message) when absent; fails when `CI` is set.
pub fn corpus() -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/corpus");
    if p.exists() {
        return Some(p);
    }
    assert!(
        std::env::var_os("CI").is_none_or(|v| v.is_empty()),
        "{} is missing and CI is set",
        p.display()
    );
    eprintln!("SKIPPED: corpus {} is missing", p.display());
    None
}

/// The first asset the inputs make, opened as the CLI does.
pub fn open(paths: &[PathBuf]) -> Asset {
    let inputs = rigport_import::detect::Inputs::new(paths.to_vec());
    let mut opened = rigport_import::detect::open(&inputs).expect("corpus rig opens");
    opened.remove(0).1.asset
}

/// An arm: the chain (grandparent, parent, joint) of a joint named like a hand or wrist
/// with the longest shorter bone, or of any joint when none is named so.
pub fn arm_chain(skeleton: &Skeleton) -> [JointIndex; 3] {
    let rest = skeleton.model_rest_matrices();
    let p = |j: JointIndex| rest[j.get()].w_axis.truncate();
    let height = {
        let (lo, hi) = rest.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), m| {
            (lo.min(m.w_axis.truncate()), hi.max(m.w_axis.truncate()))
        });
        (hi - lo).max_element()
    };
    let parents: Vec<Option<JointIndex>> = skeleton.parents().collect();
    let chains = |named: bool| {
        skeleton
            .joints()
            .iter()
            .enumerate()
            .filter(move |(_, j)| {
                let n = j.name.to_lowercase();
                !named || n.contains("hand") || n.contains("wrist")
            })
            .filter_map(|(i, _)| {
                let tip = JointIndex(i as u32);
                let mid = parents[i]?;
                let root = parents[mid.get()]?;
                let shorter = p(root).distance(p(mid)).min(p(mid).distance(p(tip)));
                (shorter > 0.05 * height).then_some(([root, mid, tip], shorter))
            })
            .collect::<Vec<_>>()
    };
    let mut found = chains(true);
    if found.is_empty() {
        found = chains(false);
    }
    found
        .into_iter()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .expect("a two-bone chain")
        .0
}
