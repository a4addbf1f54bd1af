//! The tables a crate file indexes into (tokens, strings, paths, fields, field sets,
//! specs), the value heap they grow with, and the sections they are written to.

use std::collections::HashMap;

use super::encode::{compress_ints, fast_compress};

/// Size of the bootstrap header (ident, version, TOC offset, 8 reserved words).
pub(crate) const BOOTSTRAP_LEN: usize = 88;

/// The crate version written: 0.8.0, which usd-core 20.11 and later and Apple's
/// RealityKit/Quick Look read, and which holds every value rigport writes.
pub(crate) const VERSION: [u8; 3] = [0, 8, 0];

/// A node of the path tree: parent, element (a prim or variant name, a property name, or
/// a `[target]`), and whether the element is a property.
struct PathNode {
    parent: Option<u32>,
    element: u32,
    property: bool,
}

/// A structural section's writer.
type Section = fn(&Tables) -> Vec<u8>;

/// Everything written so far.
pub(crate) struct Tables {
    /// The file: the bootstrap's space, then the value heap.
    pub out: Vec<u8>,
    tokens: Vec<String>,
    token_index: HashMap<String, u32>,
    strings: Vec<u32>,
    string_index: HashMap<u32, u32>,
    paths: Vec<PathNode>,
    path_index: HashMap<String, u32>,
    fields: Vec<(u32, u64)>,
    field_index: HashMap<(u32, u64), u32>,
    field_sets: Vec<u32>,
    specs: Vec<(u32, u32, u32)>,
}

impl Tables {
    pub(crate) fn new() -> Self {
        let mut t = Self {
            out: vec![0; BOOTSTRAP_LEN],
            tokens: Vec::new(),
            token_index: HashMap::new(),
            strings: Vec::new(),
            string_index: HashMap::new(),
            paths: Vec::new(),
            path_index: HashMap::new(),
            fields: Vec::new(),
            field_index: HashMap::new(),
            field_sets: Vec::new(),
            specs: Vec::new(),
        };
        // Token 0 is the empty token: path elements store properties as negated token
        // indices, so no element may have index 0.
        t.token("");
        t.paths.push(PathNode {
            parent: None,
            element: 0,
            property: false,
        });
        t.path_index.insert("/".into(), 0);
        t
    }

    /// The index of a token, added when new.
    pub(crate) fn token(&mut self, s: &str) -> u32 {
        if let Some(&i) = self.token_index.get(s) {
            return i;
        }
        let i = self.tokens.len() as u32;
        self.tokens.push(s.to_string());
        self.token_index.insert(s.to_string(), i);
        i
    }

    /// The index of a string (strings are stored as token indices).
    pub(crate) fn string(&mut self, s: &str) -> u32 {
        let t = self.token(s);
        if let Some(&i) = self.string_index.get(&t) {
            return i;
        }
        let i = self.strings.len() as u32;
        self.strings.push(t);
        self.string_index.insert(t, i);
        i
    }

    /// The index of an absolute path (`/A/B`, `/A{set=v}B.prop`, `/A.rel[/T]`), adding
    /// it and its ancestors when new.
    pub(crate) fn path(&mut self, path: &str) -> u32 {
        if let Some(&i) = self.path_index.get(path) {
            return i;
        }
        let (parent, element, property) = split_path(path);
        let parent = self.path(parent);
        let element = self.token(element);
        let i = self.paths.len() as u32;
        self.paths.push(PathNode {
            parent: Some(parent),
            element,
            property,
        });
        self.path_index.insert(path.to_string(), i);
        i
    }

    /// Adds a spec with its fields (name token, value representation).
    pub(crate) fn spec(&mut self, path: &str, kind: u32, fields: &[(u32, u64)]) {
        let path = self.path(path);
        let set = self.field_sets.len() as u32;
        for &field in fields {
            let next = self.fields.len() as u32;
            let index = *self.field_index.entry(field).or_insert(next);
            if index == next {
                self.fields.push(field);
            }
            self.field_sets.push(index);
        }
        self.field_sets.push(u32::MAX);
        self.specs.push((path, set, kind));
    }

    /// Pads the heap to a multiple of `n` bytes.
    pub(crate) fn align(&mut self, n: usize) {
        while self.out.len() % n != 0 {
            self.out.push(0);
        }
    }

    /// Writes the sections, the table of contents and the bootstrap; returns the file.
    pub(crate) fn finish(mut self) -> Vec<u8> {
        let mut toc: Vec<(&str, u64, u64)> = Vec::new();
        let sections: [(&str, Section); 6] = [
            ("TOKENS", Self::tokens_section),
            ("STRINGS", Self::strings_section),
            ("FIELDS", Self::fields_section),
            ("FIELDSETS", Self::field_sets_section),
            ("PATHS", Self::paths_section),
            ("SPECS", Self::specs_section),
        ];
        for (name, build) in sections {
            self.align(8);
            let bytes = build(&self);
            toc.push((name, self.out.len() as u64, bytes.len() as u64));
            self.out.extend_from_slice(&bytes);
        }
        self.align(8);
        let toc_offset = self.out.len() as u64;
        put_u64(&mut self.out, toc.len() as u64);
        for (name, start, size) in toc {
            let mut field = [0_u8; 16];
            field[..name.len()].copy_from_slice(name.as_bytes());
            self.out.extend_from_slice(&field);
            put_u64(&mut self.out, start);
            put_u64(&mut self.out, size);
        }
        let header = &mut self.out[..BOOTSTRAP_LEN];
        header[..8].copy_from_slice(crate::crate_file::MAGIC);
        header[8..11].copy_from_slice(&VERSION);
        header[16..24].copy_from_slice(&toc_offset.to_le_bytes());
        self.out
    }

    fn tokens_section(&self) -> Vec<u8> {
        let mut chars = Vec::new();
        for t in &self.tokens {
            chars.extend_from_slice(t.as_bytes());
            chars.push(0);
        }
        let packed = fast_compress(&chars);
        let mut s = Vec::new();
        put_u64(&mut s, self.tokens.len() as u64);
        put_u64(&mut s, chars.len() as u64);
        put_u64(&mut s, packed.len() as u64);
        s.extend_from_slice(&packed);
        s
    }

    fn strings_section(&self) -> Vec<u8> {
        let mut s = Vec::new();
        put_u64(&mut s, self.strings.len() as u64);
        for &t in &self.strings {
            s.extend_from_slice(&t.to_le_bytes());
        }
        s
    }

    fn fields_section(&self) -> Vec<u8> {
        let mut s = Vec::new();
        put_u64(&mut s, self.fields.len() as u64);
        put_ints(&mut s, self.fields.iter().map(|f| f.0 as i32));
        let reps: Vec<u8> = self.fields.iter().flat_map(|f| f.1.to_le_bytes()).collect();
        let packed = fast_compress(&reps);
        put_u64(&mut s, packed.len() as u64);
        s.extend_from_slice(&packed);
        s
    }

    fn field_sets_section(&self) -> Vec<u8> {
        let mut s = Vec::new();
        put_u64(&mut s, self.field_sets.len() as u64);
        put_ints(&mut s, self.field_sets.iter().map(|&f| f as i32));
        s
    }

    /// The path tree, depth first: per entry its path index, its element token (negated
    /// for properties) and a jump (-1: a child follows; 0: a sibling follows; -2:
    /// neither; n > 0: a child follows and the sibling is n entries on).
    fn paths_section(&self) -> Vec<u8> {
        let n = self.paths.len();
        let mut children: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (i, node) in self.paths.iter().enumerate() {
            if let Some(p) = node.parent {
                children[p as usize].push(i as u32);
            }
        }
        // Subtree sizes: parents have smaller indices than their children.
        let mut size = vec![1_usize; n];
        for i in (0..n).rev() {
            if let Some(p) = self.paths[i].parent {
                size[p as usize] += size[i];
            }
        }
        let (mut indices, mut elements, mut jumps) = (Vec::new(), Vec::new(), Vec::new());
        // (node, has a next sibling)
        let mut stack: Vec<(u32, bool)> = vec![(0, false)];
        while let Some((node, has_sibling)) = stack.pop() {
            let info = &self.paths[node as usize];
            indices.push(node as i32);
            elements.push(if info.property {
                -(info.element as i32)
            } else {
                info.element as i32
            });
            let kids = &children[node as usize];
            jumps.push(match (kids.is_empty(), has_sibling) {
                (false, true) => size[node as usize] as i32,
                (false, false) => -1,
                (true, true) => 0,
                (true, false) => -2,
            });
            for (k, &child) in kids.iter().enumerate().rev() {
                stack.push((child, k + 1 < kids.len()));
            }
        }
        let mut s = Vec::new();
        put_u64(&mut s, n as u64);
        put_u64(&mut s, n as u64);
        put_ints(&mut s, indices);
        put_ints(&mut s, elements);
        put_ints(&mut s, jumps);
        s
    }

    fn specs_section(&self) -> Vec<u8> {
        let mut s = Vec::new();
        put_u64(&mut s, self.specs.len() as u64);
        put_ints(&mut s, self.specs.iter().map(|x| x.0 as i32));
        put_ints(&mut s, self.specs.iter().map(|x| x.1 as i32));
        put_ints(&mut s, self.specs.iter().map(|x| x.2 as i32));
        s
    }
}

/// Splits an absolute path into its parent, last element and whether that is a property.
fn split_path(path: &str) -> (&str, &str, bool) {
    // A target (`/A.rel[/T]`) or a variant selection (`/A{set=v}`) ends the path.
    if let Some(open) = path.ends_with(']').then(|| path.rfind('[')).flatten() {
        return (&path[..open], &path[open..], false);
    }
    if let Some(open) = path.ends_with('}').then(|| path.rfind('{')).flatten() {
        return (&path[..open], &path[open..], false);
    }
    let cut = path.rfind(['/', '.', '}']).unwrap_or(0);
    match path.as_bytes().get(cut) {
        Some(b'.') => (&path[..cut], &path[cut + 1..], true),
        Some(b'}') => (&path[..=cut], &path[cut + 1..], false),
        _ if cut == 0 => ("/", &path[1..], false),
        _ => (&path[..cut], &path[cut + 1..], false),
    }
}

pub(crate) fn put_u64(out: &mut Vec<u8>, v: u64) {
    out.extend_from_slice(&v.to_le_bytes());
}

/// A compressed integer array: its compressed size, then the bytes.
fn put_ints(out: &mut Vec<u8>, values: impl IntoIterator<Item = i32>) {
    let values: Vec<i32> = values.into_iter().collect();
    let packed = compress_ints(&values);
    put_u64(out, packed.len() as u64);
    out.extend_from_slice(&packed);
}

#[cfg(test)]
mod tests {
    use super::split_path;

    #[test]
    fn paths_split_at_their_last_element() {
        assert_eq!(split_path("/A"), ("/", "A", false));
        assert_eq!(split_path("/A/B"), ("/A", "B", false));
        assert_eq!(split_path("/A/B.x:y"), ("/A/B", "x:y", true));
        assert_eq!(split_path("/A{v=a}"), ("/A", "{v=a}", false));
        assert_eq!(split_path("/A{v=}"), ("/A", "{v=}", false));
        assert_eq!(split_path("/A{v=a}B"), ("/A{v=a}", "B", false));
        assert_eq!(split_path("/A{v=a}B.p"), ("/A{v=a}B", "p", true));
        assert_eq!(split_path("/A.rel[/T/U.o]"), ("/A.rel", "[/T/U.o]", false));
    }
}
