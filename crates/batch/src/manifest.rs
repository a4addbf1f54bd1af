//! Manifests: JSON Lines of items, or a folder expanded into one `convert` item per asset.
//!
//! One item per line (blank lines are skipped):
//!
//! ```json
//! {"id": "kick", "command": "convert", "inputs": ["clips/kick.bvh"], "options": ["--reduce-tolerance", "0.001"], "outputs": ["kick.glb"]}
//! ```
//!
//! - `id` (optional, default the first output): unique; names the item in the report.
//! - `command`: the `rigport` subcommand.
//! - `inputs`: the command's positional inputs; relative paths are relative to the
//!   manifest's folder.
//! - `options`: the command's other arguments, exactly as on its command line (paths in
//!   them are relative to the working directory, as on the command line).
//! - `outputs`: files relative to the output folder (no absolute paths, no `..`), unique
//!   across the manifest.

use std::collections::BTreeMap;
use std::path::{Component, Path, PathBuf};

use serde::Deserialize;

/// One unit of work.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Item {
    /// Position in the manifest (after folder expansion), from 0: the shard rule and the
    /// report order use it.
    pub index: usize,
    /// The manifest line (1-based), 0 for items of a folder expansion.
    pub line: usize,
    /// Unique id.
    pub id: String,
    /// The `rigport` subcommand.
    pub command: String,
    /// Positional inputs, resolved against the manifest's folder.
    pub inputs: Vec<PathBuf>,
    /// Other arguments, verbatim.
    pub options: Vec<String>,
    /// Outputs, relative to the output folder.
    pub outputs: Vec<PathBuf>,
}

impl Item {
    /// The item's command line: `program COMMAND INPUTS... OPTIONS... -o OUTPUT`.
    pub fn command_line(&self, program: &str, output: &Path) -> Vec<std::ffi::OsString> {
        let mut argv = vec![program.into(), self.command.clone().into()];
        argv.extend(self.inputs.iter().map(|p| p.clone().into_os_string()));
        argv.extend(self.options.iter().map(Into::into));
        argv.extend(["-o".into(), output.as_os_str().to_os_string()]);
        argv
    }
}

/// Why a manifest cannot be used. Every variant names the manifest (and line).
#[derive(Debug, thiserror::Error)]
pub enum ManifestError {
    /// The manifest or a folder could not be read.
    #[error("{path}: cannot read")]
    Io {
        /// The file or folder.
        path: String,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A line that is not an item.
    #[error("{path}:{line}:{column}: {message}")]
    Syntax {
        /// The manifest.
        path: String,
        /// 1-based line.
        line: usize,
        /// 1-based column within the line.
        column: usize,
        /// What is wrong (serde_json's words).
        message: String,
    },
    /// An item that is well-formed JSON but not usable.
    #[error("{path}:{line}: {message}")]
    Invalid {
        /// The manifest.
        path: String,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// Nothing to do.
    #[error("{0}: no items")]
    Empty(String),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawItem {
    id: Option<String>,
    command: String,
    #[serde(default)]
    inputs: Vec<String>,
    #[serde(default)]
    options: Vec<String>,
    outputs: Vec<String>,
}

/// Reads a JSON Lines manifest file.
///
/// # Errors
/// An unreadable file, or the first bad line ([`parse`]).
pub fn read(path: &Path) -> Result<Vec<Item>, ManifestError> {
    let text = std::fs::read_to_string(path).map_err(|source| ManifestError::Io {
        path: path.display().to_string(),
        source,
    })?;
    let base = path.parent().unwrap_or(Path::new(""));
    parse(&text, &path.display().to_string(), base)
}

/// Parses manifest text; `name` is used in errors, `base` resolves relative inputs.
///
/// # Errors
/// The first line that is not an item, an item without a command or outputs, an output
/// that is absolute or climbs out of the output folder, a duplicate id or output (naming
/// the line of the first), or no items at all.
pub fn parse(text: &str, name: &str, base: &Path) -> Result<Vec<Item>, ManifestError> {
    let mut items = Vec::new();
    for (i, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let line_no = i + 1;
        let raw: RawItem = serde_json::from_str(line).map_err(|e| ManifestError::Syntax {
            path: name.into(),
            line: line_no,
            column: e.column(),
            message: strip_position(&e.to_string()),
        })?;
        let invalid = |message: String| ManifestError::Invalid {
            path: name.into(),
            line: line_no,
            message,
        };
        if raw.command.trim().is_empty() {
            return Err(invalid("\"command\" is empty".into()));
        }
        if raw.outputs.is_empty() {
            return Err(invalid(
                "\"outputs\" is empty: name at least one file".into(),
            ));
        }
        let outputs = raw
            .outputs
            .iter()
            .map(|o| relative_output(o).map_err(|m| invalid(format!("output {o:?}: {m}"))))
            .collect::<Result<Vec<_>, _>>()?;
        let id = raw.id.unwrap_or_else(|| raw.outputs[0].clone());
        if id.is_empty() {
            return Err(invalid("\"id\" is empty".into()));
        }
        items.push(Item {
            index: items.len(),
            line: line_no,
            id,
            command: raw.command,
            inputs: raw.inputs.iter().map(|p| base.join(p)).collect(),
            options: raw.options,
            outputs,
        });
    }
    if items.is_empty() {
        return Err(ManifestError::Empty(name.into()));
    }
    check_unique(&items, name)?;
    Ok(items)
}

/// serde_json appends " at line 1 column 5"; the error names the manifest line instead.
fn strip_position(message: &str) -> String {
    match message.rfind(" at line ") {
        Some(at) => message[..at].to_string(),
        None => message.to_string(),
    }
}

/// An output path that stays inside the output folder.
fn relative_output(text: &str) -> Result<PathBuf, String> {
    let path = PathBuf::from(text);
    if text.is_empty() {
        return Err("empty".into());
    }
    for c in path.components() {
        match c {
            Component::Normal(_) | Component::CurDir => {}
            Component::ParentDir => return Err("must not climb out with \"..\"".into()),
            Component::RootDir | Component::Prefix(_) => {
                return Err("must be relative to the output folder".into())
            }
        }
    }
    Ok(path)
}

/// Ids and outputs are unique; the error names both lines.
fn check_unique(items: &[Item], name: &str) -> Result<(), ManifestError> {
    let mut ids: BTreeMap<&str, usize> = BTreeMap::new();
    let mut outputs: BTreeMap<&Path, usize> = BTreeMap::new();
    let where_ = |line: usize| {
        if line == 0 {
            "the folder expansion".to_string()
        } else {
            format!("line {line}")
        }
    };
    for item in items {
        if let Some(first) = ids.insert(&item.id, item.line) {
            return Err(ManifestError::Invalid {
                path: name.into(),
                line: item.line,
                message: format!("id {:?} is already used on {}", item.id, where_(first)),
            });
        }
        for o in &item.outputs {
            if let Some(first) = outputs.insert(o, item.line) {
                return Err(ManifestError::Invalid {
                    path: name.into(),
                    line: item.line,
                    message: format!(
                        "output {:?} is already written by {}",
                        o.display(),
                        where_(first)
                    ),
                });
            }
        }
    }
    Ok(())
}

/// How a folder becomes items.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Expansion {
    /// Output extension without the dot (`glb`, `gltf`, `usda`).
    pub extension: String,
    /// Options every `convert` item gets.
    pub options: Vec<String>,
    /// A folder not to descend into (the output folder, when it is inside the input).
    pub exclude: Option<PathBuf>,
}

/// Loads the items of `path`: a folder is expanded ([`expand_folder`]), anything else is
/// read as a JSON Lines manifest ([`read`]).
///
/// # Errors
/// As those.
pub fn load(path: &Path, how: &Expansion) -> Result<Vec<Item>, ManifestError> {
    if path.is_dir() {
        expand_folder(path, how)
    } else {
        read(path)
    }
}

impl Expansion {
    /// `extension` (a leading dot is dropped) and options given as one string, split on
    /// whitespace (`"--fps 30"`), with `exclude` (the output folder) not walked.
    pub fn new(extension: &str, options: Option<&str>, exclude: Option<PathBuf>) -> Self {
        Expansion {
            extension: extension.trim_start_matches('.').to_string(),
            options: options
                .map(|o| o.split_whitespace().map(String::from).collect())
                .unwrap_or_default(),
            exclude,
        }
    }
}

/// Expands a folder into one `convert` item per recognised asset
/// ([`rigport_import::gather::assets_in`]: each glTF, BVH, USD, FBX, COLLADA file, CSCI 520
/// `.config`, `.asf` with its `.amc` files, `.obj` with the `.out` files beside it; `rigport
/// convert` says what is wrong when those are not one skeleton and one attachment).
///
/// The id is the main file's path relative to the folder (`/`-separated); the output is
/// that path with the extension replaced (`walk.bvh` -> `walk.glb`), or with the
/// extension appended when two assets would share it (`a.gltf.glb`).
///
/// # Errors
/// A folder that cannot be read; no asset found.
pub fn expand_folder(root: &Path, how: &Expansion) -> Result<Vec<Item>, ManifestError> {
    let exclude = how.exclude.as_ref().and_then(|e| e.canonicalize().ok());
    let found =
        rigport_import::gather::assets_in(root, exclude.as_deref()).map_err(|e| match e {
            rigport_import::detect::DetectError::Io { path, source, .. } => {
                ManifestError::Io { path, source }
            }
            other => ManifestError::Io {
                path: root.display().to_string(),
                source: std::io::Error::other(other.to_string()),
            },
        })?;
    let mut items = Vec::new();
    let mut taken = std::collections::BTreeSet::new();
    for (main, inputs) in found {
        let rel = main.strip_prefix(root).unwrap_or(&main);
        let id = rel
            .components()
            .map(|c| c.as_os_str().to_string_lossy())
            .collect::<Vec<_>>()
            .join("/");
        let mut output = rel.with_extension(&how.extension);
        if !taken.insert(output.clone()) {
            output = PathBuf::from(format!("{id}.{}", how.extension));
            taken.insert(output.clone());
        }
        items.push(Item {
            index: items.len(),
            line: 0,
            id,
            command: "convert".into(),
            inputs,
            options: how.options.clone(),
            outputs: vec![output],
        });
    }
    if items.is_empty() {
        return Err(ManifestError::Empty(root.display().to_string()));
    }
    check_unique(&items, &root.display().to_string())?;
    Ok(items)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_name_the_line() {
        let text = "\n{\"command\": \"convert\", \"inputs\": [\"a.bvh\"], \"outputs\": [\"a.glb\"]}\n{\"command\": \"convert\", \"outputs\": [\"b.glb\"], \"typo\": 1}\n";
        let err = parse(text, "m.jsonl", Path::new(""))
            .err()
            .map(|e| e.to_string());
        let err = err.unwrap_or_default();
        assert!(err.starts_with("m.jsonl:3:"), "{err}");
        assert!(err.contains("typo"), "{err}");

        let dup = "{\"command\": \"convert\", \"outputs\": [\"a.glb\"]}\n{\"id\": \"x\", \"command\": \"retime\", \"outputs\": [\"a.glb\"]}";
        let err = parse(dup, "m.jsonl", Path::new(""))
            .err()
            .map(|e| e.to_string());
        assert_eq!(
            err.as_deref(),
            Some("m.jsonl:2: output \"a.glb\" is already written by line 1")
        );

        let climb = "{\"command\": \"convert\", \"outputs\": [\"../a.glb\"]}";
        let err = parse(climb, "m.jsonl", Path::new(""))
            .err()
            .map(|e| e.to_string());
        assert!(err
            .unwrap_or_default()
            .starts_with("m.jsonl:1: output \"../a.glb\""));

        let broken = "{\"command\": \"convert\", \"outputs\": [\"a.glb\"]}\n{\"command\": ";
        let err = parse(broken, "m.jsonl", Path::new(""))
            .err()
            .map(|e| e.to_string());
        assert!(err.unwrap_or_default().starts_with("m.jsonl:2:"));
    }

    #[test]
    fn resolves_inputs_and_defaults_the_id() {
        let text = "{\"command\": \"convert\", \"inputs\": [\"a.bvh\", \"/abs/b.bvh\"], \"outputs\": [\"o/a.glb\"]}";
        let items = parse(text, "m", Path::new("/data")).unwrap_or_default();
        assert_eq!(items.len(), 1);
        assert_eq!(items[0].id, "o/a.glb");
        assert_eq!(
            items[0].inputs,
            [PathBuf::from("/data/a.bvh"), PathBuf::from("/abs/b.bvh")]
        );
    }

    #[test]
    fn expands_a_folder() -> Result<(), Box<dyn std::error::Error>> {
        let dir = tempfile::tempdir()?;
        let d = dir.path();
        std::fs::create_dir_all(d.join("rig"))?;
        std::fs::create_dir_all(d.join("mocap"))?;
        for f in [
            "a.bvh",
            "a.gltf",
            "a.bin",
            "notes.txt",
            "rig/m.obj",
            "rig/skeleton.out",
            "rig/attachment.out",
            "mocap/02.asf",
            "mocap/02_01.amc",
            "mocap/03-run.asf",
            "mocap/03_01-run.amc",
            ".hidden.bvh",
        ] {
            std::fs::write(d.join(f), b"")?;
        }
        let how = Expansion {
            extension: "glb".into(),
            options: vec!["--no-bone-mesh".into()],
            exclude: None,
        };
        let items = expand_folder(d, &how)?;
        let ids: Vec<&str> = items.iter().map(|i| i.id.as_str()).collect();
        assert_eq!(
            ids,
            [
                "a.bvh",
                "a.gltf",
                "mocap/02.asf",
                "mocap/03-run.asf",
                "rig/m.obj"
            ]
        );
        let outs: Vec<PathBuf> = items.iter().map(|i| i.outputs[0].clone()).collect();
        assert_eq!(outs[0], PathBuf::from("a.glb"));
        assert_eq!(outs[1], PathBuf::from("a.gltf.glb"));
        assert_eq!(items[2].inputs.len(), 2);
        assert_eq!(items[3].inputs.len(), 2);
        assert_eq!(items[4].inputs.len(), 3);
        assert_eq!(items[4].options, ["--no-bone-mesh"]);
        Ok(())
    }
}
