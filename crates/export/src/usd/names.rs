//! USD prim names and joint path components.
//!
//! A prim name (and each component of a UsdSkel joint path, which UsdSkel parses as an
//! `SdfPath`) must be an identifier. USD 24.03+ accepts UTF-8 identifiers (XID_Start /
//! XID_Continue), but older readers and many pipelines only accept `[A-Za-z_][A-Za-z0-9_]*`,
//! so rigport writes that conservative form: other ASCII characters become `_`, a non-ASCII
//! character becomes `_u` and its code point in hex (so `腕` and `脚` stay distinct), and a
//! leading digit gets a `_` prefix. Names that then clash get `_1`, `_2`, ... appended.

use std::collections::BTreeSet;

/// Whether `name` is already an ASCII USD identifier.
#[cfg(test)]
pub(crate) fn is_identifier(name: &str) -> bool {
    let mut chars = name.chars();
    match chars.next() {
        Some(c) if c.is_ascii_alphabetic() || c == '_' => {}
        _ => return false,
    }
    chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// `name` made into an ASCII identifier; `fallback` when `name` is empty.
pub(crate) fn sanitize(name: &str, fallback: &str) -> String {
    if name.is_empty() {
        return fallback.to_owned();
    }
    let mut out = String::with_capacity(name.len());
    for c in name.chars() {
        if c.is_ascii_alphanumeric() || c == '_' {
            out.push(c);
        } else if c.is_ascii() {
            out.push('_');
        } else {
            out.push_str(&format!("_u{:x}", u32::from(c)));
        }
    }
    if out.starts_with(|c: char| c.is_ascii_digit()) {
        out.insert(0, '_');
    }
    out
}

/// Hands out unique identifiers within one namespace (the children of one prim, or one
/// list of tokens).
#[derive(Debug, Default)]
pub(crate) struct Namespace {
    taken: BTreeSet<String>,
}

impl Namespace {
    /// Marks names as used without handing them out (fixed prim names such as `Skeleton`).
    pub(crate) fn reserve(&mut self, name: &str) {
        self.taken.insert(name.to_owned());
    }

    /// Whether `name` is handed out or reserved already.
    pub(crate) fn is_taken(&self, name: &str) -> bool {
        self.taken.contains(name)
    }

    /// A unique identifier for `name`: sanitized, then suffixed with `_1`, `_2`, ... on a
    /// clash. Returns the identifier and whether it differs from `name`.
    pub(crate) fn claim(&mut self, name: &str, fallback: &str) -> (String, bool) {
        let base = sanitize(name, fallback);
        let mut candidate = base.clone();
        let mut k = 1_usize;
        while self.taken.contains(&candidate) {
            candidate = format!("{base}_{k}");
            k += 1;
        }
        self.taken.insert(candidate.clone());
        let changed = candidate != name;
        (candidate, changed)
    }
}

/// Renames collected for one warning: `"from" -> "to"` pairs, the first few listed.
#[derive(Debug, Default)]
pub(crate) struct Renames {
    pairs: Vec<(String, String)>,
}

impl Renames {
    /// Records a rename.
    pub(crate) fn push(&mut self, from: &str, to: &str) {
        self.pairs.push((from.to_owned(), to.to_owned()));
    }

    /// Whether nothing was renamed.
    pub(crate) fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// `N names ... renamed: "a b" -> "a_b", ...` (at most 8 listed).
    pub(crate) fn message(&self, what: &str) -> String {
        const LISTED: usize = 8;
        let n = self.pairs.len();
        let mut msg = format!(
            "{n} {what} name{} renamed to unique USD identifiers: ",
            if n == 1 { "" } else { "s" }
        );
        let listed: Vec<String> = self
            .pairs
            .iter()
            .take(LISTED)
            .map(|(a, b)| format!("{a:?} -> {b:?}"))
            .collect();
        msg.push_str(&listed.join(", "));
        if n > LISTED {
            msg.push_str(&format!(", and {} more", n - LISTED));
        }
        msg
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sanitizes_and_keeps_names_unique() {
        assert!(is_identifier("Hips_01"));
        assert!(!is_identifier("01"));
        assert!(!is_identifier("a b"));
        assert!(!is_identifier(""));
        assert_eq!(sanitize("Left Arm.001", "x"), "Left_Arm_001");
        assert_eq!(sanitize("3d", "x"), "_3d");
        assert_eq!(sanitize("", "joint"), "joint");
        assert_eq!(sanitize("腕", "x"), "_u8155");
        assert_ne!(sanitize("腕", "x"), sanitize("脚", "x"));
        let mut ns = Namespace::default();
        ns.reserve("Skeleton");
        assert_eq!(ns.claim("a b", "m"), ("a_b".to_string(), true));
        assert_eq!(ns.claim("a_b", "m"), ("a_b_1".to_string(), true));
        assert_eq!(ns.claim("Skeleton", "m"), ("Skeleton_1".to_string(), true));
        assert_eq!(ns.claim("ok", "m"), ("ok".to_string(), false));
        for name in ["a b", "a_b_1", "_3d", "_u8155"] {
            assert!(is_identifier(&sanitize(name, "x")), "{name}");
        }
    }

    #[test]
    fn rename_message_lists_a_few() {
        let mut r = Renames::default();
        for i in 0..10 {
            r.push(&format!("a {i}"), &format!("a_{i}"));
        }
        let m = r.message("joint");
        assert!(m.starts_with("10 joint names renamed"), "{m}");
        assert!(m.contains("\"a 0\" -> \"a_0\""), "{m}");
        assert!(m.ends_with("and 2 more"), "{m}");
    }
}
