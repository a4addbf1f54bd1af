//! The report: one JSON line per item, in manifest order; merging shard reports; the
//! summary table; the exit code.
//!
//! A line: `{"index":0,"id":"kick","command":"convert","status":"done",
//! "outputs":["kick.glb"],"warnings":[],"error":null,"seconds":0.012}`. `status` is
//! `done`, `skipped` (resumed: outputs and sidecar up to date) or `failed`, with
//! `error` = `{"kind":"input"|"output","message":"...","location":"walk.bvh:12:5"}`
//! (`location` is `file:line[:column]` when the message names one, else the file when it
//! names one, else null). Everything but `seconds` is deterministic.

use std::fmt;
use std::path::Path;

use serde::{Deserialize, Serialize};

/// What happened to an item.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Run, outputs written.
    Done,
    /// Skipped by `--resume`: its outputs are up to date.
    Skipped,
    /// Failed; the other items went on.
    Failed,
}

/// Why an item failed, in terms of what to do about it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FailureKind {
    /// The item's input or options are bad: running it again will fail again.
    Input,
    /// An output could not be written: possibly transient (disk full, permissions), retry.
    Output,
}

/// An item's error.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Failure {
    /// Input or output.
    pub kind: FailureKind,
    /// The whole message, causes included.
    pub message: String,
    /// `file:line[:column]` (or a file) the message names, if any.
    pub location: Option<String>,
}

/// One report line.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// Position in the manifest.
    pub index: usize,
    /// The item's id.
    pub id: String,
    /// Its command.
    pub command: String,
    /// What happened.
    pub status: Status,
    /// Its outputs, relative to the output folder, `/`-separated.
    pub outputs: Vec<String>,
    /// Warnings (and notes) the command reported, in its order.
    pub warnings: Vec<String>,
    /// Why it failed.
    pub error: Option<Failure>,
    /// Wall time of the item in seconds (ms resolution); the one field that varies.
    pub seconds: f64,
}

/// The first `file:line[:column]` in an error message, else the first segment that looks
/// like a file name. Messages are `: `-separated contexts, e.g.
/// `cannot export "x": walk.bvh:12:5: expected OFFSET`.
pub fn location_of(message: &str) -> Option<String> {
    let segments: Vec<&str> = message.split(": ").collect();
    let is_file = |s: &str| {
        !s.is_empty()
            && !s.contains(char::is_whitespace)
            && s.rsplit_once('.').is_some_and(|(stem, ext)| {
                !stem.is_empty()
                    && (1..=5).contains(&ext.len())
                    && ext.chars().all(|c| c.is_ascii_alphanumeric())
            })
    };
    let digits = |t: &str| !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit());
    for s in &segments {
        let Some((head, last)) = s.rsplit_once(':') else {
            continue;
        };
        if !digits(last) {
            continue;
        }
        let file = match head.rsplit_once(':') {
            Some((f, line)) if digits(line) => f,
            _ => head,
        };
        if !file.trim().is_empty() && file.contains('.') {
            return Some((*s).to_string());
        }
    }
    segments
        .into_iter()
        .find(|s| is_file(s))
        .map(str::to_string)
}

/// Why a run failed: [`verdict`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Verdict {
    /// One line: how many items failed, and what to do.
    pub message: String,
    /// The outputs of the first item whose output could not be written, if any did
    /// (comma-separated), for the exit code [`exit_code`] gives (3).
    pub failed_output: Option<String>,
}

/// The verdict for failed records (`None` when none failed), for the exit code
/// [`exit_code`] gives.
pub fn verdict(records: &[Record]) -> Option<Verdict> {
    let failed = records.iter().filter(|r| r.error.is_some()).count();
    let why = match exit_code(records) {
        0 => return None,
        3 => "an output could not be written: retry",
        _ => "bad input; the other items finished",
    };
    let failed_output = records
        .iter()
        .find(|r| (r.error.as_ref()).is_some_and(|e| e.kind == FailureKind::Output))
        .map(|r| r.outputs.join(", "));
    Some(Verdict {
        message: format!("{failed} of {} items failed ({why})", records.len()),
        failed_output,
    })
}

/// A report line as JSON (no newline).
pub fn to_line(record: &Record) -> String {
    // A record has only strings, numbers and enums: serialising cannot fail.
    serde_json::to_string(record).unwrap_or_default()
}

/// Writes a report atomically, one line per record, creating its folder.
///
/// # Errors
/// I/O errors.
pub fn write(path: &Path, records: &[Record]) -> std::io::Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let mut text = String::new();
    for r in records {
        text.push_str(&to_line(r));
        text.push('\n');
    }
    rigport_atomic::write_atomic(path, text.as_bytes())
}

/// Why reports cannot be merged.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// A report could not be read.
    #[error("{path}: cannot read")]
    Io {
        /// The file.
        path: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A line that is not a record.
    #[error("{path}:{line}: not a report line: {message}")]
    Syntax {
        /// The file.
        path: String,
        /// 1-based line.
        line: usize,
        /// serde_json's words.
        message: String,
    },
    /// The same item in two places (overlapping shards, or a report given twice).
    #[error("{path}:{line}: item {id:?} (index {index}) is also at {first}")]
    Duplicate {
        /// The file.
        path: String,
        /// 1-based line.
        line: usize,
        /// The id.
        id: String,
        /// Its manifest index.
        index: usize,
        /// `file:line` of the first.
        first: String,
    },
}

/// Reads and merges reports (the shards of one manifest) into manifest order.
///
/// # Errors
/// Unreadable files, bad lines, an item present twice.
pub fn merge(paths: &[impl AsRef<Path>]) -> Result<Vec<Record>, ReportError> {
    let mut all: Vec<(Record, String)> = Vec::new();
    for path in paths {
        let path = path.as_ref();
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| ReportError::Io {
            path: name.clone(),
            source,
        })?;
        for (i, line) in text.lines().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            let record: Record = serde_json::from_str(line).map_err(|e| ReportError::Syntax {
                path: name.clone(),
                line: i + 1,
                message: e.to_string(),
            })?;
            all.push((record, format!("{name}:{}", i + 1)));
        }
    }
    // Stable: equal indexes stay in reading order, so the duplicate check names the first.
    all.sort_by_key(|(r, _)| r.index);
    let mut ids: std::collections::BTreeMap<&str, &str> = std::collections::BTreeMap::new();
    for (k, (record, at)) in all.iter().enumerate() {
        let same_index = k > 0 && all[k - 1].0.index == record.index;
        let first = match ids.insert(&record.id, at) {
            Some(first) => Some(first.to_string()),
            None if same_index => Some(all[k - 1].1.clone()),
            None => None,
        };
        if let Some(first) = first {
            let (path, line) = at
                .rsplit_once(':')
                .map(|(p, l)| (p.to_string(), l.parse().unwrap_or(0)))
                .unwrap_or_default();
            return Err(ReportError::Duplicate {
                path,
                line,
                id: record.id.clone(),
                index: record.index,
                first,
            });
        }
    }
    Ok(all.into_iter().map(|(r, _)| r).collect())
}

/// The process exit code for a set of records: 3 when an output could not be written
/// (transient: retry), else 1 when an item had bad input (permanent: do not retry), else 0.
pub fn exit_code(records: &[Record]) -> u8 {
    let kinds = || {
        records
            .iter()
            .filter_map(|r| r.error.as_ref().map(|e| e.kind))
    };
    if kinds().any(|k| k == FailureKind::Output) {
        3
    } else if kinds().next().is_some() {
        1
    } else {
        0
    }
}

/// Counts over records, shown as a table.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Summary {
    /// Items.
    pub items: usize,
    /// Done.
    pub done: usize,
    /// Skipped.
    pub skipped: usize,
    /// Failed on input.
    pub failed_input: usize,
    /// Failed on output.
    pub failed_output: usize,
    /// Sum of the items' seconds.
    pub item_seconds: f64,
    /// Items that reported warnings.
    pub with_warnings: usize,
    /// `(id, message)` of each failure, in manifest order.
    pub failures: Vec<(String, String)>,
}

impl Summary {
    /// Counts `records`.
    pub fn of(records: &[Record]) -> Summary {
        let mut s = Summary {
            items: records.len(),
            ..Summary::default()
        };
        for r in records {
            match r.status {
                Status::Done => s.done += 1,
                Status::Skipped => s.skipped += 1,
                Status::Failed => {}
            }
            if let Some(e) = &r.error {
                match e.kind {
                    FailureKind::Input => s.failed_input += 1,
                    FailureKind::Output => s.failed_output += 1,
                }
                s.failures.push((r.id.clone(), e.message.clone()));
            }
            if r.warnings
                .iter()
                .any(|w| !w.starts_with("note:") && !w.is_empty())
            {
                s.with_warnings += 1;
            }
            s.item_seconds += r.seconds;
        }
        s
    }
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{:>7} {:>7} {:>7} {:>13} {:>14} {:>14} {:>13}",
            "items",
            "done",
            "skipped",
            "failed input",
            "failed output",
            "with warnings",
            "item seconds"
        )?;
        writeln!(
            f,
            "{:>7} {:>7} {:>7} {:>13} {:>14} {:>14} {:>13.3}",
            self.items,
            self.done,
            self.skipped,
            self.failed_input,
            self.failed_output,
            self.with_warnings,
            self.item_seconds
        )?;
        if !self.failures.is_empty() {
            writeln!(f, "failed items:")?;
            for (id, message) in &self.failures {
                writeln!(f, "  {id}: {message}")?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_locations() {
        let cases = [
            (
                "cannot export \"x\": walk.bvh:12:5: expected OFFSET",
                Some("walk.bvh:12:5"),
            ),
            ("/data/a b/m.obj:7: bad face", Some("/data/a b/m.obj:7")),
            ("x.gltf: /meshes/0: index out of range", Some("x.gltf")),
            ("no clip to retime", None),
        ];
        for (message, want) in cases {
            assert_eq!(location_of(message).as_deref(), want, "{message}");
        }
    }

    #[test]
    fn exit_codes() {
        let rec = |kind: Option<FailureKind>| Record {
            index: 0,
            id: "a".into(),
            command: "convert".into(),
            status: if kind.is_some() {
                Status::Failed
            } else {
                Status::Done
            },
            outputs: vec![],
            warnings: vec![],
            error: kind.map(|kind| Failure {
                kind,
                message: "m".into(),
                location: None,
            }),
            seconds: 0.0,
        };
        assert_eq!(exit_code(&[rec(None)]), 0);
        assert_eq!(exit_code(&[rec(None), rec(Some(FailureKind::Input))]), 1);
        assert_eq!(
            exit_code(&[
                rec(Some(FailureKind::Output)),
                rec(Some(FailureKind::Input))
            ]),
            3
        );
    }

    #[test]
    fn merges_in_manifest_order_and_refuses_duplicates() -> Result<(), Box<dyn std::error::Error>> {
        let dir = tempfile::tempdir()?;
        let line = |index: usize, id: &str| {
            format!("{{\"index\":{index},\"id\":\"{id}\",\"command\":\"convert\",\"status\":\"done\",\"outputs\":[],\"warnings\":[],\"error\":null,\"seconds\":0.1}}\n")
        };
        let a = dir.path().join("a.jsonl");
        let b = dir.path().join("b.jsonl");
        std::fs::write(&a, line(0, "x") + &line(2, "z"))?;
        std::fs::write(&b, line(1, "y"))?;
        let merged = merge(&[&a, &b])?;
        let ids: Vec<&str> = merged.iter().map(|r| r.id.as_str()).collect();
        assert_eq!(ids, ["x", "y", "z"]);
        std::fs::write(&b, line(3, "x"))?;
        let err = merge(&[&a, &b])
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert!(
            err.contains("b.jsonl:1: item \"x\"") && err.contains("a.jsonl:1"),
            "{err}"
        );
        Ok(())
    }
}
