//! Clip names for `combine`: from file stems (a file of one clip) or the clips' own names
//! (a file of several), overridden per file, with `_2`, `_3`, ... added to repeated names
//! (a [`Warning::Repaired`], W003).

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use rigport_model::Warning;

use crate::PipelineError;

/// One clip to name: the file it comes from, its own name, its place among the file's
/// clips and how many the file gives.
pub(crate) struct Unnamed {
    /// The file the clip comes from (an AMC for ASF/AMC motions).
    pub file: PathBuf,
    /// The clip's name in its file.
    pub own: String,
    /// Its index among the file's clips.
    pub index: usize,
    /// How many clips the file gives.
    pub of: usize,
}

/// The stem of `path` as text.
fn stem(path: &Path) -> String {
    path.file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default()
}

/// Whether an override's `file` names `path`: the path as given, its file name or its
/// stem.
fn names_file(file: &str, path: &Path) -> bool {
    Path::new(file) == path
        || path
            .file_name()
            .is_some_and(|n| n.to_string_lossy() == file)
        || stem(path) == file
}

/// Names `clips` in order: a file of one clip gives its stem (or the override's name); a
/// file of several gives each clip's own name (`<stem>_<k>` when empty), prefixed by the
/// override's name and `_` when one names the file. Returns the names and a warning per
/// renamed repeat.
///
/// # Errors
/// An override (`FILE`, `NAME`) whose file is none of the clips' ([`PipelineError::Usage`]),
/// or an empty name.
pub(crate) fn name_clips(
    clips: &[Unnamed],
    overrides: &[(String, String)],
) -> Result<(Vec<String>, Vec<Warning>), PipelineError> {
    if let Some((file, _)) = overrides
        .iter()
        .find(|(file, _)| !clips.iter().any(|c| names_file(file, &c.file)))
    {
        return Err(PipelineError::Usage(format!(
            "a clip name is given for {file:?}, which is none of the motion files"
        )));
    }
    if let Some((file, _)) = overrides.iter().find(|(_, name)| name.trim().is_empty()) {
        return Err(PipelineError::Usage(format!(
            "the clip name given for {file:?} is empty"
        )));
    }
    let mut taken = BTreeSet::new();
    let (mut names, mut warnings) = (Vec::new(), Vec::new());
    for clip in clips {
        let given = overrides
            .iter()
            .rev()
            .find(|(file, _)| names_file(file, &clip.file))
            .map(|(_, name)| name.trim().to_string());
        let own = match clip.own.trim() {
            "" => format!("{}_{}", stem(&clip.file), clip.index + 1),
            own => own.to_string(),
        };
        let wanted = match (given, clip.of) {
            (Some(name), 1) => name,
            (Some(name), _) => format!("{name}_{own}"),
            (None, 1) => stem(&clip.file),
            (None, _) => own,
        };
        let mut name = wanted.clone();
        let mut k = 2;
        while !taken.insert(name.clone()) {
            name = format!("{wanted}_{k}");
            k += 1;
        }
        if name != wanted {
            warnings.push(Warning::Repaired {
                location: format!("clip {wanted:?} of {}", clip.file.display()),
                message: format!("an earlier clip has this name; renamed {name:?}"),
            });
        }
        names.push(name);
    }
    Ok((names, warnings))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clip(file: &str, own: &str, index: usize, of: usize) -> Unnamed {
        Unnamed {
            file: file.into(),
            own: own.into(),
            index,
            of,
        }
    }

    #[test]
    fn stems_own_names_overrides_and_suffixes() {
        let clips = [
            clip("a/walk.bvh", "Take 001", 0, 1),
            clip("b/walk.bvh", "walk", 0, 1),
            clip("b/walk.bvh", "", 0, 1),
            clip("anims.fbx", "run", 0, 2),
            clip("anims.fbx", "", 1, 2),
        ];
        let (names, warnings) = name_clips(&clips, &[]).unwrap_or_default();
        assert_eq!(names, ["walk", "walk_2", "walk_3", "run", "anims_2"]);
        assert_eq!(warnings.len(), 2);
        assert_eq!(warnings[0].code(), "W003");
        let overrides = [("a/walk.bvh".to_string(), "stroll".to_string())];
        let overrides = [overrides[0].clone(), ("anims.fbx".into(), "x".into())];
        let (names, warnings) = name_clips(&clips, &overrides).unwrap_or_default();
        assert_eq!(names, ["stroll", "walk", "walk_2", "x_run", "x_anims_2"]);
        assert_eq!(warnings.len(), 1);
        let unknown = [("nope.bvh".to_string(), "n".to_string())];
        assert!(name_clips(&clips, &unknown).is_err_and(|e| e.is_usage()));
    }
}
