//! Names the model needs unique (joints, meshes, clips) from sources that repeat or omit
//! them (FBX, COLLADA).

use std::collections::HashSet;

/// `name`, or `fallback` when empty, made unique among `used` with `_2`, `_3`, ...
pub(crate) fn unique(name: &str, fallback: &str, used: &mut HashSet<String>) -> String {
    let base = if name.is_empty() { fallback } else { name };
    let mut candidate = base.to_string();
    let mut n = 2;
    while !used.insert(candidate.clone()) {
        candidate = format!("{base}_{n}");
        n += 1;
    }
    candidate
}
