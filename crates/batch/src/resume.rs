//! Resume: a sidecar per finished item records what its outputs were made from.
//!
//! The key is a 64-bit FNV-1a hash (file contents eight bytes per step) over the rigport version, the command, its options,
//! the outputs' names, and for every input its file name and a digest of its bytes (also
//! of every option value that names an existing file, such as `--keys k.json`). The key
//! follows the bytes, not the modification time: `touch` alone does not redo an item,
//! changed content does. FNV-1a
//! detects changes, not tampering: a sidecar is a cache entry, not a signature. Files an
//! input refers to on its own (a `.gltf`'s `.bin`, textures) are not hashed; list them as
//! inputs of the item, or run without `--resume`.
//!
//! An item that failed on bad input records its failure too: `--resume` reports it again
//! without running it (output failures are retried).
//!
//! Sidecars live in `OUT/.rigport-batch/items/<hash of the id>.json` and are written
//! (atomically) after every output of the item was written, so an item interrupted
//! between its outputs and its sidecar is redone.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::manifest::Item;

/// The folder (inside the output folder) of sidecars and default reports.
pub const STATE_DIR: &str = ".rigport-batch";

/// FNV-1a, 64 bits.
#[derive(Clone, Copy)]
struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    /// Bytes eight at a time (FNV-1a's step over 64-bit words, with a rotation so that
    /// high bits reach the low ones): about eight times faster than [`Fnv::bytes`], for
    /// file contents, where resume's cost is hashing every input.
    fn words(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for chunk in &mut chunks {
            let mut word = [0u8; 8];
            word.copy_from_slice(chunk);
            self.0 ^= u64::from_le_bytes(word);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3).rotate_left(29);
        }
        self.bytes(chunks.remainder());
        self.bytes(&(bytes.len() as u64).to_le_bytes());
    }

    /// A length-prefixed field, so that ("ab", "c") and ("a", "bc") differ.
    fn field(&mut self, bytes: &[u8]) {
        self.bytes(&(bytes.len() as u64).to_le_bytes());
        self.bytes(bytes);
    }
}

/// File digests of one run, so that items sharing an input (2,500 retimes of a few
/// clips) read and hash it once.
#[derive(Debug, Default)]
pub struct Digests(std::sync::Mutex<std::collections::BTreeMap<PathBuf, u64>>);

impl Digests {
    /// The FNV-1a digest of the file's bytes.
    fn of(&self, path: &Path) -> std::io::Result<u64> {
        let lock = || self.0.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(&d) = lock().get(path) {
            return Ok(d);
        }
        let mut h = Fnv::new();
        h.words(&std::fs::read(path)?);
        lock().insert(path.to_path_buf(), h.0);
        Ok(h.0)
    }
}

/// The resume key of an item, as 16 hex digits; `digests` caches file digests over a run.
///
/// # Errors
/// An input that cannot be read (the item then runs and reports the error itself).
pub fn key(item: &Item, version: &str, digests: &Digests) -> std::io::Result<String> {
    let mut h = Fnv::new();
    h.field(version.as_bytes());
    h.field(item.command.as_bytes());
    for o in &item.options {
        h.field(o.as_bytes());
        let path = Path::new(o);
        if path.is_file() {
            h.field(&digests.of(path)?.to_le_bytes());
        }
    }
    for o in &item.outputs {
        h.field(o.to_string_lossy().as_bytes());
    }
    for input in &item.inputs {
        let name = input.file_name().map(|n| n.to_string_lossy().into_owned());
        h.field(name.unwrap_or_default().as_bytes());
        if input.is_dir() {
            continue;
        }
        h.field(&digests.of(input)?.to_le_bytes());
    }
    Ok(format!("{:016x}", h.0))
}

/// What a sidecar holds.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Sidecar {
    /// The item's id.
    pub id: String,
    /// Its resume key ([`key`]).
    pub key: String,
    /// The warnings its run reported, repeated in the report of a run that skips it.
    pub warnings: Vec<String>,
    /// Its input failure, if it failed on bad input: the same bytes, options and version
    /// fail the same way, so a resumed run reports it again without running it. Output
    /// failures are never recorded (they may be transient).
    #[serde(default)]
    pub error: Option<crate::report::Failure>,
}

/// Where a shard's report goes unless told: `OUT/.rigport-batch/report-I-of-N.jsonl`.
pub fn default_report(out_dir: &Path, shard: crate::Shard) -> PathBuf {
    out_dir
        .join(STATE_DIR)
        .join(format!("report-{}-of-{}.jsonl", shard.index, shard.count))
}

/// Where the sidecar of the item with this id lives in `out_dir`.
pub fn sidecar_path(out_dir: &Path, id: &str) -> PathBuf {
    let mut h = Fnv::new();
    h.bytes(id.as_bytes());
    out_dir
        .join(STATE_DIR)
        .join("items")
        .join(format!("{:016x}.json", h.0))
}

/// The sidecar at `path` when it exists and is one of ours for `id`.
pub fn read_sidecar(path: &Path, id: &str) -> Option<Sidecar> {
    let text = std::fs::read_to_string(path).ok()?;
    let sidecar: Sidecar = serde_json::from_str(&text).ok()?;
    (sidecar.id == id).then_some(sidecar)
}

/// Writes a sidecar atomically, creating its folder.
///
/// # Errors
/// I/O errors.
pub fn write_sidecar(path: &Path, sidecar: &Sidecar) -> std::io::Result<()> {
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)?;
    }
    let mut text = serde_json::to_string(sidecar).map_err(std::io::Error::other)?;
    text.push('\n');
    rigport_atomic::write_atomic(path, text.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_follows_bytes_and_options() -> Result<(), Box<dyn std::error::Error>> {
        let dir = tempfile::tempdir()?;
        let input = dir.path().join("a.bvh");
        std::fs::write(&input, b"one")?;
        let mut item = Item {
            index: 0,
            line: 1,
            id: "a".into(),
            command: "convert".into(),
            inputs: vec![input.clone()],
            options: vec![],
            outputs: vec!["a.glb".into()],
        };
        let k = |item: &Item, v: &str| key(item, v, &Digests::default());
        let k1 = k(&item, "0.1.0")?;
        assert_eq!(k1, k(&item, "0.1.0")?);
        assert_ne!(k1, k(&item, "0.1.1")?);
        std::fs::write(&input, b"two")?;
        let k2 = k(&item, "0.1.0")?;
        assert_ne!(k1, k2);
        item.options = vec!["--fps".into(), "30".into()];
        assert_ne!(k2, k(&item, "0.1.0")?);
        // Same length, one byte changed in a whole word.
        std::fs::write(&input, b"0123456789abcdef")?;
        let k3 = k(&item, "0.1.0")?;
        std::fs::write(&input, b"0123456789abcdeF")?;
        assert_ne!(k3, k(&item, "0.1.0")?);
        Ok(())
    }
}
