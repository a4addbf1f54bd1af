//! The motions `combine` reads: each argument a file or a folder, folders expanded as
//! `rigport batch` expands them ([`rigport_import::gather::assets_in`]), into one
//! [`Source`] per asset. An `.amc` file goes with the `.asf` motion given before it, or
//! with the rig when the rig is an `.asf` (the same skeleton's clips).

use std::path::PathBuf;

use rigport_import::asf_amc::DEFAULT_FPS;
use rigport_import::detect::{Inputs, Kind, Source, detect};

use crate::PipelineError;

/// One motion asset to read.
#[derive(Clone, Debug)]
pub(crate) struct Motion {
    /// What to import.
    pub source: Source,
    /// Found in a folder: an asset without clips there is skipped, not an error.
    pub from_folder: bool,
}

impl Motion {
    /// The file clip `index` of `clips` comes from: its AMC for an ASF/AMC motion, else
    /// the main file.
    pub(crate) fn file_of(&self, index: usize, clips: usize) -> PathBuf {
        match &self.source {
            Source::AsfAmc { motions, .. } if motions.len() == clips => motions[index].clone(),
            source => PathBuf::from(source.label()),
        }
    }
}

/// The motions of `paths`, in order (a folder's in sorted order). `rig` is the rig's
/// plan (its `.asf` takes `.amc` files given without one); `amc_fps` the AMC frame rate.
///
/// # Errors
/// An unreadable folder, a file rigport does not read, an `.amc` with no `.asf` to go
/// with, no motion at all.
pub(crate) fn expand(
    paths: &[PathBuf],
    rig: &Source,
    amc_fps: Option<f32>,
) -> Result<Vec<Motion>, PipelineError> {
    let fps = amc_fps.unwrap_or(DEFAULT_FPS);
    let mut motions: Vec<Motion> = Vec::new();
    // The motion an `.amc` joins: the last `.asf` given as a file (or the rig's).
    let mut asf: Option<usize> = None;
    for path in paths {
        let kind = detect(path)?;
        let source = match kind {
            Kind::Folder => {
                asf = None;
                motions.extend(folder(path, fps)?);
                continue;
            }
            Kind::Amc => {
                let at = match asf {
                    Some(at) => at,
                    None => {
                        let Source::AsfAmc { asf: rig_asf, .. } = rig else {
                            return Err(PipelineError::Usage(format!(
                                "{}: an AMC motion needs its .asf skeleton given before it, \
                                 or an .asf rig",
                                path.display()
                            )));
                        };
                        motions.push(Motion {
                            source: asf_amc(rig_asf.clone(), Vec::new(), fps),
                            from_folder: false,
                        });
                        motions.len() - 1
                    }
                };
                if let Source::AsfAmc { motions: amcs, .. } = &mut motions[at].source {
                    amcs.push(path.clone());
                }
                asf = Some(at);
                continue;
            }
            Kind::Asf => asf_amc(path.clone(), Vec::new(), fps),
            _ => single(vec![path.clone()])?,
        };
        asf = matches!(source, Source::AsfAmc { .. }).then_some(motions.len());
        motions.push(Motion {
            source,
            from_folder: false,
        });
    }
    if motions.is_empty() {
        return Err(PipelineError::Usage("no motion given".into()));
    }
    Ok(motions)
}

fn asf_amc(asf: PathBuf, motions: Vec<PathBuf>, fps: f32) -> Source {
    Source::AsfAmc { asf, motions, fps }
}

/// The one asset `files` make.
fn single(files: Vec<PathBuf>) -> Result<Source, PipelineError> {
    crate::load::single_plan(&Inputs::new(files))
}

/// The motions below `dir`: its assets that can carry clips (a rig of OBJ, Pinocchio or
/// CSCI 520 files carries none and is passed over).
fn folder(dir: &std::path::Path, fps: f32) -> Result<Vec<Motion>, PipelineError> {
    let mut found = Vec::new();
    for (main, mut inputs) in rigport_import::gather::assets_in(dir, None)? {
        let source = match detect(&main)? {
            Kind::Asf => asf_amc(main, inputs.split_off(1), fps),
            Kind::Obj | Kind::Csci520 => continue,
            _ => single(inputs)?,
        };
        found.push(Motion {
            source,
            from_folder: true,
        });
    }
    Ok(found)
}
